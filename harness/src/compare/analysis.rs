//! What changed between two runs, per scenario and variant: GPU time with a noise-aware verdict,
//! speedup against native, PSNR / SSIM / FLIP / JOD beyond a tolerance, and status. Pure: records in,
//! a [`Comparison`] out; the rules are written down in [`crate::compare`]'s module doc.

use tessera_results::{GateLevel, RunInfo, ScenarioResult, Status, Summary, VariantResult};

use super::load::Run;
use crate::run::gates;
use tessera_results::stats::{self, mann_whitney_p};
pub use tessera_results::stats::{frame_samples, ALPHA};

/// Metrics that get a column and a verdict, with the change each must exceed to count.
/// JOD: ColorVideoVDP (higher is better); 0.05 JOD is 1/20 of the step at which 75 % of viewers
/// prefer one over the other.
pub const JUDGED_METRICS: [(&str, &str, f64); 4] = [
    ("psnr", "PSNR dB", 0.1),
    ("ssim", "SSIM", 0.001),
    ("flip", "FLIP", 0.001),
    ("cvvdp", "JOD", 0.05),
];

#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// Smallest change of the median (in percent) that can be called faster or slower.
    pub threshold_pct: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options { threshold_pct: 5.0 }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Comparison {
    pub a: RunInfo,
    pub b: RunInfo,
    /// Same adapter name, backend, driver and driver info: times are compared in milliseconds.
    /// Otherwise they are compared by speedup against native on each adapter.
    pub same_adapter: bool,
    /// False when either run is on a CPU adapter (lavapipe): its timings measure CPU work and
    /// depend on other load on the machine, so time verdicts are shown but never a regression.
    pub timings_count: bool,
    pub options: Options,
    pub scenarios: Vec<ScenarioChange>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct ScenarioChange {
    pub scenario: String,
    /// `Some(A)` when only run A has this scenario, `Some(B)` when only B has it.
    pub only_in: Option<Side>,
    pub variants: Vec<VariantChange>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    A,
    B,
}

#[derive(Clone, Debug, PartialEq)]
pub struct VariantChange {
    pub variant: String,
    pub only_in: Option<Side>,
    /// Median per-frame GPU time (ms) in A and B.
    pub gpu_ms: (Option<f64>, Option<f64>),
    pub time: Time,
    /// Speedup against native on the same adapter, in A and B.
    pub speedup: (Option<f64>, Option<f64>),
    /// One per [`JUDGED_METRICS`] entry, in that order.
    pub metrics: Vec<MetricChange>,
    pub status: (Option<String>, Option<String>),
    pub status_verdict: Verdict,
    /// Energy per measured frame (mJ) in A and B, where the adapter's sensors recorded it.
    pub energy_mj: (Option<f64>, Option<f64>),
    /// Native's energy per frame over this variant's, in A and B.
    pub energy_saving: (Option<f64>, Option<f64>),
    /// Whether the result was throttled during its measured frames, in A and B (`None` without
    /// sensors): its time then reads lowered clocks.
    pub throttled: (Option<bool>, Option<bool>),
}

/// The time verdict and what it was computed from.
#[derive(Clone, Debug, PartialEq)]
pub enum Time {
    /// `change` is the relative change of the median (of milliseconds on one adapter, of the cost
    /// relative to native across adapters); `p` the Mann-Whitney p-value.
    Compared {
        change: f64,
        p: f64,
        verdict: Verdict,
        by_speedup: bool,
    },
    /// Native itself when compared by speedup.
    Baseline,
    NotCompared(&'static str),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    Better,
    Worse,
    Same,
}

#[derive(Clone, Debug, PartialEq)]
pub struct MetricChange {
    pub name: &'static str,
    pub values: (Option<f64>, Option<f64>),
    pub verdict: Verdict,
}

impl VariantChange {
    /// Whether anything in this row is a regression; the time verdict only if `timings_count`.
    pub fn regressed(&self, timings_count: bool) -> bool {
        self.status_verdict == Verdict::Worse
            || (timings_count
                && matches!(
                    self.time,
                    Time::Compared {
                        verdict: Verdict::Worse,
                        ..
                    }
                ))
            || self.metrics.iter().any(|m| m.verdict == Verdict::Worse)
    }
}

fn median(samples: &[f64]) -> f64 {
    Summary::of(samples).map_or(f64::NAN, |s| s.median)
}

/// `ok`, `gate failed`, `skipped: reason`, `failed: error`.
pub fn status_label(r: &VariantResult) -> String {
    match &r.status {
        Status::Ok if r.gates.iter().any(|g| g.level == GateLevel::Fail) => {
            "gate failed".to_string()
        }
        Status::Ok => "ok".to_string(),
        Status::Skipped { reason } => format!("skipped: {reason}"),
        Status::Failed { error } => format!("failed: {error}"),
    }
}

fn is_failure(r: &VariantResult) -> bool {
    matches!(r.status, Status::Failed { .. }) || r.gates.iter().any(|g| g.level == GateLevel::Fail)
}

fn same_adapter(a: &RunInfo, b: &RunInfo) -> bool {
    let (x, y) = (&a.adapter, &b.adapter);
    x.name == y.name
        && x.backend == y.backend
        && x.driver == y.driver
        && x.driver_info == y.driver_info
}

/// Median GPU time of the scenario's ok `native` variant.
fn native_ms(s: &ScenarioResult) -> Option<f64> {
    s.results
        .iter()
        .find(|r| r.variant == "native" && r.status == Status::Ok)
        .and_then(frame_samples)
        .map(|v| median(&v))
}

fn verdict_of(change: f64, p: f64, threshold_pct: f64) -> Verdict {
    match stats::verdict(change, p, threshold_pct) {
        stats::TimeVerdict::Same => Verdict::Same,
        stats::TimeVerdict::Slower => Verdict::Worse,
        stats::TimeVerdict::Faster => Verdict::Better,
    }
}

fn compare_time(
    a: (&ScenarioResult, &VariantResult),
    b: (&ScenarioResult, &VariantResult),
    by_speedup: bool,
    opts: &Options,
) -> Time {
    if a.1.status != Status::Ok || b.1.status != Status::Ok {
        return Time::NotCompared("not ok in both");
    }
    let (Some(sa), Some(sb)) = (frame_samples(a.1), frame_samples(b.1)) else {
        return Time::NotCompared("not timed");
    };
    let (sa, sb) = if by_speedup {
        if a.1.variant == "native" {
            return Time::Baseline;
        }
        let (Some(na), Some(nb)) = (native_ms(a.0), native_ms(b.0)) else {
            return Time::NotCompared("no timed native in both");
        };
        let scale = |s: Vec<f64>, n: f64| s.into_iter().map(|x| x / n).collect::<Vec<_>>();
        (scale(sa, na), scale(sb, nb))
    } else {
        (sa, sb)
    };
    let change = median(&sb) / median(&sa) - 1.0;
    let p = mann_whitney_p(&sa, &sb);
    Time::Compared {
        change,
        p,
        verdict: verdict_of(change, p, opts.threshold_pct),
        by_speedup,
    }
}

/// The metric's value and whether higher is better: the measure table's direction, or for a
/// metric it does not know, the record's.
fn metric_value(r: &VariantResult, name: &str) -> Option<(f64, bool)> {
    let known = tessera_results::measure::Measure::from_name(name);
    r.metrics.iter().find(|m| m.name == name).map(|m| {
        let higher = known.map_or(m.higher_is_better, |k| k.direction().higher_is_better());
        (m.value, higher)
    })
}

/// Beyond `tol` in the direction that is worse. Infinite PSNR (identical frames) compares as
/// larger than any finite value.
fn compare_metric(
    name: &'static str,
    tol: f64,
    a: Option<&VariantResult>,
    b: Option<&VariantResult>,
) -> MetricChange {
    let va = a.and_then(|r| metric_value(r, name));
    let vb = b.and_then(|r| metric_value(r, name));
    let verdict = match (va, vb) {
        (Some((x, higher)), Some((y, _))) if x != y => {
            let (gain, loss) = if higher {
                (y - x, x - y)
            } else {
                (x - y, y - x)
            };
            if loss > tol {
                Verdict::Worse
            } else if gain > tol {
                Verdict::Better
            } else {
                Verdict::Same
            }
        }
        _ => Verdict::Same,
    };
    MetricChange {
        name,
        values: (va.map(|v| v.0), vb.map(|v| v.0)),
        verdict,
    }
}

fn compare_status(
    a: Option<&VariantResult>,
    b: Option<&VariantResult>,
    same_adapter: bool,
) -> Verdict {
    match (a, b) {
        (_, Some(y)) if is_failure(y) && !a.is_some_and(is_failure) => Verdict::Worse,
        (Some(x), Some(y)) if is_failure(x) && !is_failure(y) => Verdict::Better,
        (Some(x), Some(y))
            if same_adapter
                && x.status == Status::Ok
                && matches!(y.status, Status::Skipped { .. }) =>
        {
            Verdict::Worse
        }
        _ => Verdict::Same,
    }
}

fn speedup(s: &ScenarioResult, r: &VariantResult) -> Option<f64> {
    if r.status != Status::Ok {
        return None;
    }
    Some(native_ms(s)? / median(&frame_samples(r)?))
}

fn compare_scenario(
    a: Option<&ScenarioResult>,
    b: Option<&ScenarioResult>,
    same: bool,
    opts: &Options,
) -> ScenarioChange {
    let scenario = a.or(b).map(|s| s.scenario.clone()).unwrap_or_default();
    let mut names: Vec<&str> = Vec::new();
    for s in [a, b].into_iter().flatten() {
        for r in &s.results {
            if !names.contains(&r.variant.as_str()) {
                names.push(&r.variant);
            }
        }
    }
    fn find<'a>(
        s: Option<&'a ScenarioResult>,
        name: &str,
    ) -> Option<(&'a ScenarioResult, &'a VariantResult)> {
        s.and_then(|s| s.results.iter().find(|r| r.variant == name).map(|r| (s, r)))
    }
    let variants = names
        .iter()
        .map(|name| {
            let (ra, rb) = (find(a, name), find(b, name));
            let time = match (ra, rb) {
                (Some(x), Some(y)) => compare_time(x, y, !same, opts),
                _ => Time::NotCompared("not in both"),
            };
            let va = ra.map(|x| x.1);
            let vb = rb.map(|x| x.1);
            VariantChange {
                variant: name.to_string(),
                only_in: match (ra, rb) {
                    (Some(_), None) => Some(Side::A),
                    (None, Some(_)) => Some(Side::B),
                    _ => None,
                },
                gpu_ms: (
                    va.and_then(frame_samples).map(|s| median(&s)),
                    vb.and_then(frame_samples).map(|s| median(&s)),
                ),
                time,
                speedup: (
                    ra.and_then(|(s, r)| speedup(s, r)),
                    rb.and_then(|(s, r)| speedup(s, r)),
                ),
                metrics: JUDGED_METRICS
                    .iter()
                    .map(|(m, _, tol)| compare_metric(m, *tol, va, vb))
                    .collect(),
                status: (va.map(status_label), vb.map(status_label)),
                status_verdict: compare_status(va, vb, same),
                energy_mj: (va.and_then(gates::energy_mj), vb.and_then(gates::energy_mj)),
                energy_saving: (
                    ra.and_then(|(s, r)| gates::energy_saving(&s.results, r)),
                    rb.and_then(|(s, r)| gates::energy_saving(&s.results, r)),
                ),
                throttled: (va.and_then(gates::throttled), vb.and_then(gates::throttled)),
            }
        })
        .collect();
    ScenarioChange {
        scenario,
        only_in: match (a, b) {
            (Some(_), None) => Some(Side::A),
            (None, Some(_)) => Some(Side::B),
            _ => None,
        },
        variants,
    }
}

/// Compares run `b` (new) against run `a` (base): every scenario and variant present in either.
pub fn compare(a: &Run, b: &Run, opts: &Options) -> Comparison {
    let same = same_adapter(&a.info, &b.info);
    let mut names: Vec<&str> = a.scenarios.iter().map(|s| s.scenario.as_str()).collect();
    for s in &b.scenarios {
        if !names.contains(&s.scenario.as_str()) {
            names.push(&s.scenario);
        }
    }
    fn find<'a>(r: &'a Run, n: &str) -> Option<&'a ScenarioResult> {
        r.scenarios.iter().find(|s| s.scenario == n)
    }
    let scenarios = names
        .iter()
        .map(|n| compare_scenario(find(a, n), find(b, n), same, opts))
        .collect();
    Comparison {
        a: a.info.clone(),
        b: b.info.clone(),
        same_adapter: same,
        timings_count: a.info.adapter.device_type != "cpu" && b.info.adapter.device_type != "cpu",
        options: opts.clone(),
        scenarios,
    }
}

impl Comparison {
    /// Whether any variant regressed beyond noise (time, a judged metric or its status).
    pub fn regressed(&self) -> bool {
        self.scenarios
            .iter()
            .flat_map(|s| &s.variants)
            .any(|v| v.regressed(self.timings_count))
    }
}
