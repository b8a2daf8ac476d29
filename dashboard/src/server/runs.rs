//! The runs list (`/`, `/api/runs`): commit, time, adapter and driver, status counts, newest
//! first; `?adapter=<id>` keeps one adapter, `?limit=` (at most 1000, default 100).

use std::fmt::Write;

use axum::extract::{Query, State};
use axum::response::Html;
use axum::Json;
use serde::Deserialize;

use super::{AppError, AppState};
use crate::html::{commit, enc, esc, page as layout};
use crate::store::read::{self, RunRow};

#[derive(Debug, Deserialize, Default)]
pub struct RunsQuery {
    pub adapter: Option<i64>,
    pub limit: Option<i64>,
}

async fn load(state: &AppState, q: RunsQuery) -> Result<Vec<RunRow>, AppError> {
    let limit = q.limit.unwrap_or(100).clamp(1, 1000);
    state
        .db(move |c| Ok(read::runs(c, q.adapter, limit)?))
        .await
}

pub async fn api(
    State(state): State<AppState>,
    Query(q): Query<RunsQuery>,
) -> Result<Json<Vec<RunRow>>, AppError> {
    Ok(Json(load(&state, q).await?))
}

/// The runs table as HTML.
pub fn render(runs: &[RunRow]) -> String {
    let mut b = String::from(
        "<table id=runs><tr><th>run</th><th>commit</th><th>started</th><th>adapter</th><th>driver</th><th>status</th><th class=n>ok</th><th class=n>skipped</th><th class=n>failed</th></tr>",
    );
    for r in runs {
        let _ = write!(
            b,
            "<tr><td><a href=\"/runs/{}\">{}</a></td><td><code>{}</code>{}</td><td>{}</td><td><a href=\"/?adapter={}\">{}</a> <span class=muted>{}</span></td><td>{} <span class=muted>{}</span></td><td>{}</td><td class=\"n ok\">{}</td><td class=\"n skipped\">{}</td><td class=\"n failed\">{}</td></tr>",
            enc(&r.run_id),
            esc(&r.run_id),
            esc(&commit(r.commit.as_deref())),
            if r.dirty { " <span class=muted>dirty</span>" } else { "" },
            esc(&r.started_at),
            r.adapter_id,
            esc(&r.adapter),
            esc(&r.backend),
            esc(&r.driver),
            esc(&r.driver_info),
            esc(&r.status),
            r.ok,
            r.skipped,
            r.failed
        );
    }
    b.push_str("</table>");
    if runs.is_empty() {
        b.push_str("<p>No runs stored yet: <code>tessera-dashboard import &lt;results folder&gt;</code> or <code>POST /api/runs</code>.</p>");
    }
    b
}

pub async fn page(
    State(state): State<AppState>,
    Query(q): Query<RunsQuery>,
) -> Result<Html<String>, AppError> {
    let runs = load(&state, q).await?;
    Ok(Html(layout("Runs", "runs", &render(&runs))))
}
