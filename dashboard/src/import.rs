//! `tessera-dashboard import`: finds run folders (the folder itself when it holds `run.json`,
//! else the folders below it that do, down to a folder of folders of runs) and stores each as an upload does: the run and detection on the
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
    /// What a stored (or already stored) run folder should tell the one importing it
    /// ([`RunBundle::warnings`]: a run without a commit).
    pub warnings: Vec<(PathBuf, String)>,
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

/// Folder levels searched below the root: a folder of folders (per adapter, per night) of runs.
pub const MAX_DEPTH: usize = 4;

/// Run folders under `root`: `root` itself when it holds `run.json`, else every folder with one
/// down to [`MAX_DEPTH`] levels below it (not inside a run folder, not hidden folders, not
/// through links), in run-folder name order (run ids sort by time).
pub fn find_run_folders(root: &Path) -> std::io::Result<Vec<PathBuf>> {
    if root.join("run.json").is_file() {
        return Ok(vec![root.to_path_buf()]);
    }
    let mut dirs = Vec::new();
    collect_runs(root, 1, &mut dirs)?;
    dirs.sort_by(|a, b| a.file_name().cmp(&b.file_name()).then_with(|| a.cmp(b)));
    Ok(dirs)
}

fn collect_runs(dir: &Path, depth: usize, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
    for entry in std::fs::read_dir(dir)? {
        let entry = entry?;
        let hidden = entry.file_name().to_string_lossy().starts_with('.');
        if hidden || !entry.file_type()?.is_dir() {
            continue;
        }
        let path = entry.path();
        if path.join("run.json").is_file() {
            out.push(path);
        } else if depth < MAX_DEPTH {
            collect_runs(&path, depth + 1, out)?;
        }
    }
    Ok(())
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
                let stored = crate::regressions::ingest_and_detect(&mut *conn, &b, params)
                    .map_err(anyhow::Error::from)?;
                summary
                    .warnings
                    .extend(b.warnings().into_iter().map(|w| (folder.clone(), w)));
                Ok(stored)
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

#[cfg(test)]
mod tests {
    #[test]
    fn run_folders_are_found_in_folders_of_folders() {
        let root = tempfile::tempdir().unwrap();
        let run = |rel: &str| {
            let p = root.path().join(rel);
            std::fs::create_dir_all(&p).unwrap();
            std::fs::write(p.join("run.json"), "{}").unwrap();
        };
        run("lavapipe/20261202T000000Z-b");
        run("h200/nightly/20261201T000000Z-a");
        run("20261203T000000Z-c");
        // Not runs: a folder inside a run, a hidden folder, a folder too deep.
        run("20261203T000000Z-c/images/inner");
        run(".cache/20261204T000000Z-d");
        run("a/b/c/d/20261205T000000Z-e");
        std::fs::create_dir_all(root.path().join("empty/also-empty")).unwrap();
        let found: Vec<String> = super::find_run_folders(root.path())
            .unwrap()
            .iter()
            .map(|p| p.strip_prefix(root.path()).unwrap().display().to_string())
            .collect();
        assert_eq!(
            found,
            [
                "h200/nightly/20261201T000000Z-a",
                "lavapipe/20261202T000000Z-b",
                "20261203T000000Z-c"
            ]
        );
    }
}
