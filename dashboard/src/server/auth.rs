//! Bearer-token check for writes. The token comes from `--token` or `TESSERA_DASHBOARD_TOKEN`;
//! without one, the server refuses every write. Compared in constant time.

use axum::http::HeaderMap;

use super::{AppError, AppState};

fn constant_time_eq(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

/// Checks a token given in a form field (the triage form) or header.
pub fn check_token(state: &AppState, given: Option<&str>) -> Result<(), AppError> {
    let Some(expected) = &state.token else {
        return Err(AppError::WritesDisabled);
    };
    match given {
        Some(g) if constant_time_eq(g.as_bytes(), expected.as_bytes()) => Ok(()),
        _ => Err(AppError::Unauthorized),
    }
}

/// Checks `Authorization: Bearer <token>`.
pub fn require_bearer(state: &AppState, headers: &HeaderMap) -> Result<(), AppError> {
    let given = headers
        .get(axum::http::header::AUTHORIZATION)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.strip_prefix("Bearer "))
        .map(str::trim);
    check_token(state, given)
}
