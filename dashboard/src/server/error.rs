//! The one error type of the server: each variant picks the status; the body is always
//! `{"error": "..."}`. Internal errors are logged with their detail and answered with a generic
//! message, so store internals never reach a client. [`json_errors`] gives the same body to the
//! errors that do not come from a handler (axum's rejections, 405, timeouts); a handler's own HTML
//! error page (the image viewer's 404) is left as it is.

use axum::extract::Request;
use axum::http::{header, HeaderValue, StatusCode};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use axum::Json;

use crate::bundle::BundleError;
use crate::db::DbError;
use crate::store::StoreError;

#[derive(Debug, thiserror::Error)]
pub enum AppError {
    #[error("{0}")]
    NotFound(String),
    #[error("{0}")]
    BadRequest(String),
    #[error("{0}")]
    Unprocessable(String),
    /// A refused field of a request: 422 with `{"error", "field"}`.
    #[error("{field}: {problem}")]
    Field { field: String, problem: String },
    /// The request contradicts what is stored: 409.
    #[error("{0}")]
    Conflict(String),
    #[error("{0}")]
    PayloadTooLarge(String),
    #[error(
        "this request needs the header `Authorization: Bearer <token>` with a write token (`tessera-dashboard token add NAME --scope write`, or the server's --token)"
    )]
    Unauthorized,
    /// A token was sent and is not a known token (it was not missing: say so).
    #[error("the token sent in `Authorization: Bearer` is not a known write token (revoked, mistyped, or another dashboard's): `tessera-dashboard token list` shows the names of the known ones")]
    UnknownToken,
    /// An `Authorization` header was sent, but it holds no Bearer token: what is wrong with it.
    #[error("the `Authorization` header was sent, but {0}: send `Authorization: Bearer <token>` with a write token")]
    MalformedToken(String),
    #[error("this dashboard needs a read token: `Authorization: Bearer <token>`, or the token as the password of HTTP Basic")]
    ReadUnauthorized,
    #[error("{0}")]
    Forbidden(String),
    #[error("writes are disabled: start the server with --token or TESSERA_DASHBOARD_TOKEN, or add a write token with `tessera-dashboard token add NAME --scope write`")]
    WritesDisabled,
    #[error("too many writes with this token: retry after {retry_after_secs} s")]
    TooManyRequests { retry_after_secs: u64 },
    #[error("{0}")]
    RequestTimeout(String),
    #[error("internal error")]
    Internal(String),
}

impl AppError {
    pub fn status(&self) -> StatusCode {
        match self {
            AppError::NotFound(_) => StatusCode::NOT_FOUND,
            AppError::BadRequest(_) => StatusCode::BAD_REQUEST,
            AppError::Unprocessable(_) | AppError::Field { .. } => StatusCode::UNPROCESSABLE_ENTITY,
            AppError::Conflict(_) => StatusCode::CONFLICT,
            AppError::PayloadTooLarge(_) => StatusCode::PAYLOAD_TOO_LARGE,
            AppError::Unauthorized
            | AppError::UnknownToken
            | AppError::MalformedToken(_)
            | AppError::ReadUnauthorized => StatusCode::UNAUTHORIZED,
            AppError::Forbidden(_) | AppError::WritesDisabled => StatusCode::FORBIDDEN,
            AppError::TooManyRequests { .. } => StatusCode::TOO_MANY_REQUESTS,
            AppError::RequestTimeout(_) => StatusCode::REQUEST_TIMEOUT,
            AppError::Internal(_) => StatusCode::INTERNAL_SERVER_ERROR,
        }
    }
}

impl IntoResponse for AppError {
    fn into_response(self) -> Response {
        if let AppError::Internal(detail) = &self {
            eprintln!("tessera-dashboard: internal error: {detail}");
        }
        let body = match &self {
            AppError::Field { field, .. } => {
                serde_json::json!({ "error": self.to_string(), "field": field })
            }
            _ => serde_json::json!({ "error": self.to_string() }),
        };
        let mut res = (self.status(), Json(body)).into_response();
        let headers = res.headers_mut();
        match self {
            AppError::Unauthorized | AppError::UnknownToken | AppError::MalformedToken(_) => {
                headers.insert(header::WWW_AUTHENTICATE, HeaderValue::from_static("Bearer"));
            }
            AppError::ReadUnauthorized => {
                headers.insert(
                    header::WWW_AUTHENTICATE,
                    HeaderValue::from_static("Basic realm=\"tessera-dashboard\""),
                );
            }
            AppError::TooManyRequests { retry_after_secs } => {
                headers.insert(header::RETRY_AFTER, HeaderValue::from(retry_after_secs));
            }
            _ => {}
        }
        res
    }
}

impl From<DbError> for AppError {
    fn from(e: DbError) -> Self {
        AppError::Internal(format!("{e}: {:?}", std::error::Error::source(&e)))
    }
}

impl From<StoreError> for AppError {
    fn from(e: StoreError) -> Self {
        match e {
            StoreError::NotFound(what) => AppError::NotFound(format!("{what} not found")),
            StoreError::Invalid(msg) => AppError::Unprocessable(msg),
            StoreError::Conflict(msg) => AppError::Conflict(msg),
            StoreError::Db(e) => e.into(),
            StoreError::Corrupt(msg) => AppError::Internal(msg),
        }
    }
}

impl From<BundleError> for AppError {
    fn from(e: BundleError) -> Self {
        match e {
            BundleError::Io { .. } => AppError::Internal(e.to_string()),
            BundleError::Field(f) => AppError::Field {
                field: f.field,
                problem: f.problem,
            },
            _ => AppError::Unprocessable(e.to_string()),
        }
    }
}

/// What an error response without a body of its own says, by status.
fn default_message(status: StatusCode, allow: Option<&str>) -> String {
    match status {
        StatusCode::METHOD_NOT_ALLOWED => match allow {
            Some(a) => format!("method not allowed here; this path takes {a}"),
            None => "method not allowed here".into(),
        },
        StatusCode::REQUEST_TIMEOUT => {
            "the request was not received in time (see serve --request-timeout-secs)".into()
        }
        StatusCode::PAYLOAD_TOO_LARGE => "the request body is too large".into(),
        s => s
            .canonical_reason()
            .map_or_else(|| format!("HTTP {}", s.as_u16()), |r| r.to_lowercase()),
    }
}

/// Middleware: turns every 4xx or 5xx response that is not JSON (axum's `text/plain` rejections
/// of a bad path parameter, query, JSON or form body, body limits, 405s with no body, timeouts)
/// into `{"error": "..."}` with the same status and headers. The text kept is at most 16 KiB.
pub async fn json_errors(req: Request, next: Next) -> Response {
    let res = next.run(req).await;
    let status = res.status();
    let is_json = res
        .headers()
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|v| v.starts_with("application/json"));
    // A page's own HTML error (the image viewer's 404) stays a page.
    let is_html = res
        .headers()
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|v| v.starts_with("text/html"));
    if !(status.is_client_error() || status.is_server_error()) || is_json || is_html {
        return res;
    }
    let (mut parts, body) = res.into_parts();
    let text = axum::body::to_bytes(body, 16 << 10)
        .await
        .map(|b| String::from_utf8_lossy(&b).trim().to_string())
        .unwrap_or_default();
    let message = if text.is_empty() {
        let allow = parts
            .headers
            .get(header::ALLOW)
            .and_then(|v| v.to_str().ok());
        default_message(status, allow)
    } else {
        text
    };
    parts.headers.remove(header::CONTENT_TYPE);
    parts.headers.remove(header::CONTENT_LENGTH);
    let mut out = Json(serde_json::json!({ "error": message })).into_response();
    *out.status_mut() = status;
    for (name, value) in parts.headers.iter() {
        out.headers_mut().append(name.clone(), value.clone());
    }
    out
}
