//! `POST /api/runs`: stores a run bundle (JSON: `run`, `scenarios`, base64 `images`; see the
//! README). Needs the bearer token. Answers 201 with `{"run_id", "stored": true, ...}` for a new run,
//! 200 with `"stored": false` for a run id already stored (idempotent), 4xx with a JSON error for
//! bad or oversized input, in which case nothing is stored. The token is checked by
//! [`super::auth::guard`] before the body is read; the [`RunnerAuth`] extractor comes first for the
//! same reason. A write token uploads any run; a runner token only a run of a job one of its
//! runners holds, named by the `X-Tessera-Job` header, at one of that job's commits (403 otherwise).

use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::State;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use axum::Json;
use serde::Serialize;

use super::auth::{RunnerAuth, Scope};
use super::{AppError, AppState};
use crate::bundle::{RunBundle, UploadBody};
use crate::store::ingest::Ingested;

#[derive(Debug, Serialize, serde::Deserialize, PartialEq)]
pub struct UploadResponse {
    pub run_id: String,
    pub stored: bool,
    pub results: usize,
    pub new_regressions: usize,
    /// What the sender should know though the run was taken ([`RunBundle::warnings`]: a run
    /// without a commit); absent when there is nothing to say.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

pub async fn api(
    State(state): State<AppState>,
    RunnerAuth(who): RunnerAuth,
    headers: axum::http::HeaderMap,
    body: Result<Bytes, BytesRejection>,
) -> Result<Response, AppError> {
    let body = body.map_err(|e| {
        if is_timeout(&e) {
            AppError::RequestTimeout(format!(
                "the body paused for more than {} s",
                state.timeouts.body_idle.as_secs()
            ))
        } else if e.status() == StatusCode::PAYLOAD_TOO_LARGE {
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
    let warnings = bundle.warnings();
    let params = state.detect;
    let job = if who.scope.allows(Scope::Write) {
        None
    } else {
        let header = tessera_results::queue::JOB_HEADER;
        let id = headers
            .get(header)
            .and_then(|v| v.to_str().ok())
            .and_then(|v| v.trim().parse::<i64>().ok())
            .ok_or_else(|| {
                AppError::Forbidden(format!(
                    "token {:?} has scope runner: it uploads only the run of a job it holds, \
                     named by the {header} header",
                    who.name
                ))
            })?;
        Some((id, who.name.clone()))
    };
    let (status, response) = state
        .db(move |conn| {
            if let Some((id, token)) = &job {
                let commit = bundle.run.commit.as_ref().map(|c| c.sha.as_str());
                if let Some(why) = crate::store::queue::upload_refusal(conn, *id, token, commit)? {
                    return Err(AppError::Forbidden(why));
                }
            }
            // The store's checkpoint runs after the response, off the writer's path.
            let ingested = crate::db::without_autocheckpoint(conn, |c| {
                crate::regressions::ingest_and_detect(c, &bundle, &params)
            })??;
            match ingested {
                (Ingested::Stored { results, .. }, changes) => {
                    let new_regressions = changes.detected;
                    Ok((
                        StatusCode::CREATED,
                        UploadResponse {
                            run_id,
                            stored: true,
                            results,
                            new_regressions,
                            warnings,
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
                        warnings,
                    },
                )),
            }
        })
        .await?;
    if status == StatusCode::CREATED {
        // Copies the pages the upload wrote into the store file ([`crate::db::checkpoint`]).
        let pool = state.pool.clone();
        tokio::task::spawn_blocking(move || {
            let done = pool.get().and_then(|mut c| crate::db::checkpoint(&mut *c));
            if let Err(e) = done {
                eprintln!("tessera-dashboard: checkpoint after an upload failed: {e}");
            }
        });
    }
    Ok((status, Json(response)).into_response())
}

/// Whether the body failed because tower-http's body timeout fired.
fn is_timeout(e: &BytesRejection) -> bool {
    let mut source: Option<&(dyn std::error::Error + 'static)> = Some(e);
    while let Some(s) = source {
        if s.is::<tower_http::timeout::TimeoutError>() {
            return true;
        }
        source = s.source();
    }
    false
}
