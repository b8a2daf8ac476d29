//! A server-drawn SVG dot-and-whisker chart of ratios with their intervals, one row per item,
//! around a reference line at 1: the adapters page's speed-up ratio B/A per variant with its 99%
//! interval, and the geometric mean as a last, bold row. Like [`crate::svg`], a chart is a string
//! of SVG with `<title>` tooltips that draws offline.
//!
//! Not for: choosing what to draw (the page does).

use std::fmt::Write;

use crate::html::esc;
use crate::svg::ticks;

/// One row: a label, the ratio and its interval (`None` where none could be given).
pub struct Row {
    pub label: String,
    pub value: f64,
    pub interval: Option<[f64; 2]>,
    /// Drawn bold (the summary).
    pub summary: bool,
}

/// The chart; `axis` titles the x axis (`speed-up ratio B / A`). Empty for no finite row.
/// Widest label margin, in pixels: past it a label is cut at its start (no label runs off the
/// chart's left edge).
const LEFT_MAX: f64 = 420.0;

pub fn chart(rows: &[Row], axis: &str) -> String {
    let rows: Vec<&Row> = rows.iter().filter(|r| r.value.is_finite()).collect();
    if rows.is_empty() {
        return String::new();
    }
    let mut lo = 1.0f64;
    let mut hi = 1.0f64;
    for r in &rows {
        let [a, b] = r.interval.unwrap_or([r.value, r.value]);
        for v in [r.value, a, b] {
            if v.is_finite() {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
    }
    let pad = ((hi - lo) * 0.08).max(0.02);
    let (lo, hi) = (lo - pad, hi + pad);
    let longest = rows
        .iter()
        .map(|r| r.label.chars().count())
        .max()
        .unwrap_or(0);
    let left = (longest as f64 * 6.6 + 12.0).clamp(80.0, LEFT_MAX);
    // Labels longer than the margin holds keep their end (the variant's parameters) after an
    // ellipsis; the whole label is the row's tooltip.
    let fits = ((LEFT_MAX - 12.0) / 6.6) as usize;
    let shown = |label: &str| {
        let n = label.chars().count();
        if n <= fits {
            label.to_string()
        } else {
            let tail: String = label.chars().skip(n - (fits - 1)).collect();
            format!("…{tail}")
        }
    };
    let (w, row_h) = (left + 480.0, 20.0);
    let h = 36.0 + rows.len() as f64 * row_h + 18.0;
    let x = |v: f64| left + (v - lo) / (hi - lo) * (w - left - 16.0);
    let mut out = format!(
        "<svg xmlns='http://www.w3.org/2000/svg' class=intervals width='{w}' height='{h}' viewBox='0 0 {w} {h}' role=img><title>{}</title>",
        esc(axis)
    );
    let bottom = 30.0 + rows.len() as f64 * row_h;
    for t in ticks(lo, hi) {
        let px = x(t);
        let _ = write!(
            out,
            "<line x1='{px:.1}' x2='{px:.1}' y1='22' y2='{bottom:.1}' stroke='#eee'/><text x='{px:.1}' y='16' font-size='10' text-anchor='middle'>{t}</text>"
        );
    }
    let one = x(1.0);
    let _ = write!(
        out,
        "<line class=reference x1='{one:.1}' x2='{one:.1}' y1='22' y2='{bottom:.1}' stroke='#888' stroke-dasharray='3 3'/><text x='{:.1}' y='{:.1}' font-size='11' text-anchor='middle'>{}</text>",
        (left + w - 16.0) / 2.0,
        bottom + 14.0,
        esc(axis)
    );
    for (i, r) in rows.iter().enumerate() {
        let py = 30.0 + i as f64 * row_h + row_h / 2.0;
        let weight = if r.summary { " font-weight='bold'" } else { "" };
        let _ = write!(
            out,
            "<text x='{:.1}' y='{:.1}' font-size='11' text-anchor='end'{weight}>{}</text>",
            left - 6.0,
            py + 4.0,
            esc(&shown(&r.label))
        );
        let tip = match r.interval {
            Some([a, b]) => format!("{}: {:.3} [{a:.3}, {b:.3}]", r.label, r.value),
            None => format!("{}: {:.3}", r.label, r.value),
        };
        if let Some([a, b]) = r.interval.filter(|[a, b]| a.is_finite() && b.is_finite()) {
            let _ = write!(
                out,
                "<line class=whisker x1='{:.1}' x2='{:.1}' y1='{py:.1}' y2='{py:.1}' stroke='#4e79a7' stroke-width='2'/>",
                x(a),
                x(b)
            );
        }
        let (fill, size) = if r.summary {
            ("#1d2733", 5.5)
        } else {
            ("#4e79a7", 4.0)
        };
        let _ = write!(
            out,
            "<circle class='point ratio' cx='{:.1}' cy='{py:.1}' r='{size}' fill='{fill}'><title>{}</title></circle>",
            x(r.value),
            esc(&tip)
        );
    }
    out.push_str("</svg>");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_get_a_dot_and_a_whisker_where_an_interval_exists() {
        let rows = [
            Row {
                label: "tiny / upscale".into(),
                value: 1.2,
                interval: Some([1.1, 1.3]),
                summary: false,
            },
            Row {
                label: "geometric mean".into(),
                value: 1.1,
                interval: None,
                summary: true,
            },
        ];
        let svg = chart(&rows, "speed-up ratio B / A");
        assert_eq!(svg.matches("class='point ratio'").count(), 2);
        assert_eq!(svg.matches("class=whisker").count(), 1);
        assert!(svg.contains("class=reference"));
        assert_eq!(chart(&[], "x"), "");
    }
}
