//! A/B and bisection endpoints. `POST /api/ab` (write token) queues an A/B of two environments,
//! one job per label; `GET /api/ab/{request_id}` answers its jobs with each one's per-measure
//! table. `POST /api/bisections` (write token) starts a bisection; `GET /api/bisections/{id}`
//! answers its state, steps (each with its A/B table) and `culprit`; `/bisections/{id}` is its
//! page. `GET /regressions/{id}/bisect` is the "bisect" form of an alert, prefilled from it, and
//! its `POST` (token as a form field) starts the bisection of the alert's range.
//!
//! Not for: the statistics or the bisection's decisions (see [`crate::ab`]).

use std::fmt::Write;

use axum::extract::{Path, State};
use axum::http::StatusCode;
use axum::response::{Html, Redirect};
use axum::{Form, Json};
use serde::{Deserialize, Serialize};
use tessera_results::queue::Arm;

use super::auth::{self, Writer};
use super::queue::{resolve_commit, Requested};
use super::{AppError, AppState};
use crate::ab::{self, bisect};
use crate::db::transaction;
use crate::html::{esc, num, page as layout};
use crate::store::queue::{self, NewJob};

/// An environment in a request body.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct EnvBody {
    pub commit: String,
    #[serde(default)]
    pub env: std::collections::BTreeMap<String, String>,
}

/// `POST /api/ab`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct AbRequest {
    /// Scenario file, relative to the repository root.
    pub scenario: String,
    #[serde(default)]
    pub variant: Option<String>,
    pub a: EnvBody,
    pub b: EnvBody,
    pub labels: Vec<String>,
    #[serde(default)]
    pub attempts: Option<usize>,
}

pub async fn create(
    State(state): State<AppState>,
    Writer(who): Writer,
    Json(req): Json<AbRequest>,
) -> Result<(StatusCode, Json<Requested>), AppError> {
    let r = enqueue(&state, req, who.name).await?;
    Ok((StatusCode::CREATED, Json(r)))
}

/// Checks an A/B request (labels, commits, attempts, scenario) and queues one job per label, on
/// behalf of `who`: the API's and the A/B form's one path.
pub async fn enqueue(state: &AppState, req: AbRequest, who: String) -> Result<Requested, AppError> {
    if req.labels.is_empty() || req.labels.len() > queue::MAX_LABELS {
        return Err(AppError::Field {
            field: "labels".into(),
            problem: format!("give 1 to {} labels", queue::MAX_LABELS),
        });
    }
    let attempts = req.attempts.unwrap_or(ab::DEFAULT_ATTEMPTS);
    let arm = |name: &str, e: &EnvBody| -> Result<Arm, AppError> {
        Ok(Arm {
            name: name.into(),
            commit: resolve_commit(state, name, &e.commit)?,
            env: e.env.clone(),
        })
    };
    let (a, b) = (arm("a", &req.a)?, arm("b", &req.b)?);
    let mut jobs = Vec::new();
    for label in &req.labels {
        jobs.push(NewJob {
            label: label.clone(),
            spec: ab::spec(
                &req.scenario,
                req.variant.as_deref(),
                a.clone(),
                b.clone(),
                attempts,
                None,
            )?,
        });
    }
    let max_attempts = state.queue.max_attempts;
    let spec = serde_json::to_value(&req).expect("a request serialises");
    let labels = req.labels.clone();
    let (request_id, jobs) = state
        .db(move |c| {
            queue::check_labels_known(c, &labels)?;
            Ok(queue::enqueue(
                c,
                "ab",
                &spec,
                None,
                &who,
                &jobs,
                max_attempts,
            )?)
        })
        .await?;
    Ok(Requested { request_id, jobs })
}

/// One job of an A/B with its table.
#[derive(Debug, Serialize)]
pub struct AbJob {
    pub job_id: i64,
    pub label: String,
    pub status: queue::JobStatus,
    pub runner: Option<String>,
    pub error: String,
    pub table: Vec<ab::Row>,
}

pub async fn get(
    State(state): State<AppState>,
    Path(request_id): Path<i64>,
) -> Result<Json<Vec<AbJob>>, AppError> {
    let jobs = state
        .db(move |c| Ok(queue::request_jobs(c, request_id)?))
        .await?;
    if jobs.is_empty() {
        return Err(AppError::NotFound(format!(
            "A/B request {request_id} not found"
        )));
    }
    Ok(Json(
        jobs.into_iter()
            .map(|j| AbJob {
                table: j
                    .outcome
                    .as_ref()
                    .map(|o| ab::table(&o.samples))
                    .unwrap_or_default(),
                job_id: j.id,
                label: j.label,
                status: j.status,
                runner: j.runner,
                error: j.error,
            })
            .collect(),
    ))
}

#[derive(Debug, Serialize, Deserialize)]
pub struct Created {
    pub id: i64,
}

/// Checks a bisection's commits against the repository (when configured) and stores it.
async fn start(state: &AppState, mut p: bisect::Params, who: String) -> Result<i64, AppError> {
    if !(1..=ab::MAX_ATTEMPTS).contains(&p.attempts) {
        return Err(AppError::Field {
            field: "attempts".into(),
            problem: format!("1 to {}, not {}", ab::MAX_ATTEMPTS, p.attempts),
        });
    }
    p.good = resolve_commit(state, "good", &p.good)?;
    p.bad = resolve_commit(state, "bad", &p.bad)?;
    let max_attempts = state.queue.max_attempts;
    state
        .db(move |c| {
            queue::check_labels_known(c, std::slice::from_ref(&p.label))?;
            transaction(c, |c| {
                Ok::<_, AppError>(bisect::create(c, &p, &who, max_attempts)?)
            })
        })
        .await
}

pub async fn bisect_create(
    State(state): State<AppState>,
    Writer(who): Writer,
    Json(p): Json<bisect::Params>,
) -> Result<(StatusCode, Json<Created>), AppError> {
    let id = start(&state, p, who.name).await?;
    Ok((StatusCode::CREATED, Json(Created { id })))
}

/// `GET /api/bisections/{id}`.
#[derive(Debug, Serialize)]
pub struct BisectionView {
    #[serde(flatten)]
    pub bisection: bisect::Bisection,
    pub steps: Vec<bisect::Step>,
}

async fn view(state: &AppState, id: i64) -> Result<BisectionView, AppError> {
    state
        .db(move |c| {
            let b = bisect::get(c, id)?;
            let steps = bisect::steps(c, &b)?;
            Ok(BisectionView {
                bisection: b,
                steps,
            })
        })
        .await
}

pub async fn bisect_get(
    State(state): State<AppState>,
    Path(id): Path<i64>,
) -> Result<Json<BisectionView>, AppError> {
    Ok(Json(view(&state, id).await?))
}

fn short(c: &str) -> &str {
    c.get(..10).unwrap_or(c)
}

/// An A/B table as HTML.
pub fn table_html(rows: &[ab::Row], highlight: &str) -> String {
    let mut out = String::from(
        "<table><tr><th>measure<th>A median<th>B median<th>B − A<th>95% interval<th>rel<th>p<th>verdict</tr>",
    );
    for r in rows {
        let interval = r
            .interval
            .map_or_else(|| "–".into(), |[l, h]| format!("[{}, {}]", num(l), num(h)));
        let rel = r
            .relative
            .map_or_else(|| "–".into(), |x| format!("{:+.2}%", x * 100.0));
        let _ = write!(
            out,
            "<tr{}><td>{}<td class=num>{}<td class=num>{}<td class=num>{}<td class=num>{}<td class=num>{}<td class=num>{:.2e}<td>{}</tr>",
            if r.measure == highlight { " class=hl" } else { "" },
            esc(&r.measure),
            num(r.a_median),
            num(r.b_median),
            num(r.estimate),
            interval,
            rel,
            r.p,
            esc(&r.verdict)
        );
    }
    out.push_str("</table>");
    out
}

pub async fn bisect_page(
    State(state): State<AppState>,
    Path(id): Path<i64>,
) -> Result<Html<String>, AppError> {
    let v = view(&state, id).await?;
    let b = &v.bisection;
    let mut body = format!(
        "<p>{} · {} · <b>{}</b> on <code>{}</code>: good <code>{}</code>, bad <code>{}</code>, {} attempts per arm</p>\
         <p class=state>state: <b>{}</b>{}{}</p>",
        esc(&b.scenario),
        esc(&b.variant),
        esc(&b.measure),
        esc(&b.label),
        esc(short(&b.good)),
        esc(short(&b.bad)),
        b.attempts,
        esc(&b.state),
        b.culprit
            .as_deref()
            .map(|c| format!(" · culprit <code>{}</code>", esc(c)))
            .unwrap_or_default(),
        if b.progress.message.is_empty() || b.culprit.is_some() {
            String::new()
        } else {
            format!(" · {}", esc(&b.progress.message))
        }
    );
    if !b.commits.is_empty() {
        let _ = write!(
            body,
            "<p>{} first-parent commits in the range; known good up to <code>{}</code>, bad from <code>{}</code>{}</p>",
            b.commits.len() - 1,
            esc(short(&b.commits[b.progress.lo])),
            esc(short(&b.commits[b.progress.hi])),
            if b.skipped.is_empty() {
                String::new()
            } else {
                format!("; skipped (no build): {}", esc(&b.skipped.join(", ")))
            }
        );
    }
    for s in &v.steps {
        let _ = write!(
            body,
            "<h2>Step {}: <code>{}</code> against good</h2><p>job {} · {:?}{}{}</p>{}",
            s.step,
            esc(short(&s.commit)),
            s.job_id,
            s.status,
            s.fraction
                .map(|f| format!(" · {:.0}% of the full change", f * 100.0))
                .unwrap_or_default(),
            s.decision.map(|d| format!(" · {d:?}")).unwrap_or_default(),
            table_html(&s.table, &b.measure)
        );
    }
    Ok(Html(layout(&format!("Bisection {id}"), "queue", &body)))
}

/// What the bisect form of alert `id` is prefilled with.
#[derive(Debug, Deserialize, Serialize)]
pub struct BisectForm {
    pub scenario: String,
    pub variant: String,
    pub measure: String,
    pub good: String,
    pub bad: String,
    pub label: String,
    #[serde(default = "ten")]
    pub attempts: usize,
    #[serde(default)]
    pub token: String,
}

fn ten() -> usize {
    ab::DEFAULT_ATTEMPTS
}

/// The alert's series and commit range, its scenario file and a label of a runner on its adapter.
fn alert_form(c: &mut dyn crate::db::Connection, id: i64) -> Result<BisectForm, AppError> {
    let t = crate::store::alerts::bisect_target(c, id)?;
    let label = crate::store::queue::label_on_adapter(c, &t.adapter)?.unwrap_or_default();
    Ok(BisectForm {
        scenario: t.scenario_file,
        variant: t.variant,
        measure: t.measure,
        good: t.commit_before.unwrap_or_default(),
        bad: t.commit_after.unwrap_or_default(),
        label,
        attempts: ab::DEFAULT_ATTEMPTS,
        token: String::new(),
    })
}

/// `GET /regressions/{id}/bisect`: the form, prefilled.
pub async fn bisect_form_page(
    State(state): State<AppState>,
    Path(id): Path<i64>,
) -> Result<Html<String>, AppError> {
    let f = state.db(move |c| alert_form(c, id)).await?;
    let mut body = format!(
        "<p>A/B steps over the first-parent commits from good to bad \
         on one runner of the label, until one commit is left.</p><form method=post action=\"/regressions/{id}/bisect\">"
    );
    for (name, value) in [
        ("scenario", f.scenario.as_str()),
        ("variant", f.variant.as_str()),
        ("measure", f.measure.as_str()),
        ("good", f.good.as_str()),
        ("bad", f.bad.as_str()),
        ("label", f.label.as_str()),
    ] {
        let _ = write!(
            body,
            "<p><label>{name} <input name={name} value=\"{}\" size=48 required></label></p>",
            esc(value)
        );
    }
    let _ = write!(
        body,
        "<p><label>attempts <input name=attempts type=number min=1 max={} value={}></label></p>\
         <p><label>write token <input name=token type=password required></label></p>\
         <p><button>bisect</button></p></form>",
        ab::MAX_ATTEMPTS,
        f.attempts
    );
    Ok(Html(layout(
        &format!("Bisect alert {id}"),
        "regressions",
        &body,
    )))
}

/// `POST /regressions/{id}/bisect` (form): starts the bisection, then shows it.
pub async fn bisect_form(
    State(state): State<AppState>,
    Path(id): Path<i64>,
    Form(f): Form<BisectForm>,
) -> Result<Redirect, AppError> {
    let who = auth::form_writer(&state, &f.token)?.name;
    state.db(move |c| alert_form(c, id).map(drop)).await?;
    let p = bisect::Params {
        scenario: f.scenario,
        variant: f.variant,
        measure: f.measure,
        good: f.good,
        bad: f.bad,
        label: f.label,
        attempts: f.attempts,
        regression_id: Some(id),
    };
    let bid = start(&state, p, who).await?;
    Ok(Redirect::to(&format!("/bisections/{bid}")))
}
