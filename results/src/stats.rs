//! The test of GPU-time changes between two runs: a two-sided Mann-Whitney U test on two sets of
//! per-frame GPU times, the smallest p-value it can reach at the sample sizes (below which no
//! verdict is possible: "too few frames"), the Hodges-Lehmann estimate of the shift with its
//! distribution-free confidence interval, and the verdict rule built on them (`COMPARISON.md`,
//! "Time"). One implementation for `tessera compare`, the dashboard's compare page and its run
//! page's "vs prev" column, through [`crate::compare`].
//!
//! Pure functions on samples and records. Exact p-values when both sets are small (at most
//! [`EXACT_MAX`] samples) and have no ties, otherwise the normal approximation with tie and
//! continuity corrections (as scipy's `mannwhitneyu` does). Not for: metric tolerances, status or
//! baseline rules (those are [`crate::compare`]'s).

use crate::{Summary, VariantResult};

pub mod shift;
pub mod signed_rank;

pub use shift::{hodges_lehmann, Shift};

/// Significance level of the Mann-Whitney U test on per-frame GPU times. The shift's interval is
/// reported at the matching confidence, 1 - `ALPHA` (99%), so a change is significant exactly
/// when its interval leaves out zero (up to ties).
pub const ALPHA: f64 = 0.01;

/// Default smallest change of the time (percent) that can be called faster or slower.
pub const DEFAULT_THRESHOLD_PCT: f64 = 5.0;

/// What a time change means once noise and sample size are accounted for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum TimeVerdict {
    /// Significant and at least the threshold, B slower.
    #[serde(rename = "slower")]
    Slower,
    /// Significant and at least the threshold, B faster.
    #[serde(rename = "faster")]
    Faster,
    /// p at or above [`ALPHA`]: the frames do not show a change.
    #[serde(rename = "within noise")]
    WithinNoise,
    /// Significant, but the shift is smaller than the threshold: real, too small to call.
    #[serde(rename = "below threshold")]
    BelowThreshold,
    /// No arrangement of this many frames can reach p < [`ALPHA`]: the test cannot tell, whatever
    /// the change ([`smallest_p`]).
    #[serde(rename = "too few frames")]
    TooFewFrames,
}

impl TimeVerdict {
    /// The words pages, the API and the Markdown use: `slower`, `faster`, `within noise`,
    /// `below threshold`, `too few frames`.
    pub fn words(self) -> &'static str {
        match self {
            TimeVerdict::Slower => "slower",
            TimeVerdict::Faster => "faster",
            TimeVerdict::WithinNoise => "within noise",
            TimeVerdict::BelowThreshold => "below threshold",
            TimeVerdict::TooFewFrames => "too few frames",
        }
    }
}

/// A compared pair of per-frame time sets: B against A.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct TimeChange {
    /// The Hodges-Lehmann shift from A to B over A's median: `+0.1` is 10% slower.
    pub change: f64,
    /// The shift's confidence interval at 1 - [`ALPHA`], over A's median; `None` when the sizes
    /// cannot give one (too few frames).
    pub interval: Option<[f64; 2]>,
    /// Two-sided Mann-Whitney U p-value.
    pub p: f64,
    /// Frames in A and in B.
    pub frames: [usize; 2],
    pub verdict: TimeVerdict,
}

/// The verdict of a change (relative shift `change`, p-value `p`) between sets of `m` and `n`
/// frames: too few frames when [`smallest_p`]`(m, n)` is not below [`ALPHA`]; otherwise slower or
/// faster when p < [`ALPHA`] and the shift is at least `threshold_pct` percent, below threshold
/// when only significant, within noise when not significant.
pub fn verdict(change: f64, p: f64, (m, n): (usize, usize), threshold_pct: f64) -> TimeVerdict {
    if smallest_p(m, n) >= ALPHA {
        TimeVerdict::TooFewFrames
    } else if p >= ALPHA || change.is_nan() {
        TimeVerdict::WithinNoise
    } else if change.abs() * 100.0 < threshold_pct {
        TimeVerdict::BelowThreshold
    } else if change > 0.0 {
        TimeVerdict::Slower
    } else {
        TimeVerdict::Faster
    }
}

/// Compares per-frame times `b` against `a`; `None` when either set is empty.
pub fn compare_times(a: &[f64], b: &[f64], threshold_pct: f64) -> Option<TimeChange> {
    let base = Summary::of(a)?.median;
    let s = hodges_lehmann(a, b, ALPHA)?;
    let change = s.estimate / base;
    let p = mann_whitney_p(a, b);
    Some(TimeChange {
        change,
        interval: s.interval.map(|[lo, hi]| [lo / base, hi / base]),
        p,
        frames: [a.len(), b.len()],
        verdict: verdict(change, p, (a.len(), b.len()), threshold_pct),
    })
}

/// The smallest two-sided p-value the test can give for sets of `m` and `n` values: the exact
/// p when every value of one set lies below every value of the other, 2 / C(m+n, m), capped at 1
/// (ties only raise it). With 4 frames per side it is 2/70 = 0.029: no change, however large, is
/// significant at 0.01.
pub fn smallest_p(m: usize, n: usize) -> f64 {
    if m == 0 || n == 0 {
        return 1.0;
    }
    let k = m.min(n);
    // C(m + n, k) as a running product: after step i it is C(m + n - k + i, i).
    let mut c = 1.0f64;
    for i in 1..=k {
        c = c * (m + n - k + i) as f64 / i as f64;
    }
    (2.0 / c).min(1.0)
}

/// The fewest frames per side (the same count in both runs) at which the test can reach
/// p < `alpha`: 5 for 0.01 (2/252 = 0.008).
pub fn frames_needed(alpha: f64) -> usize {
    (1..=10_000)
        .find(|&k| smallest_p(k, k) < alpha)
        .unwrap_or(10_000)
}

/// Per-frame GPU times: the sum over passes of each measured frame's sample. `None` without
/// timestamps (no `gpu_frame_ms`) or without samples.
pub fn frame_samples(r: &VariantResult) -> Option<Vec<f64>> {
    r.gpu_frame_ms?;
    let frames = r.passes.iter().map(|p| p.samples_ms.len()).min()?;
    let sums: Vec<f64> = (0..frames)
        .map(|i| r.passes.iter().map(|p| p.samples_ms[i]).sum())
        .collect();
    (!sums.is_empty()).then_some(sums)
}

/// Largest sample count of either set for which the exact distribution of U is used.
pub const EXACT_MAX: usize = 20;

/// Two-sided p-value of the Mann-Whitney U test that `a` and `b` come from one distribution.
/// `1.0` when either set is empty or every value is equal.
pub fn mann_whitney_p(a: &[f64], b: &[f64]) -> f64 {
    let (m, n) = (a.len(), b.len());
    if m == 0 || n == 0 {
        return 1.0;
    }
    let mut all: Vec<(f64, bool)> = a
        .iter()
        .map(|&v| (v, true))
        .chain(b.iter().map(|&v| (v, false)))
        .collect();
    all.sort_by(|x, y| x.0.total_cmp(&y.0));
    // Mid-ranks (1-based) with ties averaged; `tie_term` is the sum of t^3 - t over tie groups.
    let mut rank_sum_a = 0.0;
    let mut tie_term = 0.0;
    let mut i = 0;
    while i < all.len() {
        let mut j = i;
        while j + 1 < all.len() && all[j + 1].0 == all[i].0 {
            j += 1;
        }
        let t = (j - i + 1) as f64;
        let mid = (i + j) as f64 / 2.0 + 1.0;
        rank_sum_a += mid * all[i..=j].iter().filter(|x| x.1).count() as f64;
        tie_term += t * t * t - t;
        i = j + 1;
    }
    let u = rank_sum_a - (m * (m + 1)) as f64 / 2.0;
    if tie_term == 0.0 && m <= EXACT_MAX && n <= EXACT_MAX {
        return exact_p(u.round() as usize, m, n);
    }
    let total = (m + n) as f64;
    let mean = (m * n) as f64 / 2.0;
    let var = (m * n) as f64 / 12.0 * ((total + 1.0) - tie_term / (total * (total - 1.0)));
    if var <= 0.0 {
        return 1.0;
    }
    let z = ((u - mean).abs() - 0.5).max(0.0) / var.sqrt();
    erfc(z / std::f64::consts::SQRT_2).min(1.0)
}

/// How many arrangements of `m` and `n` untied values give each U = 0..=m*n. They are the
/// coefficients of the Gaussian binomial [m+n choose m]_q, built as the product over k = 1..m of
/// (1 - q^(n+k)) / (1 - q^k), truncated at degree m*n (exact: each step only reads lower
/// coefficients). Counts stay below 2^53 for m, n <= 20.
pub(crate) fn u_counts(m: usize, n: usize) -> Vec<f64> {
    let max = m * n;
    let mut c = vec![0.0f64; max + 1];
    c[0] = 1.0;
    for k in 1..=m {
        let d = n + k;
        for i in (d..=max).rev() {
            c[i] -= c[i - d];
        }
        for i in k..=max {
            c[i] += c[i - k];
        }
    }
    c
}

/// Exact two-sided p-value of U = `u` for sets of `m` and `n` values without ties.
fn exact_p(u: usize, m: usize, n: usize) -> f64 {
    let c = u_counts(m, n);
    let total: f64 = c.iter().sum();
    let u = u.min(m * n);
    let below: f64 = c[..=u].iter().sum();
    let above: f64 = c[u..].iter().sum();
    (2.0 * below.min(above) / total).min(1.0)
}

/// The two-sided critical value of the normal distribution: `z` with P(|Z| > z) = `alpha`
/// (2.576 for 0.01), by bisection on [`erfc`].
pub(crate) fn z_two_sided(alpha: f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 40.0f64);
    for _ in 0..200 {
        let mid = (lo + hi) / 2.0;
        if erfc(mid / std::f64::consts::SQRT_2) > alpha {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (lo + hi) / 2.0
}

/// Complementary error function (Numerical Recipes' `erfcc`, relative error below 1.2e-7).
pub(crate) fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -z * z - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98
                                + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let r = t * poly.exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) {
        assert!((a - b).abs() < 1e-4, "{a} vs {b}");
    }

    #[test]
    fn exact_matches_scipy() {
        // scipy.stats.mannwhitneyu(a, b, method="exact").pvalue
        close(mann_whitney_p(&[1.0, 2.0, 3.0], &[4.0, 5.0, 6.0]), 0.1);
        close(
            mann_whitney_p(
                &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
                &[7.0, 8.0, 9.0, 10.0, 11.0, 12.0],
            ),
            2.0 / 924.0,
        );
        close(
            mann_whitney_p(&[1.0, 3.0, 5.0, 7.0], &[2.0, 4.0, 6.0, 8.0]),
            0.685_714_285_7,
        );
    }

    #[test]
    fn asymptotic_matches_scipy() {
        // scipy.stats.mannwhitneyu(a, b, method="asymptotic").pvalue
        close(
            mann_whitney_p(&[1.0, 1.0, 2.0, 2.0, 3.0], &[2.0, 3.0, 3.0, 4.0, 4.0]),
            0.052_411_628_7,
        );
        let a: Vec<f64> = (0..30).map(f64::from).collect();
        let b: Vec<f64> = (0..25).map(|x| f64::from(x) + 5.5).collect();
        close(mann_whitney_p(&a, &b), 0.207_929_272_5);
    }

    #[test]
    fn verdict_needs_enough_frames_significance_and_size() {
        let ten = (10, 10);
        assert_eq!(verdict(0.10, 0.001, ten, 5.0), TimeVerdict::Slower);
        assert_eq!(verdict(-0.10, 0.001, ten, 5.0), TimeVerdict::Faster);
        assert_eq!(verdict(0.04, 0.001, ten, 5.0), TimeVerdict::BelowThreshold);
        assert_eq!(verdict(0.10, 0.02, ten, 5.0), TimeVerdict::WithinNoise);
        // 4 frames per side: even a complete separation has p = 2/70.
        assert_eq!(
            verdict(15.31, 0.0286, (4, 4), 5.0),
            TimeVerdict::TooFewFrames
        );
        assert_eq!(verdict(0.5, 0.0079, (5, 5), 5.0), TimeVerdict::Slower);
        let a: Vec<f64> = (0..10).map(|i| 1.0 + 0.01 * f64::from(i)).collect();
        let b: Vec<f64> = a.iter().map(|x| x * 1.2).collect();
        let c = compare_times(&a, &b, 5.0).unwrap();
        assert!((c.change - 0.2).abs() < 0.01, "{c:?}");
        assert_eq!(c.verdict, TimeVerdict::Slower);
        let [lo, hi] = c.interval.unwrap();
        assert!(lo > 0.0 && lo < c.change && c.change < hi, "{c:?}");
        assert!(compare_times(&[], &b, 5.0).is_none());
    }

    #[test]
    fn smallest_p_and_frames_needed() {
        close(smallest_p(4, 4), 2.0 / 70.0);
        close(smallest_p(5, 5), 2.0 / 252.0);
        close(smallest_p(4, 6), 2.0 / 210.0);
        close(smallest_p(1, 1), 1.0);
        assert_eq!(smallest_p(0, 8), 1.0);
        assert_eq!(smallest_p(2000, 2000), 0.0);
        // The exact test at complete separation gives the bound itself.
        close(
            mann_whitney_p(&[1.0, 2.0, 3.0, 4.0], &[5.0, 6.0, 7.0, 8.0]),
            smallest_p(4, 4),
        );
        assert_eq!(frames_needed(0.01), 5);
        assert_eq!(frames_needed(0.05), 4);
        assert_eq!(frames_needed(0.001), 7);
    }

    #[test]
    fn z_matches_the_normal_table() {
        assert!((z_two_sided(0.05) - 1.959_964).abs() < 1e-5);
        assert!((z_two_sided(0.01) - 2.575_829).abs() < 1e-5);
    }

    #[test]
    fn degenerate_sets_are_not_significant() {
        assert_eq!(mann_whitney_p(&[], &[1.0]), 1.0);
        assert_eq!(mann_whitney_p(&[2.0, 2.0], &[2.0, 2.0, 2.0]), 1.0);
    }
}
