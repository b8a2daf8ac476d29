//! `DELETE /api/runs/{run_id}` (write token): deletes a run with its results, points, images,
//! blobs no other run uses, re-pointing the alerts that named it (they keep id, group and triage)
//! and re-running detection on its series, in one transaction (see [`crate::store::delete`] and
//! [`crate::regressions::delete_and_detect`]). Answers 200 with what was removed, 404 for an
//! unknown run.

use axum::extract::{Path, State};
use axum::Json;

use super::auth::Writer;
use super::{AppError, AppState};
use crate::store::delete::Deleted;

pub async fn api(
    State(state): State<AppState>,
    Writer(who): Writer,
    Path(run_id): Path<String>,
) -> Result<Json<Deleted>, AppError> {
    let params = state.detect;
    let deleted = state
        .db(move |c| Ok(crate::regressions::delete_and_detect(c, &run_id, &params)?.0))
        .await?;
    eprintln!(
        "tessera-dashboard: run {} deleted with token {:?}",
        deleted.run_id, who.name
    );
    Ok(Json(deleted))
}
