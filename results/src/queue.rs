//! The job queue's wire format: what a runner sends to the dashboard's `/api/runners` and
//! `/api/queue` endpoints and what it gets back. One definition for both sides (`tessera runner`
//! and `tessera-dashboard`), so a runner and the dashboard cannot disagree on a job's shape.
//!
//! A job is one unit of queued work for one adapter class (`label`): one or more arms (an arm is
//! an environment: a commit plus environment variables) and the order they run in. A nightly or
//! backfill job has one arm run once and uploads the run; an A/B job has two arms run back to back
//! in a shuffled order, and its runner sends back one [`Sample`] per attempt instead of a run.
//! Not for: sending (the harness's `runner/`), storing (the dashboard's `store/queue.rs`).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// Header naming the job a runner-scope upload belongs to (`POST /api/runs`).
pub const JOB_HEADER: &str = "x-tessera-job";

/// What a job asks a runner to do.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum JobKind {
    /// Run the scenarios once at the one arm and upload the run (nightly, backfill).
    Run,
    /// Run the arms in `order`, measure `variant` of the one scenario, send samples back.
    Ab,
}

/// One environment of a job: a commit and the environment variables `tessera run` gets.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Arm {
    /// `a`, `b`, or `run`.
    pub name: String,
    /// Full commit hash, or any revision `git rev-parse` resolves in the runner's repository.
    pub commit: String,
    #[serde(default)]
    pub env: BTreeMap<String, String>,
}

/// The work of one job.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JobSpec {
    pub kind: JobKind,
    /// Scenario files or folders, relative to the repository root.
    pub scenarios: Vec<String>,
    /// A/B: the variant whose measures are sampled (`None`: every variant).
    #[serde(default)]
    pub variant: Option<String>,
    pub arms: Vec<Arm>,
    /// Indices into `arms`, run in this order (A/B: each arm `attempts` times, shuffled in pairs).
    pub order: Vec<usize>,
    /// Also list the first-parent commits from `[0]` (exclusive) to `[1]` (inclusive), oldest
    /// first, in [`Completion::commits`] (the first step of a bisection).
    #[serde(default)]
    pub list_commits: Option<[String; 2]>,
}

/// `POST /api/runners/register`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Registration {
    /// Unique per runner process; re-registering under the same name updates the row.
    pub name: String,
    /// The adapter classes this runner serves (`llvmpipe`, `nvidia`, ...).
    pub labels: Vec<String>,
    pub adapter: String,
    pub driver: String,
    pub host: String,
}

/// `POST /api/queue/claim` body.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ClaimRequest {
    pub runner: String,
}

/// A claimed job: `attempt` must come back with every later call about it, so that a runner whose
/// lease expired (and whose job another runner took) cannot complete it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Claimed {
    pub job_id: i64,
    pub attempt: i64,
    pub label: String,
    /// Heartbeat at least this often (seconds) or lose the job.
    pub lease_secs: u64,
    pub spec: JobSpec,
}

/// `POST /api/runners/heartbeat`: the runner is alive; `job` is the job it holds, if any.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Heartbeat {
    pub runner: String,
    #[serde(default)]
    pub job: Option<JobRef>,
}

/// A held job: its id and the attempt it was claimed as.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct JobRef {
    pub job_id: i64,
    pub attempt: i64,
}

/// The answer to a heartbeat: `false` when the job is no longer this runner's (its lease ran out
/// and another runner took it, or it was cancelled): stop working on it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct HeartbeatReply {
    pub job_kept: bool,
}

/// One measured attempt of an A/B arm.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sample {
    /// Index into the job's `arms`.
    pub arm: usize,
    /// Position in the job's `order`.
    pub seq: usize,
    /// Measure name (store key, e.g. `gpu_ms.median`, `psnr`) to value.
    pub measures: BTreeMap<String, f64>,
    /// A digest of the compared frames (see the runner's `frames_digest`); `None` when the run
    /// saved none.
    #[serde(default)]
    pub frames_digest: Option<String>,
}

/// `POST /api/queue/jobs/{id}/complete`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Completion {
    pub runner: String,
    pub attempt: i64,
    /// Run ids uploaded for this job (kind `run`).
    #[serde(default)]
    pub runs: Vec<String>,
    /// A/B samples (kind `ab`).
    #[serde(default)]
    pub samples: Vec<Sample>,
    /// First-parent commits asked for by [`JobSpec::list_commits`], oldest first.
    #[serde(default)]
    pub commits: Option<Vec<String>>,
}

/// `POST /api/queue/jobs/{id}/fail`: the runner's error. `build_failed` names the commit that did
/// not build: the job is then not retried (a bisection skips that commit).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Failure {
    pub runner: String,
    pub attempt: i64,
    pub error: String,
    #[serde(default)]
    pub build_failed: Option<String>,
    /// The commits listed before the failure (a bisection's first step), if any.
    #[serde(default)]
    pub commits: Option<Vec<String>>,
}

/// `POST /api/queue/jobs/{id}/return`: the runner stops (SIGTERM) and hands the job back
/// unfinished; the attempt is not counted.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Return {
    pub runner: String,
    pub attempt: i64,
}
