//! The one comparison of two runs: run A (base) and run B (new) in, a [`Comparison`] out, per
//! scenario and variant. `tessera compare`, the dashboard's compare page and its API all present
//! this value, so they cannot disagree; the rules are written down once, in `COMPARISON.md` at the
//! crate root, and each submodule cites the section it implements:
//!
//! - [`baseline`]: which adapter counts as the same, and each variant's baseline ("Baselines");
//! - [`time`]: frame and pass times, in milliseconds or relative to the baseline ("Time");
//! - [`metrics`]: image and technique metrics by their measure's direction ("Metrics");
//! - [`status`]: failures, gates and skips ("Status");
//! - [`findings`]: the regressions and improvements, each counted once, a baseline's change
//!   attributed to the baseline ("Findings");
//! - [`markdown`]: the Markdown of `tessera compare` and the dashboard's export.
//!
//! Pure: records in, values out; no files, no store, no clock. Not for: history over many runs
//! and change points (the dashboard's regression detection).

use std::collections::BTreeMap;

use serde::Serialize;

use crate::{folder, measure, RunInfo, ScenarioResult, VariantResult};

pub mod baseline;
pub mod findings;
pub mod markdown;
pub mod metrics;
pub mod status;
pub mod time;
pub mod words;

pub use crate::stats::{TimeChange, TimeVerdict, ALPHA, DEFAULT_THRESHOLD_PCT};
pub use baseline::same_adapter;
pub use findings::{Finding, Verdict};
pub use metrics::MetricComparison;
pub use time::{PassComparison, Time};

/// A frame-time change of at least this many σ of its series' night-to-night noise is large
/// enough to be called slower or faster, even below the fixed threshold (`COMPARISON.md`, "Time").
pub const NOISE_SIGMAS: f64 = 5.0;

/// The noise rule never lowers the threshold below this (percent): the smallest change regression
/// detection alerts on.
pub const NOISE_FLOOR_PCT: f64 = 1.0;

/// What the caller may choose.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Options {
    /// Smallest time change (percent) that can be called slower or faster.
    pub threshold_pct: f64,
    /// Night-to-night noise of each variant's frame-time series on B's adapter, as a fraction of
    /// its level (scenario → variant → σ), where a history knows it (the dashboard's detection
    /// estimate). A variant with a noise σ is called slower or faster from
    /// `max(NOISE_SIGMAS · σ, NOISE_FLOOR_PCT)` when that is below `threshold_pct`.
    pub noise: BTreeMap<String, BTreeMap<String, f64>>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            threshold_pct: DEFAULT_THRESHOLD_PCT,
            noise: BTreeMap::new(),
        }
    }
}

impl Options {
    /// The threshold (percent) a variant's frame time is judged with, and the noise σ that set
    /// it (`None` when the fixed threshold applies).
    pub fn threshold_for(&self, scenario: &str, variant: &str) -> (f64, Option<f64>) {
        let sigma = self
            .noise
            .get(scenario)
            .and_then(|v| v.get(variant))
            .copied()
            .filter(|s| s.is_finite() && *s >= 0.0);
        match sigma {
            Some(s) => {
                let by_noise = (NOISE_SIGMAS * s * 100.0).max(NOISE_FLOOR_PCT);
                if by_noise < self.threshold_pct {
                    (by_noise, Some(s))
                } else {
                    (self.threshold_pct, Some(s))
                }
            }
            None => (self.threshold_pct, None),
        }
    }
}

/// One run as every reader holds it: [`folder::Run`] (`tessera compare`) or the dashboard store's
/// run record and scenarios.
#[derive(Clone, Copy, Debug)]
pub struct RunRef<'a> {
    pub info: &'a RunInfo,
    pub scenarios: &'a [ScenarioResult],
}

impl<'a> From<&'a folder::Run> for RunRef<'a> {
    fn from(r: &'a folder::Run) -> Self {
        RunRef {
            info: &r.info,
            scenarios: &r.scenarios,
        }
    }
}

/// A value in run A and in run B; either may be missing.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Pair<T> {
    pub a: Option<T>,
    pub b: Option<T>,
}

impl<T> Pair<T> {
    pub fn new(a: Option<T>, b: Option<T>) -> Self {
        Pair { a, b }
    }

    /// Both sides through `f`.
    pub fn map<U>(&self, mut f: impl FnMut(&T) -> Option<U>) -> Pair<U> {
        Pair {
            a: self.a.as_ref().and_then(&mut f),
            b: self.b.as_ref().and_then(f),
        }
    }
}

/// The run a scenario or variant is in when it is in only one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Side {
    A,
    B,
}

/// The rule the verdicts were reached with, as every presentation states it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Rule {
    /// Significance level of the Mann-Whitney U test ([`ALPHA`]).
    pub alpha: f64,
    /// The shift's interval is at confidence 1 - `alpha`.
    pub confidence: f64,
    pub threshold_pct: f64,
    /// Frames per side at which the test can first reach p < `alpha`.
    pub frames_needed: usize,
    /// Whether some variants' thresholds follow their series' noise ([`Options::noise`]): a
    /// change of at least `noise_sigmas` σ (and [`NOISE_FLOOR_PCT`]) is then called too.
    pub noise_sigmas: Option<f64>,
}

impl Rule {
    /// `time: Mann-Whitney U p < 0.01 and a Hodges-Lehmann shift of at least 5%; too few frames
    /// below 5 per side`.
    pub fn sentence(&self) -> String {
        let noise = match self.noise_sigmas {
            Some(k) => format!(
                " (or {k}σ of the series' nightly noise, at least {NOISE_FLOOR_PCT}%, where a history gives it)"
            ),
            None => String::new(),
        };
        format!(
            "time: Mann-Whitney U p < {} and a Hodges-Lehmann shift of at least {}%{noise}; too few frames below {} per side",
            self.alpha, self.threshold_pct, self.frames_needed
        )
    }
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Comparison {
    pub a: RunInfo,
    pub b: RunInfo,
    /// Same adapter name, backend, driver and driver info: times are compared in milliseconds.
    /// Otherwise relative to each variant's baseline on each adapter.
    pub same_adapter: bool,
    /// False when either run is on a CPU adapter (lavapipe): its timings measure CPU work and the
    /// machine's load, so time verdicts are shown but never count.
    pub timings_count: bool,
    pub rule: Rule,
    pub scenarios: Vec<ScenarioComparison>,
    /// The regressions and improvements, each counted once ([`findings`]).
    pub findings: Vec<Finding>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ScenarioComparison {
    pub scenario: String,
    pub only_in: Option<Side>,
    pub variants: Vec<VariantComparison>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct VariantComparison {
    pub variant: String,
    pub technique: String,
    pub only_in: Option<Side>,
    /// `ok`, `gate failed`, `skipped: reason`, `failed: error` ([`status::label`]).
    pub status: Pair<String>,
    pub status_verdict: Verdict,
    /// Median per-frame GPU time, ms.
    pub gpu_ms: Pair<f64>,
    /// Measured frames timed.
    pub frames: Pair<usize>,
    /// The frame time's test ([`time`]).
    pub time: Time,
    /// The threshold (percent) the frame time was judged with: the fixed one, or lower where its
    /// series' noise says a smaller change stands out ([`Options::threshold_for`]).
    pub threshold_pct: f64,
    /// The night-to-night noise σ of the variant's frame-time series (fraction of its level),
    /// where the caller knew it.
    pub noise: Option<f64>,
    /// Per pass, on the same adapter: where a frame-time change is.
    pub passes: Vec<PassComparison>,
    /// The variant this one's speedup is computed against, in each run ([`baseline::of`]).
    pub baseline: Pair<String>,
    /// The baseline's median GPU time over this variant's.
    pub speedup: Pair<f64>,
    /// Set when the baseline's own time changed (slower or faster) on the same adapter: the
    /// speedup moved with it, and that change is counted once, on the baseline.
    pub speedup_moved_with: Option<String>,
    /// Every metric in either run, by name in A's order then B's.
    pub metrics: Vec<MetricComparison>,
    /// Energy per measured frame (mJ), where sensors recorded it. Shown, not judged.
    pub energy_mj: Pair<f64>,
    /// The baseline's energy per frame over this variant's.
    pub energy_saving: Pair<f64>,
    /// Throttled during its measured frames (`None` without sensors).
    pub throttled: Pair<bool>,
    /// Saved images in each run.
    pub images: Pair<bool>,
}

impl VariantComparison {
    /// The time test's verdict, where the frame times were tested.
    pub fn time_verdict(&self) -> Option<TimeVerdict> {
        self.time.tested().map(|t| t.verdict)
    }
}

/// What a comparison as a whole says.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Decision {
    /// Something counted as a regression.
    Regressed,
    /// Every counted time, metric and status was judged and none got worse.
    NoRegression,
    /// Nothing got worse, but the times could not be judged ([`Comparison::undecided`] says why).
    Inconclusive,
}

impl Decision {
    /// `regressed`, `no regression`, `inconclusive`.
    pub fn words(self) -> &'static str {
        match self {
            Decision::Regressed => "regressed",
            Decision::NoRegression => "no regression",
            Decision::Inconclusive => "inconclusive",
        }
    }
}

impl Comparison {
    /// The comparison's verdict: regressed, no regression, or inconclusive when nothing regressed
    /// but the times could not be judged.
    pub fn decision(&self) -> Decision {
        if self.regressed() {
            Decision::Regressed
        } else if self.undecided().is_empty() {
            Decision::NoRegression
        } else {
            Decision::Inconclusive
        }
    }

    /// Why the times could not be judged, one phrase each: a CPU adapter, too few frames, nothing
    /// timed in both runs. Empty when they were.
    pub fn undecided(&self) -> Vec<String> {
        let mut why = Vec::new();
        if !self.timings_count {
            let cpu: Vec<&str> = [&self.a, &self.b]
                .iter()
                .filter(|r| r.adapter.device_type == "cpu")
                .map(|r| r.adapter.name.as_str())
                .collect();
            let name = cpu.first().copied().unwrap_or("a CPU adapter");
            why.push(format!(
                "a CPU adapter ({name}): its times measure CPU work and the machine's load and are not judged"
            ));
            return why;
        }
        let timed = self
            .variants()
            .filter(|(_, v)| v.time.tested().is_some())
            .count();
        let few = self.too_few_frames().count();
        if timed == 0 {
            why.push("no variant was timed in both runs".to_string());
        } else if few > 0 {
            why.push(format!(
                "too few frames in {few} of {timed} timed variants ({} per side needed)",
                self.rule.frames_needed
            ));
        }
        why
    }

    /// Whether anything counted as a regression.
    pub fn regressed(&self) -> bool {
        self.findings.iter().any(|f| f.verdict == Verdict::Worse)
    }

    /// Findings with verdict `v`.
    pub fn findings_of(&self, v: Verdict) -> impl Iterator<Item = &Finding> {
        self.findings.iter().filter(move |f| f.verdict == v)
    }

    /// Every (scenario, variant) whose frame times were too few to tell.
    pub fn too_few_frames(
        &self,
    ) -> impl Iterator<Item = (&ScenarioComparison, &VariantComparison)> {
        self.variants()
            .filter(|(_, v)| v.time_verdict() == Some(TimeVerdict::TooFewFrames))
    }

    /// Every (scenario, variant), in order.
    pub fn variants(&self) -> impl Iterator<Item = (&ScenarioComparison, &VariantComparison)> {
        self.scenarios
            .iter()
            .flat_map(|s| s.variants.iter().map(move |v| (s, v)))
    }

    /// How many variants' frame times got verdict `v`.
    pub fn count_time(&self, v: TimeVerdict) -> usize {
        self.variants()
            .filter(|(_, x)| x.time_verdict() == Some(v))
            .count()
    }
}

/// Names in `a`'s order, then those only in `b`.
fn union<'x>(a: impl Iterator<Item = &'x str>, b: impl Iterator<Item = &'x str>) -> Vec<&'x str> {
    let mut names: Vec<&str> = Vec::new();
    for n in a.chain(b) {
        if !names.contains(&n) {
            names.push(n);
        }
    }
    names
}

fn only_in<T>(a: &Option<T>, b: &Option<T>) -> Option<Side> {
    match (a, b) {
        (Some(_), None) => Some(Side::A),
        (None, Some(_)) => Some(Side::B),
        _ => None,
    }
}

/// One variant's record in one run, with its scenario's results (to find its baseline).
#[derive(Clone, Copy)]
pub(crate) struct InRun<'a> {
    pub results: &'a [VariantResult],
    pub r: &'a VariantResult,
}

fn compare_variant(
    scenario: &str,
    a: Option<InRun>,
    b: Option<InRun>,
    same: bool,
    opts: &Options,
) -> VariantComparison {
    let first = a.or(b).expect("a variant is in at least one run");
    // Noise of a series in milliseconds: only where times are compared in milliseconds.
    let (threshold_pct, noise) = if same {
        opts.threshold_for(scenario, &first.r.variant)
    } else {
        (opts.threshold_pct, None)
    };
    let va = a.map(|x| x.r);
    let vb = b.map(|x| x.r);
    let base_a = a.and_then(baseline::of);
    let base_b = b.and_then(baseline::of);
    let speedup = |x: Option<InRun>, base: Option<&VariantResult>| {
        let (x, base) = (x?, base?);
        ratio(measure::gpu_ms(base)?, measure::gpu_ms(x.r)?, x.r)
    };
    let energy = |x: Option<InRun>, base: Option<&VariantResult>| {
        let (x, base) = (x?, base?);
        ratio(measure::energy_mj(base)?, measure::energy_mj(x.r)?, x.r)
    };
    let pair = |f: fn(&VariantResult) -> Option<f64>| Pair::new(va.and_then(f), vb.and_then(f));
    VariantComparison {
        variant: first.r.variant.clone(),
        technique: first.r.technique.clone(),
        only_in: only_in(&a.map(|_| ()), &b.map(|_| ())),
        status: Pair::new(va.map(status::label), vb.map(status::label)),
        status_verdict: status::verdict(va, vb, same),
        gpu_ms: pair(measure::gpu_ms),
        frames: Pair::new(
            va.and_then(crate::stats::frame_samples).map(|s| s.len()),
            vb.and_then(crate::stats::frame_samples).map(|s| s.len()),
        ),
        time: time::frame(a, b, same, threshold_pct),
        threshold_pct,
        noise,
        passes: match (va, vb) {
            (Some(x), Some(y)) if same => time::passes(x, y, opts),
            _ => Vec::new(),
        },
        baseline: Pair::new(
            base_a.map(|r| r.variant.clone()),
            base_b.map(|r| r.variant.clone()),
        ),
        speedup: Pair::new(speedup(a, base_a), speedup(b, base_b)),
        speedup_moved_with: None,
        metrics: metrics::compare(va, vb),
        energy_mj: pair(measure::energy_mj),
        energy_saving: Pair::new(energy(a, base_a), energy(b, base_b)),
        throttled: Pair::new(
            va.and_then(|r| Some(r.conditions.as_ref()?.recorded()?.throttled)),
            vb.and_then(|r| Some(r.conditions.as_ref()?.recorded()?.throttled)),
        ),
        images: Pair::new(
            va.map(|r| !r.images.is_empty()),
            vb.map(|r| !r.images.is_empty()),
        ),
    }
}

/// `base / of` for an ok result with positive values.
fn ratio(base: f64, of: f64, r: &VariantResult) -> Option<f64> {
    (r.status == crate::Status::Ok && base > 0.0 && of > 0.0).then(|| base / of)
}

fn compare_scenario(
    a: Option<&ScenarioResult>,
    b: Option<&ScenarioResult>,
    same: bool,
    opts: &Options,
) -> ScenarioComparison {
    let names = union(
        a.iter()
            .flat_map(|s| s.results.iter().map(|r| r.variant.as_str())),
        b.iter()
            .flat_map(|s| s.results.iter().map(|r| r.variant.as_str())),
    );
    fn find<'a>(s: Option<&'a ScenarioResult>, name: &str) -> Option<InRun<'a>> {
        let s = s?;
        let r = s.results.iter().find(|r| r.variant == name)?;
        Some(InRun {
            results: &s.results,
            r,
        })
    }
    let scenario = a.or(b).map(|s| s.scenario.as_str()).unwrap_or_default();
    let mut variants: Vec<VariantComparison> = names
        .iter()
        .map(|n| compare_variant(scenario, find(a, n), find(b, n), same, opts))
        .collect();
    if same {
        findings::attribute_speedups(&mut variants);
    }
    ScenarioComparison {
        scenario: a.or(b).map(|s| s.scenario.clone()).unwrap_or_default(),
        only_in: only_in(&a, &b),
        variants,
    }
}

/// Compares run `b` (new) against run `a` (base): every scenario and variant in either.
pub fn compare(a: RunRef, b: RunRef, opts: &Options) -> Comparison {
    let same = same_adapter(a.info, b.info);
    let names = union(
        a.scenarios.iter().map(|s| s.scenario.as_str()),
        b.scenarios.iter().map(|s| s.scenario.as_str()),
    );
    fn find<'a>(r: RunRef<'a>, n: &str) -> Option<&'a ScenarioResult> {
        r.scenarios.iter().find(|s| s.scenario == n)
    }
    let scenarios: Vec<ScenarioComparison> = names
        .iter()
        .map(|n| compare_scenario(find(a, n), find(b, n), same, opts))
        .collect();
    let timings_count = a.info.adapter.device_type != "cpu" && b.info.adapter.device_type != "cpu";
    let findings = findings::collect(&scenarios, timings_count);
    Comparison {
        a: a.info.clone(),
        b: b.info.clone(),
        same_adapter: same,
        timings_count,
        rule: Rule {
            alpha: ALPHA,
            confidence: 1.0 - ALPHA,
            threshold_pct: opts.threshold_pct,
            frames_needed: crate::stats::frames_needed(ALPHA),
            noise_sigmas: (same && !opts.noise.is_empty()).then_some(NOISE_SIGMAS),
        },
        scenarios,
        findings,
    }
}
