//! Regression detection applied to stored series: reads a series' points in run order with each
//! run's environment (driver and harness version), runs [`crate::detect::analyse`], and records
//! each new change point in `regressions` with triage state `new`. Existing rows (and their triage
//! state and notes) are never overwritten; a change point that moved by a few points as more runs
//! arrived is the same regression.
//!
//! Not for: the statistics (see [`crate::detect`]) or triage (see [`crate::store::triage`]).

use crate::db::{Connection, Value};
use crate::detect::{analyse, Params};
use crate::store::StoreError;

/// A change point within this many points of a stored one is taken to be that one.
const SAME_CHANGE_WITHIN: usize = 3;

/// One point of a series with what identifies its environment.
#[derive(Clone, Debug)]
pub struct SeriesPoint {
    pub run_pk: i64,
    pub run_id: String,
    pub commit: Option<String>,
    pub started_at: String,
    pub environment: String,
    pub value: f64,
}

/// Points of a series in run order (start time, then import order).
pub fn points(conn: &mut dyn Connection, series_id: i64) -> Result<Vec<SeriesPoint>, StoreError> {
    let rows = conn.query(
        "SELECT r.id, r.run_id, r.commit_sha, r.started_at, r.driver, r.driver_info, r.harness_version, p.value
         FROM points p JOIN runs r ON r.id = p.run_pk
         WHERE p.series_id = $1 ORDER BY r.started_at, r.id",
        &[Value::Int(series_id)],
    )?;
    rows.iter()
        .map(|r| {
            Ok(SeriesPoint {
                run_pk: r.i64(0)?,
                run_id: r.string(1)?,
                commit: r.opt_string(2)?,
                started_at: r.string(3)?,
                environment: format!("{} {} / harness {}", r.str(4)?, r.str(5)?, r.str(6)?),
                value: r.f64(7)?,
            })
        })
        .collect()
}

/// Runs detection on one series and stores new change points; returns how many were new.
pub fn update_series(
    conn: &mut dyn Connection,
    series_id: i64,
    params: &Params,
) -> Result<usize, StoreError> {
    let pts = points(conn, series_id)?;
    let values: Vec<f64> = pts.iter().map(|p| p.value).collect();
    let env: Vec<&str> = pts.iter().map(|p| p.environment.as_str()).collect();
    let analysis = analyse(&values, &env, params);
    if analysis.change_points.is_empty() {
        return Ok(0);
    }
    let existing: Vec<usize> = conn
        .query(
            "SELECT run_pk_after FROM regressions WHERE series_id = $1",
            &[Value::Int(series_id)],
        )?
        .iter()
        .filter_map(|r| r.i64(0).ok())
        .filter_map(|pk| pts.iter().position(|p| p.run_pk == pk))
        .collect();
    let mut added = 0;
    for cp in &analysis.change_points {
        if existing
            .iter()
            .any(|&i| i.abs_diff(cp.index) <= SAME_CHANGE_WITHIN)
        {
            continue;
        }
        let now = crate::now_rfc3339();
        added += conn.execute(
            "INSERT INTO regressions (series_id, run_pk_before, run_pk_after, value_before, value_after,
                 relative_change, confidence, state, note, detected_at, updated_at)
             VALUES ($1, $2, $3, $4, $5, $6, $7, 'new', '', $8, $9) ON CONFLICT DO NOTHING",
            &[
                Value::Int(series_id),
                Value::Int(pts[cp.index - 1].run_pk),
                Value::Int(pts[cp.index].run_pk),
                Value::Real(cp.before),
                Value::Real(cp.after),
                Value::from(cp.relative_change),
                Value::Real(cp.confidence),
                now.clone().into(),
                now.into(),
            ],
        )? as usize;
    }
    Ok(added)
}

/// Runs detection on the given series; returns how many change points were new.
pub fn update(
    conn: &mut dyn Connection,
    series: &[i64],
    params: &Params,
) -> Result<usize, StoreError> {
    let mut added = 0;
    for &id in series {
        added += update_series(conn, id, params)?;
    }
    Ok(added)
}

/// Every series in the store (for `tessera-dashboard detect`).
pub fn all_series(conn: &mut dyn Connection) -> Result<Vec<i64>, StoreError> {
    Ok(conn
        .query("SELECT id FROM series ORDER BY id", &[])?
        .iter()
        .map(|r| r.i64(0))
        .collect::<Result<_, _>>()?)
}
