//! Compare two runs: the page `/compare/runs?a=&b=` and the API
//! `/api/compare/runs?a=&b=&format=json|csv|md`. Both show one value, the comparison of
//! `tessera_results::compare` (the engine `tessera compare` prints too; its rules are
//! `results/COMPARISON.md`): per scenario and variant B's frame time against A's with its verdict
//! (`slower`, `faster`, `within noise`, `below threshold`, `too few frames`), the shift and its 99%
//! interval, every pass under the same test, metrics by their direction, status, speedups against
//! each variant's baseline, the findings counted once, and links to both runs' images.
//!
//! One job per module: [`query`] (the request and the two runs it names), [`view`] (the page's
//! HTML), [`formats`] (JSON, CSV and Markdown). Not for: runs of one adapter over time (see
//! [`super::series`]) or two adapters' newest runs (see [`super::compare`]).

use axum::extract::{RawQuery, State};
use axum::response::{Html, Response};

use super::{AppError, AppState};
use crate::html::page as layout;

pub mod formats;
pub mod query;
pub mod view;

pub use query::CompareRunsQuery;

/// `GET /api/compare/runs`.
pub async fn api(
    State(state): State<AppState>,
    RawQuery(raw): RawQuery,
) -> Result<Response, AppError> {
    let q = query::parse(raw.as_deref())?;
    let format = q.format;
    let Some(l) = query::load(&state, q).await? else {
        return Err(AppError::BadRequest(
            "give a= and b= (run ids or commits)".into(),
        ));
    };
    Ok(formats::respond(&l.comparison, &l.environment, format))
}

/// `GET /compare/runs`.
pub async fn page(
    State(state): State<AppState>,
    RawQuery(raw): RawQuery,
) -> Result<Html<String>, AppError> {
    let q = query::parse(raw.as_deref())?;
    let mut body = view::form(&q);
    let focus = q.scenario.clone();
    match query::load(&state, q).await? {
        Some(l) => {
            let c = &l.comparison;
            body.push_str(&view::render_with(&l, focus.as_deref()));
            Ok(Html(layout(
                &format!("Compare {} with {}", c.b.run_id, c.a.run_id),
                "compare",
                &body,
            )))
        }
        None => {
            body.push_str("<p>Give two run ids (or two commits, with a suite and an adapter) above, or tick two runs in the <a href=\"/\">runs list</a>.</p>");
            Ok(Html(layout("Compare two runs", "compare", &body)))
        }
    }
}
