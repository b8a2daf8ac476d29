//! The regressions pages: the list of alert groups with filters and one triage form per group,
//! and one group's page with its charts and the history of its alerts; their form posts for
//! browsers without JavaScript.
//! Not for: JSON (see [`super::api`]), the feed or Markdown.

use std::fmt::Write;

use axum::extract::{Path, Query, State};
use axum::http::HeaderMap;
use axum::response::{Html, IntoResponse, Redirect, Response};
use axum::Form;
use serde::Deserialize;

use super::api::{apply, apply_group, AlertTriage};
use super::{load_groups, GroupsQuery};
use crate::html::{commit, enc, esc, name, num, page as layout, pct};
use crate::server::{auth, AppError, AppState};
use crate::store::alerts::{self, Alert, DetectionStatus, Event, TriageState};
use crate::store::groups::{self, Facets, Group, Named, DIRECTIONS};
use crate::store::read;
use crate::svg::{series_chart, SeriesMark};

/// The form of a group without JavaScript: the token comes as a field.
#[derive(Debug, Deserialize)]
pub struct GroupForm {
    pub state: String,
    #[serde(default)]
    pub note: String,
    #[serde(default)]
    pub bug_url: String,
    #[serde(default)]
    pub token: String,
}

/// `POST /regressions/groups/{key}` (form): the same as the JSON triage, then back to the list.
pub async fn group_form(
    State(state): State<AppState>,
    Path(key): Path<String>,
    Form(f): Form<GroupForm>,
) -> Result<Redirect, AppError> {
    let who = auth::form_writer(&state, &f.token)?.name;
    let t = crate::store::triage::Triage {
        state: f.state,
        note: f.note,
        bug_url: f.bug_url,
    };
    let (id, _) = apply_group(&state, key, t, who).await?;
    Ok(Redirect::to(&format!("/regressions#g-{id}")))
}

/// The page's own style and script: kept here so the page does not depend on the shared sheet.
const STYLE: &str = "<style>
#tokenbar{background:#f6f6f1;border:1px solid #ddd;padding:6px 10px;margin:8px 0;display:flex;gap:8px;align-items:center;flex-wrap:wrap}
#filters{margin:8px 0}#filters label{margin-right:10px;white-space:nowrap}#filters select{max-width:220px}
#regressions{width:100%}#regressions tbody.group>tr.head>td{background:#f3f5f8;border-top:2px solid #1d2733;padding:8px 8px 6px}
.group h2{font-size:15px;margin:0 0 4px;font-weight:600}.group h2 a{color:#1d2733;text-decoration:none}.group h2 a:hover{text-decoration:underline}
.meta{margin:2px 0 6px;color:#444}.meta code{background:#e8ebf0;padding:0 3px}
.chg{display:inline-block;white-space:nowrap;min-width:84px;padding:0 6px;border-radius:3px;font-weight:600;font-variant-numeric:tabular-nums;text-align:right}
.chg.worse{background:#fde8e6;color:#a1140f}.chg.better{background:#e2f3e7;color:#0d6b2c}
.pivot td{vertical-align:top}.pivot a.via{color:#555}.chg.via{background:#eceff3;color:#444;white-space:normal}.count.worse{color:#a1140f;font-weight:600}.count.better{color:#0d6b2c;font-weight:600}
.badge{display:inline-block;padding:0 7px;border-radius:9px;font-size:12px;border:1px solid #aaa;background:#fff}
.st-new{background:#fff3d1;border-color:#d9a521}.st-acknowledged{background:#e3ebfb;border-color:#6f93dd}
.st-fixed{background:#e2f3e7;border-color:#5aa772}.st-invalid,.st-ignored{background:#eee;color:#555}
.stat-pending{border-style:dashed;color:#7a5a00}.stat-withdrawn{color:#777;text-decoration:line-through}
form.triage{margin:4px 0 0}form.triage input[name=note]{width:260px}form.triage input[name=bug_url]{width:220px}
.result{margin-left:8px}.result.ok{color:#17803d}.result.failed{color:#b3261e}
tr.series-row td{font-size:13px}tr.series-row.stat-withdrawn td{color:#888}
.charts h3{font-size:14px;margin:16px 0 2px}.group h2{overflow-wrap:anywhere}#events td:last-child{overflow-wrap:anywhere;min-width:12em}
@media (max-width:700px){#regressions,#regressions tbody,#regressions tr,#regressions td{display:block;width:auto}
#regressions{overflow-x:visible}#regressions tr.cols{display:none}#regressions tbody.group>tr.head>td{padding:8px 6px 6px}
#regressions tr.series-row{border-bottom:1px solid #ddd;padding:4px 0}#regressions tr.series-row td{display:inline-block;border:0;padding:1px 8px 1px 0;text-align:left}
#regressions tr.series-row td[data-label]::before{content:attr(data-label) \" \";color:#777;font-size:11px}
form.triage input[name=note],form.triage input[name=bug_url]{width:100%;box-sizing:border-box;margin:2px 0}}
</style>";

/// The pages' script: triage with the token kept for the browser session.
const SCRIPT: &str = "<script src=\"/assets/regressions.js\" defer></script>";

const TOKEN_BAR: &str = "<div id=tokenbar><span id=token-state>write token: needs JavaScript, or give it in each form</span><input id=token type=password size=18 placeholder=\"write token\" autocomplete=off hidden><button type=button id=token-save hidden>use for this session</button><button type=button id=token-forget hidden>forget token</button></div>";

fn select(name: &str, label: &str, current: Option<&str>, options: &[(String, String)]) -> String {
    let mut b = format!("<label>{label} <select name={name}><option value=\"\">all</option>");
    for (value, text) in options {
        let sel = if Some(value.as_str()) == current {
            " selected"
        } else {
            ""
        };
        let _ = write!(
            b,
            "<option value=\"{}\"{sel}>{}</option>",
            esc(value),
            esc(text)
        );
    }
    b.push_str("</select></label>");
    b
}

fn filters_form(q: &GroupsQuery, f: &Facets) -> String {
    let own = |v: &[&str]| -> Vec<(String, String)> {
        v.iter().map(|s| (s.to_string(), s.to_string())).collect()
    };
    let same = |v: &[String]| -> Vec<(String, String)> {
        v.iter().map(|s| (s.clone(), s.clone())).collect()
    };
    let adapters: Vec<(String, String)> = f
        .adapters
        .iter()
        .map(|(id, name)| (id.to_string(), name.clone()))
        .collect();
    let mut b = String::from("<form id=filters method=get action=\"/regressions\">");
    b.push_str(&select(
        "adapter",
        "adapter",
        q.adapter.as_deref(),
        &adapters,
    ));
    b.push_str(&select(
        "suite",
        "suite",
        q.suite.as_deref(),
        &same(&f.suites),
    ));
    b.push_str(&select(
        "measure",
        "measure",
        q.measure.as_deref(),
        &same(&f.measures),
    ));
    b.push_str(&select(
        "state",
        "state",
        q.state.as_deref(),
        &own(&TriageState::names()),
    ));
    b.push_str(&select(
        "direction",
        "direction",
        q.direction.as_deref(),
        &own(&DIRECTIONS),
    ));
    // Status: pending and confirmed by default; "all" also shows withdrawn alerts.
    let _ = write!(
        b,
        "<label>status <select name=status><option value=\"\">pending and confirmed</option>"
    );
    for s in groups::STATUSES {
        let sel = if q.status.as_deref() == Some(s) {
            " selected"
        } else {
            ""
        };
        let _ = write!(b, "<option{sel}>{s}</option>");
    }
    b.push_str("</select></label>");
    let _ = write!(b, "<label>sort <select name=sort>");
    for (v, text) in [("date", "newest first"), ("size", "largest change first")] {
        let sel = if q.sort.as_deref().unwrap_or("date") == v {
            " selected"
        } else {
            ""
        };
        let _ = write!(b, "<option value={v}{sel}>{text}</option>");
    }
    b.push_str(
        "</select></label> <button>apply</button> <a href=\"/regressions\">reset</a></form>",
    );
    b
}

fn change_cell(a: &Alert) -> String {
    if a.via_baseline {
        // Counted on the baseline's change, not as a change of its own.
        return format!(
            "<span class=\"chg via\">{} {} <span class=muted>moved with {}</span></span>",
            if a.relative_change >= 0.0 {
                "▲"
            } else {
                "▼"
            },
            pct(a.relative_change),
            esc(a.moved_with.as_deref().unwrap_or("its baseline"))
        );
    }
    let dir = if a.is_regression { "worse" } else { "better" };
    format!(
        "<span class=\"chg {dir}\">{} {} {dir}</span>",
        if a.relative_change >= 0.0 {
            "▲"
        } else {
            "▼"
        },
        pct(a.relative_change)
    )
}

/// The header row of a group: title, triage, commits, and its form.
fn group_head(g: &Group, b: &mut String, title_link: bool) {
    let key = g.id;
    let name = crate::titles::of(g);
    let title = if title_link {
        format!("<a href=\"/regressions/groups/{key}\">{}</a>", esc(&name))
    } else {
        esc(&name)
    };
    let _ = write!(
        b,
        "<h2>{title}</h2><p class=meta><span class=\"badge st-{}\" data-state-of=\"{}\">{}</span>{} <span class=\"badge stat-{}\">{}</span> · commits <code>{}</code> → <code>{}</code> · <span class=\"count worse\">{} worse</span>, <span class=\"count better\">{} better</span>{} on {} · newest run {} · <a href=\"/regressions/groups/{key}.md\">Markdown</a>",
        esc(g.state.as_str()),
        esc(&g.key),
        esc(g.state.as_str()),
        if g.mixed_state { " <span class=muted>(alerts differ)</span>" } else { "" },
        esc(g.status.as_str()),
        esc(g.status.as_str()),
        esc(&commit(g.commit_before.as_deref())),
        esc(&commit(g.commit_after.as_deref())),
        g.worse,
        g.better,
        if g.via_baseline > 0 {
            format!(
                ", <span class=\"count via\">{} moved with their baseline</span>",
                g.via_baseline
            )
        } else {
            String::new()
        },
        esc(&g.adapters.join(", ")),
        esc(&g.started_at),
    );
    if !g.bug_url.is_empty() {
        let _ = write!(
            b,
            " · bug: <a href=\"{}\" rel=\"noopener noreferrer\">{}</a>",
            esc(&g.bug_url),
            esc(&g.bug_url)
        );
    }
    if !g.updated_by.is_empty() {
        let _ = write!(
            b,
            " · set by {} at {}",
            esc(&g.updated_by),
            esc(&g.updated_at)
        );
    }
    if !g.note.is_empty() {
        let _ = write!(b, "<br>note: {}", esc(&g.note));
    }
    let _ = write!(
        b,
        "</p><form class=triage method=post action=\"/regressions/groups/{key}\" data-group={key} data-key=\"{}\"><select name=state aria-label=state>",
        esc(&g.key)
    );
    for s in TriageState::ALL {
        let sel = if s == g.state { " selected" } else { "" };
        let _ = write!(b, "<option{sel}>{s}</option>");
    }
    let _ = write!(
        b,
        "</select> <input name=note placeholder=note value=\"{}\" maxlength=4000> <input name=bug_url type=url placeholder=\"bug link (https://…)\" value=\"{}\"> <noscript><input name=token type=password size=10 placeholder=token></noscript><button>save for {} series</button><span class=result></span></form>",
        esc(&g.note),
        esc(&g.bug_url),
        g.series_count
    );
}

fn alert_row(a: &Alert, b: &mut String) {
    let _ = write!(
        b,
        "<tr id=r{} class=\"series-row stat-{}\"><td data-label=adapter>{}</td><td data-label=suite>{}</td><td data-label=scenario>{}</td><td data-label=variant>{}</td><td data-label=measure><a href=\"/series/{}\">{}</a></td><td class=n data-label=before>{}</td><td class=n data-label=after>{}</td><td class=n data-label=change title=\"significance of a change: {:.1}%\">{}{}</td><td class=n data-label=located>{}</td><td data-label=status>{}</td></tr>",
        a.id,
        esc(a.status.as_str()),
        esc(&a.series.adapter),
        name(&a.suite),
        name(&a.series.scenario),
        name(&a.series.variant),
        a.series.id,
        name(&a.series.measure),
        num(a.value_before),
        num(a.value_after),
        a.confidence * 100.0,
        change_cell(a),
        super::formats::interval_line(a),
        super::formats::located_cell(a),
        esc(a.status.as_str())
    );
}

const ALERT_HEADER: &str = "<tr class=cols><th>adapter</th><th>suite</th><th>scenario</th><th>variant</th><th>measure (series)</th><th class=n>before</th><th class=n>after</th><th class=n>change (95% interval)</th><th class=n>located</th><th>status</th></tr>";

/// Most series listed under a group on the list page (largest changes first); its own page
/// lists them all, so a change that moved thousands of series keeps the list fast.
const LIST_ROWS: usize = 20;

/// The list page's body.
pub fn render(groups: &[Group], facets: &Facets, q: &GroupsQuery) -> String {
    let mut b = String::from(STYLE);
    b.push_str("<p>Alerts that blame the same commit range are one group, triaged together. <a href=\"/regressions/feed.atom\">Atom feed</a> of confirmed groups · <a href=\"/api/regressions/groups\">JSON</a></p>");
    b.push_str(TOKEN_BAR);
    b.push_str(&filters_form(q, facets));
    let alerts: usize = groups.iter().map(|g| g.alerts.len()).sum();
    let _ = write!(
        b,
        "<p id=count>{} group{} with {} matching series</p>",
        groups.len(),
        if groups.len() == 1 { "" } else { "s" },
        alerts
    );
    b.push_str("<table id=regressions>");
    for g in groups {
        let _ = write!(
            b,
            "<tbody class=group id=\"g-{}\" data-key=\"{}\"><tr class=head><td colspan=10>",
            g.id,
            esc(&g.key)
        );
        group_head(g, &mut b, true);
        b.push_str("</td></tr>");
        b.push_str(ALERT_HEADER);
        for a in g.alerts.iter().take(LIST_ROWS) {
            alert_row(a, &mut b);
        }
        let shown = g.alerts.len().min(LIST_ROWS);
        if shown < g.series_count {
            let _ = write!(
                b,
                "<tr><td colspan=10 class=muted>{shown} of {} series shown{}; <a href=\"/regressions/groups/{}\">all of them, with charts</a></td></tr>",
                g.series_count,
                if g.alerts.len() < g.series_count { " (filtered)" } else { "" },
                enc(&g.key)
            );
        }
        b.push_str("</tbody>");
    }
    b.push_str("</table>");
    if groups.is_empty() {
        b.push_str("<p>No detected changes match.</p>");
    }
    b.push_str(SCRIPT);
    b
}

pub async fn page(
    State(state): State<AppState>,
    Query(q): Query<GroupsQuery>,
) -> Result<Html<String>, AppError> {
    let (groups, facets) = load_groups(&state, &q).await?;
    let stopped = state
        .db(|c| Ok(crate::store::stoppage::stoppages(c, &crate::now_rfc3339())?))
        .await?;
    let mut body = render(&groups, &facets, &q);
    // Data stoppages first: a silent adapter hides every change it would have shown.
    if !stopped.is_empty() {
        let mut s = String::from("<div id=stoppages><h2 class=worse>Data stopped</h2><ul>");
        for x in &stopped {
            let _ = write!(
                s,
                "<li class=stoppage>{} <span class=muted>(last run <a href=\"/runs/{}\">{}</a> at {})</span></li>",
                esc(&x.message),
                enc(&x.last_run),
                esc(&x.last_run),
                esc(&x.last_at)
            );
        }
        s.push_str("</ul></div>");
        let at = body.find("<p id=count>").unwrap_or(0);
        body.insert_str(at, &s);
    }
    Ok(Html(layout("Regressions", "regressions", &body)))
}

/// Most series charted on a group's page; the rest are listed.
const MAX_CHARTS: usize = 24;
/// A group of more series than this opens on a table by scenario and variant (a cell per series,
/// its change and a link to it) and charts only its [`PIVOT_CHARTS`] largest changes: one chart
/// per series of a change that moved hundreds of them is a page nobody reads.
const PIVOT_FROM: usize = MAX_CHARTS;
/// Charts on the page of a pivoted group.
const PIVOT_CHARTS: usize = 6;

/// Charts a group's page draws: all its series up to [`MAX_CHARTS`], or [`PIVOT_CHARTS`] when
/// it pivots.
fn charts_for(g: &Group) -> usize {
    if g.alerts.len() > PIVOT_FROM {
        PIVOT_CHARTS
    } else {
        MAX_CHARTS
    }
}

/// A large group's series by scenario (rows) and variant (columns): each cell the change of its
/// series (with the adapter and measure where the group has several), linked to the series.
fn pivot(g: &Group) -> String {
    let mut scenarios: Vec<&str> = Vec::new();
    let mut variants: Vec<&str> = Vec::new();
    let mut adapters: Vec<&str> = Vec::new();
    let mut measures: Vec<&str> = Vec::new();
    for a in &g.alerts {
        for (list, x) in [
            (&mut scenarios, a.series.scenario.as_str()),
            (&mut variants, a.series.variant.as_str()),
            (&mut adapters, a.series.adapter.as_str()),
            (&mut measures, a.series.measure.as_str()),
        ] {
            if !list.contains(&x) {
                list.push(x);
            }
        }
    }
    scenarios.sort_unstable();
    variants.sort_unstable();
    let mut b = format!(
        "<h2 id=pivot>{} series by scenario and variant</h2><p class=muted>{} scenarios × {} variants; each cell is a series' change (▲ up, ▼ down; red worse, green better, grey moved with its baseline), linked to its history. Charts follow for the {} largest changes.</p><div class=scroll><table class=pivot><tr><th>scenario</th>",
        g.alerts.len(),
        scenarios.len(),
        variants.len(),
        PIVOT_CHARTS.min(g.alerts.len())
    );
    for v in &variants {
        let _ = write!(b, "<th>{}</th>", name(v));
    }
    b.push_str("</tr>");
    for s in &scenarios {
        let _ = write!(b, "<tr><th>{}</th>", name(s));
        for v in &variants {
            let cell: Vec<String> = g
                .alerts
                .iter()
                .filter(|a| a.series.scenario == *s && a.series.variant == *v)
                .map(|a| {
                    let mut what = Vec::new();
                    if adapters.len() > 1 {
                        what.push(esc(&a.series.adapter));
                    }
                    if measures.len() > 1 {
                        what.push(esc(&a.series.measure));
                    }
                    let class = if a.via_baseline {
                        "via"
                    } else if a.is_regression {
                        "worse"
                    } else {
                        "better"
                    };
                    format!(
                        "<a class=\"nw {class}\" href=\"/series/{}\" title=\"{} · {}: {} → {}\">{}{} {}</a>",
                        a.series.id,
                        esc(&a.series.adapter),
                        esc(&a.series.measure),
                        num(a.value_before),
                        num(a.value_after),
                        if what.is_empty() { String::new() } else { format!("{} ", what.join(" ")) },
                        if a.relative_change >= 0.0 { "▲" } else { "▼" },
                        pct(a.relative_change)
                    )
                })
                .collect();
            let _ = write!(b, "<td class=n>{}</td>", cell.join("<br>"));
        }
        b.push_str("</tr>");
    }
    b.push_str("</table></div>");
    b
}
/// Points around the change drawn in each chart.
const CHART_POINTS: usize = 60;

/// One group's page: the list's header and table, then a chart per series.
pub fn render_group(g: &Group, charts: &[(Alert, read::SeriesDetail)]) -> String {
    let mut b = String::from(STYLE);
    b.push_str("<p><a href=\"/regressions\">all groups</a></p>");
    b.push_str(TOKEN_BAR);
    let _ = write!(
        b,
        "<table id=regressions><tbody class=group id=\"g-{}\" data-key=\"{}\"><tr class=head><td colspan=10>",
        g.id,
        esc(&g.key)
    );
    group_head(g, &mut b, false);
    b.push_str("</td></tr>");
    if g.alerts.len() > PIVOT_FROM {
        // Opens on the pivot; the list of every series stays one click away.
        b.push_str("</tbody></table>");
        b.push_str(&pivot(g));
        let _ = write!(
            b,
            "<details id=series-list><summary>all {} series as a list</summary><table class=alert-list><tbody class=group>",
            g.alerts.len()
        );
    }
    b.push_str(ALERT_HEADER);
    for a in &g.alerts {
        alert_row(a, &mut b);
    }
    b.push_str("</tbody></table>");
    if g.alerts.len() > PIVOT_FROM {
        b.push_str("</details>");
    }
    b.push_str("<div class=charts>");
    for (a, d) in charts {
        let after = d.points.iter().position(|p| p.run_id == a.run_after);
        let end = after.map_or(d.points.len(), |i| {
            (i + CHART_POINTS / 2).min(d.points.len())
        });
        let from = end.saturating_sub(CHART_POINTS);
        let pts = &d.points[from..end];
        let marks: Vec<SeriesMark> = pts
            .iter()
            .map(|p| SeriesMark {
                value: p.value,
                tick: commit(p.commit.as_deref()),
                label: format!(
                    "{} {}: {}",
                    commit(p.commit.as_deref()),
                    p.run_id,
                    num(p.value)
                ),
                href: format!("/runs/{}", enc(&p.run_id)),
            })
            .collect();
        let cps: Vec<(usize, String, String)> = after
            .filter(|&i| i >= from && i < end)
            .map(|i| {
                (
                    i - from,
                    pct(a.relative_change),
                    format!("/series/{}", a.series.id),
                )
            })
            .into_iter()
            .collect();
        let _ = write!(
            b,
            "<h3><a href=\"/series/{}\">{} · {} · {} · {}</a> {}{}</h3>",
            a.series.id,
            esc(&a.series.adapter),
            esc(&a.series.scenario),
            esc(&a.series.variant),
            esc(&a.series.measure),
            change_cell(a),
            // Runners can search a range of several commits (`server/ab.rs`).
            match (&a.commit_before, &a.commit_after) {
                (Some(x), Some(y)) if x != y => format!(
                    " <a class=bisect href=\"/regressions/{}/bisect\">bisect</a>",
                    a.id
                ),
                _ => String::new(),
            }
        );
        b.push_str(&series_chart(
            &marks,
            &cps,
            &[],
            &crate::html::axis_label(&a.series.measure),
        ));
    }
    if g.alerts.len() > charts.len() {
        let _ = write!(
            b,
            "<p class=muted>{} more series are listed above without a chart.</p>",
            g.alerts.len() - charts.len()
        );
    }
    b.push_str("</div>");
    b.push_str(SCRIPT);
    b
}

/// `GET /regressions/groups/{id}` (HTML) and `GET /regressions/groups/{id}.md` (Markdown); a
/// commit-range key the group is or was shown under answers 308 to the id's URL.
pub async fn group_page(
    State(state): State<AppState>,
    headers: HeaderMap,
    Path(file): Path<String>,
) -> Result<Response, AppError> {
    let (name, md) = match file.strip_suffix(".md") {
        Some(n) => (n.to_string(), ".md"),
        None => (file, ""),
    };
    let id = match super::resolve(&state, name).await? {
        Named::Key(id) => {
            return Ok(
                Redirect::permanent(&format!("/regressions/groups/{id}{md}")).into_response(),
            )
        }
        Named::Id(id) => id,
    };
    if !md.is_empty() {
        return super::formats::markdown(&state, &headers, id).await;
    }
    let (g, charts, history, keys) = state
        .db(move |c| {
            let g = groups::get(c, id)?;
            let mut charts = Vec::new();
            for a in g
                .alerts
                .iter()
                .filter(|a| a.status != DetectionStatus::Withdrawn)
                .take(charts_for(&g))
            {
                charts.push((a.clone(), read::series(c, a.series.id)?));
            }
            let history = alerts::events_of_group(c, id)?;
            let keys = alerts::keys_of_group(c, id)?;
            Ok((g, charts, history, keys))
        })
        .await?;
    let title = format!(
        "Alert group {}: {}..{}",
        g.id,
        commit(g.commit_before.as_deref()),
        commit(g.commit_after.as_deref())
    );
    let mut body = render_group(&g, &charts);
    body.push_str(&render_history(&g, &history, &keys));
    Ok(Html(layout(&title, "regressions", &body)).into_response())
}

/// The group's history: every move with its reason, confirmations, withdrawals, and the commit
/// ranges it was shown under (each still links here).
fn render_history(g: &Group, events: &[Event], keys: &[String]) -> String {
    let mut b = String::from("<h2 id=history>History</h2>");
    let moves = events.iter().filter(|e| e.kind == "moved").count();
    let _ = write!(
        b,
        "<p>{} event{}, {} move{} · shown under {}</p>",
        events.len(),
        if events.len() == 1 { "" } else { "s" },
        moves,
        if moves == 1 { "" } else { "s" },
        // Each key's commits shortened as everywhere else, the whole key on hover: two whole
        // shas are 82 characters that cannot break, wider than a phone.
        keys.iter()
            .map(|k| {
                let short = k.split_once("..").map_or(k.to_string(), |(b, a)| {
                    format!("{}..{}", commit(Some(b)), commit(Some(a)))
                });
                format!("<code title=\"{}\">{}</code>", esc(k), esc(&short))
            })
            .collect::<Vec<_>>()
            .join(", ")
    );
    let series: std::collections::BTreeMap<i64, String> = g
        .alerts
        .iter()
        .map(|a| {
            (
                a.id,
                format!(
                    "{} · {} · {}",
                    a.series.scenario, a.series.variant, a.series.measure
                ),
            )
        })
        .collect();
    b.push_str("<table id=events><tr><th>at</th><th>alert</th><th>event</th><th>detail</th></tr>");
    for e in events.iter().rev().take(200) {
        let _ = write!(
            b,
            "<tr class=\"ev-{}\"><td>{}</td><td><a href=\"#r{}\">{}</a></td><td>{}</td><td>{}</td></tr>",
            esc(&e.kind),
            esc(&e.at),
            e.alert,
            esc(series.get(&e.alert).map_or("", |s| s.as_str())),
            esc(&e.kind),
            esc(&e.detail)
        );
    }
    b.push_str("</table>");
    b
}

#[derive(Debug, Deserialize)]
pub struct TriageForm {
    pub state: String,
    #[serde(default)]
    pub note: String,
    #[serde(default)]
    pub token: String,
}

/// `POST /regressions/{id}` (form with the token as a field): one alert's state and note.
pub async fn triage_form(
    State(state): State<AppState>,
    Path(id): Path<i64>,
    Form(f): Form<TriageForm>,
) -> Result<Redirect, AppError> {
    let who = auth::form_writer(&state, &f.token)?.name;
    apply(
        &state,
        id,
        AlertTriage {
            state: f.state,
            note: f.note,
        },
        who,
    )
    .await?;
    Ok(Redirect::to(&format!("/regressions#r{id}")))
}
