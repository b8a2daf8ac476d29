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

/// A scenario, variant or measure name for a table cell or list, escaped, in a `name` span that
/// wraps only at its separators: after `[`, `,`, `;` and `/`. Variant names are single tokens
/// (`adaptive-shading[threshold=0.15,motion=on]`); a cell that may break anywhere is squeezed by
/// the table to a few characters and breaks them mid-word, so name cells do not (the table
/// scrolls in its box instead). Each part between separators is a `nowrap` span: a browser
/// would otherwise also break after the hyphens of `adaptive-shading` or `checkerboard-2x2`.
pub fn name(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 48);
    out.push_str("<span class=name><span>");
    let mut chars = s.chars().peekable();
    while let Some(c) = chars.next() {
        out.push_str(&esc(c.encode_utf8(&mut [0; 4])));
        if matches!(c, '[' | ',' | ';' | '/') && chars.peek().is_some() {
            out.push_str("</span><wbr><span>");
        }
    }
    out.push_str("</span></span>");
    out
}

/// An axis title for a measure key from the measure table: its label and unit, e.g.
/// `GPU time (ms)` for `gpu_ms.median`, `reconstruct (ms)` for a pass; the key itself when the
/// table does not know it.
pub fn axis_label(key: &str) -> String {
    match tessera_results::measure::Key::parse(key) {
        Some(k) => with_unit(k.label(), k.measure.unit()),
        None => match tessera_results::measure::Measure::from_name(key) {
            Some(m) => with_unit(m.label().to_string(), m.unit()),
            None => key.to_string(),
        },
    }
}

/// `label (unit)`, or the label alone when it has no unit or already ends with it
/// (`ColorVideoVDP JOD`, not `ColorVideoVDP JOD (JOD)`).
fn with_unit(label: String, unit: &str) -> String {
    if unit.is_empty() || label.ends_with(unit) {
        label
    } else {
        format!("{label} ({unit})")
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

/// A long id for a table cell: ids up to 24 characters as they are, longer ones as their first 10
/// and last 10 characters around an ellipsis (the whole id goes in the cell's `title`).
pub fn short_id(id: &str) -> String {
    let n = id.chars().count();
    if n <= 24 {
        return id.to_string();
    }
    let head: String = id.chars().take(10).collect();
    let tail: String = id.chars().skip(n - 10).collect();
    format!("{head}…{tail}")
}

const STYLE: &str = "body{font:14px/1.4 system-ui,sans-serif;margin:0;color:#222}
nav{background:#1d2733;padding:8px 16px}nav a{color:#dde;margin-right:18px;text-decoration:none}
nav a.on{color:#fff;font-weight:bold}main{padding:12px 16px;max-width:1600px}h1{font-size:20px;overflow-wrap:anywhere}h2{font-size:16px;margin-top:24px}
table{border-collapse:collapse;margin:8px 0}td,th{border-bottom:1px solid #ddd;padding:3px 8px;text-align:left;vertical-align:top}
td.n,th.n{text-align:right;font-variant-numeric:tabular-nums}td.n{white-space:nowrap;overflow-wrap:normal}.nw{white-space:nowrap}.ok{color:#17803d}.skipped{color:#8a6d00}.failed{color:#b3261e}
.worse{color:#b3261e}.better{color:#17803d}.muted{color:#777}.neutral{color:#444;background:#eceff3;padding:0 4px;border-radius:3px}svg{background:#fff;border:1px solid #eee;max-width:100%;height:auto}
form.inline{display:inline}.scroll{overflow-x:auto;max-width:100%}td.wrap{max-width:28em;overflow-wrap:break-word;font-size:12px}
.chart{width:100%;max-width:1400px;margin:8px 0}.uplot .u-legend{text-align:left;margin:4px 0 0;display:block}.uplot .u-legend th,.uplot .u-legend td{border:0;padding:1px 4px;vertical-align:middle}.uplot .u-legend.u-inline tr{margin-right:14px}.chart-controls{margin:4px 0;font-size:13px}.chart-hover{font-size:12px;color:#444;min-height:1.4em;font-variant-numeric:tabular-nums}
.alert{background:#b3261e;color:#fff;border-radius:8px;padding:0 6px;font-size:12px}.pager{margin:8px 0}.pager a{margin-right:12px}
.viewer .panes{display:flex;flex-wrap:wrap;gap:8px}.viewer figure{margin:0}.viewer figcaption{font-size:12px;color:#555}
.pane{overflow:auto;max-width:min(100%,720px);max-height:600px;border:1px solid #ccc;background:#333;cursor:grab}
img.px{image-rendering:pixelated;display:block;max-width:none}.stack{position:relative}.stack img.top{position:absolute;left:0;top:0}.stack img.overlay{opacity:.5}
#wipe-line{position:absolute;top:0;bottom:0;width:1px;background:#ff0;pointer-events:none}.viewer .controls{margin:8px 0;display:flex;flex-wrap:wrap;gap:16px;align-items:center}
kbd{border:1px solid #aaa;border-radius:3px;padding:0 4px;font-size:12px}
.pair{display:grid;grid-template-columns:1fr 1fr;gap:8px;width:100%}.pair figure{min-width:0}.pair .pane{max-width:100%}
.flip-scale{display:flex;align-items:center;gap:4px;font-size:12px;margin:2px 0}.flip-scale .bar{display:inline-block;width:160px;height:10px;border:1px solid #999}
.frame-charts{display:flex;flex-wrap:wrap;gap:8px;margin:8px 0}.frame-chart{margin:0}.frame-chart svg{border:1px solid #eee}
.run-frames summary{cursor:pointer;color:#444;margin:6px 0}.run-frame-charts{display:flex;flex-wrap:wrap;gap:12px;margin:4px 0}.run-frame-chart{margin:0;max-width:100%;width:420px}
.run-frame-chart figcaption{font-size:12px;color:#444}ul.legend{list-style:none;padding:0;margin:2px 0;font-size:12px}ul.legend li{overflow-wrap:anywhere}.swatch{display:inline-block;width:10px;height:10px;margin-right:4px}
a.ab-button{display:inline-block;padding:0 8px;border:1px solid #4e79a7;border-radius:3px;text-decoration:none;font-weight:600}
main table{display:block;overflow-x:auto;max-width:100%}td{overflow-wrap:break-word}.name{overflow-wrap:normal;word-break:normal}.name>span{white-space:nowrap}td.links{white-space:nowrap;overflow-wrap:normal}
@media (max-width:700px){.wide{display:none}#runs tr{display:block;border-bottom:1px solid #ddd;padding:4px 0}#runs tr:first-child{display:none}#runs td{display:inline-block;border:0;padding:1px 8px 1px 0}#runs td.wide{display:none}nav{padding:6px 8px}nav a{display:inline-block;margin:2px 10px 2px 0}main{padding:8px}
h1{font-size:17px}td,th{padding:3px 4px}select,input{max-width:100%}.pane{max-height:70vh}
.chart{max-width:100%}form#filters label{display:inline-block;margin:2px 8px 2px 0}form.triage input{max-width:100%}}";

/// The whole page around `body`; `active` names the navigation entry to highlight.
pub fn page(title: &str, active: &str, body: &str) -> String {
    let mut out = String::with_capacity(body.len() + 2048);
    let _ = write!(
        out,
        "<!doctype html><html lang=en><head><meta charset=utf-8><meta name=viewport content=\"width=device-width, initial-scale=1\"><link rel=icon href=\"data:,\"><title>{} · Tessera</title><style>{STYLE}</style><link rel=stylesheet href=\"/assets/uPlot.min.css\"><script src=\"/assets/uPlot.iife.min.js\" defer></script><script src=\"/assets/tessera.js\" defer></script></head><body><nav>",
        esc(title)
    );
    for (href, label) in [
        ("/", "runs"),
        ("/series", "series"),
        ("/regressions", "regressions"),
        ("/compare/runs", "compare"),
        ("/compare", "adapters"),
        ("/pareto", "error vs time"),
        ("/frames", "frames"),
        ("/queue", "queue"),
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

/// JSON for a `<script type=application/json>` element: `<` escaped so that no text in it can
/// close the element.
pub fn script_json<T: serde::Serialize>(value: &T) -> String {
    serde_json::to_string(value)
        .expect("page data serialises")
        .replace('<', "\\u003c")
}

/// A chart the page's script draws with uPlot from `spec` (JSON), over `fallback` (server-drawn
/// SVG or a table) that stays when the script does not run.
pub fn chart(id: &str, spec: &str, fallback: &str) -> String {
    format!(
        "<div class=chart id=\"{id}\" data-chart=\"{id}-data\">{fallback}</div><script type=application/json id=\"{id}-data\">{spec}</script>"
    )
}

/// Links to pages of a list: `offset` and `limit` in `base` (a URL with its other query
/// parameters, ending in `?` or `&`), with how many items there are.
pub fn pager(base: &str, offset: i64, limit: i64, total: i64, shown: usize) -> String {
    let mut out = format!(
        "<p class=pager>{}–{} of {total}",
        if shown == 0 { 0 } else { offset + 1 },
        offset + shown as i64
    );
    if offset > 0 {
        let _ = write!(
            out,
            " <a href=\"{}offset={}&limit={limit}\">previous</a>",
            esc(base),
            (offset - limit).max(0)
        );
    }
    if offset + (shown as i64) < total {
        let _ = write!(
            out,
            " <a href=\"{}offset={}&limit={limit}\">next</a>",
            esc(base),
            offset + limit
        );
    }
    out.push_str("</p>");
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
        assert_eq!(
            name("a[b=1,c<2]"),
            "<span class=name><span>a[</span><wbr><span>b=1,</span><wbr><span>c&lt;2]</span></span>"
        );
    }

    #[test]
    fn long_ids_are_shortened_around_an_ellipsis() {
        assert_eq!(
            short_id("20261122T030520Z-34ab2b4"),
            "20261122T030520Z-34ab2b4"
        );
        assert_eq!(
            short_id("nightly-20261122T030520Z-34ab2b4-retry"),
            "nightly-20…b2b4-retry"
        );
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
