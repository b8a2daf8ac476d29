//! `DELETE /api/runs/{run_id}` (write token): deletes a run with its results, points, images,
//! blobs no other run uses and the alerts that pointed at it, in one transaction (see
//! [`crate::store::delete`]). Answers 200 with what was removed, 404 for an unknown run.

use axum::extract::{Path, State};
use axum::Json;

use super::auth::Writer;
use super::{AppError, AppState};
use crate::store::delete::{delete_run, Deleted};

pub async fn api(
    State(state): State<AppState>,
    Writer(who): Writer,
    Path(run_id): Path<String>,
) -> Result<Json<Deleted>, AppError> {
    let deleted = state.db(move |c| Ok(delete_run(c, &run_id)?)).await?;
    eprintln!(
        "tessera-dashboard: run {} deleted with token {:?}",
        deleted.run_id, who.name
    );
    Ok(Json(deleted))
}
