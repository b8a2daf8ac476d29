//! Metrics of one variant in two runs (`COMPARISON.md`, "Metrics"): every metric either run has,
//! judged better or worse by its measure's direction (the measure table's, or the record's own
//! for a metric the table does not know) once it moved by more than its tolerance. References
//! are rendered in the same run, so metrics are not noisy; the tolerance absorbs rounding and
//! changes nobody could see.
//!
//! Not for: which metrics a presentation gives a column ([`super::markdown::COLUMNS`]).

use serde::Serialize;

use crate::measure::{metric_direction, Direction, Measure};
use crate::{MetricRecord, VariantResult};

use super::{findings::Verdict, Pair};

/// The tolerance of a measure without one of its own ([`crate::measure::Info::tolerance`]), relative to the
/// larger magnitude.
pub const RELATIVE_TOLERANCE: f64 = 0.001;

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MetricComparison {
    pub name: String,
    /// The measure's label (`PSNR dB`), or the name of a metric the table does not know.
    pub label: String,
    /// Aggregates (`value`); `+inf` (identical frames under PSNR) serialises as `null`.
    pub values: Pair<f64>,
    /// `None` for a metric without a direction (a fact, not a goal): shown, never judged.
    pub higher_is_better: Option<bool>,
    pub verdict: Verdict,
}

/// The direction of a metric: the measure table's, else the record's own (a technique's check
/// carries it; `None` for one without a direction).
fn direction(m: &MetricRecord) -> Option<bool> {
    match metric_direction(m) {
        Direction::Neither => None,
        d => Some(d.higher_is_better()),
    }
}

/// Worse or better when the value moved beyond the tolerance in that direction. Infinite PSNR
/// (identical frames) is larger than any finite value, so losing it is worse.
pub fn judge(name: &str, a: f64, b: f64, higher_is_better: bool) -> Verdict {
    if a == b || a.is_nan() || b.is_nan() {
        return Verdict::Same;
    }
    let tolerance = Measure::from_name(name)
        .and_then(|m| m.info().tolerance)
        .unwrap_or_else(|| RELATIVE_TOLERANCE * a.abs().max(b.abs()));
    let gain = if higher_is_better { b - a } else { a - b };
    if gain < -tolerance {
        Verdict::Worse
    } else if gain > tolerance {
        Verdict::Better
    } else {
        Verdict::Same
    }
}

/// Every metric of `a` and `b`, A's first.
pub(crate) fn compare(
    a: Option<&VariantResult>,
    b: Option<&VariantResult>,
) -> Vec<MetricComparison> {
    let all = a.into_iter().chain(b).flat_map(|r| &r.metrics);
    let mut out: Vec<MetricComparison> = Vec::new();
    for m in all {
        if out.iter().any(|x| x.name == m.name) {
            continue;
        }
        let value = |r: Option<&VariantResult>| {
            r?.metrics
                .iter()
                .find(|x| x.name == m.name)
                .map(|x| x.value)
        };
        let values = Pair::new(value(a), value(b));
        let higher_is_better = direction(m);
        let verdict = match (values.a, values.b, higher_is_better) {
            (Some(x), Some(y), Some(h)) => judge(&m.name, x, y, h),
            _ => Verdict::Same,
        };
        out.push(MetricComparison {
            name: m.name.clone(),
            label: Measure::from_name(&m.name).map_or_else(|| m.name.clone(), |x| x.label().into()),
            values,
            higher_is_better,
            verdict,
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tolerances_and_directions() {
        assert_eq!(judge("psnr", 30.0, 29.5, true), Verdict::Worse);
        assert_eq!(judge("psnr", 30.0, 30.05, true), Verdict::Same);
        assert_eq!(judge("psnr", f64::INFINITY, 60.0, true), Verdict::Worse);
        assert_eq!(judge("psnr", 40.0, f64::INFINITY, true), Verdict::Better);
        assert_eq!(judge("flip", 0.1, 0.1005, false), Verdict::Same);
        assert_eq!(judge("flip", 0.1, 0.12, false), Verdict::Worse);
        assert_eq!(judge("flip", 0.12, 0.1, false), Verdict::Better);
        // Relative tolerance for the rest: 0.1%.
        assert_eq!(judge("tde", 2.0, 2.001, false), Verdict::Same);
        assert_eq!(judge("tde", 2.0, 2.01, false), Verdict::Worse);
        let record = |name: &str, higher: bool, check: Option<crate::Check>| MetricRecord {
            name: name.into(),
            per_frame: vec![],
            frames: vec![],
            value: 0.0,
            higher_is_better: higher,
            frame_stats: None,
            metrics_device: None,
            check,
        };
        let fact = crate::Check {
            unit: "x".into(),
            direction: Direction::Neither,
        };
        assert_eq!(
            direction(&record("invocations-over-model", false, Some(fact))),
            None
        );
        assert_eq!(direction(&record("ssim", false, None)), Some(true));
        assert_eq!(direction(&record("a-new-metric", true, None)), Some(true));
    }
}
