//! The body of `POST /api/runs`: what `tessera upload` sends and the dashboard accepts. One type
//! on both sides, so the wire format (`dashboard/README.md`, "Uploading") has one definition.
//!
//! Images may travel inside the body (base64, `images`) or apart from it, as content-addressed
//! blobs: the client asks `POST /api/blobs/missing` which of its images' [`blob_digest`]s the
//! dashboard lacks, sends each of those once with `PUT /api/blobs/<digest>`, then posts the body
//! with `image_digests` (path to digest) instead of the bytes. A run of any size then fits the
//! dashboard's request cap, and a repeated upload sends only the records.
//!
//! The records travel as JSON values, not typed: the dashboard checks each one's
//! `schema_version` (and upgrades version 1, [`crate::folder::upgrade`]) before parsing, so a
//! newer format is named as such. Not for: sending (the harness's `upload.rs`) or checking a
//! bundle (the dashboard's `bundle.rs`).

use std::collections::BTreeMap;

use base64::Engine;
use serde::{Deserialize, Serialize};
use sha2::{Digest as _, Sha256};

use crate::folder::{RawRun, ReadError};

/// `run` (run.json), `scenarios` (every scenario result) and `images` (every PNG the results list
/// and the folder holds, keyed by its path in the run folder, in base64).
#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
pub struct UploadBody {
    pub run: serde_json::Value,
    pub scenarios: Vec<serde_json::Value>,
    #[serde(default)]
    pub images: BTreeMap<String, String>,
    /// Images sent apart, as blobs: path in the run folder to its [`blob_digest`]. The
    /// dashboard must hold each blob already (`PUT /api/blobs/<digest>`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub image_digests: BTreeMap<String, String>,
}

impl UploadBody {
    /// The body of a run folder read with [`crate::folder::read_raw`] (records upgraded to the
    /// current version): its records and every listed image it holds.
    pub fn from_folder(raw: &RawRun) -> Result<UploadBody, ReadError> {
        let images = raw
            .read_images()?
            .into_iter()
            .map(|(p, b)| (p, encode(&b)))
            .collect();
        Ok(UploadBody {
            run: raw.run.clone(),
            scenarios: raw.scenarios.clone(),
            images,
            image_digests: BTreeMap::new(),
        })
    }

    /// The images' bytes by path; the first path whose text is not base64 is the error, with
    /// the decoder's reason.
    pub fn decode_images(&self) -> Result<BTreeMap<String, Vec<u8>>, (String, String)> {
        self.images
            .iter()
            .map(|(path, b64)| {
                base64::engine::general_purpose::STANDARD
                    .decode(b64.as_bytes())
                    .map(|b| (path.clone(), b))
                    .map_err(|e| (path.clone(), e.to_string()))
            })
            .collect()
    }
}

/// The content address of an image blob: lowercase hex SHA-256 of its bytes.
pub fn blob_digest(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// Whether `s` has the shape of a [`blob_digest`] (64 lowercase hex digits).
pub fn is_blob_digest(s: &str) -> bool {
    s.len() == 64
        && s.bytes()
            .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b))
}

/// `POST /api/blobs/missing`: the digests a client holds.
#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
pub struct MissingRequest {
    pub digests: Vec<String>,
}

/// The answer: those of them the dashboard does not hold, in the order asked.
#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
pub struct MissingReply {
    pub missing: Vec<String>,
}

/// One record of a blob batch (`POST /api/blobs`): the 64 ASCII hex digits of the blob's
/// digest, its length as a little-endian u64, its bytes.
pub fn blob_record(bytes: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(72 + bytes.len());
    out.extend_from_slice(blob_digest(bytes).as_bytes());
    out.extend_from_slice(&(bytes.len() as u64).to_le_bytes());
    out.extend_from_slice(bytes);
    out
}

/// The records of a blob batch, each one's bytes checked against its digest; `max_len` bounds a
/// record's announced length before anything is read. The first bad record is the error, named
/// by its index.
pub fn split_batch(mut body: &[u8], max_len: u64) -> Result<Vec<(String, &[u8])>, String> {
    let mut out = Vec::new();
    while !body.is_empty() {
        let i = out.len();
        if body.len() < 72 {
            return Err(format!(
                "blob {i}: the record is cut short ({} bytes left; a record starts with a 64-byte digest and an 8-byte length)",
                body.len()
            ));
        }
        let digest = std::str::from_utf8(&body[..64])
            .ok()
            .filter(|d| is_blob_digest(d))
            .ok_or_else(|| format!("blob {i}: the digest is not 64 lowercase hex digits"))?
            .to_string();
        let len = u64::from_le_bytes(body[64..72].try_into().expect("8 bytes"));
        if len > max_len {
            return Err(format!(
                "blob {i} ({digest}) is {len} bytes; the limit is {max_len}"
            ));
        }
        let rest = &body[72..];
        if (rest.len() as u64) < len {
            return Err(format!(
                "blob {i} ({digest}): {len} bytes announced, {} sent",
                rest.len()
            ));
        }
        let (bytes, tail) = rest.split_at(len as usize);
        if blob_digest(bytes) != digest {
            return Err(format!(
                "blob {i}: its bytes do not hash to {digest} (SHA-256)"
            ));
        }
        out.push((digest, bytes));
        body = tail;
    }
    Ok(out)
}

/// Standard base64 with padding, as the body carries images.
pub fn encode(bytes: &[u8]) -> String {
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn images_round_trip_and_bad_base64_is_named() {
        let mut body = UploadBody::default();
        body.images
            .insert("images/a.png".into(), encode(b"\x89PNG"));
        assert_eq!(body.decode_images().unwrap()["images/a.png"], b"\x89PNG");
        body.images.insert("images/b.png".into(), "%%%".into());
        let (path, _) = body.decode_images().unwrap_err();
        assert_eq!(path, "images/b.png");
        // Without images the key may be absent.
        let b: UploadBody = serde_json::from_str(r#"{"run": {}, "scenarios": []}"#).unwrap();
        assert!(b.images.is_empty());
        assert!(b.image_digests.is_empty());
    }

    #[test]
    fn blob_digests_are_sha256_hex() {
        // SHA-256 of the empty string.
        let d = blob_digest(b"");
        assert_eq!(
            d,
            "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"
        );
        assert!(is_blob_digest(&d));
        assert!(!is_blob_digest(&d.to_uppercase()));
        assert!(!is_blob_digest(&d[1..]));
        assert!(!is_blob_digest("../../etc/passwd"));
    }
}
