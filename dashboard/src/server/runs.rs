//! The runs list (`/`, `/api/runs`): newest first, with suite, branch, commit, adapter and driver,
//! status counts and a marker of runs at which changes were detected. Filters `adapter` (id),
//! `suite`, `branch`, `status` (`complete`, `interrupted`, `running`, `failed`), `q` (part of a
//! run id or commit), `alerts=1`; paging `offset` and `limit` (at most 1000, default 50 on the
//! page and 100 in the API, whose total is in `X-Total-Count`). Two ticked runs open the compare
//! page.

use std::fmt::Write;

use axum::extract::{Query, State};
use axum::http::HeaderValue;
use axum::response::{Html, IntoResponse, Response};
use axum::Json;
use serde::Deserialize;

use super::{AppError, AppState};
use crate::html::{commit, enc, esc, page as layout, pager, short_id};
use crate::store::browse::{self, RunFilter, RunList, RunListRow};

#[derive(Debug, Deserialize, Default)]
pub struct RunsQuery {
    pub adapter: Option<String>,
    pub suite: Option<String>,
    pub branch: Option<String>,
    pub status: Option<String>,
    pub q: Option<String>,
    pub alerts: Option<String>,
    pub offset: Option<i64>,
    pub limit: Option<i64>,
}

impl RunsQuery {
    fn filter(&self) -> Result<RunFilter, AppError> {
        let adapter =
            match self.adapter.as_deref().filter(|a| !a.is_empty()) {
                None => None,
                Some(a) => Some(a.parse().map_err(|_| {
                    AppError::BadRequest(format!("adapter must be an id, not {a:?}"))
                })?),
            };
        if let Some(s) = self.status.as_deref().filter(|s| !s.is_empty()) {
            if !["complete", "interrupted", "running", "failed"].contains(&s) {
                return Err(AppError::BadRequest(format!(
                    "status must be complete, interrupted, running or failed, not {s:?}"
                )));
            }
        }
        Ok(RunFilter {
            adapter,
            suite: self.suite.clone(),
            branch: self.branch.clone(),
            status: self.status.clone(),
            text: self.q.clone(),
            alerts_only: matches!(self.alerts.as_deref(), Some("1" | "true" | "on")),
        })
    }
}

async fn load(state: &AppState, q: &RunsQuery, default_limit: i64) -> Result<RunList, AppError> {
    let filter = q.filter()?;
    let limit = q.limit.unwrap_or(default_limit).clamp(1, 1000);
    let offset = q.offset.unwrap_or(0).max(0);
    state
        .db(move |c| Ok(browse::run_list(c, &filter, offset, limit)?))
        .await
}

/// The matching runs as an array; the number over all pages is in `X-Total-Count`.
pub async fn api(
    State(state): State<AppState>,
    Query(q): Query<RunsQuery>,
) -> Result<Response, AppError> {
    let list = load(&state, &q, 100).await?;
    let mut res = Json(list.runs).into_response();
    res.headers_mut()
        .insert("x-total-count", HeaderValue::from(list.total));
    Ok(res)
}

fn options(b: &mut String, name: &str, values: &[String], chosen: Option<&str>) {
    let _ = write!(
        b,
        " {name} <select name={name}><option value=\"\">any</option>"
    );
    for v in values {
        let sel = if Some(v.as_str()) == chosen {
            " selected"
        } else {
            ""
        };
        let _ = write!(b, "<option{sel}>{}</option>", esc(v));
    }
    b.push_str("</select>");
}

/// The runs table as HTML, with a tick box per run for the compare page.
pub fn render(runs: &[RunListRow]) -> String {
    let mut b = String::from(
        "<div class=scroll><table id=runs><tr><th title=\"tick two runs to compare\">pick</th><th>run</th><th>suite</th><th class=wide>branch</th><th>commit</th><th class=wide>started (UTC)</th><th>adapter</th><th class=wide>driver</th><th class=wide>status</th><th class=n>ok</th><th class=n>skipped</th><th class=n>failed</th><th>alerts</th></tr>",
    );
    for row in runs {
        let r = &row.run;
        let alerts = if row.alerts > 0 {
            format!(
                "<a class=alert href=\"/regressions\" title=\"{} change(s) detected at this run\">{}</a>",
                row.alerts, row.alerts
            )
        } else {
            String::new()
        };
        let _ = write!(
            b,
            "<tr><td><input type=checkbox name=pick value=\"{}\" aria-label=\"pick {}\"></td><td class=nw><a href=\"/runs/{}\" title=\"{}\">{}</a></td><td>{}</td><td class=wide>{}</td><td class=nw><code title=\"{}\">{}</code>{}</td><td class=\"wide nw\">{}</td><td><a href=\"/?adapter={}\">{}</a> <span class=\"muted wide\">{}</span></td><td class=wide>{} <span class=muted>{}</span></td><td class=wide>{}</td><td class=\"n ok\">{}</td><td class=\"n skipped\">{}</td><td class=\"n failed\">{}</td><td>{alerts}</td></tr>",
            esc(&r.run_id),
            esc(&r.run_id),
            enc(&r.run_id),
            esc(&r.run_id),
            esc(&short_id(&r.run_id)),
            r.suite.as_deref().map_or("–".into(), |s| format!("<a href=\"/?suite={}\">{}</a>", enc(s), esc(s))),
            r.branch.as_deref().map_or("–".into(), |s| format!("<a href=\"/?branch={}\">{}</a>", enc(s), esc(s))),
            esc(r.commit.as_deref().unwrap_or("")),
            esc(&commit(r.commit.as_deref())),
            if r.dirty { " <span class=muted>dirty</span>" } else { "" },
            esc(&r.started_at),
            r.adapter_id,
            esc(&r.adapter),
            esc(&r.backend),
            esc(&r.driver),
            esc(&r.driver_info),
            esc(&r.status),
            r.ok,
            r.skipped,
            r.failed
        );
    }
    b.push_str("</table></div>");
    b
}

pub async fn page(
    State(state): State<AppState>,
    Query(q): Query<RunsQuery>,
) -> Result<Html<String>, AppError> {
    let list = load(&state, &q, 50).await?;
    let filter = q.filter()?;
    let mut b = String::from(
        "<form id=filters>adapter <select name=adapter><option value=\"\">any</option>",
    );
    for a in &list.adapters {
        let sel = if Some(a.id) == filter.adapter {
            " selected"
        } else {
            ""
        };
        let _ = write!(
            b,
            "<option value={}{sel}>{} ({}, {} runs)</option>",
            a.id,
            esc(&a.name),
            esc(&a.backend),
            a.runs
        );
    }
    b.push_str("</select>");
    options(&mut b, "suite", &list.suites, q.suite.as_deref());
    options(&mut b, "branch", &list.branches, q.branch.as_deref());
    let statuses: Vec<String> = ["complete", "interrupted", "running", "failed"]
        .map(String::from)
        .to_vec();
    options(&mut b, "status", &statuses, q.status.as_deref());
    let _ = write!(
        b,
        " run or commit <input name=q size=12 value=\"{}\"> <label><input type=checkbox name=alerts value=1{}> with alerts</label> <button>filter</button></form>",
        esc(q.q.as_deref().unwrap_or("")),
        if filter.alerts_only { " checked" } else { "" }
    );
    let base = format!(
        "/?adapter={}&suite={}&branch={}&status={}&q={}&alerts={}&",
        filter.adapter.map_or(String::new(), |a| a.to_string()),
        enc(q.suite.as_deref().unwrap_or("")),
        enc(q.branch.as_deref().unwrap_or("")),
        enc(q.status.as_deref().unwrap_or("")),
        enc(q.q.as_deref().unwrap_or("")),
        if filter.alerts_only { "1" } else { "" }
    );
    let pages = pager(&base, list.offset, list.limit, list.total, list.runs.len());
    b.push_str(&pages);
    b.push_str("<form class=pick-two action=\"/compare/runs\"><p><button class=compare type=submit>compare the two ticked runs</button> <span class=muted>(the older is A, the newer B)</span></p>");
    b.push_str(&render(&list.runs));
    b.push_str("</form>");
    if list.total == 0 {
        b.push_str("<p>No runs match. Store runs with <code>tessera-dashboard import &lt;results folder&gt;</code> or <code>POST /api/runs</code>.</p>");
    }
    b.push_str(&pages);
    Ok(Html(layout("Runs", "runs", &b)))
}
