//! Bisection: A/B steps over the first-parent commits of a range until one commit, the culprit,
//! is left, or the change is shown to be spread over several.
//!
//! Step 0 is an A/B of the good commit against the bad one; its runner also lists the
//! first-parent commits between them. Its estimate of the measure is the full change (for a time,
//! relative to A's median: see [`effect`]); if it is not significant the bisection ends
//! `no_change`. Every later step is an A/B of the good commit
//! (A) against a commit in the middle of what is left (B), and reads the fraction of the full
//! change that commit already shows: at most 1/4 (or not significant) is good, at least 3/4 is
//! bad, anything between is `spread` (part of the change before it, part after). A commit that
//! does not build is skipped (`git bisect skip`), and the next step takes its neighbour. When
//! one commit is left it is the culprit, recorded on the alert the bisection came from.
//!
//! More attempts where a step has not decided (Pinpoint adds attempts to an "unknown"
//! comparison): a step whose measure is not significant but has a p-value below [`UNSURE_P`], or
//! that reads `spread`, runs once more at twice the attempts (at most [`super::MAX_ATTEMPTS`])
//! before it decides; the later steps keep the larger count, since the noise that needed it does
//! not go away.
//!
//! Runs inside the transaction that finishes each step's job, so a step's result and the next
//! step's job are stored together: a runner killed in between loses neither. Not for: HTTP, the
//! statistics (see [`super::table`]).

use serde::{Deserialize, Serialize};
use tessera_results::queue::Arm;

use super::{table, Row};
use crate::db::{Connection, Value};
use crate::store::queue::{self, JobStatus, NewJob};
use crate::store::StoreError;

/// What a bisection is asked to find.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Params {
    /// Scenario file, relative to the repository root.
    pub scenario: String,
    pub variant: String,
    /// A store key (`gpu_ms.median`, `psnr`, ...) or `frames_changed`.
    pub measure: String,
    pub good: String,
    pub bad: String,
    pub label: String,
    #[serde(default = "default_attempts")]
    pub attempts: usize,
    /// The alert whose range this is, if any.
    #[serde(default)]
    pub regression_id: Option<i64>,
}

fn default_attempts() -> usize {
    super::DEFAULT_ATTEMPTS
}

/// Below this p-value (and above [`super::ALPHA`]) a step has not decided whether its commit
/// differs: more attempts may tell. Above it the two read the same.
pub const UNSURE_P: f64 = 0.25;

/// Progress kept between steps (`bisections.detail`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Progress {
    /// Index in `commits` of the newest commit known good.
    pub lo: usize,
    /// Index of the oldest commit known bad.
    pub hi: usize,
    /// [`effect`] of step 0 (good against bad).
    pub full_effect: Option<f64>,
    /// Why the bisection ended, in words.
    pub message: String,
    /// The commit whose step is being run again with more attempts (once per step).
    #[serde(default)]
    pub rerun: Option<String>,
}

/// What the request of a step records (`queue_requests.spec`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StepSpec {
    pub bisection: i64,
    pub step: usize,
    /// The commit tested against the good one.
    pub commit: String,
}

fn invalid(msg: impl Into<String>) -> StoreError {
    StoreError::Invalid(msg.into())
}

/// Checks `p` and queues step 0; returns the bisection's id. Call inside a transaction.
pub fn create(
    conn: &mut dyn Connection,
    p: &Params,
    created_by: &str,
    max_attempts: i64,
) -> Result<i64, StoreError> {
    queue::check_commit("good", &p.good)?;
    queue::check_commit("bad", &p.bad)?;
    queue::check_name("label", &p.label)?;
    if p.good == p.bad {
        return Err(invalid("good and bad are the same commit"));
    }
    let measure_ok = p.measure == super::FRAMES_CHANGED
        || tessera_results::measure::Key::parse(&p.measure).is_some();
    if !measure_ok {
        return Err(invalid(format!(
            "measure {:?} is not a measure name (gpu_ms.median, psnr, flip, cvvdp, ...) or {}",
            p.measure,
            super::FRAMES_CHANGED
        )));
    }
    if p.variant.is_empty() || p.variant.len() > 256 {
        return Err(invalid("variant: 1 to 256 characters"));
    }
    let now = crate::now_rfc3339();
    let id = conn.query(
        "INSERT INTO bisections (regression_id, scenario, variant, measure, label, good, bad, \
         attempts, state, commits, skipped, detail, created_by, created_at, updated_at) \
         VALUES ($1, $2, $3, $4, $5, $6, $7, $8, 'running', '[]', '[]', $9, $10, $11, $11) \
         RETURNING id",
        &[
            p.regression_id.into(),
            p.scenario.as_str().into(),
            p.variant.as_str().into(),
            p.measure.as_str().into(),
            p.label.as_str().into(),
            p.good.as_str().into(),
            p.bad.as_str().into(),
            Value::Int(p.attempts as i64),
            serde_json::to_string(&Progress::default()).unwrap().into(),
            created_by.into(),
            now.into(),
        ],
    )?[0]
        .i64(0)?;
    let spec = super::spec(
        &p.scenario,
        Some(&p.variant),
        arm("a", &p.good),
        arm("b", &p.bad),
        p.attempts,
        Some([p.good.clone(), p.bad.clone()]),
    )?;
    queue_step(
        conn,
        id,
        0,
        &p.bad,
        &p.label,
        spec,
        created_by,
        max_attempts,
    )?;
    Ok(id)
}

fn arm(name: &str, commit: &str) -> Arm {
    Arm {
        name: name.into(),
        commit: commit.into(),
        env: Default::default(),
    }
}

#[allow(clippy::too_many_arguments)]
fn queue_step(
    conn: &mut dyn Connection,
    bisection: i64,
    step: usize,
    commit: &str,
    label: &str,
    spec: tessera_results::queue::JobSpec,
    created_by: &str,
    max_attempts: i64,
) -> Result<(), StoreError> {
    let step_spec = StepSpec {
        bisection,
        step,
        commit: commit.into(),
    };
    queue::enqueue_in(
        conn,
        "bisect",
        &serde_json::to_value(&step_spec).unwrap(),
        Some(bisection),
        created_by,
        &[NewJob {
            label: label.into(),
            spec,
        }],
        max_attempts,
    )?;
    Ok(())
}

/// A stored bisection.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Bisection {
    pub id: i64,
    pub regression_id: Option<i64>,
    pub scenario: String,
    pub variant: String,
    pub measure: String,
    pub label: String,
    pub good: String,
    pub bad: String,
    pub attempts: i64,
    /// `running`, `done` (culprit found), `spread`, `no_change`, `skipped` (only commits that do
    /// not build are left), `failed`.
    pub state: String,
    /// The range, good first and bad last, first-parent order (empty until step 0 is done).
    pub commits: Vec<String>,
    pub skipped: Vec<String>,
    pub culprit: Option<String>,
    pub progress: Progress,
    pub created_at: String,
    pub updated_at: String,
}

fn corrupt(e: serde_json::Error) -> StoreError {
    StoreError::Corrupt(format!("bisection: {e}"))
}

pub fn get(conn: &mut dyn Connection, id: i64) -> Result<Bisection, StoreError> {
    let r = conn
        .query_opt(
            "SELECT id, regression_id, scenario, variant, measure, label, good, bad, attempts, \
             state, commits, skipped, culprit, detail, created_at, updated_at \
             FROM bisections WHERE id = $1",
            &[Value::Int(id)],
        )?
        .ok_or_else(|| StoreError::NotFound(format!("bisection {id}")))?;
    Ok(Bisection {
        id: r.i64(0)?,
        regression_id: r.opt_i64(1)?,
        scenario: r.string(2)?,
        variant: r.string(3)?,
        measure: r.string(4)?,
        label: r.string(5)?,
        good: r.string(6)?,
        bad: r.string(7)?,
        attempts: r.i64(8)?,
        state: r.string(9)?,
        commits: serde_json::from_str(r.str(10)?).map_err(corrupt)?,
        skipped: serde_json::from_str(r.str(11)?).map_err(corrupt)?,
        culprit: r.opt_string(12)?,
        progress: serde_json::from_str(r.str(13)?).map_err(corrupt)?,
        created_at: r.string(14)?,
        updated_at: r.string(15)?,
    })
}

fn save(conn: &mut dyn Connection, b: &Bisection) -> Result<(), StoreError> {
    conn.execute(
        "UPDATE bisections SET state = $2, commits = $3, skipped = $4, culprit = $5, detail = $6, \
         updated_at = $7, attempts = $8 WHERE id = $1",
        &[
            Value::Int(b.id),
            b.state.as_str().into(),
            serde_json::to_string(&b.commits).unwrap().into(),
            serde_json::to_string(&b.skipped).unwrap().into(),
            b.culprit.clone().into(),
            serde_json::to_string(&b.progress).unwrap().into(),
            crate::now_rfc3339().into(),
            Value::Int(b.attempts),
        ],
    )?;
    Ok(())
}

/// The size of a step's change that fractions compare: for a time (GPU or CPU ms, of the frame or
/// of a pass) B − A relative to A's median, since a CPU adapter's times scale with the machine's
/// load, which changes between steps but not within a back-to-back pair; for anything else
/// (PSNR, FLIP, JOD, `frames_changed`) B − A itself.
pub fn effect(row: &Row) -> f64 {
    use tessera_results::measure::{Key, Measure};
    let is_time = Key::parse(&row.measure)
        .is_some_and(|k| matches!(k.measure, Measure::GpuMs | Measure::CpuMs));
    if is_time {
        row.relative.unwrap_or(0.0)
    } else {
        row.estimate
    }
}

/// How a step's commit reads against the full change.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Decision {
    Good,
    Bad,
    Spread,
}

/// The fraction of the full change a step shows, and what it means.
pub fn decide(row: Option<&Row>, full_effect: f64) -> (Option<f64>, Decision) {
    let Some(row) = row else {
        return (None, Decision::Good);
    };
    let fraction = if full_effect != 0.0 {
        effect(row) / full_effect
    } else {
        0.0
    };
    let decision = if row.verdict != "changed" || fraction <= 0.25 {
        Decision::Good
    } else if fraction >= 0.75 {
        Decision::Bad
    } else {
        Decision::Spread
    };
    (Some(fraction), decision)
}

/// Advances the bisection job `job_id` belongs to, if any: called in the transaction that
/// finished the job (done, failed or build-failed).
pub fn on_job_finished(conn: &mut dyn Connection, job_id: i64) -> Result<(), StoreError> {
    let Some(r) = conn.query_opt(
        "SELECT q.bisection_id, q.spec, q.created_by FROM queue_jobs j \
         JOIN queue_requests q ON q.id = j.request_id WHERE j.id = $1",
        &[Value::Int(job_id)],
    )?
    else {
        return Ok(());
    };
    let Some(bisection) = r.opt_i64(0)? else {
        return Ok(());
    };
    let step: StepSpec = serde_json::from_str(r.str(1)?).map_err(corrupt)?;
    let created_by = r.string(2)?;
    let job = queue::job(conn, job_id)?;
    let mut b = get(conn, bisection)?;
    if b.state != "running" {
        return Ok(());
    }
    let max_attempts = job.max_attempts;
    match job.status {
        JobStatus::Done => {}
        JobStatus::BuildFailed if step.step > 0 => {
            b.skipped.push(step.commit.clone());
            return next(conn, &mut b, &created_by, max_attempts);
        }
        JobStatus::BuildFailed | JobStatus::Failed => {
            b.state = "failed".into();
            b.progress.message = format!("step {} failed: {}", step.step, job.error);
            save(conn, &b)?;
            return record_on_alert(conn, &b);
        }
        JobStatus::Queued | JobStatus::InProgress => return Ok(()),
    }
    let outcome = job
        .outcome
        .ok_or_else(|| StoreError::Corrupt(format!("job {job_id} is done without outcome")))?;
    let rows = table(&outcome.samples);
    let row = rows.iter().find(|r| r.measure == b.measure);
    if step.step == 0 {
        let Some(list) = outcome.commits.filter(|c| !c.is_empty()) else {
            b.state = "failed".into();
            b.progress.message = "the runner listed no commits between good and bad (is good an \
                                  ancestor of bad on the first-parent line?)"
                .into();
            save(conn, &b)?;
            return record_on_alert(conn, &b);
        };
        b.commits = std::iter::once(b.good.clone()).chain(list).collect();
        b.progress.lo = 0;
        b.progress.hi = b.commits.len() - 1;
        match row {
            Some(r) if r.verdict == "changed" => {
                b.progress.full_effect = Some(effect(r));
            }
            Some(r) if unsure(r) && more_attempts(&mut b, &step, r) => {
                b.commits.clear();
                return rerun(conn, &mut b, 0, &created_by, max_attempts);
            }
            _ => {
                b.state = "no_change".into();
                b.progress.message = match row {
                    Some(r) => format!(
                        "good and bad do not differ in {} (p = {:.3} over {} pairs)",
                        b.measure, r.p, r.pairs
                    ),
                    None => format!(
                        "the samples have no {}; they have: {}",
                        b.measure,
                        rows.iter()
                            .map(|r| r.measure.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                };
                save(conn, &b)?;
                return record_on_alert(conn, &b);
            }
        }
    } else {
        let full = b.progress.full_effect.unwrap_or(0.0);
        let idx = b
            .commits
            .iter()
            .position(|c| *c == step.commit)
            .ok_or_else(|| StoreError::Corrupt(format!("step commit {}", step.commit)))?;
        let decision = decide(row, full).1;
        let undecided =
            decision == Decision::Spread || (decision == Decision::Good && row.is_some_and(unsure));
        if let Some(r) = row.filter(|_| undecided) {
            if more_attempts(&mut b, &step, r) {
                return rerun(conn, &mut b, idx, &created_by, max_attempts);
            }
        }
        b.progress.rerun = None;
        match decision {
            Decision::Good => b.progress.lo = b.progress.lo.max(idx),
            Decision::Bad => b.progress.hi = b.progress.hi.min(idx),
            Decision::Spread => {
                b.state = "spread".into();
                b.progress.message = format!(
                    "{} shows part of the change, not all of it: the change is spread over \
                     {}..{}",
                    step.commit, b.commits[b.progress.lo], b.commits[b.progress.hi]
                );
                save(conn, &b)?;
                return record_on_alert(conn, &b);
            }
        }
    }
    next(conn, &mut b, &created_by, max_attempts)
}

/// Whether `r` is not significant but not clearly the same either (p in [ALPHA, UNSURE_P)).
fn unsure(r: &Row) -> bool {
    r.verdict != "changed" && r.p < UNSURE_P
}

/// Doubles the attempts for a second run of `step`'s commit, unless it ran again already or the
/// count is at its most; says so in the progress.
fn more_attempts(b: &mut Bisection, step: &StepSpec, r: &Row) -> bool {
    let doubled = (b.attempts * 2).min(super::MAX_ATTEMPTS as i64);
    if b.progress.rerun.as_deref() == Some(step.commit.as_str()) || doubled <= b.attempts {
        return false;
    }
    b.progress.message = format!(
        "step {} at {}: {} undecided (p = {:.3} over {} pairs): again with {} attempts",
        step.step, step.commit, b.measure, r.p, r.pairs, doubled
    );
    b.attempts = doubled;
    b.progress.rerun = Some(step.commit.clone());
    true
}

/// Queues the step of `b.commits[idx]` again (step 0 when `idx` is 0: good against bad, with
/// the commit list) at `b.attempts`.
fn rerun(
    conn: &mut dyn Connection,
    b: &mut Bisection,
    idx: usize,
    created_by: &str,
    max_attempts: i64,
) -> Result<(), StoreError> {
    let steps = conn.query(
        "SELECT COUNT(*) FROM queue_requests WHERE bisection_id = $1",
        &[Value::Int(b.id)],
    )?[0]
        .i64(0)? as usize;
    let (commit, step, list) = if idx == 0 {
        (b.bad.clone(), 0, Some([b.good.clone(), b.bad.clone()]))
    } else {
        (b.commits[idx].clone(), steps, None)
    };
    let spec = super::spec(
        &b.scenario,
        Some(&b.variant),
        arm("a", &b.good),
        arm("b", &commit),
        b.attempts as usize,
        list,
    )?;
    queue_step(
        conn,
        b.id,
        step,
        &commit,
        &b.label,
        spec,
        created_by,
        max_attempts,
    )?;
    save(conn, b)
}

/// Queues the next step, or ends the bisection when one commit is left.
fn next(
    conn: &mut dyn Connection,
    b: &mut Bisection,
    created_by: &str,
    max_attempts: i64,
) -> Result<(), StoreError> {
    let (lo, hi) = (b.progress.lo, b.progress.hi);
    let candidates: Vec<usize> = (lo + 1..hi)
        .filter(|&i| !b.skipped.contains(&b.commits[i]))
        .collect();
    if hi - lo == 1 || candidates.is_empty() {
        if hi - lo == 1 {
            b.state = "done".into();
            b.culprit = Some(b.commits[hi].clone());
            b.progress.message = format!("culprit {}", b.commits[hi]);
        } else {
            b.state = "skipped".into();
            b.progress.message = format!(
                "the culprit is one of {}..={}: the commits between do not build",
                b.commits[lo + 1],
                b.commits[hi]
            );
        }
        save(conn, b)?;
        return record_on_alert(conn, b);
    }
    let middle = (lo + hi) / 2;
    let mid = *candidates
        .iter()
        .min_by_key(|&&i| i.abs_diff(middle))
        .expect("candidates is not empty");
    let steps = conn.query(
        "SELECT COUNT(*) FROM queue_requests WHERE bisection_id = $1",
        &[Value::Int(b.id)],
    )?[0]
        .i64(0)? as usize;
    let spec = super::spec(
        &b.scenario,
        Some(&b.variant),
        arm("a", &b.commits[0]),
        arm("b", &b.commits[mid]),
        b.attempts as usize,
        None,
    )?;
    let commit = b.commits[mid].clone();
    queue_step(
        conn,
        b.id,
        steps,
        &commit,
        &b.label,
        spec,
        created_by,
        max_attempts,
    )?;
    save(conn, b)
}

fn record_on_alert(conn: &mut dyn Connection, b: &Bisection) -> Result<(), StoreError> {
    if let Some(alert) = b.regression_id {
        crate::store::alerts::event(
            conn,
            alert,
            "bisected",
            format!(
                "bisection {} of {} on {}: {} ({})",
                b.id, b.measure, b.label, b.state, b.progress.message
            ),
        )?;
    }
    Ok(())
}

/// One step as shown: its A/B table and what it decided.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Step {
    pub step: usize,
    pub request_id: i64,
    pub job_id: i64,
    /// The commit tested against the good one (step 0: the bad one).
    pub commit: String,
    pub status: JobStatus,
    pub fraction: Option<f64>,
    pub decision: Option<Decision>,
    pub table: Vec<Row>,
}

/// Every step of bisection `b`, oldest first.
pub fn steps(conn: &mut dyn Connection, b: &Bisection) -> Result<Vec<Step>, StoreError> {
    let requests = conn.query(
        "SELECT id, spec FROM queue_requests WHERE bisection_id = $1 ORDER BY id",
        &[Value::Int(b.id)],
    )?;
    let mut out = Vec::new();
    for r in requests {
        let request_id = r.i64(0)?;
        let spec: StepSpec = serde_json::from_str(r.str(1)?).map_err(corrupt)?;
        for job in queue::request_jobs(conn, request_id)? {
            let table = job
                .outcome
                .as_ref()
                .map(|o| table(&o.samples))
                .unwrap_or_default();
            let row = table.iter().find(|r| r.measure == b.measure);
            let (fraction, decision) = if job.status != JobStatus::Done {
                (None, None)
            } else if spec.step == 0 {
                (Some(1.0), None)
            } else {
                let (f, d) = decide(row, b.progress.full_effect.unwrap_or(0.0));
                (f, Some(d))
            };
            out.push(Step {
                step: spec.step,
                request_id,
                job_id: job.id,
                commit: spec.commit.clone(),
                status: job.status,
                fraction,
                decision,
                table,
            });
        }
    }
    Ok(out)
}
