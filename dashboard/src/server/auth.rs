//! Who may do what: named tokens with a `read`, `runner` or `write` scope (stored hashed, managed with
//! `tessera-dashboard token`), plus the legacy `--token` / `TESSERA_DASHBOARD_TOKEN`, which is a
//! write token named `legacy`. A secret is hashed (SHA-256) and compared with every known hash in
//! constant time (`subtle`).
//!
//! [`guard`] runs before every handler: a write (any method but GET, HEAD, OPTIONS) must carry
//! `Authorization: Bearer <write token>`, checked before a byte of its body is read, and is then
//! rate-limited per token (429 with `Retry-After`). The one exception is a browser form
//! (`application/x-www-form-urlencoded`) without that header: its token is a form field, so its
//! body (capped at [`FORM_MAX_BYTES`]) is read and the handler checks the field with
//! [`require_token`]. Reads are public unless `--require-read-token`: then every page and API call
//! but `/healthz` needs a read or write token, as `Bearer` or as the password of HTTP Basic (which
//! browsers ask for; Basic is never accepted for writes, so a cross-site form cannot use it).
//!
//! The guard reloads the token table before each write and each protected read, so a revoked
//! token is refused from the next request on; [`require`] and friends then check against that
//! copy without touching the store.

use std::num::NonZeroU32;
use std::sync::{Arc, RwLock};

use axum::extract::{FromRequestParts, Request, State};
use axum::http::request::Parts;
use axum::http::{header, HeaderMap, Method};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use base64::Engine;
use governor::clock::{Clock, DefaultClock};
use governor::{DefaultKeyedRateLimiter, Quota, RateLimiter};
use subtle::ConstantTimeEq;

use super::{AppError, AppState};
pub use crate::store::tokens::Scope;
use crate::store::tokens::{self, StoredToken, LEGACY_NAME};

/// Largest browser-form body accepted from a request without a bearer header.
pub const FORM_MAX_BYTES: usize = 64 << 10;

/// Who made a request: the token's name (`legacy` for `--token`) and its scope.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Principal {
    pub name: String,
    pub scope: Scope,
}

/// How tokens are enforced; set from `serve`'s options.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AuthConfig {
    /// Reads need a read or write token too.
    pub require_read_token: bool,
    /// Sustained writes per minute per token; 0 turns the limit off.
    pub writes_per_minute: u32,
    /// Writes a token may make at once before the per-minute rate applies.
    pub write_burst: u32,
}

impl Default for AuthConfig {
    fn default() -> Self {
        AuthConfig {
            require_read_token: false,
            writes_per_minute: 120,
            write_burst: 60,
        }
    }
}

/// The tokens as last loaded, the rate limiter and the config; cheap to clone.
#[derive(Clone)]
pub struct Auth {
    inner: Arc<Inner>,
}

struct Inner {
    config: AuthConfig,
    tokens: RwLock<Vec<StoredToken>>,
    limiter: Option<DefaultKeyedRateLimiter<String>>,
}

impl Auth {
    pub fn new(config: AuthConfig) -> Auth {
        let limiter = NonZeroU32::new(config.writes_per_minute).map(|rate| {
            let burst = NonZeroU32::new(config.write_burst).unwrap_or(NonZeroU32::MIN);
            RateLimiter::keyed(Quota::per_minute(rate).allow_burst(burst))
        });
        Auth {
            inner: Arc::new(Inner {
                config,
                tokens: RwLock::new(Vec::new()),
                limiter,
            }),
        }
    }

    pub fn config(&self) -> AuthConfig {
        self.inner.config
    }

    fn tokens(&self) -> std::sync::RwLockReadGuard<'_, Vec<StoredToken>> {
        self.inner.tokens.read().unwrap_or_else(|e| e.into_inner())
    }
}

impl Default for Auth {
    fn default() -> Self {
        Auth::new(AuthConfig::default())
    }
}

/// Reloads the token table from the store.
pub async fn refresh(state: &AppState) -> Result<(), AppError> {
    let loaded = state.db(|c| Ok(tokens::load(c)?)).await?;
    *state
        .auth
        .inner
        .tokens
        .write()
        .unwrap_or_else(|e| e.into_inner()) = loaded;
    Ok(())
}

/// The principal whose secret this is, if any. Every known hash is compared, in constant time.
fn identify(state: &AppState, secret: &str) -> Option<Principal> {
    let given = tokens::hash(secret);
    let mut found = None;
    if let Some(legacy) = &state.token {
        if bool::from(tokens::hash(legacy).ct_eq(&given)) {
            found = Some(Principal {
                name: LEGACY_NAME.into(),
                scope: Scope::Write,
            });
        }
    }
    for t in state.auth.tokens().iter() {
        if bool::from(t.secret_sha256.ct_eq(&given)) && found.is_none() {
            found = Some(Principal {
                name: t.name.clone(),
                scope: t.scope,
            });
        }
    }
    found
}

fn any_token_for(state: &AppState, scope: Scope) -> bool {
    state.token.is_some() || state.auth.tokens().iter().any(|t| t.scope.allows(scope))
}

/// The secret of `Authorization: Bearer <secret>`.
pub fn bearer(headers: &HeaderMap) -> Option<&str> {
    headers
        .get(header::AUTHORIZATION)?
        .to_str()
        .ok()?
        .strip_prefix("Bearer ")
        .map(str::trim)
}

/// The password of `Authorization: Basic ...` (the user name is ignored).
fn basic_password(headers: &HeaderMap) -> Option<String> {
    let b64 = headers
        .get(header::AUTHORIZATION)?
        .to_str()
        .ok()?
        .strip_prefix("Basic ")?;
    let raw = base64::engine::general_purpose::STANDARD
        .decode(b64.trim())
        .ok()?;
    let text = String::from_utf8(raw).ok()?;
    Some(text.split_once(':')?.1.to_string())
}

/// Checks a secret for `scope`: 403 when no token of that scope is configured at all (writes
/// disabled) or the token's scope is too small, 401 when it is missing or unknown.
pub fn require_token(
    state: &AppState,
    given: Option<&str>,
    scope: Scope,
) -> Result<Principal, AppError> {
    if scope != Scope::Read && !any_token_for(state, scope) {
        return Err(AppError::WritesDisabled);
    }
    let unauthorized = || match scope {
        Scope::Write | Scope::Runner => AppError::Unauthorized,
        Scope::Read => AppError::ReadUnauthorized,
    };
    let given = given.filter(|g| !g.is_empty());
    let principal = match given {
        None => return Err(unauthorized()),
        Some(g) => identify(state, g).ok_or(match scope {
            // Sent, but unknown: not "the header is missing".
            Scope::Write | Scope::Runner => AppError::UnknownToken,
            Scope::Read => AppError::ReadUnauthorized,
        })?,
    };
    if !principal.scope.allows(scope) {
        return Err(AppError::Forbidden(format!(
            "token {:?} has scope {}; this request needs {}",
            principal.name,
            principal.scope.as_str(),
            scope.as_str()
        )));
    }
    Ok(principal)
}

/// Checks the request's `Authorization` header for `scope` (Bearer; for reads also Basic).
pub fn require(state: &AppState, headers: &HeaderMap, scope: Scope) -> Result<Principal, AppError> {
    let basic = (scope == Scope::Read)
        .then(|| basic_password(headers))
        .flatten();
    // A header was sent that holds no Bearer token (another scheme, or `Bearer` with nothing):
    // say what was wrong with it, not that it is missing.
    if scope != Scope::Read && any_token_for(state, scope) {
        if let Some(sent) = headers.get(header::AUTHORIZATION) {
            if bearer(headers).is_none_or(str::is_empty) {
                let text = sent.to_str().unwrap_or("");
                let scheme = text.split_whitespace().next().unwrap_or("");
                return Err(AppError::MalformedToken(if scheme.is_empty() {
                    "it is empty".into()
                } else if scheme == "Bearer" {
                    "`Bearer` is followed by no token".into()
                } else {
                    format!("it uses the scheme {scheme:?}, not `Bearer`")
                }));
            }
        }
    }
    require_token(state, bearer(headers).or(basic.as_deref()), scope)
}

/// Counts one write against `principal`'s rate limit.
pub fn rate_limit(state: &AppState, principal: &Principal) -> Result<(), AppError> {
    let Some(limiter) = &state.auth.inner.limiter else {
        return Ok(());
    };
    limiter.check_key(&principal.name).map_err(|not_until| {
        let wait = not_until.wait_time_from(DefaultClock::default().now());
        AppError::TooManyRequests {
            retry_after_secs: wait.as_secs() + u64::from(wait.subsec_nanos() > 0),
        }
    })
}

/// A browser form's `token` field: a write token, counted against its rate limit here (the guard
/// cannot see a token inside a body).
pub fn form_writer(state: &AppState, token: &str) -> Result<Principal, AppError> {
    let p = require_token(state, Some(token), Scope::Write)?;
    rate_limit(state, &p)?;
    Ok(p)
}

/// Legacy form check (the triage form's `token` field): a write token, rate-limited.
pub fn check_token(state: &AppState, given: Option<&str>) -> Result<(), AppError> {
    form_writer(state, given.unwrap_or_default()).map(drop)
}

/// Legacy header check: a write bearer token (the guard has already rate-limited it).
pub fn require_bearer(state: &AppState, headers: &HeaderMap) -> Result<(), AppError> {
    require(state, headers, Scope::Write).map(drop)
}

/// Extractor for handlers that write: the principal the guard found (or checks the header).
pub struct Writer(pub Principal);

impl FromRequestParts<AppState> for Writer {
    type Rejection = AppError;

    async fn from_request_parts(parts: &mut Parts, state: &AppState) -> Result<Self, AppError> {
        if let Some(p) = parts.extensions.get::<Principal>() {
            if p.scope.allows(Scope::Write) {
                return Ok(Writer(p.clone()));
            }
        }
        require(state, &parts.headers, Scope::Write).map(Writer)
    }
}

/// Extractor for the queue's runner endpoints: a runner or write token.
pub struct RunnerAuth(pub Principal);

impl FromRequestParts<AppState> for RunnerAuth {
    type Rejection = AppError;

    async fn from_request_parts(parts: &mut Parts, state: &AppState) -> Result<Self, AppError> {
        if let Some(p) = parts.extensions.get::<Principal>() {
            if p.scope.allows(Scope::Runner) {
                return Ok(RunnerAuth(p.clone()));
            }
        }
        require(state, &parts.headers, Scope::Runner).map(RunnerAuth)
    }
}

fn is_form(headers: &HeaderMap) -> bool {
    headers
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|v| v.starts_with("application/x-www-form-urlencoded"))
}

fn content_length(headers: &HeaderMap) -> Option<u64> {
    headers
        .get(header::CONTENT_LENGTH)?
        .to_str()
        .ok()?
        .parse()
        .ok()
}

/// The middleware described in the module doc; runs before any extractor reads the body.
pub async fn guard(State(state): State<AppState>, req: Request, next: Next) -> Response {
    match check(&state, req).await {
        Ok(req) => next.run(req).await,
        Err(e) => e.into_response(),
    }
}

async fn check(state: &AppState, mut req: Request) -> Result<Request, AppError> {
    let safe = matches!(*req.method(), Method::GET | Method::HEAD | Method::OPTIONS);
    if safe {
        if state.auth.config().require_read_token && req.uri().path() != "/healthz" {
            refresh(state).await?;
            let p = require(state, req.headers(), Scope::Read)?;
            req.extensions_mut().insert(p);
        }
        return Ok(req);
    }
    refresh(state).await?;
    if bearer(req.headers()).is_none() && is_form(req.headers()) {
        if content_length(req.headers()).is_some_and(|n| n > FORM_MAX_BYTES as u64) {
            return Err(AppError::PayloadTooLarge(format!(
                "a form is at most {FORM_MAX_BYTES} bytes"
            )));
        }
        // The handler checks the form's token; the body it may read is capped.
        return Ok(
            req.map(|b| axum::body::Body::new(http_body_util::Limited::new(b, FORM_MAX_BYTES)))
        );
    }
    // Runner tokens pass here too; each handler then asks for the scope it needs ([`Writer`],
    // [`RunnerAuth`]), so a runner token reaches only the queue endpoints and job uploads.
    let p = require(state, req.headers(), Scope::Runner)?;
    rate_limit(state, &p)?;
    if let Some(n) = content_length(req.headers()) {
        if n > state.max_upload_bytes as u64 {
            return Err(AppError::PayloadTooLarge(format!(
                "the body is {n} bytes, larger than {} bytes",
                state.max_upload_bytes
            )));
        }
    }
    req.extensions_mut().insert(p);
    Ok(req)
}
