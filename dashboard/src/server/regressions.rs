//! Regressions, triaged by change: the page `/regressions` lists alert groups (the alerts that
//! blame one commit range, see [`crate::store::groups`]) with their series, filters (adapter,
//! suite, measure, state, direction, status) and sorting (date, size), and one triage form per
//! group. `/regressions/groups/{key}` shows one group with a chart per series, `{key}.md` is its
//! Markdown. JSON: `GET /api/regressions/groups`, `GET /api/regressions/groups/{key}`, triage
//! `POST /api/regressions/groups/{key}` (`{"state", "note", "bug_url"}`, bearer token).
//!
//! The write token is entered once per browser session: a small script keeps it in
//! `sessionStorage` and sends it as `Authorization: Bearer`. Without JavaScript the pages still
//! show everything, and each form takes the token as a field instead (`POST
//! /regressions/groups/{key}`). The flat per-alert API (`/api/regressions`, `POST
//! /api/regressions/{id}`, `POST /regressions/{id}`) is kept.

use std::fmt::Write;

use axum::extract::{Path, Query, State};
use axum::http::{header, HeaderMap};
use axum::response::{Html, IntoResponse, Redirect, Response};
use axum::{Form, Json};
use serde::Deserialize;

use super::{auth, AppError, AppState};
use crate::html::{commit, enc, esc, num, page as layout, pct};
use crate::notify;
use crate::store::groups::{self, Alert, Facets, Filter, Group, Sort, DIRECTIONS};
use crate::store::read::{self, RegressionRow};
use crate::store::triage::{self, Triage, STATES};
use crate::svg::{series_chart, SeriesMark};

#[derive(Debug, Deserialize, Default)]
pub struct RegressionsQuery {
    pub state: Option<String>,
    pub limit: Option<i64>,
}

async fn load(state: &AppState, q: RegressionsQuery) -> Result<Vec<RegressionRow>, AppError> {
    let limit = q.limit.unwrap_or(200).clamp(1, 2000);
    let st = q.state.filter(|s| !s.is_empty());
    if let Some(s) = &st {
        if !STATES.contains(&s.as_str()) {
            return Err(AppError::BadRequest(format!(
                "state must be one of {}",
                STATES.join(", ")
            )));
        }
    }
    state
        .db(move |c| Ok(read::regressions(c, st.as_deref(), None, limit)?))
        .await
}

/// `GET /api/regressions`: every alert, one per series change, newest first.
pub async fn api(
    State(state): State<AppState>,
    Query(q): Query<RegressionsQuery>,
) -> Result<Json<Vec<RegressionRow>>, AppError> {
    Ok(Json(load(&state, q).await?))
}

/// A one-line summary of a change, e.g.
/// `tiny · upscale[scale=0.5] · llvmpipe · gpu_ms.median: 3.476 → 3.824 (+10.0%, worse), 99.9% confidence`.
pub fn summary(r: &RegressionRow) -> String {
    format!(
        "{} · {} · {} · {}: {} → {} ({}, {}), {:.1}% confidence",
        r.series.scenario,
        r.series.variant,
        r.series.adapter,
        r.series.measure,
        num(r.value_before),
        num(r.value_after),
        pct(r.relative_change),
        if r.is_regression { "worse" } else { "better" },
        r.confidence * 100.0
    )
}

// ---------------------------------------------------------------------------------------------
// Groups: query, loading.

/// Filters and sorting of the page and `GET /api/regressions/groups`; empty values mean "all".
#[derive(Debug, Deserialize, Default, Clone)]
pub struct GroupsQuery {
    pub adapter: Option<String>,
    pub suite: Option<String>,
    pub measure: Option<String>,
    pub state: Option<String>,
    pub direction: Option<String>,
    pub status: Option<String>,
    pub sort: Option<String>,
    pub limit: Option<usize>,
}

fn non_empty(s: &Option<String>) -> Option<String> {
    s.as_ref()
        .map(|s| s.trim())
        .filter(|s| !s.is_empty())
        .map(str::to_string)
}

impl GroupsQuery {
    fn parse(&self) -> Result<(Filter, Sort, usize), AppError> {
        let adapter = match non_empty(&self.adapter) {
            Some(a) => Some(a.parse::<i64>().map_err(|_| {
                AppError::BadRequest(format!("adapter must be an adapter id, not {a:?}"))
            })?),
            None => None,
        };
        let filter = Filter {
            adapter,
            suite: non_empty(&self.suite),
            measure: non_empty(&self.measure),
            state: non_empty(&self.state),
            direction: non_empty(&self.direction),
            status: non_empty(&self.status),
        };
        filter
            .validate()
            .map_err(|e| AppError::BadRequest(e.to_string()))?;
        let sort = Sort::parse(non_empty(&self.sort).as_deref())
            .map_err(|e| AppError::BadRequest(e.to_string()))?;
        Ok((filter, sort, self.limit.unwrap_or(200).clamp(1, 2000)))
    }
}

async fn load_groups(state: &AppState, q: &GroupsQuery) -> Result<(Vec<Group>, Facets), AppError> {
    let (filter, sort, limit) = q.parse()?;
    state
        .db(move |c| Ok(groups::list_with_facets(c, &filter, sort, limit)?))
        .await
}

async fn load_group(state: &AppState, key: String) -> Result<Group, AppError> {
    state.db(move |c| Ok(groups::get(c, &key)?)).await
}

/// The dashboard's public URL: `--public-url`, else `http://` and the request's `Host`.
pub fn base_url(state: &AppState, headers: &HeaderMap) -> String {
    if let Some(u) = &state.public_url {
        return u.trim_end_matches('/').to_string();
    }
    let host = headers
        .get(header::HOST)
        .and_then(|h| h.to_str().ok())
        .filter(|h| {
            h.bytes()
                .all(|b| b.is_ascii_alphanumeric() || b"-.:[]".contains(&b))
        })
        .unwrap_or("localhost");
    format!("http://{host}")
}

/// Who is changing triage, as recorded in `updated_by`: the write token's name (`legacy` for
/// `--token`).
pub fn writer(state: &AppState, headers: &HeaderMap) -> Result<String, AppError> {
    Ok(auth::require(state, headers, auth::Scope::Write)?.name)
}

// ---------------------------------------------------------------------------------------------
// JSON API.

/// `GET /api/regressions/groups`: groups with their matching alerts.
pub async fn groups_api(
    State(state): State<AppState>,
    Query(q): Query<GroupsQuery>,
) -> Result<Json<Vec<Group>>, AppError> {
    Ok(Json(load_groups(&state, &q).await?.0))
}

/// `GET /api/regressions/groups/{key}`: one group with all its alerts.
pub async fn group_api(
    State(state): State<AppState>,
    Path(key): Path<String>,
) -> Result<Json<Group>, AppError> {
    Ok(Json(load_group(&state, key).await?))
}

async fn apply_group(
    state: &AppState,
    key: String,
    t: Triage,
    who: String,
) -> Result<usize, AppError> {
    state
        .db(move |c| Ok(triage::set_group(c, &key, &t, &who)?))
        .await
}

/// `POST /api/regressions/groups/{key}`: sets state, note and bug link on every alert of the
/// group in one transaction.
pub async fn group_triage_api(
    State(state): State<AppState>,
    headers: HeaderMap,
    Path(key): Path<String>,
    body: Result<Json<Triage>, axum::extract::rejection::JsonRejection>,
) -> Result<Json<serde_json::Value>, AppError> {
    let who = writer(&state, &headers)?;
    let Json(t) = body.map_err(|e| AppError::BadRequest(e.body_text()))?;
    let n = apply_group(&state, key.clone(), t.clone(), who.clone()).await?;
    Ok(Json(serde_json::json!({
        "key": key, "updated": n, "state": t.state, "updated_by": who
    })))
}

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
    let t = Triage {
        state: f.state,
        note: f.note,
        bug_url: f.bug_url,
    };
    apply_group(&state, key.clone(), t, who).await?;
    Ok(Redirect::to(&format!("/regressions#g-{}", enc(&key))))
}

// ---------------------------------------------------------------------------------------------
// HTML.

/// The page's own style and script: kept here so the page does not depend on the shared sheet.
const STYLE: &str = "<style>
#tokenbar{background:#f6f6f1;border:1px solid #ddd;padding:6px 10px;margin:8px 0;display:flex;gap:8px;align-items:center;flex-wrap:wrap}
#filters{margin:8px 0}#filters label{margin-right:10px;white-space:nowrap}#filters select{max-width:220px}
#regressions{width:100%}#regressions tbody.group>tr.head>td{background:#f3f5f8;border-top:2px solid #1d2733;padding:8px 8px 6px}
.group h2{font-size:15px;margin:0 0 4px;font-weight:600}.group h2 a{color:#1d2733;text-decoration:none}.group h2 a:hover{text-decoration:underline}
.meta{margin:2px 0 6px;color:#444}.meta code{background:#e8ebf0;padding:0 3px}
.chg{display:inline-block;white-space:nowrap;min-width:84px;padding:0 6px;border-radius:3px;font-weight:600;font-variant-numeric:tabular-nums;text-align:right}
.chg.worse{background:#fde8e6;color:#a1140f}.chg.better{background:#e2f3e7;color:#0d6b2c}
.count.worse{color:#a1140f;font-weight:600}.count.better{color:#0d6b2c;font-weight:600}
.badge{display:inline-block;padding:0 7px;border-radius:9px;font-size:12px;border:1px solid #aaa;background:#fff}
.st-new{background:#fff3d1;border-color:#d9a521}.st-acknowledged{background:#e3ebfb;border-color:#6f93dd}
.st-fixed{background:#e2f3e7;border-color:#5aa772}.st-invalid,.st-ignored{background:#eee;color:#555}
.stat-pending{border-style:dashed;color:#7a5a00}.stat-withdrawn{color:#777;text-decoration:line-through}
form.triage{margin:4px 0 0}form.triage input[name=note]{width:260px}form.triage input[name=bug_url]{width:220px}
.result{margin-left:8px}.result.ok{color:#17803d}.result.failed{color:#b3261e}
tr.series-row td{font-size:13px}tr.series-row.stat-withdrawn td{color:#888}
.charts h3{font-size:14px;margin:16px 0 2px}
</style>";

const SCRIPT: &str = r#"<script>
(() => {
  const KEY = 'tessera-write-token';
  const box = document.getElementById('token');
  const save = document.getElementById('token-save');
  const forget = document.getElementById('token-forget');
  const said = document.getElementById('token-state');
  const show = () => {
    const t = sessionStorage.getItem(KEY);
    said.textContent = t ? 'write token set for this browser session' : 'enter the write token once to triage in this browser session';
    box.hidden = save.hidden = !!t;
    forget.hidden = !t;
  };
  save.addEventListener('click', () => {
    const t = box.value.trim();
    if (t) { sessionStorage.setItem(KEY, t); box.value = ''; }
    show();
  });
  box.addEventListener('keydown', e => { if (e.key === 'Enter') { e.preventDefault(); save.click(); } });
  forget.addEventListener('click', () => { sessionStorage.removeItem(KEY); show(); });
  for (const f of document.querySelectorAll('form.triage')) {
    f.addEventListener('submit', async e => {
      e.preventDefault();
      const out = f.querySelector('.result');
      const t = sessionStorage.getItem(KEY);
      if (!t) { out.className = 'result failed'; out.textContent = 'enter the write token above first'; box.focus(); return; }
      const body = { state: f.elements.state.value, note: f.elements.note.value, bug_url: f.elements.bug_url.value };
      out.className = 'result'; out.textContent = 'saving…';
      try {
        const r = await fetch('/api/regressions/groups/' + encodeURIComponent(f.dataset.key), {
          method: 'POST',
          headers: { 'Content-Type': 'application/json', 'Authorization': 'Bearer ' + t },
          body: JSON.stringify(body),
        });
        const j = await r.json().catch(() => ({}));
        if (r.ok) {
          out.className = 'result ok';
          out.textContent = 'saved for ' + j.updated + ' series by ' + j.updated_by;
          const badge = document.querySelector('[data-state-of="' + CSS.escape(f.dataset.key) + '"]');
          if (badge) { badge.textContent = body.state; badge.className = 'badge st-' + body.state; }
        } else {
          out.className = 'result failed';
          out.textContent = (j.error || ('HTTP ' + r.status));
          if (r.status === 401) { sessionStorage.removeItem(KEY); show(); }
        }
      } catch (err) {
        out.className = 'result failed'; out.textContent = 'not saved: ' + err;
      }
    });
  }
  show();
})();
</script>"#;

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
    b.push_str(&select("state", "state", q.state.as_deref(), &own(&STATES)));
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
    let key = enc(&g.key);
    let title = if title_link {
        format!(
            "<a href=\"/regressions/groups/{key}\">{}</a>",
            esc(&g.title)
        )
    } else {
        esc(&g.title)
    };
    let _ = write!(
        b,
        "<h2>{title}</h2><p class=meta><span class=\"badge st-{}\" data-state-of=\"{}\">{}</span>{} <span class=\"badge stat-{}\">{}</span> · commits <code>{}</code> → <code>{}</code> · <span class=\"count worse\">{} worse</span>, <span class=\"count better\">{} better</span> on {} · newest run {} · <a href=\"/regressions/groups/{key}.md\">Markdown</a>",
        esc(&g.state),
        esc(&g.key),
        esc(&g.state),
        if g.mixed_state { " <span class=muted>(alerts differ)</span>" } else { "" },
        esc(&g.status),
        esc(&g.status),
        esc(&commit(g.commit_before.as_deref())),
        esc(&commit(g.commit_after.as_deref())),
        g.worse,
        g.better,
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
        "</p><form class=triage method=post action=\"/regressions/groups/{key}\" data-key=\"{}\"><select name=state aria-label=state>",
        esc(&g.key)
    );
    for s in STATES {
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
        "<tr id=r{} class=\"series-row stat-{}\"><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td><a href=\"/series/{}\">{}</a></td><td class=n>{}</td><td class=n>{}</td><td class=n>{}</td><td class=n>{:.1}%</td><td>{}</td></tr>",
        a.id,
        esc(&a.status),
        esc(&a.series.adapter),
        esc(&a.suite),
        esc(&a.series.scenario),
        esc(&a.series.variant),
        a.series.id,
        esc(&a.series.measure),
        num(a.value_before),
        num(a.value_after),
        change_cell(a),
        a.confidence * 100.0,
        esc(&a.status)
    );
}

const ALERT_HEADER: &str = "<tr><th>adapter</th><th>suite</th><th>scenario</th><th>variant</th><th>measure (series)</th><th class=n>before</th><th class=n>after</th><th class=n>change</th><th class=n>confidence</th><th>status</th></tr>";

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
            "<tbody class=group id=\"g-{}\"><tr class=head><td colspan=10>",
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
    Ok(Html(layout(
        "Regressions",
        "regressions",
        &render(&groups, &facets, &q),
    )))
}

/// Most series charted on a group's page; the rest are listed.
const MAX_CHARTS: usize = 24;
/// Points around the change drawn in each chart.
const CHART_POINTS: usize = 60;

/// One group's page: the list's header and table, then a chart per series.
pub fn render_group(g: &Group, charts: &[(Alert, read::SeriesDetail)]) -> String {
    let mut b = String::from(STYLE);
    b.push_str("<p><a href=\"/regressions\">all groups</a></p>");
    b.push_str(TOKEN_BAR);
    let _ = write!(
        b,
        "<table id=regressions><tbody class=group id=\"g-{}\"><tr class=head><td colspan=10>",
        esc(&g.key)
    );
    group_head(g, &mut b, false);
    b.push_str("</td></tr>");
    b.push_str(ALERT_HEADER);
    for a in &g.alerts {
        alert_row(a, &mut b);
    }
    b.push_str("</tbody></table><div class=charts>");
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
            "<h3><a href=\"/series/{}\">{} · {} · {} · {}</a> {}</h3>",
            a.series.id,
            esc(&a.series.adapter),
            esc(&a.series.scenario),
            esc(&a.series.variant),
            esc(&a.series.measure),
            change_cell(a)
        );
        b.push_str(&series_chart(&marks, &cps, &[], &a.series.measure));
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

/// `GET /regressions/groups/{key}` (HTML) and `GET /regressions/groups/{key}.md` (Markdown).
pub async fn group_page(
    State(state): State<AppState>,
    headers: HeaderMap,
    Path(file): Path<String>,
) -> Result<Response, AppError> {
    if let Some(key) = file
        .strip_suffix(".md")
        .filter(|k| groups::parse_key(k).is_some())
    {
        let g = load_group(&state, key.to_string()).await?;
        let md = notify::markdown::render(&g, &base_url(&state, &headers));
        return Ok(([(header::CONTENT_TYPE, "text/markdown; charset=utf-8")], md).into_response());
    }
    let (g, charts) = state
        .db(move |c| {
            let g = groups::get(c, &file)?;
            let mut charts = Vec::new();
            for a in g
                .alerts
                .iter()
                .filter(|a| a.status != "withdrawn")
                .take(MAX_CHARTS)
            {
                charts.push((a.clone(), read::series(c, a.series.id)?));
            }
            Ok((g, charts))
        })
        .await?;
    let title = format!(
        "Alert group {}..{}",
        commit(g.commit_before.as_deref()),
        commit(g.commit_after.as_deref())
    );
    Ok(Html(layout(&title, "regressions", &render_group(&g, &charts))).into_response())
}

#[derive(Debug, Deserialize, Default)]
pub struct FeedQuery {
    /// Only groups in this triage state (e.g. `new`).
    pub state: Option<String>,
}

/// `GET /regressions/feed.atom`: the 50 most recently detected confirmed groups.
pub async fn feed(
    State(state): State<AppState>,
    headers: HeaderMap,
    Query(q): Query<FeedQuery>,
) -> Result<Response, AppError> {
    let filter = Filter {
        status: Some("confirmed".into()),
        state: non_empty(&q.state),
        ..Filter::default()
    };
    filter
        .validate()
        .map_err(|e| AppError::BadRequest(e.to_string()))?;
    let mut groups = state
        .db(move |c| Ok(groups::list(c, &filter, Sort::Date, usize::MAX)?))
        .await?;
    groups.sort_by(|x, y| {
        (y.detected_at.cmp(&x.detected_at))
            .then(y.started_at.cmp(&x.started_at))
            .then(x.key.cmp(&y.key))
    });
    groups.truncate(50);
    let xml = notify::atom::feed(&groups, &base_url(&state, &headers), &crate::now_rfc3339());
    Ok((
        [(header::CONTENT_TYPE, "application/atom+xml; charset=utf-8")],
        xml,
    )
        .into_response())
}

// ---------------------------------------------------------------------------------------------
// Per-alert triage (kept for scripts written against it).

#[derive(Debug, Deserialize)]
pub struct AlertTriage {
    pub state: String,
    #[serde(default)]
    pub note: String,
}

async fn apply(state: &AppState, id: i64, t: AlertTriage, who: String) -> Result<(), AppError> {
    state
        .db(move |c| Ok(triage::set_alert(c, id, &t.state, &t.note, &who)?))
        .await
}

/// `POST /api/regressions/{id}`: one alert's state and note.
pub async fn triage_api(
    State(state): State<AppState>,
    headers: HeaderMap,
    Path(id): Path<i64>,
    body: Result<Json<AlertTriage>, axum::extract::rejection::JsonRejection>,
) -> Result<Json<serde_json::Value>, AppError> {
    let who = writer(&state, &headers)?;
    let Json(t) = body.map_err(|e| AppError::BadRequest(e.body_text()))?;
    apply(&state, id, t, who).await?;
    Ok(Json(serde_json::json!({ "id": id, "updated": true })))
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
