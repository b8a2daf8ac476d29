//! `tessera-dashboard`: import run folders into the store, serve the dashboard, re-run regression
//! detection, write an upload bundle. Errors print their whole chain; exit code 1 for a failed
//! command, 2 for bad arguments (clap).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use tessera_dashboard::store::ingest::{ingest, Ingested};
use tessera_dashboard::{
    bundle::RunBundle, db, detect::Params, import, regressions, server, synth,
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
    },
    /// Re-run regression detection on every stored series.
    Detect {
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
        } => {
            let pool = db::open(&db)?;
            let mut state = server::AppState::new(pool, token.filter(|t| !t.is_empty()));
            state.max_upload_bytes = max_upload_mib << 20;
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
            let added = regressions::update(&mut *conn, &series, &Params::default())?;
            println!("checked {} series; {added} new change points", series.len());
        }
        Command::Generate {
            template,
            runs,
            scenarios,
            prefix,
            db,
        } => {
            let pool = db::open(&db)?;
            let template = synth::widen(&RunBundle::read_folder(&template)?, scenarios);
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
        }
        Command::Bundle { folder } => {
            let bundle = RunBundle::read_folder(&folder)?;
            serde_json::to_writer(std::io::stdout().lock(), &bundle.to_upload())?;
        }
    }
    Ok(())
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
