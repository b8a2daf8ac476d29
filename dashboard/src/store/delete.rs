//! Deleting runs: one run with everything that hangs off it, in one transaction
//! (`DELETE /api/runs/{run_id}`), and choosing which runs a retention rule drops
//! (`tessera-dashboard retention`), which then deletes each with the same [`delete_run`].
//!
//! What goes with a run: its scenario results, results, points, images, the blobs that no other
//! run's images use, and every regression (alert) whose before or after run it was, with its
//! history (`regression_events`). Series stay
//! (other runs' points may use them; an empty series shows no points). Detection is not re-run
//! here. Not for: HTTP (see [`crate::server::delete`]).

use super::StoreError;
use crate::db::{transaction, Connection, Value};

/// What [`delete_run`] removed, row counts per table.
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Deleted {
    pub run_id: String,
    pub results: u64,
    pub points: u64,
    pub images: u64,
    pub blobs: u64,
    pub alerts: u64,
}

/// Deletes run `run_id` and what hangs off it, all or nothing. `NotFound` if there is no such run.
pub fn delete_run(conn: &mut dyn Connection, run_id: &str) -> Result<Deleted, StoreError> {
    let mut attempt = 0;
    loop {
        match transaction(conn, |c| delete_once(c, run_id)) {
            Err(StoreError::Db(e)) if e.is_retryable() && attempt < 5 => attempt += 1,
            other => return other,
        }
    }
}

fn delete_once(c: &mut dyn Connection, run_id: &str) -> Result<Deleted, StoreError> {
    let Some(row) = c.query_opt("SELECT id FROM runs WHERE run_id = $1", &[run_id.into()])? else {
        return Err(StoreError::NotFound(format!("run {run_id}")));
    };
    let pk = [Value::Int(row.i64(0)?)];
    c.execute(
        "DELETE FROM regression_events WHERE regression_id IN \
         (SELECT id FROM regressions WHERE run_pk_before = $1 OR run_pk_after = $1)",
        &pk,
    )?;
    let alerts = c.execute(
        "DELETE FROM regressions WHERE run_pk_before = $1 OR run_pk_after = $1",
        &pk,
    )?;
    // The p5-p95 bands of the run's timed points (series charts).
    c.execute("DELETE FROM point_bands WHERE run_pk = $1", &pk)?;
    let points = c.execute("DELETE FROM points WHERE run_pk = $1", &pk)?;
    // The run's distinct digests, so that only blobs it used are checked for other users.
    let digests: Vec<String> = c
        .query(
            "SELECT DISTINCT digest FROM images WHERE run_pk = $1 ORDER BY digest",
            &pk,
        )?
        .iter()
        .map(|r| r.string(0))
        .collect::<Result<_, _>>()?;
    let images = c.execute("DELETE FROM images WHERE run_pk = $1", &pk)?;
    let mut blobs = 0;
    for d in digests {
        blobs += c.execute(
            "DELETE FROM blobs WHERE digest = $1 \
             AND NOT EXISTS (SELECT 1 FROM images WHERE images.digest = $1)",
            &[d.into()],
        )?;
    }
    let results = c.execute("DELETE FROM results WHERE run_pk = $1", &pk)?;
    c.execute("DELETE FROM scenario_results WHERE run_pk = $1", &pk)?;
    c.execute("DELETE FROM runs WHERE id = $1", &pk)?;
    Ok(Deleted {
        run_id: run_id.to_string(),
        results,
        points,
        images,
        blobs,
        alerts,
    })
}

/// Which runs a retention rule keeps. A run is kept when any given rule keeps it; with no rule
/// every run is kept.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Retention {
    /// Keep runs that started at most this many days ago.
    pub keep_days: Option<u32>,
    /// Keep the newest this many runs of each adapter (by start time).
    pub keep_runs: Option<u32>,
}

/// A run a retention rule would delete.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Expired {
    pub run_id: String,
    pub started_at: String,
    pub adapter: String,
}

/// The runs `rule` does not keep, oldest first. `now` is RFC 3339 UTC (the cut-off is
/// `now - keep_days`).
pub fn expired(
    conn: &mut dyn Connection,
    rule: Retention,
    now: chrono::DateTime<chrono::Utc>,
) -> Result<Vec<Expired>, StoreError> {
    if rule.keep_days.is_none() && rule.keep_runs.is_none() {
        return Ok(Vec::new());
    }
    let rows = conn.query(
        "SELECT r.run_id, r.started_at, a.name, \
                ROW_NUMBER() OVER (PARTITION BY r.adapter_id ORDER BY r.started_at DESC, r.id DESC) \
         FROM runs r JOIN adapters a ON a.id = r.adapter_id \
         ORDER BY r.started_at, r.id",
        &[],
    )?;
    let cutoff = rule.keep_days.map(|d| {
        (now - chrono::Duration::days(d.into())).to_rfc3339_opts(chrono::SecondsFormat::Secs, true)
    });
    let mut out = Vec::new();
    for r in rows {
        let started_at = r.string(1)?;
        let rank = r.i64(3)?;
        let kept_by_age = cutoff.as_ref().is_some_and(|c| started_at >= *c);
        let kept_by_count = rule.keep_runs.is_some_and(|n| rank <= i64::from(n));
        if !kept_by_age && !kept_by_count {
            out.push(Expired {
                run_id: r.string(0)?,
                started_at,
                adapter: r.string(2)?,
            });
        }
    }
    Ok(out)
}
