//! What the pages show, read from the store: one function per view, each returning a plain
//! serialisable struct that is also the JSON API's response. Not for: rendering (see
//! [`crate::server`]) or statistics (see [`crate::detect`]).

use serde::Serialize;
use tessera_results::stats::frame_samples;
use tessera_results::{RunInfo, ScenarioResult, Status};

pub(crate) use super::run_pk;
use super::series::{self, series_key, SERIES_COLUMNS};
pub use super::series::{SeriesKey, SeriesLink};
use super::StoreError;
use crate::db::{Connection, Row, Value};

/// One run in lists.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct RunRow {
    pub run_id: String,
    pub commit: Option<String>,
    pub dirty: bool,
    pub started_at: String,
    pub status: String,
    pub harness_version: String,
    pub adapter_id: i64,
    pub adapter: String,
    pub backend: String,
    pub driver: String,
    pub driver_info: String,
    pub ok: i64,
    pub skipped: i64,
    pub failed: i64,
    /// Suite and branch (`None` when the run did not record them).
    pub suite: Option<String>,
    pub branch: Option<String>,
}

pub(crate) const RUN_COLUMNS: &str =
    "r.run_id, r.commit_sha, r.dirty, r.started_at, r.status, r.harness_version, r.adapter_id,
    a.name, a.backend, r.driver, r.driver_info, r.n_ok, r.n_skipped, r.n_failed, r.suite, r.branch";

pub(crate) fn run_row(r: &Row) -> Result<RunRow, StoreError> {
    Ok(RunRow {
        run_id: r.string(0)?,
        commit: r.opt_string(1)?,
        dirty: r.bool(2)?,
        started_at: r.string(3)?,
        status: r.string(4)?,
        harness_version: r.string(5)?,
        adapter_id: r.i64(6)?,
        adapter: r.string(7)?,
        backend: r.string(8)?,
        driver: r.string(9)?,
        driver_info: r.string(10)?,
        ok: r.i64(11)?,
        skipped: r.i64(12)?,
        failed: r.i64(13)?,
        suite: r.opt_string(14)?,
        branch: r.opt_string(15)?,
    })
}

/// The newest runs first, optionally on one adapter.
pub fn runs(
    conn: &mut dyn Connection,
    adapter: Option<i64>,
    limit: i64,
) -> Result<Vec<RunRow>, StoreError> {
    let rows = match adapter {
        Some(a) => conn.query(
            &format!(
                "SELECT {RUN_COLUMNS} FROM runs r JOIN adapters a ON a.id = r.adapter_id
                 WHERE r.adapter_id = $1 ORDER BY r.started_at DESC, r.id DESC LIMIT $2"
            ),
            &[Value::Int(a), Value::Int(limit)],
        )?,
        None => conn.query(
            &format!(
                "SELECT {RUN_COLUMNS} FROM runs r JOIN adapters a ON a.id = r.adapter_id
                 ORDER BY r.started_at DESC, r.id DESC LIMIT $1"
            ),
            &[Value::Int(limit)],
        )?,
    };
    rows.iter().map(run_row).collect()
}

/// An adapter as stored (GPU without driver: the driver is part of each run's environment).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct AdapterRow {
    pub id: i64,
    pub name: String,
    pub backend: String,
    pub device_type: String,
    pub runs: i64,
}

pub fn adapters(conn: &mut dyn Connection) -> Result<Vec<AdapterRow>, StoreError> {
    conn.query(
        "SELECT a.id, a.name, a.backend, a.device_type, (SELECT COUNT(*) FROM runs r WHERE r.adapter_id = a.id)
         FROM adapters a ORDER BY a.name, a.backend",
        &[],
    )?
    .iter()
    .map(|r| {
        Ok(AdapterRow {
            id: r.i64(0)?,
            name: r.string(1)?,
            backend: r.string(2)?,
            device_type: r.string(3)?,
            runs: r.i64(4)?,
        })
    })
    .collect()
}

/// An image stored for a result.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ImageRow {
    pub scenario: String,
    pub variant: String,
    pub frame: i64,
    pub kind: String,
    pub digest: String,
}

/// One run with its records.
#[derive(Clone, Debug, Serialize)]
pub struct RunDetail {
    pub run: RunRow,
    pub info: RunInfo,
    pub scenarios: Vec<ScenarioResult>,
    pub images: Vec<ImageRow>,
    pub series: Vec<SeriesLink>,
}

pub fn run(conn: &mut dyn Connection, run_id: &str) -> Result<RunDetail, StoreError> {
    let RunHead { pk, run, info } = run_head(conn, run_id)?;
    let scenarios = scenarios_of(conn, pk)?;
    let images = images_of(conn, pk, None)?;
    let series = super::series::links_of_run(conn, pk)?;
    Ok(RunDetail {
        run,
        info,
        scenarios,
        images,
        series,
    })
}

/// A run's record and every scenario's record, without its images or series links: what a
/// comparison of two runs reads (a nightly run's 1,700 results have some 15,000 series links
/// and thousands of image rows that a comparison never shows).
pub fn run_records(
    conn: &mut dyn Connection,
    run_id: &str,
) -> Result<(RunHead, Vec<ScenarioResult>), StoreError> {
    let head = run_head(conn, run_id)?;
    let scenarios = scenarios_of(conn, head.pk)?;
    Ok((head, scenarios))
}

/// One scenario of a run as [`run`] reads the whole run (its record, images and series links),
/// with the names of all the run's scenarios; no other record is decoded. `None` when the run
/// has no such scenario.
pub fn run_scenario(
    conn: &mut dyn Connection,
    run_id: &str,
    scenario: &str,
) -> Result<Option<(RunDetail, Vec<String>)>, StoreError> {
    let RunHead { pk, run, info } = run_head(conn, run_id)?;
    let names = conn
        .query(
            "SELECT scenario FROM scenario_results WHERE run_pk = $1 ORDER BY scenario",
            &[Value::Int(pk)],
        )?
        .iter()
        .map(|r| r.string(0).map_err(StoreError::from))
        .collect::<Result<Vec<String>, _>>()?;
    if !names.iter().any(|n| n == scenario) {
        return Ok(None);
    }
    let detail = RunDetail {
        run,
        info,
        scenarios: vec![scenario_result(conn, run_id, scenario)?],
        images: images_of(conn, pk, Some(scenario))?,
        series: super::series::links_of_run_in(conn, pk, Some(scenario))?,
    };
    Ok(Some((detail, names)))
}

/// A run's row and record, without its scenarios: what a page says above them.
pub struct RunHead {
    pub pk: i64,
    pub run: RunRow,
    pub info: RunInfo,
}

pub fn run_head(conn: &mut dyn Connection, run_id: &str) -> Result<RunHead, StoreError> {
    let pk = run_pk(conn, run_id)?;
    let row = conn.query(
        &format!(
            "SELECT {RUN_COLUMNS}, r.run_json FROM runs r JOIN adapters a ON a.id = r.adapter_id WHERE r.id = $1"
        ),
        &[Value::Int(pk)],
    )?;
    let run = run_row(&row[0])?;
    let info: RunInfo =
        serde_json::from_str(row[0].str(16)?).map_err(|e| StoreError::Corrupt(e.to_string()))?;
    Ok(RunHead { pk, run, info })
}

/// What a run's summary reads of one variant: its status and its per-frame GPU times (the
/// samples `tessera compare` tests; `None` without timestamps).
#[derive(Clone, Debug, PartialEq)]
pub struct VariantLine {
    pub variant: String,
    pub status: Status,
    pub frames: Option<Vec<f64>>,
}

/// One scenario's variants as summary lines, in the run's order.
#[derive(Clone, Debug, PartialEq)]
pub struct ScenarioLines {
    pub scenario: String,
    pub variants: Vec<VariantLine>,
}

impl ScenarioLines {
    pub fn of(s: &ScenarioResult) -> Self {
        ScenarioLines {
            scenario: s.scenario.clone(),
            variants: s
                .results
                .iter()
                .map(|v| VariantLine {
                    variant: v.variant.clone(),
                    status: v.status.clone(),
                    frames: frame_samples(v),
                })
                .collect(),
        }
    }
}

/// Run `pk`'s scenarios as summary lines, by scenario name, read from its `results` rows: no
/// scenario record is decoded, so a run of 1,700 results reads in milliseconds. A run stored
/// before the rows kept their frame times (`frame_ms` NULL) is read from its records.
pub fn lines(conn: &mut dyn Connection, pk: i64) -> Result<Vec<ScenarioLines>, StoreError> {
    let rows = conn.query(
        "SELECT scenario, variant, status, reason, frame_ms FROM results WHERE run_pk = $1
         ORDER BY scenario, id",
        &[Value::Int(pk)],
    )?;
    let mut out: Vec<ScenarioLines> = Vec::new();
    for r in &rows {
        let Some(frames) = r.opt_blob(4)? else {
            return Ok(scenarios_of(conn, pk)?
                .iter()
                .map(ScenarioLines::of)
                .collect());
        };
        let frames = super::records::decode_frames(frames)?;
        let reason = r.opt_string(3)?.unwrap_or_default();
        let status = match r.str(2)? {
            "ok" => Status::Ok,
            "skipped" => Status::Skipped { reason },
            "failed" => Status::Failed { error: reason },
            other => return Err(StoreError::Corrupt(format!("result status {other:?}"))),
        };
        let line = VariantLine {
            variant: r.string(1)?,
            status,
            frames: (!frames.is_empty()).then_some(frames),
        };
        let scenario = r.str(0)?;
        match out.last_mut() {
            Some(s) if s.scenario == scenario => s.variants.push(line),
            _ => out.push(ScenarioLines {
                scenario: scenario.to_string(),
                variants: vec![line],
            }),
        }
    }
    Ok(out)
}

pub(crate) fn scenarios_of(
    conn: &mut dyn Connection,
    pk: i64,
) -> Result<Vec<ScenarioResult>, StoreError> {
    super::records::decode_all(&record_rows(conn, pk)?, 0)
}

/// The stored records of run `pk` ([`super::records::COLUMNS`]), in scenario order, not decoded.
pub(crate) fn record_rows(conn: &mut dyn Connection, pk: i64) -> Result<Vec<Row>, StoreError> {
    Ok(conn.query(
        &format!(
            "SELECT {} FROM scenario_results WHERE run_pk = $1 ORDER BY scenario",
            super::records::COLUMNS
        ),
        &[Value::Int(pk)],
    )?)
}

fn images_of(
    conn: &mut dyn Connection,
    pk: i64,
    scenario: Option<&str>,
) -> Result<Vec<ImageRow>, StoreError> {
    let rows = match scenario {
        Some(s) => conn.query(
            "SELECT scenario, variant, frame, kind, digest FROM images WHERE run_pk = $1 AND scenario = $2
             ORDER BY scenario, variant, frame, kind",
            &[Value::Int(pk), s.into()],
        )?,
        None => conn.query(
            "SELECT scenario, variant, frame, kind, digest FROM images WHERE run_pk = $1
             ORDER BY scenario, variant, frame, kind",
            &[Value::Int(pk)],
        )?,
    };
    rows.iter()
        .map(|r| {
            Ok(ImageRow {
                scenario: r.string(0)?,
                variant: r.string(1)?,
                frame: r.i64(2)?,
                kind: r.string(3)?,
                digest: r.string(4)?,
            })
        })
        .collect()
}

/// Images of one scenario of a run (the image viewer shows one variant with the reference).
pub fn run_images(
    conn: &mut dyn Connection,
    run_id: &str,
    scenario: &str,
) -> Result<Vec<ImageRow>, StoreError> {
    let pk = run_pk(conn, run_id)?;
    images_of(conn, pk, Some(scenario))
}

/// The bytes of a stored image by digest.
pub fn blob(conn: &mut dyn Connection, digest: &str) -> Result<Vec<u8>, StoreError> {
    let row = conn
        .query_opt(
            "SELECT bytes FROM blobs WHERE digest = $1",
            &[digest.into()],
        )?
        .ok_or_else(|| StoreError::NotFound(format!("image {digest}")))?;
    Ok(row.blob(0)?.to_vec())
}

/// Series matching a filter (each part optional), at most `limit`.
pub fn find_series(
    conn: &mut dyn Connection,
    scenario: Option<&str>,
    variant: Option<&str>,
    adapter: Option<i64>,
    measure: Option<&str>,
    limit: i64,
) -> Result<Vec<SeriesKey>, StoreError> {
    // Optional filters as bound parameters: `CAST($n AS type) IS NULL OR column = $n` (the cast
    // tells PostgreSQL the parameter's type).
    conn.query(
        &format!(
            "SELECT {SERIES_COLUMNS} FROM series s JOIN adapters a ON a.id = s.adapter_id
             WHERE (CAST($1 AS TEXT) IS NULL OR s.scenario = $1) AND (CAST($2 AS TEXT) IS NULL OR s.variant = $2)
               AND (CAST($3 AS BIGINT) IS NULL OR s.adapter_id = $3) AND (CAST($4 AS TEXT) IS NULL OR s.measure = $4)
             ORDER BY s.scenario, s.variant, a.name, s.measure LIMIT $5"
        ),
        &[
            scenario.map(str::to_string).into(),
            variant.map(str::to_string).into(),
            adapter.into(),
            measure.map(str::to_string).into(),
            Value::Int(limit),
        ],
    )?
    .iter()
    .map(series_key)
    .collect()
}

/// One point of a series as shown.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct PointRow {
    pub run_id: String,
    pub commit: Option<String>,
    pub started_at: String,
    pub environment: String,
    pub value: f64,
}

/// A series with its points, environment segments and stored regressions.
#[derive(Clone, Debug, Serialize)]
pub struct SeriesDetail {
    pub series: SeriesKey,
    pub points: Vec<PointRow>,
    /// Indices into `points` where the environment (driver, harness version) changes.
    pub segment_starts: Vec<usize>,
    pub regressions: Vec<RegressionRow>,
}

pub fn series(conn: &mut dyn Connection, id: i64) -> Result<SeriesDetail, StoreError> {
    let series = series::key(conn, id)?;
    let pts = series::points(conn, id)?;
    let mut segment_starts = Vec::new();
    for i in 0..pts.len() {
        if i == 0 || pts[i].environment != pts[i - 1].environment {
            segment_starts.push(i);
        }
    }
    let points = pts
        .into_iter()
        .map(|p| PointRow {
            run_id: p.run_id,
            commit: p.commit,
            started_at: p.started_at,
            environment: p.environment,
            value: p.value,
        })
        .collect();
    let regressions = regressions(conn, None, Some(id), 1000)?;
    Ok(SeriesDetail {
        series,
        points,
        segment_starts,
        regressions,
    })
}

/// A stored change as the series page and `GET /api/regressions` show it: the alert row, read by
/// its one owner.
pub type RegressionRow = super::alerts::Alert;

/// Stored changes that the data still supports (pending or confirmed), newest first, optionally
/// of one triage state or one series.
pub fn regressions(
    conn: &mut dyn Connection,
    state: Option<&str>,
    series: Option<i64>,
    limit: i64,
) -> Result<Vec<RegressionRow>, StoreError> {
    let state: Option<super::alerts::TriageState> = state.map(str::parse).transpose()?;
    let mut rows = super::alerts::read(
        conn,
        super::alerts::Select {
            series,
            live_only: true,
            limit: if state.is_some() { i64::MAX } else { limit },
            ..Default::default()
        },
    )?;
    if let Some(st) = state {
        rows.retain(|r| r.state == st);
    }
    rows.truncate(limit.max(0) as usize);
    Ok(rows)
}

/// The newest run on an adapter that has `scenario` (any scenario when `None`), and the one before.
pub fn latest_runs_with(
    conn: &mut dyn Connection,
    adapter: i64,
    scenario: Option<&str>,
    limit: i64,
) -> Result<Vec<String>, StoreError> {
    conn.query(
        "SELECT r.run_id FROM runs r WHERE r.adapter_id = $1
           AND (CAST($2 AS TEXT) IS NULL OR EXISTS (SELECT 1 FROM scenario_results s WHERE s.run_pk = r.id AND s.scenario = $2))
         ORDER BY r.started_at DESC, r.id DESC LIMIT $3",
        &[Value::Int(adapter), scenario.map(str::to_string).into(), Value::Int(limit)],
    )?
    .iter()
    .map(|r| r.string(0).map_err(Into::into))
    .collect()
}

/// One scenario's record in a run.
pub fn scenario_result(
    conn: &mut dyn Connection,
    run_id: &str,
    scenario: &str,
) -> Result<ScenarioResult, StoreError> {
    let pk = run_pk(conn, run_id)?;
    let row = conn
        .query_opt(
            &format!(
                "SELECT {} FROM scenario_results WHERE run_pk = $1 AND scenario = $2",
                super::records::COLUMNS
            ),
            &[Value::Int(pk), scenario.into()],
        )?
        .ok_or_else(|| StoreError::NotFound(format!("scenario {scenario} in run {run_id}")))?;
    super::records::decode(&row, 0)
}

/// Every scenario record of a run (the adapter comparison reads two runs).
pub fn run_scenarios(
    conn: &mut dyn Connection,
    run_id: &str,
) -> Result<Vec<ScenarioResult>, StoreError> {
    let pk = run_pk(conn, run_id)?;
    scenarios_of(conn, pk)
}

/// Scenario names on an adapter, for pickers.
pub fn scenarios_on(
    conn: &mut dyn Connection,
    adapter: Option<i64>,
) -> Result<Vec<String>, StoreError> {
    conn.query(
        "SELECT DISTINCT scenario FROM series WHERE (CAST($1 AS BIGINT) IS NULL OR adapter_id = $1) ORDER BY scenario",
        &[adapter.into()],
    )?
    .iter()
    .map(|r| r.string(0).map_err(Into::into))
    .collect()
}
