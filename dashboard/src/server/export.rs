//! Exports: `?format=json` (default), `csv` or `md` on API routes, answered with the right
//! content type and a download file name. CSV follows RFC 4180 (fields with commas, quotes or line
//! breaks are quoted).
//!
//! Not for: what is exported (each endpoint builds its rows).

use axum::http::header;
use axum::response::{IntoResponse, Response};
use serde::Deserialize;

use super::AppError;

#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Format {
    #[default]
    Json,
    Csv,
    Md,
}

#[derive(Debug, Default, Deserialize)]
pub struct FormatQuery {
    #[serde(default)]
    pub format: Format,
}

/// One CSV field. Text that a spreadsheet would run as a formula (starting with `=`, `+`, `-`,
/// `@`, a tab or a carriage return, e.g. `=HYPERLINK(...)` in a name) gets a leading `'`, as
/// OWASP advises; a plain number (`-0.05`) is left as it is.
pub fn csv_field(s: &str) -> String {
    let formula = s.starts_with(['=', '+', '-', '@', '\t', '\r']) && s.parse::<f64>().is_err();
    let s = if formula {
        format!("'{s}")
    } else {
        s.to_string()
    };
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s
    }
}

/// Rows as CSV text, header first.
pub fn csv(header: &[&str], rows: &[Vec<String>]) -> String {
    let mut out = header.join(",");
    out.push('\n');
    for r in rows {
        let fields: Vec<String> = r.iter().map(|f| csv_field(f)).collect();
        out.push_str(&fields.join(","));
        out.push('\n');
    }
    out
}

/// An optional number as a CSV or Markdown cell: empty when absent.
pub fn cell(v: Option<f64>) -> String {
    v.map_or_else(String::new, |v| v.to_string())
}

/// A text download: `name` is the suggested file name (ASCII, no quotes).
pub fn download(body: String, content_type: &'static str, name: &str) -> Response {
    let name: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "-_.".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect();
    (
        [
            (header::CONTENT_TYPE, content_type.to_string()),
            (
                header::CONTENT_DISPOSITION,
                format!("inline; filename=\"{name}\""),
            ),
        ],
        body,
    )
        .into_response()
}

pub fn csv_response(body: String, name: &str) -> Response {
    download(body, "text/csv; charset=utf-8", name)
}

pub fn md_response(body: String, name: &str) -> Response {
    download(body, "text/markdown; charset=utf-8", name)
}

/// `md` where an endpoint has no Markdown form.
pub fn no_markdown() -> AppError {
    AppError::BadRequest("format must be json or csv here".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_quotes_what_needs_it() {
        assert_eq!(
            csv(
                &["a", "b"],
                &[vec!["upscale[scale=0.5,x=1]".into(), "say \"hi\"".into()]]
            ),
            "a,b\n\"upscale[scale=0.5,x=1]\",\"say \"\"hi\"\"\"\n"
        );
    }

    #[test]
    fn csv_neutralises_formulas_not_numbers() {
        assert_eq!(csv_field("=HYPERLINK(\"x\")"), "\"'=HYPERLINK(\"\"x\"\")\"");
        assert_eq!(csv_field("+cmd"), "'+cmd");
        assert_eq!(csv_field("@SUM(A1)"), "'@SUM(A1)");
        assert_eq!(csv_field("-x"), "'-x");
        assert_eq!(csv_field("-0.05"), "-0.05");
        assert_eq!(csv_field("+1e3"), "+1e3");
        assert_eq!(csv_field("native"), "native");
    }
}
