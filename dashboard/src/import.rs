//! `tessera-dashboard import`: finds run folders (the folder itself when it holds `run.json`,
//! else its sub-folders that do) and stores each as an upload does: the run and detection on the
//! series it touched in one transaction ([`crate::regressions::ingest_and_detect`]).
//!
//! Not for: checking records (see [`crate::bundle`]) or SQL (see [`crate::store::ingest`]).

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use crate::bundle::RunBundle;
use crate::db::Pool;
use crate::detect::Params;
use crate::store::ingest::Ingested;

/// What an import did, for the summary line.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct ImportSummary {
    pub stored: usize,
    pub already_stored: usize,
    pub results: usize,
    pub regressions: usize,
    pub failed: Vec<(PathBuf, String)>,
    pub elapsed: Duration,
}

impl ImportSummary {
    /// One verdict line, e.g. `imported 3 runs (42 results), 1 already stored, 0 failed; 2 new regressions in 0.41 s`.
    pub fn line(&self) -> String {
        format!(
            "imported {} run{} ({} results), {} already stored, {} failed; {} new regression{} in {:.2} s",
            self.stored,
            if self.stored == 1 { "" } else { "s" },
            self.results,
            self.already_stored,
            self.failed.len(),
            self.regressions,
            if self.regressions == 1 { "" } else { "s" },
            self.elapsed.as_secs_f64()
        )
    }
}

/// Run folders under `root`, in name order (run ids sort by time).
pub fn find_run_folders(root: &Path) -> std::io::Result<Vec<PathBuf>> {
    if root.join("run.json").is_file() {
        return Ok(vec![root.to_path_buf()]);
    }
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(root)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join("run.json").is_file())
        .collect();
    dirs.sort();
    Ok(dirs)
}

/// Imports every run folder under `root`. A folder that fails is reported and skipped; the others
/// are still stored.
pub fn import(pool: &Pool, root: &Path, params: &Params) -> anyhow::Result<ImportSummary> {
    let start = Instant::now();
    let folders = find_run_folders(root)
        .map_err(|e| anyhow::anyhow!("cannot read {}: {e}", root.display()))?;
    if folders.is_empty() {
        anyhow::bail!(
            "{} holds no run folder (a folder with run.json, or folders of them)",
            root.display()
        );
    }
    let mut summary = ImportSummary::default();
    let mut conn = pool.get()?;
    for folder in folders {
        let outcome = RunBundle::read_folder(&folder)
            .map_err(anyhow::Error::from)
            .and_then(|b| {
                crate::regressions::ingest_and_detect(&mut *conn, &b, params)
                    .map_err(anyhow::Error::from)
            });
        match outcome {
            Ok((Ingested::Stored { results, .. }, changes)) => {
                summary.stored += 1;
                summary.results += results;
                summary.regressions += changes.detected;
            }
            Ok((Ingested::AlreadyStored { .. }, _)) => summary.already_stored += 1,
            Err(e) => summary.failed.push((folder, format!("{e:#}"))),
        }
    }
    summary.elapsed = start.elapsed();
    Ok(summary)
}
