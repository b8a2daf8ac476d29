//! `tessera runner`: a long-running process on a GPU machine that claims jobs of its labels from a
//! dashboard's queue, builds each job's commit in its own worktree, runs it and reports back.
//!
//! It registers (name, labels, adapter, driver, host), then polls `POST /api/queue/claim`. While
//! it holds a job a thread heartbeats every quarter lease, so a runner that dies (`kill -9`) has
//! its job claimed again by another after the lease; a heartbeat answered "not yours" makes it
//! drop the job. SIGTERM (or Ctrl-C) stops it after the current run: the job is handed back
//! (`/return`, the attempt not counted) unless that was its last run, then it is finished.
//! Everything the dashboard acknowledged (an upload, a completion) is stored there, so nothing
//! acknowledged is lost by a kill.
//!
//! Not for: the queue's rules (the dashboard's `store/queue.rs`).

pub mod build;
pub mod client;
pub mod job;
pub mod sample;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use tessera_results::queue::{Failure, JobRef, Registration, Return};

use client::{Client, ClientError};
use job::Outcome;

/// `tessera runner`'s options.
#[derive(Clone, Debug)]
pub struct Options {
    pub dashboard: String,
    pub labels: Vec<String>,
    pub repository: PathBuf,
    /// Worktree and results live here (default `<repository>/../tessera-runner-<name>`).
    pub work: Option<PathBuf>,
    /// Cargo target directory, shareable between runners (default `<work>/target`).
    pub target_dir: Option<PathBuf>,
    /// Unique name of this runner (default `<host>-<pid>`).
    pub name: Option<String>,
    /// Seconds between two claims while the queue is empty.
    pub poll_secs: u64,
    /// Which adapter to report (as `tessera run --adapter`).
    pub adapter: Option<String>,
    /// Stop when the queue has been empty for this many seconds (`None`: never).
    pub exit_when_idle_secs: Option<u64>,
}

#[derive(Debug, thiserror::Error)]
pub enum RunnerError {
    #[error(transparent)]
    Client(#[from] ClientError),
    #[error(transparent)]
    Build(#[from] build::BuildError),
    #[error(transparent)]
    Upload(#[from] crate::upload::UploadError),
    #[error("{0}")]
    Setup(String),
}

fn hostname() -> String {
    std::fs::read_to_string("/etc/hostname")
        .map(|s| s.trim().to_string())
        .ok()
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "localhost".into())
}

/// The adapter and driver this runner reports at registration.
fn adapter(wanted: Option<&str>) -> (String, String) {
    match crate::gpu::select(wanted) {
        Ok(a) => {
            let i = crate::gpu::describe(&a);
            (
                i.name,
                format!("{} {}", i.driver, i.driver_info).trim().to_string(),
            )
        }
        Err(e) => (format!("(no adapter: {e})"), String::new()),
    }
}

/// Uploads a run folder for `job_id` (the `X-Tessera-Job` header lets a runner token store it).
pub fn upload_run(dir: &Path, dashboard: &str, job_id: i64) -> Result<String, RunnerError> {
    let token = crate::upload::token_from_env()?;
    let body =
        serde_json::to_vec(&crate::upload::bundle(dir)?).expect("the upload body serialises");
    let reply = crate::upload::post_for_job(dashboard, &token, &body, Some(job_id))?;
    Ok(reply.run_id)
}

/// Sleeps `d` unless `stop` is raised first.
fn nap(d: Duration, stop: &AtomicBool) {
    let end = Instant::now() + d;
    while Instant::now() < end && !stop.load(Ordering::SeqCst) {
        std::thread::sleep(Duration::from_millis(100).min(end - Instant::now()));
    }
}

/// Runs until SIGTERM / SIGINT (or idle, with `exit_when_idle_secs`). Prints one line per job on
/// stderr.
pub fn run(opts: &Options) -> Result<(), RunnerError> {
    let token = crate::upload::token_from_env()?;
    let client = Client::new(&opts.dashboard, &token);
    let name = opts
        .name
        .clone()
        .unwrap_or_else(|| format!("{}-{}", hostname(), std::process::id()));
    let repository = std::fs::canonicalize(&opts.repository).map_err(|e| {
        RunnerError::Setup(format!("--repository {}: {e}", opts.repository.display()))
    })?;
    let work = match &opts.work {
        Some(w) => w.clone(),
        None => repository
            .parent()
            .unwrap_or(&repository)
            .join(format!("tessera-runner-{name}")),
    };
    std::fs::create_dir_all(&work)
        .map_err(|e| RunnerError::Setup(format!("--work {}: {e}", work.display())))?;
    let work = std::fs::canonicalize(&work)
        .map_err(|e| RunnerError::Setup(format!("--work {}: {e}", work.display())))?;
    let target = opts
        .target_dir
        .clone()
        .unwrap_or_else(|| work.join("target"));
    let mut workspace = build::Workspace::open(&repository, &work, &target)?;

    let stop = Arc::new(AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGTERM, signal_hook::consts::SIGINT] {
        signal_hook::flag::register(sig, stop.clone())
            .map_err(|e| RunnerError::Setup(format!("cannot handle signal {sig}: {e}")))?;
    }

    let (adapter, driver) = adapter(opts.adapter.as_deref());
    let lease_secs = client.register(&Registration {
        name: name.clone(),
        labels: opts.labels.clone(),
        adapter: adapter.clone(),
        driver,
        host: hostname(),
    })?;
    eprintln!(
        "runner {name}: registered at {} for {} on {adapter}; worktree {}",
        client.base(),
        opts.labels.join(","),
        workspace.checkout.display()
    );

    // The heartbeat thread: alive every quarter lease, with the job held, if any.
    let current: Arc<Mutex<Option<JobRef>>> = Arc::default();
    let lost = Arc::new(AtomicBool::new(false));
    let done = Arc::new(AtomicBool::new(false));
    let beat = {
        let (client, name, current, lost, done) = (
            client.clone(),
            name.clone(),
            current.clone(),
            lost.clone(),
            done.clone(),
        );
        let every = Duration::from_millis((lease_secs * 1000 / 4).max(250));
        std::thread::spawn(move || {
            while !done.load(Ordering::SeqCst) {
                let job = *current.lock().unwrap_or_else(|e| e.into_inner());
                match client.heartbeat(&name, job) {
                    Ok(false) if job.is_some() => lost.store(true, Ordering::SeqCst),
                    Ok(_) => {}
                    Err(e) => eprintln!("runner {name}: heartbeat: {e}"),
                }
                nap(every, &done);
            }
        })
    };

    let results = work.join("results");
    let mut idle_since = Instant::now();
    let outcome = loop {
        if stop.load(Ordering::SeqCst) {
            break Ok(());
        }
        let claimed = match client.claim(&name) {
            Ok(c) => c,
            Err(e) => {
                eprintln!("runner {name}: claim: {e}");
                nap(Duration::from_secs(opts.poll_secs), &stop);
                continue;
            }
        };
        let Some(job) = claimed else {
            if opts
                .exit_when_idle_secs
                .is_some_and(|s| idle_since.elapsed() >= Duration::from_secs(s))
            {
                break Ok(());
            }
            nap(Duration::from_secs(opts.poll_secs), &stop);
            continue;
        };
        let started = Instant::now();
        eprintln!(
            "runner {name}: job {} attempt {} ({:?}, {} runs)",
            job.job_id,
            job.attempt,
            job.spec.kind,
            job.spec.order.len()
        );
        lost.store(false, Ordering::SeqCst);
        *current.lock().unwrap_or_else(|e| e.into_inner()) = Some(JobRef {
            job_id: job.job_id,
            attempt: job.attempt,
        });
        let builds_before = workspace.builds;
        let mut cx = job::Context {
            runner: &name,
            work: &mut workspace,
            results: results.clone(),
            dashboard: client.base(),
            stop: &stop,
            lost: &lost,
        };
        let result = job::execute(&job, &mut cx);
        let report = match &result {
            Outcome::Done(c) => client.complete(job.job_id, c),
            Outcome::Failed {
                error,
                build_failed,
                commits,
            } => client.fail(
                job.job_id,
                &Failure {
                    runner: name.clone(),
                    attempt: job.attempt,
                    error: error.clone(),
                    build_failed: build_failed.clone(),
                    commits: commits.clone(),
                },
            ),
            Outcome::Stopped => client.give_back(
                job.job_id,
                &Return {
                    runner: name.clone(),
                    attempt: job.attempt,
                },
            ),
            Outcome::Lost => Ok(()),
        };
        *current.lock().unwrap_or_else(|e| e.into_inner()) = None;
        let verdict = match &result {
            Outcome::Done(_) => "done".to_string(),
            Outcome::Failed { error, .. } => {
                format!("failed: {}", error.lines().next().unwrap_or(""))
            }
            Outcome::Stopped => "handed back (stopping)".into(),
            Outcome::Lost => "lost to another runner (lease ran out)".into(),
        };
        eprintln!(
            "runner {name}: job {} {verdict} in {:.1} s, {} build(s){}",
            job.job_id,
            started.elapsed().as_secs_f64(),
            workspace.builds - builds_before,
            match &report {
                Err(e) if !e.is_lost_job() => format!("; report failed: {e}"),
                Err(_) => "; the dashboard says the job is no longer ours".into(),
                Ok(()) => String::new(),
            }
        );
        idle_since = Instant::now();
    };
    done.store(true, Ordering::SeqCst);
    let _ = beat.join();
    eprintln!(
        "runner {name}: stopped; {} build(s) in this process",
        workspace.builds
    );
    outcome
}
