//! Which speed-up alerts moved because their baseline moved, read from the data rather than from
//! the baseline's own alert (which may not exist yet: a slower `native` is often confirmed a
//! night after the speed-ups against it, and may sit in another group). A speed-up is the
//! baseline's frame time over the variant's, so its change is the baseline's change over the
//! variant's; it *moved with its baseline* when the baseline's frame time changed more (in log
//! terms) across the alert's runs than the variant's own did. Both changes are medians of up to
//! [`SIDE_POINTS`] points on each side of the alert (the run before and earlier, the run after and
//! later), so one noisy night does not decide.
//!
//! Not for: grouping or counting (see [`super::groups`]), the comparison of two runs (the engine's
//! `findings::attribute_speedups` does the same there).

use std::collections::BTreeMap;

use super::alerts::{Alert, DetectionStatus};
use super::StoreError;
use crate::db::{Connection, Value};

/// Points read on each side of an alert's change.
pub const SIDE_POINTS: i64 = 3;

/// The baseline's change that carried a speed-up alert.
#[derive(Clone, Debug, PartialEq)]
pub struct BaselineMove {
    /// The baseline variant (`native`, `native-vrs`, ...).
    pub baseline: String,
    /// Relative change of the baseline's frame time across the alert's runs.
    pub baseline_change: f64,
    /// Relative change of the variant's own frame time across them.
    pub own_change: f64,
}

/// The baseline a `speedup` measure is computed against: its suffix, else `native`.
pub fn baseline_of(measure: &str) -> Option<&str> {
    let rest = measure.strip_prefix("speedup")?;
    Some(
        rest.strip_prefix('.')
            .filter(|b| !b.is_empty())
            .unwrap_or(tessera_results::measure::DEFAULT_BASELINE),
    )
}

fn series_id(
    conn: &mut dyn Connection,
    a: &Alert,
    variant: &str,
) -> Result<Option<i64>, StoreError> {
    Ok(conn
        .query_opt(
            "SELECT id FROM series WHERE scenario = $1 AND variant = $2 AND adapter_id = $3 AND measure = 'gpu_ms.median'",
            &[
                a.series.scenario.as_str().into(),
                variant.into(),
                Value::Int(a.series.adapter_id),
            ],
        )?
        .map(|r| r.i64(0))
        .transpose()?)
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[v.len() / 2])
}

/// Median of the series' points at and before run `before`, and at and after run `after`.
fn sides(
    conn: &mut dyn Connection,
    series: i64,
    before: i64,
    after: i64,
) -> Result<Option<(f64, f64)>, StoreError> {
    let side = |conn: &mut dyn Connection, run: i64, earlier: bool| {
        let values = super::series::values_beside(conn, series, run, earlier, SIDE_POINTS)?;
        Ok::<_, StoreError>(median(values))
    };
    let b = side(conn, before, true)?;
    let a = side(conn, after, false)?;
    Ok(b.zip(a))
}

/// For each live speed-up alert of `alerts` that moved with its baseline, the move, by alert id.
pub fn of_alerts(
    conn: &mut dyn Connection,
    alerts: &[Alert],
) -> Result<BTreeMap<i64, BaselineMove>, StoreError> {
    let mut out = BTreeMap::new();
    for a in alerts {
        if a.status == DetectionStatus::Withdrawn {
            continue;
        }
        let Some(baseline) = baseline_of(&a.series.measure) else {
            continue;
        };
        let (Some(own), Some(base)) = (
            series_id(conn, a, &a.series.variant)?,
            series_id(conn, a, baseline)?,
        ) else {
            continue;
        };
        let (Some(o), Some(b)) = (
            sides(conn, own, a.run_pk_before, a.run_pk_after)?,
            sides(conn, base, a.run_pk_before, a.run_pk_after)?,
        ) else {
            continue;
        };
        if o.0 <= 0.0 || o.1 <= 0.0 || b.0 <= 0.0 || b.1 <= 0.0 {
            continue;
        }
        let (own_log, base_log) = ((o.1 / o.0).ln(), (b.1 / b.0).ln());
        if base_log.abs() > own_log.abs() {
            out.insert(
                a.id,
                BaselineMove {
                    baseline: baseline.to_string(),
                    baseline_change: b.1 / b.0 - 1.0,
                    own_change: o.1 / o.0 - 1.0,
                },
            );
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn baselines_of_speedup_measures() {
        assert_eq!(baseline_of("speedup"), Some("native"));
        assert_eq!(baseline_of("speedup.native-vrs"), Some("native-vrs"));
        assert_eq!(baseline_of("gpu_ms.median"), None);
    }
}
