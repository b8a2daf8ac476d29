//! The no-change model: the distribution of the largest split statistic on a Gaussian series of a
//! given length, with σ estimated as on real series, by simulation (a parametric bootstrap), fitted
//! with a Gumbel law so that small tail probabilities come from a few hundred simulations.
//!
//! Results are cached per (length bucket, min_segment): lengths above 64 share buckets 5% wide,
//! each using its largest length (the statistic grows with length, so this errs on fewer alerts).

use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

use super::{max_statistic, Rng};

/// Shortest segment tested at all: σ is not known well enough from fewer points.
pub const MIN_POINTS: usize = 8;
/// Simulated series per length bucket.
pub const SIMULATIONS: usize = 400;

#[derive(Clone, Copy, Debug)]
struct Gumbel {
    mu: f64,
    beta: f64,
}

fn bucket(n: usize) -> usize {
    if n <= 64 {
        return n;
    }
    let mut b = 64.0f64;
    while (b as usize) < n {
        b *= 1.05;
    }
    b.ceil() as usize
}

fn fit(n: usize, min_segment: usize) -> Gumbel {
    let mut rng = Rng::new(0x7e55e7a ^ (n as u64) << 8 ^ min_segment as u64);
    let mut maxima = Vec::with_capacity(SIMULATIONS);
    let mut x = vec![0.0; n];
    for _ in 0..SIMULATIONS {
        x.iter_mut().for_each(|v| *v = rng.normal());
        if let Some((_, t)) = max_statistic(&x, 1e-12, min_segment) {
            maxima.push(t);
        }
    }
    let m = maxima.iter().sum::<f64>() / maxima.len() as f64;
    let var = maxima.iter().map(|t| (t - m).powi(2)).sum::<f64>() / (maxima.len() - 1) as f64;
    // Method of moments: variance = π²β²/6, mean = μ + γβ.
    let beta = (6.0 * var).sqrt() / std::f64::consts::PI;
    Gumbel {
        mu: m - 0.577_215_664_9 * beta,
        beta,
    }
}

fn model(n: usize, min_segment: usize) -> Gumbel {
    static CACHE: OnceLock<Mutex<HashMap<(usize, usize), Gumbel>>> = OnceLock::new();
    let key = (bucket(n), min_segment);
    let cache = CACHE.get_or_init(Default::default);
    if let Some(g) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
        return *g;
    }
    let g = fit(key.0, min_segment);
    cache
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .insert(key, g);
    g
}

/// P(max statistic ≥ t) on a no-change series of length `n`.
pub fn tail_probability(n: usize, min_segment: usize, t: f64) -> f64 {
    let g = model(n, min_segment);
    1.0 - (-(-(t - g.mu) / g.beta).exp()).exp()
}

/// The statistic value whose tail probability is `alpha`: what a split must exceed.
pub fn threshold(n: usize, min_segment: usize, alpha: f64) -> f64 {
    let g = model(n, min_segment);
    g.mu - g.beta * (-(1.0 - alpha).ln()).ln()
}
