//! Change-point detection on one series, with a model of that series' own noise. Pure functions.
//!
//! Method (documented with its parameters in `dashboard/docs/regressions.md`):
//! 1. The series is cut into *segments* wherever the environment (driver or harness version)
//!    changes; such a cut is an annotation, never an alert, and each segment is tested alone.
//! 2. In a segment, the noise σ is estimated robustly from successive differences
//!    (1.4826 · MAD(Δx) / √2), which a step in the mean barely moves; values beyond 5σ of the
//!    median are clipped so that a single outlier cannot make a step.
//! 3. For every split k (at least `min_segment` points on each side) the two-sample t statistic
//!    T_k = |x̄_left − x̄_right| / (s_k·√(1/n_left + 1/n_right)) is computed, s_k being the pooled
//!    standard deviation of the clipped values around the two means; the largest is the candidate.
//! 4. Its significance comes from a parametric bootstrap: the same statistic (with the same σ
//!    estimator) on Gaussian series of the same length, fitted with a Gumbel law; the candidate is a
//!    change point when its tail probability is below `alpha` and the relative change is at least
//!    `min_relative_change`. Confidence is 1 − p.
//! 5. A candidate at the newest admissible split (`min_segment` points after it) may really lie
//!    among the last `min_segment − 1` points: the constraint pushes the maximum earlier, which
//!    blamed a +20% step on the commit before it with "+13.3%" (two of the three points "after" are
//!    new). Such a candidate is placed where a two-mean fit of the points from it to the end has the
//!    smallest residual sum of squares; the change then has fewer than `min_segment` points after it,
//!    which keeps it *pending* (see [`Params::confirm_after`]).
//! 6. Binary segmentation: accepted change points split the segment and both halves are tested
//!    again.
//!
//! Not for: reading series from the store or storing regressions (see [`crate::regressions`]).

pub mod null;
mod rng;

pub use rng::Rng;

/// Detection parameters. The defaults are what the dashboard uses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// Tail probability under the no-change model below which a split is a change point.
    pub alpha: f64,
    /// Fewest points on each side of a change point.
    pub min_segment: usize,
    /// Smallest |after − before| / |before| reported; smaller changes are not worth an alert.
    pub min_relative_change: f64,
    /// Values further than this many σ from the segment median are clipped to it.
    pub clip_sigmas: f64,
    /// A change point with fewer points than this after it (in its environment segment) is
    /// *pending*: shown, not notified, free to move or vanish as runs arrive.
    pub confirm_after: usize,
    /// Detection reads the newest `window` points of a series; changes older than the open part of
    /// the window (see [`crate::regressions`]) are final.
    pub window: usize,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            alpha: 0.002,
            min_segment: 3,
            min_relative_change: 0.01,
            clip_sigmas: 5.0,
            confirm_after: 4,
            window: 256,
        }
    }
}

/// A detected change in the mean of a series.
#[derive(Clone, Debug, PartialEq)]
pub struct ChangePoint {
    /// Index of the first point after the change.
    pub index: usize,
    /// Mean of the sub-segment before and after the change.
    pub before: f64,
    pub after: f64,
    /// (after − before) / |before|.
    pub relative_change: f64,
    /// 1 − tail probability under the no-change model.
    pub confidence: f64,
    /// Noise σ estimated for the tested segment.
    pub sigma: f64,
}

/// Segments and change points of a series.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Analysis {
    /// Start indices of environment segments (always begins with 0 for a non-empty series).
    pub segment_starts: Vec<usize>,
    pub change_points: Vec<ChangePoint>,
}

impl Analysis {
    /// Points after change point `index` within its environment segment, in a series of `len`.
    pub fn points_after(&self, index: usize, len: usize) -> usize {
        let end = self
            .segment_starts
            .iter()
            .copied()
            .find(|&s| s > index)
            .unwrap_or(len);
        end - index
    }
}

/// Splits the series at every change of environment, then detects change points within each
/// environment segment. `environment[i]` is whatever identifies the driver and harness of point i.
pub fn analyse<E: PartialEq>(values: &[f64], environment: &[E], params: &Params) -> Analysis {
    assert_eq!(values.len(), environment.len(), "one environment per point");
    let mut segment_starts = Vec::new();
    for i in 0..values.len() {
        if i == 0 || environment[i] != environment[i - 1] {
            segment_starts.push(i);
        }
    }
    let mut change_points = Vec::new();
    for (j, &start) in segment_starts.iter().enumerate() {
        let end = segment_starts.get(j + 1).copied().unwrap_or(values.len());
        for mut cp in detect(&values[start..end], params) {
            cp.index += start;
            change_points.push(cp);
        }
    }
    Analysis {
        segment_starts,
        change_points,
    }
}

/// Change points in one environment segment, in index order.
pub fn detect(values: &[f64], params: &Params) -> Vec<ChangePoint> {
    let mut found = Vec::new();
    split(values, 0, params, &mut found);
    found.sort_by_key(|c| c.index);
    found
}

fn split(values: &[f64], offset: usize, params: &Params, found: &mut Vec<ChangePoint>) {
    let n = values.len();
    if n < 2 * params.min_segment || n < null::MIN_POINTS {
        return;
    }
    let sigma = noise_sigma(values);
    let clipped = clip(values, sigma, params.clip_sigmas);
    let Some((k, t)) = max_statistic(&clipped, sigma_floor(values), params.min_segment) else {
        return;
    };
    let p = null::tail_probability(n, params.min_segment, t);
    if p >= params.alpha {
        return;
    }
    let k = if k == n - params.min_segment.max(1) {
        refine_at_end(&clipped, k)
    } else {
        k
    };
    let before = mean(&values[..k]);
    let after = mean(&values[k..]);
    let relative_change = if before != 0.0 {
        (after - before) / before.abs()
    } else {
        f64::INFINITY
    };
    if relative_change.abs() < params.min_relative_change {
        return;
    }
    found.push(ChangePoint {
        index: offset + k,
        before,
        after,
        relative_change,
        confidence: 1.0 - p,
        sigma,
    });
    split(&values[..k], offset, params, found);
    split(&values[k..], offset + k, params, found);
}

/// Where in `from..values.len()` a single step best fits the points: the split with the smallest
/// residual sum of squares around the two means (at least one point after it). Used only for a
/// change already found significant at `from`, the newest split the statistic may take.
pub fn refine_at_end(values: &[f64], from: usize) -> usize {
    let n = values.len();
    let rss = |k: usize| {
        let (l, r) = (&values[..k], &values[k..]);
        let (ml, mr) = (mean(l), mean(r));
        l.iter().map(|v| (v - ml).powi(2)).sum::<f64>()
            + r.iter().map(|v| (v - mr).powi(2)).sum::<f64>()
    };
    let mut best = (from, rss(from));
    for k in from + 1..n {
        let e = rss(k);
        if e < best.1 {
            best = (k, e);
        }
    }
    best.0
}

pub fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

fn median(v: &mut [f64]) -> f64 {
    let mid = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, |a, b| a.total_cmp(b));
    *m
}

/// Robust σ of the noise from successive differences: a step changes one difference only. Falls
/// back to the standard deviation of the differences when more than half of them are equal
/// (quantised timings), and to a tiny floor for a constant series, so that any change of a
/// deterministic value stands out.
pub fn noise_sigma(values: &[f64]) -> f64 {
    if values.len() < 2 {
        return f64::MIN_POSITIVE;
    }
    let mut diffs: Vec<f64> = values.windows(2).map(|w| w[1] - w[0]).collect();
    let m = median(&mut diffs);
    let mut dev: Vec<f64> = diffs.iter().map(|d| (d - m).abs()).collect();
    let mad = median(&mut dev);
    let mut sigma = 1.4826 * mad / std::f64::consts::SQRT_2;
    if sigma <= 0.0 {
        let md = mean(&diffs);
        let var = diffs.iter().map(|d| (d - md).powi(2)).sum::<f64>() / diffs.len() as f64;
        sigma = (var / 2.0).sqrt();
    }
    let scale = values.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    sigma.max(scale * 1e-9).max(f64::MIN_POSITIVE)
}

fn clip(values: &[f64], sigma: f64, k: f64) -> Vec<f64> {
    let mut sorted = values.to_vec();
    let med = median(&mut sorted);
    values
        .iter()
        .map(|v| v.clamp(med - k * sigma, med + k * sigma))
        .collect()
}

/// The split with the largest two-sample t statistic: (index of the first point after, T). The
/// pooled σ of each split is floored at `sigma_floor` so that a constant series gives finite values.
pub fn max_statistic(values: &[f64], sigma_floor: f64, min_segment: usize) -> Option<(usize, f64)> {
    let n = values.len();
    let m = min_segment.max(1);
    if n < 2 * m || n < 3 {
        return None;
    }
    // Centre first so that sums of squares do not cancel catastrophically.
    let centre = mean(values);
    let total: f64 = values.iter().map(|v| v - centre).sum();
    let total_sq: f64 = values.iter().map(|v| (v - centre).powi(2)).sum();
    let mut left = 0.0;
    let mut best: Option<(usize, f64)> = None;
    for k in 1..n {
        left += values[k - 1] - centre;
        if k < m || n - k < m {
            continue;
        }
        let (nl, nr) = (k as f64, (n - k) as f64);
        let right = total - left;
        let rss = (total_sq - left * left / nl - right * right / nr).max(0.0);
        let s = (rss / (n - 2) as f64).sqrt().max(sigma_floor);
        let t = (left / nl - right / nr).abs() / (s * (1.0 / nl + 1.0 / nr).sqrt());
        if best.is_none_or(|(_, b)| t > b) {
            best = Some((k, t));
        }
    }
    best
}

/// The smallest σ a split statistic uses: a millionth of the series' scale, so that a change of a
/// deterministic value is still finite and very significant.
pub fn sigma_floor(values: &[f64]) -> f64 {
    let scale = values.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    (scale * 1e-9).max(f64::MIN_POSITIVE)
}

#[cfg(test)]
mod tests;
