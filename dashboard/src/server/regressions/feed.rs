//! `GET /regressions/feed.atom`: the confirmed groups in which some series got worse on its own,
//! newest first. Improvements are never announced here as regressions.
//! Not for: the feed's XML (see [`crate::notify::atom`]).

use axum::extract::{Query, State};
use axum::http::{header, HeaderMap};
use axum::response::{IntoResponse, Response};
use serde::Deserialize;

use super::{base_url, non_empty};
use crate::notify;
use crate::server::{AppError, AppState};
use crate::store::groups::{self, Filter, Sort};

#[derive(Debug, Deserialize, Default)]
pub struct FeedQuery {
    /// Only groups in this triage state (e.g. `new`).
    pub state: Option<String>,
}

/// `GET /regressions/feed.atom`: the 50 most recently detected confirmed groups.
pub async fn feed(
    State(state): State<AppState>,
    headers: HeaderMap,
    Query(q): Query<FeedQuery>,
) -> Result<Response, AppError> {
    let filter = Filter {
        status: Some("confirmed".into()),
        state: non_empty(&q.state),
        regressions_only: true,
        ..Filter::default()
    };
    filter
        .validate()
        .map_err(|e| AppError::BadRequest(e.to_string()))?;
    let now = crate::now_rfc3339();
    let at = now.clone();
    let (mut groups, stopped) = state
        .db(move |c| {
            Ok((
                groups::list(c, &filter, Sort::Date, usize::MAX)?,
                crate::store::stoppage::stoppages(c, &at)?,
            ))
        })
        .await?;
    groups.sort_by(|x, y| {
        (y.detected_at.cmp(&x.detected_at))
            .then(y.started_at.cmp(&x.started_at))
            .then(y.id.cmp(&x.id))
    });
    groups.truncate(50);
    let xml =
        notify::atom::feed_with_stoppages(&groups, &stopped, &base_url(&state, &headers), &now);
    Ok((
        [(header::CONTENT_TYPE, "application/atom+xml; charset=utf-8")],
        xml,
    )
        .into_response())
}
