//! Alert groups: the alerts (rows of `regressions`, one per series change) of one change, seen in
//! every series and on every adapter it moved ("`c0ffee`: 12 series on 2 adapters; checkerboard
//! gpu_ms +6.0%, reconstruct +35.0%"), triaged as one. A group has an id for life
//! (`/regressions/groups/{id}`); an alert joins the group its commit range names when it is
//! detected and stays in it when detection moves it, so links, feed entries and webhook keys keep
//! naming the same change. The commit ranges a group was shown under still find it ([`resolve`]).
//!
//! Direction-aware: a group says how many of its series got worse and how many better; a
//! `speedup` series whose baseline variant moved in the same group is counted as *via its
//! baseline*, not as a change of its own (a slower `native` makes every speed-up against it rise).
//!
//! Not for: the alert row and its writes (see [`super::alerts`]), triage writes (see
//! [`super::triage`]), rendering and titles (see [`crate::titles`],
//! [`crate::server::regressions`] and [`crate::notify`]).

use std::collections::{BTreeMap, BTreeSet};

use serde::Serialize;

use super::alerts::{self, Alert, DetectionStatus, Select, TriageState};
use super::baseline_moves::{self, BaselineMove};
use super::StoreError;
use crate::db::Connection;

pub use super::alerts::{has_status_column, is_key, key};

/// Most alerts read for one listing, newest first; older alerts are not grouped.
pub const MAX_ALERTS: i64 = 20_000;

/// A group of alerts with one triage.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Group {
    /// The group's id for life: its page is `/regressions/groups/{id}`.
    pub id: i64,
    /// The commit range it is shown under now: `<commit before>..<commit after>` of most of its
    /// live alerts; a run without a usable commit is `~<run pk>`.
    pub key: String,
    pub commit_before: Option<String>,
    pub commit_after: Option<String>,
    /// `confirmed` when any alert is, else `pending` when any is, else `withdrawn`.
    pub status: DetectionStatus,
    /// The state shared by the alerts; when they differ (an alert joined after triage),
    /// `new` if any alert is new, else the most recently set state, and `mixed_state` is true.
    pub state: TriageState,
    pub mixed_state: bool,
    pub note: String,
    pub bug_url: String,
    pub updated_by: String,
    pub updated_at: String,
    pub adapters: Vec<String>,
    /// Alerts of the group (withdrawn ones left out unless all are withdrawn).
    pub series_count: usize,
    /// Series that got worse and better on their own (not through their baseline).
    pub worse: usize,
    pub better: usize,
    /// Speed-up series that moved only because their baseline did.
    pub via_baseline: usize,
    /// `regression` when any series got worse on its own, else `improvement`.
    pub direction: &'static str,
    /// Largest |relative change| of the group's alerts.
    pub size: f64,
    /// Newest start of a run after the change (the commit's date as the runs saw it).
    pub started_at: String,
    /// Newest detection of one of its alerts.
    pub detected_at: String,
    /// The alerts that match the filter, largest change first.
    pub alerts: Vec<Alert>,
    /// The alerts the group's counts describe, in the store's order: the live ones, or all of
    /// them when none is live. Its title is made from them (see [`crate::titles`]).
    #[serde(skip)]
    pub basis: Vec<Alert>,
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
    /// Only groups in which some series got worse on its own (the feed and the webhook of
    /// confirmed *regressions*: improvements are never announced as regressions).
    pub regressions_only: bool,
}

pub const DIRECTIONS: [&str; 2] = ["worse", "better"];
pub const STATUSES: [&str; 4] = ["pending", "confirmed", "withdrawn", "all"];
/// Longest filter value accepted, in bytes (longer ones are refused with 400, not searched).
pub const MAX_FILTER_LEN: usize = 200;

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
        for (what, v) in [
            ("adapter", &self.adapter.map(|a| a.to_string())),
            ("suite", &self.suite),
            ("measure", &self.measure),
            ("state", &self.state),
            ("direction", &self.direction),
            ("status", &self.status),
        ] {
            if v.as_ref().is_some_and(|v| v.len() > MAX_FILTER_LEN) {
                return Err(StoreError::Invalid(format!(
                    "{what} is longer than {MAX_FILTER_LEN} bytes"
                )));
            }
        }
        check("state", &self.state, &TriageState::names())?;
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

/// Whether a `speedup` alert moved through its baseline: the baseline variant's frame time moved
/// in the same group, on the same scenario and adapter. The baseline is the measure's suffix
/// (`speedup.native-vrs`), else `native`.
fn via_baseline(a: &Alert, group: &[Alert]) -> bool {
    let m = a.series.measure.as_str();
    let Some(rest) = m.strip_prefix("speedup") else {
        return false;
    };
    let baseline = rest
        .strip_prefix('.')
        .filter(|b| !b.is_empty())
        .unwrap_or(tessera_results::measure::DEFAULT_BASELINE);
    group.iter().any(|b| {
        b.series.variant == baseline
            && b.series.scenario == a.series.scenario
            && b.series.adapter_id == a.series.adapter_id
            && b.status != DetectionStatus::Withdrawn
            && (b.series.measure == "gpu_ms.median" || b.series.measure == "cpu_ms.median")
    })
}

/// Builds the groups of `alerts` (in their order: newest first); `filter` picks the alerts
/// listed and the groups kept. `moves`: the speed-up alerts that moved with their baseline
/// ([`baseline_moves::of_alerts`]), whether or not the baseline's alert is in the group.
fn build(all: Vec<Alert>, filter: &Filter, moves: &BTreeMap<i64, BaselineMove>) -> Vec<Group> {
    let mut order: Vec<i64> = Vec::new();
    let mut by_id: BTreeMap<i64, Vec<Alert>> = BTreeMap::new();
    for a in all {
        if !by_id.contains_key(&a.group_id) {
            order.push(a.group_id);
        }
        by_id.entry(a.group_id).or_default().push(a);
    }
    let mut out = Vec::new();
    for id in order {
        let mut members = by_id.remove(&id).unwrap_or_default();
        let flags: Vec<bool> = members.iter().map(|a| via_baseline(a, &members)).collect();
        for (a, f) in members.iter_mut().zip(flags) {
            a.via_baseline = f || moves.contains_key(&a.id);
            if let Some(m) = moves.get(&a.id) {
                a.moved_with = Some(format!(
                    "{} GPU time {}",
                    m.baseline,
                    crate::html::pct(m.baseline_change)
                ));
                a.moved_with_change = Some(m.baseline_change);
            }
        }
        let live: Vec<&Alert> = members
            .iter()
            .filter(|a| a.status != DetectionStatus::Withdrawn)
            .collect();
        let basis: Vec<&Alert> = if live.is_empty() {
            members.iter().collect()
        } else {
            live
        };
        // The range most of its live alerts are at now (ties: the newest alert's).
        let mut ranges: BTreeMap<String, (usize, usize)> = BTreeMap::new();
        for (i, a) in basis.iter().enumerate() {
            let e = ranges.entry(a.group_key()).or_insert((0, i));
            e.0 += 1;
        }
        let (key, &(_, at)) = ranges
            .iter()
            .max_by(|x, y| x.1 .0.cmp(&y.1 .0).then(y.1 .1.cmp(&x.1 .1)))
            .expect("a group has alerts");
        let key = key.clone();
        let first = basis[at];
        let states: BTreeSet<TriageState> = basis.iter().map(|a| a.state).collect();
        let latest = basis
            .iter()
            .max_by(|x, y| x.updated_at.cmp(&y.updated_at).then(x.id.cmp(&y.id)))
            .unwrap();
        let state = if states.len() == 1 {
            first.state
        } else if states.contains(&TriageState::New) {
            TriageState::New
        } else {
            latest.state
        };
        let status = [DetectionStatus::Confirmed, DetectionStatus::Pending]
            .into_iter()
            .find(|s| basis.iter().any(|a| a.status == *s))
            .unwrap_or(DetectionStatus::Withdrawn);
        let adapters: BTreeSet<String> = basis.iter().map(|a| a.series.adapter.clone()).collect();
        let own: Vec<&Alert> = basis.iter().copied().filter(|a| !a.via_baseline).collect();
        let worse = own.iter().filter(|a| a.is_regression).count();
        let mut group = Group {
            id,
            key,
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
            worse,
            better: own.len() - worse,
            via_baseline: basis.len() - own.len(),
            direction: if worse > 0 {
                "regression"
            } else {
                "improvement"
            },
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
            basis: basis.iter().map(|&a| a.clone()).collect(),
        };
        if filter
            .state
            .as_ref()
            .is_some_and(|s| s != group.state.as_str())
        {
            continue;
        }
        if filter.regressions_only && group.worse == 0 {
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

fn read_all(conn: &mut dyn Connection, group: Option<i64>) -> Result<Vec<Alert>, StoreError> {
    alerts::read(
        conn,
        Select {
            group,
            limit: MAX_ALERTS,
            ..Select::default()
        },
    )
}

/// The groups matching `filter`, sorted, at most `limit`.
pub fn list(
    conn: &mut dyn Connection,
    filter: &Filter,
    sort: Sort,
    limit: usize,
) -> Result<Vec<Group>, StoreError> {
    filter.validate()?;
    let all = read_all(conn, None)?;
    let moves = baseline_moves::of_alerts(conn, &all)?;
    let mut groups = build(all, filter, &moves);
    sort_groups(&mut groups, sort);
    groups.truncate(limit);
    Ok(groups)
}

/// What a group link names: a group id (`12`), or a commit-range key the group is or was shown
/// under (`c0ffee..beef42`), which the pages redirect to the id.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Named {
    Id(i64),
    Key(i64),
}

impl Named {
    pub fn id(self) -> i64 {
        match self {
            Named::Id(i) | Named::Key(i) => i,
        }
    }
}

/// The group `name` (an id or a key) refers to.
pub fn resolve(conn: &mut dyn Connection, name: &str) -> Result<Named, StoreError> {
    let not_found = || StoreError::NotFound(format!("alert group {name:?}"));
    let named = if let Ok(id) = name.parse::<i64>() {
        if alerts::group_exists(conn, id)? {
            Named::Id(id)
        } else {
            return Err(not_found());
        }
    } else {
        if !is_key(name) {
            return Err(not_found());
        }
        alerts::group_of_key(conn, name)?
            .map(Named::Key)
            .ok_or_else(not_found)?
    };
    // A group whose alerts all moved to other groups names where they went (a redirect).
    let mut id = named.id();
    let mut hops = 0;
    while hops < 16
        && conn
            .query_opt(
                "SELECT 1 FROM regressions WHERE group_id = $1 LIMIT 1",
                &[crate::db::Value::Int(id)],
            )?
            .is_none()
    {
        match alerts::successor(conn, id)? {
            Some(next) if next != id => id = next,
            _ => break,
        }
        hops += 1;
    }
    Ok(if id == named.id() {
        named
    } else {
        Named::Key(id)
    })
}

/// One group with all its alerts (withdrawn ones included), by id.
pub fn get(conn: &mut dyn Connection, id: i64) -> Result<Group, StoreError> {
    let filter = Filter {
        status: Some("all".into()),
        ..Filter::default()
    };
    let all = read_all(conn, Some(id))?;
    let moves = baseline_moves::of_alerts(conn, &all)?;
    build(all, &filter, &moves)
        .into_iter()
        .next()
        .ok_or_else(|| StoreError::NotFound(format!("alert group {id}")))
}

/// One group by id or key (see [`resolve`]).
pub fn get_named(conn: &mut dyn Connection, name: &str) -> Result<Group, StoreError> {
    let id = resolve(conn, name)?.id();
    get(conn, id)
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
    let all = read_all(conn, None)?;
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
    let moves = baseline_moves::of_alerts(conn, &all)?;
    let mut groups = build(all, filter, &moves);
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
                .then(y.id.cmp(&x.id))
        }),
        Sort::Size => groups.sort_by(|x, y| y.size.total_cmp(&x.size).then(y.id.cmp(&x.id))),
    }
}
