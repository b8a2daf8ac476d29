//! `POST /api/runs`: stores a run bundle (JSON: `run`, `scenarios`, base64 `images`; see the
//! README). Needs the bearer token. Answers 201 with `{"run_id", "stored": true, ...}` for a new run,
//! 200 with `"stored": false` for a run id already stored (idempotent), 4xx with a JSON error for
//! bad or oversized input, in which case nothing is stored.

use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::State;
use axum::http::{HeaderMap, StatusCode};
use axum::response::{IntoResponse, Response};
use axum::Json;
use serde::Serialize;

use super::{auth, AppError, AppState};
use crate::bundle::{RunBundle, UploadBody};
use crate::store::ingest::Ingested;

#[derive(Debug, Serialize, serde::Deserialize, PartialEq)]
pub struct UploadResponse {
    pub run_id: String,
    pub stored: bool,
    pub results: usize,
    pub new_regressions: usize,
}

pub async fn api(
    State(state): State<AppState>,
    headers: HeaderMap,
    body: Result<Bytes, BytesRejection>,
) -> Result<Response, AppError> {
    auth::require_bearer(&state, &headers)?;
    let body = body.map_err(|e| {
        if e.status() == StatusCode::PAYLOAD_TOO_LARGE {
            AppError::PayloadTooLarge(format!(
                "the upload is larger than {} bytes",
                state.max_upload_bytes
            ))
        } else {
            AppError::BadRequest(e.body_text())
        }
    })?;
    if body.len() > state.max_upload_bytes {
        return Err(AppError::PayloadTooLarge(format!(
            "the upload is larger than {} bytes",
            state.max_upload_bytes
        )));
    }
    let parsed: UploadBody = serde_json::from_slice(&body).map_err(|e| {
        AppError::BadRequest(format!(
            "the body is not an upload bundle (run, scenarios, images): {e}"
        ))
    })?;
    let bundle = tokio::task::spawn_blocking(move || RunBundle::from_upload(parsed))
        .await
        .map_err(|e| AppError::Internal(e.to_string()))??;
    let run_id = bundle.run.run_id.clone();
    let params = state.detect;
    let (status, response) = state
        .db(
            move |conn| match crate::regressions::ingest_and_detect(conn, &bundle, &params)? {
                (Ingested::Stored { results, .. }, changes) => {
                    let new_regressions = changes.detected;
                    Ok((
                        StatusCode::CREATED,
                        UploadResponse {
                            run_id,
                            stored: true,
                            results,
                            new_regressions,
                        },
                    ))
                }
                (Ingested::AlreadyStored { .. }, _) => Ok((
                    StatusCode::OK,
                    UploadResponse {
                        run_id,
                        stored: false,
                        results: 0,
                        new_regressions: 0,
                    },
                )),
            },
        )
        .await?;
    Ok((status, Json(response)).into_response())
}
