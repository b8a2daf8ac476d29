//! Per-frame charts of a variant: one small SVG per metric (and the frame's GPU time) over the
//! measured frames, each with a marker at the frame the image viewer shows; the viewer's script
//! moves every marker when its frame slider moves (`data-f0`, `data-x0`, `data-dx` place frame
//! `f` at `x0 + (f - f0) * dx`). The worst frame of each metric is marked and named, so "find the
//! frames where this technique is worst and look at them" is one glance. Server-drawn, so the
//! numbers are there without JavaScript.
//!
//! Not for: series over commits (see [`crate::svg`], [`crate::chart`]).

use std::fmt::Write;

use tessera_results::measure::{metric_direction, metric_unit, Direction};
use tessera_results::VariantResult;

use super::frame_plot::FramePlot;
use crate::html::{esc, num};

const W: f64 = 360.0;
const H: f64 = 96.0;
const LEFT: f64 = 52.0;
const RIGHT: f64 = 8.0;
const TOP: f64 = 18.0;
const BOTTOM: f64 = 18.0;

/// One chart: a title with its unit, the frames and their values (non-finite values are gaps),
/// and whether higher is worse (to name the worst frame).
pub struct FrameSeries {
    pub title: String,
    pub frames: Vec<u32>,
    pub values: Vec<f64>,
    pub higher_is_worse: bool,
}

/// The per-frame series of a variant: its frame GPU time (the sum of its passes per frame) and
/// every metric with per-frame values.
pub fn series_of(v: &VariantResult) -> Vec<FrameSeries> {
    let mut out = Vec::new();
    let n = v
        .passes
        .iter()
        .map(|p| p.samples_ms.len())
        .max()
        .unwrap_or(0);
    if n > 0 && v.passes.iter().all(|p| p.samples_ms.len() == n) {
        out.push(FrameSeries {
            title: "GPU time per frame (ms)".into(),
            frames: (0..n as u32).collect(),
            values: (0..n)
                .map(|i| v.passes.iter().map(|p| p.samples_ms[i]).sum())
                .collect(),
            higher_is_worse: true,
        });
    }
    for m in &v.metrics {
        if m.per_frame.len() < 2
            || m.per_frame.len() != m.frames.len()
            || !m.per_frame.iter().any(|v| v.is_finite())
        {
            continue;
        }
        // The measure table's unit, or the one a technique's own check carries.
        let unit = metric_unit(m);
        let title = if unit.is_empty() {
            format!("{} per frame", m.name)
        } else {
            format!("{} per frame ({unit})", m.name)
        };
        let higher_is_worse = metric_direction(m) != Direction::HigherIsBetter;
        out.push(FrameSeries {
            title,
            frames: m.frames.clone(),
            values: m.per_frame.clone(),
            higher_is_worse,
        });
    }
    out
}

/// The charts of `series` side by side (they wrap on a narrow screen).
pub fn render(series: &[FrameSeries]) -> String {
    if series.is_empty() {
        return String::new();
    }
    let mut b = String::from("<div class=frame-charts id=frame-charts>");
    for s in series {
        b.push_str(&chart(s));
    }
    b.push_str("</div>");
    b
}

/// The worst frame of `s` and its value (the first of equals; non-finite values never), as the
/// harness picks the worst frame it saves.
pub fn worst_of(s: &FrameSeries) -> Option<(u32, f64)> {
    let mut worst: Option<(u32, f64)> = None;
    for (&f, &v) in s.frames.iter().zip(&s.values) {
        let worse = v.is_finite()
            && worst.is_none_or(|(_, w)| if s.higher_is_worse { v > w } else { v < w });
        if worse {
            worst = Some((f, v));
        }
    }
    worst
}

fn chart(s: &FrameSeries) -> String {
    let plot = FramePlot::over(
        [W, H, LEFT, RIGHT, TOP, BOTTOM],
        std::iter::once((&s.frames[..], &s.values[..])),
    );
    let worst = worst_of(s);
    let mut out = format!(
        "<figure class=frame-chart><svg viewBox=\"0 0 {W} {H}\" width={W} height={H} role=img aria-label=\"{}\" data-f0={} data-x0={LEFT} data-dx={:.4}>",
        esc(&s.title),
        plot.f0,
        plot.dx()
    );
    let _ = write!(
        out,
        "<text x={LEFT} y=12 font-size=11>{}</text><text x={} y=12 font-size=10 text-anchor=end fill=#555>{}</text>",
        esc(&s.title),
        W - RIGHT,
        worst.map_or(String::new(), |(f, v)| format!("worst: frame {f} ({})", num(v)))
    );
    plot.axes(&mut out);
    plot.lines(&mut out, &s.frames, &s.values, "#1f5fa8", None);
    if let Some((f, v)) = worst {
        let _ = write!(
            out,
            "<circle cx={:.1} cy={:.1} r=3 fill=#b3261e><title>worst: frame {f}, {}</title></circle>",
            plot.x(f),
            plot.y(v),
            num(v)
        );
    }
    let _ = write!(
        out,
        "<line class=frame-marker x1={x0:.1} x2={x0:.1} y1={TOP} y2={} stroke=#e08a00 stroke-width=2 /></svg></figure>",
        H - BOTTOM,
        x0 = plot.x(plot.f0)
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_worst_frame_is_named_and_the_marker_starts_at_the_first() {
        let s = FrameSeries {
            title: "flip per frame".into(),
            frames: vec![0, 1, 2, 3],
            values: vec![0.1, 0.4, 0.2, f64::INFINITY],
            higher_is_worse: true,
        };
        let svg = chart(&s);
        assert!(svg.contains("worst: frame 1 (0.4000)"), "{svg}");
        assert!(svg.contains("class=frame-marker x1=52.0"), "{svg}");
        let psnr = FrameSeries {
            higher_is_worse: false,
            ..s
        };
        assert!(chart(&psnr).contains("worst: frame 0"));
    }
}
