//! The HTTP server: [`app`] builds the axum router (tested with `oneshot`), [`AppState`] holds
//! the store and the upload token, [`AppError`] turns every failure into a status and a JSON body.
//! The write path (tokens, rate limit, timeouts, JSON for every error) is [`auth`], [`listen`]
//! and the layers at the end of [`app`].
//! One module per endpoint; each serves its HTML page and the JSON API the page is built from.
//!
//! Not for: SQL (see [`crate::store`]) or chart drawing (see [`crate::svg`]).

pub mod ab;
pub mod ab_form;
pub mod assets;
pub mod auth;
pub mod blobs;
pub mod compare;
pub mod compare_runs;
pub mod conditions_view;
pub mod delete;
pub mod error;
pub mod export;
pub mod frame_charts;
mod frame_plot;
pub mod frames;
pub mod headers;
pub mod health;
pub mod images;
pub mod listen;
pub mod pareto;
pub mod queue;
pub mod queue_page;
pub mod regressions;
pub mod run;
pub mod run_frame_charts;
pub mod runs;
pub mod series;
pub mod upload;

use std::sync::Arc;

use axum::body::Body;
use axum::extract::DefaultBodyLimit;
use axum::extract::Request;
use axum::http::StatusCode;
use axum::routing::{delete, get, post};
use axum::{middleware, Router};
use tower_http::timeout::{RequestBodyTimeoutLayer, TimeoutBody, TimeoutLayer};

pub use error::AppError;
pub use listen::Timeouts;

use crate::db::{Connection, Pool};
use crate::detect::Params;

/// Largest upload accepted by `POST /api/runs`, by default.
pub const DEFAULT_MAX_UPLOAD_BYTES: usize = 64 << 20;

#[derive(Clone)]
pub struct AppState {
    pub pool: Pool,
    /// Bearer token that writes need; `None` disables writes.
    pub token: Option<String>,
    pub max_upload_bytes: usize,
    pub detect: Params,
    /// Named tokens, rate limit, read protection (see [`auth`]).
    pub auth: auth::Auth,
    /// Header, body and request deadlines (see [`listen`]).
    pub timeouts: Timeouts,
    /// The dashboard's public URL for absolute links (feed, Markdown); `None`: from `Host`.
    pub public_url: Option<String>,
    /// Lease, offline threshold, retries and repository of the job queue (see [`queue`]).
    pub queue: queue::QueueConfig,
    /// Decoded records and noise of recently compared runs ([`crate::store::run_cache`]).
    pub runs: Arc<crate::store::run_cache::RunCache>,
}

impl AppState {
    pub fn new(pool: Pool, token: Option<String>) -> AppState {
        AppState {
            pool,
            token,
            max_upload_bytes: DEFAULT_MAX_UPLOAD_BYTES,
            detect: Params::default(),
            auth: auth::Auth::default(),
            timeouts: Timeouts::default(),
            public_url: None,
            queue: queue::QueueConfig::default(),
            runs: Arc::default(),
        }
    }

    /// Runs blocking store work off the async threads.
    pub async fn db<T: Send + 'static>(
        &self,
        f: impl FnOnce(&mut dyn Connection) -> Result<T, AppError> + Send + 'static,
    ) -> Result<T, AppError> {
        let pool = self.pool.clone();
        tokio::task::spawn_blocking(move || {
            let mut conn = pool.get().map_err(AppError::from)?;
            f(&mut *conn)
        })
        .await
        .map_err(|e| AppError::Internal(format!("store task failed: {e}")))?
    }
}

/// The router with every page and API route.
pub fn app(state: AppState) -> Router {
    let routes = Router::new()
        .route("/", get(runs::page))
        .route("/api/runs", get(runs::api).post(upload::api))
        .route("/runs/{run_id}", get(run::page))
        .route("/api/runs/{run_id}", get(run::api))
        .route(
            "/runs/{run_id}/scenarios/{scenario}",
            get(run::scenario_page),
        )
        .route(
            "/runs/{run_id}/images/{scenario}/{variant}",
            get(images::page),
        )
        .route("/api/runs/{run_id}/images/{scenario}", get(images::api))
        .route("/images/{digest}", get(images::blob))
        .route("/api/blobs/missing", post(blobs::missing))
        .route("/api/blobs", post(blobs::store))
        .route("/series", get(series::list_page))
        .route("/api/series", get(series::list_api))
        .route("/series/{id}", get(series::page))
        .route("/api/series/{id}", get(series::api))
        .route("/regressions", get(regressions::page))
        .route("/api/regressions", get(regressions::api))
        .route("/regressions/{id}", post(regressions::triage_form))
        .route("/api/regressions/{id}", post(regressions::triage_api))
        .route("/regressions/feed.atom", get(regressions::feed))
        .route(
            "/regressions/groups/{key}",
            get(regressions::group_page).post(regressions::group_form),
        )
        .route("/api/regressions/groups", get(regressions::groups_api))
        .route(
            "/api/regressions/groups/{key}",
            get(regressions::group_api).post(regressions::group_triage_api),
        )
        .route("/compare", get(compare::page))
        .route("/api/compare", get(compare::api))
        .route("/compare/runs", get(compare_runs::page))
        .route("/api/compare/runs", get(compare_runs::api))
        .route("/assets/{name}", get(assets::file))
        .route("/pareto", get(pareto::page))
        .route("/api/pareto", get(pareto::api))
        .route("/healthz", get(health::healthz))
        .route("/api/runs/{run_id}", delete(delete::api))
        .route("/frames", get(frames::list_page))
        .route("/api/frames", get(frames::list_api))
        .route(
            "/frames/{run_id}/{scenario}/{variant}/{frame}",
            get(frames::detail_page).post(frames::judge_form),
        )
        .route(
            "/api/frames/{run_id}/{scenario}/{variant}/{frame}",
            get(frames::detail_api),
        )
        .route("/api/frames/judge", post(frames::judge_api))
        .route("/api/approved-frames", get(frames::approved_api))
        .route("/api/runners/register", post(queue::register))
        .route("/api/runners/heartbeat", post(queue::heartbeat))
        .route("/api/queue", get(queue::overview))
        .route("/api/queue/claim", post(queue::claim))
        .route("/api/queue/requests", post(queue::request))
        .route("/api/queue/jobs/{id}", get(queue::job))
        .route("/api/queue/jobs/{id}/complete", post(queue::complete))
        .route("/api/queue/jobs/{id}/fail", post(queue::fail))
        .route("/api/queue/jobs/{id}/return", post(queue::give_back))
        .route("/queue", get(queue_page::page))
        .route("/api/ab", post(ab::create))
        .route("/ab/new", get(ab_form::page).post(ab_form::submit))
        .route("/api/ab/{request_id}", get(ab::get))
        .route("/api/bisections", post(ab::bisect_create))
        .route("/api/bisections/{id}", get(ab::bisect_get))
        .route("/bisections/{id}", get(ab::bisect_page))
        .route(
            "/regressions/{id}/bisect",
            get(ab::bisect_form_page).post(ab::bisect_form),
        )
        .fallback(|| async { AppError::NotFound("no such page".into()) })
        .layer(DefaultBodyLimit::max(state.max_upload_bytes))
        // gzip (or deflate, br) for clients that accept it: pages and JSON shrink about 6x.
        .layer(tower_http::compression::CompressionLayer::new())
        .with_state(state.clone());
    write_path(routes, &state)
}

/// The write path's layers around the whole router, outermost first: every error as JSON, the
/// whole-request deadline (408), the body idle deadline, then the token check and rate limit,
/// which run before any handler reads a body. Wrapped around the router as a service, not with
/// `Router::layer`, so that axum still sets `Allow` on its 405s.
fn write_path(routes: Router, state: &AppState) -> Router {
    let service = tower::ServiceBuilder::new()
        .layer(middleware::from_fn(headers::secure))
        .layer(middleware::from_fn(error::json_errors))
        .layer(TimeoutLayer::with_status_code(
            StatusCode::REQUEST_TIMEOUT,
            state.timeouts.request,
        ))
        .layer(RequestBodyTimeoutLayer::new(state.timeouts.body_idle))
        .map_request(|req: Request<TimeoutBody<Body>>| req.map(Body::new))
        .layer(middleware::from_fn_with_state(state.clone(), auth::guard))
        .service(routes);
    Router::new().fallback_service(service)
}
