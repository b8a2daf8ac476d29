//! The webhook's outbox: one row per (webhook target, alert group) saying whether the group was
//! sent, is waiting for its next attempt, was given up on, or was already there when the webhook
//! was first configured (`baseline`, never sent). Kept in the store so that a restart of the
//! server neither loses nor repeats a notification.
//!
//! Not for: deciding what to send or sending it (see [`crate::notify::webhook`]).

use serde::Serialize;

use super::StoreError;
use crate::db::{Connection, Value};

/// A delivery's state: waiting to be (re)tried, delivered, given up, or never to be sent.
pub const PENDING: &str = "pending";
pub const SENT: &str = "sent";
pub const FAILED: &str = "failed";
pub const BASELINE: &str = "baseline";

#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Delivery {
    pub group_key: String,
    pub state: String,
    pub attempts: i64,
    pub next_attempt_at: String,
    pub last_error: String,
    pub created_at: String,
    pub sent_at: Option<String>,
}

/// Records `target` as configured; `true` the first time (its groups then are the baseline).
pub fn register_target(
    conn: &mut dyn Connection,
    target: &str,
    now: &str,
) -> Result<bool, StoreError> {
    Ok(conn.execute(
        "INSERT INTO webhook_targets (target, created_at) VALUES ($1, $2) ON CONFLICT DO NOTHING",
        &[target.into(), now.into()],
    )? == 1)
}

/// Adds group `key` in `state` (`pending` or `baseline`) unless the target has it; `true` if added.
pub fn add(
    conn: &mut dyn Connection,
    target: &str,
    key: &str,
    state: &str,
    now: &str,
) -> Result<bool, StoreError> {
    Ok(conn.execute(
        "INSERT INTO webhook_deliveries (target, group_key, state, attempts, next_attempt_at, last_error, created_at)
         VALUES ($1, $2, $3, 0, $4, '', $4) ON CONFLICT DO NOTHING",
        &[target.into(), key.into(), state.into(), now.into()],
    )? == 1)
}

/// Group keys the target has any row for.
pub fn known(conn: &mut dyn Connection, target: &str) -> Result<Vec<String>, StoreError> {
    Ok(conn
        .query(
            "SELECT group_key FROM webhook_deliveries WHERE target = $1",
            &[target.into()],
        )?
        .iter()
        .map(|r| r.string(0))
        .collect::<Result<_, _>>()?)
}

fn delivery(r: &crate::db::Row) -> Result<Delivery, StoreError> {
    Ok(Delivery {
        group_key: r.string(0)?,
        state: r.string(1)?,
        attempts: r.i64(2)?,
        next_attempt_at: r.string(3)?,
        last_error: r.string(4)?,
        created_at: r.string(5)?,
        sent_at: r.opt_string(6)?,
    })
}

const COLUMNS: &str =
    "group_key, state, attempts, next_attempt_at, last_error, created_at, sent_at";

/// Pending deliveries whose next attempt is due at `now`, oldest first.
pub fn due(
    conn: &mut dyn Connection,
    target: &str,
    now: &str,
    limit: i64,
) -> Result<Vec<Delivery>, StoreError> {
    conn.query(
        &format!(
            "SELECT {COLUMNS} FROM webhook_deliveries
             WHERE target = $1 AND state = 'pending' AND next_attempt_at <= $2
             ORDER BY next_attempt_at, created_at, group_key LIMIT $3"
        ),
        &[target.into(), now.into(), Value::Int(limit)],
    )?
    .iter()
    .map(delivery)
    .collect()
}

/// Every delivery of a target (for tests and inspection).
pub fn all(conn: &mut dyn Connection, target: &str) -> Result<Vec<Delivery>, StoreError> {
    conn.query(
        &format!(
            "SELECT {COLUMNS} FROM webhook_deliveries WHERE target = $1 ORDER BY created_at, group_key"
        ),
        &[target.into()],
    )?
    .iter()
    .map(delivery)
    .collect()
}

/// Stores an attempt's outcome: `d`'s state, attempts, next attempt, last error and sent time.
pub fn update(conn: &mut dyn Connection, target: &str, d: &Delivery) -> Result<(), StoreError> {
    conn.execute(
        "UPDATE webhook_deliveries SET state = $1, attempts = $2, next_attempt_at = $3, last_error = $4, sent_at = $5
         WHERE target = $6 AND group_key = $7",
        &[
            d.state.as_str().into(),
            Value::Int(d.attempts),
            d.next_attempt_at.as_str().into(),
            d.last_error.as_str().into(),
            d.sent_at.clone().into(),
            target.into(),
            d.group_key.as_str().into(),
        ],
    )?;
    Ok(())
}
