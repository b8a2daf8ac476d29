//! Tessera's queries, written once against [`crate::db::Connection`] for both backends: storing a
//! run bundle, reading what each page shows, keeping regressions and their triage.
//!
//! Not for: SQL dialect details (see [`crate::db`]), HTTP or HTML.

pub mod adapter_pairs;
pub mod alerts;
pub mod baseline_moves;
pub mod blobs;
pub mod browse;
pub mod delete;
pub mod extras;
pub mod frames;
pub mod groups;
pub mod ingest;
pub mod noise;
pub mod outbox;
pub mod queue;
pub mod read;
pub mod records;
pub mod run_cache;
pub mod series;
pub mod stoppage;
pub mod tokens;
pub mod triage;

use crate::db::{Connection, DbError};

/// Errors of the store's queries.
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    #[error(transparent)]
    Db(#[from] DbError),
    #[error("stored record is corrupt: {0}")]
    Corrupt(String),
    #[error("{0} not found")]
    NotFound(String),
    #[error("{0}")]
    Invalid(String),
    /// The request contradicts what is stored (a run id stored with different content).
    #[error("{0}")]
    Conflict(String),
}

/// The row id of run `run_id`.
pub(crate) fn run_pk(conn: &mut dyn Connection, run_id: &str) -> Result<i64, StoreError> {
    conn.query_opt("SELECT id FROM runs WHERE run_id = $1", &[run_id.into()])?
        .ok_or_else(|| StoreError::NotFound(format!("run {run_id}")))?
        .i64(0)
        .map_err(Into::into)
}
