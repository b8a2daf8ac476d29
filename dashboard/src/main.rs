//! `tessera-dashboard`: import run folders into the store, serve the dashboard, re-run regression
//! detection, write an upload bundle, manage API tokens, apply a retention rule. Errors print their
//! whole chain; exit code 1 for a failed command, 2 for bad arguments (clap).

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use clap::{Parser, Subcommand};
use tessera_dashboard::notify::webhook;
use tessera_dashboard::server::auth::{AuthConfig, Scope};
use tessera_dashboard::store::delete::{expired, Retention};
use tessera_dashboard::store::ingest::{ingest, Ingested};
use tessera_dashboard::store::tokens;
use tessera_dashboard::{
    bundle::RunBundle, db, detect::Params, import, queue_cli, regressions, replay, server, synth,
};

/// The server decodes hundreds of scenario records per wide page on several threads; mimalloc
/// keeps their many small allocations off glibc's shared arenas.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

const DEFAULT_DB: &str = "tessera-dashboard.sqlite";

#[derive(Parser)]
#[command(version, about = "Results store and dashboard for Tessera runs")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Approve a stored run's frames (or one scenario's) as a reviewer would after looking: their
    /// digests become the approved frames of their adapter class, and the frame alerts they
    /// raised are withdrawn. With --regression, mark them as a regression instead.
    Approve {
        /// The run id.
        #[arg(long)]
        run: String,
        /// Only this scenario's frames.
        #[arg(long)]
        scenario: Option<String>,
        /// Only this variant's frames (`(reference)` for a separate reference).
        #[arg(long)]
        variant: Option<String>,
        /// Mark the frames as a regression (`negative`) instead of approving them.
        #[arg(long)]
        regression: bool,
        /// Who approves, as recorded (default: $USER).
        #[arg(long)]
        by: Option<String>,
        #[arg(long, env = "TESSERA_DASHBOARD_DB", default_value = DEFAULT_DB)]
        db: String,
    },
    /// Store a run folder, or every run folder inside a folder (idempotent by run id).
    Import {
        /// A run folder (with run.json) or a folder of run folders.
        folder: PathBuf,
        /// SQLite file path or postgres://user:password@host/db URL.
        #[arg(long, env = "TESSERA_DASHBOARD_DB", default_value = DEFAULT_DB)]
        db: String,
    },
    /// Serve the pages and the JSON API.
    Serve {
        #[arg(long, env = "TESSERA_DASHBOARD_DB", default_value = DEFAULT_DB)]
        db: String,
        #[arg(long, default_value = "127.0.0.1:8080")]
        listen: String,
        /// Legacy write token (named `legacy`), besides the tokens of `tessera-dashboard token`.
        #[arg(long, env = "TESSERA_DASHBOARD_TOKEN", hide_env_values = true)]
        token: Option<String>,
        /// Largest accepted upload in MiB.
        #[arg(long, default_value_t = 64)]
        max_upload_mib: usize,
        /// Reads (pages and API, not /healthz) need a read or write token too.
        #[arg(long)]
        require_read_token: bool,
        /// Sustained writes per minute per token (0: no limit).
        #[arg(long, default_value_t = AuthConfig::default().writes_per_minute)]
        writes_per_minute: u32,
        /// Writes a token may make at once before the per-minute rate applies.
        #[arg(long, default_value_t = AuthConfig::default().write_burst)]
        write_burst: u32,
        /// A client must send a whole request head within this many seconds of connecting.
        #[arg(long, default_value_t = server::Timeouts::default().header.as_secs(), value_parser = clap::value_parser!(u64).range(1..))]
        header_timeout_secs: u64,
        /// Longest pause between two chunks of a request body.
        #[arg(long, default_value_t = server::Timeouts::default().body_idle.as_secs(), value_parser = clap::value_parser!(u64).range(1..))]
        body_timeout_secs: u64,
        /// Longest time for a whole request, body and answer included (408 after it).
        #[arg(long, default_value_t = server::Timeouts::default().request.as_secs(), value_parser = clap::value_parser!(u64).range(1..))]
        request_timeout_secs: u64,
        /// The dashboard's URL as others reach it, for links in the feed, Markdown and webhook
        /// (default: http:// and the request's Host; the webhook uses http://<listen>).
        #[arg(long, env = "TESSERA_DASHBOARD_PUBLIC_URL")]
        public_url: Option<String>,
        /// POST a JSON body to this URL for each newly confirmed alert group (retried with
        /// backoff; what was sent is kept in the store).
        #[arg(long, env = "TESSERA_DASHBOARD_WEBHOOK_URL", hide_env_values = true)]
        webhook_url: Option<String>,
        /// Seconds one webhook request may take.
        #[arg(long, default_value_t = 10)]
        webhook_timeout_s: u64,
        /// Seconds between two looks for newly confirmed groups.
        #[arg(long, default_value_t = 30)]
        webhook_poll_s: u64,
        /// A claimed job goes back to the queue this many seconds after its runner's last
        /// heartbeat; a runner not heard from for twice as long is shown offline.
        #[arg(long, default_value_t = 60, value_parser = clap::value_parser!(u64).range(1..=86400))]
        lease_secs: u64,
        /// Claims of one job before it is marked failed.
        #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(i64).range(1..=10))]
        max_job_attempts: i64,
        /// A clone of the project: queue requests naming a commit it lacks are refused.
        #[arg(long)]
        repository: Option<PathBuf>,
    },
    /// Named API tokens with read or write scope, stored hashed.
    Token {
        #[command(subcommand)]
        command: TokenCommand,
        #[arg(long, env = "TESSERA_DASHBOARD_DB", default_value = DEFAULT_DB, global = true)]
        db: String,
    },
    /// Delete runs that no retention rule keeps (dry run unless --apply; the list is printed
    /// first either way). A run is kept when its commit time (else the time it was stored) is
    /// within --keep-days or it is among the newest --keep-runs of its adapter in that order.
    Retention {
        /// Keep runs whose commit (else storing) time is at most this many days old.
        #[arg(long, required_unless_present = "keep_runs")]
        keep_days: Option<u32>,
        /// Keep the newest this many runs of each adapter (by commit time, else storing time).
        #[arg(long)]
        keep_runs: Option<u32>,
        /// Delete; without it, only list what would be deleted.
        #[arg(long)]
        apply: bool,
        #[arg(long, env = "TESSERA_DASHBOARD_DB", default_value = DEFAULT_DB)]
        db: String,
    },
    /// Re-run regression detection on every stored series.
    Detect {
        #[arg(long, env = "TESSERA_DASHBOARD_DB", default_value = DEFAULT_DB)]
        db: String,
    },
    /// Replay benchmark of online detection: synthetic nightly histories made from a real run,
    /// uploaded run by run as `POST /api/runs` stores them, scored against the injected changes
    /// and against one batch pass (see docs/regressions.md). Exit code 1 when a target is missed.
    Replay {
        /// The run folder to copy (default: the committed lavapipe fixture).
        #[arg(default_value = "dashboard/tests/fixtures/runs/20261122T030520Z-34ab2b4")]
        template: PathBuf,
        #[arg(long, default_value_t = 120)]
        nights: usize,
        /// Copies of the template's scenarios in each run.
        #[arg(long, default_value_t = 16)]
        scenarios: usize,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// An empty store to replay into (default: a temporary SQLite file).
        #[arg(long)]
        db: Option<String>,
        /// List the changes not blamed on their exact commit and the false alerts.
        #[arg(long)]
        verbose: bool,
    },
    /// Queue a nightly run (or backfill) of suites at a commit: one job per suite and label.
    Request {
        #[arg(long)]
        commit: String,
        /// Folders under scenarios/, comma-separated.
        #[arg(long, value_delimiter = ',', required = true)]
        suites: Vec<String>,
        /// Adapter classes, comma-separated (one job per suite and label).
        #[arg(long, value_delimiter = ',', required = true)]
        labels: Vec<String>,
        /// `nightly` or `backfill`.
        #[arg(long, default_value = "nightly")]
        kind: String,
        /// A clone of the project: unknown commits are refused, short ones expanded.
        #[arg(long)]
        repository: Option<PathBuf>,
        #[arg(long, env = "TESSERA_DASHBOARD_DB", default_value = DEFAULT_DB)]
        db: String,
    },
    /// A/B two environments (`COMMIT [KEY=VALUE ...]`) on one runner of each label, back to back
    /// in random order; with --wait, print the paired comparison per measure (exit 1 if a job
    /// failed).
    Ab {
        /// Scenario file, relative to the repository root.
        #[arg(long)]
        scenario: String,
        #[arg(long)]
        variant: Option<String>,
        #[arg(long, value_name = "COMMIT_OR_ENV")]
        a: String,
        #[arg(long, value_name = "COMMIT_OR_ENV")]
        b: String,
        #[arg(long, value_delimiter = ',', required = true)]
        labels: Vec<String>,
        /// Attempts of each environment (1 to 100).
        #[arg(long, default_value_t = tessera_dashboard::ab::DEFAULT_ATTEMPTS)]
        attempts: usize,
        #[arg(long)]
        repository: Option<PathBuf>,
        /// Wait for the result and print it.
        #[arg(long)]
        wait: bool,
        #[arg(long, env = "TESSERA_DASHBOARD_DB", default_value = DEFAULT_DB)]
        db: String,
    },
    /// Bisect a change of one measure between a good and a bad commit with A/B steps on one
    /// label's runners; with --wait, print the steps and the culprit (exit 1 without one).
    Bisect {
        #[arg(long)]
        scenario: String,
        #[arg(long)]
        variant: String,
        /// A measure name (gpu_ms.median, psnr, flip, cvvdp (JOD), ...) or frames_changed.
        #[arg(long)]
        measure: String,
        #[arg(long)]
        good: String,
        #[arg(long)]
        bad: String,
        #[arg(long)]
        labels: String,
        #[arg(long, default_value_t = tessera_dashboard::ab::DEFAULT_ATTEMPTS)]
        attempts: usize,
        /// Record the result on this alert.
        #[arg(long)]
        alert: Option<i64>,
        #[arg(long)]
        repository: Option<PathBuf>,
        #[arg(long)]
        wait: bool,
        #[arg(long, env = "TESSERA_DASHBOARD_DB", default_value = DEFAULT_DB)]
        db: String,
    },
    /// Print a run folder as the JSON body that `POST /api/runs` takes.
    Bundle { folder: PathBuf },
    /// Store generated runs made from a real one (for benchmarks): timings scaled with 1% noise.
    Generate {
        /// The run folder to copy.
        template: PathBuf,
        #[arg(long, default_value_t = 100)]
        runs: u64,
        /// Copies of the template's scenarios in each run.
        #[arg(long, default_value_t = 1)]
        scenarios: usize,
        /// Run ids are `<prefix>-<index>`: a second generate into one store needs another prefix.
        #[arg(long, default_value = "gen")]
        prefix: String,
        #[arg(long, env = "TESSERA_DASHBOARD_DB", default_value = DEFAULT_DB)]
        db: String,
        /// Then time this many further runs stored as an upload stores them (run and detection
        /// in one transaction) and print the median and 95th percentile.
        #[arg(long, default_value_t = 0)]
        then_upload: u64,
        /// Scenario copies in each timed upload (default: as many as the generated runs).
        #[arg(long)]
        upload_scenarios: Option<usize>,
    },
    /// Store a nightly history with one injected step, made from a real run, as uploads store it
    /// (detection on each run): the morning-after case of the compare, run and regressions pages.
    Steps {
        /// The run folder to copy (default: the committed lavapipe fixture).
        #[arg(long)]
        template: Option<PathBuf>,
        #[arg(long, default_value_t = 24)]
        nights: usize,
        /// First night with the step.
        #[arg(long, default_value_t = 20)]
        step_night: usize,
        /// The variant that steps.
        #[arg(long, default_value = "native")]
        variant: String,
        /// Its times are multiplied by this from the step's night on.
        #[arg(long, default_value_t = 1.05)]
        factor: f64,
        /// Measured frames per result.
        #[arg(long, default_value_t = 30)]
        frames: usize,
        /// `h200` (GPU, 0.1% nightly noise, recorded conditions) or `lavapipe` (CPU, 2%).
        #[arg(long, default_value = "h200", value_parser = ["h200", "lavapipe"])]
        profile: String,
        /// From this night on the H200's graphics clock reads lower (and it is throttled).
        #[arg(long)]
        clock_from: Option<usize>,
        #[arg(long, env = "TESSERA_DASHBOARD_DB", default_value = DEFAULT_DB)]
        db: String,
    },
}

#[derive(Subcommand)]
enum TokenCommand {
    /// Make a token and print its secret (shown only this once).
    Add {
        name: String,
        #[arg(long, value_parser = ["read", "runner", "write"])]
        scope: String,
    },
    /// List tokens: name, scope, creation time (never secrets).
    List,
    /// Delete a token; requests with it are refused from the next request on.
    Revoke { name: String },
}

fn token_command(command: TokenCommand, db: &str) -> anyhow::Result<()> {
    let pool = db::open(db)?;
    let mut conn = pool.get()?;
    match command {
        TokenCommand::Add { name, scope } => {
            let scope: Scope = scope.parse().map_err(anyhow::Error::msg)?;
            let secret = tokens::add(&mut *conn, &name, scope)?;
            eprintln!(
                "token {name:?} ({}) added; its secret is shown only now:",
                scope.as_str()
            );
            println!("{secret}");
        }
        TokenCommand::List => {
            let list = tokens::list(&mut *conn)?;
            if list.is_empty() {
                eprintln!(
                    "no tokens (add one with `tessera-dashboard token add NAME --scope write`)"
                );
            }
            for t in list {
                println!("{}\t{}\t{}", t.name, t.scope.as_str(), t.created_at);
            }
        }
        TokenCommand::Revoke { name } => {
            tokens::revoke(&mut *conn, &name)?;
            println!("token {name:?} revoked");
        }
    }
    Ok(())
}

fn retention(rule: Retention, apply: bool, db: &str) -> anyhow::Result<()> {
    let pool = db::open(db)?;
    let mut conn = pool.get()?;
    let runs = expired(&mut *conn, rule, chrono::Utc::now())?;
    // The whole list first, so that what --apply removes is on screen before the first delete.
    for r in &runs {
        println!(
            "would delete {} ({} time {}, {})",
            r.run_id, r.by, r.at, r.adapter
        );
    }
    if !apply {
        println!(
            "{} runs would be deleted; nothing was changed (add --apply to delete)",
            runs.len()
        );
        return Ok(());
    }
    for r in &runs {
        let (d, _) = tessera_dashboard::regressions::delete_and_detect(
            &mut *conn,
            &r.run_id,
            &Params::default(),
        )?;
        println!(
            "deleted {}: {} results, {} images, {} alerts re-pointed",
            r.run_id, d.results, d.images, d.alerts
        );
    }
    println!("deleted {} runs", runs.len());
    Ok(())
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Approve {
            run,
            scenario,
            variant,
            regression,
            by,
            db,
        } => {
            use tessera_dashboard::store::frames;
            let pool = db::open(&db)?;
            let mut conn = pool.get()?;
            let state = if regression {
                frames::NEGATIVE
            } else {
                frames::POSITIVE
            };
            let j = frames::Judge {
                run_id: run.clone(),
                scenario,
                variant,
                frame: None,
                state: state.to_string(),
                by: by
                    .or_else(|| std::env::var("USER").ok())
                    .unwrap_or_else(|| "command line".into()),
            };
            let n = tessera_dashboard::db::transaction(&mut *conn, |c| frames::judge(c, &j))?;
            println!("{n} frames of run {run} are now {state}");
        }
        Command::Import { folder, db } => {
            let pool = db::open(&db)?;
            let summary = import::import(&pool, &folder, &Params::default())?;
            for (path, err) in &summary.failed {
                eprintln!("error: {}: {err}", path.display());
            }
            for (path, warning) in &summary.warnings {
                eprintln!("warning: {}: {warning}", path.display());
            }
            println!("{}", summary.line());
            if !summary.failed.is_empty() {
                anyhow::bail!(
                    "{} run folder(s) could not be imported",
                    summary.failed.len()
                );
            }
        }
        Command::Serve {
            db,
            listen,
            token,
            max_upload_mib,
            require_read_token,
            writes_per_minute,
            write_burst,
            header_timeout_secs,
            body_timeout_secs,
            request_timeout_secs,
            public_url,
            webhook_url,
            webhook_timeout_s,
            webhook_poll_s,
            lease_secs,
            max_job_attempts,
            repository,
        } => {
            let pool = db::open(&db)?;
            let named = tokens::list(&mut *pool.get()?)?;
            let mut state = server::AppState::new(pool, token.filter(|t| !t.is_empty()));
            state.max_upload_bytes = max_upload_mib << 20;
            state.auth = server::auth::Auth::new(AuthConfig {
                require_read_token,
                writes_per_minute,
                write_burst,
            });
            state.timeouts = server::Timeouts {
                header: Duration::from_secs(header_timeout_secs),
                body_idle: Duration::from_secs(body_timeout_secs),
                request: Duration::from_secs(request_timeout_secs),
            };
            let public_url = public_url.filter(|u| !u.is_empty());
            if let Some(u) = &public_url {
                if !(u.starts_with("http://") || u.starts_with("https://")) {
                    anyhow::bail!("--public-url must start with http:// or https://, not {u:?}");
                }
            }
            state.public_url = public_url.clone();
            state.queue = server::queue::QueueConfig {
                lease_ms: lease_secs as i64 * 1000,
                offline_after_ms: lease_secs as i64 * 2000,
                max_attempts: max_job_attempts,
                repository,
            };
            if let Some(url) = webhook_url.filter(|u| !u.is_empty()) {
                if !(url.starts_with("http://") || url.starts_with("https://")) {
                    anyhow::bail!("--webhook-url must start with http:// or https://");
                }
                let base = public_url.unwrap_or_else(|| format!("http://{listen}"));
                let mut config = webhook::Config::new(&url, &base);
                config.timeout = std::time::Duration::from_secs(webhook_timeout_s.max(1));
                config.poll = std::time::Duration::from_secs(webhook_poll_s.max(1));
                let notifier = webhook::Notifier::new(state.pool.clone(), config);
                eprintln!(
                    "webhook: posting newly confirmed alert groups (outbox target {})",
                    notifier.target()
                );
                notifier.spawn();
            }
            if state.token.is_none() && !named.iter().any(|t| t.scope == Scope::Write) {
                eprintln!(
                    "note: no write token (tessera-dashboard token add NAME --scope write, or --token): uploads and triage are refused"
                );
            }
            let rt = tokio::runtime::Runtime::new()?;
            rt.block_on(async move {
                let listener = tokio::net::TcpListener::bind(&listen)
                    .await
                    .map_err(|e| anyhow::anyhow!("cannot listen on {listen}: {e}"))?;
                let addr = listener.local_addr()?;
                eprintln!("serving {} on http://{addr}", state.pool.describe());
                let timeouts = state.timeouts;
                server::listen::serve(listener, server::app(state), timeouts, async {
                    let _ = tokio::signal::ctrl_c().await;
                })
                .await?;
                anyhow::Ok(())
            })?;
        }
        Command::Token { command, db } => token_command(command, &db)?,
        Command::Request {
            commit,
            suites,
            labels,
            kind,
            repository,
            db,
        } => queue_cli::request(&db, &kind, &commit, &suites, &labels, repository.as_deref())?,
        Command::Ab {
            scenario,
            variant,
            a,
            b,
            labels,
            attempts,
            repository,
            wait,
            db,
        } => {
            let ok = queue_cli::ab(
                &db,
                &scenario,
                variant.as_deref(),
                &a,
                &b,
                &labels,
                attempts,
                repository.as_deref(),
                wait,
            )?;
            if !ok {
                anyhow::bail!("an A/B job failed");
            }
        }
        Command::Bisect {
            scenario,
            variant,
            measure,
            good,
            bad,
            labels,
            attempts,
            alert,
            repository,
            wait,
            db,
        } => {
            let p = tessera_dashboard::ab::bisect::Params {
                scenario,
                variant,
                measure,
                good,
                bad,
                label: labels,
                attempts,
                regression_id: alert,
            };
            if !queue_cli::bisect(&db, p, repository.as_deref(), wait)? {
                anyhow::bail!("the bisection ended without a culprit");
            }
        }
        Command::Retention {
            keep_days,
            keep_runs,
            apply,
            db,
        } => retention(
            Retention {
                keep_days,
                keep_runs,
            },
            apply,
            &db,
        )?,
        Command::Detect { db } => {
            let pool = db::open(&db)?;
            let mut conn = pool.get()?;
            let series = regressions::all_series(&mut *conn)?;
            let c = regressions::update_all(&mut *conn, &series, &Params::default())?;
            println!(
                "checked {} series: {} new alerts, {} moved, {} merged, {} withdrawn, {} confirmed, {} reinstated",
                series.len(),
                c.detected,
                c.moved,
                c.merged,
                c.withdrawn,
                c.confirmed,
                c.reinstated
            );
        }
        Command::Generate {
            template,
            runs,
            scenarios,
            prefix,
            db,
            then_upload,
            upload_scenarios,
        } => {
            let pool = db::open(&db)?;
            let base = RunBundle::read_folder(&template)?;
            let template = synth::widen(&base, scenarios);
            let mut rng = tessera_dashboard::detect::Rng::new(1);
            let mut conn = pool.get()?;
            let start = std::time::Instant::now();
            let mut results = 0;
            let mut touched = std::collections::BTreeSet::new();
            for i in 0..runs {
                let b = synth::run_from(&template, &prefix, i, 1.0, 0.01, &mut rng);
                if let Ingested::Stored {
                    results: n, series, ..
                } = ingest(&mut *conn, &b)?
                {
                    results += n;
                    touched.extend(series);
                }
            }
            let stored = start.elapsed().as_secs_f64();
            let touched: Vec<i64> = touched.into_iter().collect();
            let added = regressions::update(&mut *conn, &touched, &Params::default())?;
            println!(
                "stored {runs} runs ({results} results) in {stored:.1} s ({:.0} results/s); detection on {} series in {:.1} s: {added} change points",
                results as f64 / stored,
                touched.len(),
                start.elapsed().as_secs_f64() - stored
            );
            if then_upload > 0 {
                let small = synth::widen(&base, upload_scenarios.unwrap_or(scenarios));
                let first: u64 = conn.query("SELECT COUNT(*) FROM runs", &[])?[0].i64(0)? as u64;
                let mut ms = Vec::new();
                let mut checkpoints = Vec::new();
                let mut series = 0;
                for i in first..first + then_upload {
                    let b = synth::run_from(&small, "gen", i, 1.0, 0.01, &mut rng);
                    let t = std::time::Instant::now();
                    // As `serve` stores an upload: the checkpoint after it, timed apart.
                    let (ingested, _) = db::without_autocheckpoint(&mut *conn, |c| {
                        regressions::ingest_and_detect(c, &b, &Params::default())
                    })??;
                    ms.push(t.elapsed().as_secs_f64() * 1e3);
                    let t = std::time::Instant::now();
                    db::checkpoint(&mut *conn)?;
                    checkpoints.push(t.elapsed().as_secs_f64() * 1e3);
                    if let Ingested::Stored { series: s, .. } = ingested {
                        series = s.len();
                    }
                }
                ms.sort_by(|a, b| a.total_cmp(b));
                checkpoints.sort_by(|a, b| a.total_cmp(b));
                println!(
                    "{then_upload} uploads of {} results ({series} series each): p50 {:.1} ms, p95 {:.1} ms; the checkpoint after each: p50 {:.1} ms",
                    small.scenarios.iter().map(|s| s.results.len()).sum::<usize>(),
                    ms[ms.len() / 2],
                    ms[(ms.len() - 1) * 95 / 100],
                    checkpoints[checkpoints.len() / 2]
                );
            }
        }
        Command::Steps {
            template,
            nights,
            step_night,
            variant,
            factor,
            frames,
            profile,
            clock_from,
            db,
        } => {
            let gpu = profile == "h200";
            let template = template.unwrap_or_else(|| {
                PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                    .join("tests/fixtures/runs/20261122T030520Z-34ab2b4")
            });
            let template = RunBundle::read_folder(&template).map_err(|e| {
                anyhow::anyhow!("reading the template run {}: {e}", template.display())
            })?;
            let history = tessera_dashboard::steps::StepHistory {
                name: profile.clone(),
                nights,
                step_night,
                variant,
                factor,
                frames,
                gpu,
                clock_from,
                seed: 38,
            };
            let pool = db::open(&db)?;
            let mut conn = pool.get()?;
            for run in history.runs(&template) {
                regressions::ingest_and_detect(&mut *conn, &run, &Params::default())?;
            }
            println!(
                "stored {nights} {profile} nights into {db}: {} x{factor} from night {step_night} ({})",
                history.variant,
                history.run_id(step_night)
            );
        }
        Command::Replay {
            template,
            nights,
            scenarios,
            seed,
            db,
            verbose,
        } => {
            // Everything that can refuse the replay is asked before a store is made, so a refusal
            // leaves no empty store behind: the number of nights, then the template. The default
            // template is the repository's fixture wherever the command runs from.
            let config = replay::Config {
                nights,
                scenarios,
                seed,
            };
            config.check().map_err(anyhow::Error::msg)?;
            let template = if template.is_relative() && !template.exists() {
                let fixture = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                    .join("..")
                    .join(&template);
                if fixture.exists() {
                    fixture
                } else {
                    template
                }
            } else {
                template
            };
            let template = RunBundle::read_folder(&template).map_err(|e| {
                anyhow::anyhow!("reading the template run {}: {e}", template.display())
            })?;
            let dir = tempfile_dir()?;
            let url = db.unwrap_or_else(|| dir.join("replay.sqlite").display().to_string());
            let pool = db::open(&url)?;
            {
                let mut conn = pool.get()?;
                let runs = conn.query("SELECT COUNT(*) FROM runs", &[])?[0].i64(0)?;
                if runs > 0 {
                    anyhow::bail!("{url} already holds {runs} runs; replay needs an empty store");
                }
            }
            eprintln!(
                "replaying {nights} nights x {} profiles into {}",
                replay::PROFILES.len(),
                pool.describe()
            );
            let report = replay::run(&pool, &template, &config, &Params::default())?;
            for line in report.lines() {
                println!("{line}");
            }
            for d in report.disagreements.iter().take(20) {
                eprintln!("  {d}");
            }
            for u in report.published.broken.iter().take(20) {
                eprintln!("  not answering: {u}");
            }
            for t in report.published.triage_lost.iter().take(20) {
                eprintln!("  triage lost: {t}");
            }
            if verbose {
                for m in &report.misses {
                    eprintln!("  not exact: {m}");
                }
                for f in &report.false_list {
                    eprintln!("  false: {f}");
                }
            }
            let _ = std::fs::remove_dir_all(&dir);
            if !report.meets_targets() {
                anyhow::bail!("the replay missed a target");
            }
        }
        Command::Bundle { folder } => {
            let bundle = RunBundle::read_folder(&folder)?;
            serde_json::to_writer(std::io::stdout().lock(), &bundle.to_upload())?;
        }
    }
    Ok(())
}

/// A fresh folder under the system's temporary directory.
fn tempfile_dir() -> anyhow::Result<PathBuf> {
    let dir = std::env::temp_dir().join(format!(
        "tessera-replay-{}-{}",
        std::process::id(),
        chrono::Utc::now().timestamp_micros()
    ));
    std::fs::create_dir_all(&dir)
        .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", dir.display()))?;
    Ok(dir)
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            for cause in e.chain().skip(1) {
                eprintln!("  caused by: {cause}");
            }
            ExitCode::FAILURE
        }
    }
}
