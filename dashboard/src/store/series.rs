//! Series and their points: the one owner of every query over `points` (and the `series` rows
//! they hang on). Ingest writes points through it, detection ([`crate::regressions`]) reads a
//! series' window through it, pages read a series' points, a run's series and the points either
//! side of a run through it, and deleting a run removes its points through it.
//!
//! A point is (series, run, value) with the run's place in commit order (`points.ord`, see
//! [`super::ingest::order_key`]); a series is read in (`ord`, `run_pk`) order.
//!
//! Not for: detection and alerts (see [`crate::regressions`] and [`super::alerts`]), which sit
//! above this module and are never imported by it.

use std::collections::HashMap;

use serde::Serialize;

use super::StoreError;
use crate::db::{Backend, Connection, Row, Value};

/// The measure of the series that carries a variant's untriaged-frame alerts: it has no points,
/// so detection leaves it alone (see [`super::frames`]).
pub const UNTRIAGED_MEASURE: &str = "frames.untriaged";

/// What identifies a series.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct SeriesKey {
    pub id: i64,
    pub scenario: String,
    pub variant: String,
    pub adapter_id: i64,
    pub adapter: String,
    pub measure: String,
    pub higher_is_better: bool,
}

pub(crate) const SERIES_COLUMNS: &str =
    "s.id, s.scenario, s.variant, s.adapter_id, a.name, s.measure, s.higher_is_better";

pub(crate) fn series_key(r: &Row) -> Result<SeriesKey, StoreError> {
    Ok(SeriesKey {
        id: r.i64(0)?,
        scenario: r.string(1)?,
        variant: r.string(2)?,
        adapter_id: r.i64(3)?,
        adapter: r.string(4)?,
        measure: r.string(5)?,
        higher_is_better: r.bool(6)?,
    })
}

/// The key of series `id`.
pub fn key(conn: &mut dyn Connection, id: i64) -> Result<SeriesKey, StoreError> {
    let row = conn
        .query_opt(
            &format!("SELECT {SERIES_COLUMNS} FROM series s JOIN adapters a ON a.id = s.adapter_id WHERE s.id = $1"),
            &[Value::Int(id)],
        )?
        .ok_or_else(|| StoreError::NotFound(format!("series {id}")))?;
    series_key(&row)
}

/// The environment a point was measured in, as pages show it.
fn environment(driver: &str, info: &str, harness: &str) -> String {
    format!("{driver} {info} / harness {harness}")
}

/// One point of a series with what identifies its environment.
#[derive(Clone, Debug)]
pub struct SeriesPoint {
    pub run_pk: i64,
    pub run_id: String,
    pub commit: Option<String>,
    pub started_at: String,
    pub environment: String,
    pub value: f64,
}

/// All points of a series in commit order (commit time, start time, import order): for pages.
pub fn points(conn: &mut dyn Connection, series_id: i64) -> Result<Vec<SeriesPoint>, StoreError> {
    let rows = conn.query(
        "SELECT r.id, r.run_id, r.commit_sha, r.started_at, r.driver, r.driver_info, r.harness_version, p.value
         FROM points p JOIN runs r ON r.id = p.run_pk
         WHERE p.series_id = $1 ORDER BY p.ord, p.run_pk",
        &[Value::Int(series_id)],
    )?;
    rows.iter()
        .map(|r| {
            Ok(SeriesPoint {
                run_pk: r.i64(0)?,
                run_id: r.string(1)?,
                commit: r.opt_string(2)?,
                started_at: r.string(3)?,
                environment: environment(r.str(4)?, r.str(5)?, r.str(6)?),
                value: r.f64(7)?,
            })
        })
        .collect()
}

/// A point with its p5-p95 band (`point_bands`), for the series charts.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct BandPoint {
    pub run_id: String,
    pub commit: Option<String>,
    pub started_at: String,
    pub environment: String,
    pub value: f64,
    pub p5: Option<f64>,
    pub p95: Option<f64>,
}

/// A series' points in run order (start time, then import order), with bands.
pub fn band_points(
    conn: &mut dyn Connection,
    series_id: i64,
) -> Result<Vec<BandPoint>, StoreError> {
    conn.query(
        "SELECT r.run_id, r.commit_sha, r.started_at, r.driver, r.driver_info, r.harness_version, p.value, b.p5, b.p95
         FROM points p JOIN runs r ON r.id = p.run_pk
         LEFT JOIN point_bands b ON b.series_id = p.series_id AND b.run_pk = p.run_pk
         WHERE p.series_id = $1 ORDER BY r.started_at, r.id",
        &[Value::Int(series_id)],
    )?
    .iter()
    .map(|r| {
        Ok(BandPoint {
            run_id: r.string(0)?,
            commit: r.opt_string(1)?,
            started_at: r.string(2)?,
            environment: environment(r.str(3)?, r.str(4)?, r.str(5)?),
            value: r.f64(6)?,
            p5: r.opt_f64(7)?,
            p95: r.opt_f64(8)?,
        })
    })
    .collect()
}

/// A point as detection reads it: its run, its environment (an id from [`Environments`]) and value.
#[derive(Clone, Debug, PartialEq)]
pub struct WindowPoint {
    pub run_pk: i64,
    pub environment: u32,
    pub value: f64,
}

/// Environment (driver, driver version, harness version) of each run, read once per run and
/// shared by every series a detection pass reads: a point is then just a run and a value.
#[derive(Debug, Default)]
pub struct Environments {
    by_run: HashMap<i64, u32>,
    ids: HashMap<String, u32>,
}

impl Environments {
    pub fn of(&mut self, conn: &mut dyn Connection, run_pk: i64) -> Result<u32, StoreError> {
        if let Some(&e) = self.by_run.get(&run_pk) {
            return Ok(e);
        }
        let row = conn.query(
            "SELECT driver || ' ' || driver_info || ' / harness ' || harness_version FROM runs WHERE id = $1",
            &[Value::Int(run_pk)],
        )?;
        let name = row
            .first()
            .map(|r| r.string(0))
            .transpose()?
            .unwrap_or_default();
        let next = self.ids.len() as u32;
        let id = *self.ids.entry(name).or_insert(next);
        self.by_run.insert(run_pk, id);
        Ok(id)
    }
}

/// The newest `len` points of a series, oldest first: one range of the primary key of `points`
/// (series_id, ord, run_pk), whatever the length of the series.
pub fn window(
    conn: &mut dyn Connection,
    series_id: i64,
    len: usize,
    envs: &mut Environments,
) -> Result<Vec<WindowPoint>, StoreError> {
    let rows = conn.query(
        "SELECT run_pk, value FROM points WHERE series_id = $1 ORDER BY ord DESC, run_pk DESC LIMIT $2",
        &[Value::Int(series_id), Value::Int(len as i64)],
    )?;
    let mut pts = Vec::with_capacity(rows.len());
    for r in rows.iter().rev() {
        let run_pk = r.i64(0)?;
        pts.push(WindowPoint {
            run_pk,
            environment: envs.of(conn, run_pk)?,
            value: r.f64(1)?,
        });
    }
    Ok(pts)
}

/// Every series in the store (for `tessera-dashboard detect`), but the frame alerts' series
/// ([`UNTRIAGED_MEASURE`], which have no points: their alerts are triaged, not detected).
pub fn all_series(conn: &mut dyn Connection) -> Result<Vec<i64>, StoreError> {
    Ok(conn
        .query(
            "SELECT id FROM series WHERE measure <> $1 ORDER BY id",
            &[UNTRIAGED_MEASURE.into()],
        )?
        .iter()
        .map(|r| r.i64(0))
        .collect::<Result<_, _>>()?)
}

/// The series run `run_pk` has a point in, by id.
pub fn of_run(conn: &mut dyn Connection, run_pk: i64) -> Result<Vec<i64>, StoreError> {
    Ok(conn
        .query(
            "SELECT series_id FROM points WHERE run_pk = $1 ORDER BY series_id",
            &[Value::Int(run_pk)],
        )?
        .iter()
        .map(|r| r.i64(0))
        .collect::<Result<_, _>>()?)
}

/// On PostgreSQL, locks the series run `run_pk` has points in, in id order, so that two uploads
/// touching one series analyse it one after the other, each seeing the other's point (SQLite's
/// `BEGIN IMMEDIATE` already serialises writers).
pub fn lock_of_run(conn: &mut dyn Connection, run_pk: i64) -> Result<(), StoreError> {
    if conn.backend() == Backend::Postgres {
        conn.query(
            "SELECT id FROM series WHERE id IN (SELECT series_id FROM points WHERE run_pk = $1)
             ORDER BY id FOR UPDATE",
            &[Value::Int(run_pk)],
        )?;
    }
    Ok(())
}

/// On PostgreSQL, locks series `id` for the rest of the transaction (see [`lock_of_run`]).
pub fn lock(conn: &mut dyn Connection, id: i64) -> Result<(), StoreError> {
    if conn.backend() == Backend::Postgres {
        conn.query(
            "SELECT id FROM series WHERE id = $1 FOR UPDATE",
            &[Value::Int(id)],
        )?;
    }
    Ok(())
}

/// Series ids of a run's results, so that pages can link to their history.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct SeriesLink {
    pub scenario: String,
    pub variant: String,
    pub measure: String,
    pub series_id: i64,
}

/// The series run `run_pk` has a point in, by scenario, variant and measure.
pub fn links_of_run(conn: &mut dyn Connection, run_pk: i64) -> Result<Vec<SeriesLink>, StoreError> {
    links_of_run_in(conn, run_pk, None)
}

/// [`links_of_run`], of one scenario only when `scenario` names it.
pub fn links_of_run_in(
    conn: &mut dyn Connection,
    run_pk: i64,
    scenario: Option<&str>,
) -> Result<Vec<SeriesLink>, StoreError> {
    conn.query(
        "SELECT DISTINCT s.scenario, s.variant, s.measure, s.id FROM points p JOIN series s ON s.id = p.series_id
         WHERE p.run_pk = $1 AND (CAST($2 AS TEXT) IS NULL OR s.scenario = $2)
         ORDER BY s.scenario, s.variant, s.measure",
        &[Value::Int(run_pk), scenario.into()],
    )?
    .iter()
    .map(|r| {
        Ok(SeriesLink {
            scenario: r.string(0)?,
            variant: r.string(1)?,
            measure: r.string(2)?,
            series_id: r.i64(3)?,
        })
    })
    .collect()
}

/// The id of series (scenario, variant, adapter, measure), created when it is new.
pub fn id_or_insert(
    conn: &mut dyn Connection,
    scenario: &str,
    variant: &str,
    adapter: i64,
    measure: &str,
    higher_is_better: bool,
) -> Result<i64, StoreError> {
    let key = [
        scenario.into(),
        variant.into(),
        Value::Int(adapter),
        measure.into(),
    ];
    let select =
        "SELECT id FROM series WHERE scenario = $1 AND variant = $2 AND adapter_id = $3 AND measure = $4";
    if let Some(row) = conn.query_opt(select, &key)? {
        return Ok(row.i64(0)?);
    }
    let mut params = key.to_vec();
    params.push(higher_is_better.into());
    conn.execute(
        "INSERT INTO series (scenario, variant, adapter_id, measure, higher_is_better)
         VALUES ($1, $2, $3, $4, $5) ON CONFLICT DO NOTHING",
        &params,
    )?;
    Ok(conn.query(select, &key)?[0].i64(0)?)
}

/// Stores the point of run `run_pk` in series `series_id`; `ord` is the run's place in commit order.
pub fn insert_point(
    conn: &mut dyn Connection,
    series_id: i64,
    run_pk: i64,
    value: f64,
    ord: i64,
) -> Result<(), StoreError> {
    conn.execute(
        "INSERT INTO points (series_id, run_pk, value, ord) VALUES ($1, $2, $3, $4)",
        &[
            Value::Int(series_id),
            Value::Int(run_pk),
            Value::Real(value),
            Value::Int(ord),
        ],
    )?;
    Ok(())
}

/// Deletes the points of run `run_pk` (and their bands); returns how many points went.
pub fn delete_of_run(conn: &mut dyn Connection, run_pk: i64) -> Result<u64, StoreError> {
    let pk = [Value::Int(run_pk)];
    conn.execute("DELETE FROM point_bands WHERE run_pk = $1", &pk)?;
    Ok(conn.execute("DELETE FROM points WHERE run_pk = $1", &pk)?)
}

/// The run of the nearest point of series `series` after (`later`) or before run `run_pk`'s
/// point, in commit order; `None` when the run has no point there or none lies on that side.
pub fn neighbour(
    conn: &mut dyn Connection,
    series: i64,
    run_pk: i64,
    later: bool,
) -> Result<Option<i64>, StoreError> {
    let Some(ord) = conn
        .query_opt(
            "SELECT ord FROM points WHERE series_id = $1 AND run_pk = $2",
            &[Value::Int(series), Value::Int(run_pk)],
        )?
        .map(|r| r.i64(0))
        .transpose()?
    else {
        return Ok(None);
    };
    let sql = if later {
        "SELECT run_pk FROM points WHERE series_id = $1 AND run_pk <> $2 AND (ord > $3 OR (ord = $3 AND run_pk > $2))
         ORDER BY ord, run_pk LIMIT 1"
    } else {
        "SELECT run_pk FROM points WHERE series_id = $1 AND run_pk <> $2 AND (ord < $3 OR (ord = $3 AND run_pk < $2))
         ORDER BY ord DESC, run_pk DESC LIMIT 1"
    };
    Ok(conn
        .query_opt(
            sql,
            &[Value::Int(series), Value::Int(run_pk), Value::Int(ord)],
        )?
        .map(|r| r.i64(0))
        .transpose()?)
}

/// Up to `limit` values of series `series` at and before run `run`'s point (`earlier`), newest
/// first, or at and after it, oldest first.
pub fn values_beside(
    conn: &mut dyn Connection,
    series: i64,
    run: i64,
    earlier: bool,
    limit: i64,
) -> Result<Vec<f64>, StoreError> {
    let sql = if earlier {
        "SELECT p.value FROM points p, points q WHERE q.series_id = $1 AND q.run_pk = $2
           AND p.series_id = $1 AND (p.ord < q.ord OR (p.ord = q.ord AND p.run_pk <= q.run_pk))
         ORDER BY p.ord DESC, p.run_pk DESC LIMIT $3"
    } else {
        "SELECT p.value FROM points p, points q WHERE q.series_id = $1 AND q.run_pk = $2
           AND p.series_id = $1 AND (p.ord > q.ord OR (p.ord = q.ord AND p.run_pk >= q.run_pk))
         ORDER BY p.ord, p.run_pk LIMIT $3"
    };
    Ok(conn
        .query(
            sql,
            &[Value::Int(series), Value::Int(run), Value::Int(limit)],
        )?
        .iter()
        .map(|r| r.f64(0))
        .collect::<Result<_, _>>()?)
}

/// A series of measure `measure` with a point of run `run_pk`.
#[derive(Clone, Debug, PartialEq)]
pub struct RunSeries {
    pub id: i64,
    pub scenario: String,
    pub variant: String,
    /// The commit order of the run's point in the series ([`super::ingest::order_key`]).
    pub ord: i64,
}

/// The series of measure `measure` run `run_pk` has a point in, by id.
pub fn of_run_with_measure(
    conn: &mut dyn Connection,
    run_pk: i64,
    measure: &str,
) -> Result<Vec<RunSeries>, StoreError> {
    conn.query(
        "SELECT s.id, s.scenario, s.variant, p.ord FROM points p JOIN series s ON s.id = p.series_id
         WHERE p.run_pk = $1 AND s.measure = $2 ORDER BY s.id",
        &[Value::Int(run_pk), measure.into()],
    )?
    .iter()
    .map(|r| {
        Ok(RunSeries {
            id: r.i64(0)?,
            scenario: r.string(1)?,
            variant: r.string(2)?,
            ord: r.i64(3)?,
        })
    })
    .collect()
}

/// A run's environment as three parts: driver, driver version, harness version.
pub type Environment = (String, String, String);

/// Up to `limit` points of series `s` before run `run_pk`'s point (`s.ord`, as
/// [`of_run_with_measure`] read it), newest first, each with the primary key of its run (the
/// run's environment is looked up once per run by the caller, see [`environment_of`], not joined
/// into every point: a wide run asks this of each of its 1,700 series).
pub fn before_with_run(
    conn: &mut dyn Connection,
    s: &RunSeries,
    run_pk: i64,
    limit: i64,
) -> Result<Vec<(f64, i64)>, StoreError> {
    conn.query(
        "SELECT p.value, p.run_pk FROM points p
         WHERE p.series_id = $1 AND (p.ord < $2 OR (p.ord = $2 AND p.run_pk < $3))
         ORDER BY p.ord DESC, p.run_pk DESC LIMIT $4",
        &[
            Value::Int(s.id),
            Value::Int(s.ord),
            Value::Int(run_pk),
            Value::Int(limit),
        ],
    )?
    .iter()
    .map(|r| Ok((r.f64(0)?, r.i64(1)?)))
    .collect()
}

/// The environment of run `run_pk` (`None` for no such run).
pub fn environment_of(
    conn: &mut dyn Connection,
    run_pk: i64,
) -> Result<Option<Environment>, StoreError> {
    conn.query_opt(
        "SELECT driver, driver_info, harness_version FROM runs WHERE id = $1",
        &[Value::Int(run_pk)],
    )?
    .map(|r| Ok((r.string(0)?, r.string(1)?, r.string(2)?)))
    .transpose()
}
