//! The JSON API of regressions: alert groups (`GET /api/regressions/groups`, one group by id or
//! key, bulk triage by `POST`) and the flat per-alert list and triage kept for scripts.
//! Not for: HTML (see [`super::pages`]).

use axum::extract::{Path, Query, State};
use axum::http::HeaderMap;
use axum::response::{IntoResponse, Redirect, Response};
use axum::Json;
use serde::Deserialize;

use super::{load_group, load_groups, resolve, writer, GroupsQuery};
use crate::server::{AppError, AppState};
use crate::store::alerts::TriageState;
use crate::store::groups::Named;
use crate::store::read::{self, RegressionRow};
use crate::store::triage::{self, Triage};
use crate::titles::{self, Titled};

#[derive(Debug, Deserialize, Default)]
pub struct RegressionsQuery {
    pub state: Option<String>,
    pub limit: Option<i64>,
}

async fn load(state: &AppState, q: RegressionsQuery) -> Result<Vec<RegressionRow>, AppError> {
    let limit = q.limit.unwrap_or(200).clamp(1, 2000);
    let st = q.state.filter(|s| !s.is_empty());
    if let Some(s) = &st {
        if s.parse::<TriageState>().is_err() {
            return Err(AppError::BadRequest(format!(
                "state must be one of {}",
                TriageState::names().join(", ")
            )));
        }
    }
    state
        .db(move |c| Ok(read::regressions(c, st.as_deref(), None, limit)?))
        .await
}

/// `GET /api/regressions`: every alert, one per series change, newest first.
pub async fn api(
    State(state): State<AppState>,
    Query(q): Query<RegressionsQuery>,
) -> Result<Json<Vec<RegressionRow>>, AppError> {
    Ok(Json(load(&state, q).await?))
}

/// `GET /api/regressions/groups`: groups with their matching alerts.
pub async fn groups_api(
    State(state): State<AppState>,
    Query(q): Query<GroupsQuery>,
) -> Result<Json<Vec<Titled>>, AppError> {
    let groups = load_groups(&state, &q).await?.0;
    Ok(Json(groups.into_iter().map(titles::titled).collect()))
}

/// `GET /api/regressions/groups/{id}`: one group with all its alerts; a key it is or was shown
/// under redirects (308) to its id.
pub async fn group_api(
    State(state): State<AppState>,
    Path(name): Path<String>,
) -> Result<Response, AppError> {
    match resolve(&state, name).await? {
        Named::Key(id) => {
            Ok(Redirect::permanent(&format!("/api/regressions/groups/{id}")).into_response())
        }
        Named::Id(id) => Ok(Json(titles::titled(load_group(&state, id).await?)).into_response()),
    }
}

pub(super) async fn apply_group(
    state: &AppState,
    key: String,
    t: Triage,
    who: String,
) -> Result<(i64, usize), AppError> {
    state
        .db(move |c| Ok(triage::set_group(c, &key, &t, &who)?))
        .await
}

/// `POST /api/regressions/groups/{key}`: sets state, note and bug link on every alert of the
/// group in one transaction.
pub async fn group_triage_api(
    State(state): State<AppState>,
    headers: HeaderMap,
    Path(key): Path<String>,
    body: Result<Json<Triage>, axum::extract::rejection::JsonRejection>,
) -> Result<Json<serde_json::Value>, AppError> {
    let who = writer(&state, &headers)?;
    let Json(t) = body.map_err(|e| AppError::BadRequest(e.body_text()))?;
    let (id, n) = apply_group(&state, key.clone(), t.clone(), who.clone()).await?;
    Ok(Json(serde_json::json!({
        "id": id, "key": key, "updated": n, "state": t.state, "updated_by": who
    })))
}

// Per-alert triage (kept for scripts written against it).

#[derive(Debug, Deserialize)]
pub struct AlertTriage {
    pub state: String,
    #[serde(default)]
    pub note: String,
}

pub(super) async fn apply(
    state: &AppState,
    id: i64,
    t: AlertTriage,
    who: String,
) -> Result<(), AppError> {
    state
        .db(move |c| Ok(triage::set_alert(c, id, &t.state, &t.note, &who)?))
        .await
}

/// `POST /api/regressions/{id}`: one alert's state and note.
pub async fn triage_api(
    State(state): State<AppState>,
    headers: HeaderMap,
    Path(id): Path<i64>,
    body: Result<Json<AlertTriage>, axum::extract::rejection::JsonRejection>,
) -> Result<Json<serde_json::Value>, AppError> {
    let who = writer(&state, &headers)?;
    let Json(t) = body.map_err(|e| AppError::BadRequest(e.body_text()))?;
    apply(&state, id, t, who).await?;
    Ok(Json(serde_json::json!({ "id": id, "updated": true })))
}
