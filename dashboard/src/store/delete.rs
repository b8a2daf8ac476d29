//! Deleting runs: one run with everything that hangs off it, in one transaction
//! (`DELETE /api/runs/{run_id}`), and choosing which runs a retention rule drops
//! (`tessera-dashboard retention`), which then deletes each with the same [`delete_run`].
//!
//! What goes with a run: its scenario results, results, points, images and the blobs that no
//! other run's images use. Alerts stay: those whose before or after run it was are re-pointed to
//! the neighbouring runs of their series first ([`crate::store::alerts::repoint_for_deleted_run`]),
//! so that an alert keeps its id, group, history and triage (ids are never reused). Series stay
//! (other runs' points may use them; an empty series shows no points). Detection is re-run on the
//! run's series by [`crate::regressions::delete_and_detect`], which the server and retention use.
//! Not for: HTTP (see [`crate::server::delete`]).

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
    /// Alerts re-pointed away from the run (none is deleted).
    pub alerts: u64,
}

/// Deletes run `run_id` and what hangs off it, all or nothing. `NotFound` if there is no such run.
pub fn delete_run(conn: &mut dyn Connection, run_id: &str) -> Result<Deleted, StoreError> {
    let mut attempt = 0;
    loop {
        match transaction(conn, |c| delete_in_transaction(c, run_id).map(|d| d.0)) {
            Err(StoreError::Db(e)) if e.is_retryable() && attempt < 5 => attempt += 1,
            other => return other,
        }
    }
}

/// The body of [`delete_run`] for a caller that holds a transaction; also returns the series the
/// run had points in (for detection).
pub fn delete_in_transaction(
    c: &mut dyn Connection,
    run_id: &str,
) -> Result<(Deleted, Vec<i64>), StoreError> {
    let Some(row) = c.query_opt("SELECT id FROM runs WHERE run_id = $1", &[run_id.into()])? else {
        return Err(StoreError::NotFound(format!("run {run_id}")));
    };
    let pk = [Value::Int(row.i64(0)?)];
    let series = super::series::of_run(c, row.i64(0)?)?;
    let alerts = super::alerts::repoint_for_deleted_run(c, row.i64(0)?)?;
    // The points and the p5-p95 bands of the run's timed points (series charts).
    let points = super::series::delete_of_run(c, row.i64(0)?)?;
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
    // Its frame digests go; a frame approved from it stays approved, without its run.
    c.execute("DELETE FROM run_frames WHERE run_pk = $1", &pk)?;
    c.execute(
        "UPDATE approved_frames SET run_pk = NULL WHERE run_pk = $1",
        &pk,
    )?;
    let results = c.execute("DELETE FROM results WHERE run_pk = $1", &pk)?;
    c.execute("DELETE FROM scenario_results WHERE run_pk = $1", &pk)?;
    c.execute("DELETE FROM runs WHERE id = $1", &pk)?;
    Ok((
        Deleted {
            run_id: run_id.to_string(),
            results,
            points,
            images,
            blobs,
            alerts,
        },
        series,
    ))
}

/// Which runs a retention rule keeps. A run is kept when any given rule keeps it; with no rule
/// every run is kept. Runs are placed in time by their commit time, or, for a run without one, by
/// when the server stored it ([`order_time`]): never by the client's `started_at`, which a
/// runner's clock (or a bad upload) can put anywhere.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Retention {
    /// Keep runs whose commit (or, without one, storing) is at most this many days old.
    pub keep_days: Option<u32>,
    /// Keep the newest this many runs of each adapter (by commit time, else storing time).
    pub keep_runs: Option<u32>,
}

/// A run a retention rule would delete.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Expired {
    pub run_id: String,
    /// The time retention placed it at (RFC 3339 UTC) and which one it is: `commit` or `stored`.
    pub at: String,
    pub by: &'static str,
    pub adapter: String,
}

/// Where retention places a run: its commit time when it has one that parses, else the time the
/// server stored it; as RFC 3339 UTC to the second, which sorts as text.
pub fn order_time(commit_time: Option<&str>, imported_at: &str) -> (String, &'static str) {
    let norm = |t: &str| {
        chrono::DateTime::parse_from_rfc3339(t).ok().map(|d| {
            d.with_timezone(&chrono::Utc)
                .to_rfc3339_opts(chrono::SecondsFormat::Secs, true)
        })
    };
    match commit_time.and_then(norm) {
        Some(t) => (t, "commit"),
        None => (
            norm(imported_at).unwrap_or_else(|| imported_at.to_string()),
            "stored",
        ),
    }
}

/// The runs `rule` does not keep, oldest first. `now` is the server's clock (the cut-off is
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
        "SELECT r.run_id, r.commit_time, r.imported_at, r.adapter_id, a.name, r.id \
         FROM runs r JOIN adapters a ON a.id = r.adapter_id",
        &[],
    )?;
    // (at, imported_at, id): a total order; the newest last.
    let mut runs = Vec::with_capacity(rows.len());
    for r in &rows {
        let imported = r.string(2)?;
        let (at, by) = order_time(r.opt_string(1)?.as_deref(), &imported);
        runs.push((
            at,
            imported,
            r.i64(5)?,
            r.i64(3)?,
            r.string(0)?,
            by,
            r.string(4)?,
        ));
    }
    runs.sort();
    let mut per_adapter: std::collections::HashMap<i64, i64> = std::collections::HashMap::new();
    let mut rank = vec![0i64; runs.len()];
    for (i, r) in runs.iter().enumerate().rev() {
        let n = per_adapter.entry(r.3).or_insert(0);
        *n += 1;
        rank[i] = *n;
    }
    let cutoff = rule.keep_days.map(|d| {
        (now - chrono::Duration::days(d.into())).to_rfc3339_opts(chrono::SecondsFormat::Secs, true)
    });
    let mut out = Vec::new();
    for (i, (at, _, _, _, run_id, by, adapter)) in runs.into_iter().enumerate() {
        let kept_by_age = cutoff.as_ref().is_some_and(|c| at >= *c);
        let kept_by_count = rule.keep_runs.is_some_and(|n| rank[i] <= i64::from(n));
        if !kept_by_age && !kept_by_count {
            out.push(Expired {
                run_id,
                at,
                by,
                adapter,
            });
        }
    }
    Ok(out)
}
