//! Frame and pass times of one variant in two runs (`COMPARISON.md`, "Time"): the per-frame GPU
//! times in milliseconds on the same adapter, or each divided by its baseline's median on each
//! adapter when the adapters differ, then the test of [`crate::stats`] (too few frames, the
//! Mann-Whitney p, the Hodges-Lehmann shift and its interval, the threshold).
//!
//! Not for: which variant is the baseline ([`super::baseline`]) or what counts as a regression
//! ([`super::findings`]).

use serde::{Serialize, Serializer};

use crate::stats::{compare_times, frame_samples, TimeChange};
use crate::{Status, Summary, VariantResult};

use super::{baseline, InRun, Options, Pair};

/// The frame time's comparison.
#[derive(Clone, Debug, PartialEq)]
pub enum Time {
    /// Both timed: the test. `relative_to`: on different adapters, the baseline each run's frames
    /// were divided by (the change is then the change of the cost relative to the baseline).
    Tested {
        test: TimeChange,
        relative_to: Pair<String>,
    },
    /// On different adapters, a variant without a baseline (`native`): the unit the others are
    /// measured in, so its own time is not compared.
    Baseline,
    /// Why there is no test: `not in both`, `not ok in both`, `not timed`, `no timed baseline in
    /// both`.
    NotCompared(&'static str),
}

impl Time {
    pub fn tested(&self) -> Option<&TimeChange> {
        match self {
            Time::Tested { test, .. } => Some(test),
            _ => None,
        }
    }

    /// The words every presentation shows: the test's verdict (`slower`, `faster`, `within
    /// noise`, `below threshold`, `too few frames`), `baseline`, or why it was not compared.
    pub fn words(&self) -> &'static str {
        match self {
            Time::Tested { test, .. } => test.verdict.words(),
            Time::Baseline => "baseline",
            Time::NotCompared(why) => why,
        }
    }
}

/// The JSON of a [`Time`]: `verdict` (its words), and for a test `change`, `interval`, `p`,
/// `frames` and `relative_to`.
impl Serialize for Time {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        #[derive(Serialize)]
        struct View<'a> {
            verdict: &'a str,
            change: Option<f64>,
            interval: Option<[f64; 2]>,
            p: Option<f64>,
            frames: Option<[usize; 2]>,
            relative_to: Option<&'a Pair<String>>,
        }
        let t = self.tested();
        View {
            verdict: self.words(),
            change: t.map(|t| t.change),
            interval: t.and_then(|t| t.interval),
            p: t.map(|t| t.p),
            frames: t.map(|t| t.frames),
            relative_to: match self {
                Time::Tested { relative_to, .. } if relative_to.a.is_some() => Some(relative_to),
                _ => None,
            },
        }
        .serialize(s)
    }
}

/// One pass's time in both runs (same adapter only).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PassComparison {
    pub name: String,
    /// Median GPU time of the pass, ms.
    pub gpu_ms: Pair<f64>,
    pub time: Time,
}

fn median(s: &[f64]) -> Option<f64> {
    Summary::of(s).map(|s| s.median)
}

/// The frame time of a variant found in both runs, judged with `threshold_pct`.
pub(crate) fn frame(a: Option<InRun>, b: Option<InRun>, same: bool, threshold_pct: f64) -> Time {
    let (Some(a), Some(b)) = (a, b) else {
        return Time::NotCompared("not in both");
    };
    if a.r.status != Status::Ok || b.r.status != Status::Ok {
        return Time::NotCompared("not ok in both");
    }
    let (Some(sa), Some(sb)) = (frame_samples(a.r), frame_samples(b.r)) else {
        return Time::NotCompared("not timed");
    };
    let mut relative_to = Pair::default();
    let (sa, sb) = if same {
        (sa, sb)
    } else {
        if baseline::is_root(a) {
            return Time::Baseline;
        }
        let (ba, bb) = (baseline::of(a), baseline::of(b));
        let unit = |x: Option<&VariantResult>| median(&frame_samples(x?)?).filter(|m| *m > 0.0);
        let (Some(ua), Some(ub)) = (unit(ba), unit(bb)) else {
            return Time::NotCompared("no timed baseline in both");
        };
        relative_to = Pair::new(ba.map(|r| r.variant.clone()), bb.map(|r| r.variant.clone()));
        let scale = |s: Vec<f64>, u: f64| s.into_iter().map(|x| x / u).collect::<Vec<_>>();
        (scale(sa, ua), scale(sb, ub))
    };
    match compare_times(&sa, &sb, threshold_pct) {
        Some(test) => Time::Tested { test, relative_to },
        None => Time::NotCompared("not timed"),
    }
}

/// Every pass of A with its namesake in B, under the same test.
pub(crate) fn passes(a: &VariantResult, b: &VariantResult, opts: &Options) -> Vec<PassComparison> {
    if a.status != Status::Ok || b.status != Status::Ok {
        return Vec::new();
    }
    let samples = |p: &crate::PassRecord| {
        (p.gpu_ms.is_some() && !p.samples_ms.is_empty()).then(|| p.samples_ms.clone())
    };
    a.passes
        .iter()
        .map(|pa| {
            let pb = b.passes.iter().find(|p| p.name == pa.name);
            let (sa, sb) = (samples(pa), pb.and_then(samples));
            let time = match (&sa, &sb) {
                (Some(x), Some(y)) => compare_times(x, y, opts.threshold_pct).map_or(
                    Time::NotCompared("not timed"),
                    |test| Time::Tested {
                        test,
                        relative_to: Pair::default(),
                    },
                ),
                _ => Time::NotCompared("not timed in both"),
            };
            PassComparison {
                name: pa.name.clone(),
                gpu_ms: Pair::new(
                    sa.as_deref().and_then(median),
                    sb.as_deref().and_then(median),
                ),
                time,
            }
        })
        .collect()
}

#[cfg(test)]
pub(crate) mod tests {

    use super::*;
    use crate::stats::DEFAULT_THRESHOLD_PCT;

    /// An ok result of technique `name` with one pass timed `samples` ([`VariantResult::timed`]).
    pub(crate) fn result(name: &str, samples: &[f64]) -> VariantResult {
        VariantResult::timed(name, samples)
    }

    fn frames(n: usize, start: f64) -> Vec<f64> {
        (0..n).map(|i| start + 0.001 * i as f64).collect()
    }

    fn in_run(results: &[VariantResult], i: usize) -> Option<InRun<'_>> {
        Some(InRun {
            results,
            r: &results[i],
        })
    }

    #[test]
    fn four_frames_are_too_few_whatever_the_change() {
        let a = vec![result("native", &frames(4, 1.0))];
        let b = vec![result("native", &frames(4, 16.31))];
        let t = frame(in_run(&a, 0), in_run(&b, 0), true, DEFAULT_THRESHOLD_PCT);
        assert_eq!(t.words(), "too few frames");
        assert!(t.tested().unwrap().change > 15.0);
    }

    #[test]
    fn other_adapters_divide_by_each_runs_baseline() {
        // B's adapter is twice as fast for everything: upscale's cost relative to native holds.
        let a = vec![
            result("native", &frames(10, 1.0)),
            result("upscale", &frames(10, 0.5)),
        ];
        let b = vec![
            result("native", &frames(10, 0.5)),
            result("upscale", &frames(10, 0.25)),
        ];
        let t = frame(in_run(&a, 1), in_run(&b, 1), false, DEFAULT_THRESHOLD_PCT);
        assert_eq!(t.words(), "within noise", "{t:?}");
        let Time::Tested { relative_to, .. } = &t else {
            unreachable!()
        };
        assert_eq!(relative_to.a.as_deref(), Some("native"));
        assert_eq!(
            frame(in_run(&a, 0), in_run(&b, 0), false, DEFAULT_THRESHOLD_PCT),
            Time::Baseline
        );
    }
}
