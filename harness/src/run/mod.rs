//! Running a suite: open the adapter, run each scenario, write its results as soon as it finishes.
//!
//! The run folder is `<out>/<run-id>/`. `run.json` is written first (status `running`) and again at
//! the end; each scenario's JSON and the whole `results.csv` are rewritten atomically after every
//! scenario, so an interrupted run keeps what it completed. With `timings`, where the run's wall
//! time went ([`phases`]) is printed per scenario and for the run, and written to
//! `timings.json`.

pub mod capture;
pub mod captured;
pub mod console;
pub mod convergence;
pub mod cvvdp;
pub mod evaluate;
pub mod frames;
pub mod gates;
pub mod images;
pub mod memory;
pub mod metrics;
pub mod motion;
pub mod motion_blur;
pub mod output;
pub mod phases;
pub mod plan;
pub mod record;
pub mod reference;
pub mod reference_noise;
pub mod rendered;
pub mod report;
pub mod scenario;
pub mod select;
pub mod sequence;
pub mod stability;
pub mod summary;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use tessera_results::{
    CommitInfo, HostInfo, RunInfo, RunStatus, ScenarioResult, Status, SCHEMA_VERSION,
};

use crate::conditions::Sensors;
use crate::gpu::{self, Gpu, GpuError};
use crate::scenario::Scenario;
use output::WriteError;
use report::Report;

pub struct Options {
    pub adapter: Option<String>,
    pub out: PathBuf,
    pub junit: Option<PathBuf>,
    pub progress: bool,
    pub command_line: Vec<String>,
    /// Recorded as the run's suite (see [`suite_name`]).
    pub suite: Option<String>,
    /// Recorded as the run's branch; `None` asks git.
    pub branch: Option<String>,
    /// Print where the wall time went and write `timings.json` (`tessera run --timings`).
    pub timings: bool,
    /// The suites' expectations (`scenarios/<suite>/expectations.toml`, see [`crate::expect`]).
    pub expectations: crate::expect::Book,
    /// Run the variants an expectation labels `slow` (`tessera run --slow`).
    pub slow: bool,
    /// The adapter class the run declares (`--adapter-class`); `None` derives it.
    pub adapter_class: Option<String>,
}

#[derive(Debug, thiserror::Error)]
pub enum SuiteError {
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error(transparent)]
    Write(#[from] WriteError),
}

pub struct SuiteOutcome {
    pub run_dir: PathBuf,
    pub scenarios: Vec<ScenarioResult>,
    pub device_lost: bool,
}

/// Opens the adapter and runs every scenario.
pub fn run_suite(scenarios: &[Scenario], opts: &Options) -> Result<SuiteOutcome, SuiteError> {
    let adapter = gpu::select(opts.adapter.as_deref())?;
    let gpu = gpu::open(adapter)?;
    run_on(&gpu, scenarios, opts)
}

/// Runs every scenario on an open device, with the adapter's own sensors (or none, and why).
pub fn run_on(
    gpu: &Gpu,
    scenarios: &[Scenario],
    opts: &Options,
) -> Result<SuiteOutcome, SuiteError> {
    run_with_sensors(gpu, scenarios, opts, &Sensors::open(&gpu.info))
}

/// Runs every scenario on an open device, reading `sensors` during measured frames (tests give a
/// fake source here).
pub fn run_with_sensors(
    gpu: &Gpu,
    scenarios: &[Scenario],
    opts: &Options,
    sensors: &Sensors,
) -> Result<SuiteOutcome, SuiteError> {
    let lost = watch_device(gpu);
    let mut run = run_info(gpu, scenarios, opts, sensors);
    let (run_id, run_dir) = (run.run_id.clone(), opts.out.join(&run.run_id));
    let bar = progress_bar(scenarios, opts.progress);

    // Every output of the run, called in this order at each stage.
    let mut files = report::Files {
        run_dir: run_dir.clone(),
    };
    let mut screen = report::Console { bar: &bar };
    let mut junit = opts.junit.clone().map(|path| report::JUnit { path });
    let mut reports: Vec<&mut dyn Report> = vec![&mut files, &mut screen];
    if let Some(j) = junit.as_mut() {
        reports.push(j);
    }
    for r in reports.iter_mut() {
        r.started(&run)?;
    }

    let mut results: Vec<ScenarioResult> = Vec::new();
    let run_start = std::time::Instant::now();
    let run_phases = phases::totals();
    let mut breakdown = Vec::new();
    for s in scenarios {
        bar.set_message(s.name.clone());
        let (start, before) = (std::time::Instant::now(), phases::totals());
        let result = if lost.load(Ordering::SeqCst) {
            device_lost_result(s, &run_id)
        } else {
            run_expecting(gpu, s, &run_id, &run_dir, sensors, opts, &mut || bar.inc(1))
        };
        results.push(result);
        phases::time("result files", || -> Result<(), SuiteError> {
            for r in reports.iter_mut() {
                r.scenario(&run, &results)?;
            }
            Ok(())
        })?;
        let wall_s = start.elapsed().as_secs_f64();
        let spent = phases::since(&before, &phases::totals());
        if opts.timings {
            bar.suspend(|| eprint!("{}", phases::table(&s.name, &spent, wall_s)));
        }
        breakdown.push(timings::Scenario {
            scenario: s.name.clone(),
            wall_s,
            phases: spent,
        });
    }
    bar.finish_and_clear();

    run.finished_at = Some(chrono::Utc::now().to_rfc3339_opts(chrono::SecondsFormat::Secs, true));
    run.status = RunStatus::Complete;
    for r in reports.iter_mut() {
        r.finished(&run, &results)?;
    }
    if opts.timings {
        let wall_s = run_start.elapsed().as_secs_f64();
        let spent = phases::since(&run_phases, &phases::totals());
        eprint!("{}", phases::table("run (scenarios)", &spent, wall_s));
        timings::write(&run_dir, wall_s, &spent, &breakdown)?;
    }
    Ok(SuiteOutcome {
        run_dir,
        scenarios: results,
        device_lost: lost.load(Ordering::SeqCst),
    })
}

/// Watches `gpu` for device loss (the flag it returns) and reports errors outside an error scope
/// instead of panicking.
fn watch_device(gpu: &Gpu) -> Arc<AtomicBool> {
    let lost = Arc::new(AtomicBool::new(false));
    {
        let lost = lost.clone();
        gpu.device.set_device_lost_callback(move |_, message| {
            eprintln!("error: the GPU device was lost: {message}");
            lost.store(true, Ordering::SeqCst);
        });
    }
    // Errors outside an error scope are reported, not turned into a panic.
    gpu.device.on_uncaptured_error(Arc::new(|e| {
        eprintln!("warning: uncaptured GPU error: {e}")
    }));
    lost
}

/// The run's record as it starts: id, commit, adapter, host, scenarios.
fn run_info(gpu: &Gpu, scenarios: &[Scenario], opts: &Options, sensors: &Sensors) -> RunInfo {
    let started = chrono::Utc::now();
    let commit = git_commit();
    if commit.is_none() {
        eprintln!(
            "warning: not in a git checkout (or git failed): the run is recorded without a commit; the dashboard stores it but never compares a later run with it as its previous run (run tessera from the repository to record the commit)"
        );
    }
    let commit_time = commit.as_ref().and_then(|_| git_commit_time());
    let run_id = unique_run_id(&opts.out, &started, commit.as_ref());
    RunInfo {
        schema_version: SCHEMA_VERSION,
        run_id: run_id.clone(),
        commit,
        commit_time,
        started_at: started.to_rfc3339_opts(chrono::SecondsFormat::Secs, true),
        finished_at: None,
        status: RunStatus::Running,
        harness_version: env!("CARGO_PKG_VERSION").to_string(),
        adapter: gpu.info.clone(),
        host: host_info(),
        command_line: opts.command_line.clone(),
        scenarios: scenarios
            .iter()
            .map(|s| s.file.display().to_string())
            .collect(),
        conditions: Some(sensors.device_record()),
        suite: opts.suite.clone(),
        branch: opts.branch.clone().or_else(git_branch),
        adapter_class: opts.adapter_class.clone(),
    }
}

/// The progress bar over every frame the run renders (hidden without `progress`).
fn progress_bar(scenarios: &[Scenario], progress: bool) -> indicatif::ProgressBar {
    let total: u64 = scenarios
        .iter()
        .map(|s| 2 * s.total_frames() as u64 * (s.variants.len() as u64 + 1))
        .sum();
    if progress {
        let b = indicatif::ProgressBar::new(total);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} frames  {msg}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b
    } else {
        indicatif::ProgressBar::hidden()
    }
}

/// `timings.json`: where the run's wall time went (see [`phases`]).
mod timings {
    use super::output::WriteError;
    use super::phases::Phase;
    use std::path::Path;

    #[derive(serde::Serialize)]
    pub struct Scenario {
        pub scenario: String,
        pub wall_s: f64,
        pub phases: Vec<Phase>,
    }

    #[derive(serde::Serialize)]
    struct File<'a> {
        /// The scenarios' wall time, from the first scenario's start to the last result file.
        wall_s: f64,
        phases: &'a [Phase],
        scenarios: &'a [Scenario],
    }

    pub fn write(
        run_dir: &Path,
        wall_s: f64,
        phases: &[Phase],
        scenarios: &[Scenario],
    ) -> Result<(), WriteError> {
        let file = File {
            wall_s,
            phases,
            scenarios,
        };
        let json = serde_json::to_string_pretty(&file).expect("plain data serialises");
        super::output::write_atomic(&run_dir.join("timings.json"), json.as_bytes())
    }
}

/// Runs one scenario as its suite's expectations say: without the variants not to run here
/// (`skip`, `slow`), a failed `flaky` variant once more, and each result with the entry that
/// applied to it (`crate::expect::apply`).
fn run_expecting(
    gpu: &Gpu,
    s: &Scenario,
    run_id: &str,
    run_dir: &Path,
    sensors: &Sensors,
    opts: &Options,
    on_frame: &mut dyn FnMut(),
) -> ScenarioResult {
    use crate::expect::apply;
    let exp = opts.expectations.for_scenario(s);
    let adapter = &gpu.info;
    let split = apply::split(s, exp, adapter, opts.slow);
    let start = std::time::Instant::now();
    let mut result = if split.to_run.variants.is_empty() {
        record::finish(s, run_id, Vec::new(), start)
    } else {
        scenario::run(gpu, &split.to_run, run_id, run_dir, sensors, on_frame)
    };
    let retry = apply::to_retry(&s.name, &result.results, exp, adapter);
    let mut first_errors = Vec::new();
    if !retry.is_empty() {
        for r in result.results.iter().filter(|r| retry.contains(&r.variant)) {
            let error = apply::failure_text(r).unwrap_or_default();
            eprintln!(
                "note: {} / {} is labelled flaky and failed ({error}): running it once more",
                s.name, r.variant
            );
            first_errors.push((r.variant.clone(), error));
        }
        let mut again = split.to_run.clone();
        again.variants.retain(|v| retry.contains(&v.name));
        let second = scenario::run(gpu, &again, run_id, run_dir, sensors, on_frame);
        for r in second.results {
            if let Some(slot) = result.results.iter_mut().find(|x| x.variant == r.variant) {
                *slot = r;
            }
        }
    }
    apply::judge(&s.name, &mut result.results, exp, adapter, &first_errors);
    let not_run = split.not_run.into_iter().map(|n| {
        let mut r = record::empty_result(&n.variant, n.status);
        r.expectation = Some(n.expectation);
        r
    });
    apply::merge_in_order(s, &mut result.results, not_run.collect());
    result
}

fn device_lost_result(s: &Scenario, run_id: &str) -> ScenarioResult {
    let mut r = record::run_failed(s, run_id, "the GPU device was lost earlier in the run");
    for v in &mut r.results {
        v.status = Status::Failed {
            error: "the GPU device was lost earlier in the run".into(),
        };
    }
    r
}

/// `20261122T031500Z-<sha7>`, with a counter appended if that folder exists.
fn unique_run_id(
    out: &Path,
    t: &chrono::DateTime<chrono::Utc>,
    commit: Option<&CommitInfo>,
) -> String {
    let base = match commit {
        Some(c) => format!(
            "{}-{}",
            t.format("%Y%m%dT%H%M%SZ"),
            &c.sha[..c.sha.len().min(7)]
        ),
        None => t.format("%Y%m%dT%H%M%SZ").to_string(),
    };
    let mut id = base.clone();
    let mut n = 2;
    while out.join(&id).exists() {
        id = format!("{base}-{n}");
        n += 1;
    }
    id
}

/// The commit of the current directory's git checkout, if any.
fn git_commit() -> Option<CommitInfo> {
    let sha = std::process::Command::new("git")
        .args(["rev-parse", "HEAD"])
        .output()
        .ok()?;
    if !sha.status.success() {
        return None;
    }
    let dirty = std::process::Command::new("git")
        .args(["status", "--porcelain", "--untracked-files=no"])
        .output()
        .map(|o| !o.stdout.is_empty())
        .unwrap_or(false);
    Some(CommitInfo {
        sha: String::from_utf8_lossy(&sha.stdout).trim().to_string(),
        dirty,
    })
}

/// The checkout's branch (`git symbolic-ref --short HEAD`); `None` on a detached head or outside
/// git.
fn git_branch() -> Option<String> {
    let out = std::process::Command::new("git")
        .args(["symbolic-ref", "--quiet", "--short", "HEAD"])
        .output()
        .ok()?;
    let branch = String::from_utf8_lossy(&out.stdout).trim().to_string();
    (out.status.success() && !branch.is_empty()).then_some(branch)
}

/// The suite of a run from the paths given on the command line: each folder's name, or a file's
/// parent folder's name, in order without repeats, joined by `+` (`scenarios/smoke` gives
/// `smoke`). `None` when no path has a usable name.
pub fn suite_name(paths: &[PathBuf]) -> Option<String> {
    let mut names: Vec<String> = Vec::new();
    for p in paths {
        let folder = if p.is_dir() {
            Some(p.as_path())
        } else {
            p.parent()
        };
        // `canonicalize` resolves `.` and a bare file name's empty parent to a real folder name.
        let name = folder
            .and_then(|f| f.canonicalize().ok())
            .and_then(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()));
        if let Some(n) = name {
            if !names.contains(&n) {
                names.push(n);
            }
        }
    }
    (!names.is_empty()).then(|| names.join("+"))
}

/// The committer date of `HEAD`, RFC 3339 in UTC (git prints it with the committer's offset).
fn git_commit_time() -> Option<String> {
    let out = std::process::Command::new("git")
        .args(["show", "-s", "--format=%cI", "HEAD"])
        .output()
        .ok()?;
    if !out.status.success() {
        return None;
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let t = chrono::DateTime::parse_from_rfc3339(text.trim()).ok()?;
    Some(
        t.with_timezone(&chrono::Utc)
            .to_rfc3339_opts(chrono::SecondsFormat::Secs, true),
    )
}

fn host_info() -> HostInfo {
    let hostname = std::fs::read_to_string("/etc/hostname")
        .map(|s| s.trim().to_string())
        .or_else(|_| std::env::var("HOSTNAME"))
        .or_else(|_| std::env::var("COMPUTERNAME"))
        .unwrap_or_default();
    HostInfo {
        hostname,
        os: std::env::consts::OS.to_string(),
        arch: std::env::consts::ARCH.to_string(),
        cpu_cores: std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1),
    }
}
