//! Image blobs sent apart from a run's records (`POST /api/blobs/missing`, `POST /api/blobs`):
//! which digests the store lacks, and storing a batch of blobs, each checked against its
//! digest. The `blobs` table is the one inline images go to, so a blob is stored once whichever
//! way it came. Not for: linking images to results (ingest does that) or serving them
//! (`read::blob`).

use super::StoreError;
use crate::db::{transaction, Connection, DbError, Value};

/// Of `digests`, those the store does not hold, in the order given (each once).
pub fn missing(conn: &mut dyn Connection, digests: &[String]) -> Result<Vec<String>, StoreError> {
    let mut out: Vec<String> = Vec::new();
    for d in digests {
        if out.contains(d) {
            continue;
        }
        if conn
            .query_opt(
                "SELECT 1 FROM blobs WHERE digest = $1",
                &[d.as_str().into()],
            )?
            .is_none()
        {
            out.push(d.clone());
        }
    }
    Ok(out)
}

/// Stores `(digest, bytes)` pairs already checked by the caller, in one transaction, in digest
/// order (concurrent uploads take rows in one order); returns how many were new.
pub fn store(conn: &mut dyn Connection, blobs: &[(String, Vec<u8>)]) -> Result<usize, StoreError> {
    let mut sorted: Vec<&(String, Vec<u8>)> = blobs.iter().collect();
    sorted.sort_by(|a, b| a.0.cmp(&b.0));
    let mut attempt = 0;
    loop {
        let r = transaction(conn, |c| {
            let mut new = 0;
            for (d, bytes) in &sorted {
                new += c.execute(
                    "INSERT INTO blobs (digest, bytes) VALUES ($1, $2) ON CONFLICT DO NOTHING",
                    &[d.as_str().into(), Value::Blob(bytes.clone())],
                )? as usize;
            }
            Ok::<_, DbError>(new)
        });
        match r {
            Err(e) if e.is_retryable() && attempt < 5 => attempt += 1,
            other => return Ok(other?),
        }
    }
}
