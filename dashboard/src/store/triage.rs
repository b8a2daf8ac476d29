//! Triage of detected regressions: state (`new`, `acknowledged`, `ignored`, `fixed`) and a note,
//! kept in the store so that everyone sees the same. Not for: detection.

use super::StoreError;
use crate::db::{Connection, Value};

pub const STATES: [&str; 4] = ["new", "acknowledged", "ignored", "fixed"];

/// Sets the state and note of regression `id`.
pub fn set(conn: &mut dyn Connection, id: i64, state: &str, note: &str) -> Result<(), StoreError> {
    if !STATES.contains(&state) {
        return Err(StoreError::Invalid(format!(
            "state {state:?} is not one of {}",
            STATES.join(", ")
        )));
    }
    if note.len() > 4000 {
        return Err(StoreError::Invalid("note is longer than 4000 bytes".into()));
    }
    let n = conn.execute(
        "UPDATE regressions SET state = $1, note = $2, updated_at = $3 WHERE id = $4",
        &[
            state.into(),
            note.into(),
            crate::now_rfc3339().into(),
            Value::Int(id),
        ],
    )?;
    if n == 0 {
        return Err(StoreError::NotFound(format!("regression {id}")));
    }
    Ok(())
}
