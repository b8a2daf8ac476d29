//! Regressions: detected changes with size, confidence and triage state (`/regressions`,
//! `/api/regressions?state=`), and triage writes: `POST /api/regressions/{id}` (JSON
//! `{"state", "note"}`, bearer token) and `POST /regressions/{id}` (the page's form, with the
//! token as a form field). States are kept in the store, shared by everyone.

use std::fmt::Write;

use axum::extract::{Path, Query, State};
use axum::http::HeaderMap;
use axum::response::{Html, Redirect};
use axum::{Form, Json};
use serde::Deserialize;

use super::{auth, AppError, AppState};
use crate::html::{commit, enc, esc, num, page as layout, pct};
use crate::store::read::{self, RegressionRow};
use crate::store::triage::{self, STATES};

#[derive(Debug, Deserialize, Default)]
pub struct RegressionsQuery {
    pub state: Option<String>,
    pub limit: Option<i64>,
}

async fn load(state: &AppState, q: RegressionsQuery) -> Result<Vec<RegressionRow>, AppError> {
    let limit = q.limit.unwrap_or(200).clamp(1, 2000);
    let st = q.state.filter(|s| !s.is_empty());
    if let Some(s) = &st {
        if !STATES.contains(&s.as_str()) {
            return Err(AppError::BadRequest(format!(
                "state must be one of {}",
                STATES.join(", ")
            )));
        }
    }
    state
        .db(move |c| Ok(read::regressions(c, st.as_deref(), None, limit)?))
        .await
}

pub async fn api(
    State(state): State<AppState>,
    Query(q): Query<RegressionsQuery>,
) -> Result<Json<Vec<RegressionRow>>, AppError> {
    Ok(Json(load(&state, q).await?))
}

/// A one-line summary of a change, e.g.
/// `tiny · upscale[scale=0.5] · llvmpipe · gpu_ms.median: 3.476 → 3.824 (+10.0%, worse), 99.9% confidence`.
pub fn summary(r: &RegressionRow) -> String {
    format!(
        "{} · {} · {} · {}: {} → {} ({}, {}), {:.1}% confidence",
        r.series.scenario,
        r.series.variant,
        r.series.adapter,
        r.series.measure,
        num(r.value_before),
        num(r.value_after),
        pct(r.relative_change),
        if r.is_regression { "worse" } else { "better" },
        r.confidence * 100.0
    )
}

pub fn render(rows: &[RegressionRow]) -> String {
    let mut b = String::from("<p>filter: <a href=\"/regressions\">all</a>");
    for s in STATES {
        let _ = write!(b, " <a href=\"?state={s}\">{s}</a>");
    }
    b.push_str(
        "</p><table id=regressions><tr><th>change</th><th>commits</th><th>state and note</th></tr>",
    );
    for r in rows {
        let _ = write!(
            b,
            "<tr id=r{}><td class=\"{}\"><a href=\"/series/{}\">{}</a></td><td><code>{}</code> → <a href=\"/runs/{}\"><code>{}</code></a></td><td><form class=inline method=post action=\"/regressions/{}\"><select name=state>",
            r.id,
            if r.is_regression { "worse" } else { "better" },
            r.series.id,
            esc(&summary(r)),
            esc(&commit(r.commit_before.as_deref())),
            enc(&r.run_after),
            esc(&commit(r.commit_after.as_deref())),
            r.id
        );
        for s in STATES {
            let sel = if s == r.state { " selected" } else { "" };
            let _ = write!(b, "<option{sel}>{s}</option>");
        }
        let _ = write!(
            b,
            "</select> <input name=note size=30 value=\"{}\"> <input name=token type=password size=8 placeholder=token> <button>save</button></form></td></tr>",
            esc(&r.note)
        );
    }
    b.push_str("</table>");
    if rows.is_empty() {
        b.push_str("<p>No detected changes.</p>");
    }
    b
}

pub async fn page(
    State(state): State<AppState>,
    Query(q): Query<RegressionsQuery>,
) -> Result<Html<String>, AppError> {
    let rows = load(&state, q).await?;
    Ok(Html(layout("Regressions", "regressions", &render(&rows))))
}

#[derive(Debug, Deserialize)]
pub struct Triage {
    pub state: String,
    #[serde(default)]
    pub note: String,
}

async fn apply(state: &AppState, id: i64, t: Triage) -> Result<(), AppError> {
    state
        .db(move |c| Ok(triage::set(c, id, &t.state, &t.note)?))
        .await
}

pub async fn triage_api(
    State(state): State<AppState>,
    headers: HeaderMap,
    Path(id): Path<i64>,
    body: Result<Json<Triage>, axum::extract::rejection::JsonRejection>,
) -> Result<Json<serde_json::Value>, AppError> {
    auth::require_bearer(&state, &headers)?;
    let Json(t) = body.map_err(|e| AppError::BadRequest(e.body_text()))?;
    apply(&state, id, t).await?;
    Ok(Json(serde_json::json!({ "id": id, "updated": true })))
}

#[derive(Debug, Deserialize)]
pub struct TriageForm {
    pub state: String,
    #[serde(default)]
    pub note: String,
    #[serde(default)]
    pub token: String,
}

pub async fn triage_form(
    State(state): State<AppState>,
    Path(id): Path<i64>,
    Form(f): Form<TriageForm>,
) -> Result<Redirect, AppError> {
    auth::check_token(&state, Some(&f.token))?;
    apply(
        &state,
        id,
        Triage {
            state: f.state,
            note: f.note,
        },
    )
    .await?;
    Ok(Redirect::to(&format!("/regressions#r{id}")))
}
