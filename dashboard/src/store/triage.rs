//! Triage of detected changes: a state ([`TriageState`]), a note, a bug link, who changed it and
//! when, kept in the store so that everyone sees the same. Set per alert, or per alert group
//! ([`set_group`]: every alert of the group in one statement). The rows are
//! [`super::alerts`]'s; this module checks what a person asks for and names the group.
//!
//! Not for: detection, grouping (see [`super::groups`]).

use super::alerts::{self, TriageSet, TriageState};
use super::{groups, StoreError};
use crate::db::{transaction, Connection};

/// The triage states, as words (pickers, messages).
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
    pub fn validate(&self) -> Result<TriageState, StoreError> {
        let state: TriageState = self.state.parse()?;
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
        Ok(state)
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
    let state = Triage {
        state: state.into(),
        note: note.into(),
        bug_url: String::new(),
    }
    .validate()?;
    let t = TriageSet {
        state,
        note,
        bug_url: None,
        who,
    };
    if !alerts::set_triage(conn, id, &t)? {
        return Err(StoreError::NotFound(format!("regression {id}")));
    }
    Ok(())
}

/// Sets state, note and bug link on every alert of group `name` (its id, or a commit range it
/// is or was shown under) in one transaction, recording who did it; returns the group's id and
/// how many alerts it set.
pub fn set_group(
    conn: &mut dyn Connection,
    name: &str,
    t: &Triage,
    who: &str,
) -> Result<(i64, usize), StoreError> {
    let state = t.validate()?;
    transaction(conn, |c| {
        let id = groups::resolve(c, name)?.id();
        let set = TriageSet {
            state,
            note: &t.note,
            bug_url: Some(t.bug_url.trim()),
            who,
        };
        let n = alerts::set_group_triage(c, id, &set)?;
        if n == 0 {
            return Err(StoreError::NotFound(format!("alert group {name:?}")));
        }
        Ok::<_, StoreError>((id, n))
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
        assert!(s.validate().unwrap_err().to_string().contains("not one of"));
    }

    #[test]
    fn the_words_are_the_enums() {
        assert_eq!(STATES.to_vec(), TriageState::names());
    }
}
