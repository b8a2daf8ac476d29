//! Pooling a FLIP error map into the numbers people report: mean, max and FLIP's *weighted*
//! percentiles.
//!
//! For: summarising one error map. Not for: statistics over frames (see `series`).
//!
//! The weighted percentile is `FLIPPooling::pooling::getPercentile(p, weighted = true)` (also
//! what nv-flip's `get_percentile(p, true)` and wgpu's tests use): sort the values ascending and
//! return the first value at which the running sum of values exceeds `p` times the total; 0 when
//! none does (e.g. an all-zero map). Each value is weighted by itself, so the percentile says
//! "p of the total error lies in pixels with error at most this". FLIP accumulates in f32; this
//! accumulates in f64, which can move the chosen value by a neighbouring sorted value.
//!
//! Instead of sorting all values, values are first binned by magnitude (with f64 bin sums), and
//! only the bin that holds the crossing is sorted.

use rayon::prelude::*;

const BINS: usize = 4096;

/// Pooled statistics of one error map.
pub(crate) struct Pooled {
    pub mean: f64,
    pub max: f64,
    pub percentiles: Vec<f64>,
}

/// Mean, max and the weighted percentiles `ps` (each in [0,1]) of `values` (all in [0,1];
/// anything else is clamped into the end bins, NaN counts as 0).
pub(crate) fn pool(values: &[f32], ps: &[f64]) -> Pooled {
    let n = values.len();
    if n == 0 {
        return Pooled {
            mean: 0.0,
            max: 0.0,
            percentiles: vec![0.0; ps.len()],
        };
    }
    let bin_of = |v: f32| -> usize { ((v.max(0.0) * BINS as f32) as usize).min(BINS - 1) };
    let clean = |v: f32| if v.is_nan() { 0.0 } else { v };
    // Per-chunk bin sums, reduced in chunk order so the result is deterministic.
    const CHUNK: usize = 1 << 16;
    let partial: Vec<(Vec<f64>, f32)> = values
        .par_chunks(CHUNK)
        .map(|chunk| {
            let mut sums = vec![0.0f64; BINS];
            let mut max = 0.0f32;
            for &v in chunk {
                let v = clean(v);
                sums[bin_of(v)] += v as f64;
                max = max.max(v);
            }
            (sums, max)
        })
        .collect();
    let mut sums = vec![0.0f64; BINS];
    let mut max = 0.0f32;
    for (s, m) in &partial {
        for (a, b) in sums.iter_mut().zip(s) {
            *a += b;
        }
        max = max.max(*m);
    }
    let total: f64 = sums.iter().sum();
    let percentiles = ps
        .iter()
        .map(|&p| weighted_percentile(values, &sums, total, p, &bin_of, &clean))
        .collect();
    Pooled {
        mean: total / n as f64,
        max: max as f64,
        percentiles,
    }
}

fn weighted_percentile(
    values: &[f32],
    sums: &[f64],
    total: f64,
    p: f64,
    bin_of: &(dyn Fn(f32) -> usize + Sync),
    clean: &(dyn Fn(f32) -> f32 + Sync),
) -> f64 {
    let target = p * total;
    let mut before = 0.0f64;
    for (bin, &s) in sums.iter().enumerate() {
        if before + s > target {
            let mut members: Vec<f32> = values
                .par_iter()
                .with_min_len(1 << 14)
                .map(|&v| clean(v))
                .filter(|&v| bin_of(v) == bin)
                .collect();
            members.sort_unstable_by(f32::total_cmp);
            let mut running = before;
            for &v in &members {
                running += v as f64;
                if running > target {
                    return v as f64;
                }
            }
            // The bin sum and the running sum can round apart: take the bin's largest value.
            return members.last().copied().unwrap_or(0.0) as f64;
        }
        before += s;
    }
    0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The definition, written plainly: sort, walk the running sum.
    fn naive(values: &[f32], p: f64) -> f64 {
        let mut v = values.to_vec();
        v.sort_by(f32::total_cmp);
        let total: f64 = v.iter().map(|&x| x as f64).sum();
        let mut run = 0.0;
        for x in v {
            run += x as f64;
            if run > p * total {
                return x as f64;
            }
        }
        0.0
    }

    #[test]
    fn matches_naive_definition() {
        let mut state = 12345u32;
        let values: Vec<f32> = (0..100_000)
            .map(|_| {
                state = state.wrapping_mul(1664525).wrapping_add(1013904223);
                let u = (state >> 8) as f32 / (1u32 << 24) as f32;
                u * u
            })
            .collect();
        let ps = [0.25, 0.5, 0.95, 0.99];
        let pooled = pool(&values, &ps);
        for (i, &p) in ps.iter().enumerate() {
            assert_eq!(pooled.percentiles[i], naive(&values, p), "p = {p}");
        }
        let mean = values.iter().map(|&x| x as f64).sum::<f64>() / values.len() as f64;
        assert!((pooled.mean - mean).abs() < 1e-12);
    }

    #[test]
    fn hand_computed() {
        // total 1.0; running sums 0.1, 0.3, 0.6, 1.0
        let values = [0.4f32, 0.1, 0.3, 0.2];
        let pooled = pool(&values, &[0.05, 0.2, 0.5, 0.7, 1.0]);
        assert_eq!(
            pooled.percentiles,
            vec![
                0.1f32 as f64,
                0.2f32 as f64,
                0.3f32 as f64,
                0.4f32 as f64,
                0.0
            ]
        );
        assert_eq!(pooled.max, 0.4f32 as f64);
    }

    #[test]
    fn all_zero_map() {
        let pooled = pool(&[0.0; 10], &[0.5]);
        assert_eq!(
            (pooled.mean, pooled.max, pooled.percentiles[0]),
            (0.0, 0.0, 0.0)
        );
    }
}
