//! Named API tokens: each has a name, a scope (`read`, `runner` or `write`) and a secret that is shown once
//! when it is made and stored only as its SHA-256, so a copy of the store never holds a usable
//! token. Revoking a token deletes its row; its name can then be used again.
//!
//! Not for: checking a request's token (see [`crate::server::auth`]).

use base64::Engine;
use sha2::{Digest, Sha256};

use super::StoreError;
use crate::db::{Connection, Value};

/// What a token may do. `Write` includes `Runner`, which includes `Read`. A `Runner` token may
/// register runners, claim, heartbeat, complete and fail jobs, and upload the runs of jobs its
/// runners hold: nothing else.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Scope {
    Read,
    Runner,
    Write,
}

impl Scope {
    pub fn as_str(self) -> &'static str {
        match self {
            Scope::Read => "read",
            Scope::Runner => "runner",
            Scope::Write => "write",
        }
    }

    /// Whether a token of this scope may do what `needed` asks.
    pub fn allows(self, needed: Scope) -> bool {
        self >= needed
    }
}

impl std::str::FromStr for Scope {
    type Err = String;
    fn from_str(s: &str) -> Result<Scope, String> {
        match s {
            "read" => Ok(Scope::Read),
            "runner" => Ok(Scope::Runner),
            "write" => Ok(Scope::Write),
            _ => Err(format!("scope {s:?} is not one of read, runner, write")),
        }
    }
}

/// The name the legacy `--token` / `TESSERA_DASHBOARD_TOKEN` goes by; no stored token may use it.
pub const LEGACY_NAME: &str = "legacy";

/// A stored token as listed: never its secret.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct TokenInfo {
    pub name: String,
    pub scope: Scope,
    pub created_at: String,
}

/// A stored token as the server checks it: the SHA-256 of its secret.
#[derive(Clone, Debug)]
pub struct StoredToken {
    pub name: String,
    pub scope: Scope,
    pub secret_sha256: [u8; 32],
}

/// SHA-256 of a secret, as stored.
pub fn hash(secret: &str) -> [u8; 32] {
    Sha256::digest(secret.as_bytes()).into()
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

fn unhex(s: &str) -> Option<[u8; 32]> {
    let mut out = [0u8; 32];
    if s.len() != 64 {
        return None;
    }
    for (i, o) in out.iter_mut().enumerate() {
        *o = u8::from_str_radix(s.get(2 * i..2 * i + 2)?, 16).ok()?;
    }
    Some(out)
}

/// A new secret: `tsr_` and 32 bytes from the operating system's random source, base64url.
pub fn new_secret() -> Result<String, StoreError> {
    let mut bytes = [0u8; 32];
    getrandom::getrandom(&mut bytes)
        .map_err(|e| StoreError::Invalid(format!("no random source for a token: {e}")))?;
    Ok(format!(
        "tsr_{}",
        base64::engine::general_purpose::URL_SAFE_NO_PAD.encode(bytes)
    ))
}

fn check_name(name: &str) -> Result<(), StoreError> {
    let ok_chars = name
        .chars()
        .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'));
    if name.is_empty() || name.len() > 64 || !ok_chars {
        return Err(StoreError::Invalid(format!(
            "token name {name:?}: use 1 to 64 letters, digits, '-', '_' or '.'"
        )));
    }
    if name == LEGACY_NAME {
        return Err(StoreError::Invalid(format!(
            "token name {LEGACY_NAME:?} is reserved for --token / TESSERA_DASHBOARD_TOKEN"
        )));
    }
    Ok(())
}

/// Makes token `name` with `scope`; returns its secret, which is not stored and cannot be shown
/// again.
pub fn add(conn: &mut dyn Connection, name: &str, scope: Scope) -> Result<String, StoreError> {
    check_name(name)?;
    let secret = new_secret()?;
    let n = conn.execute(
        "INSERT INTO api_tokens (name, scope, secret_sha256, created_at) VALUES ($1, $2, $3, $4) \
         ON CONFLICT (name) DO NOTHING",
        &[
            name.into(),
            scope.as_str().into(),
            hex(&hash(&secret)).into(),
            crate::now_rfc3339().into(),
        ],
    )?;
    if n == 0 {
        return Err(StoreError::Invalid(format!(
            "a token named {name:?} exists: revoke it first or pick another name"
        )));
    }
    Ok(secret)
}

/// Every token, by name.
pub fn list(conn: &mut dyn Connection) -> Result<Vec<TokenInfo>, StoreError> {
    conn.query(
        "SELECT name, scope, created_at FROM api_tokens ORDER BY name",
        &[],
    )?
    .iter()
    .map(|r| {
        Ok(TokenInfo {
            name: r.string(0)?,
            scope: r.str(1)?.parse().map_err(StoreError::Corrupt)?,
            created_at: r.string(2)?,
        })
    })
    .collect()
}

/// Deletes token `name`; requests with its secret are refused from the next request on.
pub fn revoke(conn: &mut dyn Connection, name: &str) -> Result<(), StoreError> {
    let n = conn.execute(
        "DELETE FROM api_tokens WHERE name = $1",
        &[Value::from(name)],
    )?;
    if n == 0 {
        return Err(StoreError::NotFound(format!("token {name:?}")));
    }
    Ok(())
}

/// Every token with its hash, for the server's check.
pub fn load(conn: &mut dyn Connection) -> Result<Vec<StoredToken>, StoreError> {
    conn.query("SELECT name, scope, secret_sha256 FROM api_tokens", &[])?
        .iter()
        .map(|r| {
            let name = r.string(0)?;
            Ok(StoredToken {
                scope: r.str(1)?.parse().map_err(StoreError::Corrupt)?,
                secret_sha256: unhex(r.str(2)?).ok_or_else(|| {
                    StoreError::Corrupt(format!("token {name:?} has a malformed hash"))
                })?,
                name,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hashes_round_trip_through_hex() {
        let h = hash("tsr_x");
        assert_eq!(unhex(&hex(&h)), Some(h));
        assert_eq!(unhex("zz"), None);
    }

    #[test]
    fn secrets_differ_and_names_are_checked() {
        assert_ne!(new_secret().unwrap(), new_secret().unwrap());
        assert_eq!(new_secret().unwrap().len(), 4 + 43);
        assert!(check_name("ci-runner_1.x").is_ok());
        for bad in ["", "a b", "legacy", "ü", &"x".repeat(65)] {
            assert!(check_name(bad).is_err(), "{bad:?}");
        }
    }
}
