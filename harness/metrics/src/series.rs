//! Temporal statistics over the per-frame values of one metric.
//!
//! For: summarising a series (mean, p95, max, population standard deviation). Not for: pooling
//! the pixels of one frame (FLIP has its own weighted histogram in `flip::pool`).

use serde::Serialize;

/// Summary of a per-frame series.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SeriesStats {
    pub mean: f64,
    /// 95th percentile with linear interpolation between closest ranks (numpy's default):
    /// position `0.95 * (n - 1)` in the sorted values.
    pub p95: f64,
    pub max: f64,
    /// Population standard deviation (divides by n).
    pub std_dev: f64,
}

/// Mean, p95, max and population standard deviation of `values`.
///
/// `None` for an empty series or one with a non-finite value (NaN or infinity; a PSNR series of
/// identical frames holds infinities: aggregate MSEs and use `psnr_from_mse` instead).
pub fn series_stats(values: &[f64]) -> Option<SeriesStats> {
    if values.is_empty() || values.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    Some(SeriesStats {
        mean,
        p95: percentile_linear(&sorted, 0.95),
        max: sorted[sorted.len() - 1],
        std_dev: var.sqrt(),
    })
}

/// Percentile `p` in [0,1] of sorted, non-empty values, interpolating linearly between ranks.
fn percentile_linear(sorted: &[f64], p: f64) -> f64 {
    let pos = p * (sorted.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = pos.ceil() as usize;
    let frac = pos - lo as f64;
    sorted[lo] + (sorted[hi] - sorted[lo]) * frac
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_and_nan_give_none() {
        assert_eq!(series_stats(&[]), None);
        assert_eq!(series_stats(&[1.0, f64::NAN]), None);
        assert_eq!(series_stats(&[1.0, f64::INFINITY]), None);
    }

    #[test]
    fn single_value() {
        let s = series_stats(&[3.5]).unwrap();
        assert_eq!((s.mean, s.p95, s.max, s.std_dev), (3.5, 3.5, 3.5, 0.0));
    }

    #[test]
    fn hand_computed() {
        // 1..=20 shuffled: mean 10.5, population variance (n^2-1)/12 = 33.25,
        // p95 at position 0.95*19 = 18.05 -> 19 + 0.05 = 19.05.
        let mut v: Vec<f64> = (1..=20).map(f64::from).collect();
        v.reverse();
        v.swap(3, 11);
        let s = series_stats(&v).unwrap();
        assert!((s.mean - 10.5).abs() < 1e-12);
        assert!((s.std_dev - 33.25f64.sqrt()).abs() < 1e-12);
        assert!((s.p95 - 19.05).abs() < 1e-12);
        assert_eq!(s.max, 20.0);
    }
}
