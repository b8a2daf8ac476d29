//! Images sent apart from a run's records, so that a run of any size uploads under the request
//! cap and a repeated upload sends only what the dashboard lacks (`dashboard/README.md`,
//! "Uploading"):
//!
//! - `POST /api/blobs/missing` `{"digests": [...]}` answers `{"missing": [...]}`: which of the
//!   client's image digests (lowercase hex SHA-256) the store does not hold.
//! - `POST /api/blobs` stores a batch: a body of records `<64 hex digest bytes><u64 length,
//!   little-endian><bytes>`, each a PNG of at most `MAX_IMAGE_BYTES` whose SHA-256 is its
//!   digest; answers `{"stored", "already"}`. A batch is all or nothing; blobs a client sent
//!   before a failure stay, so an interrupted upload resumes where it stopped.
//!
//! Both take a write token, or a runner token (a runner uploads the run of the job it holds with
//! its images; a blob is content-addressed and checked against its digest, so storing one grants
//! nothing else), like `POST /api/runs` that then refers to the blobs by digest.

use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::State;
use axum::http::StatusCode;
use axum::Json;
use serde::Serialize;
use tessera_results::upload::{is_blob_digest, split_batch, MissingReply, MissingRequest};

use super::auth::RunnerAuth;
use super::{AppError, AppState};
use crate::bundle::{MAX_IMAGE_BYTES, PNG_SIGNATURE};

/// Most digests one `missing` question may hold.
pub const MAX_DIGESTS: usize = 100_000;

pub async fn missing(
    State(state): State<AppState>,
    RunnerAuth(_who): RunnerAuth,
    body: Result<Bytes, BytesRejection>,
) -> Result<Json<MissingReply>, AppError> {
    let body = body.map_err(|e| AppError::BadRequest(e.body_text()))?;
    let req: MissingRequest = serde_json::from_slice(&body).map_err(|e| {
        AppError::BadRequest(format!("the body is not {{\"digests\": [...]}}: {e}"))
    })?;
    if req.digests.len() > MAX_DIGESTS {
        return Err(AppError::BadRequest(format!(
            "{} digests asked at once; at most {MAX_DIGESTS}",
            req.digests.len()
        )));
    }
    if let Some(bad) = req.digests.iter().find(|d| !is_blob_digest(d)) {
        return Err(AppError::BadRequest(format!(
            "digest {bad:?} is not 64 lowercase hex digits (SHA-256)"
        )));
    }
    let digests = req.digests;
    let missing = state
        .db(move |c| Ok(crate::store::blobs::missing(c, &digests)?))
        .await?;
    Ok(Json(MissingReply { missing }))
}

#[derive(Debug, Serialize, serde::Deserialize, PartialEq)]
pub struct StoreReply {
    /// Blobs the store did not hold before.
    pub stored: usize,
    /// Blobs of the batch it held already.
    pub already: usize,
}

pub async fn store(
    State(state): State<AppState>,
    RunnerAuth(_who): RunnerAuth,
    body: Result<Bytes, BytesRejection>,
) -> Result<(StatusCode, Json<StoreReply>), AppError> {
    let body = body.map_err(|e| {
        if e.status() == StatusCode::PAYLOAD_TOO_LARGE {
            AppError::PayloadTooLarge(format!(
                "a batch of blobs is at most {} bytes; send fewer at once",
                state.max_upload_bytes
            ))
        } else {
            AppError::BadRequest(e.body_text())
        }
    })?;
    let blobs = tokio::task::spawn_blocking(move || parse_batch(&body))
        .await
        .map_err(|e| AppError::Internal(e.to_string()))?
        .map_err(AppError::BadRequest)?;
    let n = blobs.len();
    let stored = state
        .db(move |c| Ok(crate::store::blobs::store(c, &blobs)?))
        .await?;
    Ok((
        StatusCode::CREATED,
        Json(StoreReply {
            stored,
            already: n - stored,
        }),
    ))
}

/// The blobs of a batch (the shared framing, `tessera_results::upload::split_batch`), each also
/// a PNG of at most [`MAX_IMAGE_BYTES`]; the first bad one is the error.
pub fn parse_batch(body: &[u8]) -> Result<Vec<(String, Vec<u8>)>, String> {
    split_batch(body, MAX_IMAGE_BYTES as u64)?
        .into_iter()
        .enumerate()
        .map(|(i, (digest, bytes))| {
            if bytes.starts_with(PNG_SIGNATURE) {
                Ok((digest, bytes.to_vec()))
            } else {
                Err(format!("blob {i} ({digest}) is not a PNG file"))
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use tessera_results::upload::{blob_digest, blob_record as record};

    fn png(tag: u8) -> Vec<u8> {
        let mut b = PNG_SIGNATURE.to_vec();
        b.extend_from_slice(&[tag; 20]);
        b
    }

    #[test]
    fn a_batch_round_trips_and_bad_records_are_named() {
        let mut body = record(&png(1));
        body.extend(record(&png(2)));
        let blobs = parse_batch(&body).unwrap();
        assert_eq!(blobs.len(), 2);
        assert_eq!(blobs[1].0, blob_digest(&png(2)));
        assert_eq!(blobs[1].1, png(2));

        // A flipped byte of the second blob: its hash no longer matches.
        let mut bad = body.clone();
        let last = bad.len() - 1;
        bad[last] ^= 1;
        assert!(parse_batch(&bad)
            .unwrap_err()
            .starts_with("blob 1: its bytes"));
        // Cut short.
        assert!(parse_batch(&body[..body.len() - 3])
            .unwrap_err()
            .contains("announced"));
        // Not a PNG.
        let e = parse_batch(&record(b"GIF89a")).unwrap_err();
        assert!(e.contains("not a PNG"), "{e}");
        // A digest in capitals.
        let mut caps = record(&png(3));
        caps[..64].make_ascii_uppercase();
        assert!(parse_batch(&caps).unwrap_err().contains("lowercase hex"));
        assert!(parse_batch(&[]).unwrap().is_empty());
    }
}
