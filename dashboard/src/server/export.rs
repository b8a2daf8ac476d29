//! Exports: `?format=json` (default), `csv` or `md` on API routes, answered with the right
//! content type and a download file name. CSV is `tessera_results::csv_file`'s (RFC 4180, formula
//! cells guarded), the writer `results.csv` uses too.
//!
//! Not for: what is exported (each endpoint builds its rows).

use axum::http::header;
use axum::response::{IntoResponse, Response};
use serde::Deserialize;
use tessera_results::csv_file::{self, Formulas};

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

/// Rows as CSV text, header first, formula cells guarded (see `tessera_results::csv_file`).
pub fn csv(header: &[&str], rows: &[Vec<String>]) -> String {
    String::from_utf8(csv_file::write(header, rows, Formulas::Guard))
        .expect("CSV of UTF-8 fields is UTF-8")
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
    fn exports_quote_and_guard_formula_cells() {
        assert_eq!(
            csv(
                &["a", "b", "c"],
                &[vec![
                    "upscale[scale=0.5,x=1]".into(),
                    "=HYPERLINK(\"x\")".into(),
                    "-0.05".into()
                ]]
            ),
            "a,b,c\n\"upscale[scale=0.5,x=1]\",\"'=HYPERLINK(\"\"x\"\")\",-0.05\n"
        );
    }
}
