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
//! [`super::triage`]), rendering (see [`crate::server::regressions`] and [`crate::notify`]).

use std::collections::{BTreeMap, BTreeSet};

use serde::Serialize;
use tessera_results::measure::Measure;

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
    /// One line: commit, series and adapters, the largest changes by variant and measure.
    pub title: String,
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
    counted_title(commit_after, alerts, alerts, code)
}

/// The title naming the changes of `alerts`, with the series and adapters of `all` counted (so
/// the HTML and the Markdown of a group count the same series).
fn counted_title(commit_after: &str, alerts: &[&Alert], all: &[&Alert], code: bool) -> String {
    // In Markdown, names are code spans, in which nothing can be escaped: backticks and pipes
    // are replaced (names are validated on upload; older stores may hold anything).
    let q = |s: &str| {
        if code {
            format!(
                "`{}`",
                s.replace('`', "'")
                    .replace('|', "¦")
                    .replace(['\n', '\r'], " ")
            )
        } else {
            s.to_string()
        }
    };
    let adapters: BTreeSet<&str> = all.iter().map(|a| a.series.adapter.as_str()).collect();
    let mut t = format!(
        "{}: {} series on {} adapter{}",
        q(commit_after),
        all.len(),
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

/// The title of a group whose only changes are speed-ups that moved with their baseline (the
/// baseline's own alert not detected yet, or in another group): led by the baseline's change.
fn baseline_title(commit_after: &str, alerts: &[&Alert], code: bool) -> Option<String> {
    let q = |s: &str| {
        if code {
            format!("`{s}`")
        } else {
            s.to_string()
        }
    };
    // (baseline, scenario) → (the baseline's changes, the variants whose speed-ups moved).
    type Moved<'a> = BTreeMap<(&'a str, &'a str), (Vec<f64>, BTreeSet<&'a str>)>;
    let mut by_base: Moved = BTreeMap::new();
    for a in alerts {
        let m = a.moved_with_change?;
        let base = baseline_moves::baseline_of(&a.series.measure)?;
        let e = by_base.entry((base, &a.series.scenario)).or_default();
        e.0.push(m);
        e.1.insert(&a.series.variant);
    }
    let adapters: BTreeSet<&str> = alerts.iter().map(|a| a.series.adapter.as_str()).collect();
    let mut parts: Vec<(f64, String)> = by_base
        .into_iter()
        .map(|((base, scenario), (changes, variants))| {
            let m = median(changes);
            (
                m.abs(),
                format!(
                    "{} GPU time {} on {} (the speed-ups of {} moved with it)",
                    q(base),
                    crate::html::pct(m),
                    q(scenario),
                    variants.into_iter().map(q).collect::<Vec<_>>().join(", ")
                ),
            )
        })
        .collect();
    parts.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
    let lead = parts
        .into_iter()
        .map(|p| p.1)
        .collect::<Vec<_>>()
        .join("; ");
    Some(format!(
        "{}: {} series on {} adapter{}; {lead}",
        q(commit_after),
        alerts.len(),
        adapters.len(),
        if adapters.len() == 1 { "" } else { "s" }
    ))
}

/// The one-line title of a group's alerts: led by the changes of their own, else by the
/// baseline change the speed-ups moved with.
pub fn group_title(commit_after: &str, basis: &[&Alert], code: bool) -> String {
    let own: Vec<&Alert> = basis.iter().copied().filter(|a| !a.via_baseline).collect();
    if own.is_empty() {
        if let Some(t) = baseline_title(commit_after, basis, code) {
            return t;
        }
        return title(commit_after, basis, code);
    }
    counted_title(commit_after, &own, basis, code)
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
        let commit_after = crate::html::commit(first.commit_after.as_deref());
        let own: Vec<&Alert> = basis.iter().copied().filter(|a| !a.via_baseline).collect();
        let worse = own.iter().filter(|a| a.is_regression).count();
        let mut group = Group {
            id,
            title: group_title(&commit_after, &basis, false),
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

#[cfg(test)]
mod tests {
    use super::*;

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
