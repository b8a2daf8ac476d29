//! The night-to-night noise of a run's frame-time series, as regression detection estimates it
//! ([`crate::detect::noise_sigma`]: robust, from successive differences), read from the points
//! stored before the run in its own environment (driver, driver version, harness version). The
//! two-run comparison and the run page's "vs prev" judge a frame-time change against it as well
//! as against the fixed threshold (`tessera_results::compare::Options::noise`), so a change many σ
//! outside a quiet series' noise is called even when it is below the fixed percentage.
//!
//! Not for: detection itself ([`crate::regressions`]).

use std::collections::{BTreeMap, HashMap};

use crate::db::Connection;
use crate::detect::noise_sigma;
use crate::store::{series, StoreError};

/// Points read before the run (the newest ones).
pub const NOISE_POINTS: i64 = 64;

/// Fewest points in the run's environment for a noise estimate; with fewer the fixed threshold
/// alone applies.
pub const MIN_POINTS: usize = 8;

/// The series measure read: median frame GPU time.
const FRAME_TIME: &str = "gpu_ms.median";

/// Relative noise σ (σ over the median level) of each frame-time series of run `run_id`'s adapter
/// that has a point in the run, from the points before it: scenario → variant → σ. Series with
/// fewer than [`MIN_POINTS`] earlier points in the run's environment are left out.
pub fn frame_time_noise(
    conn: &mut dyn Connection,
    run_id: &str,
) -> Result<BTreeMap<String, BTreeMap<String, f64>>, StoreError> {
    frame_time_noise_where(conn, run_id, &|_, _| true)
}

/// [`frame_time_noise`] of the series whose scenario and variant `wanted` accepts only: each
/// series costs a query, so a page that needs a few of a wide run's 1,700 asks for those.
pub fn frame_time_noise_where(
    conn: &mut dyn Connection,
    run_id: &str,
    wanted: &dyn Fn(&str, &str) -> bool,
) -> Result<BTreeMap<String, BTreeMap<String, f64>>, StoreError> {
    let mut out: BTreeMap<String, BTreeMap<String, f64>> = BTreeMap::new();
    let Some(run) = conn.query_opt(
        "SELECT id, driver, driver_info, harness_version FROM runs WHERE run_id = $1",
        &[run_id.into()],
    )?
    else {
        return Ok(out);
    };
    let pk = run.i64(0)?;
    let env = (run.string(1)?, run.string(2)?, run.string(3)?);
    // Whether each earlier run shares the run's environment, asked once per run.
    let mut same_env: HashMap<i64, bool> = HashMap::new();
    for s in series::of_run_with_measure(conn, pk, FRAME_TIME)? {
        if !wanted(&s.scenario, &s.variant) {
            continue;
        }
        let mut values = Vec::new();
        for (value, earlier) in series::before_with_run(conn, &s, pk, NOISE_POINTS)? {
            let same = match same_env.get(&earlier) {
                Some(same) => *same,
                None => {
                    let same = series::environment_of(conn, earlier)?.as_ref() == Some(&env);
                    same_env.insert(earlier, same);
                    same
                }
            };
            if !same {
                break;
            }
            values.push(value);
        }
        if let Some(sigma) = relative_sigma(&mut values) {
            out.entry(s.scenario).or_default().insert(s.variant, sigma);
        }
    }
    Ok(out)
}

/// σ over the median of `values` (newest first), or `None` for fewer than [`MIN_POINTS`] or a
/// level that is not positive.
fn relative_sigma(values: &mut [f64]) -> Option<f64> {
    if values.len() < MIN_POINTS {
        return None;
    }
    values.reverse();
    let sigma = noise_sigma(values);
    let mut sorted = values.to_vec();
    sorted.sort_by(|a, b| a.total_cmp(b));
    let level = sorted[sorted.len() / 2];
    (level > 0.0).then(|| sigma / level)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_sigma_needs_enough_points_and_scales_by_the_level() {
        assert_eq!(relative_sigma(&mut [1.0; 7]), None);
        // Alternating ±0.01 around 2.0: successive differences of 0.02.
        let mut v: Vec<f64> = (0..20)
            .map(|i| if i % 2 == 0 { 2.01 } else { 1.99 })
            .collect();
        let s = relative_sigma(&mut v).unwrap();
        assert!(s > 0.0 && s < 0.02, "{s}");
        let mut scaled: Vec<f64> = (0..20)
            .map(|i| if i % 2 == 0 { 20.1 } else { 19.9 })
            .collect();
        assert!((relative_sigma(&mut scaled).unwrap() - s).abs() < 1e-12);
        assert_eq!(relative_sigma(&mut [0.0; 10]), None);
    }
}
