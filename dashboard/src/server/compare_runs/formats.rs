//! The compare API's formats: JSON (the serialised `tessera_results::compare::Comparison`, its
//! wire format in `results/COMPARISON.md`, "Presentations", plus `by_speedup`), CSV (one row per
//! scenario, variant and measure, the engine's verdict words in `verdict`) and Markdown (the very
//! text `tessera compare` prints, `compare::markdown`).
//!
//! Not for: the page ([`super::view`]).

use axum::response::{IntoResponse, Response};
use axum::Json;
use serde::Serialize;
use tessera_results::compare::{markdown, Comparison, Time};
use tessera_results::measure::{Key, Measure};

use crate::server::export::{cell, csv, csv_response, md_response, Format};

/// The JSON body: the comparison, and `by_speedup` (times relative to each variant's baseline,
/// because the adapters or drivers differ) for clients of the earlier API.
#[derive(Serialize)]
struct Body<'a> {
    by_speedup: bool,
    /// `regressed`, `no regression` or `inconclusive` (`Comparison::decision`).
    decision: &'static str,
    /// Why the times could not be judged (`Comparison::undecided`); empty when they were.
    undecided: Vec<String>,
    /// What differs between A's and B's conditions (driver, clocks, throttling).
    environment: &'a [String],
    #[serde(flatten)]
    comparison: &'a Comparison,
}

pub const CSV_HEADER: [&str; 10] = [
    "scenario", "variant", "measure", "a", "b", "change", "low", "high", "p", "verdict",
];

/// One CSV row per (scenario, variant, measure): the frame time (`gpu_ms.median`, or
/// `gpu_ms.relative_to_baseline` on different adapters), each pass, the speedup, each metric.
pub fn csv_rows(c: &Comparison) -> Vec<Vec<String>> {
    let mut rows = Vec::new();
    let gpu_ms = Key::of(Measure::GpuMs).statistic("median");
    for (s, v) in c.variants() {
        let mut row = |measure: String,
                       a: Option<f64>,
                       b: Option<f64>,
                       time: Option<&Time>,
                       verdict: String| {
            let t = time.and_then(Time::tested);
            let interval = t.and_then(|t| t.interval);
            rows.push(vec![
                s.scenario.clone(),
                v.variant.clone(),
                measure,
                cell(a.filter(|x| x.is_finite())),
                cell(b.filter(|x| x.is_finite())),
                cell(t.map(|t| t.change)),
                cell(interval.map(|i| i[0])),
                cell(interval.map(|i| i[1])),
                cell(t.map(|t| t.p)),
                verdict,
            ]);
        };
        if c.same_adapter {
            row(
                gpu_ms.render(),
                v.gpu_ms.a,
                v.gpu_ms.b,
                Some(&v.time),
                v.time.words().into(),
            );
        } else {
            // Not a measure of a result: the median over the run's baseline's median.
            let cost = |s: Option<f64>| s.filter(|x| *x > 0.0).map(|x| 1.0 / x);
            row(
                "gpu_ms.relative_to_baseline".into(),
                cost(v.speedup.a),
                cost(v.speedup.b),
                Some(&v.time),
                v.time.words().into(),
            );
        }
        for p in &v.passes {
            row(
                gpu_ms.clone().pass(&p.name).render(),
                p.gpu_ms.a,
                p.gpu_ms.b,
                Some(&p.time),
                p.time.words().into(),
            );
        }
        if v.speedup.a.is_some() || v.speedup.b.is_some() {
            let moved = v
                .speedup_moved_with
                .as_ref()
                .map_or_else(String::new, |b| format!("moved with {b}"));
            row(
                Measure::Speedup.name().into(),
                v.speedup.a,
                v.speedup.b,
                None,
                moved,
            );
        }
        for m in &v.metrics {
            let verdict = match m.higher_is_better {
                None => "not judged".to_string(),
                Some(_) => serde_json::to_value(m.verdict)
                    .ok()
                    .and_then(|x| x.as_str().map(str::to_string))
                    .unwrap_or_default(),
            };
            row(m.name.clone(), m.values.a, m.values.b, None, verdict);
        }
    }
    rows
}

/// The comparison in `format`.
pub fn respond(c: &Comparison, environment: &[String], format: Format) -> Response {
    let name = format!("compare-{}-{}", c.a.run_id, c.b.run_id);
    match format {
        Format::Json => Json(Body {
            by_speedup: !c.same_adapter,
            decision: c.decision().words(),
            undecided: c.undecided(),
            environment,
            comparison: c,
        })
        .into_response(),
        Format::Csv => csv_response(csv(&CSV_HEADER, &csv_rows(c)), &format!("{name}.csv")),
        Format::Md => md_response(markdown::render(c), &format!("{name}.md")),
    }
}
