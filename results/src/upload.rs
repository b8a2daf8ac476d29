//! The body of `POST /api/runs`: what `tessera upload` sends and the dashboard accepts. One type
//! on both sides, so the wire format (`dashboard/README.md`, "Uploading") has one definition.
//!
//! The records travel as JSON values, not typed: the dashboard checks each one's
//! `schema_version` (and upgrades version 1, [`crate::folder::upgrade`]) before parsing, so a
//! newer format is named as such. Not for: sending (the harness's `upload.rs`) or checking a
//! bundle (the dashboard's `bundle.rs`).

use std::collections::BTreeMap;

use base64::Engine;
use serde::{Deserialize, Serialize};

use crate::folder::{RawRun, ReadError};

/// `run` (run.json), `scenarios` (every scenario result) and `images` (every PNG the results list
/// and the folder holds, keyed by its path in the run folder, in base64).
#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
pub struct UploadBody {
    pub run: serde_json::Value,
    pub scenarios: Vec<serde_json::Value>,
    #[serde(default)]
    pub images: BTreeMap<String, String>,
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
    }
}
