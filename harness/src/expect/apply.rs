//! What a run does with a suite's expectations: which variants it does not run (`skip`, and
//! `slow` without `--slow`), which failed `flaky` variants it runs again, and the record of each
//! result an entry applied to (expected failure, unexpected pass, passed on retry, ...).
//!
//! Pure decisions over records; running scenarios, and the records of variants not run, are
//! `run/`'s.

use tessera_results::expectation::{ExpectationRecord, Label, Outcome};
use tessera_results::{AdapterInfo, GateLevel, Status, VariantResult};

use super::Expectations;
use crate::scenario::Scenario;
use crate::techniques::Variant;

/// Whether a result failed: a failed status or a failed gate.
pub fn failed(r: &VariantResult) -> bool {
    matches!(r.status, Status::Failed { .. }) || r.gates.iter().any(|g| g.level == GateLevel::Fail)
}

/// What failed, in one line: the error, else the failed gates' messages.
pub fn failure_text(r: &VariantResult) -> Option<String> {
    match &r.status {
        Status::Failed { error } => Some(error.clone()),
        _ => {
            let gates: Vec<&str> = r
                .gates
                .iter()
                .filter(|g| g.level == GateLevel::Fail)
                .map(|g| g.message.as_str())
                .collect();
            (!gates.is_empty()).then(|| gates.join("; "))
        }
    }
}

/// A scenario split by its expectations: what to run, and what is not run and why.
pub struct Split {
    /// The scenario with only the variants to run (all of them without expectations).
    pub to_run: Scenario,
    /// The variants not run, each with its `skipped` status and expectation.
    pub not_run: Vec<NotRun>,
}

/// A variant an expectation holds back: what its result records instead of measurements.
pub struct NotRun {
    pub variant: Variant,
    /// `skipped`, with the expectation's label and reason.
    pub status: Status,
    pub expectation: ExpectationRecord,
}

/// Leaves out the variants an entry says not to run on `adapter`: `skip`, and `slow` unless
/// `slow` (`tessera run --slow`).
pub fn split(
    scenario: &Scenario,
    exp: Option<&Expectations>,
    adapter: &AdapterInfo,
    slow: bool,
) -> Split {
    let mut to_run = scenario.clone();
    let mut not_run = Vec::new();
    if let Some(exp) = exp {
        to_run.variants.retain(|v| {
            let Some(mut e) = exp.find(&scenario.name, &v.name, adapter) else {
                return true;
            };
            // A matching `slow` entry holds the variant back without `--slow`, whatever else
            // matches (a `skip` always does).
            if e.label != Label::Skip && !slow {
                if let Some(s) = exp
                    .matching(&scenario.name, &v.name, adapter)
                    .into_iter()
                    .find(|x| x.label == Label::Slow)
                {
                    e = s;
                }
            }
            let run = match e.label {
                Label::Skip => false,
                Label::Slow => slow,
                _ => true,
            };
            if !run {
                let why = match e.label {
                    Label::Slow => "expectation `slow` (run with --slow)",
                    _ => "expectation `skip`",
                };
                not_run.push(NotRun {
                    variant: v.clone(),
                    status: Status::Skipped {
                        reason: format!("{why}: {}", e.reason),
                    },
                    expectation: ExpectationRecord {
                        label: e.label,
                        reason: e.reason.clone(),
                        source: exp.source(e),
                        outcome: Outcome::NotRun,
                        error: None,
                    },
                });
            }
            run
        });
    }
    Split { to_run, not_run }
}

/// The variants of `results` labelled `flaky` that failed: to be run once more.
pub fn to_retry(
    scenario: &str,
    results: &[VariantResult],
    exp: Option<&Expectations>,
    adapter: &AdapterInfo,
) -> Vec<String> {
    let Some(exp) = exp else {
        return Vec::new();
    };
    results
        .iter()
        .filter(|r| failed(r))
        .filter(|r| {
            exp.find(scenario, &r.variant, adapter)
                .is_some_and(|e| e.label == Label::Flaky)
        })
        .map(|r| r.variant.clone())
        .collect()
}

/// Records on each result the entry that applied to it and what came of it. `first_errors`:
/// the first attempt's failure of each `flaky` variant that was run again.
pub fn judge(
    scenario: &str,
    results: &mut [VariantResult],
    exp: Option<&Expectations>,
    adapter: &AdapterInfo,
    first_errors: &[(String, String)],
) {
    let Some(exp) = exp else {
        return;
    };
    for r in results.iter_mut().filter(|r| r.expectation.is_none()) {
        let Some(e) = exp.find(scenario, &r.variant, adapter) else {
            continue;
        };
        let skipped = matches!(r.status, Status::Skipped { .. });
        let retried = first_errors.iter().find(|(v, _)| *v == r.variant);
        let (outcome, error) = match e.label {
            Label::Broken if skipped => (Outcome::Ran, None),
            Label::Broken if failed(r) => (Outcome::ExpectedFailure, failure_text(r)),
            Label::Broken => (Outcome::UnexpectedPass, None),
            Label::Flaky => match retried {
                Some((_, first)) if failed(r) => (Outcome::FailedOnRetry, Some(first.clone())),
                Some((_, first)) => (Outcome::PassedOnRetry, Some(first.clone())),
                None => (Outcome::Ran, None),
            },
            _ => (Outcome::Ran, None),
        };
        r.expectation = Some(ExpectationRecord {
            label: e.label,
            reason: e.reason.clone(),
            source: exp.source(e),
            outcome,
            error,
        });
    }
}

/// Whether a result's failure is what its expectation said (it does not fail the run).
pub fn expected_failure(r: &VariantResult) -> bool {
    r.expectation
        .as_ref()
        .is_some_and(|e| e.outcome == Outcome::ExpectedFailure)
}

/// Whether a result passed against a `broken` entry (it fails the run).
pub fn unexpected_pass(r: &VariantResult) -> bool {
    r.expectation
        .as_ref()
        .is_some_and(|e| e.outcome == Outcome::UnexpectedPass)
}

/// Puts `extra` results into `results` in the scenario's declaration order.
pub fn merge_in_order(
    scenario: &Scenario,
    results: &mut Vec<VariantResult>,
    extra: Vec<VariantResult>,
) {
    results.extend(extra);
    results.sort_by_key(|r| scenario.declared_position(&r.variant));
}
