//! `tessera-dashboard`: import run folders into the store, serve the dashboard, re-run regression
//! detection, write an upload bundle. Errors print their whole chain; exit code 1 for a failed
//! command, 2 for bad arguments (clap).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use tessera_dashboard::notify::webhook;
use tessera_dashboard::store::ingest::{ingest, Ingested};
use tessera_dashboard::{
    bundle::RunBundle, db, detect::Params, import, regressions, replay, server, synth,
};

const DEFAULT_DB: &str = "tessera-dashboard.sqlite";

#[derive(Parser)]
#[command(version, about = "Results store and dashboard for Tessera runs")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
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
        /// Bearer token that uploads and triage need; without one, writes are refused.
        #[arg(long, env = "TESSERA_DASHBOARD_TOKEN", hide_env_values = true)]
        token: Option<String>,
        /// Largest accepted upload in MiB.
        #[arg(long, default_value_t = 64)]
        max_upload_mib: usize,
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
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Import { folder, db } => {
            let pool = db::open(&db)?;
            let summary = import::import(&pool, &folder, &Params::default())?;
            for (path, err) in &summary.failed {
                eprintln!("error: {}: {err}", path.display());
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
            public_url,
            webhook_url,
            webhook_timeout_s,
            webhook_poll_s,
        } => {
            let pool = db::open(&db)?;
            let mut state = server::AppState::new(pool, token.filter(|t| !t.is_empty()));
            state.max_upload_bytes = max_upload_mib << 20;
            let public_url = public_url.filter(|u| !u.is_empty());
            if let Some(u) = &public_url {
                if !(u.starts_with("http://") || u.starts_with("https://")) {
                    anyhow::bail!("--public-url must start with http:// or https://, not {u:?}");
                }
            }
            state.public_url = public_url.clone();
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
            if state.token.is_none() {
                eprintln!(
                    "note: no --token or TESSERA_DASHBOARD_TOKEN: uploads and triage are refused"
                );
            }
            let rt = tokio::runtime::Runtime::new()?;
            rt.block_on(async move {
                let listener = tokio::net::TcpListener::bind(&listen)
                    .await
                    .map_err(|e| anyhow::anyhow!("cannot listen on {listen}: {e}"))?;
                eprintln!("serving {} on http://{listen}", state.pool.describe());
                axum::serve(listener, server::app(state))
                    .with_graceful_shutdown(async {
                        let _ = tokio::signal::ctrl_c().await;
                    })
                    .await?;
                anyhow::Ok(())
            })?;
        }
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
                let b = synth::run_from(&template, "gen", i, 1.0, 0.01, &mut rng);
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
                let mut series = 0;
                for i in first..first + then_upload {
                    let b = synth::run_from(&small, "gen", i, 1.0, 0.01, &mut rng);
                    let t = std::time::Instant::now();
                    let (ingested, _) =
                        regressions::ingest_and_detect(&mut *conn, &b, &Params::default())?;
                    ms.push(t.elapsed().as_secs_f64() * 1e3);
                    if let Ingested::Stored { series: s, .. } = ingested {
                        series = s.len();
                    }
                }
                ms.sort_by(|a, b| a.total_cmp(b));
                println!(
                    "{then_upload} uploads of {} results ({series} series each): p50 {:.1} ms, p95 {:.1} ms",
                    small.scenarios.iter().map(|s| s.results.len()).sum::<usize>(),
                    ms[ms.len() / 2],
                    ms[(ms.len() - 1) * 95 / 100]
                );
            }
        }
        Command::Replay {
            template,
            nights,
            scenarios,
            seed,
            db,
            verbose,
        } => {
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
            let template = RunBundle::read_folder(&template)?;
            let config = replay::Config {
                nights,
                scenarios,
                seed,
            };
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
