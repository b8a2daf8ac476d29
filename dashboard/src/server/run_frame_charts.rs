//! Per-frame charts of a scenario on the run page: one small SVG per measure with per-frame
//! values (the frame GPU time and each metric), a line per variant over the measured frames, and
//! a legend naming each variant's worst frame with a link to the image viewer at that frame when
//! it was saved (the harness saves each metric's worst frame by default, `frames.save_worst`), so
//! "find the frames where this technique is worst and look at them" starts on the run page.
//! Server-drawn SVG: the numbers are there without JavaScript.
//!
//! Not for: one variant's charts synced with the viewer's slider (see [`super::frame_charts`]).

use std::fmt::Write;

use tessera_results::{ScenarioResult, Status};

use super::frame_charts::{series_of, worst_of, FrameSeries};
use super::frame_plot::FramePlot;
use crate::html::{enc, esc, num};

const W: f64 = 420.0;
const H: f64 = 140.0;
const LEFT: f64 = 56.0;
const RIGHT: f64 = 10.0;
const TOP: f64 = 10.0;
const BOTTOM: f64 = 20.0;

/// Line colours, one per variant in declaration order (Tableau 10).
const COLOURS: [&str; 10] = [
    "#4e79a7", "#f28e2b", "#e15759", "#76b7b2", "#59a14f", "#edc948", "#b07aa1", "#ff9da7",
    "#9c755f", "#bab0ac",
];

/// One variant's line in a chart.
struct Line<'a> {
    variant: &'a str,
    colour: &'static str,
    series: FrameSeries,
}

/// The charts of scenario `s` of run `run_id`: one per measure that some ok variant has per-frame
/// values of, in the order of the first variant that has it. `saved(variant, frame)` says whether
/// the viewer has that frame. Empty when no variant has per-frame values.
pub fn render(run_id: &str, s: &ScenarioResult, saved: &dyn Fn(&str, u32) -> bool) -> String {
    let mut charts: Vec<(String, Vec<Line<'_>>)> = Vec::new();
    let ok = s.results.iter().filter(|v| v.status == Status::Ok);
    for (i, v) in ok.enumerate() {
        for series in series_of(v) {
            let line = Line {
                variant: &v.variant,
                colour: COLOURS[i % COLOURS.len()],
                series,
            };
            match charts.iter_mut().find(|c| c.0 == line.series.title) {
                Some(c) => c.1.push(line),
                None => charts.push((line.series.title.clone(), vec![line])),
            }
        }
    }
    if charts.is_empty() {
        return String::new();
    }
    let mut out = format!(
        "<details class=run-frames open><summary>per-frame charts of {} ({} measured frames)</summary><div class=run-frame-charts>",
        esc(&s.scenario),
        s.measured_frames
    );
    for (title, lines) in &charts {
        out.push_str(&chart(run_id, &s.scenario, title, lines, saved));
    }
    out.push_str("</div></details>");
    out
}

fn chart(
    run_id: &str,
    scenario: &str,
    title: &str,
    lines: &[Line<'_>],
    saved: &dyn Fn(&str, u32) -> bool,
) -> String {
    let plot = FramePlot::over(
        [W, H, LEFT, RIGHT, TOP, BOTTOM],
        lines
            .iter()
            .map(|l| (&l.series.frames[..], &l.series.values[..])),
    );
    let mut out = format!(
        "<figure class=run-frame-chart><figcaption>{}</figcaption><svg viewBox=\"0 0 {W} {H}\" width={W} height={H} role=img aria-label=\"{}\">",
        esc(title),
        esc(title)
    );
    plot.axes(&mut out);
    for l in lines {
        plot.lines(
            &mut out,
            &l.series.frames,
            &l.series.values,
            l.colour,
            Some(l.variant),
        );
        if let Some((f, v)) = worst_of(&l.series) {
            let _ = write!(
                out,
                "<circle cx={:.1} cy={:.1} r=3 fill=\"{}\"><title>{}: worst frame {f}, {}</title></circle>",
                plot.x(f),
                plot.y(v),
                l.colour,
                esc(l.variant),
                num(v)
            );
        }
    }
    out.push_str("</svg><ul class=legend>");
    for l in lines {
        let worst = match worst_of(&l.series) {
            Some((f, v)) if saved(l.variant, f) => format!(
                " · worst <a href=\"/runs/{}/images/{}/{}#f={f}\">frame {f}</a> ({})",
                enc(run_id),
                enc(scenario),
                enc(l.variant),
                num(v)
            ),
            Some((f, v)) => format!(" · worst frame {f} ({})", num(v)),
            None => String::new(),
        };
        let _ = write!(
            out,
            "<li><span class=swatch style=\"background:{}\"></span>{}{worst}</li>",
            l.colour,
            esc(l.variant)
        );
    }
    out.push_str("</ul></figure>");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scenario() -> ScenarioResult {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/fixtures/viewer-runs/20261201T045513Z-ab7188d/scenarios/basic.json"
        );
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
    }

    #[test]
    fn one_chart_per_measure_a_line_per_variant_and_the_worst_frame_linked_when_saved() {
        let s = scenario();
        let html = render("r1", &s, &|v, f| v == "checkerboard-2x2" && f == 5);
        // GPU time plus the five metrics of the fixture.
        assert_eq!(
            html.matches("<figure class=run-frame-chart>").count(),
            6,
            "{html}"
        );
        assert!(html.contains("<figcaption>GPU time per frame (ms)</figcaption>"));
        assert!(
            html.contains("<figcaption>flip per frame</figcaption>"),
            "{html}"
        );
        // Five ok variants (the msaa2x one is skipped), each in every legend but native's two
        // PSNR charts: against itself its PSNR is infinite on every frame, no line to draw.
        assert_eq!(
            html.matches("<li><span class=swatch").count(),
            6 * 5 - 2,
            "{html}"
        );
        let psnr = &html[html.find("psnr per frame").unwrap()..];
        let psnr = &psnr[..psnr.find("</figure>").unwrap()];
        assert!(!psnr.contains("</span>native"), "{psnr}");
        let flip = &html[html.find("flip per frame").unwrap()..];
        let flip = &flip[..flip.find("</figure>").unwrap()];
        let cb = s
            .results
            .iter()
            .find(|v| v.variant == "checkerboard-2x2")
            .unwrap();
        let m = cb.metrics.iter().find(|m| m.name == "flip").unwrap();
        let (i, _) = m
            .per_frame
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .unwrap();
        let worst = m.frames[i];
        if worst == 5 {
            assert!(
                flip.contains("/runs/r1/images/basic/checkerboard-2x2#f=5\">frame 5</a>"),
                "{flip}"
            );
        } else {
            assert!(
                flip.contains(&format!("checkerboard-2x2 · worst frame {worst} (")),
                "{flip}"
            );
        }
    }

    #[test]
    fn no_per_frame_values_no_charts() {
        let mut s = scenario();
        for v in &mut s.results {
            v.metrics.clear();
            v.passes.clear();
        }
        assert_eq!(render("r1", &s, &|_, _| true), "");
    }
}
