//! `tessera regimes <run>...`: where a frame's time goes, and each technique's speed-up against
//! it (issue 23, item 5): one Markdown row per scenario, ordered from vertex-bound to
//! shading-bound.
//!
//! The **pixel-bound fraction** of `native`'s frame is the part that scales with the number of
//! pixels shaded, the part a shading-reduction technique can save. It is measured, not modelled:
//! with `upscale` at `scale = 0.7071` in the scenario (half the pixels, the same scene), a frame of
//! cost `T = A + P` (`A` independent of the pixel count, `P` proportional to it) renders its half
//! in `A + P/2`, so `P / T = 2 (1 - T_half / T)`, where `T_half` is that variant's `scene` pass.
//! Checkerboard's ideal speed-up at fraction `p` is `1 / (1 - p/2)`, which the table prints
//! beside the measured ones (Intel's white paper: 1.14-1.2x on average game frames, up to 1.4x
//! when pixel-bound). Without the half-resolution variant the fraction is `-`.
//!
//! Not for: comparing two runs (`compare.rs`) or history (the dashboard).

use std::fmt::Write as _;

use tessera_results::{ScenarioResult, Status, VariantResult};

use crate::compare::Run;

/// Render scale whose pixel count is half the output's, within this of 0.5 in area.
const HALF_AREA_TOLERANCE: f64 = 0.01;

/// One scenario's row.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub scenario: String,
    pub width: u32,
    pub height: u32,
    /// `native`'s median GPU frame time.
    pub native_ms: f64,
    /// The pixel-bound fraction of `native`'s frame, in [0, 1] (clamped), if measurable.
    pub pixel_fraction: Option<f64>,
    /// Every other ok variant's speed-up against `native` (variant name, speed-up).
    pub speedups: Vec<(String, f64)>,
}

fn median(r: &VariantResult) -> Option<f64> {
    r.gpu_frame_ms.as_ref().map(|s| s.median)
}

fn ok(r: &VariantResult) -> bool {
    matches!(r.status, Status::Ok)
}

/// The median GPU ms of the `scene` pass of a variant rendering the scene at half the pixels.
fn half_pixel_scene_ms(s: &ScenarioResult) -> Option<f64> {
    s.results
        .iter()
        .filter(|r| ok(r) && r.technique == "upscale")
        .find(|r| {
            r.params
                .get("scale")
                .and_then(|v| v.as_f64())
                .is_some_and(|k| (k * k - 0.5).abs() < HALF_AREA_TOLERANCE)
        })
        .and_then(|r| r.passes.iter().find(|p| p.name == "scene"))
        .and_then(|p| p.gpu_ms.as_ref().map(|g| g.median))
}

/// The row of scenario `s`, if it has a timed `native`.
pub fn row(s: &ScenarioResult) -> Option<Row> {
    let native = s
        .results
        .iter()
        .find(|r| ok(r) && r.technique == "native" && r.variant == "native")?;
    let native_ms = median(native).filter(|&t| t > 0.0)?;
    let pixel_fraction =
        half_pixel_scene_ms(s).map(|half| (2.0 * (1.0 - half / native_ms)).clamp(0.0, 1.0));
    let speedups = s
        .results
        .iter()
        .filter(|r| ok(r) && r.variant != native.variant)
        .filter_map(|r| {
            median(r)
                .filter(|&t| t > 0.0)
                .map(|t| (r.variant.clone(), native_ms / t))
        })
        .collect();
    Some(Row {
        scenario: s.scenario.clone(),
        width: s.width,
        height: s.height,
        native_ms,
        pixel_fraction,
        speedups,
    })
}

/// Every row of the runs, ordered by pixel-bound fraction (unknown last), then by name.
pub fn rows(runs: &[Run]) -> Vec<Row> {
    let mut rows: Vec<Row> = runs
        .iter()
        .flat_map(|r| r.scenarios.iter())
        .filter_map(row)
        .collect();
    rows.sort_by(|a, b| {
        let key = |r: &Row| r.pixel_fraction.unwrap_or(f64::INFINITY);
        key(a)
            .total_cmp(&key(b))
            .then_with(|| a.scenario.cmp(&b.scenario))
    });
    rows
}

/// The Markdown table: one column per variant seen in any row (`-` where a row lacks it).
pub fn markdown(rows: &[Row]) -> String {
    let mut variants: Vec<&str> = Vec::new();
    for r in rows {
        for (v, _) in &r.speedups {
            if !variants.contains(&v.as_str()) {
                variants.push(v);
            }
        }
    }
    let mut out = String::from(
        "| scenario | size | native GPU ms | pixel-bound fraction | ideal checkerboard |",
    );
    for v in &variants {
        let _ = write!(out, " {} |", v.replace('|', "\\|"));
    }
    out.push_str("\n|---|---|---|---|---|");
    out.push_str(&"---|".repeat(variants.len()));
    out.push('\n');
    for r in rows {
        let (fraction, ideal) = match r.pixel_fraction {
            Some(p) => (
                format!("{:.0}%", p * 100.0),
                format!("{:.2}x", 1.0 / (1.0 - p / 2.0)),
            ),
            None => ("-".into(), "-".into()),
        };
        let _ = write!(
            out,
            "| {} | {}x{} | {:.3} | {fraction} | {ideal} |",
            r.scenario.replace('|', "\\|"),
            r.width,
            r.height,
            r.native_ms
        );
        for v in &variants {
            match r.speedups.iter().find(|(n, _)| n == v) {
                Some((_, s)) => {
                    let _ = write!(out, " {s:.2}x |");
                }
                None => out.push_str(" - |"),
            }
        }
        out.push('\n');
    }
    out
}
