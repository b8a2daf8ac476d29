//! The job queue's endpoints. Runner endpoints (a `runner` or `write` token, and the runner must
//! have been registered with that token): `POST /api/runners/register`, `POST
//! /api/runners/heartbeat`, `POST /api/queue/claim` (200 with the job, 204 when none),
//! `POST /api/queue/jobs/{id}/complete`, `/fail`, `/return`. Requests (a `write` token):
//! `POST /api/queue/requests` (a nightly run or backfill of suites at a commit). Reads:
//! `GET /api/queue` (runners and jobs), `GET /api/queue/jobs/{id}`.
//!
//! Every body is checked before anything is stored: a bad field is a 422 naming it, a job the
//! runner does not hold a 409, a runner of another token a 403. Not for: SQL (see
//! [`crate::store::queue`]), A/B and bisection requests (see [`super::ab`]).

use std::collections::BTreeMap;
use std::path::PathBuf;

use axum::extract::{Path, State};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use axum::Json;
use serde::{Deserialize, Serialize};
use tessera_results::queue::{
    Arm, ClaimRequest, Completion, Failure, Heartbeat, HeartbeatReply, JobKind, JobSpec,
    Registration, Return,
};

use super::auth::{Principal, RunnerAuth, Scope, Writer};
use super::{AppError, AppState};
use crate::db::{transaction, Connection};
use crate::store::queue::{self, NewJob};

/// Lease, offline threshold and retries of the queue; set from `serve`'s options.
#[derive(Clone, Debug)]
pub struct QueueConfig {
    /// A claimed job goes back to the queue this long after its runner's last heartbeat.
    pub lease_ms: i64,
    /// A runner not heard from for this long is shown offline.
    pub offline_after_ms: i64,
    /// Claims of one job before it is marked failed.
    pub max_attempts: i64,
    /// A git repository of the project: when set, requests naming a commit it does not have are
    /// refused (422), and short commits are expanded.
    pub repository: Option<PathBuf>,
}

impl Default for QueueConfig {
    fn default() -> Self {
        QueueConfig {
            lease_ms: 60_000,
            offline_after_ms: 120_000,
            max_attempts: queue::DEFAULT_MAX_ATTEMPTS,
            repository: None,
        }
    }
}

pub fn now_ms() -> i64 {
    chrono::Utc::now().timestamp_millis()
}

/// The runner's id, after checking it was registered with this principal's token (a write token
/// may act for any runner).
fn own_runner(c: &mut dyn Connection, who: &Principal, name: &str) -> Result<i64, AppError> {
    let (id, token) = queue::runner(c, name)?;
    if token != who.name && !who.scope.allows(Scope::Write) {
        return Err(AppError::Forbidden(format!(
            "runner {name:?} was registered with another token"
        )));
    }
    Ok(id)
}

#[derive(Debug, Serialize, Deserialize, PartialEq)]
pub struct Registered {
    pub runner_id: i64,
    pub lease_secs: u64,
}

pub async fn register(
    State(state): State<AppState>,
    RunnerAuth(who): RunnerAuth,
    Json(reg): Json<Registration>,
) -> Result<Json<Registered>, AppError> {
    let lease_secs = (state.queue.lease_ms / 1000).max(1) as u64;
    let id = state
        .db(move |c| Ok(queue::register(c, &reg, &who.name, now_ms())?))
        .await?;
    Ok(Json(Registered {
        runner_id: id,
        lease_secs,
    }))
}

pub async fn heartbeat(
    State(state): State<AppState>,
    RunnerAuth(who): RunnerAuth,
    Json(hb): Json<Heartbeat>,
) -> Result<Json<HeartbeatReply>, AppError> {
    let lease = state.queue.lease_ms;
    let kept = state
        .db(move |c| {
            let id = own_runner(c, &who, &hb.runner)?;
            Ok(queue::heartbeat(
                c,
                id,
                hb.job.map(|j| (j.job_id, j.attempt)),
                now_ms(),
                lease,
            )?)
        })
        .await?;
    Ok(Json(HeartbeatReply { job_kept: kept }))
}

pub async fn claim(
    State(state): State<AppState>,
    RunnerAuth(who): RunnerAuth,
    Json(req): Json<ClaimRequest>,
) -> Result<Response, AppError> {
    let lease = state.queue.lease_ms;
    let claimed = state
        .db(move |c| {
            let id = own_runner(c, &who, &req.runner)?;
            Ok(queue::claim(c, id, now_ms(), lease)?)
        })
        .await?;
    Ok(match claimed {
        Some(job) => Json(job).into_response(),
        None => StatusCode::NO_CONTENT.into_response(),
    })
}

/// What a finished job changed besides itself (a bisection's next step).
#[derive(Debug, Serialize, Deserialize, PartialEq)]
pub struct Finished {
    pub job_id: i64,
    pub status: queue::JobStatus,
}

pub async fn complete(
    State(state): State<AppState>,
    RunnerAuth(who): RunnerAuth,
    Path(job_id): Path<i64>,
    Json(done): Json<Completion>,
) -> Result<Json<Finished>, AppError> {
    if done.samples.len() > queue::MAX_ORDER || done.runs.len() > queue::MAX_ORDER {
        return Err(AppError::Field {
            field: "samples".into(),
            problem: format!("at most {} samples and runs", queue::MAX_ORDER),
        });
    }
    if let Some(c) = &done.commits {
        if c.len() > 100_000 {
            return Err(AppError::Field {
                field: "commits".into(),
                problem: "at most 100000 commits".into(),
            });
        }
        for sha in c {
            queue::check_commit("commits", sha)?;
        }
    }
    state
        .db(move |c| {
            let id = own_runner(c, &who, &done.runner)?;
            transaction(c, |c| {
                queue::complete(c, id, job_id, &done)?;
                crate::ab::bisect::on_job_finished(c, job_id)?;
                Ok::<_, AppError>(())
            })
        })
        .await?;
    Ok(Json(Finished {
        job_id,
        status: queue::JobStatus::Done,
    }))
}

pub async fn fail(
    State(state): State<AppState>,
    RunnerAuth(who): RunnerAuth,
    Path(job_id): Path<i64>,
    Json(f): Json<Failure>,
) -> Result<Json<Finished>, AppError> {
    if let Some(c) = &f.build_failed {
        queue::check_commit("build_failed", c)?;
    }
    let status = state
        .db(move |c| {
            let id = own_runner(c, &who, &f.runner)?;
            let outcome = f.commits.clone().map(|commits| Completion {
                runner: f.runner.clone(),
                attempt: f.attempt,
                runs: vec![],
                samples: vec![],
                commits: Some(commits),
            });
            transaction(c, |c| {
                let status = queue::fail(
                    c,
                    id,
                    job_id,
                    f.attempt,
                    &f.error,
                    f.build_failed.is_some(),
                    outcome.as_ref(),
                )?;
                if status.is_final() {
                    crate::ab::bisect::on_job_finished(c, job_id)?;
                }
                Ok::<_, AppError>(status)
            })
        })
        .await?;
    Ok(Json(Finished { job_id, status }))
}

pub async fn give_back(
    State(state): State<AppState>,
    RunnerAuth(who): RunnerAuth,
    Path(job_id): Path<i64>,
    Json(r): Json<Return>,
) -> Result<Json<Finished>, AppError> {
    state
        .db(move |c| {
            let id = own_runner(c, &who, &r.runner)?;
            Ok(queue::give_back(c, id, job_id, r.attempt)?)
        })
        .await?;
    Ok(Json(Finished {
        job_id,
        status: queue::JobStatus::Queued,
    }))
}

/// Resolves `commit` in the configured repository (422 when it has no such commit); unchanged
/// without a repository.
pub fn resolve_commit(state: &AppState, what: &str, commit: &str) -> Result<String, AppError> {
    queue::check_commit(what, commit)?;
    let Some(repo) = &state.queue.repository else {
        return Ok(commit.to_string());
    };
    let out = std::process::Command::new("git")
        .arg("-C")
        .arg(repo)
        .args(["rev-parse", "--verify", "--quiet"])
        .arg(format!("{commit}^{{commit}}"))
        .output()
        .map_err(|e| AppError::Internal(format!("git rev-parse: {e}")))?;
    if !out.status.success() {
        return Err(AppError::Field {
            field: what.into(),
            problem: format!("{commit} is not a commit of the dashboard's repository"),
        });
    }
    Ok(String::from_utf8_lossy(&out.stdout).trim().to_string())
}

/// `POST /api/queue/requests`.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RunRequest {
    /// `nightly` (default) or `backfill`.
    #[serde(default = "nightly")]
    pub kind: String,
    pub commit: String,
    /// Folders under `scenarios/` (`smoke`, `perf`), one job per suite and label.
    pub suites: Vec<String>,
    pub labels: Vec<String>,
    #[serde(default)]
    pub env: BTreeMap<String, String>,
}

fn nightly() -> String {
    "nightly".into()
}

#[derive(Debug, Serialize, Deserialize, PartialEq)]
pub struct Requested {
    pub request_id: i64,
    pub jobs: Vec<i64>,
}

pub async fn request(
    State(state): State<AppState>,
    Writer(who): Writer,
    Json(req): Json<RunRequest>,
) -> Result<(StatusCode, Json<Requested>), AppError> {
    if !matches!(req.kind.as_str(), "nightly" | "backfill") {
        return Err(AppError::Field {
            field: "kind".into(),
            problem: format!("{:?} is not one of nightly, backfill", req.kind),
        });
    }
    if req.suites.is_empty() || req.labels.is_empty() {
        return Err(AppError::Field {
            field: "suites".into(),
            problem: "give at least one suite and one label".into(),
        });
    }
    for s in &req.suites {
        queue::check_name("suite", s)?;
    }
    let commit = resolve_commit(&state, "commit", &req.commit)?;
    let mut jobs = Vec::new();
    for label in &req.labels {
        for suite in &req.suites {
            jobs.push(NewJob {
                label: label.clone(),
                spec: JobSpec {
                    kind: JobKind::Run,
                    scenarios: vec![format!("scenarios/{suite}")],
                    variant: None,
                    arms: vec![Arm {
                        name: "run".into(),
                        commit: commit.clone(),
                        env: req.env.clone(),
                    }],
                    order: vec![0],
                    list_commits: None,
                },
            });
        }
    }
    let max_attempts = state.queue.max_attempts;
    let spec = serde_json::to_value(&req).expect("a request serialises");
    let labels = req.labels.clone();
    let (request_id, jobs) = state
        .db(move |c| {
            queue::check_labels_known(c, &labels)?;
            Ok(queue::enqueue(
                c,
                &req.kind,
                &spec,
                None,
                &who.name,
                &jobs,
                max_attempts,
            )?)
        })
        .await?;
    Ok((StatusCode::CREATED, Json(Requested { request_id, jobs })))
}

/// `GET /api/queue`.
pub async fn overview(State(state): State<AppState>) -> Result<Json<queue::Overview>, AppError> {
    let offline = state.queue.offline_after_ms;
    Ok(Json(
        state
            .db(move |c| Ok(queue::overview(c, now_ms(), offline, 50)?))
            .await?,
    ))
}

/// `GET /api/queue/jobs/{id}`.
pub async fn job(
    State(state): State<AppState>,
    Path(id): Path<i64>,
) -> Result<Json<queue::JobRow>, AppError> {
    Ok(Json(state.db(move |c| Ok(queue::job(c, id)?)).await?))
}
