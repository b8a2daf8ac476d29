//! `tessera`: the command line. Parses arguments, calls the library, prints, and picks the exit code.
//!
//! Exit codes (documented in README.md): 0 ok (expected failures included), 1 a gate failed or a
//! variant failed, an unexpected pass, or an unapproved frame (`--expect`), 2 bad input
//! (scenario, expectations or digest file, arguments, images, output folder), 3 no usable adapter
//! or a device failure, 4 the upload to a dashboard failed (results are on disk) or `--expect URL`
//! could not reach it.
//! `tessera runner`: 0 after SIGTERM, 2 bad setup (repository, work folder, token), 4 the
//! dashboard refused or could not be reached.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use tessera::run::{self, console, SuiteError};
use tessera::scenario::{self, Scenario};

/// Counts the harness's heap for the results' `peak_heap_bytes` (`run/memory.rs`).
#[global_allocator]
static ALLOC: tessera::run::memory::CountingAlloc = tessera::run::memory::CountingAlloc;

const EXIT_GATE: u8 = 1;
const EXIT_INPUT: u8 = 2;
const EXIT_DEVICE: u8 = 3;
const EXIT_UPLOAD: u8 = 4;

#[derive(Parser)]
#[command(
    name = "tessera",
    version,
    about = "GPU benchmark harness for shading-reduction techniques"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run scenarios (files or folders of *.toml) on one adapter and write results.
    Run {
        #[arg(required = true)]
        paths: Vec<PathBuf>,
        /// Adapter whose name, driver or backend contains this text, or its vendor (nvidia, amd, intel,
        /// 0x10de), case-insensitive.
        #[arg(long)]
        adapter: Option<String>,
        /// Folder that receives `<run-id>/`.
        #[arg(long, default_value = "results")]
        out: PathBuf,
        /// Also write JUnit XML here.
        #[arg(long)]
        junit: Option<PathBuf>,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
        /// Then send the run to this dashboard (token from TESSERA_DASHBOARD_TOKEN).
        #[arg(long, value_name = "URL")]
        upload: Option<String>,
        /// Branch recorded with the run (default: the checkout's git branch).
        #[arg(long)]
        branch: Option<String>,
        /// Where the metrics are computed, for every scenario: `gpu` (the device that rendered
        /// the frames) or `cpu` (the reference implementations). Default: each scenario's
        /// `metrics_device`, else the GPU unless the adapter is a CPU (lavapipe).
        #[arg(long, value_name = "gpu|cpu", value_parser = tessera::metrics_device::Backend::parse)]
        metrics_device: Option<tessera::metrics_device::Backend>,
        /// Print where the run's wall time went (clock warm-up, timed frames, capture,
        /// metrics, images, ...) per scenario and for the run, on stderr, and write it to
        /// `<run>/timings.json`.
        #[arg(long)]
        timings: bool,
        /// Run only the variants whose names match (comma-separated, `*` as a wildcard, e.g.
        /// "taau*,fsr1[scale=0.5]"), with `native` and their own baselines; scenarios without
        /// a match are left out.
        #[arg(long, value_name = "PATTERN")]
        variants: Option<String>,
        /// Also run the variants the suite's expectations label `slow`.
        #[arg(long)]
        slow: bool,
        /// Approved frame digests to check every frame against (exit 1 on an unapproved
        /// change): a dashboard URL (`GET /api/approved-frames`) or a digest file such as
        /// `scenarios/smoke/digests/llvmpipe.json`. Read before the run starts.
        #[arg(long, value_name = "URL|FILE")]
        expect: Option<String>,
        /// The adapter class the run declares (e.g. a runner's label); default: derived from the
        /// adapter (`llvmpipe`, `nvidia`, `amd`, `intel`).
        #[arg(long, value_name = "CLASS")]
        adapter_class: Option<String>,
    },
    /// Approved frame digests committed beside a suite (`scenarios/<suite>/digests/<class>.json`).
    Digests {
        #[command(subcommand)]
        command: DigestsCommand,
    },
    /// A suite's expectations (`scenarios/<suite>/expectations.toml`).
    Expectations {
        #[command(subcommand)]
        command: ExpectationsCommand,
    },
    /// Check scenarios without a GPU.
    Validate {
        #[arg(required = true)]
        paths: Vec<PathBuf>,
    },
    /// Load the scenes of scenarios on one adapter and time it: meshes, glTF materials, the city,
    /// textures and their mip chains, waited for on the GPU (what a run does before its first frame).
    Load {
        #[arg(required = true)]
        paths: Vec<PathBuf>,
        /// Adapter whose name, driver or backend contains this text, or its vendor (nvidia, amd, intel,
        /// 0x10de), case-insensitive.
        #[arg(long)]
        adapter: Option<String>,
    },
    /// List every adapter with the features that matter to Tessera.
    Adapters {
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Compare two run folders: the Markdown a pull request would show (exit 1 on a regression).
    Compare {
        /// The base run folder.
        run_a: PathBuf,
        /// The new run folder, compared against the base.
        run_b: PathBuf,
        /// Smallest median GPU-time change (percent) that can be a verdict.
        #[arg(long, default_value_t = 5.0)]
        threshold_pct: f64,
    },
    /// Where each scenario's frame time goes and every technique's speed-up against it, ordered
    /// from vertex-bound to shading-bound (the pixel-bound fraction of `native`, measured with
    /// `upscale` at scale 0.7071): a Markdown table.
    Regimes {
        /// Run folders (e.g. of `scenarios/content/regimes.toml`).
        #[arg(required = true)]
        runs: Vec<PathBuf>,
    },
    /// The measured tables of the READMEs from run folders: per scenario and adapter, the driver
    /// and clocks, then per variant GPU ms, speed-up, every metric, its Pareto fronts and run ids.
    Report {
        /// Run folders, or folders holding run folders.
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// `text` (aligned columns) or `md` (Markdown, for a README).
        #[arg(long, value_enum, default_value_t = tessera::tables::Format::Text)]
        format: tessera::tables::Format,
    },
    /// Send a run folder to a dashboard (`POST /api/runs`, token from TESSERA_DASHBOARD_TOKEN).
    Upload {
        run: PathBuf,
        /// The dashboard, e.g. http://dashboard:8080.
        #[arg(long)]
        url: String,
    },
    /// Claim jobs of these labels from a dashboard's queue, build each job's commit in a worktree
    /// of REPOSITORY, run it and report back, until SIGTERM (token in TESSERA_DASHBOARD_TOKEN).
    Runner {
        /// The dashboard, e.g. http://dashboard:8080.
        #[arg(long, value_name = "URL")]
        dashboard: String,
        /// Adapter classes this runner serves, comma-separated (llvmpipe, nvidia, amd, ...).
        #[arg(long, value_delimiter = ',', required = true)]
        labels: Vec<String>,
        /// A git clone of the project; the runner adds its own worktree to it.
        #[arg(long)]
        repository: PathBuf,
        /// Worktree and results folder (default: beside the repository).
        #[arg(long)]
        work: Option<PathBuf>,
        /// Cargo target directory; several runners on one machine may share one.
        #[arg(long)]
        target_dir: Option<PathBuf>,
        /// Unique runner name (default: host and process id).
        #[arg(long)]
        name: Option<String>,
        /// Seconds between claims while the queue is empty.
        #[arg(long, default_value_t = 5)]
        poll_secs: u64,
        /// Adapter whose name, driver or backend contains this text, as reported at registration.
        #[arg(long)]
        adapter: Option<String>,
        /// Stop after the queue has been empty this many seconds (scripts, tests).
        #[arg(long)]
        exit_when_idle_secs: Option<u64>,
    },
    /// Compare two images (PSNR, SSIM, FLIP and more), or two image sequences (folders of
    /// numbered PNG/EXR frames, or run-folder variant stems like `<run>/<scenario>/checkerboard`):
    /// the same averaged over frames, plus ColorVideoVDP (JOD).
    Diff {
        reference: PathBuf,
        test: PathBuf,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
        /// Write the FLIP error map in magma colours here (image pairs only).
        #[arg(long)]
        heatmap: Option<PathBuf>,
        /// Sequences: the ColorVideoVDP display, a name (standard_4k, paper_27in_4k, ...) or
        /// key=value pairs (base=standard_4k,diagonal_inches=27,distance_m=0.6,peak_luminance=400).
        #[arg(long, default_value = tessera_metrics::DEFAULT_DISPLAY)]
        display: String,
        /// Sequences: frames per second.
        #[arg(long, default_value_t = 60.0)]
        fps: f64,
        /// Compute PSNR, SSIM and FLIP on the GPU (first adapter by the same rules as `run`;
        /// `WGPU_BACKEND` applies); ColorVideoVDP and 16-bit PNG metrics stay on the CPU.
        #[arg(long)]
        gpu: bool,
    },
}

#[derive(Subcommand)]
enum ExpectationsCommand {
    /// Rewrite each suite's expectations.toml from run folders: a failure without an entry becomes
    /// a `broken` entry with the error as its reason, an entry whose results passed is removed;
    /// prints the change as a unified diff, then writes it.
    Update {
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// Print the diff without writing (exit 1 when something would change).
        #[arg(long)]
        dry_run: bool,
    },
    /// Check expectations files without running anything.
    Check {
        #[arg(required = true)]
        files: Vec<PathBuf>,
    },
}

#[derive(Subcommand)]
enum DigestsCommand {
    /// Approve run folders' frames: write their digests as `positive` into
    /// `<suite folder>/digests/<adapter class>.json`, replacing the same frames' entries.
    Approve {
        #[arg(required = true)]
        runs: Vec<PathBuf>,
    },
}

fn main() -> ExitCode {
    quiet_headless_probing();
    // `tessera validate ... | head`: a closed pipe ends the process quietly, as for any Unix tool,
    // instead of a panic in `println!` (Rust ignores SIGPIPE by default).
    #[cfg(unix)]
    // SAFETY: called first thing on the main thread, before any other thread exists; restores
    // the default disposition of one signal.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() { EXIT_INPUT } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    ExitCode::from(match cli.command {
        Command::Run {
            paths,
            adapter,
            out,
            junit,
            quiet,
            upload,
            branch,
            metrics_device,
            timings,
            variants,
            slow,
            expect,
            adapter_class,
        } => run_command(
            &paths,
            adapter,
            out,
            junit,
            quiet,
            upload,
            branch,
            metrics_device,
            RunFlags {
                timings,
                slow,
                expect,
                adapter_class,
                variants,
            },
        ),
        Command::Digests {
            command: DigestsCommand::Approve { runs },
        } => match tessera::expect::digests::approve(&runs) {
            Ok(files) => {
                for (path, n) in files {
                    println!("{}: {n} frames approved", path.display());
                }
                0
            }
            Err(e) => {
                eprintln!("error: {e}");
                EXIT_INPUT
            }
        },
        Command::Expectations { command } => expectations_command(command),
        Command::Validate { paths } => validate_command(&paths),
        Command::Load { paths, adapter } => load_command(&paths, adapter),
        Command::Adapters { json } => adapters_command(json),
        Command::Compare {
            run_a,
            run_b,
            threshold_pct,
        } => compare_command(&run_a, &run_b, threshold_pct),
        Command::Upload { run, url } => upload_command(&run, &url),
        Command::Regimes { runs } => regimes_command(&runs),
        Command::Report { runs, format } => report_command(&runs, format),
        Command::Runner {
            dashboard,
            labels,
            repository,
            work,
            target_dir,
            name,
            poll_secs,
            adapter,
            exit_when_idle_secs,
        } => runner_command(&tessera::runner::Options {
            dashboard,
            labels,
            repository,
            work,
            target_dir,
            name,
            poll_secs,
            adapter,
            exit_when_idle_secs,
        }),
        Command::Diff {
            reference,
            test,
            json,
            heatmap,
            display,
            fps,
            gpu,
        } if heatmap.is_none() && !(reference.is_file() && test.is_file()) => {
            diff_sequence_command(&reference, &test, json, &display, fps, gpu)
        }
        Command::Diff {
            reference,
            test,
            json,
            heatmap,
            gpu,
            ..
        } => diff_command(&reference, &test, json, heatmap, gpu),
    })
}

/// Tessera never presents to a display, but libwayland (loaded by the Vulkan and EGL loaders while
/// probing) prints "error: XDG_RUNTIME_DIR is invalid" on headless machines. Give it a private
/// runtime folder so that the only `error:` lines on stderr are Tessera's own.
fn quiet_headless_probing() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        let dir = std::env::temp_dir().join("tessera-runtime");
        if std::fs::create_dir_all(&dir).is_ok() {
            #[cfg(unix)]
            {
                use std::os::unix::fs::PermissionsExt;
                let _ = std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o700));
            }
            std::env::set_var("XDG_RUNTIME_DIR", &dir);
        }
    }
}

/// Loads every scenario, printing every problem; `None` if any file is bad.
fn load_all(paths: &[PathBuf]) -> Option<Vec<Scenario>> {
    let files = match scenario::collect(paths) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("error: {e}");
            return None;
        }
    };
    let mut ok = Vec::new();
    let mut bad = 0;
    for f in &files {
        match scenario::load_all(f) {
            Ok(s) => ok.extend(s),
            Err(errors) => {
                bad += 1;
                for e in errors.0 {
                    eprintln!("error: {e}");
                }
            }
        }
    }
    let mut names: Vec<&str> = ok.iter().map(|s| s.name.as_str()).collect();
    names.sort();
    if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
        eprintln!(
            "error: two scenarios are named \"{}\": names must be unique within a run (set `name`)",
            w[0]
        );
        return None;
    }
    (bad == 0).then_some(ok)
}

fn validate_command(paths: &[PathBuf]) -> u8 {
    match load_all(paths) {
        Some(s) => {
            let variants: usize = s.iter().map(|s| s.variants.len()).sum();
            println!("{} scenarios valid ({variants} variants)", s.len());
            // What needs more than every adapter has, said before any device is opened.
            for scenario in &s {
                for v in &scenario.variants {
                    for reason in tessera::techniques::skip_reasons(v) {
                        println!("{}: {}: {reason}", scenario.file.display(), v.name);
                    }
                    if let Some(reason) = tessera::techniques::scene_skip_reason(v, &scenario.scene)
                    {
                        println!(
                            "{}: {}: {reason} (skipped on every adapter)",
                            scenario.file.display(),
                            v.name
                        );
                    }
                }
            }
            0
        }
        None => EXIT_INPUT,
    }
}

fn load_command(paths: &[PathBuf], adapter: Option<String>) -> u8 {
    let Some(scenarios) = load_all(paths) else {
        return EXIT_INPUT;
    };
    let gpu = match tessera::gpu::select(adapter.as_deref()).and_then(tessera::gpu::open) {
        Ok(g) => g,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_DEVICE;
        }
    };
    let mut failed = false;
    for s in &scenarios {
        let start = std::time::Instant::now();
        match tessera::render::scene::SceneGpu::new(&gpu.device, &gpu.queue, s) {
            Ok(scene) => {
                let _ = gpu.device.poll(wgpu::PollType::Wait {
                    submission_index: None,
                    timeout: None,
                });
                let ms = start.elapsed().as_secs_f64() * 1e3;
                println!(
                    "{:<40} {:>9.1} ms  {:>10} triangles  {:>8.1} MiB",
                    s.name,
                    ms,
                    scene.triangles,
                    scene.buffer_bytes as f64 / (1u64 << 20) as f64
                );
            }
            Err(e) => {
                eprintln!("error: {}: {e}", s.file.display());
                failed = true;
            }
        }
    }
    if failed {
        EXIT_INPUT
    } else {
        0
    }
}

/// `tessera run`'s switches beyond where and how to run.
struct RunFlags {
    timings: bool,
    slow: bool,
    expect: Option<String>,
    adapter_class: Option<String>,
    variants: Option<String>,
}

#[allow(clippy::too_many_arguments)]
fn run_command(
    paths: &[PathBuf],
    adapter: Option<String>,
    out: PathBuf,
    junit: Option<PathBuf>,
    quiet: bool,
    upload: Option<String>,
    branch: Option<String>,
    metrics_device: Option<tessera::metrics_device::Backend>,
    flags: RunFlags,
) -> u8 {
    let RunFlags {
        timings,
        slow,
        expect,
        adapter_class,
        variants,
    } = flags;
    let started = std::time::Instant::now();
    let Some(mut scenarios) = load_all(paths) else {
        return EXIT_INPUT;
    };
    if let Some(pattern) = &variants {
        match run::select::select(&mut scenarios, pattern) {
            Ok(sel) => {
                if !sel.dropped_scenarios.is_empty() {
                    eprintln!(
                        "--variants: left out {} scenario(s) without a match: {}",
                        sel.dropped_scenarios.len(),
                        sel.dropped_scenarios.join(", ")
                    );
                }
            }
            Err(e) => {
                eprintln!("error: {e}");
                return EXIT_INPUT;
            }
        }
    }
    let expectations = match tessera::expect::Book::load_for(&scenarios) {
        Ok(b) => b,
        Err(errors) => {
            for e in errors {
                eprintln!("error: {e}");
            }
            return EXIT_INPUT;
        }
    };
    if let Some(device) = metrics_device {
        for s in &mut scenarios {
            s.metrics_device = Some(device);
        }
    }
    // Refuse a bad URL or a missing token before the run, not after it.
    if let Some(url) = &upload {
        if let Err(e) = tessera::upload::endpoint(url).and(tessera::upload::token_from_env()) {
            eprintln!("error: --upload: {e}");
            return EXIT_INPUT;
        }
    }
    // Approved frame digests, read before the run (the adapter's class picks them).
    let approved = match &expect {
        Some(source) => {
            let class = match &adapter_class {
                Some(c) => c.clone(),
                None => match tessera::gpu::select(adapter.as_deref()) {
                    Ok(a) => tessera_results::adapter::class(&tessera::gpu::describe(&a)),
                    Err(e) => {
                        eprintln!("error: {e}");
                        return EXIT_DEVICE;
                    }
                },
            };
            match tessera::expect::digests::load(source, &class) {
                Ok(f) => Some(f),
                Err(e @ tessera::expect::digests::DigestError::Fetch { .. }) => {
                    eprintln!("error: --expect: {e}");
                    return EXIT_UPLOAD;
                }
                Err(e) => {
                    eprintln!("error: --expect: {e}");
                    return EXIT_INPUT;
                }
            }
        }
        None => None,
    };
    let opts = run::Options {
        adapter,
        out,
        junit,
        progress: !quiet && std::io::IsTerminal::is_terminal(&std::io::stderr()),
        command_line: std::env::args().collect(),
        suite: run::suite_name(paths),
        branch,
        timings,
        expectations,
        slow,
        adapter_class,
    };
    let outcome = match run::run_suite(&scenarios, &opts) {
        Ok(o) => o,
        Err(SuiteError::Gpu(e)) => {
            eprintln!("error: {e}");
            return EXIT_DEVICE;
        }
        Err(SuiteError::Write(e)) => {
            eprintln!("error: {e}");
            return EXIT_INPUT;
        }
    };
    if timings {
        // From the command's start: loading scenarios, opening the adapter, the run.
        eprintln!(
            "wall time of the command: {:.2} s",
            started.elapsed().as_secs_f64()
        );
    }
    let tally = console::tally(&outcome.scenarios);
    eprintln!("results: {}", outcome.run_dir.display());
    println!("{}", console::stability_summary(&outcome.scenarios));
    let frames_changed = match (&approved, &expect) {
        (Some(file), Some(source)) => {
            let check = tessera::expect::digests::check(&outcome.scenarios, file);
            for at in &check.unapproved {
                eprintln!("error: unapproved frame: {at}");
            }
            for at in &check.negative {
                eprintln!("error: frame marked as a regression: {at}");
            }
            println!("{}", check.summary(source));
            check.failed()
        }
        _ => false,
    };
    println!("{}", console::verdict(&tally));
    let code = if outcome.device_lost {
        EXIT_DEVICE
    } else if tally.failed > 0
        || tally.gate_failures > 0
        || tally.unexpected_passes > 0
        || frames_changed
    {
        EXIT_GATE
    } else {
        0
    };
    match upload.map(|url| (tessera::upload::upload(&outcome.run_dir, &url), url)) {
        Some((Err(e), url)) => {
            eprintln!("error: {e}");
            eprintln!(
                "hint: the results are in {}; send them later with `tessera upload {} --url {url}`",
                outcome.run_dir.display(),
                outcome.run_dir.display()
            );
            if code == 0 {
                EXIT_UPLOAD
            } else {
                code
            }
        }
        Some((Ok(reply), _)) => {
            eprintln!("{}", reply.summary());
            for w in &reply.warnings {
                eprintln!("warning: {w}");
            }
            code
        }
        None => code,
    }
}

fn expectations_command(command: ExpectationsCommand) -> u8 {
    use tessera::expect::update;
    match command {
        ExpectationsCommand::Check { files } => {
            let mut bad = false;
            for f in &files {
                match tessera::expect::load(f) {
                    Ok(Some(e)) => println!("{}: {} entries valid", f.display(), e.entries.len()),
                    Ok(None) => {
                        eprintln!("error: {}: no such file", f.display());
                        bad = true;
                    }
                    Err(errors) => {
                        for e in errors {
                            eprintln!("error: {e}");
                        }
                        bad = true;
                    }
                }
            }
            if bad {
                EXIT_INPUT
            } else {
                0
            }
        }
        ExpectationsCommand::Update { runs, dry_run } => {
            let updates = match update::plan(&runs) {
                Ok(u) => u,
                Err(e) => {
                    eprintln!("error: {e}");
                    return EXIT_INPUT;
                }
            };
            let mut changed = 0;
            for u in &updates {
                for note in &u.notes {
                    eprintln!("note: {note}");
                }
                if !u.changed() {
                    continue;
                }
                changed += 1;
                print!("{}", u.diff());
                if !dry_run {
                    if let Err(e) = update::write(u) {
                        eprintln!("error: {e}");
                        return EXIT_INPUT;
                    }
                }
            }
            match (changed, dry_run) {
                (0, _) => {
                    eprintln!("expectations are up to date with these runs");
                    0
                }
                (n, true) => {
                    eprintln!("{n} expectations files would change (--dry-run: nothing written)");
                    EXIT_GATE
                }
                (n, false) => {
                    eprintln!("{n} expectations files updated");
                    0
                }
            }
        }
    }
}

fn upload_command(run: &std::path::Path, url: &str) -> u8 {
    match tessera::upload::upload(run, url) {
        Ok(reply) => {
            println!("{}", reply.summary());
            for w in &reply.warnings {
                eprintln!("warning: {w}");
            }
            0
        }
        Err(e) => {
            eprintln!("error: {e}");
            if e.is_bad_input() {
                EXIT_INPUT
            } else {
                EXIT_UPLOAD
            }
        }
    }
}

fn runner_command(opts: &tessera::runner::Options) -> u8 {
    use tessera::runner::RunnerError;
    match tessera::runner::run(opts) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            match e {
                RunnerError::Client(_) => EXIT_UPLOAD,
                _ => EXIT_INPUT,
            }
        }
    }
}

fn compare_command(a: &std::path::Path, b: &std::path::Path, threshold_pct: f64) -> u8 {
    use tessera::compare;
    if !(threshold_pct.is_finite() && threshold_pct >= 0.0) {
        eprintln!("error: --threshold-pct must be a number >= 0, not {threshold_pct}");
        return EXIT_INPUT;
    }
    let (a, b) = match (compare::load_run(a), compare::load_run(b)) {
        (Ok(a), Ok(b)) => (a, b),
        (Err(e), _) | (_, Err(e)) => {
            eprintln!("error: {e}");
            return EXIT_INPUT;
        }
    };
    let c = compare::compare(
        &a,
        &b,
        &compare::Options {
            threshold_pct,
            ..Default::default()
        },
    );
    print!("{}", compare::markdown::render(&c));
    if c.regressed() {
        EXIT_GATE
    } else {
        0
    }
}

/// Reads run folders; the first that cannot be read is printed and ends the command.
fn load_runs(dirs: &[PathBuf]) -> Option<Vec<tessera::compare::Run>> {
    let mut runs = Vec::new();
    for d in dirs {
        match tessera::compare::load_run(d) {
            Ok(r) => runs.push(r),
            Err(e) => {
                eprintln!("error: {e}");
                return None;
            }
        }
    }
    Some(runs)
}

fn regimes_command(dirs: &[PathBuf]) -> u8 {
    let Some(runs) = load_runs(dirs) else {
        return EXIT_INPUT;
    };
    let rows = tessera::regimes::rows(&runs);
    if rows.is_empty() {
        eprintln!("error: no scenario in these runs has a timed `native` variant");
        return EXIT_INPUT;
    }
    print!("{}", tessera::regimes::markdown(&rows));
    0
}

fn report_command(args: &[PathBuf], format: tessera::tables::Format) -> u8 {
    let dirs = match tessera::tables::run_folders(args) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("error: cannot list the run folders: {e}");
            return EXIT_INPUT;
        }
    };
    let Some(runs) = load_runs(&dirs) else {
        return EXIT_INPUT;
    };
    let tables = tessera::tables::tables(&runs);
    if tables.is_empty() {
        eprintln!("error: these runs hold no scenario results");
        return EXIT_INPUT;
    }
    print!("{}", tessera::tables::render(&tables, format));
    0
}

fn adapters_command(json: bool) -> u8 {
    let adapters = tessera::gpu::enumerate();
    if adapters.is_empty() {
        eprintln!("error: {}", tessera::gpu::GpuError::NoAdapter);
        return EXIT_DEVICE;
    }
    let infos: Vec<_> = adapters.iter().map(tessera::gpu::describe).collect();
    if json {
        println!(
            "{}",
            serde_json::to_string_pretty(&infos).unwrap_or_default()
        );
        return 0;
    }
    for i in infos {
        let f = &i.features;
        println!("{} ({}, {})", i.name, i.backend, i.device_type);
        println!("  driver:         {} {}", i.driver, i.driver_info);
        println!(
            "  ids:            vendor 0x{:04x}, device 0x{:04x}",
            i.vendor, i.device
        );
        println!(
            "  timestamps:     {}{}",
            if f.timestamps { "yes" } else { "no" },
            if f.timestamps_inside_passes {
                " (inside passes too)"
            } else {
                ""
            }
        );
        println!(
            "  pipeline stats: {}",
            if f.pipeline_statistics { "yes" } else { "no" }
        );
        println!(
            "  shader f16:     {}",
            if f.shader_f16 { "yes" } else { "no" }
        );
        println!("  max texture:    {}", f.max_texture_dimension_2d);
        for (format, counts) in &f.msaa {
            let c: Vec<String> = counts.iter().map(|n| format!("{n}x")).collect();
            println!("  msaa {format:<12}  {}", c.join(" "));
        }
    }
    0
}

fn diff_sequence_command(
    reference: &std::path::Path,
    test: &std::path::Path,
    json: bool,
    display: &str,
    fps: f64,
    gpu: bool,
) -> u8 {
    let mut metrics = match gpu
        .then(|| tessera::metrics_device::open_gpu(None))
        .transpose()
    {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: --gpu: {e}");
            return EXIT_INPUT;
        }
    };
    let report = tessera_metrics::DisplaySpec::parse(display)
        .map_err(|e| e.to_string())
        .and_then(|display| {
            let settings = tessera_metrics::CvvdpSettings {
                display,
                fps,
                ..Default::default()
            };
            match metrics.as_mut() {
                Some(m) => {
                    tessera::metrics_device::diff_sequence_paths(m, reference, test, &settings)
                }
                None => tessera_metrics::diff_sequence_paths(reference, test, &settings)
                    .map_err(|e| e.to_string()),
            }
        });
    match report {
        Ok(r) if json => println!("{}", with_device(&r, metrics.as_ref())),
        Ok(r) => {
            print_device(metrics.as_ref());
            print!("{}", r.to_text())
        }
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_INPUT;
        }
    }
    0
}

fn diff_command(
    reference: &std::path::Path,
    test: &std::path::Path,
    json: bool,
    heatmap: Option<PathBuf>,
    gpu: bool,
) -> u8 {
    let load = tessera_metrics::load_image;
    let (r, t) = match (load(reference), load(test)) {
        (Ok(r), Ok(t)) => (r, t),
        (Err(e), _) | (_, Err(e)) => {
            eprintln!("error: {e}");
            return EXIT_INPUT;
        }
    };
    let mut metrics = match gpu
        .then(|| tessera::metrics_device::open_gpu(None))
        .transpose()
    {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: --gpu: {e}");
            return EXIT_INPUT;
        }
    };
    let report = match metrics.as_mut() {
        Some(m) => tessera::metrics_device::diff_images(m, &r, &t),
        None => tessera_metrics::diff_images(&r, &t).map_err(|e| e.to_string()),
    };
    let report = match report {
        Ok(rep) => rep,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_INPUT;
        }
    };
    if let Some(path) = heatmap {
        if let Err(e) =
            tessera_metrics::save_png(&path, &tessera_metrics::flip_heatmap(&report.flip))
        {
            eprintln!("error: {e}");
            return EXIT_INPUT;
        }
    }
    if json {
        println!("{}", with_device(&report, metrics.as_ref()));
    } else {
        print_device(metrics.as_ref());
        print!("{}", report.to_text());
    }
    0
}

/// A diff report's JSON; with `--gpu` it records the back end (`"metrics_device": "gpu"` and
/// the adapter). Without it the CPU computed everything, and the JSON is as before.
fn with_device(
    report: &impl serde::Serialize,
    gpu: Option<&tessera::metrics_device::GpuMetrics>,
) -> String {
    let mut v = serde_json::to_value(report).unwrap_or_default();
    if let (Some(g), Some(obj)) = (gpu, v.as_object_mut()) {
        obj.insert("metrics_device".into(), "gpu".into());
        obj.insert("metrics_adapter".into(), g.adapter_name().into());
    }
    serde_json::to_string_pretty(&v).unwrap_or_default()
}

fn print_device(gpu: Option<&tessera::metrics_device::GpuMetrics>) {
    if let Some(g) = gpu {
        println!("metrics device: gpu ({})", g.adapter_name());
    }
}
