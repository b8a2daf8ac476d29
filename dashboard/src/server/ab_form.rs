//! The A/B button of the run and comparison pages: `GET /ab/new?a=RUN&b=RUN&scenario=NAME` is a
//! form prefilled from two stored runs (their commits, the scenario's file, a label of a runner
//! on B's adapter), and its `POST` (the write token as a form field, as the triage and bisect
//! forms take it) queues the A/B through the API's own path ([`super::ab::enqueue`]) and shows
//! where its table will be.
//!
//! Not for: the A/B's statistics or its jobs (see [`crate::ab`], [`super::ab`]).

use std::fmt::Write;

use axum::extract::{Query, State};
use axum::http::StatusCode;
use axum::response::Html;
use axum::Form;
use serde::Deserialize;

use super::ab::{AbRequest, EnvBody};
use super::{auth, AppError, AppState};
use crate::ab;
use crate::db::{Connection, Value};
use crate::html::{enc, esc, page as layout};

/// `GET /ab/new`: the runs (and scenario) the form is prefilled from.
#[derive(Debug, Default, Deserialize)]
pub struct FromRuns {
    #[serde(default)]
    pub a: Option<String>,
    #[serde(default)]
    pub b: Option<String>,
    /// A scenario name of run B; by default its first scenario.
    #[serde(default)]
    pub scenario: Option<String>,
}

/// The form's fields (`POST /ab/new`).
#[derive(Debug, Default, Deserialize)]
pub struct AbForm {
    /// Scenario file, relative to the repository root.
    pub scenario: String,
    #[serde(default)]
    pub variant: String,
    pub a: String,
    pub b: String,
    /// Comma-separated runner labels.
    pub labels: String,
    #[serde(default)]
    pub attempts: Option<usize>,
    #[serde(default)]
    pub token: String,
}

/// The link to the form from a page of runs `a` and `b` (A: the base), on `scenario` when given.
pub fn link(a: &str, b: &str, scenario: Option<&str>) -> String {
    format!(
        "<a class=ab-button href=\"/ab/new?a={}&b={}{}\" title=\"queue an A/B of the two runs' commits on a runner\">A/B</a>",
        enc(a),
        enc(b),
        scenario.map_or(String::new(), |s| format!("&scenario={}", enc(s)))
    )
}

/// A run's commit and adapter name.
fn run_of(c: &mut dyn Connection, id: &str) -> Result<(String, String), AppError> {
    let r = c
        .query_opt(
            "SELECT r.commit_sha, a.name FROM runs r JOIN adapters a ON a.id = r.adapter_id WHERE r.run_id = $1",
            &[id.into()],
        )?
        .ok_or_else(|| AppError::NotFound(format!("run {id} not found")))?;
    Ok((r.opt_string(0)?.unwrap_or_default(), r.string(1)?))
}

/// The form prefilled from the runs: their commits, the scenario's file in B, a runner label.
fn prefill(c: &mut dyn Connection, q: &FromRuns) -> Result<AbForm, AppError> {
    let mut f = AbForm {
        attempts: Some(ab::DEFAULT_ATTEMPTS),
        ..AbForm::default()
    };
    let b = match (&q.a, &q.b) {
        (Some(a), Some(b)) => {
            f.a = run_of(c, a)?.0;
            Some(b)
        }
        (None, Some(b)) | (Some(b), None) => Some(b),
        (None, None) => None,
    };
    let Some(b) = b else { return Ok(f) };
    let (commit, adapter) = run_of(c, b)?;
    f.b = commit;
    if f.a.is_empty() {
        // One run: A/B of its commit against itself (the noise of the measure on a runner).
        f.a = f.b.clone();
    }
    let record = c.query_opt(
        &format!(
            "SELECT sr.file, {} FROM scenario_results sr JOIN runs r ON r.id = sr.run_pk
             WHERE r.run_id = $1 AND (CAST($2 AS TEXT) IS NULL OR sr.scenario = $2)
             ORDER BY sr.scenario LIMIT 1",
            crate::store::records::COLUMNS
        ),
        &[b.as_str().into(), q.scenario.clone().into()],
    )?;
    if let Some(r) = record {
        // The compact schema keeps the file in a column and the record deflated; rows stored
        // before it have only the record's text.
        f.scenario = match r.opt_string(0)? {
            Some(file) => file,
            None => {
                let text = crate::store::records::text(&r, 1)?;
                let v: serde_json::Value = serde_json::from_str(&text).unwrap_or_default();
                v["file"].as_str().unwrap_or_default().to_string()
            }
        };
    }
    f.labels = c
        .query_opt(
            "SELECT l.label FROM runners r JOIN runner_labels l ON l.runner_id = r.id \
             WHERE r.adapter = $1 ORDER BY r.last_heartbeat_ms DESC, l.label LIMIT 1",
            &[Value::Text(adapter)],
        )?
        .map(|l| l.string(0))
        .transpose()?
        .unwrap_or_default();
    Ok(f)
}

/// `GET /ab/new`: the form.
pub async fn page(
    State(state): State<AppState>,
    Query(q): Query<FromRuns>,
) -> Result<Html<String>, AppError> {
    let f = state.db(move |c| prefill(c, &q)).await?;
    let mut body = String::from(
        "<p>A and B run back to back on one runner of each label, in random order, several attempts each, and are compared per measure with a paired test (<code>tessera-dashboard ab</code> does the same).</p><form id=ab-form method=post action=\"/ab/new\">",
    );
    for (name, label, value, required) in [
        ("scenario", "scenario file", f.scenario.as_str(), true),
        ("variant", "variant (empty: all)", f.variant.as_str(), false),
        ("a", "commit A", f.a.as_str(), true),
        ("b", "commit B", f.b.as_str(), true),
        (
            "labels",
            "runner labels (comma-separated)",
            f.labels.as_str(),
            true,
        ),
    ] {
        let _ = write!(
            body,
            "<p><label>{label} <input name={name} value=\"{}\" size=44{}></label></p>",
            esc(value),
            if required { " required" } else { "" }
        );
    }
    let _ = write!(
        body,
        "<p><label>attempts <input name=attempts type=number min=1 max={} value={}></label></p><p><label>write token <input name=token type=password required autocomplete=current-password></label></p><p><button>queue the A/B</button></p></form>",
        ab::MAX_ATTEMPTS,
        f.attempts.unwrap_or(ab::DEFAULT_ATTEMPTS)
    );
    Ok(Html(layout("A/B of two commits", "queue", &body)))
}

/// `POST /ab/new`: checks the form's token, queues the A/B, and says where its table will be.
pub async fn submit(
    State(state): State<AppState>,
    Form(f): Form<AbForm>,
) -> Result<(StatusCode, Html<String>), AppError> {
    let who = auth::form_writer(&state, &f.token)?.name;
    let labels: Vec<String> = f
        .labels
        .split(',')
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .map(str::to_string)
        .collect();
    let variant = Some(f.variant.trim().to_string()).filter(|v| !v.is_empty());
    let req = AbRequest {
        scenario: f.scenario.trim().to_string(),
        variant,
        a: EnvBody {
            commit: f.a.trim().to_string(),
            env: Default::default(),
        },
        b: EnvBody {
            commit: f.b.trim().to_string(),
            env: Default::default(),
        },
        labels,
        attempts: f.attempts,
    };
    let r = super::ab::enqueue(&state, req, who).await?;
    let body = format!(
        "<p id=queued>A/B request {id} queued: {} job{} (<a href=\"/queue\">queue</a>). Its per-measure table, once a runner has run it: <a href=\"/api/ab/{id}\">/api/ab/{id}</a>.</p>",
        r.jobs.len(),
        if r.jobs.len() == 1 { "" } else { "s" },
        id = r.request_id
    );
    Ok((
        StatusCode::CREATED,
        Html(layout("A/B queued", "queue", &body)),
    ))
}
