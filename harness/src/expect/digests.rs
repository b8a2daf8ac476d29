//! Approved frame digests on the harness's side: `tessera run --expect URL|FILE` reads the digests
//! approved for the run's adapter class (from a dashboard's `GET /api/approved-frames?class=`, or
//! a committed file `scenarios/<suite>/digests/<class>.json`) before running, and fails the run
//! on a frame whose digest is not approved; `tessera digests approve RUN...` writes those files
//! from runs a person has looked at. The format is `results/README.md`, "Approved frame digests".
//!
//! Not for: computing digests (`run/frames.rs`, `tessera_results::digest`) or the dashboard's
//! triage.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use tessera_results::ScenarioResult;

/// The variant name a separately rendered reference's frames are kept under.
pub const REFERENCE_VARIANT: &str = "(reference)";

/// A file of judged digests of one adapter class.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq, Eq)]
#[serde(deny_unknown_fields)]
pub struct DigestFile {
    pub adapter_class: String,
    pub frames: Vec<DigestEntry>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Eq, PartialOrd, Ord)]
#[serde(deny_unknown_fields)]
pub struct DigestEntry {
    pub scenario: String,
    pub variant: String,
    pub frame: u32,
    pub digest: String,
    /// `positive` (approved) or `negative` (marked as a regression).
    pub state: String,
}

#[derive(Debug, thiserror::Error)]
pub enum DigestError {
    #[error("cannot read {path}: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(
        "{path} is not a digest file (results/README.md, \"Approved frame digests\"): {source}"
    )]
    Parse {
        path: String,
        source: serde_json::Error,
    },
    #[error("cannot fetch approved frames from {url}: {message}")]
    Fetch { url: String, message: String },
    #[error("{what} holds digests of adapter class `{found}`, but this run's adapter is class `{wanted}`: approved frames are kept per adapter class")]
    WrongClass {
        what: String,
        found: String,
        wanted: String,
    },
    #[error("cannot write {path}: {message}")]
    Write { path: PathBuf, message: String },
}

/// Reads approved digests from a dashboard (`http://` or `https://`) or a file, for `class`.
pub fn load(source: &str, class: &str) -> Result<DigestFile, DigestError> {
    let (what, text) = if source.starts_with("http://") || source.starts_with("https://") {
        let url = format!(
            "{}/api/approved-frames?class={}",
            source.trim_end_matches('/'),
            class
        );
        let fetch_err = |message: String| DigestError::Fetch {
            url: url.clone(),
            message,
        };
        let mut reply = ureq::get(&url)
            .call()
            .map_err(|e| fetch_err(e.to_string()))?;
        let text = reply
            .body_mut()
            .read_to_string()
            .map_err(|e| fetch_err(e.to_string()))?;
        (url, text)
    } else {
        let text = std::fs::read_to_string(source).map_err(|e| DigestError::Read {
            path: source.into(),
            source: e,
        })?;
        (source.to_string(), text)
    };
    let file: DigestFile = serde_json::from_str(&text).map_err(|e| DigestError::Parse {
        path: what.clone(),
        source: e,
    })?;
    if file.adapter_class != class {
        return Err(DigestError::WrongClass {
            what,
            found: file.adapter_class,
            wanted: class.to_string(),
        });
    }
    Ok(file)
}

/// Every (variant, frame, digest) of a scenario result, the separate reference's under
/// [`REFERENCE_VARIANT`].
pub fn digests_of(s: &ScenarioResult) -> Vec<(String, u32, String)> {
    let mut out = Vec::new();
    for v in &s.results {
        for (i, d) in v.frame_digests.iter().enumerate() {
            out.push((v.variant.clone(), i as u32, d.clone()));
        }
    }
    for (i, d) in s.reference_digests.iter().enumerate() {
        out.push((REFERENCE_VARIANT.to_string(), i as u32, d.clone()));
    }
    out
}

/// How a run's frames compare with the approved digests.
#[derive(Debug, Default, PartialEq, Eq)]
pub struct Check {
    pub matched: usize,
    /// Frames with no judged digest (a new scenario or variant): reported, not failed.
    pub new: usize,
    /// `scenario / variant frame N: digest` of frames whose digest is not approved.
    pub unapproved: Vec<String>,
    /// Frames whose digest was marked as a regression.
    pub negative: Vec<String>,
}

impl Check {
    pub fn failed(&self) -> bool {
        !self.unapproved.is_empty() || !self.negative.is_empty()
    }

    /// One line for the console.
    pub fn summary(&self, source: &str) -> String {
        format!(
            "approved frames ({source}): {} matched, {} unapproved, {} marked as regressions, {} without approved frames",
            self.matched,
            self.unapproved.len(),
            self.negative.len(),
            self.new
        )
    }
}

/// Compares every frame digest of `results` with `file`.
pub fn check(results: &[ScenarioResult], file: &DigestFile) -> Check {
    let mut judged: BTreeMap<(&str, &str, u32), Vec<&DigestEntry>> = BTreeMap::new();
    for e in &file.frames {
        judged
            .entry((e.scenario.as_str(), e.variant.as_str(), e.frame))
            .or_default()
            .push(e);
    }
    let mut c = Check::default();
    for s in results {
        for (variant, frame, digest) in digests_of(s) {
            let at = format!("{} / {variant} frame {frame}: {digest}", s.scenario);
            match judged.get(&(s.scenario.as_str(), variant.as_str(), frame)) {
                None => c.new += 1,
                Some(entries) => match entries.iter().find(|e| e.digest == digest) {
                    Some(e) if e.state == "positive" => c.matched += 1,
                    Some(_) => c.negative.push(at),
                    None => c.unapproved.push(at),
                },
            }
        }
    }
    c
}

/// `tessera digests approve RUN...`: each run's digests become `positive` in the file of its
/// suite and adapter class (`<scenario folder>/digests/<class>.json`), replacing what the file
/// held for the same frames. Returns (file, frames written) per file.
pub fn approve(runs: &[PathBuf]) -> Result<Vec<(PathBuf, usize)>, DigestError> {
    let mut files: BTreeMap<PathBuf, (String, Vec<DigestEntry>)> = BTreeMap::new();
    for dir in runs {
        let run = tessera_results::folder::read(dir).map_err(|e| DigestError::Write {
            path: dir.clone(),
            message: e.to_string(),
        })?;
        let class = run
            .info
            .adapter_class
            .clone()
            .unwrap_or_else(|| tessera_results::adapter::class(&run.info.adapter));
        for s in &run.scenarios {
            let path = Path::new(&s.file)
                .parent()
                .unwrap_or(Path::new(""))
                .join("digests")
                .join(format!("{class}.json"));
            let entry = files
                .entry(path)
                .or_insert_with(|| (class.clone(), Vec::new()));
            for (variant, frame, digest) in digests_of(s) {
                entry.1.push(DigestEntry {
                    scenario: s.scenario.clone(),
                    variant,
                    frame,
                    digest,
                    state: "positive".into(),
                });
            }
        }
    }
    let mut written = Vec::new();
    for (path, (class, new)) in files {
        let mut file = match std::fs::read_to_string(&path) {
            Ok(text) => serde_json::from_str(&text).map_err(|e| DigestError::Parse {
                path: path.display().to_string(),
                source: e,
            })?,
            Err(_) => DigestFile {
                adapter_class: class,
                frames: Vec::new(),
            },
        };
        let replaced: BTreeSet<(String, String, u32)> = new
            .iter()
            .map(|e| (e.scenario.clone(), e.variant.clone(), e.frame))
            .collect();
        file.frames
            .retain(|e| !replaced.contains(&(e.scenario.clone(), e.variant.clone(), e.frame)));
        let n = new.len();
        file.frames.extend(new);
        file.frames.sort();
        let mut json = serde_json::to_string_pretty(&file).expect("plain data serialises");
        json.push('\n');
        crate::files::write_atomic(&path, json.as_bytes()).map_err(|e| DigestError::Write {
            path: e.path,
            message: e.source.to_string(),
        })?;
        written.push((path, n));
    }
    Ok(written)
}
