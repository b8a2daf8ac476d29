//! Regression detection applied to stored series, online: every pass over a series re-derives its
//! alerts from the data and brings the stored ones in line, so that alerts after any sequence of
//! uploads equal those of one batch pass over the same data.
//!
//! One pass over a series ([`update_series`]):
//! 1. reads the newest `window` points in commit order ([`window`], an index range of `points`);
//! 2. runs [`crate::detect::analyse`] on them; a change point is *pending* until `confirm_after`
//!    points (in its environment segment) follow the last commit of its range, and twice that while
//!    its range holds more than one commit; then *confirmed* ([`find`]);
//! 3. reconciles ([`plan`]) with the series' stored alerts in the *open* part of the window (all of
//!    it while the series is shorter than the window, else all but its oldest quarter, whose alerts
//!    are final): a change is the alert stored at its commit, else the nearest open alert within
//!    [`SAME_CHANGE_WITHIN`] points in the same direction (which then *moves* there, triage and
//!    all); other open alerts near a matched one are *merged* into it; the rest are *withdrawn*.
//!    A *confirmed* alert moves only on strong new evidence ([`move_reason`]): a run backfilled
//!    inside its range, or a location probability at its commit below [`STRONG_EVIDENCE`];
//!    otherwise it stays where it was announced. Rows are never deleted; every transition is a
//!    `regression_events` row, and a move says why.
//!
//! [`ingest_and_detect`] stores a run and runs this on the series it touched in one transaction, so
//! a crash cannot leave a stored run unanalysed.
//!
//! [`delete_and_detect`] deletes a run and re-runs this on the series it had points in, so the
//! alerts that named it keep their id, group and triage.
//!
//! Not for: the statistics (see [`crate::detect`]), the alert row (see [`crate::store::alerts`])
//! or triage (see [`crate::store::triage`]).

use std::collections::{BTreeMap, BTreeSet};

use crate::bundle::RunBundle;
use crate::db::{transaction, Connection};
use crate::detect::{analyse, Analysis, ChangePoint, Params};
use crate::store::alerts::{self, DetectionStatus, Placement};
use crate::store::ingest::{ingest_in_transaction, Ingested};
use crate::store::series;
use crate::store::StoreError;

pub use crate::store::alerts::StoredAlert;
pub use crate::store::series::{
    all_series, points, window, Environments, SeriesPoint, WindowPoint,
};

/// A change point within this many points of an open alert, in the same direction, is that alert.
pub const SAME_CHANGE_WITHIN: usize = 3;

/// Alert statuses (`regressions.status`).
pub const PENDING: DetectionStatus = DetectionStatus::Pending;
pub const CONFIRMED: DetectionStatus = DetectionStatus::Confirmed;
pub const WITHDRAWN: DetectionStatus = DetectionStatus::Withdrawn;

/// A confirmed alert moves to another commit without a backfill inside its range only when the
/// location probability at its own commit has fallen below this.
pub const STRONG_EVIDENCE: f64 = 0.01;

/// A change point found in the window, with its status.
#[derive(Clone, Debug, PartialEq)]
pub struct Found {
    pub change: ChangePoint,
    pub status: DetectionStatus,
}

/// What reconciliation does to the store.
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    /// A new alert.
    Insert { found: usize },
    /// Alert `id` now describes change `found` (moved if its commit differs, status updated).
    Update { id: i64, found: usize },
    /// Alert `id` is withdrawn: the data no longer supports it (`into: None`) or it duplicates the
    /// alert `into`.
    Withdraw { id: i64, into: Option<i64> },
}

/// Counts of what a detection pass did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Changes {
    pub detected: usize,
    pub moved: usize,
    pub merged: usize,
    pub withdrawn: usize,
    pub confirmed: usize,
    pub reinstated: usize,
}

impl std::ops::AddAssign for Changes {
    fn add_assign(&mut self, o: Changes) {
        self.detected += o.detected;
        self.moved += o.moved;
        self.merged += o.merged;
        self.withdrawn += o.withdrawn;
        self.confirmed += o.confirmed;
        self.reinstated += o.reinstated;
    }
}

/// The change points of a window with their status (pure).
pub fn find(pts: &[WindowPoint], params: &Params) -> Vec<Found> {
    let values: Vec<f64> = pts.iter().map(|p| p.value).collect();
    let env: Vec<u32> = pts.iter().map(|p| p.environment).collect();
    let analysis = analyse(&values, &env, params);
    analysis
        .change_points
        .iter()
        .map(|c| Found {
            status: status(&analysis, c, pts.len(), params),
            change: c.clone(),
        })
        .collect()
}

/// Confirmed only once the runs after the *latest* commit change `c` may lie at (its range's
/// last candidate) number `confirm_after`, and twice that while the range holds more than one
/// commit: a confirmed alert stays where it was announced, so it is not announced while its
/// location is still spread over the range (pending alerts follow the data).
fn status(analysis: &Analysis, c: &ChangePoint, len: usize, params: &Params) -> DetectionStatus {
    let after = analysis.points_after(c.index.max(c.last_candidate), len);
    let needed = if c.first_candidate == c.last_candidate {
        params.confirm_after
    } else {
        2 * params.confirm_after
    };
    if after < needed {
        PENDING
    } else {
        CONFIRMED
    }
}

/// Index of the first point whose alerts are still open: 0 while the series fits in the window.
pub fn open_from(window_len: usize, params: &Params) -> usize {
    if window_len < params.window {
        0
    } else {
        params.window / 4
    }
}

/// Reconciles found changes with stored alerts (pure). `pks` are the window's run ids in order;
/// only alerts whose `run_pk_after` lies at or after `open_from` take part.
pub fn plan(pks: &[i64], open_from: usize, found: &[Found], alerts: &[StoredAlert]) -> Vec<Action> {
    let pos: BTreeMap<i64, usize> = pks.iter().enumerate().map(|(i, &pk)| (pk, i)).collect();
    let alerts: Vec<(usize, &StoredAlert)> = alerts
        .iter()
        .filter_map(|a| pos.get(&a.run_pk_after).map(|&i| (i, a)))
        .filter(|&(i, _)| i >= open_from)
        .collect();
    let found_idx: Vec<usize> = (0..found.len())
        .filter(|&f| found[f].change.index >= open_from.max(1))
        .collect();
    let mut matched: BTreeMap<usize, i64> = BTreeMap::new(); // found -> alert id
    let mut used: BTreeSet<i64> = BTreeSet::new();
    // 1. The alert stored at a change's own commit is that change's, whatever its status.
    for &f in &found_idx {
        if let Some(&(_, a)) = alerts.iter().find(|(i, _)| *i == found[f].change.index) {
            matched.insert(f, a.id);
            used.insert(a.id);
        }
    }
    // 2. Else the nearest open alert in the same direction moves to it.
    for &f in &found_idx {
        if matched.contains_key(&f) {
            continue;
        }
        let c = &found[f].change;
        let best = alerts
            .iter()
            .filter(|(i, a)| {
                !used.contains(&a.id)
                    && a.status != WITHDRAWN
                    && i.abs_diff(c.index) <= SAME_CHANGE_WITHIN
                    && (a.relative_change > 0.0) == (c.relative_change > 0.0)
            })
            .min_by_key(|(i, a)| (i.abs_diff(c.index), a.id));
        if let Some(&(_, a)) = best {
            matched.insert(f, a.id);
            used.insert(a.id);
        }
    }
    let mut actions = Vec::new();
    for &f in &found_idx {
        actions.push(match matched.get(&f) {
            Some(&id) => Action::Update { id, found: f },
            None => Action::Insert { found: f },
        });
    }
    // 3. Open alerts left over: merged into a kept alert near them, else withdrawn.
    for &(i, a) in &alerts {
        if used.contains(&a.id) || a.status == WITHDRAWN {
            continue;
        }
        let into = matched
            .iter()
            .filter(|(&f, _)| {
                let c = &found[f].change;
                i.abs_diff(c.index) <= SAME_CHANGE_WITHIN
                    && (a.relative_change > 0.0) == (c.relative_change > 0.0)
            })
            .map(|(_, &id)| id)
            .next();
        actions.push(Action::Withdraw { id: a.id, into });
    }
    actions
}

fn describe(f: &Found) -> String {
    format!(
        "{:+.1}% ({:.4} -> {:.4}), {}",
        f.change.relative_change * 100.0,
        f.change.before,
        f.change.after,
        f.status
    )
}

/// Why confirmed alert `old` may move to the change `f` (at window index `f.change.index`), or
/// `None` when it stays where it was announced. `pks` are the window's runs in order.
pub fn move_reason(old: &StoredAlert, f: &Found, pks: &[i64]) -> Option<String> {
    let at = |pk: i64| pks.iter().position(|&p| p == pk);
    let (Some(b), Some(a)) = (at(old.run_pk_before), at(old.run_pk_after)) else {
        return Some("its runs are no longer both in the window".into());
    };
    if a > b + 1 {
        return Some(format!(
            "backfill: {} run{} landed inside its range",
            a - b - 1,
            if a - b - 1 == 1 { "" } else { "s" }
        ));
    }
    let p_old = f.change.probability_at(a);
    if p_old < STRONG_EVIDENCE {
        return Some(format!(
            "strong new evidence: location probability {:.1}% at the new commit, {:.2}% at the old one",
            f.change.location_probability() * 100.0,
            p_old * 100.0
        ));
    }
    None
}

fn placement(f: &Found, pks: &[i64], at: usize) -> Placement {
    let c = &f.change;
    Placement {
        run_pk_before: pks[at - 1],
        run_pk_after: pks[at],
        value_before: c.before,
        value_after: c.after,
        relative_change: c.relative_change,
        change_low: c.change_low,
        change_high: c.change_high,
        confidence: c.confidence,
        location_probability: c.probability_at(at),
        first_candidate: pks[c.first_candidate.min(at)],
        last_candidate: pks[c.last_candidate.max(at)],
        status: f.status,
    }
}

/// One detection pass over one series (see the module doc). Runs inside the caller's transaction.
pub fn update_series(
    conn: &mut dyn Connection,
    series_id: i64,
    params: &Params,
    envs: &mut Environments,
) -> Result<Changes, StoreError> {
    let alerts = alerts::of_series(conn, series_id)?;
    update_series_with(conn, series_id, params, envs, alerts)
}

/// [`update_series`] with the series' stored alerts already read.
fn update_series_with(
    conn: &mut dyn Connection,
    series_id: i64,
    params: &Params,
    envs: &mut Environments,
    alerts: Vec<StoredAlert>,
) -> Result<Changes, StoreError> {
    let pts = window(conn, series_id, params.window, envs)?;
    let found = find(&pts, params);
    if found.is_empty() && alerts.iter().all(|a| a.status == WITHDRAWN) {
        return Ok(Changes::default());
    }
    let pks: Vec<i64> = pts.iter().map(|p| p.run_pk).collect();
    let by_id: BTreeMap<i64, &StoredAlert> = alerts.iter().map(|a| (a.id, a)).collect();
    let mut changes = Changes::default();
    for action in plan(&pks, open_from(pts.len(), params), &found, &alerts) {
        match action {
            Action::Insert { found: f } => {
                let f = &found[f];
                let id = alerts::insert(conn, series_id, &placement(f, &pks, f.change.index))?;
                alerts::event(conn, id, "detected", describe(f))?;
                changes.detected += 1;
            }
            Action::Update { id, found: f } => {
                let f = &found[f];
                let old = by_id[&id];
                let mut at = f.change.index;
                if pks[at] != old.run_pk_after {
                    let reason = if old.status == CONFIRMED {
                        move_reason(old, f, &pks)
                    } else {
                        Some(format!("{} alerts follow the data", old.status))
                    };
                    match reason {
                        Some(reason) => {
                            let from = alerts::run_label(conn, old.run_pk_after)?;
                            let to = alerts::run_label(conn, pks[at])?;
                            alerts::event(
                                conn,
                                id,
                                "moved",
                                format!("from {from} to {to} ({reason}): {}", describe(f)),
                            )?;
                            changes.moved += 1;
                        }
                        // Stays where it was announced: the evidence for the new commit is weak.
                        None => {
                            at = pks
                                .iter()
                                .position(|&p| p == old.run_pk_after)
                                .expect("move_reason checked it");
                        }
                    }
                }
                if old.status != f.status {
                    let kind = if old.status == WITHDRAWN {
                        changes.reinstated += 1;
                        "reinstated"
                    } else if f.status == CONFIRMED {
                        changes.confirmed += 1;
                        "confirmed"
                    } else {
                        "pending"
                    };
                    alerts::event(conn, id, kind, describe(f))?;
                }
                alerts::place(conn, id, &placement(f, &pks, at))?;
            }
            Action::Withdraw { id, into } => {
                alerts::set_status(conn, id, WITHDRAWN)?;
                match into {
                    Some(into) => {
                        alerts::event(conn, id, "merged", format!("into alert {into}"))?;
                        changes.merged += 1;
                    }
                    None => {
                        alerts::event(
                            conn,
                            id,
                            "withdrawn",
                            "no change point here any more".into(),
                        )?;
                        changes.withdrawn += 1;
                    }
                }
            }
        }
    }
    Ok(changes)
}

/// Stores `bundle` and runs detection on the series it touched, in one transaction (retried on a
/// write conflict): the path of every upload and import.
pub fn ingest_and_detect(
    conn: &mut dyn Connection,
    bundle: &RunBundle,
    params: &Params,
) -> Result<(Ingested, Changes), StoreError> {
    let mut attempt = 0;
    loop {
        let outcome = transaction(conn, |c| {
            let ingested = ingest_in_transaction(c, bundle)?;
            let mut changes = Changes::default();
            if let Ingested::Stored { run_pk, series, .. } = &ingested {
                series::lock_of_run(c, *run_pk)?;
                let mut envs = Environments::default();
                let mut stored_alerts = alerts::of_series_in(c, series)?;
                for &id in series {
                    let stored = stored_alerts.remove(&id).unwrap_or_default();
                    changes += update_series_with(c, id, params, &mut envs, stored)?;
                }
            }
            Ok::<_, StoreError>((ingested, changes))
        });
        match outcome {
            Err(StoreError::Db(e)) if e.is_retryable() && attempt < 5 => attempt += 1,
            other => return other,
        }
    }
}

/// Deletes run `run_id` ([`crate::store::delete`]) and runs detection on the series it had points
/// in, in one transaction (retried on a write conflict): the alerts that named the run are
/// re-pointed first, so they keep their id, group and triage, and then follow the data.
pub fn delete_and_detect(
    conn: &mut dyn Connection,
    run_id: &str,
    params: &Params,
) -> Result<(crate::store::delete::Deleted, Changes), StoreError> {
    let mut attempt = 0;
    loop {
        let outcome = transaction(conn, |c| {
            let (deleted, series) = crate::store::delete::delete_in_transaction(c, run_id)?;
            let mut envs = Environments::default();
            let mut changes = Changes::default();
            for id in series {
                changes += update_series(c, id, params, &mut envs)?;
            }
            Ok::<_, StoreError>((deleted, changes))
        });
        match outcome {
            Err(StoreError::Db(e)) if e.is_retryable() && attempt < 5 => attempt += 1,
            other => return other,
        }
    }
}

/// Runs detection on the given series, 64 series per transaction; returns what changed.
pub fn update_all(
    conn: &mut dyn Connection,
    series: &[i64],
    params: &Params,
) -> Result<Changes, StoreError> {
    let mut changes = Changes::default();
    let mut envs = Environments::default();
    for chunk in series.chunks(64) {
        changes += transaction(conn, |c| {
            for &id in chunk {
                series::lock(c, id)?;
            }
            let mut ch = Changes::default();
            for &id in chunk {
                ch += update_series(c, id, params, &mut envs)?;
            }
            Ok::<_, StoreError>(ch)
        })?;
    }
    Ok(changes)
}

/// Runs detection on the given series; returns how many alerts were new.
pub fn update(
    conn: &mut dyn Connection,
    series: &[i64],
    params: &Params,
) -> Result<usize, StoreError> {
    Ok(update_all(conn, series, params)?.detected)
}

#[cfg(test)]
mod tests;
