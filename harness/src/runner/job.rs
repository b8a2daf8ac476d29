//! One claimed job, start to end: list the commits a bisection asks for, build every arm's
//! commit, run the arms in the job's order with `tessera run` (the arm's environment variables
//! set, its commit checked out so that its scenario files are the ones run), then upload each run
//! (kind `run`) or keep one sample per run (kind `ab`).
//!
//! Between runs it looks at two flags: `stop` (SIGTERM: hand the job back unless it is on its
//! last run) and `lost` (a heartbeat said the job is no longer ours: drop it). Not for: talking to
//! the queue (see [`super::client`]) or the loop around jobs (see [`super`]).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicBool, Ordering};

use tessera_results::queue::{Claimed, Completion, JobKind};

use super::build::{BuildError, Workspace};
use super::sample::sample;

/// How a job ended on this runner.
#[derive(Debug)]
pub enum Outcome {
    Done(Completion),
    /// `build_failed` names the commit that did not build (not retried).
    Failed {
        error: String,
        build_failed: Option<String>,
        commits: Option<Vec<String>>,
    },
    /// SIGTERM arrived before the job was finished: give it back.
    Stopped,
    /// The dashboard gave the job to another runner.
    Lost,
}

/// What a job needs from the runner around it.
pub struct Context<'a> {
    pub runner: &'a str,
    pub work: &'a mut Workspace,
    pub results: PathBuf,
    pub dashboard: &'a str,
    pub stop: &'a AtomicBool,
    pub lost: &'a AtomicBool,
}

fn failed(error: impl ToString, commits: &Option<Vec<String>>) -> Outcome {
    Outcome::Failed {
        error: error.to_string(),
        build_failed: None,
        commits: commits.clone(),
    }
}

pub fn execute(job: &Claimed, cx: &mut Context) -> Outcome {
    let spec = &job.spec;
    let commits = match &spec.list_commits {
        Some([good, bad]) => match cx.work.first_parent(good, bad) {
            Ok(c) => Some(c),
            Err(e) => return failed(e, &None),
        },
        None => None,
    };
    // Resolve and build each arm's commit once, before any run.
    let mut arms = Vec::new();
    for arm in &spec.arms {
        let commit = match cx.work.resolve(&arm.commit) {
            Ok(c) => c,
            Err(e) => {
                return Outcome::Failed {
                    error: format!("arm {}: unknown commit: {e}", arm.name),
                    build_failed: Some(arm.commit.clone()),
                    commits,
                }
            }
        };
        match cx.work.binary(&commit) {
            Ok(bin) => arms.push((commit, bin)),
            Err(BuildError::Build { commit, message }) => {
                return Outcome::Failed {
                    error: format!("{commit} does not build:\n{message}"),
                    build_failed: Some(commit),
                    commits,
                }
            }
            Err(e) => return failed(e, &commits),
        }
    }
    let mut runs = Vec::new();
    let mut samples = Vec::new();
    for (seq, &i) in spec.order.iter().enumerate() {
        if cx.lost.load(Ordering::SeqCst) {
            return Outcome::Lost;
        }
        if cx.stop.load(Ordering::SeqCst) && seq + 1 < spec.order.len() {
            return Outcome::Stopped;
        }
        let (commit, bin) = &arms[i];
        if let Err(e) = cx.work.checkout(commit) {
            return failed(e, &commits);
        }
        let out = cx
            .results
            .join(format!("job{}-a{}-{seq}", job.job_id, job.attempt));
        let _ = std::fs::remove_dir_all(&out);
        // An A/B or bisection step renders only the variant it samples, with its baselines
        // and reference (`tessera run --variants`); a whole run uploads every variant.
        let only = match spec.kind {
            JobKind::Ab => spec.variant.as_deref(),
            JobKind::Run => None,
        };
        let run_dir = match run_once(
            bin,
            &cx.work.checkout,
            &spec.scenarios,
            only,
            &spec.arms[i].env,
            &out,
        ) {
            Ok(d) => d,
            Err(e) => return failed(format!("run {seq} ({}): {e}", spec.arms[i].name), &commits),
        };
        match spec.kind {
            JobKind::Run => match super::upload_run(&run_dir, cx.dashboard, job.job_id) {
                Ok(id) => runs.push(id),
                Err(e) => return failed(format!("upload: {e}"), &commits),
            },
            JobKind::Ab => {
                let run = match tessera_results::folder::read(&run_dir) {
                    Ok(r) => r,
                    Err(e) => return failed(e, &commits),
                };
                let Some(s) = run
                    .scenarios
                    .first()
                    .and_then(|sc| sample(&run_dir, sc, spec.variant.as_deref(), i, seq))
                else {
                    let names: Vec<&str> = run
                        .scenarios
                        .iter()
                        .flat_map(|s| s.results.iter().map(|r| r.variant.as_str()))
                        .collect();
                    return failed(
                        format!(
                            "the run has no variant {:?} in {} (it has: {})",
                            spec.variant,
                            spec.scenarios.join(" "),
                            names.join(", ")
                        ),
                        &commits,
                    );
                };
                samples.push(s);
                // A/B runs are not uploaded: keep the disk from filling over long bisections.
                let _ = std::fs::remove_dir_all(&out);
            }
        }
    }
    Outcome::Done(Completion {
        runner: cx.runner.to_string(),
        attempt: job.attempt,
        runs,
        samples,
        commits,
    })
}

/// Runs `tessera run` once into the empty folder `out`, with `--variants` where `only` names
/// one (a commit built before that flag existed runs every variant); the run folder it wrote.
fn run_once(
    bin: &Path,
    checkout: &Path,
    scenarios: &[String],
    only: Option<&str>,
    env: &std::collections::BTreeMap<String, String>,
    out: &Path,
) -> Result<PathBuf, String> {
    let run = |only: Option<&str>| {
        let mut cmd = Command::new(bin);
        cmd.arg("run").args(scenarios);
        if let Some(v) = only {
            cmd.args(["--variants", v]);
        }
        cmd.arg("--out")
            .arg(out)
            .arg("--quiet")
            .envs(env)
            .current_dir(checkout)
            .output()
            .map_err(|e| format!("{}: {e}", bin.display()))
    };
    let mut output = run(only)?;
    if only.is_some()
        && output.status.code() == Some(2)
        && String::from_utf8_lossy(&output.stderr).contains("unexpected argument '--variants'")
    {
        output = run(None)?;
    }
    // 0: ok, 1: a gate or variant failed (results written); anything else is an error.
    let code = output.status.code();
    if !matches!(code, Some(0) | Some(1)) {
        let stderr = String::from_utf8_lossy(&output.stderr);
        let tail: Vec<&str> = stderr.lines().rev().take(20).collect();
        return Err(format!(
            "tessera run exited with {code:?}:\n{}",
            tail.into_iter().rev().collect::<Vec<_>>().join("\n")
        ));
    }
    let abs_out = checkout.join(out);
    let dir = std::fs::read_dir(&abs_out)
        .map_err(|e| format!("{}: {e}", abs_out.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.is_dir())
        .ok_or_else(|| format!("tessera run wrote no run folder in {}", abs_out.display()))?;
    Ok(dir)
}
