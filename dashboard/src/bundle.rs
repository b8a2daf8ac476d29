//! A run bundle: one run's `run.json`, its scenario results and its saved images, as read from a
//! run folder or received by `POST /api/runs`, checked before anything touches the store.
//!
//! The wire format of the upload is documented in the crate README ("Uploading"); its type,
//! [`UploadBody`], and the run-folder reader are `tessera-results`'s, shared with `tessera upload`
//! and `tessera compare`, as is the upgrade of schema version 1 records. Not for: storing (see
//! [`crate::store`]) or HTTP details (see [`crate::server::upload`]).

use std::collections::BTreeMap;
use std::path::Path;

use tessera_results::folder::{self, ReadError};
use tessera_results::{RunInfo, ScenarioResult, OLDEST_SCHEMA_VERSION, SCHEMA_VERSION};

pub use tessera_results::folder::safe_relative_path;
pub use tessera_results::upload::UploadBody;

/// Largest single image accepted, in bytes.
pub const MAX_IMAGE_BYTES: usize = 16 << 20;

/// A checked run, ready to store.
#[derive(Debug, Clone)]
pub struct RunBundle {
    pub run: RunInfo,
    pub scenarios: Vec<ScenarioResult>,
    /// Image bytes by path in the run folder.
    pub images: BTreeMap<String, Vec<u8>>,
    /// Images uploaded apart as blobs: path in the run folder to the blob's digest
    /// (`UploadBody::image_digests`); the store checks that it holds each blob.
    pub image_digests: BTreeMap<String, String>,
}

#[derive(Debug, thiserror::Error)]
pub enum BundleError {
    #[error("{what} has schema_version {found}; this dashboard reads versions {OLDEST_SCHEMA_VERSION} to {SCHEMA_VERSION}: upgrade tessera-dashboard to store it")]
    UnknownSchema { what: String, found: String },
    #[error("{what} is not a valid record: {source}")]
    Invalid {
        what: String,
        #[source]
        source: serde_json::Error,
    },
    #[error("{0}")]
    Inconsistent(String),
    /// A field outside what an upload may hold (see [`crate::validate`]).
    #[error(transparent)]
    Field(#[from] crate::validate::FieldError),
    #[error("image {path}: {problem}")]
    Image { path: String, problem: String },
    #[error("cannot read {path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
}

impl From<folder::SchemaError> for BundleError {
    fn from(e: folder::SchemaError) -> Self {
        BundleError::UnknownSchema {
            what: e.what,
            found: e.found,
        }
    }
}

impl From<ReadError> for BundleError {
    fn from(e: ReadError) -> Self {
        match e {
            ReadError::Schema(s) => s.into(),
            ReadError::Io { path, source } => BundleError::Io {
                path: path.display().to_string(),
                source,
            },
            ReadError::Invalid { path, source } => BundleError::Invalid {
                what: path.display().to_string(),
                source,
            },
            ReadError::NotARun(dir) => BundleError::Io {
                path: dir.join("run.json").display().to_string(),
                source: std::io::Error::new(
                    std::io::ErrorKind::NotFound,
                    "no run.json: not a run folder written by `tessera run`",
                ),
            },
        }
    }
}

/// Upgrades a record to the current schema version (version 1 is read, newer ones are named),
/// then types it.
fn parse<T: serde::de::DeserializeOwned>(
    what: &str,
    value: serde_json::Value,
) -> Result<T, BundleError> {
    let value = folder::upgrade(what, value)?;
    serde_json::from_value(value).map_err(|source| BundleError::Invalid {
        what: what.to_string(),
        source,
    })
}

/// Run ids appear in URLs: letters, digits, `.`, `_`, `-`, at most 128.
pub fn valid_run_id(id: &str) -> bool {
    !id.is_empty()
        && id.len() <= 128
        && id != "."
        && id != ".."
        && id
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-'))
}

/// The first bytes of every PNG file.
pub const PNG_SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";

/// Every image path the results list.
fn referenced_images(scenarios: &[ScenarioResult]) -> std::collections::BTreeSet<&str> {
    scenarios
        .iter()
        .flat_map(|s| {
            s.results
                .iter()
                .flat_map(|v| v.images.iter().map(|i| i.path.as_str()))
        })
        .collect()
}

/// What is wrong with an image's path, inline or sent as a blob: outside the run folder, or
/// listed by no result.
fn path_problem(path: &str, referenced: &std::collections::BTreeSet<&str>) -> Option<String> {
    if !safe_relative_path(path) {
        Some("must be a relative path inside the run folder".to_string())
    } else if !referenced.contains(path) {
        Some("is not listed in any result's images".to_string())
    } else {
        None
    }
}

impl RunBundle {
    /// Checks the schema versions first (so a newer format is named as such rather than as a
    /// parse error), then the records, the run ids, every field against [`crate::validate`]
    /// (times against the server's clock now) and every image.
    pub fn from_parts(
        run: serde_json::Value,
        scenarios: Vec<serde_json::Value>,
        images: BTreeMap<String, Vec<u8>>,
    ) -> Result<RunBundle, BundleError> {
        Self::from_parts_at(run, scenarios, images, chrono::Utc::now())
    }

    /// [`RunBundle::from_parts`] with the server's clock given (tests).
    pub fn from_parts_at(
        run: serde_json::Value,
        scenarios: Vec<serde_json::Value>,
        images: BTreeMap<String, Vec<u8>>,
        now: chrono::DateTime<chrono::Utc>,
    ) -> Result<RunBundle, BundleError> {
        let run: RunInfo = parse("run.json", run)?;
        if !valid_run_id(&run.run_id) {
            return Err(BundleError::Inconsistent(format!(
                "run_id {:?} may only hold letters, digits, '.', '_' and '-' (at most 128)",
                run.run_id
            )));
        }
        let mut parsed: Vec<ScenarioResult> = Vec::with_capacity(scenarios.len());
        for (i, s) in scenarios.into_iter().enumerate() {
            let name = s
                .get("scenario")
                .and_then(|v| v.as_str())
                .unwrap_or("?")
                .to_string();
            let s: ScenarioResult = parse(&format!("scenario result {i} ({name})"), s)?;
            if s.run_id != run.run_id {
                return Err(BundleError::Inconsistent(format!(
                    "scenario {} has run_id {:?} but run.json has {:?}",
                    s.scenario, s.run_id, run.run_id
                )));
            }
            if parsed.iter().any(|p| p.scenario == s.scenario) {
                return Err(BundleError::Inconsistent(format!(
                    "scenario {} appears twice",
                    s.scenario
                )));
            }
            let mut seen = std::collections::BTreeSet::new();
            for v in &s.results {
                if !seen.insert(&v.variant) {
                    return Err(BundleError::Inconsistent(format!(
                        "scenario {} lists variant {} twice",
                        s.scenario, v.variant
                    )));
                }
            }
            parsed.push(s);
        }
        crate::validate::check(&run, &parsed, now)?;
        let referenced = referenced_images(&parsed);
        for (path, bytes) in &images {
            let problem = if let Some(p) = path_problem(path, &referenced) {
                Some(p)
            } else if bytes.len() > MAX_IMAGE_BYTES {
                Some(format!(
                    "is {} bytes; the limit is {MAX_IMAGE_BYTES}",
                    bytes.len()
                ))
            } else if !bytes.starts_with(PNG_SIGNATURE) {
                Some("is not a PNG file".to_string())
            } else {
                None
            };
            if let Some(problem) = problem {
                return Err(BundleError::Image {
                    path: path.clone(),
                    problem,
                });
            }
        }
        Ok(RunBundle {
            run,
            scenarios: parsed,
            images,
            image_digests: BTreeMap::new(),
        })
    }

    /// Adds images sent apart as blobs (path to digest), each checked as an inline image's path
    /// is, and its digest for shape; whether the store holds the blob is the store's check.
    pub fn with_image_digests(
        mut self,
        digests: BTreeMap<String, String>,
    ) -> Result<RunBundle, BundleError> {
        let referenced = referenced_images(&self.scenarios);
        for (path, digest) in &digests {
            let problem = if let Some(p) = path_problem(path, &referenced) {
                Some(p)
            } else if self.images.contains_key(path) {
                Some("is sent both inline and as a blob".to_string())
            } else if !tessera_results::upload::is_blob_digest(digest) {
                Some(format!(
                    "has digest {digest:?}; a blob digest is 64 lowercase hex digits (SHA-256)"
                ))
            } else {
                None
            };
            if let Some(problem) = problem {
                return Err(BundleError::Image {
                    path: path.clone(),
                    problem,
                });
            }
        }
        self.image_digests = digests;
        Ok(self)
    }

    /// Every image's digest by path: inline images hashed, blobs as referenced.
    pub fn digests_by_path(&self) -> BTreeMap<&str, String> {
        let mut out: BTreeMap<&str, String> = self
            .images
            .iter()
            .map(|(p, b)| (p.as_str(), tessera_results::upload::blob_digest(b)))
            .collect();
        for (p, d) in &self.image_digests {
            out.insert(p.as_str(), d.clone());
        }
        out
    }

    /// Decodes an upload body.
    pub fn from_upload(body: UploadBody) -> Result<RunBundle, BundleError> {
        let images = body
            .decode_images()
            .map_err(|(path, e)| BundleError::Image {
                path,
                problem: format!("is not valid base64: {e}"),
            })?;
        RunBundle::from_parts(body.run, body.scenarios, images)?
            .with_image_digests(body.image_digests)
    }

    /// Reads a run folder through the shared reader: `run.json`, `scenarios/*.json` (in name
    /// order, upgraded to the current version) and every listed image that exists (a missing
    /// image is left out, not an error: runs may be saved without them).
    pub fn read_folder(dir: &Path) -> Result<RunBundle, BundleError> {
        let raw = folder::read_raw(dir)?;
        let images = raw.read_images()?;
        RunBundle::from_parts(raw.run, raw.scenarios, images)
    }

    /// What storing this run should tell the one who sends it, though nothing refuses it: a run
    /// whose record carries no commit (tessera ran outside a git checkout) is stored, but has no
    /// commit to place it among and is never a previous run, which nothing else would say until
    /// someone opens its page. `import` prints these; `POST /api/runs` answers them for `tessera
    /// upload` to print.
    pub fn warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        if self.run.commit.is_none() {
            out.push(format!(
                "run {} records no commit (tessera ran outside a git checkout): it is stored, but it is never the previous run of its suite and no alert can name its commit; run tessera from a checkout of the project",
                self.run.run_id
            ));
        }
        out
    }

    /// The upload body for this bundle (what `tessera run --upload` sends).
    pub fn to_upload(&self) -> UploadBody {
        UploadBody {
            run: serde_json::to_value(&self.run).expect("records serialise"),
            scenarios: self
                .scenarios
                .iter()
                .map(|s| serde_json::to_value(s).expect("records serialise"))
                .collect(),
            images: self
                .images
                .iter()
                .map(|(p, b)| (p.clone(), tessera_results::upload::encode(b)))
                .collect(),
            image_digests: self.image_digests.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_ids_are_url_safe() {
        assert!(valid_run_id("20261122T025424Z"));
        for bad in ["", "..", "a/b", "a b", "%2e"] {
            assert!(!valid_run_id(bad), "{bad}");
        }
    }

    #[test]
    fn unknown_schema_version_is_named() {
        let err = RunBundle::from_parts(
            serde_json::json!({"schema_version": 99}),
            vec![],
            BTreeMap::new(),
        )
        .unwrap_err();
        assert_eq!(
            err.to_string(),
            "run.json has schema_version 99; this dashboard reads versions 1 to 3: upgrade tessera-dashboard to store it"
        );
    }
}
