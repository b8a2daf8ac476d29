//! Triage of detected regressions: a state (`new`, `acknowledged`, `invalid`, `fixed`,
//! `ignored`), a note, a bug link, who changed it and when, kept in the store so that everyone
//! sees the same. Set per alert, or per alert group ([`set_group`]: every alert of the group in
//! one transaction). Not for: detection, grouping (see [`super::groups`]).

use super::{groups, StoreError};
use crate::db::{transaction, Connection, Value};

pub const STATES: [&str; 5] = ["new", "acknowledged", "invalid", "fixed", "ignored"];

/// Longest note and bug link accepted, in bytes.
pub const MAX_NOTE: usize = 4000;
pub const MAX_BUG_URL: usize = 2000;

/// What a person sets on an alert or a group.
#[derive(Clone, Debug, Default, PartialEq, serde::Deserialize)]
pub struct Triage {
    pub state: String,
    #[serde(default)]
    pub note: String,
    /// An `http://` or `https://` link to the bug, or empty.
    #[serde(default)]
    pub bug_url: String,
}

impl Triage {
    /// Checks state, note and bug link, with a message that says what is allowed.
    pub fn validate(&self) -> Result<(), StoreError> {
        if !STATES.contains(&self.state.as_str()) {
            return Err(StoreError::Invalid(format!(
                "state {:?} is not one of {}",
                self.state,
                STATES.join(", ")
            )));
        }
        if self.note.len() > MAX_NOTE {
            return Err(StoreError::Invalid(format!(
                "note is longer than {MAX_NOTE} bytes"
            )));
        }
        let url = self.bug_url.trim();
        if !url.is_empty()
            && (url.len() > MAX_BUG_URL
                || !(url.starts_with("https://") || url.starts_with("http://"))
                || url.chars().any(|c| c.is_whitespace() || c.is_control()))
        {
            return Err(StoreError::Invalid(format!(
                "bug_url must be an http:// or https:// link without spaces, at most {MAX_BUG_URL} bytes"
            )));
        }
        Ok(())
    }
}

/// Sets the state and note of regression `id` (bug link unchanged, nobody named).
pub fn set(conn: &mut dyn Connection, id: i64, state: &str, note: &str) -> Result<(), StoreError> {
    set_alert(conn, id, state, note, "")
}

/// Sets the state and note of regression `id`, recording who did it.
pub fn set_alert(
    conn: &mut dyn Connection,
    id: i64,
    state: &str,
    note: &str,
    who: &str,
) -> Result<(), StoreError> {
    Triage {
        state: state.into(),
        note: note.into(),
        bug_url: String::new(),
    }
    .validate()?;
    let n = conn.execute(
        "UPDATE regressions SET state = $1, note = $2, updated_at = $3, updated_by = $4 WHERE id = $5",
        &[
            state.into(),
            note.into(),
            crate::now_rfc3339().into(),
            who.into(),
            Value::Int(id),
        ],
    )?;
    if n == 0 {
        return Err(StoreError::NotFound(format!("regression {id}")));
    }
    Ok(())
}

/// Sets state, note and bug link on every alert of group `key` in one transaction, recording who
/// did it; returns how many alerts it set.
pub fn set_group(
    conn: &mut dyn Connection,
    key: &str,
    t: &Triage,
    who: &str,
) -> Result<usize, StoreError> {
    t.validate()?;
    let now = crate::now_rfc3339();
    transaction(conn, |c| {
        let ids = groups::alert_ids(c, key)?;
        if ids.is_empty() {
            return Err(StoreError::NotFound(format!("alert group {key:?}")));
        }
        let mut n = 0;
        for id in &ids {
            n += c.execute(
                "UPDATE regressions SET state = $1, note = $2, bug_url = $3, updated_by = $4, updated_at = $5
                 WHERE id = $6",
                &[
                    t.state.as_str().into(),
                    t.note.as_str().into(),
                    t.bug_url.trim().into(),
                    who.into(),
                    now.as_str().into(),
                    Value::Int(*id),
                ],
            )? as usize;
        }
        Ok::<_, StoreError>(n)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bug_links_must_be_http() {
        let t = |url: &str| Triage {
            state: "acknowledged".into(),
            note: String::new(),
            bug_url: url.into(),
        };
        assert!(t("").validate().is_ok());
        assert!(t("https://bugs.example/1").validate().is_ok());
        for bad in ["javascript:alert(1)", "ftp://x", "https://a b", "bugs/1"] {
            assert!(t(bad).validate().is_err(), "{bad}");
        }
        let mut s = t("");
        s.state = "closed".into();
        assert!(s.validate().unwrap_err().to_string().contains("invalid"));
    }
}
