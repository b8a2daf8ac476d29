//! Page layout and small formatting helpers for the server-rendered HTML: escaping, URL
//! encoding, number formats, the shared navigation and style sheet. No JavaScript framework, no
//! external requests: every page works offline.
//!
//! Not for: charts (see [`crate::svg`]) or data (see [`crate::store::read`]).

use std::fmt::Write;

use percent_encoding::{utf8_percent_encode, AsciiSet, NON_ALPHANUMERIC};

/// Escapes text for HTML content and attribute values.
pub fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

const COMPONENT: &AsciiSet = &NON_ALPHANUMERIC
    .remove(b'-')
    .remove(b'_')
    .remove(b'.')
    .remove(b'~');

/// Encodes one URL path segment or query value.
pub fn enc(s: &str) -> String {
    utf8_percent_encode(s, COMPONENT).to_string()
}

/// Milliseconds with three decimals, or `–` when absent.
pub fn ms(v: Option<f64>) -> String {
    v.map_or_else(|| "–".to_string(), |v| format!("{v:.3}"))
}

/// A number with four significant digits, `inf` for infinite PSNR.
pub fn num(v: f64) -> String {
    if v.is_infinite() {
        return "inf".into();
    }
    if v == 0.0 {
        return "0".into();
    }
    let digits = (3 - v.abs().log10().floor() as i32).clamp(0, 6) as usize;
    format!("{v:.digits$}")
}

/// A signed percentage: `+3.1%`.
pub fn pct(v: f64) -> String {
    if v.is_finite() {
        format!("{:+.1}%", v * 100.0)
    } else {
        "new".into()
    }
}

/// Bytes in KiB / MiB.
pub fn bytes(b: u64) -> String {
    if b >= 1 << 20 {
        format!("{:.1} MiB", b as f64 / (1u64 << 20) as f64)
    } else {
        format!("{:.1} KiB", b as f64 / 1024.0)
    }
}

/// A commit for display: the first 10 characters, or `(no commit)`.
pub fn commit(c: Option<&str>) -> String {
    c.map_or_else(
        || "(no commit)".to_string(),
        |c| c.chars().take(10).collect(),
    )
}

const STYLE: &str = "body{font:14px/1.4 system-ui,sans-serif;margin:0;color:#222}
nav{background:#1d2733;padding:8px 16px}nav a{color:#dde;margin-right:18px;text-decoration:none}
nav a.on{color:#fff;font-weight:bold}main{padding:12px 16px}h1{font-size:20px}h2{font-size:16px;margin-top:24px}
table{border-collapse:collapse;margin:8px 0}td,th{border-bottom:1px solid #ddd;padding:3px 8px;text-align:left;vertical-align:top}
td.n{text-align:right;font-variant-numeric:tabular-nums}.ok{color:#17803d}.skipped{color:#8a6d00}.failed{color:#b3261e}
.worse{color:#b3261e}.better{color:#17803d}.muted{color:#777}svg{background:#fff;border:1px solid #eee}
form.inline{display:inline}img.shot{image-rendering:pixelated;border:1px solid #ccc;max-width:32%}";

/// The whole page around `body`; `active` names the navigation entry to highlight.
pub fn page(title: &str, active: &str, body: &str) -> String {
    let mut out = String::with_capacity(body.len() + 2048);
    let _ = write!(
        out,
        "<!doctype html><html lang=en><head><meta charset=utf-8><link rel=icon href=\"data:,\"><title>{} · Tessera</title><style>{STYLE}</style></head><body><nav>",
        esc(title)
    );
    for (href, label) in [
        ("/", "runs"),
        ("/series", "series"),
        ("/regressions", "regressions"),
        ("/compare", "adapters"),
        ("/pareto", "error vs time"),
    ] {
        let class = if label == active { " class=on" } else { "" };
        let _ = write!(out, "<a href=\"{href}\"{class}>{label}</a>");
    }
    let _ = write!(
        out,
        "</nav><main><h1>{}</h1>{body}</main></body></html>",
        esc(title)
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_and_encodes() {
        assert_eq!(
            esc("<a href=\"x\">'&'</a>"),
            "&lt;a href=&quot;x&quot;&gt;&#39;&amp;&#39;&lt;/a&gt;"
        );
        assert_eq!(enc("upscale[scale=0.5]"), "upscale%5Bscale%3D0.5%5D");
        assert_eq!(enc("../x"), "..%2Fx");
    }

    #[test]
    fn formats_numbers() {
        assert_eq!(num(20.988830645356607), "20.99");
        assert_eq!(num(0.105755), "0.1058");
        assert_eq!(num(f64::INFINITY), "inf");
        assert_eq!(pct(0.031), "+3.1%");
        assert_eq!(bytes(844800), "825.0 KiB");
    }
}
