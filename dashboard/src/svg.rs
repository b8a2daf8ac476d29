//! Hand-written SVG charts, generated on the server: a series over commits with change points and
//! environment segments, horizontal stacked bars of per-pass GPU time, and a scatter of error
//! against GPU time with the Pareto front. No JavaScript and no external library: a chart is a
//! string of SVG that draws offline, with `<title>` tooltips and `<a>` links on the marks.
//!
//! Not for: data selection (the pages pick what to draw).

use std::fmt::Write;

use crate::html::{esc, num};

/// Tableau 10, then 14 more hues and shades apart from them (Kelly's and Glasbey's lists), so a
/// scene with 21 passes (the city) has 21 colours a reader can tell apart.
const PALETTE: [&str; 24] = [
    "#4e79a7", "#f28e2b", "#59a14f", "#e15759", "#76b7b2", "#edc948", "#b07aa1", "#ff9da7",
    "#9c755f", "#bab0ac", "#1b3a6b", "#a6d854", "#8c2d04", "#17becf", "#6a3d9a", "#fdbf6f",
    "#2ca02c", "#d62728", "#000000", "#c7e9c0", "#7f7f00", "#e7298a", "#66c2a5", "#5c3566",
];

/// A colour per index, distinct for the first 24, then repeating.
pub fn colour(i: usize) -> &'static str {
    PALETTE[i % PALETTE.len()]
}

/// About five round tick values covering [lo, hi].
pub fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite()) || hi <= lo {
        return vec![lo];
    }
    let raw = (hi - lo) / 5.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    // Integer multiples of the step, rounded to its decimals, so that labels print cleanly.
    let decimals = (-step.log10().floor()).max(0.0) as i32;
    let round = 10f64.powi(decimals);
    let out: Vec<f64> = (first..=last)
        .map(|k| (k as f64 * step * round).round() / round)
        .collect();
    out
}

/// Linear map from data to pixels.
#[derive(Clone, Copy)]
struct Scale {
    d0: f64,
    d1: f64,
    p0: f64,
    p1: f64,
}

impl Scale {
    fn new(d0: f64, d1: f64, p0: f64, p1: f64) -> Scale {
        let (d0, d1) = if d1 > d0 {
            (d0, d1)
        } else {
            (d0 - 0.5, d0 + 0.5)
        };
        Scale { d0, d1, p0, p1 }
    }
    fn at(&self, v: f64) -> f64 {
        self.p0 + (v - self.d0) / (self.d1 - self.d0) * (self.p1 - self.p0)
    }
}

fn padded(lo: f64, hi: f64) -> (f64, f64) {
    let pad = ((hi - lo) * 0.08).max(hi.abs() * 0.01).max(1e-12);
    (lo - pad, hi + pad)
}

fn y_axis(out: &mut String, y: Scale, left: f64, right: f64, label: &str) {
    let (lo, hi) = if y.d0 < y.d1 {
        (y.d0, y.d1)
    } else {
        (y.d1, y.d0)
    };
    for t in ticks(lo, hi) {
        let py = y.at(t);
        let _ = write!(
            out,
            "<line x1='{left}' x2='{right}' y1='{py:.1}' y2='{py:.1}' stroke='#eee'/><text x='{:.1}' y='{:.1}' font-size='10' text-anchor='end'>{}</text>",
            left - 4.0,
            py + 3.0,
            num(t)
        );
    }
    let _ = write!(
        out,
        "<text x='4' y='12' font-size='11'>{}</text>",
        esc(label)
    );
}

/// One point of a series chart.
pub struct SeriesMark {
    pub value: f64,
    pub label: String,
    pub href: String,
    /// Its label on the x axis (a short commit); empty: none.
    pub tick: String,
}

/// A series over commits: points joined by a line, change points as red dashed lines (with their
/// href), environment segment starts as grey lines labelled with the new environment.
pub fn series_chart(
    marks: &[SeriesMark],
    change_points: &[(usize, String, String)],
    segments: &[(usize, String)],
    y_label: &str,
) -> String {
    let (w, h, left, top, bottom) = (900.0, 300.0, 60.0, 20.0, 30.0);
    let mut out = format!("<svg xmlns='http://www.w3.org/2000/svg' width='{w}' height='{h}' viewBox='0 0 {w} {h}' role=img>");
    if marks.is_empty() {
        out.push_str("<text x='20' y='40'>no points</text></svg>");
        return out;
    }
    let lo = marks.iter().map(|m| m.value).fold(f64::INFINITY, f64::min);
    let hi = marks
        .iter()
        .map(|m| m.value)
        .fold(f64::NEG_INFINITY, f64::max);
    let (lo, hi) = padded(lo, hi);
    let x = Scale::new(0.0, (marks.len().max(2) - 1) as f64, left + 8.0, w - 12.0);
    let y = Scale::new(lo, hi, h - bottom, top);
    y_axis(&mut out, y, left, w - 10.0, y_label);
    for (i, env) in segments {
        let px = x.at(*i as f64 - 0.5);
        let _ = write!(
            out,
            "<line class='segment' x1='{px:.1}' x2='{px:.1}' y1='{top}' y2='{:.1}' stroke='#999'/><text x='{:.1}' y='{:.1}' font-size='9' fill='#666'>{}</text>",
            h - bottom,
            px + 2.0,
            h - 6.0,
            esc(env)
        );
    }
    for (i, label, href) in change_points {
        let px = x.at(*i as f64 - 0.5);
        let _ = write!(
            out,
            "<a href='{}'><line class='change-point' x1='{px:.1}' x2='{px:.1}' y1='{top}' y2='{:.1}' stroke='#d62728' stroke-width='2' stroke-dasharray='5 3'><title>{}</title></line></a>",
            esc(href),
            h - bottom,
            esc(label)
        );
    }
    // The x axis: a line, and the commits of up to eight evenly spaced points.
    let _ = write!(
        out,
        "<line class='x-axis' x1='{left}' x2='{:.1}' y1='{:.1}' y2='{:.1}' stroke='#999'/>",
        w - 10.0,
        h - bottom,
        h - bottom
    );
    let every = marks.len().div_ceil(8).max(1);
    for (i, m) in marks.iter().enumerate() {
        if m.tick.is_empty() || i % every != 0 {
            continue;
        }
        let px = x.at(i as f64);
        let _ = write!(
            out,
            "<line x1='{px:.1}' x2='{px:.1}' y1='{:.1}' y2='{:.1}' stroke='#999'/><text x='{px:.1}' y='{:.1}' font-size='10' text-anchor='middle' fill='#444'>{}</text>",
            h - bottom,
            h - bottom + 4.0,
            h - bottom + 14.0,
            esc(&m.tick)
        );
    }
    let path: Vec<String> = marks
        .iter()
        .enumerate()
        .map(|(i, m)| format!("{:.1},{:.1}", x.at(i as f64), y.at(m.value)))
        .collect();
    let _ = write!(
        out,
        "<polyline fill='none' stroke='#4e79a7' stroke-width='1.5' points='{}'/>",
        path.join(" ")
    );
    let r = if marks.len() > 300 { 1.5 } else { 3.0 };
    for (i, m) in marks.iter().enumerate() {
        let _ = write!(
            out,
            "<a href='{}'><circle class='point' cx='{:.1}' cy='{:.1}' r='{r}' fill='#4e79a7'><title>{}</title></circle></a>",
            esc(&m.href),
            x.at(i as f64),
            y.at(m.value),
            esc(&m.label)
        );
    }
    out.push_str("</svg>");
    out
}

/// One bar of a stacked chart: a label and its (part, value) segments.
pub struct Bar {
    pub label: String,
    pub parts: Vec<(String, f64)>,
}

/// Horizontal stacked bars (per-pass GPU time per variant) with a legend of part names.
pub fn stacked_bars(bars: &[Bar], unit: &str) -> String {
    let mut names: Vec<&str> = Vec::new();
    for b in bars {
        for (n, _) in &b.parts {
            if !names.contains(&n.as_str()) {
                names.push(n);
            }
        }
    }
    // The label column fits the longest variant name (about 6.6 px a character at 11 px), and the
    // legend wraps onto as many rows as it needs, so nothing is clipped.
    let longest = bars
        .iter()
        .map(|b| b.label.chars().count())
        .max()
        .unwrap_or(0);
    // The axis title sits in the same column, right-aligned 14 px before the bars (about 6 px a
    // character at 10 px).
    let left = (longest as f64 * 6.6 + 14.0)
        .max(unit.chars().count() as f64 * 6.0 + 20.0)
        .max(80.0);
    let (w, bar_h) = (left + 720.0, 18.0);
    let item_w = |n: &str| 24.0 + 7.0 * n.chars().count() as f64;
    let mut legend_rows = 1;
    let mut lx = 0.0;
    for n in &names {
        if lx > 0.0 && lx + item_w(n) > w - 20.0 {
            legend_rows += 1;
            lx = 0.0;
        }
        lx += item_w(n);
    }
    let chart_h = 30.0 + bars.len() as f64 * (bar_h + 6.0);
    let h = chart_h + 18.0 * legend_rows as f64 + 6.0;
    let max = bars
        .iter()
        .map(|b| b.parts.iter().map(|p| p.1).sum::<f64>())
        .fold(0.0, f64::max);
    let x = Scale::new(
        0.0,
        if max > 0.0 { max * 1.05 } else { 1.0 },
        left,
        w - 20.0,
    );
    let mut out = format!("<svg xmlns='http://www.w3.org/2000/svg' width='{w}' height='{h}' viewBox='0 0 {w} {h}' role=img>");
    for t in ticks(0.0, x.d1) {
        let px = x.at(t);
        let _ = write!(out, "<line x1='{px:.1}' x2='{px:.1}' y1='20' y2='{:.1}' stroke='#eee'/><text x='{px:.1}' y='14' font-size='10' text-anchor='middle'>{}</text>", chart_h - 6.0, num(t));
    }
    let _ = write!(
        out,
        "<text x='{:.1}' y='14' font-size='10' text-anchor='end'>{}</text>",
        left - 14.0,
        esc(unit)
    );
    for (i, b) in bars.iter().enumerate() {
        let py = 24.0 + i as f64 * (bar_h + 6.0);
        let _ = write!(
            out,
            "<text x='{:.1}' y='{:.1}' font-size='11' text-anchor='end'>{}</text>",
            left - 6.0,
            py + 13.0,
            esc(&b.label)
        );
        let mut acc = 0.0;
        for (name, v) in &b.parts {
            let ci = names.iter().position(|n| n == name).unwrap_or(0);
            let _ = write!(
                out,
                "<rect class='bar' x='{:.1}' y='{py:.1}' width='{:.1}' height='{bar_h}' fill='{}'><title>{}: {} {}</title></rect>",
                x.at(acc),
                (x.at(acc + v) - x.at(acc)).max(0.5),
                colour(ci),
                esc(name),
                num(*v),
                esc(unit)
            );
            acc += v;
        }
    }
    let (mut lx, mut ly) = (10.0, chart_h);
    for (i, n) in names.iter().enumerate() {
        if lx > 10.0 && lx + item_w(n) > w - 10.0 {
            lx = 10.0;
            ly += 18.0;
        }
        let _ = write!(out, "<rect x='{lx:.1}' y='{ly:.1}' width='10' height='10' fill='{}'/><text x='{:.1}' y='{:.1}' font-size='11'>{}</text>", colour(i), lx + 14.0, ly + 9.0, esc(n));
        lx += item_w(n);
    }
    out.push_str("</svg>");
    out
}

/// A point of the error-against-time scatter.
pub struct ScatterPoint {
    pub label: String,
    pub x: f64,
    pub y: f64,
    /// 0: the newer run, 1: the older one (drawn hollow).
    pub group: usize,
    pub on_front: bool,
    /// Drawn beside a point of the newer run: a short tag (its row number), so that labels do not
    /// collide; the label is its tooltip. Empty: nothing drawn (a point with no table row).
    pub tag: String,
    /// The point's colour (the page colours by technique, so every chart of it agrees).
    pub colour: &'static str,
}

/// Error (y) against GPU time (x): every variant a point, the Pareto front of each group joined
/// by a line, and an arrow from a variant's older position to its newer one.
pub fn scatter(points: &[ScatterPoint], x_label: &str, y_label: &str) -> String {
    let (w, h, left, top, bottom) = (700.0, 420.0, 60.0, 20.0, 34.0);
    let mut out = format!("<svg xmlns='http://www.w3.org/2000/svg' width='{w}' height='{h}' viewBox='0 0 {w} {h}' role=img>");
    if points.is_empty() {
        out.push_str("<text x='20' y='40'>no points</text></svg>");
        return out;
    }
    let fold = |f: fn(&ScatterPoint) -> f64| {
        let lo = points.iter().map(f).fold(f64::INFINITY, f64::min);
        let hi = points.iter().map(f).fold(f64::NEG_INFINITY, f64::max);
        padded(lo, hi)
    };
    let (xl, xh) = fold(|p| p.x);
    let (yl, yh) = fold(|p| p.y);
    let x = Scale::new(xl, xh, left, w - 20.0);
    let y = Scale::new(yl, yh, h - bottom, top);
    y_axis(&mut out, y, left, w - 20.0, y_label);
    for t in ticks(x.d0, x.d1) {
        let _ = write!(
            out,
            "<text x='{:.1}' y='{:.1}' font-size='10' text-anchor='middle'>{}</text>",
            x.at(t),
            h - bottom + 14.0,
            num(t)
        );
    }
    let _ = write!(
        out,
        "<text x='{:.1}' y='{:.1}' font-size='11' text-anchor='end'>{}</text>",
        w - 20.0,
        h - 4.0,
        esc(x_label)
    );
    for g in [1, 0] {
        let mut front: Vec<&ScatterPoint> = points
            .iter()
            .filter(|p| p.group == g && p.on_front)
            .collect();
        front.sort_by(|a, b| a.x.total_cmp(&b.x));
        let path: Vec<String> = front
            .iter()
            .map(|p| format!("{:.1},{:.1}", x.at(p.x), y.at(p.y)))
            .collect();
        let (stroke, dash) = if g == 0 {
            ("#e15759", "")
        } else {
            ("#bbb", " stroke-dasharray='4 3'")
        };
        let _ = write!(out, "<polyline class='front' fill='none' stroke='{stroke}' stroke-width='1.5'{dash} points='{}'/>", path.join(" "));
    }
    for p in points.iter().filter(|p| p.group == 1) {
        if let Some(q) = points.iter().find(|q| q.group == 0 && q.label == p.label) {
            let _ = write!(
                out,
                "<line x1='{:.1}' y1='{:.1}' x2='{:.1}' y2='{:.1}' stroke='#aaa'/>",
                x.at(p.x),
                y.at(p.y),
                x.at(q.x),
                y.at(q.y)
            );
        }
    }
    for p in points {
        let c = p.colour;
        let fill = if p.group == 0 { c } else { "none" };
        let _ = write!(
            out,
            "<circle class='point' cx='{:.1}' cy='{:.1}' r='{}' fill='{fill}' stroke='{c}' stroke-width='1.5'><title>{}: {} ms, {}</title></circle>",
            x.at(p.x),
            y.at(p.y),
            if p.on_front { 5 } else { 4 },
            esc(&p.label),
            num(p.x),
            num(p.y)
        );
        if p.group == 0 && !p.tag.is_empty() {
            let _ = write!(
                out,
                "<text x='{:.1}' y='{:.1}' font-size='10'>{}</text>",
                x.at(p.x) + 6.0,
                y.at(p.y) - 4.0,
                esc(&p.tag)
            );
        }
    }
    out.push_str("</svg>");
    out
}

/// Indices of the points not dominated by another: no other point is at least as fast and at
/// least as good, and strictly better in one. `higher_is_better` is that of the error measure.
pub fn pareto_front(points: &[(f64, f64)], higher_is_better: bool) -> Vec<usize> {
    let better = |a: f64, b: f64| if higher_is_better { a >= b } else { a <= b };
    let strictly = |a: f64, b: f64| if higher_is_better { a > b } else { a < b };
    (0..points.len())
        .filter(|&i| {
            let (xi, yi) = points[i];
            !points.iter().enumerate().any(|(j, &(xj, yj))| {
                j != i && xj <= xi && better(yj, yi) && (xj < xi || strictly(yj, yi))
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stacked_bars_leave_room_for_a_long_axis_title() {
        let bars = [Bar {
            label: "native".into(),
            parts: vec![("scene".into(), 0.5)],
        }];
        let title = "GPU ms (median per pass)";
        let svg = stacked_bars(&bars, title);
        // The title is right-aligned at x = left - 14: it must start inside the picture.
        let at = svg.find(&format!(">{title}<")).unwrap();
        let tag = &svg[svg[..at].rfind("<text").unwrap()..at];
        let x: f64 = tag
            .split("x='")
            .nth(1)
            .unwrap()
            .split('\'')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        assert!(
            x - 6.0 * title.len() as f64 >= 0.0,
            "title at x = {x}: {svg}"
        );
    }

    #[test]
    fn the_palette_stays_distinct_past_twenty_passes() {
        let first: Vec<&str> = (0..24).map(colour).collect();
        for (i, c) in first.iter().enumerate() {
            assert!(!first[..i].contains(c), "colour {i} {c} repeats");
        }
    }

    #[test]
    fn ticks_are_round() {
        assert_eq!(ticks(0.0, 10.0), vec![0.0, 2.0, 4.0, 6.0, 8.0, 10.0]);
        assert_eq!(ticks(3.2, 3.9), vec![3.2, 3.4, 3.6, 3.8]);
    }

    #[test]
    fn pareto_front_keeps_undominated_points() {
        // (ms, flip): native is slow and exact, 0.5 fast and rough, (5, 0.2) is dominated by (4, 0.1).
        let pts = [(8.0, 0.0), (3.5, 0.11), (4.0, 0.1), (5.0, 0.2)];
        assert_eq!(pareto_front(&pts, false), vec![0, 1, 2]);
        // With PSNR (higher is better).
        let pts = [(8.0, 60.0), (3.5, 21.0), (5.0, 20.0)];
        assert_eq!(pareto_front(&pts, true), vec![0, 1]);
    }

    #[test]
    fn charts_draw_marks() {
        let marks: Vec<SeriesMark> = (0..5)
            .map(|i| SeriesMark {
                value: i as f64,
                label: format!("p{i}"),
                href: format!("/runs/{i}"),
                tick: format!("c{i}"),
            })
            .collect();
        let svg = series_chart(
            &marks,
            &[(3, "+10%".into(), "/regressions".into())],
            &[(0, "Mesa".into())],
            "ms",
        );
        assert_eq!(svg.matches("class='point'").count(), 5);
        assert_eq!(svg.matches("class='change-point'").count(), 1);
        // An x axis: a line and every point's commit as a tick (five fit).
        assert!(svg.contains("class='x-axis'"), "{svg}");
        for i in 0..5 {
            assert!(svg.contains(&format!(">c{i}</text>")), "{svg}");
        }
        assert!(svg.starts_with("<svg") && svg.ends_with("</svg>"));
    }
}
