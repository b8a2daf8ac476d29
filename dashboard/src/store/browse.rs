//! Queries for browsing: the runs list with filters and paging, the series finder with substring
//! filters and paging, a series' points with their p5-p95 bands, and the runs a page compares
//! against (the previous run of the same suite, a run of a commit, the nearest run on another
//! adapter). Each returns a plain serialisable struct that is also the JSON API's response.
//!
//! Not for: rendering (see [`crate::server`]) or statistics (see `tessera_results::stats`).

use serde::Serialize;

use super::read::{run_row, AdapterRow, RunRow, RUN_COLUMNS};
pub use super::series::{band_points, BandPoint};
use super::series::{series_key, SeriesKey, SERIES_COLUMNS};
use super::StoreError;
use crate::db::{Connection, Value};

/// A `LIKE` pattern matching `text` anywhere, lower case, with `\` escaping `%`, `_` and `\`.
pub fn contains_pattern(text: &str) -> String {
    let mut p = String::from("%");
    for c in text.to_lowercase().chars() {
        if matches!(c, '%' | '_' | '\\') {
            p.push('\\');
        }
        p.push(c);
    }
    p.push('%');
    p
}

fn opt_text(s: &Option<String>) -> Value {
    s.as_ref()
        .filter(|s| !s.is_empty())
        .map(|s| s.to_string())
        .into()
}

/// What the runs list keeps; every part optional.
#[derive(Clone, Debug, Default)]
pub struct RunFilter {
    pub adapter: Option<i64>,
    pub suite: Option<String>,
    pub branch: Option<String>,
    /// `complete`, `interrupted`, `running`, or `failed` (runs with a failed result).
    pub status: Option<String>,
    /// Substring of the run id or the commit.
    pub text: Option<String>,
    /// Only runs in which a change was detected.
    pub alerts_only: bool,
}

/// A run in the list, with the number of changes detected at it.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct RunListRow {
    #[serde(flatten)]
    pub run: RunRow,
    /// Detected changes whose first run after the change is this run.
    pub alerts: i64,
}

/// One page of the runs list and what its filters can pick from.
#[derive(Clone, Debug, Serialize)]
pub struct RunList {
    pub runs: Vec<RunListRow>,
    /// Runs matching the filter, over all pages.
    pub total: i64,
    pub offset: i64,
    pub limit: i64,
    pub adapters: Vec<AdapterRow>,
    pub suites: Vec<String>,
    pub branches: Vec<String>,
}

const RUN_WHERE: &str = "(CAST($1 AS BIGINT) IS NULL OR r.adapter_id = $1)
   AND (CAST($2 AS TEXT) IS NULL OR r.suite = $2)
   AND (CAST($3 AS TEXT) IS NULL OR r.branch = $3)
   AND (CAST($4 AS TEXT) IS NULL OR r.status = $4 OR ($4 = 'failed' AND r.n_failed > 0))
   AND (CAST($5 AS TEXT) IS NULL OR LOWER(r.run_id) LIKE $5 ESCAPE '\\' OR LOWER(COALESCE(r.commit_sha, '')) LIKE $5 ESCAPE '\\')
   AND (CAST($6 AS BIGINT) = 0 OR EXISTS (SELECT 1 FROM regressions g WHERE g.run_pk_after = r.id))";

pub fn run_list(
    conn: &mut dyn Connection,
    f: &RunFilter,
    offset: i64,
    limit: i64,
) -> Result<RunList, StoreError> {
    let text = f
        .text
        .as_deref()
        .filter(|t| !t.is_empty())
        .map(contains_pattern);
    let params = [
        f.adapter.into(),
        opt_text(&f.suite),
        opt_text(&f.branch),
        opt_text(&f.status),
        text.into(),
        Value::Int(f.alerts_only.into()),
    ];
    let total = conn.query(
        &format!("SELECT COUNT(*) FROM runs r WHERE {RUN_WHERE}"),
        &params,
    )?[0]
        .i64(0)?;
    let mut p = params.to_vec();
    p.push(Value::Int(limit));
    p.push(Value::Int(offset));
    let runs = conn
        .query(
            &format!(
                "SELECT {RUN_COLUMNS}, (SELECT COUNT(*) FROM regressions g WHERE g.run_pk_after = r.id)
                 FROM runs r JOIN adapters a ON a.id = r.adapter_id
                 WHERE {RUN_WHERE} ORDER BY r.started_at DESC, r.id DESC LIMIT $7 OFFSET $8"
            ),
            &p,
        )?
        .iter()
        .map(|r| {
            Ok(RunListRow {
                run: run_row(r)?,
                alerts: r.i64(16)?,
            })
        })
        .collect::<Result<Vec<_>, StoreError>>()?;
    let distinct = |c: &mut dyn Connection, col: &str| -> Result<Vec<String>, StoreError> {
        c.query(
            &format!("SELECT DISTINCT {col} FROM runs WHERE {col} IS NOT NULL ORDER BY {col}"),
            &[],
        )?
        .iter()
        .map(|r| r.string(0).map_err(Into::into))
        .collect()
    };
    Ok(RunList {
        runs,
        total,
        offset,
        limit,
        adapters: super::read::adapters(conn)?,
        suites: distinct(conn, "suite")?,
        branches: distinct(conn, "branch")?,
    })
}

/// What the series finder keeps: substrings of scenario, variant and measure, and an adapter.
#[derive(Clone, Debug, Default)]
pub struct SeriesFilter {
    pub scenario: Option<String>,
    pub variant: Option<String>,
    pub measure: Option<String>,
    pub adapter: Option<i64>,
}

/// One page of the series finder.
#[derive(Clone, Debug, Serialize)]
pub struct SeriesList {
    pub series: Vec<SeriesKey>,
    /// Series matching the filter, over all pages.
    pub total: i64,
    pub offset: i64,
    pub limit: i64,
    pub adapters: Vec<AdapterRow>,
}

const SERIES_WHERE: &str = "(CAST($1 AS TEXT) IS NULL OR LOWER(s.scenario) LIKE $1 ESCAPE '\\')
   AND (CAST($2 AS TEXT) IS NULL OR LOWER(s.variant) LIKE $2 ESCAPE '\\')
   AND (CAST($3 AS TEXT) IS NULL OR LOWER(s.measure) LIKE $3 ESCAPE '\\')
   AND (CAST($4 AS BIGINT) IS NULL OR s.adapter_id = $4)";

pub fn series_list(
    conn: &mut dyn Connection,
    f: &SeriesFilter,
    offset: i64,
    limit: i64,
) -> Result<SeriesList, StoreError> {
    let pat = |s: &Option<String>| -> Value {
        s.as_deref()
            .filter(|s| !s.is_empty())
            .map(contains_pattern)
            .into()
    };
    let params = [
        pat(&f.scenario),
        pat(&f.variant),
        pat(&f.measure),
        f.adapter.into(),
    ];
    let total = conn.query(
        &format!("SELECT COUNT(*) FROM series s WHERE {SERIES_WHERE}"),
        &params,
    )?[0]
        .i64(0)?;
    let mut p = params.to_vec();
    p.push(Value::Int(limit));
    p.push(Value::Int(offset));
    let series = conn
        .query(
            &format!(
                "SELECT {SERIES_COLUMNS} FROM series s JOIN adapters a ON a.id = s.adapter_id
                 WHERE {SERIES_WHERE} ORDER BY s.scenario, s.variant, a.name, s.measure LIMIT $5 OFFSET $6"
            ),
            &p,
        )?
        .iter()
        .map(series_key)
        .collect::<Result<Vec<_>, StoreError>>()?;
    Ok(SeriesList {
        series,
        total,
        offset,
        limit,
        adapters: super::read::adapters(conn)?,
    })
}

/// Series that can be overlaid on `key`: the same scenario and measure on other variants and
/// adapters, and the same scenario, variant and adapter under other measures (passes).
pub fn related_series(
    conn: &mut dyn Connection,
    key: &SeriesKey,
) -> Result<Vec<SeriesKey>, StoreError> {
    conn.query(
        &format!(
            "SELECT {SERIES_COLUMNS} FROM series s JOIN adapters a ON a.id = s.adapter_id
             WHERE s.scenario = $1 AND s.id <> $2
               AND (s.measure = $3 OR (s.variant = $4 AND s.adapter_id = $5))
             ORDER BY s.measure <> $3, s.variant, a.name, s.measure LIMIT 200"
        ),
        &[
            key.scenario.as_str().into(),
            Value::Int(key.id),
            key.measure.as_str().into(),
            key.variant.as_str().into(),
            Value::Int(key.adapter_id),
        ],
    )?
    .iter()
    .map(series_key)
    .collect()
}

/// Series by id (for overlays), in the order given; unknown ids are left out.
pub fn series_keys(conn: &mut dyn Connection, ids: &[i64]) -> Result<Vec<SeriesKey>, StoreError> {
    let mut out = Vec::new();
    for &id in ids {
        if let Some(r) = conn.query_opt(
            &format!("SELECT {SERIES_COLUMNS} FROM series s JOIN adapters a ON a.id = s.adapter_id WHERE s.id = $1"),
            &[Value::Int(id)],
        )? {
            out.push(series_key(&r)?);
        }
    }
    Ok(out)
}

/// The run before `run_id` on the same adapter with the same suite (runs without a suite count as
/// one suite) that holds at least one of its scenarios (a suite split over several runs has runs
/// with other scenarios), by start time. A run recorded without a commit is never the previous
/// run: nothing says what it measured.
pub fn previous_in_suite(
    conn: &mut dyn Connection,
    run_id: &str,
) -> Result<Option<String>, StoreError> {
    Ok(conn
        .query_opt(
            "SELECT p.run_id FROM runs r JOIN runs p ON p.adapter_id = r.adapter_id
               AND p.suite IS NOT DISTINCT FROM r.suite
               AND (p.started_at < r.started_at OR (p.started_at = r.started_at AND p.id < r.id))
             WHERE r.run_id = $1 AND p.commit_sha IS NOT NULL
               AND EXISTS (SELECT 1 FROM scenario_results sp JOIN scenario_results sr
                             ON sr.scenario = sp.scenario
                           WHERE sp.run_pk = p.id AND sr.run_pk = r.id)
             ORDER BY p.started_at DESC, p.id DESC LIMIT 1",
            &[run_id.into()],
        )?
        .map(|r| r.string(0))
        .transpose()?)
}

/// The newest run whose commit starts with `commit` (at least 4 characters), optionally on one
/// adapter and one suite.
pub fn run_of_commit(
    conn: &mut dyn Connection,
    commit: &str,
    adapter: Option<i64>,
    suite: Option<&str>,
) -> Result<Option<String>, StoreError> {
    if commit.len() < 4 || !commit.bytes().all(|b| b.is_ascii_hexdigit()) {
        return Ok(None);
    }
    let pattern = format!("{}%", commit.to_lowercase());
    Ok(conn
        .query_opt(
            "SELECT r.run_id FROM runs r WHERE LOWER(r.commit_sha) LIKE $1
               AND (CAST($2 AS BIGINT) IS NULL OR r.adapter_id = $2)
               AND (CAST($3 AS TEXT) IS NULL OR r.suite = $3)
             ORDER BY r.started_at DESC, r.id DESC LIMIT 1",
            &[
                pattern.into(),
                adapter.into(),
                suite.map(str::to_string).into(),
            ],
        )?
        .map(|r| r.string(0))
        .transpose()?)
}

/// How a run on another adapter was matched to a given run.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Counterpart {
    pub run_id: String,
    /// `same commit` or `nearest in time` (no run of that commit on the adapter).
    pub how: String,
}

/// The run on `adapter` that best matches `run_id`: the same suite, the same commit if there is
/// one (the newest such run), otherwise the run nearest in start time.
pub fn counterpart(
    conn: &mut dyn Connection,
    run_id: &str,
    adapter: i64,
) -> Result<Option<Counterpart>, StoreError> {
    let Some(r) = conn.query_opt(
        "SELECT commit_sha, suite, started_at FROM runs WHERE run_id = $1",
        &[run_id.into()],
    )?
    else {
        return Ok(None);
    };
    let (sha, suite, started) = (r.opt_string(0)?, r.opt_string(1)?, r.string(2)?);
    if let Some(sha) = &sha {
        if let Some(row) = conn.query_opt(
            "SELECT run_id FROM runs WHERE adapter_id = $1 AND commit_sha = $2 AND suite IS NOT DISTINCT FROM $3
             ORDER BY started_at DESC, id DESC LIMIT 1",
            &[Value::Int(adapter), sha.as_str().into(), suite.clone().into()],
        )? {
            return Ok(Some(Counterpart {
                run_id: row.string(0)?,
                how: "same commit".into(),
            }));
        }
    }
    let mut best: Option<(i64, String)> = None;
    let t0 = parse_time(&started);
    for (cmp, order) in [("<=", "DESC"), (">", "ASC")] {
        if let Some(row) = conn.query_opt(
            &format!(
                "SELECT run_id, started_at FROM runs WHERE adapter_id = $1 AND suite IS NOT DISTINCT FROM $2
                   AND started_at {cmp} $3 ORDER BY started_at {order}, id {order} LIMIT 1"
            ),
            &[Value::Int(adapter), suite.clone().into(), started.as_str().into()],
        )? {
            let gap = match (t0, parse_time(row.str(1)?)) {
                (Some(a), Some(b)) => (a - b).abs(),
                _ => i64::MAX,
            };
            if best.as_ref().is_none_or(|(g, _)| gap < *g) {
                best = Some((gap, row.string(0)?));
            }
        }
    }
    Ok(best.map(|(_, run_id)| Counterpart {
        run_id,
        how: "nearest in time".into(),
    }))
}

/// The newest run on adapter `a` of a suite that also has runs on adapter `b` (runs without a
/// suite count as one suite).
pub fn newest_with_shared_suite(
    conn: &mut dyn Connection,
    a: i64,
    b: i64,
) -> Result<Option<String>, StoreError> {
    Ok(conn
        .query_opt(
            "SELECT r.run_id FROM runs r WHERE r.adapter_id = $1
               AND EXISTS (SELECT 1 FROM runs q WHERE q.adapter_id = $2 AND q.suite IS NOT DISTINCT FROM r.suite)
             ORDER BY r.started_at DESC, r.id DESC LIMIT 1",
            &[Value::Int(a), Value::Int(b)],
        )?
        .map(|r| r.string(0))
        .transpose()?)
}

/// Seconds since the epoch of an RFC 3339 time.
pub fn parse_time(t: &str) -> Option<i64> {
    chrono::DateTime::parse_from_rfc3339(t)
        .ok()
        .map(|d| d.timestamp())
}

/// Runs (newest first, at most 30) that stored images of `variant` in `scenario`.
pub fn runs_with_images(
    conn: &mut dyn Connection,
    scenario: &str,
    variant: &str,
) -> Result<Vec<String>, StoreError> {
    conn.query(
        "SELECT r.run_id FROM runs r WHERE EXISTS (SELECT 1 FROM images i WHERE i.run_pk = r.id AND i.scenario = $1 AND i.variant = $2)
         ORDER BY r.started_at DESC, r.id DESC LIMIT 30",
        &[scenario.into(), variant.into()],
    )?
    .iter()
    .map(|r| r.string(0).map_err(Into::into))
    .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn like_patterns_escape_wildcards() {
        assert_eq!(contains_pattern("Up_scale%"), "%up\\_scale\\%%");
        assert_eq!(parse_time("2026-01-01T00:01:00Z"), Some(1_767_225_660));
    }
}
