//! The paired test of an A/B: the Wilcoxon signed-rank test on the differences `b_i - a_i` of
//! attempts run back to back (Pinpoint's choice), and the size of the change with its
//! distribution-free interval: the Hodges-Lehmann estimate (the median of the Walsh averages
//! `(d_i + d_j) / 2`, i <= j) between the order statistics the test's critical value picks
//! (Hollander & Wolfe, *Nonparametric Statistical Methods*, 3.2).
//!
//! Zero differences are dropped for the p-value (Wilcoxon's method, scipy's default); the
//! estimate and interval use every pair. Exact null distribution up to [`EXACT_MAX_PAIRS`]
//! non-zero differences without ties, else the normal approximation with tie and continuity
//! corrections. Pure functions. Not for: unpaired sets (see [`super::mann_whitney_p`]).

use super::{erfc, z_two_sided};

/// Largest number of non-zero differences for which the exact distribution is used.
pub const EXACT_MAX_PAIRS: usize = 25;

/// The outcome of a paired comparison of B against A.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Paired {
    /// Pairs compared.
    pub n: usize,
    /// Two-sided p-value that the differences are centred on zero; 1 when every one is zero.
    pub p: f64,
    /// Hodges-Lehmann estimate of B - A, in the measure's unit.
    pub estimate: f64,
    /// `[low, high]` of B - A at confidence 1 - `alpha`; `None` with too few pairs for one.
    pub interval: Option<[f64; 2]>,
}

/// How many subsets of {1..n} sum to each w = 0..=n(n+1)/2: the null distribution of W+.
fn w_counts(n: usize) -> Vec<f64> {
    let max = n * (n + 1) / 2;
    let mut c = vec![0.0f64; max + 1];
    c[0] = 1.0;
    for k in 1..=n {
        for w in (k..=max).rev() {
            c[w] += c[w - k];
        }
    }
    c
}

/// Compares paired samples: `a[i]` and `b[i]` were measured back to back. `None` when the
/// lengths differ, are zero, or a value is not finite.
pub fn wilcoxon_signed_rank(a: &[f64], b: &[f64], alpha: f64) -> Option<Paired> {
    if a.len() != b.len() || a.is_empty() || a.iter().chain(b).any(|x| !x.is_finite()) {
        return None;
    }
    let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| y - x).collect();
    Some(Paired {
        n: d.len(),
        p: p_value(&d),
        estimate: walsh_median(&d),
        interval: interval(&d, alpha),
    })
}

fn p_value(d: &[f64]) -> f64 {
    let mut nz: Vec<f64> = d.iter().copied().filter(|&x| x != 0.0).collect();
    let n = nz.len();
    if n == 0 {
        return 1.0;
    }
    nz.sort_by(|x, y| x.abs().total_cmp(&y.abs()));
    let mut w_plus = 0.0;
    let mut tie_term = 0.0;
    let mut i = 0;
    while i < n {
        let mut j = i;
        while j + 1 < n && nz[j + 1].abs() == nz[i].abs() {
            j += 1;
        }
        let t = (j - i + 1) as f64;
        let mid = (i + j) as f64 / 2.0 + 1.0;
        w_plus += mid * nz[i..=j].iter().filter(|x| **x > 0.0).count() as f64;
        tie_term += t * t * t - t;
        i = j + 1;
    }
    if tie_term == 0.0 && n <= EXACT_MAX_PAIRS {
        let c = w_counts(n);
        let total: f64 = c.iter().sum();
        let w = w_plus.round() as usize;
        let below: f64 = c[..=w].iter().sum();
        let above: f64 = c[w..].iter().sum();
        return (2.0 * below.min(above) / total).min(1.0);
    }
    let nf = n as f64;
    let mean = nf * (nf + 1.0) / 4.0;
    let var = nf * (nf + 1.0) * (2.0 * nf + 1.0) / 24.0 - tie_term / 48.0;
    if var <= 0.0 {
        return 1.0;
    }
    let z = ((w_plus - mean).abs() - 0.5).max(0.0) / var.sqrt();
    erfc(z / std::f64::consts::SQRT_2).min(1.0)
}

fn walsh(d: &[f64]) -> Vec<f64> {
    let mut w = Vec::with_capacity(d.len() * (d.len() + 1) / 2);
    for i in 0..d.len() {
        for j in i..d.len() {
            w.push((d[i] + d[j]) / 2.0);
        }
    }
    w.sort_by(f64::total_cmp);
    w
}

fn walsh_median(d: &[f64]) -> f64 {
    let w = walsh(d);
    let m = w.len();
    if m % 2 == 1 {
        w[m / 2]
    } else {
        (w[m / 2 - 1] + w[m / 2]) / 2.0
    }
}

/// The largest w with P(W+ <= w) <= alpha / 2 for `n` pairs; `None` when even w = 0 is likelier.
fn critical_w(n: usize, alpha: f64) -> Option<usize> {
    if n <= EXACT_MAX_PAIRS {
        let c = w_counts(n);
        let total: f64 = c.iter().sum();
        let mut cumulative = 0.0;
        let mut last = None;
        for (w, count) in c.iter().enumerate() {
            cumulative += count;
            if cumulative / total > alpha / 2.0 {
                break;
            }
            last = Some(w);
        }
        return last;
    }
    let nf = n as f64;
    let k = nf * (nf + 1.0) / 4.0
        - z_two_sided(alpha) * (nf * (nf + 1.0) * (2.0 * nf + 1.0) / 24.0).sqrt()
        - 0.5;
    (k >= 0.0).then(|| k.floor() as usize)
}

fn interval(d: &[f64], alpha: f64) -> Option<[f64; 2]> {
    let k = critical_w(d.len(), alpha)?;
    let w = walsh(d);
    let m = w.len();
    Some([w[k], w[m - 1 - k]])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_p_values_match_r_wilcox_test() {
        // R: wilcox.test(b, a, paired = TRUE)$p.value for
        // a = 1:8, b = a + c(0.5, 1.5, -0.25, 2, 3, 0.75, 1.25, 2.5) -> 0.015625
        let a: Vec<f64> = (1..=8).map(f64::from).collect();
        let d = [0.5, 1.5, -0.25, 2.0, 3.0, 0.75, 1.25, 2.5];
        let b: Vec<f64> = a.iter().zip(d).map(|(x, y)| x + y).collect();
        let r = wilcoxon_signed_rank(&a, &b, 0.05).unwrap();
        assert!((r.p - 0.015625).abs() < 1e-12, "{}", r.p);
        // All ten differences positive: p = 2 / 2^10.
        let a = [1.0; 10];
        let b: Vec<f64> = (1..=10).map(|i| 1.0 + i as f64).collect();
        let r = wilcoxon_signed_rank(&a, &b, 0.05).unwrap();
        assert!((r.p - 2.0 / 1024.0).abs() < 1e-15);
        assert_eq!(r.estimate, 5.5);
        let [lo, hi] = r.interval.unwrap();
        assert!(lo > 0.0 && hi > lo, "{lo} {hi}");
    }

    #[test]
    fn identical_attempts_read_no_change() {
        let a = [2.0, 2.1, 1.9, 2.05, 1.95, 2.0, 2.02, 1.98, 2.01, 1.99];
        let r = wilcoxon_signed_rank(&a, &a, 0.05).unwrap();
        assert_eq!((r.p, r.estimate, r.interval), (1.0, 0.0, Some([0.0, 0.0])));
    }

    #[test]
    fn the_interval_has_the_stated_coverage_under_the_null() {
        // n = 10 at alpha 0.05: critical w is 8 (tables: P(W <= 8) = 0.0244).
        assert_eq!(critical_w(10, 0.05), Some(8));
        assert_eq!(critical_w(5, 0.05), None);
        let c = w_counts(10);
        let total: f64 = c.iter().sum();
        assert_eq!(total, 1024.0);
        assert!((c[..=8].iter().sum::<f64>() / total - 25.0 / 1024.0).abs() < 1e-12);
    }

    #[test]
    fn large_samples_use_the_normal_approximation() {
        let a: Vec<f64> = (0..40).map(|i| i as f64).collect();
        let b: Vec<f64> = a
            .iter()
            .enumerate()
            .map(|(i, x)| x + if i % 3 == 0 { -1.0 } else { 1.0 })
            .collect();
        let r = wilcoxon_signed_rank(&a, &b, 0.05).unwrap();
        // 26 of 40 tied differences of +1, 14 of -1: W+ = 26 * 20.5 = 533, mean 410, variance
        // 5535 - 63960 / 48 = 4202.5: z = 122.5 / 64.83 = 1.89, p = 0.059.
        assert!((r.p - 0.0588).abs() < 0.001, "{}", r.p);
        // Walsh averages: 105 of -1, 364 of 0, 351 of +1: the median is 0.
        assert_eq!(r.estimate, 0.0);
        assert!(wilcoxon_signed_rank(&a, &b[1..], 0.05).is_none());
    }
}
