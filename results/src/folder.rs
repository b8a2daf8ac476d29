//! The one run-folder reader: `run.json`, `scenarios/*.json` and the images they list, as
//! `tessera run` writes them (`results/README.md`). `tessera compare`, `tessera upload` and the
//! dashboard's import and `POST /api/runs` all read through here, so they accept and refuse the
//! same folders and upgrade older schema versions the same way.
//!
//! Reading upgrades: a version-1 record is rewritten in memory to the current version
//! ([`upgrade`]) before it is typed, so every caller sees one format. Not for: writing runs (the
//! harness's `run/output.rs`) or checking a bundle's consistency (the dashboard's `bundle.rs`).

use std::collections::BTreeMap;
use std::path::{Component, Path, PathBuf};

use crate::measure::Measure;
use crate::{layout, RunInfo, ScenarioResult, OLDEST_SCHEMA_VERSION, SCHEMA_VERSION};

/// A run folder, or one of its records, that could not be read. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
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
    #[error(transparent)]
    Schema(#[from] SchemaError),
}

/// A record whose `schema_version` this reader does not know.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
#[error("{what} has schema_version {found}; this reader knows versions {OLDEST_SCHEMA_VERSION} to {SCHEMA_VERSION}: read it with the newer tessera or tessera-dashboard that wrote it")]
pub struct SchemaError {
    /// The file, or the record's place in an upload.
    pub what: String,
    /// The version found, as written (`none` when absent).
    pub found: String,
}

/// Brings one record (`run.json` or a scenario result, as JSON) to [`SCHEMA_VERSION`]:
///
/// - version 1 → 2: a metric's `series` is now `frame_stats`; a gate outcome's `measure` is the
///   measure's canonical name (`non-finite` → `non_finite_values`, `spread-non-finite` →
///   `spread_non_finite`, `unrecovered-cuts` → `unrecovered_cuts`). `run.json` only changes its
///   version.
/// - version 2 → 3: only the version changes; version 3 added optional fields (a result's
///   `frame_digests` and `expectation`, a scenario's `reference_digests`) that version 2 lacks.
///
/// Anything else is refused with the version found, before the record is parsed, so that a newer
/// format is named as such rather than as a parse error.
pub fn upgrade(what: &str, mut value: serde_json::Value) -> Result<serde_json::Value, SchemaError> {
    let version = value.get("schema_version").and_then(|v| v.as_u64());
    let known =
        version.filter(|v| (OLDEST_SCHEMA_VERSION as u64..=SCHEMA_VERSION as u64).contains(v));
    let Some(version) = known else {
        return Err(SchemaError {
            what: what.to_string(),
            found: value
                .get("schema_version")
                .map_or_else(|| "none".to_string(), |v| v.to_string()),
        });
    };
    if version == 1 {
        v1_to_v2(&mut value);
    }
    if version <= 2 {
        value["schema_version"] = 3.into();
    }
    Ok(value)
}

fn v1_to_v2(value: &mut serde_json::Value) {
    value["schema_version"] = 2.into();
    let Some(results) = value.get_mut("results").and_then(|r| r.as_array_mut()) else {
        return;
    };
    for r in results {
        if let Some(metrics) = r.get_mut("metrics").and_then(|m| m.as_array_mut()) {
            for m in metrics.iter_mut().filter_map(|m| m.as_object_mut()) {
                if let Some(s) = m.remove("series") {
                    m.insert("frame_stats".into(), s);
                }
            }
        }
        if let Some(gates) = r.get_mut("gates").and_then(|g| g.as_array_mut()) {
            for g in gates {
                let canonical = g["measure"]
                    .as_str()
                    .and_then(Measure::from_name)
                    .map(Measure::name);
                if let Some(name) = canonical {
                    g["measure"] = name.into();
                }
            }
        }
    }
}

/// Upgrades and types one record.
pub fn parse<T: serde::de::DeserializeOwned>(
    path: &Path,
    value: serde_json::Value,
) -> Result<T, ReadError> {
    let value = upgrade(&path.display().to_string(), value)?;
    serde_json::from_value(value).map_err(|source| ReadError::Invalid {
        path: path.to_path_buf(),
        source,
    })
}

/// A run folder's records as JSON, upgraded to [`SCHEMA_VERSION`], scenarios in file-name order.
/// What an upload sends: the records as written, only brought to the current version.
#[derive(Debug, Clone)]
pub struct RawRun {
    pub dir: PathBuf,
    pub run: serde_json::Value,
    pub scenarios: Vec<serde_json::Value>,
}

/// A run folder's records, typed.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    pub info: RunInfo,
    /// In the order `run.json` lists their files where it can, otherwise by name.
    pub scenarios: Vec<ScenarioResult>,
}

fn read_json(path: &Path) -> Result<serde_json::Value, ReadError> {
    let bytes = std::fs::read(path).map_err(|source| ReadError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let value: serde_json::Value =
        serde_json::from_slice(&bytes).map_err(|source| ReadError::Invalid {
            path: path.to_path_buf(),
            source,
        })?;
    Ok(upgrade(&path.display().to_string(), value)?)
}

/// Reads `dir/run.json` and every `dir/scenarios/*.json` (a run interrupted before its first
/// scenario has none), upgrading each.
pub fn read_raw(dir: &Path) -> Result<RawRun, ReadError> {
    let run_json = dir.join(layout::RUN_JSON);
    if !run_json.is_file() {
        return Err(ReadError::NotARun(dir.to_path_buf()));
    }
    let run = read_json(&run_json)?;
    let files = layout::scenario_files(dir).map_err(|source| ReadError::Io {
        path: dir.join(layout::SCENARIOS_DIR),
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

impl RawRun {
    /// Types the records; scenarios in the order `run.json` lists their files.
    pub fn typed(self) -> Result<Run, ReadError> {
        let dir = self.dir;
        let info: RunInfo = typed(dir.join(layout::RUN_JSON), self.run)?;
        let mut scenarios: Vec<ScenarioResult> = Vec::new();
        for v in self.scenarios {
            let name = v["scenario"].as_str().unwrap_or("?").to_string();
            scenarios.push(typed(
                dir.join(layout::SCENARIOS_DIR).join(format!("{name}.json")),
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

    /// The image paths the results list, each once, in order; paths that would leave the run
    /// folder are left out (an upload checker names them).
    pub fn listed_images(&self) -> Vec<&str> {
        let mut out: Vec<&str> = Vec::new();
        for s in &self.scenarios {
            let paths = s["results"].as_array().into_iter().flatten().flat_map(|v| {
                v["images"]
                    .as_array()
                    .into_iter()
                    .flatten()
                    .filter_map(|i| i["path"].as_str())
            });
            for p in paths {
                if safe_relative_path(p) && !out.contains(&p) {
                    out.push(p);
                }
            }
        }
        out
    }

    /// The bytes of every listed image the folder holds, by path; a listed image that is missing
    /// is left out, not an error (runs may be saved without them).
    pub fn read_images(&self) -> Result<BTreeMap<String, Vec<u8>>, ReadError> {
        let mut images = BTreeMap::new();
        for path in self.listed_images() {
            let full = self.dir.join(path);
            if full.is_file() {
                let bytes = std::fs::read(&full).map_err(|source| ReadError::Io {
                    path: full.clone(),
                    source,
                })?;
                images.insert(path.to_string(), bytes);
            }
        }
        Ok(images)
    }
}

fn typed<T: serde::de::DeserializeOwned>(
    path: PathBuf,
    v: serde_json::Value,
) -> Result<T, ReadError> {
    serde_json::from_value(v).map_err(|source| ReadError::Invalid { path, source })
}

/// Reads and types a run folder.
pub fn read(dir: &Path) -> Result<Run, ReadError> {
    read_raw(dir)?.typed()
}

/// An image path must stay inside the run folder: relative, no `..`, no root, no backslash.
pub fn safe_relative_path(path: &str) -> bool {
    !path.is_empty()
        && !path.contains('\\')
        && Path::new(path)
            .components()
            .all(|c| matches!(c, Component::Normal(_)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_cannot_leave_the_run_folder() {
        assert!(safe_relative_path("images/tiny/native-f002.png"));
        for bad in ["../x.png", "/etc/passwd", "images/../../x", "", "a\\..\\b"] {
            assert!(!safe_relative_path(bad), "{bad}");
        }
    }

    #[test]
    fn unknown_versions_are_named_before_parsing() {
        for (v, found) in [
            (serde_json::json!({"schema_version": 99}), "99"),
            (serde_json::json!({"schema_version": 0}), "0"),
            (serde_json::json!({"schema_version": "2"}), "\"2\""),
            (serde_json::json!({}), "none"),
        ] {
            let e = upgrade("run.json", v).unwrap_err();
            assert_eq!(e.found, found);
            assert_eq!(
                e.to_string(),
                format!("run.json has schema_version {found}; this reader knows versions 1 to 3: read it with the newer tessera or tessera-dashboard that wrote it")
            );
        }
    }

    #[test]
    fn version_1_gates_and_frame_stats_are_renamed() {
        let v1 = serde_json::json!({"schema_version": 1, "results": [{
            "metrics": [{"name": "psnr", "series": {"mean": 1.0}}],
            "gates": [{"measure": "non-finite"}, {"measure": "psnr"}, {"measure": "unknown"}],
        }]});
        let v3 = upgrade("x", v1).unwrap();
        assert_eq!(
            v3,
            serde_json::json!({"schema_version": 3, "results": [{
                "metrics": [{"name": "psnr", "frame_stats": {"mean": 1.0}}],
                "gates": [{"measure": "non_finite_values"}, {"measure": "psnr"}, {"measure": "unknown"}],
            }]})
        );
        // The current version passes through unchanged; version 2 only changes its number.
        assert_eq!(upgrade("x", v3.clone()).unwrap(), v3);
        let v2 = serde_json::json!({"schema_version": 2, "results": []});
        assert_eq!(
            upgrade("x", v2).unwrap(),
            serde_json::json!({"schema_version": 3, "results": []})
        );
    }
}
