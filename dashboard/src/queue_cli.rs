//! The queue's commands: `tessera-dashboard request` (a nightly run or backfill of suites at a
//! commit), `ab` (an A/B of two environments) and `bisect` (a bisection of a range). Each queues
//! its jobs in the store directly, as `import` does, and with `--wait` polls the store until the
//! work is done, then prints the A/B table or the bisection's culprit.
//!
//! Not for: the rules of the queue, A/B or bisection (see [`crate::store::queue`], [`crate::ab`]).

use std::path::Path;
use std::time::Duration;

use crate::ab::{self, bisect};
use crate::db::{self, transaction, Pool};
use crate::store::queue::{self, JobStatus, NewJob};
use crate::store::StoreError;
use tessera_results::queue::{Arm, JobKind, JobSpec};

/// Who the commands act as in the store's records.
const CLI: &str = "cli";

/// Resolves `commit` in `repository`, when given; an unknown commit is an error.
pub fn resolve(repository: Option<&Path>, what: &str, commit: &str) -> anyhow::Result<String> {
    let Some(repo) = repository else {
        queue::check_commit(what, commit)?;
        return Ok(commit.to_string());
    };
    let out = std::process::Command::new("git")
        .arg("-C")
        .arg(repo)
        .args(["rev-parse", "--verify", "--quiet"])
        .arg(format!("{commit}^{{commit}}"))
        .output()?;
    if !out.status.success() {
        anyhow::bail!("{what}: {commit} is not a commit of {}", repo.display());
    }
    Ok(String::from_utf8_lossy(&out.stdout).trim().to_string())
}

/// `tessera-dashboard request`: one job per suite and label; prints the request and job ids.
pub fn request(
    db: &str,
    kind: &str,
    commit: &str,
    suites: &[String],
    labels: &[String],
    repository: Option<&Path>,
) -> anyhow::Result<()> {
    if !matches!(kind, "nightly" | "backfill") {
        anyhow::bail!("--kind must be nightly or backfill, not {kind:?}");
    }
    let commit = resolve(repository, "--commit", commit)?;
    let mut jobs = Vec::new();
    for label in labels {
        for suite in suites {
            queue::check_name("suite", suite)?;
            jobs.push(NewJob {
                label: label.clone(),
                spec: JobSpec {
                    kind: JobKind::Run,
                    scenarios: vec![format!("scenarios/{suite}")],
                    variant: None,
                    arms: vec![Arm {
                        name: "run".into(),
                        commit: commit.clone(),
                        env: Default::default(),
                    }],
                    order: vec![0],
                    list_commits: None,
                },
            });
        }
    }
    let pool = db::open(db)?;
    queue::check_labels_known(&mut *pool.get()?, labels)?;
    let spec = serde_json::json!({"commit": commit, "suites": suites, "labels": labels});
    let (id, job_ids) = queue::enqueue(
        &mut *pool.get()?,
        kind,
        &spec,
        None,
        CLI,
        &jobs,
        queue::DEFAULT_MAX_ATTEMPTS,
    )?;
    println!(
        "request {id}: {} job(s) queued ({})",
        job_ids.len(),
        job_ids
            .iter()
            .map(i64::to_string)
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(())
}

/// Polls `done` every `every` until it returns `Some`.
fn wait_for<T>(
    pool: &Pool,
    every: Duration,
    mut done: impl FnMut(&mut dyn db::Connection) -> Result<Option<T>, StoreError>,
) -> anyhow::Result<T> {
    loop {
        if let Some(v) = done(&mut *pool.get()?)? {
            return Ok(v);
        }
        std::thread::sleep(every);
    }
}

/// `tessera-dashboard ab`: queues the A/B on each label; with `wait`, prints each job's table.
#[allow(clippy::too_many_arguments)]
pub fn ab(
    db: &str,
    scenario: &str,
    variant: Option<&str>,
    a: &str,
    b: &str,
    labels: &[String],
    attempts: usize,
    repository: Option<&Path>,
    wait: bool,
) -> anyhow::Result<bool> {
    let mut a = ab::parse_env("a", a)?;
    let mut b = ab::parse_env("b", b)?;
    a.commit = resolve(repository, "--a", &a.commit)?;
    b.commit = resolve(repository, "--b", &b.commit)?;
    let mut jobs = Vec::new();
    for label in labels {
        jobs.push(NewJob {
            label: label.clone(),
            spec: ab::spec(scenario, variant, a.clone(), b.clone(), attempts, None)?,
        });
    }
    let pool = db::open(db)?;
    queue::check_labels_known(&mut *pool.get()?, labels)?;
    let spec = serde_json::json!({"scenario": scenario, "variant": variant, "a": a, "b": b});
    let (id, job_ids) = queue::enqueue(
        &mut *pool.get()?,
        "ab",
        &spec,
        None,
        CLI,
        &jobs,
        queue::DEFAULT_MAX_ATTEMPTS,
    )?;
    eprintln!("A/B request {id}: job(s) {job_ids:?} queued");
    if !wait {
        return Ok(true);
    }
    let rows = wait_for(&pool, Duration::from_secs(2), |c| {
        let jobs = queue::request_jobs(c, id)?;
        Ok(jobs.iter().all(|j| j.status.is_final()).then_some(jobs))
    })?;
    let mut ok = true;
    for j in rows {
        println!("{} (job {}, {:?}):", j.label, j.id, j.status);
        match (&j.outcome, j.status) {
            (Some(o), JobStatus::Done) => print!("{}", ab::text(&ab::table(&o.samples))),
            _ => {
                ok = false;
                println!("  {}", j.error);
            }
        }
    }
    Ok(ok)
}

/// `tessera-dashboard bisect`: starts the bisection; with `wait`, prints its end and its steps.
/// `Ok(false)` when it ended without a culprit.
pub fn bisect(
    db: &str,
    mut p: bisect::Params,
    repository: Option<&Path>,
    wait: bool,
) -> anyhow::Result<bool> {
    if !(1..=ab::MAX_ATTEMPTS).contains(&p.attempts) {
        anyhow::bail!(
            "--attempts must be 1 to {}, not {}",
            ab::MAX_ATTEMPTS,
            p.attempts
        );
    }
    p.good = resolve(repository, "--good", &p.good)?;
    p.bad = resolve(repository, "--bad", &p.bad)?;
    let pool = db::open(db)?;
    queue::check_labels_known(&mut *pool.get()?, std::slice::from_ref(&p.label))?;
    let id = transaction(&mut *pool.get()?, |c| {
        bisect::create(c, &p, CLI, queue::DEFAULT_MAX_ATTEMPTS)
    })?;
    eprintln!("bisection {id} started");
    if !wait {
        println!("{id}");
        return Ok(true);
    }
    let b = wait_for(&pool, Duration::from_secs(2), |c| {
        let b = bisect::get(c, id)?;
        Ok((b.state != "running").then_some(b))
    })?;
    let steps = bisect::steps(&mut *pool.get()?, &b)?;
    for s in &steps {
        let row = s.table.iter().find(|r| r.measure == b.measure);
        println!(
            "step {:>2}  {}  {:?}{}{}",
            s.step,
            s.commit.get(..10).unwrap_or(&s.commit),
            s.status,
            row.map(|r| format!("  B - A {:.4} (p {:.2e})", r.estimate, r.p))
                .unwrap_or_default(),
            s.decision.map(|d| format!("  {d:?}")).unwrap_or_default()
        );
    }
    println!(
        "bisection {id}: {}{} ({})",
        b.state,
        b.culprit
            .as_deref()
            .map(|c| format!(", culprit {c}"))
            .unwrap_or_default(),
        b.progress.message
    );
    Ok(b.culprit.is_some())
}
