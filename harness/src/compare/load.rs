//! Reading a run folder back: `run.json` and `scenarios/*.json`, schema version checked first.
//!
//! Used by `tessera compare` (typed records) and `tessera upload` (the JSON as written, so the
//! upload carries exactly what is on disk). Not for: writing runs (see [`crate::run::output`]).

use std::path::{Path, PathBuf};

use tessera_results::{RunInfo, ScenarioResult, SCHEMA_VERSION};

/// A run folder that could not be read. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    #[error("{0}: no such run folder (expected <run-id>/run.json as written by `tessera run`)")]
    NotARun(PathBuf),
    #[error("cannot read {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path} is not a valid result record: {source}")]
    Invalid {
        path: PathBuf,
        #[source]
        source: serde_json::Error,
    },
    #[error("{path} has schema_version {found}; this tessera reads version {SCHEMA_VERSION} only: use the tessera that wrote it")]
    UnknownSchema { path: PathBuf, found: String },
}

/// A run folder's records as JSON, schema versions checked, scenarios in file-name order.
#[derive(Debug, Clone)]
pub struct RawRun {
    pub dir: PathBuf,
    pub run: serde_json::Value,
    pub scenarios: Vec<serde_json::Value>,
}

/// A run folder's records, typed.
#[derive(Debug, Clone)]
pub struct Run {
    pub info: RunInfo,
    pub scenarios: Vec<ScenarioResult>,
}

fn read_json(path: &Path) -> Result<serde_json::Value, LoadError> {
    let bytes = std::fs::read(path).map_err(|source| LoadError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let value: serde_json::Value =
        serde_json::from_slice(&bytes).map_err(|source| LoadError::Invalid {
            path: path.to_path_buf(),
            source,
        })?;
    match value.get("schema_version") {
        Some(v) if v.as_u64() == Some(u64::from(SCHEMA_VERSION)) => Ok(value),
        other => Err(LoadError::UnknownSchema {
            path: path.to_path_buf(),
            found: other.map_or_else(|| "none".to_string(), |v| v.to_string()),
        }),
    }
}

/// Reads `dir/run.json` and every `dir/scenarios/*.json` (a run interrupted before its first
/// scenario has none).
pub fn read_raw(dir: &Path) -> Result<RawRun, LoadError> {
    let run_json = dir.join("run.json");
    if !run_json.is_file() {
        return Err(LoadError::NotARun(dir.to_path_buf()));
    }
    let run = read_json(&run_json)?;
    let files = tessera_results::layout::scenario_files(dir).map_err(|source| LoadError::Io {
        path: dir.join(tessera_results::layout::SCENARIOS_DIR),
        source,
    })?;
    let scenarios = files
        .iter()
        .map(|p| read_json(p))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(RawRun {
        dir: dir.to_path_buf(),
        run,
        scenarios,
    })
}

fn typed<T: serde::de::DeserializeOwned>(
    path: PathBuf,
    v: serde_json::Value,
) -> Result<T, LoadError> {
    serde_json::from_value(v).map_err(|source| LoadError::Invalid { path, source })
}

/// Reads and types a run folder; scenarios in the order `run.json` lists their files where it
/// can, otherwise by name.
pub fn load_run(dir: &Path) -> Result<Run, LoadError> {
    let raw = read_raw(dir)?;
    let info: RunInfo = typed(dir.join("run.json"), raw.run)?;
    let mut scenarios: Vec<ScenarioResult> = Vec::new();
    for v in raw.scenarios {
        let name = v["scenario"].as_str().unwrap_or("?").to_string();
        scenarios.push(typed(
            dir.join("scenarios").join(format!("{name}.json")),
            v,
        )?);
    }
    let order = |s: &ScenarioResult| {
        info.scenarios
            .iter()
            .position(|f| *f == s.file)
            .unwrap_or(usize::MAX)
    };
    scenarios.sort_by_key(|s| order(s));
    Ok(Run { info, scenarios })
}
