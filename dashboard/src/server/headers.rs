//! Headers every answer carries, and the one check every request passes first: pages cannot be
//! framed (`X-Frame-Options: DENY`, CSP `frame-ancestors 'none'`: a same-site page could frame the
//! triage form with the stored token), scripts come only from the dashboard itself (no inline
//! script runs: the pages' scripts are `/assets/*.js`; JSON data blocks are not scripts), and a
//! query string longer than [`MAX_QUERY`] is refused with 400 before any handler parses it (a
//! 50,000-character filter answered 500).
//!
//! Not for: authentication (see [`super::auth`]) or error bodies (see [`super::error`]).

use axum::extract::Request;
use axum::http::{header, HeaderValue};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};

use super::AppError;

/// Longest query string accepted, in bytes.
pub const MAX_QUERY: usize = 4096;

/// The Content-Security-Policy of every answer.
pub const CSP: &str = "default-src 'self'; script-src 'self'; style-src 'self' 'unsafe-inline'; img-src 'self' data:; connect-src 'self'; object-src 'none'; base-uri 'none'; form-action 'self'; frame-ancestors 'none'";

pub async fn secure(req: Request, next: Next) -> Response {
    let long = req.uri().query().map_or(0, str::len);
    let mut res = if long > MAX_QUERY {
        AppError::BadRequest(format!(
            "the query string is {long} bytes; filters are limited to {MAX_QUERY} bytes in all"
        ))
        .into_response()
    } else {
        next.run(req).await
    };
    let h = res.headers_mut();
    h.insert(header::X_FRAME_OPTIONS, HeaderValue::from_static("DENY"));
    h.insert(
        header::CONTENT_SECURITY_POLICY,
        HeaderValue::from_static(CSP),
    );
    h.insert(
        header::X_CONTENT_TYPE_OPTIONS,
        HeaderValue::from_static("nosniff"),
    );
    h.insert(
        header::REFERRER_POLICY,
        HeaderValue::from_static("same-origin"),
    );
    res
}
