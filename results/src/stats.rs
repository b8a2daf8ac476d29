//! The significance test of GPU-time changes between two runs: a two-sided Mann-Whitney U test on
//! two sets of per-frame GPU times, and the verdict rule built on it (p below [`ALPHA`] and a
//! median change of at least a threshold). One implementation for `tessera compare` and the
//! dashboard's compare page.
//!
//! Pure functions on samples and records. Exact p-values when both sets are small (at most
//! [`EXACT_MAX`] samples) and have no ties, otherwise the normal approximation with tie and
//! continuity corrections (as scipy's `mannwhitneyu` does). Not for: metric tolerances or status
//! rules (those stay with each caller).

use crate::{Summary, VariantResult};

/// Significance level of the Mann-Whitney U test on per-frame GPU times.
pub const ALPHA: f64 = 0.01;

/// Default smallest change of the median (percent) that can be called faster or slower.
pub const DEFAULT_THRESHOLD_PCT: f64 = 5.0;

/// What a time change means once noise is accounted for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimeVerdict {
    /// Not significant, or smaller than the threshold.
    Same,
    Slower,
    Faster,
}

/// A compared pair of per-frame time sets: B against A.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeChange {
    /// `median(b) / median(a) - 1`.
    pub change: f64,
    /// Two-sided Mann-Whitney U p-value.
    pub p: f64,
    pub verdict: TimeVerdict,
}

/// Slower or faster when p < [`ALPHA`] and the median moved by at least `threshold_pct` percent.
pub fn verdict(change: f64, p: f64, threshold_pct: f64) -> TimeVerdict {
    if p >= ALPHA || change.abs() * 100.0 < threshold_pct || change.is_nan() {
        TimeVerdict::Same
    } else if change > 0.0 {
        TimeVerdict::Slower
    } else {
        TimeVerdict::Faster
    }
}

/// Compares per-frame times `b` against `a`; `None` when either set is empty.
pub fn compare_times(a: &[f64], b: &[f64], threshold_pct: f64) -> Option<TimeChange> {
    let (ma, mb) = (Summary::of(a)?.median, Summary::of(b)?.median);
    let change = mb / ma - 1.0;
    let p = mann_whitney_p(a, b);
    Some(TimeChange {
        change,
        p,
        verdict: verdict(change, p, threshold_pct),
    })
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

/// Exact two-sided p-value of U = `u` for sets of `m` and `n` values without ties. The counts of
/// rank arrangements giving each U are the coefficients of the Gaussian binomial [m+n choose m]_q,
/// built as the product over k = 1..m of (1 - q^(n+k)) / (1 - q^k), truncated at degree m*n (exact:
/// each step only reads lower coefficients). Counts stay below 2^53 for m, n <= 20.
fn exact_p(u: usize, m: usize, n: usize) -> f64 {
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
    let total: f64 = c.iter().sum();
    let u = u.min(max);
    let below: f64 = c[..=u].iter().sum();
    let above: f64 = c[u..].iter().sum();
    (2.0 * below.min(above) / total).min(1.0)
}

/// Complementary error function (Numerical Recipes' `erfcc`, relative error below 1.2e-7).
fn erfc(x: f64) -> f64 {
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
    fn verdict_needs_both_significance_and_size() {
        assert_eq!(verdict(0.10, 0.001, 5.0), TimeVerdict::Slower);
        assert_eq!(verdict(-0.10, 0.001, 5.0), TimeVerdict::Faster);
        assert_eq!(verdict(0.04, 0.001, 5.0), TimeVerdict::Same);
        assert_eq!(verdict(0.10, 0.02, 5.0), TimeVerdict::Same);
        let a: Vec<f64> = (0..10).map(|i| 1.0 + 0.01 * f64::from(i)).collect();
        let b: Vec<f64> = a.iter().map(|x| x * 1.2).collect();
        let c = compare_times(&a, &b, 5.0).unwrap();
        assert!((c.change - 0.2).abs() < 1e-9);
        assert_eq!(c.verdict, TimeVerdict::Slower);
        assert!(compare_times(&[], &b, 5.0).is_none());
    }

    #[test]
    fn degenerate_sets_are_not_significant() {
        assert_eq!(mann_whitney_p(&[], &[1.0]), 1.0);
        assert_eq!(mann_whitney_p(&[2.0, 2.0], &[2.0, 2.0, 2.0]), 1.0);
    }
}
