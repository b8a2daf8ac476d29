//! The regressions and improvements of a comparison, each counted once (`COMPARISON.md`,
//! "Findings"): a frame time that is slower or faster (only where timings count), a metric that
//! got worse or better, a status that got worse or better. Speedups are never findings of their
//! own: on one adapter a speedup moves when the variant's time moves (counted on the variant) or
//! when its baseline's time moves (counted once, on the baseline, with the variants whose speedups
//! moved with it named beside it), so a slower `native` is one regression, not one regression and
//! an improvement per variant measured against it.
//!
//! Not for: presenting them (the page, the CSV and [`super::markdown`]).

use serde::Serialize;

use crate::stats::TimeVerdict;

use super::words::{change_with_interval, p_value};
use super::{ScenarioComparison, Time, VariantComparison};

/// Which way something moved, once noise and tolerances are accounted for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    Better,
    Worse,
    Same,
}

/// One regression or improvement.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Finding {
    pub scenario: String,
    pub variant: String,
    /// `worse` (a regression) or `better` (an improvement).
    pub verdict: Verdict,
    /// `GPU time`, `GPU time relative to native`, a metric's label, or `status`.
    pub what: String,
    /// The change: `+18.3% [+16.0%, +20.6%] (p<0.001)`, `30.00 → 29.50`, `ok → gate failed`.
    pub change: String,
    /// Variants of the scenario whose speedup moved with this (baseline's) time change: shown
    /// here, counted nowhere else.
    pub moves_speedups_of: Vec<String>,
}

/// On one adapter: marks each variant whose baseline's own frame time is slower or faster, so
/// its speedup's change is read as the baseline's.
pub(crate) fn attribute_speedups(variants: &mut [VariantComparison]) {
    let moved: Vec<String> = variants
        .iter()
        .filter(|v| {
            matches!(
                v.time_verdict(),
                Some(TimeVerdict::Slower | TimeVerdict::Faster)
            )
        })
        .map(|v| v.variant.clone())
        .collect();
    for v in variants.iter_mut() {
        let base = v.baseline.b.clone().or_else(|| v.baseline.a.clone());
        if let Some(base) = base.filter(|b| moved.contains(b)) {
            if v.speedup.a.is_some() && v.speedup.b.is_some() {
                v.speedup_moved_with = Some(base);
            }
        }
    }
}

fn number(name: &str, v: f64) -> String {
    if v.is_infinite() {
        "inf".to_string()
    } else if name.starts_with("psnr") {
        format!("{v:.2}")
    } else {
        format!("{v:.4}")
    }
}

/// `a → b`, or one value when both are the same, `-` for a missing side.
pub fn pair_text(a: Option<String>, b: Option<String>) -> String {
    match (a, b) {
        (Some(x), Some(y)) if x == y => x,
        (None, None) => "-".to_string(),
        (x, y) => format!(
            "{} → {}",
            x.unwrap_or_else(|| "-".into()),
            y.unwrap_or_else(|| "-".into())
        ),
    }
}

/// A metric's values as the findings and the Markdown write them.
pub fn metric_values(m: &super::MetricComparison) -> String {
    pair_text(
        m.values.a.map(|v| number(&m.name, v)),
        m.values.b.map(|v| number(&m.name, v)),
    )
}

fn of_variant(s: &ScenarioComparison, v: &VariantComparison, timings_count: bool) -> Vec<Finding> {
    let mut out = Vec::new();
    let mut push = |verdict: Verdict, what: String, change: String, moves: Vec<String>| {
        out.push(Finding {
            scenario: s.scenario.clone(),
            variant: v.variant.clone(),
            verdict,
            what,
            change,
            moves_speedups_of: moves,
        })
    };
    if let Time::Tested { test, relative_to } = &v.time {
        let verdict = match test.verdict {
            TimeVerdict::Slower => Some(Verdict::Worse),
            TimeVerdict::Faster => Some(Verdict::Better),
            _ => None,
        };
        if let Some(verdict) = verdict.filter(|_| timings_count) {
            let what = match (&relative_to.a, &relative_to.b) {
                (Some(x), Some(y)) if x == y => format!("GPU time relative to {x}"),
                (Some(x), Some(y)) => format!("GPU time relative to {x} → {y}"),
                _ => "GPU time".to_string(),
            };
            let moves = s
                .variants
                .iter()
                .filter(|w| w.speedup_moved_with.as_deref() == Some(v.variant.as_str()))
                .map(|w| w.variant.clone())
                .collect();
            push(
                verdict,
                what,
                format!("{} ({})", change_with_interval(test), p_value(test.p)),
                moves,
            );
        }
    }
    for m in &v.metrics {
        if m.verdict != Verdict::Same {
            push(m.verdict, m.label.clone(), metric_values(m), Vec::new());
        }
    }
    if v.status_verdict != Verdict::Same {
        push(
            v.status_verdict,
            "status".into(),
            pair_text(v.status.a.clone(), v.status.b.clone()),
            Vec::new(),
        );
    }
    out
}

/// Every finding, in scenario and variant order.
pub(crate) fn collect(scenarios: &[ScenarioComparison], timings_count: bool) -> Vec<Finding> {
    scenarios
        .iter()
        .flat_map(|s| {
            s.variants
                .iter()
                .flat_map(move |v| of_variant(s, v, timings_count))
        })
        .collect()
}
