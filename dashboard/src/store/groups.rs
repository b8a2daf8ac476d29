//! Alert groups: the alerts (rows of `regressions`, one per series change) that blame the same
//! commit range (the commits of `run_pk_before` and `run_pk_after`) are one *group*, triaged as
//! one change ("`c0ffee`: 12 series on 2 adapters; checkerboard gpu_ms +6.0%, reconstruct
//! +35.0%"). Grouping is done when reading, so it follows whatever detection stores or moves;
//! the group's triage is kept on each of its alerts (see [`super::triage::set_group`]).
//!
//! Reads the `status` column of detection (`pending`, `confirmed`, `withdrawn`) when the store
//! has it and takes every alert as `confirmed` when it does not.
//!
//! Not for: detection (see [`crate::regressions`]), triage writes (see [`super::triage`]),
//! rendering (see [`crate::server::regressions`] and [`crate::notify`]).

use std::collections::{BTreeMap, BTreeSet};

use serde::Serialize;
use tessera_results::measure::Measure;

use super::read::SeriesKey;
use super::StoreError;
use crate::db::{Backend, Connection, Row, Value};

/// Most alerts read for one listing, newest first; older alerts are not grouped.
pub const MAX_ALERTS: i64 = 20_000;

/// One alert with its series, runs and triage.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Alert {
    pub id: i64,
    pub series: SeriesKey,
    /// The scenario file's folder (`quality` for `scenarios/quality/cut.toml`), else the scenario.
    pub suite: String,
    pub run_before: String,
    pub commit_before: Option<String>,
    pub run_after: String,
    pub commit_after: Option<String>,
    /// Start of the run after the change.
    pub started_at: String,
    pub value_before: f64,
    pub value_after: f64,
    pub relative_change: f64,
    /// `true` when the change makes the measure worse.
    pub is_regression: bool,
    pub confidence: f64,
    /// `pending`, `confirmed` or `withdrawn` (detection's word on the alert).
    pub status: String,
    pub state: String,
    pub note: String,
    pub bug_url: String,
    pub updated_by: String,
    pub detected_at: String,
    pub updated_at: String,
    #[serde(skip)]
    run_pk_before: i64,
    #[serde(skip)]
    run_pk_after: i64,
}

impl Alert {
    /// The key of the group this alert belongs to.
    pub fn group_key(&self) -> String {
        key(
            self.commit_before.as_deref(),
            self.run_pk_before,
            self.commit_after.as_deref(),
            self.run_pk_after,
        )
    }
}

/// A group of alerts with one triage.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Group {
    /// `<commit before>..<commit after>`; a run without a usable commit is `~<run pk>`.
    pub key: String,
    pub commit_before: Option<String>,
    pub commit_after: Option<String>,
    /// One line: commit, series and adapters, the largest changes by variant and measure.
    pub title: String,
    /// `confirmed` when any alert is, else `pending` when any is, else `withdrawn`.
    pub status: String,
    /// The state shared by the alerts; when they differ (an alert joined after triage),
    /// `new` if any alert is new, else the most recently set state, and `mixed_state` is true.
    pub state: String,
    pub mixed_state: bool,
    pub note: String,
    pub bug_url: String,
    pub updated_by: String,
    pub updated_at: String,
    pub adapters: Vec<String>,
    /// Alerts of the group (withdrawn ones left out unless all are withdrawn).
    pub series_count: usize,
    pub worse: usize,
    pub better: usize,
    /// Largest |relative change| of the group's alerts.
    pub size: f64,
    /// Newest start of a run after the change (the commit's date as the runs saw it).
    pub started_at: String,
    /// Newest detection of one of its alerts.
    pub detected_at: String,
    /// The alerts that match the filter, largest change first.
    pub alerts: Vec<Alert>,
}

/// One side of a commit range in a group key.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Side {
    Commit(String),
    Run(i64),
}

fn usable_commit(c: &str) -> bool {
    !c.is_empty()
        && c.len() <= 64
        && c.bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'-' || b == b'_')
}

fn side(commit: Option<&str>, run_pk: i64) -> String {
    match commit {
        Some(c) if usable_commit(c) => c.to_string(),
        _ => format!("~{run_pk}"),
    }
}

/// The group key of an alert from its two runs' commits (or run keys without a commit).
pub fn key(
    commit_before: Option<&str>,
    run_pk_before: i64,
    commit_after: Option<&str>,
    run_pk_after: i64,
) -> String {
    format!(
        "{}..{}",
        side(commit_before, run_pk_before),
        side(commit_after, run_pk_after)
    )
}

fn parse_side(s: &str) -> Option<Side> {
    match s.strip_prefix('~') {
        Some(pk) => pk.parse().ok().map(Side::Run),
        None => usable_commit(s).then(|| Side::Commit(s.to_string())),
    }
}

/// The two sides of a group key; `None` for anything that is not one.
pub fn parse_key(k: &str) -> Option<(Side, Side)> {
    let (b, a) = k.split_once("..")?;
    Some((parse_side(b)?, parse_side(a)?))
}

/// What the regressions page and API filter on; every part optional.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Filter {
    pub adapter: Option<i64>,
    pub suite: Option<String>,
    pub measure: Option<String>,
    /// Group triage state.
    pub state: Option<String>,
    /// `worse` or `better`.
    pub direction: Option<String>,
    /// `pending`, `confirmed`, `withdrawn` or `all`; by default withdrawn alerts are hidden.
    pub status: Option<String>,
}

pub const DIRECTIONS: [&str; 2] = ["worse", "better"];
pub const STATUSES: [&str; 4] = ["pending", "confirmed", "withdrawn", "all"];

impl Filter {
    /// Checks the values, with a message that says what is allowed.
    pub fn validate(&self) -> Result<(), StoreError> {
        let check = |what: &str, v: &Option<String>, allowed: &[&str]| match v {
            Some(v) if !allowed.contains(&v.as_str()) => Err(StoreError::Invalid(format!(
                "{what} {v:?} is not one of {}",
                allowed.join(", ")
            ))),
            _ => Ok(()),
        };
        check("state", &self.state, &super::triage::STATES)?;
        check("direction", &self.direction, &DIRECTIONS)?;
        check("status", &self.status, &STATUSES)
    }

    fn shows(&self, a: &Alert) -> bool {
        let status_ok = match self.status.as_deref() {
            None => a.status != "withdrawn",
            Some("all") => true,
            Some(s) => a.status == s,
        };
        status_ok
            && self.adapter.is_none_or(|id| a.series.adapter_id == id)
            && self.suite.as_ref().is_none_or(|s| &a.suite == s)
            && self.measure.as_ref().is_none_or(|m| &a.series.measure == m)
            && self
                .direction
                .as_ref()
                .is_none_or(|d| (d == "worse") == a.is_regression)
    }
}

/// How groups are ordered: newest change first (`date`) or largest change first (`size`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Sort {
    #[default]
    Date,
    Size,
}

impl Sort {
    pub fn parse(s: Option<&str>) -> Result<Sort, StoreError> {
        match s {
            None | Some("") | Some("date") => Ok(Sort::Date),
            Some("size") => Ok(Sort::Size),
            Some(other) => Err(StoreError::Invalid(format!(
                "sort {other:?} is not one of date, size"
            ))),
        }
    }
}

/// Whether the store has detection's `status` column (added by its own migration). Asks the
/// catalogue, so it never fails a statement (which would abort a PostgreSQL transaction).
pub fn has_status_column(conn: &mut dyn Connection) -> Result<bool, StoreError> {
    let sql = match conn.backend() {
        Backend::Sqlite => "SELECT COUNT(*) FROM pragma_table_info('regressions') WHERE name = 'status'",
        Backend::Postgres => {
            "SELECT COUNT(*) FROM information_schema.columns
             WHERE table_schema = current_schema() AND table_name = 'regressions' AND column_name = 'status'"
        }
    };
    Ok(conn.query(sql, &[])?[0].i64(0)? > 0)
}

/// The suite of each scenario that has alerts: the folder of its newest scenario file (one JSON
/// read per scenario, not per alert).
fn suites(conn: &mut dyn Connection) -> Result<BTreeMap<String, String>, StoreError> {
    let file = match conn.backend() {
        Backend::Sqlite => "json_extract(sr.record_json, '$.file')",
        Backend::Postgres => "CAST(sr.record_json AS JSON) ->> 'file'",
    };
    let rows = conn.query(
        &format!(
            "SELECT sr.scenario, {file} FROM scenario_results sr
             WHERE sr.id IN (SELECT MAX(id) FROM scenario_results
                             WHERE scenario IN (SELECT DISTINCT s.scenario FROM regressions g JOIN series s ON s.id = g.series_id)
                             GROUP BY scenario)"
        ),
        &[],
    )?;
    let mut out = BTreeMap::new();
    for r in &rows {
        let scenario = r.string(0)?;
        let folder = r.opt_string(1)?.and_then(|f| {
            std::path::Path::new(&f)
                .parent()
                .and_then(|p| p.file_name())
                .map(|n| n.to_string_lossy().into_owned())
        });
        out.insert(scenario.clone(), folder.unwrap_or(scenario));
    }
    Ok(out)
}

/// Alerts, newest first, of one group (`only`) or of all groups.
fn alerts(
    conn: &mut dyn Connection,
    only: Option<&(Side, Side)>,
    limit: i64,
) -> Result<Vec<Alert>, StoreError> {
    let status = if has_status_column(conn)? {
        "g.status"
    } else {
        "'confirmed'"
    };
    let suites = suites(conn)?;
    let (cb, pb) = match only.map(|k| &k.0) {
        Some(Side::Commit(c)) => (Value::from(c.as_str()), Value::Null),
        Some(Side::Run(pk)) => (Value::Null, Value::Int(*pk)),
        None => (Value::Null, Value::Null),
    };
    let (ca, pa) = match only.map(|k| &k.1) {
        Some(Side::Commit(c)) => (Value::from(c.as_str()), Value::Null),
        Some(Side::Run(pk)) => (Value::Null, Value::Int(*pk)),
        None => (Value::Null, Value::Null),
    };
    let rows = conn.query(
        &format!(
            "SELECT s.id, s.scenario, s.variant, s.adapter_id, a.name, s.measure, s.higher_is_better,
                g.id, g.run_pk_before, rb.run_id, rb.commit_sha, g.run_pk_after, ra.run_id, ra.commit_sha,
                ra.started_at, g.value_before, g.value_after, g.relative_change, g.confidence,
                {status}, g.state, g.note, g.bug_url, g.updated_by, g.detected_at, g.updated_at
             FROM regressions g JOIN series s ON s.id = g.series_id JOIN adapters a ON a.id = s.adapter_id
             JOIN runs rb ON rb.id = g.run_pk_before JOIN runs ra ON ra.id = g.run_pk_after
             WHERE (CAST($1 AS TEXT) IS NULL OR rb.commit_sha = $1)
               AND (CAST($2 AS BIGINT) IS NULL OR g.run_pk_before = $2)
               AND (CAST($3 AS TEXT) IS NULL OR ra.commit_sha = $3)
               AND (CAST($4 AS BIGINT) IS NULL OR g.run_pk_after = $4)
             ORDER BY ra.started_at DESC, g.id DESC LIMIT $5"
        ),
        &[cb, pb, ca, pa, Value::Int(limit)],
    )?;
    rows.iter().map(|r| alert(r, &suites)).collect()
}

fn alert(r: &Row, suites: &BTreeMap<String, String>) -> Result<Alert, StoreError> {
    let series = SeriesKey {
        id: r.i64(0)?,
        scenario: r.string(1)?,
        variant: r.string(2)?,
        adapter_id: r.i64(3)?,
        adapter: r.string(4)?,
        measure: r.string(5)?,
        higher_is_better: r.bool(6)?,
    };
    let relative_change = r.opt_f64(17)?.unwrap_or(f64::INFINITY);
    let suite = suites
        .get(&series.scenario)
        .cloned()
        .unwrap_or_else(|| series.scenario.clone());
    Ok(Alert {
        id: r.i64(7)?,
        is_regression: (relative_change > 0.0) != series.higher_is_better,
        suite,
        run_pk_before: r.i64(8)?,
        run_before: r.string(9)?,
        commit_before: r.opt_string(10)?,
        run_pk_after: r.i64(11)?,
        run_after: r.string(12)?,
        commit_after: r.opt_string(13)?,
        started_at: r.string(14)?,
        value_before: r.f64(15)?,
        value_after: r.f64(16)?,
        relative_change,
        confidence: r.f64(18)?,
        status: r.string(19)?,
        state: r.string(20)?,
        note: r.string(21)?,
        bug_url: r.string(22)?,
        updated_by: r.string(23)?,
        detected_at: r.string(24)?,
        updated_at: r.string(25)?,
        series,
    })
}

/// The short name of a measure in a title: `gpu_ms`, a pass name, a metric.
pub fn measure_label(measure: &str) -> &str {
    // The parts of the key are the measure table's (`tessera_results::measure::Key`): a pass's GPU
    // time is named by its pass, a median by its measure.
    match tessera_results::measure::Key::parse(measure) {
        Some(k)
            if k.measure == Measure::GpuMs && k.pass.is_some() && k.statistic == Some("median") =>
        {
            let pass = k.pass.as_deref().unwrap_or_default();
            &measure["pass.".len().."pass.".len() + pass.len()]
        }
        Some(k) if k.pass.is_none() && k.statistic == Some("median") => k.measure.name(),
        _ => measure,
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    }
}

/// The group's one-line title. With `code`, names are wrapped in backticks (Markdown).
pub fn title(commit_after: &str, alerts: &[&Alert], code: bool) -> String {
    let q = |s: &str| {
        if code {
            format!("`{s}`")
        } else {
            s.to_string()
        }
    };
    let adapters: BTreeSet<&str> = alerts.iter().map(|a| a.series.adapter.as_str()).collect();
    let mut t = format!(
        "{}: {} series on {} adapter{}",
        q(commit_after),
        alerts.len(),
        adapters.len(),
        if adapters.len() == 1 { "" } else { "s" }
    );
    // Per variant, its measures with the median change over scenarios and adapters.
    let mut by_variant: BTreeMap<&str, BTreeMap<&str, Vec<f64>>> = BTreeMap::new();
    let mut scenarios: BTreeMap<&str, BTreeSet<&str>> = BTreeMap::new();
    for a in alerts {
        by_variant
            .entry(&a.series.variant)
            .or_default()
            .entry(measure_label(&a.series.measure))
            .or_default()
            .push(a.relative_change);
        scenarios
            .entry(&a.series.variant)
            .or_default()
            .insert(&a.series.scenario);
    }
    let mut parts: Vec<(f64, String)> = by_variant
        .into_iter()
        .map(|(variant, measures)| {
            let mut ms: Vec<(f64, &str)> =
                measures.into_iter().map(|(m, v)| (median(v), m)).collect();
            ms.sort_by(|x, y| y.0.abs().total_cmp(&x.0.abs()).then(x.1.cmp(y.1)));
            let largest = ms.first().map_or(0.0, |m| m.0.abs());
            let shown: Vec<String> = ms
                .iter()
                .take(2)
                .map(|(v, m)| format!("{} {}", q(m), crate::html::pct(*v)))
                .collect();
            let more = if ms.len() > 2 {
                format!(" and {} more", ms.len() - 2)
            } else {
                String::new()
            };
            let on = match scenarios.get(variant) {
                Some(s) if s.len() == 1 => format!(" on {}", q(s.iter().next().unwrap())),
                _ => String::new(),
            };
            (
                largest,
                format!("{} {}{more}{on}", q(variant), shown.join(", ")),
            )
        })
        .collect();
    parts.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
    for (i, (_, p)) in parts.iter().enumerate() {
        if i == 3 {
            t.push_str(&format!("; {} more variants", parts.len() - 3));
            break;
        }
        t.push_str("; ");
        t.push_str(p);
    }
    t
}

/// Builds the groups of `alerts` (in their order: newest first); `filter` picks the alerts
/// listed and the groups kept.
fn build(all: Vec<Alert>, filter: &Filter) -> Vec<Group> {
    let mut order: Vec<String> = Vec::new();
    let mut by_key: BTreeMap<String, Vec<Alert>> = BTreeMap::new();
    for a in all {
        let k = a.group_key();
        if !by_key.contains_key(&k) {
            order.push(k.clone());
        }
        by_key.entry(k).or_default().push(a);
    }
    let mut out = Vec::new();
    for k in order {
        let members = by_key.remove(&k).unwrap_or_default();
        let live: Vec<&Alert> = members.iter().filter(|a| a.status != "withdrawn").collect();
        let basis: Vec<&Alert> = if live.is_empty() {
            members.iter().collect()
        } else {
            live
        };
        let first = basis[0];
        let states: BTreeSet<&str> = basis.iter().map(|a| a.state.as_str()).collect();
        let latest = basis
            .iter()
            .max_by(|x, y| x.updated_at.cmp(&y.updated_at).then(x.id.cmp(&y.id)))
            .unwrap();
        let state = if states.len() == 1 {
            first.state.clone()
        } else if states.contains("new") {
            "new".to_string()
        } else {
            latest.state.clone()
        };
        let status = ["confirmed", "pending"]
            .into_iter()
            .find(|s| basis.iter().any(|a| a.status == *s))
            .unwrap_or("withdrawn")
            .to_string();
        let adapters: BTreeSet<String> = basis.iter().map(|a| a.series.adapter.clone()).collect();
        let commit_after = crate::html::commit(first.commit_after.as_deref());
        let mut group = Group {
            title: title(&commit_after, &basis, false),
            key: k,
            commit_before: first.commit_before.clone(),
            commit_after: first.commit_after.clone(),
            status,
            mixed_state: states.len() > 1,
            state,
            note: latest.note.clone(),
            bug_url: latest.bug_url.clone(),
            updated_by: latest.updated_by.clone(),
            updated_at: latest.updated_at.clone(),
            adapters: adapters.into_iter().collect(),
            series_count: basis.len(),
            worse: basis.iter().filter(|a| a.is_regression).count(),
            better: basis.iter().filter(|a| !a.is_regression).count(),
            size: basis
                .iter()
                .map(|a| a.relative_change.abs())
                .fold(0.0, f64::max),
            started_at: basis
                .iter()
                .map(|a| a.started_at.clone())
                .max()
                .unwrap_or_default(),
            detected_at: basis
                .iter()
                .map(|a| a.detected_at.clone())
                .max()
                .unwrap_or_default(),
            alerts: Vec::new(),
        };
        if filter.state.as_ref().is_some_and(|s| s != &group.state) {
            continue;
        }
        let mut shown: Vec<Alert> = members.into_iter().filter(|a| filter.shows(a)).collect();
        if shown.is_empty() {
            continue;
        }
        shown.sort_by(|x, y| {
            y.relative_change
                .abs()
                .total_cmp(&x.relative_change.abs())
                .then(x.id.cmp(&y.id))
        });
        group.alerts = shown;
        out.push(group);
    }
    out
}

/// The groups matching `filter`, sorted, at most `limit`.
pub fn list(
    conn: &mut dyn Connection,
    filter: &Filter,
    sort: Sort,
    limit: usize,
) -> Result<Vec<Group>, StoreError> {
    filter.validate()?;
    let mut groups = build(alerts(conn, None, MAX_ALERTS)?, filter);
    sort_groups(&mut groups, sort);
    groups.truncate(limit);
    Ok(groups)
}

/// One group with all its alerts (withdrawn ones included).
pub fn get(conn: &mut dyn Connection, key: &str) -> Result<Group, StoreError> {
    let not_found = || StoreError::NotFound(format!("alert group {key:?}"));
    let parsed = parse_key(key).ok_or_else(not_found)?;
    let all = alerts(conn, Some(&parsed), MAX_ALERTS)?;
    let filter = Filter {
        status: Some("all".into()),
        ..Filter::default()
    };
    build(all, &filter)
        .into_iter()
        .find(|g| g.key == key)
        .ok_or_else(not_found)
}

/// Ids of the alerts of group `key` (withdrawn ones included), for triage.
pub fn alert_ids(conn: &mut dyn Connection, key: &str) -> Result<Vec<i64>, StoreError> {
    let parsed =
        parse_key(key).ok_or_else(|| StoreError::NotFound(format!("alert group {key:?}")))?;
    Ok(alerts(conn, Some(&parsed), MAX_ALERTS)?
        .into_iter()
        .filter(|a| a.group_key() == key)
        .map(|a| a.id)
        .collect())
}

/// Values the filters can take: adapters (id, name), suites and measures that have alerts.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct Facets {
    pub adapters: Vec<(i64, String)>,
    pub suites: Vec<String>,
    pub measures: Vec<String>,
}

/// The groups matching `filter` and the filter's choices, from one read of the alerts.
pub fn list_with_facets(
    conn: &mut dyn Connection,
    filter: &Filter,
    sort: Sort,
    limit: usize,
) -> Result<(Vec<Group>, Facets), StoreError> {
    filter.validate()?;
    let all = alerts(conn, None, MAX_ALERTS)?;
    let mut adapters = BTreeSet::new();
    let mut suites = BTreeSet::new();
    let mut measures = BTreeSet::new();
    for a in &all {
        adapters.insert((a.series.adapter_id, a.series.adapter.clone()));
        suites.insert(a.suite.clone());
        measures.insert(a.series.measure.clone());
    }
    let facets = Facets {
        adapters: adapters.into_iter().collect(),
        suites: suites.into_iter().collect(),
        measures: measures.into_iter().collect(),
    };
    let mut groups = build(all, filter);
    sort_groups(&mut groups, sort);
    groups.truncate(limit);
    Ok((groups, facets))
}

fn sort_groups(groups: &mut [Group], sort: Sort) {
    match sort {
        Sort::Date => groups.sort_by(|x, y| {
            y.started_at
                .cmp(&x.started_at)
                .then(y.detected_at.cmp(&x.detected_at))
                .then(x.key.cmp(&y.key))
        }),
        Sort::Size => groups.sort_by(|x, y| y.size.total_cmp(&x.size).then(x.key.cmp(&y.key))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_round_trip_and_refuse_junk() {
        let k = key(Some("abc123"), 1, Some("def456"), 2);
        assert_eq!(k, "abc123..def456");
        assert_eq!(
            parse_key(&k),
            Some((Side::Commit("abc123".into()), Side::Commit("def456".into())))
        );
        let k = key(None, 7, Some("bad sha/../x"), 9);
        assert_eq!(k, "~7..~9");
        assert_eq!(parse_key(&k), Some((Side::Run(7), Side::Run(9))));
        for junk in ["", "abc", "a..b..c", "~x..a", "a b..c", "../..x"] {
            assert_eq!(parse_key(junk), None, "{junk:?}");
        }
    }

    #[test]
    fn measure_labels() {
        assert_eq!(measure_label("gpu_ms.median"), "gpu_ms");
        assert_eq!(
            measure_label("pass.reconstruct.gpu_ms.median"),
            "reconstruct"
        );
        assert_eq!(measure_label("flip"), "flip");
        assert_eq!(measure_label("pass.a.b.gpu_ms.median"), "a.b");
        assert_eq!(
            measure_label("not-a-measure.median"),
            "not-a-measure.median"
        );
    }
}
