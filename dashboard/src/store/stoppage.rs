//! Data stoppage: an adapter that has stopped reporting a suite ("NVIDIA H200: no perf run for 3
//! nights (usually every night)"). Per (adapter, suite) the runs' times (commit time, else start)
//! give the usual gap between runs (the median gap, in whole nights, at least 1); when more nights
//! than that have passed since the newest run, the pair has stopped. Pairs with fewer than
//! [`MIN_RUNS`] runs have no usual gap yet and never alert. Shown on the regressions page and in
//! the Atom feed beside the alert groups.
//!
//! Not for: changes in the data (see [`crate::regressions`]).

use serde::Serialize;

use super::StoreError;
use crate::db::Connection;

/// Runs of an (adapter, suite) needed before its usual gap is known.
pub const MIN_RUNS: usize = 3;

/// A silence longer than this many nights is an adapter or suite that was retired, not a
/// stoppage to act on: it is no longer listed.
pub const MAX_NIGHTS: i64 = 30;

const NIGHT_S: i64 = 86_400;

/// One adapter that stopped reporting one suite.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Stoppage {
    pub adapter_id: i64,
    pub adapter: String,
    /// The suite (`(no suite)` for runs without one).
    pub suite: String,
    /// The newest run and its time.
    pub last_run: String,
    pub last_at: String,
    /// Whole nights since the newest run.
    pub nights: i64,
    /// The usual gap between runs, in nights.
    pub usual_gap: i64,
    /// `NVIDIA H200: no perf run for 3 nights (usually every night)`.
    pub message: String,
}

fn nights_phrase(n: i64) -> String {
    if n == 1 {
        "every night".into()
    } else {
        format!("every {n} nights")
    }
}

/// Every (adapter, suite) that has not reported for more nights than its usual gap, as of `now`
/// (RFC 3339), longest silence first.
pub fn stoppages(conn: &mut dyn Connection, now: &str) -> Result<Vec<Stoppage>, StoreError> {
    let Some(now) = super::browse::parse_time(now) else {
        return Ok(Vec::new());
    };
    let rows = conn.query(
        "SELECT r.adapter_id, a.name, r.suite, r.run_id, COALESCE(r.commit_time, r.started_at)
         FROM runs r JOIN adapters a ON a.id = r.adapter_id
         ORDER BY r.adapter_id, r.suite, COALESCE(r.commit_time, r.started_at), r.id",
        &[],
    )?;
    // (adapter id, suite), adapter name, runs as (run id, time, seconds since the epoch).
    type Key = (i64, Option<String>);
    type Runs = Vec<(String, String, i64)>;
    let mut groups: Vec<(Key, String, Runs)> = Vec::new();
    for r in &rows {
        let key = (r.i64(0)?, r.opt_string(2)?);
        let at = r.string(4)?;
        let Some(t) = super::browse::parse_time(&at) else {
            continue;
        };
        if groups.last().is_none_or(|g| g.0 != key) {
            groups.push((key.clone(), r.string(1)?, Vec::new()));
        }
        groups
            .last_mut()
            .expect("pushed above")
            .2
            .push((r.string(3)?, at, t));
    }
    let mut out = Vec::new();
    for ((adapter_id, suite), adapter, runs) in groups {
        if runs.len() < MIN_RUNS {
            continue;
        }
        let mut gaps: Vec<i64> = runs
            .windows(2)
            .map(|w| ((w[1].2 - w[0].2) as f64 / NIGHT_S as f64).round() as i64)
            .collect();
        gaps.sort_unstable();
        let usual_gap = gaps[gaps.len() / 2].max(1);
        let (last_run, last_at, t) = runs.last().expect("at least MIN_RUNS").clone();
        let nights = (now - t).div_euclid(NIGHT_S);
        if nights > usual_gap && nights <= MAX_NIGHTS.max(usual_gap * 2) {
            let suite = suite.unwrap_or_else(|| "(no suite)".into());
            out.push(Stoppage {
                message: format!(
                    "{adapter}: no {suite} run for {nights} nights (usually {})",
                    nights_phrase(usual_gap)
                ),
                adapter_id,
                adapter,
                suite,
                last_run,
                last_at,
                nights,
                usual_gap,
            });
        }
    }
    out.sort_by(|x, y| y.nights.cmp(&x.nights).then(x.message.cmp(&y.message)));
    Ok(out)
}
