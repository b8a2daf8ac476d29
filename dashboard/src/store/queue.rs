//! The job queue: requests (a nightly run of suites at a commit, an A/B, a bisection step, a
//! backfill) split into jobs, one per adapter-class label; runners registered with the labels
//! they serve; claims with a lease that heartbeats extend.
//!
//! A job is claimed by one statement that picks the oldest claimable job of one of the runner's
//! labels and marks it in progress (rustc-perf's `dequeue_benchmark_job`): on PostgreSQL the pick
//! is `FOR UPDATE SKIP LOCKED`, so concurrent claimers never wait on or take the same row; on
//! SQLite the single `UPDATE ... RETURNING` runs under the database's one writer lock. Claimable
//! means queued, or in progress with its lease run out (its runner stopped heartbeating), and
//! claimed fewer than `max_attempts` times; a job whose lease ran out on its last attempt is
//! marked failed by [`reap`]. Every later call about a job names the attempt it was claimed as,
//! so a runner that lost its job cannot finish or fail it. Jobs of a label no online runner serves
//! wait, and say so in [`overview`], without holding up any other label.
//!
//! Times are epoch milliseconds passed in by the caller, so tests move the clock. Not for: HTTP
//! (see `server/queue.rs`), A/B statistics or bisection decisions (see [`crate::ab`]).

use std::collections::BTreeMap;

use serde::Serialize;
use tessera_results::queue::{Claimed, Completion, JobKind, JobSpec, Registration};

use super::StoreError;
use crate::db::{transaction, Backend, Connection, Row, Value};

/// How many times a job is claimed before it is marked failed.
pub const DEFAULT_MAX_ATTEMPTS: i64 = 3;
/// Most labels a runner may declare, jobs one request may make, arms and scenarios of a job.
pub const MAX_LABELS: usize = 16;
pub const MAX_SCENARIOS: usize = 64;
pub const MAX_ENV: usize = 32;
/// Most runs of one job (A/B: attempts times arms).
pub const MAX_ORDER: usize = 200;

/// Where a job is in its life.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JobStatus {
    Queued,
    InProgress,
    Done,
    Failed,
    /// A commit of the job did not build; never retried.
    BuildFailed,
}

impl JobStatus {
    pub fn as_str(self) -> &'static str {
        match self {
            JobStatus::Queued => "queued",
            JobStatus::InProgress => "in_progress",
            JobStatus::Done => "done",
            JobStatus::Failed => "failed",
            JobStatus::BuildFailed => "build_failed",
        }
    }

    pub fn parse(s: &str) -> Result<JobStatus, StoreError> {
        Ok(match s {
            "queued" => JobStatus::Queued,
            "in_progress" => JobStatus::InProgress,
            "done" => JobStatus::Done,
            "failed" => JobStatus::Failed,
            "build_failed" => JobStatus::BuildFailed,
            other => return Err(StoreError::Corrupt(format!("job status {other:?}"))),
        })
    }

    /// Done, failed or build-failed: the job will not run again.
    pub fn is_final(self) -> bool {
        !matches!(self, JobStatus::Queued | JobStatus::InProgress)
    }
}

/// A job to enqueue.
#[derive(Clone, Debug, PartialEq)]
pub struct NewJob {
    pub label: String,
    pub spec: JobSpec,
}

fn invalid(msg: impl Into<String>) -> StoreError {
    StoreError::Invalid(msg.into())
}

/// A label, runner name: 1 to 64 of letters, digits, `-`, `_`, `.`.
pub fn check_name(what: &str, s: &str) -> Result<(), StoreError> {
    let ok = !s.is_empty()
        && s.len() <= 64
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'));
    if ok {
        Ok(())
    } else {
        Err(invalid(format!(
            "{what} {s:?}: use 1 to 64 letters, digits, '-', '_' or '.'"
        )))
    }
}

/// A commit as a job names it: 7 to 40 hexadecimal digits.
pub fn check_commit(what: &str, s: &str) -> Result<(), StoreError> {
    if (7..=40).contains(&s.len()) && s.chars().all(|c| c.is_ascii_hexdigit()) {
        Ok(())
    } else {
        Err(invalid(format!(
            "{what} {s:?} is not a commit: give 7 to 40 hexadecimal digits"
        )))
    }
}

/// A scenario path: relative, inside the repository, no `..`.
fn check_scenario_path(s: &str) -> Result<(), StoreError> {
    let p = std::path::Path::new(s);
    let inside = !s.is_empty()
        && s.len() <= 256
        && p.is_relative()
        && p.components()
            .all(|c| matches!(c, std::path::Component::Normal(_)));
    if inside {
        Ok(())
    } else {
        Err(invalid(format!(
            "scenario path {s:?}: give a path relative to the repository root, without '..'"
        )))
    }
}

/// Checks a job's spec: what a runner will execute must be well formed before it is queued.
pub fn check_spec(spec: &JobSpec) -> Result<(), StoreError> {
    if spec.scenarios.is_empty() || spec.scenarios.len() > MAX_SCENARIOS {
        return Err(invalid(format!(
            "a job runs 1 to {MAX_SCENARIOS} scenario paths, not {}",
            spec.scenarios.len()
        )));
    }
    for s in &spec.scenarios {
        check_scenario_path(s)?;
    }
    let arms = match spec.kind {
        JobKind::Run => 1,
        JobKind::Ab => 2,
    };
    if spec.arms.len() != arms {
        return Err(invalid(format!(
            "a {:?} job has {arms} arm(s), not {}",
            spec.kind,
            spec.arms.len()
        )));
    }
    for arm in &spec.arms {
        check_name("arm", &arm.name)?;
        check_commit(&format!("arm {} commit", arm.name), &arm.commit)?;
        if arm.env.len() > MAX_ENV {
            return Err(invalid(format!(
                "arm {}: at most {MAX_ENV} environment variables",
                arm.name
            )));
        }
        for (k, v) in &arm.env {
            let ok = !k.is_empty()
                && k.len() <= 128
                && !k.starts_with(|c: char| c.is_ascii_digit())
                && k.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
            if !ok || v.len() > 4096 || v.contains('\0') {
                return Err(invalid(format!(
                    "arm {}: environment variable {k:?}: names are letters, digits and '_' (not \
                     starting with a digit), values at most 4096 bytes",
                    arm.name
                )));
            }
        }
    }
    if spec.order.is_empty() || spec.order.len() > MAX_ORDER {
        return Err(invalid(format!(
            "a job runs 1 to {MAX_ORDER} times, not {}",
            spec.order.len()
        )));
    }
    if let Some(bad) = spec.order.iter().find(|&&i| i >= spec.arms.len()) {
        return Err(invalid(format!(
            "order names arm {bad}, which does not exist"
        )));
    }
    if let Some(v) = &spec.variant {
        if v.is_empty() || v.len() > 256 {
            return Err(invalid("variant: 1 to 256 characters"));
        }
    }
    if let Some([a, b]) = &spec.list_commits {
        check_commit("list_commits", a)?;
        check_commit("list_commits", b)?;
    }
    Ok(())
}

fn check_registration(reg: &Registration) -> Result<(), StoreError> {
    check_name("runner name", &reg.name)?;
    if reg.labels.is_empty() || reg.labels.len() > MAX_LABELS {
        return Err(invalid(format!(
            "a runner declares 1 to {MAX_LABELS} labels, not {}",
            reg.labels.len()
        )));
    }
    for l in &reg.labels {
        check_name("label", l)?;
    }
    for (what, v) in [
        ("adapter", &reg.adapter),
        ("driver", &reg.driver),
        ("host", &reg.host),
    ] {
        if v.len() > 256 {
            return Err(invalid(format!("{what}: at most 256 characters")));
        }
    }
    Ok(())
}

/// Registers runner `reg.name` for the token `token_name` (or updates it: labels, adapter, driver,
/// host); returns its id. A name registered by another token is refused (409).
pub fn register(
    conn: &mut dyn Connection,
    reg: &Registration,
    token_name: &str,
    now_ms: i64,
) -> Result<i64, StoreError> {
    check_registration(reg)?;
    transaction(conn, |c| {
        c.execute(
            "INSERT INTO runners (name, token_name, adapter, driver, host, registered_at, \
             last_heartbeat_ms) VALUES ($1, $2, $3, $4, $5, $6, $7) ON CONFLICT (name) DO NOTHING",
            &[
                reg.name.as_str().into(),
                token_name.into(),
                reg.adapter.as_str().into(),
                reg.driver.as_str().into(),
                reg.host.as_str().into(),
                crate::now_rfc3339().into(),
                Value::Int(now_ms),
            ],
        )?;
        let row = c
            .query_opt(
                "SELECT id, token_name FROM runners WHERE name = $1",
                &[reg.name.as_str().into()],
            )?
            .ok_or_else(|| StoreError::Corrupt("runner row vanished".into()))?;
        let id = row.i64(0)?;
        if row.str(1)? != token_name {
            return Err(StoreError::Conflict(format!(
                "runner {:?} is registered with another token; pick another --name",
                reg.name
            )));
        }
        c.execute(
            "UPDATE runners SET adapter = $2, driver = $3, host = $4, last_heartbeat_ms = $5 \
             WHERE id = $1",
            &[
                Value::Int(id),
                reg.adapter.as_str().into(),
                reg.driver.as_str().into(),
                reg.host.as_str().into(),
                Value::Int(now_ms),
            ],
        )?;
        c.execute(
            "DELETE FROM runner_labels WHERE runner_id = $1",
            &[Value::Int(id)],
        )?;
        for l in &reg.labels {
            c.execute(
                "INSERT INTO runner_labels (runner_id, label) VALUES ($1, $2) \
                 ON CONFLICT DO NOTHING",
                &[Value::Int(id), l.as_str().into()],
            )?;
        }
        Ok(id)
    })
}

/// The id of runner `name` and the token it was registered with.
pub fn runner(conn: &mut dyn Connection, name: &str) -> Result<(i64, String), StoreError> {
    let row = conn
        .query_opt(
            "SELECT id, token_name FROM runners WHERE name = $1",
            &[name.into()],
        )?
        .ok_or_else(|| StoreError::NotFound(format!("runner {name:?} (register it first)")))?;
    Ok((row.i64(0)?, row.string(1)?))
}

/// Queues a request and its jobs in one transaction; returns the request id and the job ids.
pub fn enqueue(
    conn: &mut dyn Connection,
    kind: &str,
    request_spec: &serde_json::Value,
    bisection_id: Option<i64>,
    created_by: &str,
    jobs: &[NewJob],
    max_attempts: i64,
) -> Result<(i64, Vec<i64>), StoreError> {
    if jobs.is_empty() || jobs.len() > MAX_LABELS {
        return Err(invalid(format!(
            "a request makes 1 to {MAX_LABELS} jobs, not {}",
            jobs.len()
        )));
    }
    for j in jobs {
        check_name("label", &j.label)?;
        check_spec(&j.spec)?;
    }
    if !(1..=10).contains(&max_attempts) {
        return Err(invalid("max_attempts: 1 to 10"));
    }
    transaction(conn, |c| {
        enqueue_in(
            c,
            kind,
            request_spec,
            bisection_id,
            created_by,
            jobs,
            max_attempts,
        )
    })
}

/// [`enqueue`] for a caller that holds a transaction (a bisection queueing its next step).
pub fn enqueue_in(
    c: &mut dyn Connection,
    kind: &str,
    request_spec: &serde_json::Value,
    bisection_id: Option<i64>,
    created_by: &str,
    jobs: &[NewJob],
    max_attempts: i64,
) -> Result<(i64, Vec<i64>), StoreError> {
    let now = crate::now_rfc3339();
    let request_id = c.query(
        "INSERT INTO queue_requests (kind, spec, bisection_id, created_by, created_at) \
         VALUES ($1, $2, $3, $4, $5) RETURNING id",
        &[
            kind.into(),
            request_spec.to_string().into(),
            bisection_id.into(),
            created_by.into(),
            now.as_str().into(),
        ],
    )?[0]
        .i64(0)?;
    let mut ids = Vec::with_capacity(jobs.len());
    for j in jobs {
        let spec = serde_json::to_string(&j.spec).expect("a job spec serialises");
        ids.push(
            c.query(
                "INSERT INTO queue_jobs (request_id, label, spec, status, attempts, max_attempts, \
                 error, created_at) VALUES ($1, $2, $3, 'queued', 0, $4, '', $5) RETURNING id",
                &[
                    Value::Int(request_id),
                    j.label.as_str().into(),
                    spec.into(),
                    Value::Int(max_attempts),
                    now.as_str().into(),
                ],
            )?[0]
                .i64(0)?,
        );
    }
    Ok((request_id, ids))
}

/// Marks failed every job whose lease ran out on its last allowed attempt; returns how many.
pub fn reap(conn: &mut dyn Connection, now_ms: i64) -> Result<u64, StoreError> {
    Ok(conn.execute(
        "UPDATE queue_jobs SET status = 'failed', finished_at = $2, \
         error = 'its runner stopped heartbeating on the last allowed attempt (lease expired)' \
         WHERE status = 'in_progress' AND lease_expires_ms < $1 AND attempts >= max_attempts",
        &[Value::Int(now_ms), crate::now_rfc3339().into()],
    )?)
}

/// The claim statement: one `UPDATE` whose sub-select picks the job. PostgreSQL adds `FOR UPDATE
/// SKIP LOCKED` to the pick; SQLite needs nothing more, as one statement holds its writer lock.
fn claim_sql(backend: Backend) -> String {
    let lock = match backend {
        Backend::Postgres => " FOR UPDATE SKIP LOCKED",
        Backend::Sqlite => "",
    };
    format!(
        "UPDATE queue_jobs SET status = 'in_progress', runner_id = $1, attempts = attempts + 1, \
         lease_expires_ms = $3, started_at = $4 \
         WHERE id = (SELECT id FROM queue_jobs \
             WHERE (status = 'queued' OR (status = 'in_progress' AND lease_expires_ms < $2)) \
             AND attempts < max_attempts \
             AND label IN (SELECT label FROM runner_labels WHERE runner_id = $1) \
             ORDER BY id LIMIT 1{lock}) \
         RETURNING id, attempts, label, spec"
    )
}

/// Claims the oldest claimable job of one of the runner's labels, with a lease of `lease_ms`.
pub fn claim(
    conn: &mut dyn Connection,
    runner_id: i64,
    now_ms: i64,
    lease_ms: i64,
) -> Result<Option<Claimed>, StoreError> {
    reap(conn, now_ms)?;
    conn.execute(
        "UPDATE runners SET last_heartbeat_ms = $2 WHERE id = $1",
        &[Value::Int(runner_id), Value::Int(now_ms)],
    )?;
    let sql = claim_sql(conn.backend());
    let Some(row) = conn.query_opt(
        &sql,
        &[
            Value::Int(runner_id),
            Value::Int(now_ms),
            Value::Int(now_ms + lease_ms),
            crate::now_rfc3339().into(),
        ],
    )?
    else {
        return Ok(None);
    };
    Ok(Some(Claimed {
        job_id: row.i64(0)?,
        attempt: row.i64(1)?,
        label: row.string(2)?,
        lease_secs: (lease_ms / 1000).max(1) as u64,
        spec: parse_spec(row.str(3)?)?,
    }))
}

fn parse_spec(s: &str) -> Result<JobSpec, StoreError> {
    serde_json::from_str(s).map_err(|e| StoreError::Corrupt(format!("job spec: {e}")))
}

/// Records that the runner is alive and extends the lease of the job it holds; `false` when that
/// job is no longer its own.
pub fn heartbeat(
    conn: &mut dyn Connection,
    runner_id: i64,
    job: Option<(i64, i64)>,
    now_ms: i64,
    lease_ms: i64,
) -> Result<bool, StoreError> {
    conn.execute(
        "UPDATE runners SET last_heartbeat_ms = $2 WHERE id = $1",
        &[Value::Int(runner_id), Value::Int(now_ms)],
    )?;
    let Some((job_id, attempt)) = job else {
        return Ok(true);
    };
    let n = conn.execute(
        "UPDATE queue_jobs SET lease_expires_ms = $4 \
         WHERE id = $1 AND runner_id = $2 AND attempts = $3 AND status = 'in_progress'",
        &[
            Value::Int(job_id),
            Value::Int(runner_id),
            Value::Int(attempt),
            Value::Int(now_ms + lease_ms),
        ],
    )?;
    Ok(n == 1)
}

fn lost(job_id: i64, attempt: i64) -> StoreError {
    StoreError::Conflict(format!(
        "job {job_id} attempt {attempt} is not held by this runner (its lease ran out and another \
         runner took it, or it is finished)"
    ))
}

/// Marks a held job done with its outcome. Call inside a transaction to act on the outcome in the
/// same one (a bisection's next step).
pub fn complete(
    conn: &mut dyn Connection,
    runner_id: i64,
    job_id: i64,
    outcome: &Completion,
) -> Result<(), StoreError> {
    let n = conn.execute(
        "UPDATE queue_jobs SET status = 'done', outcome = $4, finished_at = $5, \
         lease_expires_ms = NULL \
         WHERE id = $1 AND runner_id = $2 AND attempts = $3 AND status = 'in_progress'",
        &[
            Value::Int(job_id),
            Value::Int(runner_id),
            Value::Int(outcome.attempt),
            serde_json::to_string(outcome)
                .expect("a completion serialises")
                .into(),
            crate::now_rfc3339().into(),
        ],
    )?;
    if n == 0 {
        return Err(lost(job_id, outcome.attempt));
    }
    Ok(())
}

/// Records a held job's failure: back to the queue while attempts remain, else failed; a build
/// failure is final at once. Returns the status the job is left in.
pub fn fail(
    conn: &mut dyn Connection,
    runner_id: i64,
    job_id: i64,
    attempt: i64,
    error: &str,
    build_failed: bool,
    outcome: Option<&Completion>,
) -> Result<JobStatus, StoreError> {
    let error: String = error.chars().take(4000).collect();
    let row = conn.query_opt(
        "UPDATE queue_jobs SET \
         status = CASE WHEN $5 = 1 THEN 'build_failed' WHEN attempts < max_attempts THEN 'queued' \
             ELSE 'failed' END, \
         finished_at = CASE WHEN $5 = 1 OR attempts >= max_attempts THEN $6 ELSE NULL END, \
         runner_id = CASE WHEN $5 = 1 OR attempts >= max_attempts THEN runner_id ELSE NULL END, \
         error = $4, outcome = $7, lease_expires_ms = NULL \
         WHERE id = $1 AND runner_id = $2 AND attempts = $3 AND status = 'in_progress' \
         RETURNING status",
        &[
            Value::Int(job_id),
            Value::Int(runner_id),
            Value::Int(attempt),
            error.into(),
            Value::Int(build_failed as i64),
            crate::now_rfc3339().into(),
            outcome
                .map(|o| serde_json::to_string(o).expect("a completion serialises"))
                .into(),
        ],
    )?;
    match row {
        Some(r) => JobStatus::parse(r.str(0)?),
        None => Err(lost(job_id, attempt)),
    }
}

/// Hands a held job back unfinished (the runner is stopping): queued again, the attempt not
/// counted.
pub fn give_back(
    conn: &mut dyn Connection,
    runner_id: i64,
    job_id: i64,
    attempt: i64,
) -> Result<(), StoreError> {
    let n = conn.execute(
        "UPDATE queue_jobs SET status = 'queued', attempts = attempts - 1, runner_id = NULL, \
         lease_expires_ms = NULL \
         WHERE id = $1 AND runner_id = $2 AND attempts = $3 AND status = 'in_progress'",
        &[
            Value::Int(job_id),
            Value::Int(runner_id),
            Value::Int(attempt),
        ],
    )?;
    if n == 0 {
        return Err(lost(job_id, attempt));
    }
    Ok(())
}

/// A job as listed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct JobRow {
    pub id: i64,
    pub request_id: i64,
    /// The request's kind: `nightly`, `backfill`, `ab`, `bisect`.
    pub kind: String,
    pub label: String,
    pub status: JobStatus,
    pub attempts: i64,
    pub max_attempts: i64,
    pub runner: Option<String>,
    pub lease_expires_ms: Option<i64>,
    pub error: String,
    pub created_at: String,
    pub started_at: Option<String>,
    pub finished_at: Option<String>,
    pub spec: JobSpec,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub outcome: Option<Completion>,
    /// Why a queued job is not running: no online runner has its label.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub waiting: Option<String>,
}

const JOB_COLUMNS: &str = "j.id, j.request_id, q.kind, j.label, j.status, j.attempts, \
    j.max_attempts, r.name, j.lease_expires_ms, j.error, j.created_at, j.started_at, \
    j.finished_at, j.spec, j.outcome";

fn job_row(r: &Row) -> Result<JobRow, StoreError> {
    Ok(JobRow {
        id: r.i64(0)?,
        request_id: r.i64(1)?,
        kind: r.string(2)?,
        label: r.string(3)?,
        status: JobStatus::parse(r.str(4)?)?,
        attempts: r.i64(5)?,
        max_attempts: r.i64(6)?,
        runner: r.opt_string(7)?,
        lease_expires_ms: r.opt_i64(8)?,
        error: r.string(9)?,
        created_at: r.string(10)?,
        started_at: r.opt_string(11)?,
        finished_at: r.opt_string(12)?,
        spec: parse_spec(r.str(13)?)?,
        outcome: r
            .opt_string(14)?
            .map(|s| serde_json::from_str(&s))
            .transpose()
            .map_err(|e| StoreError::Corrupt(format!("job outcome: {e}")))?,
        waiting: None,
    })
}

/// One job by id.
pub fn job(conn: &mut dyn Connection, id: i64) -> Result<JobRow, StoreError> {
    let sql = format!(
        "SELECT {JOB_COLUMNS} FROM queue_jobs j JOIN queue_requests q ON q.id = j.request_id \
         LEFT JOIN runners r ON r.id = j.runner_id WHERE j.id = $1"
    );
    let row = conn
        .query_opt(&sql, &[Value::Int(id)])?
        .ok_or_else(|| StoreError::NotFound(format!("job {id}")))?;
    job_row(&row)
}

/// The jobs of one request, by id.
pub fn request_jobs(conn: &mut dyn Connection, request_id: i64) -> Result<Vec<JobRow>, StoreError> {
    let sql = format!(
        "SELECT {JOB_COLUMNS} FROM queue_jobs j JOIN queue_requests q ON q.id = j.request_id \
         LEFT JOIN runners r ON r.id = j.runner_id WHERE j.request_id = $1 ORDER BY j.id"
    );
    conn.query(&sql, &[Value::Int(request_id)])?
        .iter()
        .map(job_row)
        .collect()
}

/// A runner as listed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunnerRow {
    pub name: String,
    pub labels: Vec<String>,
    pub adapter: String,
    pub driver: String,
    pub host: String,
    pub last_heartbeat_ms: i64,
    /// Heard from within the offline threshold.
    pub online: bool,
    /// The job it holds, if any.
    pub current_job: Option<i64>,
}

/// The queue as the dashboard shows it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Overview {
    pub runners: Vec<RunnerRow>,
    /// Queued and in-progress jobs, oldest first.
    pub active: Vec<JobRow>,
    /// The newest finished jobs, newest first.
    pub finished: Vec<JobRow>,
    /// Queued jobs per label.
    pub queued_by_label: BTreeMap<String, i64>,
}

/// Every runner with its labels, online state and current job. A runner is online when heard
/// from within `offline_after_ms`.
pub fn runners(
    conn: &mut dyn Connection,
    now_ms: i64,
    offline_after_ms: i64,
) -> Result<Vec<RunnerRow>, StoreError> {
    let mut labels: BTreeMap<i64, Vec<String>> = BTreeMap::new();
    for r in conn.query(
        "SELECT runner_id, label FROM runner_labels ORDER BY runner_id, label",
        &[],
    )? {
        labels.entry(r.i64(0)?).or_default().push(r.string(1)?);
    }
    conn.query(
        "SELECT r.id, r.name, r.adapter, r.driver, r.host, r.last_heartbeat_ms, \
         (SELECT MIN(j.id) FROM queue_jobs j WHERE j.runner_id = r.id AND j.status = 'in_progress') \
         FROM runners r ORDER BY r.name",
        &[],
    )?
    .iter()
    .map(|r| {
        let last = r.i64(5)?;
        Ok(RunnerRow {
            labels: labels.remove(&r.i64(0)?).unwrap_or_default(),
            name: r.string(1)?,
            adapter: r.string(2)?,
            driver: r.string(3)?,
            host: r.string(4)?,
            last_heartbeat_ms: last,
            online: now_ms - last <= offline_after_ms,
            current_job: r.opt_i64(6)?,
        })
    })
    .collect()
}

/// Runners, active jobs (each queued one saying when no online runner has its label) and the
/// newest `finished` finished jobs.
pub fn overview(
    conn: &mut dyn Connection,
    now_ms: i64,
    offline_after_ms: i64,
    finished: i64,
) -> Result<Overview, StoreError> {
    reap(conn, now_ms)?;
    let runners = runners(conn, now_ms, offline_after_ms)?;
    let served: std::collections::BTreeSet<&str> = runners
        .iter()
        .filter(|r| r.online)
        .flat_map(|r| r.labels.iter().map(String::as_str))
        .collect();
    let sql = format!(
        "SELECT {JOB_COLUMNS} FROM queue_jobs j JOIN queue_requests q ON q.id = j.request_id \
         LEFT JOIN runners r ON r.id = j.runner_id \
         WHERE j.status IN ('queued', 'in_progress') ORDER BY j.id"
    );
    let mut active: Vec<JobRow> = conn
        .query(&sql, &[])?
        .iter()
        .map(job_row)
        .collect::<Result<_, _>>()?;
    let mut queued_by_label = BTreeMap::new();
    for j in &mut active {
        if j.status == JobStatus::Queued {
            *queued_by_label.entry(j.label.clone()).or_insert(0) += 1;
            if !served.contains(j.label.as_str()) {
                j.waiting = Some(format!("no online runner has label {:?}", j.label));
            }
        }
    }
    let sql = format!(
        "SELECT {JOB_COLUMNS} FROM queue_jobs j JOIN queue_requests q ON q.id = j.request_id \
         LEFT JOIN runners r ON r.id = j.runner_id \
         WHERE j.status NOT IN ('queued', 'in_progress') ORDER BY j.id DESC LIMIT $1"
    );
    let finished = conn
        .query(&sql, &[Value::Int(finished)])?
        .iter()
        .map(job_row)
        .collect::<Result<_, _>>()?;
    Ok(Overview {
        runners,
        active,
        finished,
        queued_by_label,
    })
}

/// Why a runner-scope upload for job `job_id` is refused, or `None` when it is allowed: the job
/// is in progress, held by a runner registered with token `token_name`, and the run's `commit` is
/// one of the job's arms' commits.
pub fn upload_refusal(
    conn: &mut dyn Connection,
    job_id: i64,
    token_name: &str,
    commit: Option<&str>,
) -> Result<Option<String>, StoreError> {
    let row = conn.query_opt(
        "SELECT j.status, j.spec, r.token_name FROM queue_jobs j \
         LEFT JOIN runners r ON r.id = j.runner_id WHERE j.id = $1",
        &[Value::Int(job_id)],
    )?;
    let Some(row) = row else {
        return Ok(Some(format!("job {job_id} does not exist")));
    };
    if row.str(0)? != "in_progress" || row.opt_string(2)?.as_deref() != Some(token_name) {
        return Ok(Some(format!(
            "job {job_id} is not in progress on a runner of token {token_name:?}"
        )));
    }
    let spec = parse_spec(row.str(1)?)?;
    let Some(commit) = commit else {
        return Ok(Some("the run records no commit".into()));
    };
    if !spec
        .arms
        .iter()
        .any(|a| commit.starts_with(&a.commit) || a.commit.starts_with(commit))
    {
        return Ok(Some(format!(
            "the run's commit {commit} is not a commit of job {job_id}"
        )));
    }
    Ok(None)
}

/// Refuses labels no runner has ever registered with (a typo would otherwise queue jobs that
/// wait for ever); labels whose runners are only offline are fine: their jobs wait, visibly.
pub fn check_labels_known(conn: &mut dyn Connection, labels: &[String]) -> Result<(), StoreError> {
    let known: Vec<String> = conn
        .query(
            "SELECT DISTINCT label FROM runner_labels ORDER BY label",
            &[],
        )?
        .iter()
        .map(|r| r.string(0))
        .collect::<Result<_, _>>()?;
    for l in labels {
        check_name("label", l)?;
        if !known.contains(l) {
            return Err(invalid(format!(
                "label {l:?}: no runner has registered with it (known labels: {})",
                if known.is_empty() {
                    "none yet".to_string()
                } else {
                    known.join(", ")
                }
            )));
        }
    }
    Ok(())
}

/// A label of the runner on adapter `adapter` that was heard from last (the bisect form's
/// default), if any.
pub fn label_on_adapter(
    conn: &mut dyn Connection,
    adapter: &str,
) -> Result<Option<String>, StoreError> {
    Ok(conn
        .query_opt(
            "SELECT l.label FROM runners r JOIN runner_labels l ON l.runner_id = r.id
             WHERE r.adapter = $1 ORDER BY r.last_heartbeat_ms DESC, l.label LIMIT 1",
            &[adapter.into()],
        )?
        .map(|l| l.string(0))
        .transpose()?)
}
