//! The HTTP server: [`app`] builds the axum router (tested with `oneshot`), [`AppState`] holds
//! the store and the upload token, [`AppError`] turns every failure into a status and a JSON body.
//! One module per endpoint; each serves its HTML page and the JSON API the page is built from.
//!
//! Not for: SQL (see [`crate::store`]) or chart drawing (see [`crate::svg`]).

pub mod auth;
pub mod compare;
pub mod error;
pub mod images;
pub mod pareto;
pub mod regressions;
pub mod run;
pub mod runs;
pub mod series;
pub mod upload;

use axum::extract::DefaultBodyLimit;
use axum::routing::{get, post};
use axum::Router;

pub use error::AppError;

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
    /// The dashboard's public URL for absolute links (feed, Markdown); `None`: from `Host`.
    pub public_url: Option<String>,
}

impl AppState {
    pub fn new(pool: Pool, token: Option<String>) -> AppState {
        AppState {
            pool,
            token,
            max_upload_bytes: DEFAULT_MAX_UPLOAD_BYTES,
            detect: Params::default(),
            public_url: None,
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
    Router::new()
        .route("/", get(runs::page))
        .route("/api/runs", get(runs::api).post(upload::api))
        .route("/runs/{run_id}", get(run::page))
        .route("/api/runs/{run_id}", get(run::api))
        .route(
            "/runs/{run_id}/images/{scenario}/{variant}",
            get(images::page),
        )
        .route("/api/runs/{run_id}/images/{scenario}", get(images::api))
        .route("/images/{digest}", get(images::blob))
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
        .route("/pareto", get(pareto::page))
        .route("/api/pareto", get(pareto::api))
        .fallback(|| async { AppError::NotFound("no such page".into()) })
        .layer(DefaultBodyLimit::max(state.max_upload_bytes))
        .with_state(state)
}
