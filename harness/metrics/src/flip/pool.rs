//! Pooling a FLIP error map into the numbers people report: mean, max and FLIP's *weighted*
//! percentiles, computed the way flip-evaluator's `FLIPPooling::pooling<float>` computes them.
//!
//! For: summarising one error map. Not for: statistics over frames (see `series`).
//!
//! * `mean`: the f32 sum of the values in row-major order divided by their count, in f32. This
//!   is what flip-evaluator's Python API, its CLI and nv-flip report. On a 1080p map with large
//!   errors that f32 accumulation drifts from the true mean by up to ~3e-3; `exact_mean` is
//!   the f64 mean.
//! * weighted percentile `p` (`getPercentile(p, weighted = true)`, what nv-flip's
//!   `get_percentile(p, true)` and wgpu's tests use): sort ascending, walk a running f32 sum,
//!   and return the first value at which it exceeds `p * sum` (p as f32); 0 when none does (e.g.
//!   an all-zero map). Each value is weighted by itself: "p of the total error lies in pixels
//!   with error at most this".
//!
//! Emulating FLIP's f32 sums (rather than summing exactly) is what keeps the pooled values
//! within 1e-4 of flip-evaluator on large maps: with exact sums the p99 of a 1080p map moved by
//! up to 3e-3 from FLIP's.

use rayon::prelude::*;

/// Pooled statistics of one error map.
pub(crate) struct Pooled {
    pub mean: f64,
    pub exact_mean: f64,
    pub max: f64,
    pub percentiles: Vec<f64>,
}

/// Mean, max and the weighted percentiles `ps` (each in [0,1]) of `values` (FLIP errors in
/// [0,1]; NaN is counted as 0, negative values as 0).
pub(crate) fn pool(values: &[f32], ps: &[f64]) -> Pooled {
    let n = values.len();
    if n == 0 {
        return Pooled {
            mean: 0.0,
            exact_mean: 0.0,
            max: 0.0,
            percentiles: vec![0.0; ps.len()],
        };
    }
    let clean = |v: f32| if v > 0.0 { v } else { 0.0 };
    let (sum32, (exact, max)) = rayon::join(
        || running_sum(values),
        || {
            let parts: Vec<(f64, f32)> = values
                .par_chunks(1 << 16)
                .map(|c| {
                    c.iter().fold((0.0f64, 0.0f32), |(s, m), &v| {
                        let v = clean(v);
                        (s + v as f64, m.max(v))
                    })
                })
                .collect();
            parts
                .iter()
                .fold((0.0f64, 0.0f32), |(s, m), &(ps, pm)| (s + ps, m.max(pm)))
        },
    );
    let sorted = radix_sorted(values, clean);
    let percentiles = ps
        .iter()
        .map(|&p| {
            let target = p as f32 * sum32;
            let mut running = 0.0f32;
            for &v in &sorted {
                running += v;
                if running > target {
                    return v as f64;
                }
            }
            0.0
        })
        .collect();
    Pooled {
        mean: (sum32 / n as f32) as f64,
        exact_mean: exact / n as f64,
        max: max as f64,
        percentiles,
    }
}

/// The f32 running sum of the values in order (NaN and negative values as 0), as FLIP sums.
pub(crate) fn running_sum(values: &[f32]) -> f32 {
    values
        .iter()
        .fold(0.0f32, |s, &v| s + if v > 0.0 { v } else { 0.0 })
}

/// The cleaned values sorted ascending: an LSD radix sort on the bit patterns, which order like
/// the values because all are non-negative (3 passes of 11 bits cover all 32).
fn radix_sorted(values: &[f32], clean: impl Fn(f32) -> f32 + Sync) -> Vec<f32> {
    let mut keys: Vec<u32> = values
        .par_iter()
        .with_min_len(1 << 14)
        .map(|&v| clean(v).to_bits())
        .collect();
    let mut tmp = vec![0u32; keys.len()];
    for shift in [0u32, 11, 22] {
        let mut count = vec![0usize; 1 << 11];
        for &k in &keys {
            count[((k >> shift) & 0x7ff) as usize] += 1;
        }
        let mut pos = 0;
        for c in count.iter_mut() {
            let n = *c;
            *c = pos;
            pos += n;
        }
        for &k in &keys {
            let d = ((k >> shift) & 0x7ff) as usize;
            tmp[count[d]] = k;
            count[d] += 1;
        }
        std::mem::swap(&mut keys, &mut tmp);
    }
    keys.into_iter().map(f32::from_bits).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The definition, written plainly: sort, walk the running f32 sum.
    fn naive(values: &[f32], p: f64) -> f64 {
        let total = values.iter().fold(0.0f32, |s, &v| s + v);
        let mut v = values.to_vec();
        v.sort_by(f32::total_cmp);
        let mut run = 0.0f32;
        for x in v {
            run += x;
            if run > p as f32 * total {
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
        assert!((pooled.exact_mean - mean).abs() < 1e-12);
        assert!((pooled.mean - mean).abs() < 1e-4);
    }

    #[test]
    fn hand_computed() {
        // total 1.0; running sums 0.1, 0.3, 0.6, 1.0
        let values = [0.4f32, 0.1, 0.3, 0.2];
        let pooled = pool(&values, &[0.05, 0.2, 0.5, 0.7, 1.0]);
        let f = |v: f32| v as f64;
        assert_eq!(
            pooled.percentiles,
            vec![f(0.1), f(0.2), f(0.3), f(0.4), 0.0]
        );
        assert_eq!(pooled.max, f(0.4));
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
