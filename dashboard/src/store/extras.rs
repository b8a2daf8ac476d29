//! What a stored run carries beyond the core tables, written in the run's ingest transaction:
//! its suite and branch (`runs.suite`, `runs.branch`) and the p5-p95 band of each timed point
//! (`point_bands`), which the series charts draw around the median.
//!
//! Not for: the points themselves (see [`super::ingest`]) or reading (see [`super::read`]).

use std::path::Path;

use tessera_results::{RunInfo, Status, Summary};

use super::StoreError;
use crate::bundle::RunBundle;
use crate::db::{Connection, Value};

/// The run's suite: as recorded by the harness, or for runs written before it was recorded, the
/// parent folder names of its scenario files (`scenarios/smoke/basic.toml` gives `smoke`), in
/// order without repeats, joined by `+`.
pub fn suite_of(run: &RunInfo) -> Option<String> {
    if let Some(s) = run.suite.as_ref().filter(|s| !s.is_empty()) {
        return Some(s.clone());
    }
    let mut names: Vec<String> = Vec::new();
    for f in &run.scenarios {
        let name = Path::new(f)
            .parent()
            .and_then(Path::file_name)
            .map(|n| n.to_string_lossy().into_owned());
        if let Some(n) = name {
            if !names.contains(&n) {
                names.push(n);
            }
        }
    }
    (!names.is_empty()).then(|| names.join("+"))
}

/// The bands of one result: (measure, p5, p95) for every timed measure with a summary.
fn bands(v: &tessera_results::VariantResult) -> Vec<(String, Summary)> {
    if v.status != Status::Ok {
        return Vec::new();
    }
    let mut out = Vec::new();
    if let Some(g) = v.gpu_frame_ms {
        out.push(("gpu_ms.median".to_string(), g));
    }
    out.push(("cpu_ms.median".to_string(), v.cpu_frame_ms));
    for p in &v.passes {
        if let Some(g) = p.gpu_ms {
            out.push((format!("pass.{}.gpu_ms.median", p.name), g));
        }
    }
    out
}

/// Stores the suite, branch and bands of the run stored as `run_pk` on `adapter`; its series and
/// points must already be stored.
pub fn store(
    conn: &mut dyn Connection,
    run_pk: i64,
    adapter: i64,
    bundle: &RunBundle,
) -> Result<(), StoreError> {
    conn.execute(
        "UPDATE runs SET suite = $1, branch = $2 WHERE id = $3",
        &[
            suite_of(&bundle.run).into(),
            bundle.run.branch.clone().into(),
            Value::Int(run_pk),
        ],
    )?;
    for s in &bundle.scenarios {
        for v in &s.results {
            for (measure, sum) in bands(v) {
                if !(sum.p5.is_finite() && sum.p95.is_finite()) {
                    continue;
                }
                conn.execute(
                    "INSERT INTO point_bands (series_id, run_pk, p5, p95)
                     SELECT id, $1, $2, $3 FROM series
                     WHERE scenario = $4 AND variant = $5 AND adapter_id = $6 AND measure = $7
                     ON CONFLICT DO NOTHING",
                    &[
                        Value::Int(run_pk),
                        Value::Real(sum.p5),
                        Value::Real(sum.p95),
                        s.scenario.as_str().into(),
                        v.variant.as_str().into(),
                        Value::Int(adapter),
                        measure.into(),
                    ],
                )?;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn suite_falls_back_to_scenario_folders() {
        let json = include_str!("../../tests/fixtures/runs/20261122T030520Z-34ab2b4/run.json");
        let mut run: RunInfo = serde_json::from_str(json).unwrap();
        run.suite = None;
        run.scenarios = vec![
            "scenarios/smoke/a.toml".into(),
            "scenarios/smoke/b.toml".into(),
            "scenarios/perf/c.toml".into(),
        ];
        assert_eq!(suite_of(&run).as_deref(), Some("smoke+perf"));
        run.suite = Some("nightly".into());
        assert_eq!(suite_of(&run).as_deref(), Some("nightly"));
        run.scenarios = vec!["x.toml".into()];
        run.suite = None;
        assert_eq!(suite_of(&run), None);
    }
}
