//! Reporting, the last stage of a run (render, evaluate, save, report): one [`Report`] interface
//! that the run loop calls as the run starts, after each scenario and at the end, and its
//! outputs: the run folder's files ([`Files`]: `run.json`, each scenario's JSON, `results.csv`,
//! rewritten after every scenario so an interrupted run keeps what it completed), the console
//! ([`Console`]: the scenario table on stdout, hints on stderr) and JUnit XML ([`JUnit`]).
//! Each output formats through `output.rs` / `console.rs` (pure); this module only decides when.
//!
//! Not for: rendering, metrics, records.

use std::path::PathBuf;

use tessera_results::{RunInfo, ScenarioResult};

use super::console;
use super::output::{self, write_atomic, WriteError};

/// An output of a run.
pub trait Report {
    /// The run has started (`run.status` is `running`).
    fn started(&mut self, _run: &RunInfo) -> Result<(), WriteError> {
        Ok(())
    }

    /// A scenario has finished; `results` holds every scenario so far, the last one new.
    fn scenario(&mut self, _run: &RunInfo, _results: &[ScenarioResult]) -> Result<(), WriteError> {
        Ok(())
    }

    /// The run has finished (`run.status` is `complete`).
    fn finished(&mut self, _run: &RunInfo, _results: &[ScenarioResult]) -> Result<(), WriteError> {
        Ok(())
    }
}

/// The run folder: `run.json` at the start and the end, each scenario's JSON and the whole
/// `results.csv` after each scenario.
pub struct Files {
    pub run_dir: PathBuf,
}

impl Report for Files {
    fn started(&mut self, run: &RunInfo) -> Result<(), WriteError> {
        write_atomic(&self.run_dir.join("run.json"), &output::run_json(run))
    }

    fn scenario(&mut self, run: &RunInfo, results: &[ScenarioResult]) -> Result<(), WriteError> {
        let Some(last) = results.last() else {
            return Ok(());
        };
        write_atomic(
            &self
                .run_dir
                .join("scenarios")
                .join(format!("{}.json", last.scenario)),
            &output::scenario_json(last),
        )?;
        write_atomic(
            &self.run_dir.join("results.csv"),
            &output::results_csv(run, results),
        )
    }

    fn finished(&mut self, run: &RunInfo, _results: &[ScenarioResult]) -> Result<(), WriteError> {
        write_atomic(&self.run_dir.join("run.json"), &output::run_json(run))
    }
}

/// The console: each scenario's table on stdout and its throttling hints on stderr, printed
/// around the progress bar.
pub struct Console<'a> {
    pub bar: &'a indicatif::ProgressBar,
}

impl Report for Console<'_> {
    fn scenario(&mut self, _run: &RunInfo, results: &[ScenarioResult]) -> Result<(), WriteError> {
        if let Some(last) = results.last() {
            self.bar.suspend(|| {
                print!("{}", console::scenario_table(last));
                for hint in console::throttle_hints(last) {
                    eprintln!("{hint}");
                }
                for r in &last.results {
                    let c = r.convergence.as_ref();
                    if let Some(h) =
                        c.and_then(|c| super::convergence::hint(&last.scenario, &r.variant, c))
                    {
                        eprintln!("{h}");
                    }
                }
            });
        }
        Ok(())
    }
}

/// JUnit XML of the whole run, written at the end.
pub struct JUnit {
    pub path: PathBuf,
}

impl Report for JUnit {
    fn finished(&mut self, run: &RunInfo, results: &[ScenarioResult]) -> Result<(), WriteError> {
        write_atomic(&self.path, &output::junit(run, results))
    }
}
