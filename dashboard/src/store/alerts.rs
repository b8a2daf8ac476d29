//! The alert row: one owner for the `regressions` table (one row per detected change of one
//! series), its triage state and detection status as enums, its reader and every write to it.
//! Detection ([`crate::regressions`]) inserts, moves and withdraws alerts through this module;
//! grouping ([`super::groups`]) and triage ([`super::triage`]) read and set them through it, so
//! no other module parses the row.
//!
//! Identities are for life (issue 22, item 2): rows are never deleted (deleting a run re-points
//! the alerts that named it, see [`repoint_for_deleted_run`]), so an alert id is never reused; each
//! alert belongs to one *alert group* (`alert_groups`, rows never deleted either) from its
//! insertion on, and every commit range a group was ever shown under is kept in
//! `alert_group_keys`, so that an old `<commit>..<commit>` link still finds its group.
//!
//! Not for: the statistics (see [`crate::detect`]), building group summaries and titles (see
//! [`super::groups`]), HTTP.

use std::collections::BTreeMap;
use std::fmt;
use std::str::FromStr;

use serde::{Serialize, Serializer};

use super::series::{self, SeriesKey};
use super::StoreError;
use crate::db::{Backend, Connection, Row, Value};

/// What a person decided about an alert (group).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub enum TriageState {
    #[default]
    New,
    Acknowledged,
    Invalid,
    Fixed,
    Ignored,
}

impl TriageState {
    pub const ALL: [TriageState; 5] = [
        TriageState::New,
        TriageState::Acknowledged,
        TriageState::Invalid,
        TriageState::Fixed,
        TriageState::Ignored,
    ];

    pub fn as_str(self) -> &'static str {
        match self {
            TriageState::New => "new",
            TriageState::Acknowledged => "acknowledged",
            TriageState::Invalid => "invalid",
            TriageState::Fixed => "fixed",
            TriageState::Ignored => "ignored",
        }
    }

    /// The words, for messages and pickers.
    pub fn names() -> Vec<&'static str> {
        Self::ALL.iter().map(|s| s.as_str()).collect()
    }
}

impl FromStr for TriageState {
    type Err = StoreError;
    fn from_str(s: &str) -> Result<Self, StoreError> {
        Self::ALL
            .into_iter()
            .find(|t| t.as_str() == s)
            .ok_or_else(|| {
                StoreError::Invalid(format!(
                    "state {s:?} is not one of {}",
                    Self::names().join(", ")
                ))
            })
    }
}

/// What detection says about an alert now.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum DetectionStatus {
    /// Too few runs at the new level yet: shown, not notified, free to move or vanish.
    Pending,
    /// Enough runs at the new level: notified; moves only on strong new evidence.
    Confirmed,
    /// The data no longer supports it (or it merged into another alert); kept with its triage.
    Withdrawn,
}

impl DetectionStatus {
    pub const ALL: [DetectionStatus; 3] = [
        DetectionStatus::Pending,
        DetectionStatus::Confirmed,
        DetectionStatus::Withdrawn,
    ];

    pub fn as_str(self) -> &'static str {
        match self {
            DetectionStatus::Pending => "pending",
            DetectionStatus::Confirmed => "confirmed",
            DetectionStatus::Withdrawn => "withdrawn",
        }
    }
}

impl FromStr for DetectionStatus {
    type Err = StoreError;
    fn from_str(s: &str) -> Result<Self, StoreError> {
        Self::ALL
            .into_iter()
            .find(|t| t.as_str() == s)
            .ok_or_else(|| StoreError::Corrupt(format!("alert status {s:?}")))
    }
}

macro_rules! words {
    ($t:ty) => {
        impl fmt::Display for $t {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(self.as_str())
            }
        }
        impl Serialize for $t {
            fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.serialize_str(self.as_str())
            }
        }
        impl PartialEq<&str> for $t {
            fn eq(&self, o: &&str) -> bool {
                self.as_str() == *o
            }
        }
    };
}
words!(TriageState);
words!(DetectionStatus);

/// One alert with its series, runs, location and triage.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Alert {
    pub id: i64,
    /// The alert group it has belonged to since it was detected (`/regressions/groups/{id}`).
    pub group_id: i64,
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
    /// The interval of the relative change (95%), where detection stored one.
    pub change_low: Option<f64>,
    pub change_high: Option<f64>,
    /// `true` when the change makes the measure worse.
    pub is_regression: bool,
    /// A speed-up that moved because its baseline did (set when grouping, see
    /// [`super::groups`]); not counted as a change of its own.
    pub via_baseline: bool,
    /// For a speed-up that moved with its baseline: the baseline and its frame-time change
    /// (`native GPU time +5.0%`), read from the data (see [`super::baseline_moves`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub moved_with: Option<String>,
    /// The baseline's relative change behind `moved_with`.
    #[serde(skip)]
    pub moved_with_change: Option<f64>,
    /// How sure detection is that *a* change happened (1 − tail probability).
    pub confidence: f64,
    /// How likely the change lies exactly at `run_after` among the candidate splits (0 to 1).
    pub location_probability: Option<f64>,
    /// The first and last candidate run of the change's range (95% of the location
    /// probability), where detection stored them.
    pub first_candidate: Option<String>,
    pub last_candidate: Option<String>,
    pub status: DetectionStatus,
    pub state: TriageState,
    pub note: String,
    pub bug_url: String,
    pub updated_by: String,
    pub detected_at: String,
    pub updated_at: String,
    #[serde(skip)]
    pub run_pk_before: i64,
    #[serde(skip)]
    pub run_pk_after: i64,
}

impl Alert {
    /// The commit range this alert is shown under now (see [`key`]).
    pub fn group_key(&self) -> String {
        key(
            self.commit_before.as_deref(),
            self.run_pk_before,
            self.commit_after.as_deref(),
            self.run_pk_after,
        )
    }
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

/// The commit-range key of an alert: `<commit before>..<commit after>`; a run without a usable
/// commit stands as `~<run pk>`. Keys name where a group *is*; its id names what it *is*.
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

/// Whether `k` has the shape of a commit-range key.
pub fn is_key(k: &str) -> bool {
    let ok = |s: &str| match s.strip_prefix('~') {
        Some(pk) => pk.parse::<i64>().is_ok(),
        None => usable_commit(s),
    };
    k.split_once("..")
        .is_some_and(|(b, a)| ok(b) && ok(a) && !a.contains(".."))
}

/// Whether the store has detection's `status` column (added by its own migration). Asks the
/// catalogue, so it never fails a statement (which would abort a PostgreSQL transaction).
pub fn has_status_column(conn: &mut dyn Connection) -> Result<bool, StoreError> {
    let sql = match conn.backend() {
        Backend::Sqlite => {
            "SELECT COUNT(*) FROM pragma_table_info('regressions') WHERE name = 'status'"
        }
        Backend::Postgres => {
            "SELECT COUNT(*) FROM information_schema.columns
             WHERE table_schema = current_schema() AND table_name = 'regressions' AND column_name = 'status'"
        }
    };
    Ok(conn.query(sql, &[])?[0].i64(0)? > 0)
}

/// The SQL for the scenario file of the `scenario_results` row `sr`: a column from the compact
/// schema on; older rows keep it in their JSON.
fn file_of_record(backend: Backend) -> &'static str {
    match backend {
        Backend::Sqlite => "COALESCE(sr.file, json_extract(sr.record_json, '$.file'))",
        Backend::Postgres => {
            "COALESCE(sr.file, CAST(NULLIF(sr.record_json, '') AS JSON) ->> 'file')"
        }
    }
}

/// What a bisection of an alert starts from: its series, commit range, scenario file and adapter.
#[derive(Clone, Debug, PartialEq)]
pub struct BisectTarget {
    pub scenario_file: String,
    pub variant: String,
    pub measure: String,
    pub commit_before: Option<String>,
    pub commit_after: Option<String>,
    pub adapter: String,
}

/// The [`BisectTarget`] of alert `id`.
pub fn bisect_target(conn: &mut dyn Connection, id: i64) -> Result<BisectTarget, StoreError> {
    let file = file_of_record(conn.backend());
    let r = conn
        .query_opt(
            &format!(
                "SELECT {file}, s.variant, s.measure, rb.commit_sha, ra.commit_sha, a.name
                 FROM regressions g JOIN series s ON s.id = g.series_id
                 JOIN runs rb ON rb.id = g.run_pk_before JOIN runs ra ON ra.id = g.run_pk_after
                 JOIN adapters a ON a.id = s.adapter_id
                 LEFT JOIN scenario_results sr ON sr.run_pk = ra.id AND sr.scenario = s.scenario
                 WHERE g.id = $1"
            ),
            &[Value::Int(id)],
        )?
        .ok_or_else(|| StoreError::NotFound(format!("alert {id}")))?;
    Ok(BisectTarget {
        scenario_file: r.opt_string(0)?.unwrap_or_default(),
        variant: r.string(1)?,
        measure: r.string(2)?,
        commit_before: r.opt_string(3)?,
        commit_after: r.opt_string(4)?,
        adapter: r.string(5)?,
    })
}

/// Each alerted scenario's newest record's file: one seek of `scenario_results (scenario, id)`
/// per scenario (schema step 12).
fn suites_sql(backend: Backend) -> String {
    format!(
        "SELECT sr.scenario, {} FROM scenario_results sr
         WHERE sr.id IN (SELECT (SELECT MAX(x.id) FROM scenario_results x WHERE x.scenario = d.scenario)
                         FROM (SELECT DISTINCT s.scenario FROM regressions g JOIN series s ON s.id = g.series_id) d)",
        file_of_record(backend)
    )
}

/// The suite of each scenario that has alerts: the folder of its newest scenario file (one JSON
/// read per scenario, not per alert).
fn suites(conn: &mut dyn Connection) -> Result<BTreeMap<String, String>, StoreError> {
    let rows = conn.query(&suites_sql(conn.backend()), &[])?;
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

/// Which alerts [`read`] returns.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Select {
    /// Only this group's.
    pub group: Option<i64>,
    /// Only this series'.
    pub series: Option<i64>,
    /// Only this one.
    pub id: Option<i64>,
    /// Leave withdrawn alerts out.
    pub live_only: bool,
    /// Most rows, newest run after the change first.
    pub limit: i64,
}

/// Alerts, newest first: the one reader of the row.
pub fn read(conn: &mut dyn Connection, sel: Select) -> Result<Vec<Alert>, StoreError> {
    assign_missing_groups(conn)?;
    let suites = suites(conn)?;
    let rows = conn.query(
        "SELECT s.id, s.scenario, s.variant, s.adapter_id, a.name, s.measure, s.higher_is_better,
            g.id, g.run_pk_before, rb.run_id, rb.commit_sha, g.run_pk_after, ra.run_id, ra.commit_sha,
            ra.started_at, g.value_before, g.value_after, g.relative_change, g.confidence,
            g.status, g.state, g.note, g.bug_url, g.updated_by, g.detected_at, g.updated_at,
            g.group_id, g.change_low, g.change_high, g.location_probability, rf.run_id, rl.run_id
         FROM regressions g JOIN series s ON s.id = g.series_id JOIN adapters a ON a.id = s.adapter_id
         JOIN runs rb ON rb.id = g.run_pk_before JOIN runs ra ON ra.id = g.run_pk_after
         LEFT JOIN runs rf ON rf.id = g.first_candidate LEFT JOIN runs rl ON rl.id = g.last_candidate
         WHERE (CAST($1 AS BIGINT) IS NULL OR g.group_id = $1)
           AND (CAST($2 AS BIGINT) IS NULL OR g.series_id = $2)
           AND (CAST($3 AS BIGINT) IS NULL OR g.id = $3)
           AND (CAST($4 AS BIGINT) = 0 OR g.status <> 'withdrawn')
         ORDER BY ra.started_at DESC, g.id DESC LIMIT $5",
        &[
            sel.group.into(),
            sel.series.into(),
            sel.id.into(),
            Value::Int(sel.live_only.into()),
            Value::Int(sel.limit),
        ],
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
        group_id: r.i64(26)?,
        is_regression: (relative_change > 0.0) != series.higher_is_better,
        via_baseline: false,
        moved_with: None,
        moved_with_change: None,
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
        status: r.str(19)?.parse()?,
        state: r.str(20)?.parse().map_err(|_| {
            StoreError::Corrupt(format!("alert triage state {:?}", r.str(20).unwrap_or("")))
        })?,
        note: r.string(21)?,
        bug_url: r.string(22)?,
        updated_by: r.string(23)?,
        detected_at: r.string(24)?,
        updated_at: r.string(25)?,
        change_low: r.opt_f64(27)?,
        change_high: r.opt_f64(28)?,
        location_probability: r.opt_f64(29)?,
        first_candidate: r.opt_string(30)?,
        last_candidate: r.opt_string(31)?,
        series,
    })
}

// ---------------------------------------------------------------------------------------------
// Groups: identity and keys.

fn key_of_runs(conn: &mut dyn Connection, before: i64, after: i64) -> Result<String, StoreError> {
    let rows = conn.query(
        "SELECT id, commit_sha FROM runs WHERE id = $1 OR id = $2",
        &[Value::Int(before), Value::Int(after)],
    )?;
    let mut commits = BTreeMap::new();
    for r in &rows {
        commits.insert(r.i64(0)?, r.opt_string(1)?);
    }
    let c = |pk: i64| commits.get(&pk).cloned().flatten();
    Ok(key(
        c(before).as_deref(),
        before,
        c(after).as_deref(),
        after,
    ))
}

/// The group a commit-range key names: the one it was first recorded for.
pub fn group_of_key(conn: &mut dyn Connection, k: &str) -> Result<Option<i64>, StoreError> {
    assign_missing_groups(conn)?;
    conn.query_opt(
        "SELECT group_id FROM alert_group_keys WHERE key = $1",
        &[k.into()],
    )?
    .map(|r| r.i64(0))
    .transpose()
    .map_err(Into::into)
}

/// Every key group `id` was shown under, oldest first.
pub fn keys_of_group(conn: &mut dyn Connection, id: i64) -> Result<Vec<String>, StoreError> {
    conn.query(
        "SELECT key FROM alert_group_keys WHERE group_id = $1 ORDER BY created_at, key",
        &[Value::Int(id)],
    )?
    .iter()
    .map(|r| r.string(0).map_err(Into::into))
    .collect()
}

/// Whether group `id` exists (it may have no alerts left to show).
pub fn group_exists(conn: &mut dyn Connection, id: i64) -> Result<bool, StoreError> {
    Ok(conn
        .query_opt(
            "SELECT id FROM alert_groups WHERE id = $1",
            &[Value::Int(id)],
        )?
        .is_some())
}

/// Records that `group` is (also) shown under `k`; a key already recorded keeps its group.
fn remember_key(conn: &mut dyn Connection, k: &str, group: i64) -> Result<(), StoreError> {
    conn.execute(
        "INSERT INTO alert_group_keys (key, group_id, created_at) VALUES ($1, $2, $3) ON CONFLICT DO NOTHING",
        &[k.into(), Value::Int(group), crate::now_rfc3339().into()],
    )?;
    Ok(())
}

/// The group for a new alert at `k`: the group the key names, else a new one.
fn group_for_key(conn: &mut dyn Connection, k: &str) -> Result<i64, StoreError> {
    if let Some(row) = conn.query_opt(
        "SELECT group_id FROM alert_group_keys WHERE key = $1",
        &[k.into()],
    )? {
        return Ok(row.i64(0)?);
    }
    let row = conn.query(
        "INSERT INTO alert_groups (created_at) VALUES ($1) RETURNING id",
        &[crate::now_rfc3339().into()],
    )?;
    let id = row[0].i64(0)?;
    remember_key(conn, k, id)?;
    Ok(id)
}

/// Gives a group to the alerts stored before groups had ids (by their commit range, as they were
/// grouped then). A no-op, one indexed count, on a store where every alert has one.
pub fn assign_missing_groups(conn: &mut dyn Connection) -> Result<(), StoreError> {
    let missing = conn.query(
        "SELECT id, run_pk_before, run_pk_after FROM regressions WHERE group_id IS NULL ORDER BY id",
        &[],
    )?;
    for r in &missing {
        let (id, before, after) = (r.i64(0)?, r.i64(1)?, r.i64(2)?);
        let k = key_of_runs(conn, before, after)?;
        let group = group_for_key(conn, &k)?;
        conn.execute(
            "UPDATE regressions SET group_id = $1 WHERE id = $2 AND group_id IS NULL",
            &[Value::Int(group), Value::Int(id)],
        )?;
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Detection's writes.

/// A stored alert as detection's reconciliation sees it.
#[derive(Clone, Debug, PartialEq)]
pub struct StoredAlert {
    pub id: i64,
    pub run_pk_before: i64,
    pub run_pk_after: i64,
    pub relative_change: f64,
    pub status: DetectionStatus,
}

fn stored(r: &Row, at: usize) -> Result<StoredAlert, StoreError> {
    Ok(StoredAlert {
        id: r.i64(at)?,
        run_pk_before: r.i64(at + 1)?,
        run_pk_after: r.i64(at + 2)?,
        relative_change: r.opt_f64(at + 3)?.unwrap_or(f64::INFINITY),
        status: r.str(at + 4)?.parse()?,
    })
}

/// The stored alerts of one series.
pub fn of_series(
    conn: &mut dyn Connection,
    series_id: i64,
) -> Result<Vec<StoredAlert>, StoreError> {
    conn.query(
        "SELECT id, run_pk_before, run_pk_after, relative_change, status FROM regressions WHERE series_id = $1",
        &[Value::Int(series_id)],
    )?
    .iter()
    .map(|r| stored(r, 0))
    .collect()
}

/// The stored alerts of the series `ids`, by series: one query per 500 series for an upload
/// instead of one per series.
pub fn of_series_in(
    conn: &mut dyn Connection,
    ids: &[i64],
) -> Result<std::collections::HashMap<i64, Vec<StoredAlert>>, StoreError> {
    let mut out: std::collections::HashMap<i64, Vec<StoredAlert>> = Default::default();
    for chunk in ids.chunks(500) {
        let marks: Vec<String> = (1..=chunk.len()).map(|i| format!("${i}")).collect();
        let params: Vec<Value> = chunk.iter().map(|&id| Value::Int(id)).collect();
        for r in conn.query(
            &format!(
                "SELECT series_id, id, run_pk_before, run_pk_after, relative_change, status FROM regressions
                 WHERE series_id IN ({})",
                marks.join(", ")
            ),
            &params,
        )? {
            out.entry(r.i64(0)?).or_default().push(stored(&r, 1)?);
        }
    }
    Ok(out)
}

/// How an alert's history names run `pk`: its short commit and run id.
pub fn run_label(conn: &mut dyn Connection, pk: i64) -> Result<String, StoreError> {
    let row = conn.query(
        "SELECT run_id, commit_sha FROM runs WHERE id = $1",
        &[Value::Int(pk)],
    )?;
    Ok(match row.first() {
        Some(r) => match r.opt_string(1)? {
            Some(sha) => format!("{} ({})", &sha[..sha.len().min(7)], r.str(0)?),
            None => r.string(0)?,
        },
        None => format!("run {pk}"),
    })
}

/// Where detection places a change and how sure it is.
#[derive(Clone, Debug, PartialEq)]
pub struct Placement {
    pub run_pk_before: i64,
    pub run_pk_after: i64,
    pub value_before: f64,
    pub value_after: f64,
    /// Stored finite (a change from 0 is stored as ±1e300).
    pub relative_change: f64,
    pub change_low: f64,
    pub change_high: f64,
    pub confidence: f64,
    pub location_probability: f64,
    pub first_candidate: i64,
    pub last_candidate: i64,
    pub status: DetectionStatus,
}

/// The group key of a placement: the commit the series itself locates the change at (its runs
/// before and after the change), never the candidate range around it. Two series join one group
/// only when each places the change on the same commit; a candidate range that merely overlaps
/// another series' commit (a noisy CPU adapter's 95% range over the night a GPU located exactly)
/// names no group of its own, so it cannot pull a series of another commit in with it.
fn own_key(conn: &mut dyn Connection, p: &Placement) -> Result<String, StoreError> {
    key_of_runs(conn, p.run_pk_before, p.run_pk_after)
}

fn placement_values(p: &Placement) -> Vec<Value> {
    let fin = |v: f64| Value::Real(v.clamp(-1e300, 1e300));
    vec![
        Value::Int(p.run_pk_before),
        Value::Int(p.run_pk_after),
        Value::Real(p.value_before),
        Value::Real(p.value_after),
        fin(p.relative_change),
        Value::Real(p.confidence),
        p.status.as_str().into(),
        fin(p.change_low),
        fin(p.change_high),
        Value::Real(p.location_probability),
        Value::Int(p.first_candidate),
        Value::Int(p.last_candidate),
    ]
}

/// A new alert; it joins the group its commit range names (taking the group's triage, so a change
/// detected again keeps what people said about it), else a new group. Returns its id.
pub fn insert(conn: &mut dyn Connection, series_id: i64, p: &Placement) -> Result<i64, StoreError> {
    let k = own_key(conn, p)?;
    let group = group_for_key(conn, &k)?;
    let now = crate::now_rfc3339();
    let mut params = placement_values(p);
    params.extend([
        Value::Int(series_id),
        Value::Int(group),
        now.as_str().into(),
    ]);
    let id = conn.query(
        "INSERT INTO regressions (run_pk_before, run_pk_after, value_before, value_after, relative_change,
             confidence, status, change_low, change_high, location_probability, first_candidate,
             last_candidate, series_id, group_id, detected_at, updated_at, state, note)
         VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12, $13, $14, $15, $15, 'new', '')
         RETURNING id",
        &params,
    )?[0]
        .i64(0)?;
    // The group's triage, when people already triaged it.
    if let Some(t) = conn.query_opt(
        "SELECT state, note, bug_url, updated_by, updated_at FROM regressions
         WHERE group_id = $1 AND id <> $2 AND updated_by <> '' ORDER BY updated_at DESC, id DESC LIMIT 1",
        &[Value::Int(group), Value::Int(id)],
    )? {
        conn.execute(
            "UPDATE regressions SET state = $1, note = $2, bug_url = $3, updated_by = $4, updated_at = $5 WHERE id = $6",
            &[
                t.string(0)?.into(),
                t.string(1)?.into(),
                t.string(2)?.into(),
                t.string(3)?.into(),
                t.string(4)?.into(),
                Value::Int(id),
            ],
        )?;
    }
    Ok(id)
}

/// Alert `id` now describes placement `p` (the same row: its triage stays). A new commit range is
/// remembered as one of its group's keys. An alert that moves to another commit range leaves a
/// group whose other alerts stay where they were ([`regroup_target`]): a change placed a night
/// early and moved the next night joins the change it belongs to instead of staying for good in
/// the other.
pub fn place(conn: &mut dyn Connection, id: i64, p: &Placement) -> Result<(), StoreError> {
    let old = conn.query_opt(
        "SELECT group_id, run_pk_before, run_pk_after FROM regressions WHERE id = $1",
        &[Value::Int(id)],
    )?;
    let mut params = placement_values(p);
    params.push(Value::Int(id));
    conn.execute(
        "UPDATE regressions SET run_pk_before = $1, run_pk_after = $2, value_before = $3, value_after = $4,
             relative_change = $5, confidence = $6, status = $7, change_low = $8, change_high = $9,
             location_probability = $10, first_candidate = $11, last_candidate = $12
         WHERE id = $13",
        &params,
    )?;
    let k = own_key(conn, p)?;
    let Some(row) = old else {
        return Ok(());
    };
    let Some(g) = row.opt_i64(0)? else {
        return Ok(());
    };
    // Staying at its located commit (the one its group was recorded under).
    let named = conn
        .query_opt(
            "SELECT group_id FROM alert_group_keys WHERE key = $1",
            &[k.as_str().into()],
        )?
        .map(|r| r.i64(0))
        .transpose()?;
    let target = if named == Some(g) {
        g
    } else {
        regroup_target(conn, id, g, &k)?
    };
    if target != g {
        conn.execute(
            "UPDATE regressions SET group_id = $1 WHERE id = $2",
            &[Value::Int(target), Value::Int(id)],
        )?;
        event(
            conn,
            id,
            "regrouped",
            format!("left group {g} for group {target} (moved to {k})"),
        )?;
    }
    remember_key(conn, &k, target)?;
    Ok(())
}

/// The group alert `id` (in group `g`) belongs to after moving to commit range `k`: the group the
/// range names, else the group an earlier alert of `g` moved to at `k`, else a new group when
/// other live alerts of `g` stay at other ranges, else `g` (a group that moves as a whole keeps
/// its id).
fn regroup_target(conn: &mut dyn Connection, id: i64, g: i64, k: &str) -> Result<i64, StoreError> {
    if let Some(r) = conn.query_opt(
        "SELECT group_id FROM alert_group_keys WHERE key = $1",
        &[k.into()],
    )? {
        let named = r.i64(0)?;
        if named != g {
            return Ok(named);
        }
    }
    let moved = format!("left group {g} for group %(moved to {k})");
    if let Some(r) = conn.query_opt(
        "SELECT e.detail FROM regression_events e WHERE e.kind = 'regrouped' AND e.detail LIKE $1
         ORDER BY e.id DESC LIMIT 1",
        &[moved.as_str().into()],
    )? {
        if let Some(to) = group_in_detail(&r.string(0)?) {
            return Ok(to);
        }
    }
    let others = conn.query(
        "SELECT run_pk_before, run_pk_after FROM regressions
         WHERE group_id = $1 AND id <> $2 AND status <> 'withdrawn'",
        &[Value::Int(g), Value::Int(id)],
    )?;
    for r in &others {
        if key_of_runs(conn, r.i64(0)?, r.i64(1)?)? != k {
            return Ok(conn.query(
                "INSERT INTO alert_groups (created_at) VALUES ($1) RETURNING id",
                &[crate::now_rfc3339().into()],
            )?[0]
                .i64(0)?);
        }
    }
    Ok(g)
}

/// The group a `regrouped` event's detail names as the new one.
fn group_in_detail(detail: &str) -> Option<i64> {
    let rest = detail.split_once(" for group ")?.1;
    rest.split_whitespace().next()?.parse().ok()
}

/// Where the alerts of group `id` went when all of them moved to other groups: the newest group
/// one of them joined (`None` when none left it).
pub fn successor(conn: &mut dyn Connection, id: i64) -> Result<Option<i64>, StoreError> {
    let left = format!("left group {id} for group %");
    Ok(conn
        .query_opt(
            "SELECT detail FROM regression_events WHERE kind = 'regrouped' AND detail LIKE $1
             ORDER BY id DESC LIMIT 1",
            &[left.as_str().into()],
        )?
        .map(|r| r.string(0))
        .transpose()?
        .and_then(|d| group_in_detail(&d)))
}

/// Sets detection's status of alert `id`.
pub fn set_status(
    conn: &mut dyn Connection,
    id: i64,
    status: DetectionStatus,
) -> Result<(), StoreError> {
    conn.execute(
        "UPDATE regressions SET status = $1 WHERE id = $2",
        &[status.as_str().into(), Value::Int(id)],
    )?;
    Ok(())
}

/// Kinds of `regression_events`.
pub const EVENTS: [&str; 10] = [
    "detected",
    "moved",
    "merged",
    "withdrawn",
    "confirmed",
    "pending",
    "reinstated",
    "repointed",
    // A bisection of the alert's range ended (`ab/bisect.rs`): its culprit or why none.
    "bisected",
    "regrouped",
];

/// Appends to alert `id`'s history.
pub fn event(
    conn: &mut dyn Connection,
    id: i64,
    kind: &str,
    detail: String,
) -> Result<(), StoreError> {
    debug_assert!(EVENTS.contains(&kind), "{kind}");
    conn.execute(
        "INSERT INTO regression_events (regression_id, at, kind, detail) VALUES ($1, $2, $3, $4)",
        &[
            Value::Int(id),
            crate::now_rfc3339().into(),
            kind.into(),
            detail.into(),
        ],
    )?;
    Ok(())
}

/// One entry of an alert's history.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Event {
    pub alert: i64,
    pub at: String,
    pub kind: String,
    pub detail: String,
}

/// The history of the alerts of group `group`, oldest first.
pub fn events_of_group(conn: &mut dyn Connection, group: i64) -> Result<Vec<Event>, StoreError> {
    conn.query(
        "SELECT e.regression_id, e.at, e.kind, e.detail FROM regression_events e
         JOIN regressions g ON g.id = e.regression_id WHERE g.group_id = $1 ORDER BY e.id",
        &[Value::Int(group)],
    )?
    .iter()
    .map(|r| {
        Ok(Event {
            alert: r.i64(0)?,
            at: r.string(1)?,
            kind: r.string(2)?,
            detail: r.string(3)?,
        })
    })
    .collect()
}

/// Before run `run_pk` is deleted: every alert that names it as its run before or after the change
/// is re-pointed to the nearest remaining point of its series on that side (or, with none left on
/// that side, withdrawn and pointed at its other run), so that the alert, its id, its group and
/// its triage outlive the run. Returns how many alerts were re-pointed.
pub fn repoint_for_deleted_run(conn: &mut dyn Connection, run_pk: i64) -> Result<u64, StoreError> {
    let rows = conn.query(
        "SELECT id, series_id, run_pk_before, run_pk_after FROM regressions
         WHERE run_pk_before = $1 OR run_pk_after = $1 ORDER BY id",
        &[Value::Int(run_pk)],
    )?;
    let mut n = 0;
    for r in &rows {
        let (id, series, before, after) = (r.i64(0)?, r.i64(1)?, r.i64(2)?, r.i64(3)?);
        let neighbour =
            |conn: &mut dyn Connection, later: bool| series::neighbour(conn, series, run_pk, later);
        let (new_before, new_after, lost) = if after == run_pk {
            match neighbour(conn, true)? {
                Some(a) if a != before => (before, a, false),
                _ => (before, before, true),
            }
        } else {
            match neighbour(conn, false)? {
                Some(b) if b != after => (b, after, false),
                _ => (after, after, true),
            }
        };
        conn.execute(
            "UPDATE regressions SET run_pk_before = $1, run_pk_after = $2 WHERE id = $3",
            &[
                Value::Int(new_before),
                Value::Int(new_after),
                Value::Int(id),
            ],
        )?;
        if lost {
            set_status(conn, id, DetectionStatus::Withdrawn)?;
        }
        event(
            conn,
            id,
            "repointed",
            format!(
                "run {run_pk} was deleted; the alert now lies between runs {new_before} and {new_after}{}",
                if lost { " and is withdrawn: no point is left on that side" } else { "" }
            ),
        )?;
        n += 1;
    }
    // A candidate range that named the run shrinks to the alert's own run after the change.
    for col in ["first_candidate", "last_candidate"] {
        conn.execute(
            &format!("UPDATE regressions SET {col} = run_pk_after WHERE {col} = $1"),
            &[Value::Int(run_pk)],
        )?;
    }
    Ok(n)
}

// ---------------------------------------------------------------------------------------------
// Triage's writes.

/// What triage sets on alerts.
#[derive(Clone, Debug, PartialEq)]
pub struct TriageSet<'a> {
    pub state: TriageState,
    pub note: &'a str,
    /// `None` keeps each alert's bug link.
    pub bug_url: Option<&'a str>,
    pub who: &'a str,
}

/// Sets triage on alert `id`; `false` when there is no such alert.
pub fn set_triage(conn: &mut dyn Connection, id: i64, t: &TriageSet) -> Result<bool, StoreError> {
    let n = conn.execute(
        "UPDATE regressions SET state = $1, note = $2, bug_url = COALESCE(CAST($3 AS TEXT), bug_url),
             updated_by = $4, updated_at = $5 WHERE id = $6",
        &[
            t.state.as_str().into(),
            t.note.into(),
            t.bug_url.map(str::to_string).into(),
            t.who.into(),
            crate::now_rfc3339().into(),
            Value::Int(id),
        ],
    )?;
    Ok(n > 0)
}

/// Sets triage on every alert of group `group` (withdrawn ones included); returns how many.
pub fn set_group_triage(
    conn: &mut dyn Connection,
    group: i64,
    t: &TriageSet,
) -> Result<usize, StoreError> {
    let n = conn.execute(
        "UPDATE regressions SET state = $1, note = $2, bug_url = COALESCE(CAST($3 AS TEXT), bug_url),
             updated_by = $4, updated_at = $5 WHERE group_id = $6",
        &[
            t.state.as_str().into(),
            t.note.into(),
            t.bug_url.map(str::to_string).into(),
            t.who.into(),
            crate::now_rfc3339().into(),
            Value::Int(group),
        ],
    )?;
    Ok(n as usize)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scenarios_newest_record_is_a_seek_not_a_scan_of_every_record() {
        let pool = crate::db::open(":memory:").unwrap();
        let mut c = pool.get().unwrap();
        let plan: Vec<String> = c
            .query(
                &format!("EXPLAIN QUERY PLAN {}", suites_sql(Backend::Sqlite)),
                &[],
            )
            .unwrap()
            .iter()
            .map(|r| r.string(3).unwrap())
            .collect();
        let plan = plan.join("\n");
        assert!(
            plan.contains("SEARCH x USING COVERING INDEX scenario_results_scenario (scenario=?)"),
            "{plan}"
        );
        assert!(!plan.contains("SCAN scenario_results"), "{plan}");
        assert!(!plan.contains("SCAN x"), "{plan}");
    }

    #[test]
    fn keys_have_a_shape() {
        assert_eq!(key(Some("abc123"), 1, Some("def456"), 2), "abc123..def456");
        assert_eq!(key(None, 7, Some("bad sha/../x"), 9), "~7..~9");
        assert!(is_key("abc123..def456"));
        assert!(is_key("~7..~9"));
        for junk in ["", "abc", "a..b..c", "~x..a", "a b..c", "../..x", "12"] {
            assert!(!is_key(junk), "{junk:?}");
        }
    }

    #[test]
    fn words_round_trip() {
        for s in TriageState::ALL {
            assert_eq!(s.as_str().parse::<TriageState>().unwrap(), s);
        }
        for s in DetectionStatus::ALL {
            assert_eq!(s.as_str().parse::<DetectionStatus>().unwrap(), s);
        }
        let e = "closed".parse::<TriageState>().unwrap_err().to_string();
        assert_eq!(
            e,
            "state \"closed\" is not one of new, acknowledged, invalid, fixed, ignored"
        );
        assert_eq!(
            serde_json::to_string(&DetectionStatus::Pending).unwrap(),
            "\"pending\""
        );
    }
}
