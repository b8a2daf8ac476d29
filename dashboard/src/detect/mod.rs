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
//! 6. Location apart from certainty: near the statistic's split, each split's probability comes
//!    from the profile likelihood of a two-level model with Student-t noise that leaves outliers
//!    out ([`locate`]), so an outlier next to the step cannot capture it and a noisy night beside
//!    a small step is priced as heavy-tailed noise is; the most likely split is the change point,
//!    the shortest run of candidates holding 95% is its commit range, and the size gets a 95%
//!    interval.
//! 7. Binary segmentation: accepted change points split the segment and both halves are tested
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
    /// A change point with fewer points than this after the last commit of its range (in its
    /// environment segment; twice this while the range holds more than one commit, see
    /// [`crate::regressions::find`]) is *pending*: shown, not notified, free to move or vanish
    /// as runs arrive.
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
    /// Median of the sub-segment before and after the change (robust to an outlier on either side).
    pub before: f64,
    pub after: f64,
    /// (after − before) / |before|.
    pub relative_change: f64,
    /// 1 − tail probability under the no-change model.
    pub confidence: f64,
    /// Noise σ estimated for the tested segment.
    pub sigma: f64,
    /// The 95% interval of `relative_change` (from σ and the points on each side).
    pub change_low: f64,
    pub change_high: f64,
    /// Where the change lies, apart from whether there is one: the probability of each candidate
    /// split near `index` (point index, probability; they sum to 1), from a robust two-level fit
    /// (see [`locate`]). `index` is the most likely one.
    pub candidates: Vec<(usize, f64)>,
    /// The shortest run of candidates around `index` holding at least 95% of the probability:
    /// the commit range the change lies in (first and last candidate point).
    pub first_candidate: usize,
    pub last_candidate: usize,
}

impl ChangePoint {
    /// The probability that the change lies exactly at point `i` (0 outside the candidates).
    pub fn probability_at(&self, i: usize) -> f64 {
        self.candidates
            .iter()
            .find(|c| c.0 == i)
            .map_or(0.0, |c| c.1)
    }

    /// The probability at `index`.
    pub fn location_probability(&self) -> f64 {
        self.probability_at(self.index)
    }
}

/// Candidate splits tested on each side of the statistic's split by [`locate`].
pub const LOCATE_WITHIN: usize = 3;
/// In [`locate`], a point further than this many σ from *both* levels is an outlier: it says
/// nothing about where the change is and is left out of the fit. Far enough that noise does not reach it even when σ, estimated from a few dozen
/// points, comes out at half the true value (a 4.6σ night at the new level of a 50σ step is still
/// the new level's), close enough that a whole-run outlier (1.5x: 25σ at 2% noise) always does.
pub const LOCATE_CAP_SIGMAS: f64 = 10.0;

/// Degrees of freedom of the Student-t noise law of [`locate`]: tails heavy enough that a 4σ
/// night costs what it is under timing noise (a few per hundred runs, not one in 30,000), the
/// value Lange, Little and Taylor (1989) recommend when ν is not estimated.
pub const LOCATE_NU: f64 = 4.0;

/// Where a change found near split `k` lies: the probability of each split `j` within
/// [`LOCATE_WITHIN`] of the most likely split (itself within twice that of `k`; always
/// `lo <= j <= hi`), from the profile likelihood of a
/// two-level model with Student-t noise ([`LOCATE_NU`] degrees of freedom, standard deviation
/// `sigma`): each side's level is its maximum-likelihood estimate under that law, so every
/// split is priced at its best fit. Outliers (see [`LOCATE_CAP_SIGMAS`]) are left out.
///
/// History (issue 22). With plain squares, a one-night outlier two runs before a +10% step cost
/// less on the "after" side and the step was blamed on the outlier; with squares capped at 3σ, a
/// noisy night at the new level of a large step cost as much as on the old level's side and the
/// step was blamed a night late. Squares around the sides' *medians* were neither Gaussian nor
/// robust maximum likelihood: moving one point across the split moved the short side's median by
/// up to half the gap between two of its points, which flipped a 3σ step back and forth between
/// two commits with "0.00%" at each in turn, and put a step whose night before it was 1.2σ high
/// on that night. Left out, an outlier costs nothing on either side: splits that differ only by
/// the side of outliers are equally likely, and of those the latest is the change point, the
/// first run that shows the new level, so a step is never blamed on the outlier the night before
/// it ("outliers next to a step do not move the split onto them").
pub fn locate(values: &[f64], k: usize, sigma: f64, lo: usize, hi: usize) -> Vec<(usize, f64)> {
    // Searched twice as far, then centred on the most likely split: the statistic's split is a
    // noisier estimate of the same change, and a window centred on it moved by a few points as
    // runs arrived, giving a split 0% one night (outside the window) and 97% the next.
    let from = k.saturating_sub(2 * LOCATE_WITHIN).max(lo).max(1);
    let to = (k + 2 * LOCATE_WITHIN)
        .min(hi)
        .min(values.len().saturating_sub(1));
    if from > to {
        return vec![(k, 1.0)];
    }
    let cap = LOCATE_CAP_SIGMAS * sigma;
    let (ml, mr) = (level(&values[..k.max(1)]), level(&values[k.max(1)..]));
    let kept: Vec<bool> = values
        .iter()
        .map(|v| (v - ml).abs() <= cap || (v - mr).abs() <= cap)
        .collect();
    let side = |r: std::ops::Range<usize>| -> Vec<f64> {
        let v: Vec<f64> = r.clone().filter(|&i| kept[i]).map(|i| values[i]).collect();
        if v.is_empty() {
            values[r].to_vec()
        } else {
            v
        }
    };
    let noise = StudentT::with_sd(sigma);
    let cost = |j: usize| noise.deviance(&side(0..j)) + noise.deviance(&side(j..values.len()));
    let costs: Vec<(usize, f64)> = (from..=to).map(|j| (j, cost(j))).collect();
    let best = costs.iter().map(|c| c.1).fold(f64::INFINITY, f64::min);
    // The latest of equals (see `most_likely`).
    let centre = costs.iter().rev().find(|c| c.1 == best).map_or(k, |c| c.0);
    let weights: Vec<(usize, f64)> = costs
        .iter()
        .filter(|c| c.0.abs_diff(centre) <= LOCATE_WITHIN)
        .map(|&(j, c)| (j, (-(c - best) / 2.0).exp()))
        .collect();
    let total: f64 = weights.iter().map(|w| w.1).sum();
    weights.into_iter().map(|(j, w)| (j, w / total)).collect()
}

/// The Student-t noise law of [`locate`]: [`LOCATE_NU`] degrees of freedom, scale `s`.
#[derive(Clone, Copy, Debug)]
pub struct StudentT {
    s: f64,
}

impl StudentT {
    /// The law whose standard deviation is `sd` (scale sd·√((ν−2)/ν)).
    pub fn with_sd(sd: f64) -> StudentT {
        StudentT {
            s: sd * ((LOCATE_NU - 2.0) / LOCATE_NU).sqrt(),
        }
    }

    /// −2 log-likelihood of `v` around `m`, up to a constant: Σ (ν+1)·ln(1 + r²/ν), r = (x−m)/s.
    pub fn deviance_at(&self, v: &[f64], m: f64) -> f64 {
        v.iter()
            .map(|x| {
                let r = (x - m) / self.s;
                (LOCATE_NU + 1.0) * (r * r / LOCATE_NU).ln_1p()
            })
            .sum()
    }

    /// The maximum-likelihood level of `v` (iteratively reweighted means from the median: the
    /// weights (ν+1)/(ν+r²) fall with the residual, so a far point hardly pulls it).
    pub fn level(&self, v: &[f64]) -> f64 {
        let mut m = level(v);
        for _ in 0..100 {
            let (mut sw, mut swx) = (0.0, 0.0);
            for &x in v {
                let r = (x - m) / self.s;
                let w = (LOCATE_NU + 1.0) / (LOCATE_NU + r * r);
                sw += w;
                swx += w * x;
            }
            let next = swx / sw;
            let done = (next - m).abs() <= 1e-9 * self.s;
            m = next;
            if done {
                break;
            }
        }
        m
    }

    /// −2 log-likelihood of `v` at its maximum-likelihood level.
    pub fn deviance(&self, v: &[f64]) -> f64 {
        self.deviance_at(v, self.level(v))
    }
}

/// The most likely of `candidates`, the latest of equals (see [`locate`]).
fn most_likely(candidates: &[(usize, f64)]) -> Option<usize> {
    (0..candidates.len()).max_by(|&a, &b| {
        candidates[a]
            .1
            .total_cmp(&candidates[b].1)
            .then(candidates[a].0.cmp(&candidates[b].0))
    })
}

/// The shortest contiguous run of candidates around the most likely one holding `mass`.
fn credible_range(candidates: &[(usize, f64)], mass: f64) -> (usize, usize) {
    let Some(best) = most_likely(candidates) else {
        return (0, 0);
    };
    let (mut a, mut b) = (best, best);
    let mut held = candidates[best].1;
    while held < mass && (a > 0 || b + 1 < candidates.len()) {
        let left = if a > 0 { candidates[a - 1].1 } else { -1.0 };
        let right = if b + 1 < candidates.len() {
            candidates[b + 1].1
        } else {
            -1.0
        };
        if left >= right {
            a -= 1;
            held += left;
        } else {
            b += 1;
            held += right;
        }
    }
    (candidates[a].0, candidates[b].0)
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
            cp.first_candidate += start;
            cp.last_candidate += start;
            for c in &mut cp.candidates {
                c.0 += start;
            }
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
    let m = params.min_segment.max(1);
    let at_end = k == n - m;
    let k = if at_end {
        refine_at_end(&clipped, k)
    } else {
        k
    };
    // Where exactly: the robust location step may move the split a little (never past the
    // newest points unless the change already lies among them).
    let hi = if at_end || k > n - m { n - 1 } else { n - m };
    let candidates = locate(values, k, sigma, m.min(k), hi);
    let k = most_likely(&candidates).map_or(k, |i| candidates[i].0);
    let (first, last) = credible_range(&candidates, 0.95);
    // Levels are medians: an outlier on the short side must not cancel (or fake) the step's size.
    let before = level(&values[..k]);
    let after = level(&values[k..]);
    let relative_change = if before != 0.0 {
        (after - before) / before.abs()
    } else {
        f64::INFINITY
    };
    if relative_change.abs() < params.min_relative_change {
        return;
    }
    // The standard error of a difference of two medians: 1.2533 σ √(1/n₁ + 1/n₂).
    let se = 1.2533 * sigma * (1.0 / k as f64 + 1.0 / (n - k) as f64).sqrt();
    let (change_low, change_high) = if before != 0.0 {
        (
            (after - before - 1.96 * se) / before.abs(),
            (after - before + 1.96 * se) / before.abs(),
        )
    } else {
        (relative_change, relative_change)
    };
    found.push(ChangePoint {
        index: offset + k,
        before,
        after,
        relative_change,
        confidence: 1.0 - p,
        sigma,
        change_low,
        change_high,
        candidates: candidates.iter().map(|&(j, p)| (offset + j, p)).collect(),
        first_candidate: offset + first,
        last_candidate: offset + last,
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

/// The median of `v` (mean of the two middle values for an even count): a side's level.
pub fn level(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(|a, b| a.total_cmp(b));
    let n = s.len();
    if n % 2 == 1 {
        s[n / 2]
    } else {
        (s[n / 2 - 1] + s[n / 2]) / 2.0
    }
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
