//! What a suite's expectations file (`scenarios/<suite>/expectations.toml`) said about one result,
//! and what came of it: the record the harness writes beside the result's status
//! ([`crate::VariantResult::expectation`]) and the dashboard, `tessera expectations update` and
//! the console read.
//!
//! Not for: parsing the expectations file or deciding outcomes (the harness's `expect/`).

use serde::{Deserialize, Serialize};

/// An expectation's label (Mesa's trace lists, wgpu's test expectations).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[serde(rename_all = "kebab-case")]
pub enum Label {
    /// Never run on the matching adapters.
    Skip,
    /// Run only with `tessera run --slow`.
    Slow,
    /// Known to fail: a failure is expected, a pass fails the run ("unexpected pass").
    Broken,
    /// Sometimes fails: a failure is retried once.
    Flaky,
    /// Runs and is checked, but its timings are not measurements (no series of them).
    NoPerf,
}

impl Label {
    pub const ALL: [Label; 5] = [
        Label::Skip,
        Label::Slow,
        Label::Broken,
        Label::Flaky,
        Label::NoPerf,
    ];

    pub fn as_str(self) -> &'static str {
        match self {
            Label::Skip => "skip",
            Label::Slow => "slow",
            Label::Broken => "broken",
            Label::Flaky => "flaky",
            Label::NoPerf => "no-perf",
        }
    }

    pub fn parse(s: &str) -> Option<Label> {
        Label::ALL.into_iter().find(|l| l.as_str() == s)
    }
}

/// What came of a result that an expectation applied to.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[serde(rename_all = "kebab-case")]
pub enum Outcome {
    /// `skip`, or `slow` without `--slow`: not run (status `skipped`).
    NotRun,
    /// `broken` and it failed (a failed status or a failed gate): as expected, the run passes.
    ExpectedFailure,
    /// `broken` and it passed: the run fails until the entry is removed.
    UnexpectedPass,
    /// `flaky`: it failed, and passed when run again.
    PassedOnRetry,
    /// `flaky`: it failed twice; the failure counts.
    FailedOnRetry,
    /// Ran as usual (`no-perf`; `slow` with `--slow`; `flaky` that passed at once; `broken` the
    /// adapter could not run).
    Ran,
}

impl Outcome {
    pub fn as_str(self) -> &'static str {
        match self {
            Outcome::NotRun => "not-run",
            Outcome::ExpectedFailure => "expected-failure",
            Outcome::UnexpectedPass => "unexpected-pass",
            Outcome::PassedOnRetry => "passed-on-retry",
            Outcome::FailedOnRetry => "failed-on-retry",
            Outcome::Ran => "ran",
        }
    }
}

/// The expectation that applied to one result (`results/README.md`, "Expectations").
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Eq)]
pub struct ExpectationRecord {
    pub label: Label,
    pub reason: String,
    /// Where the entry is: `<file>:<line>`.
    pub source: String,
    pub outcome: Outcome,
    /// `flaky` retried: the first attempt's error; `broken` failed: the error or failed gate that
    /// was expected. `None` otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

impl ExpectationRecord {
    /// Whether the result's timings are measurements (not `no-perf`).
    pub fn timings_count(&self) -> bool {
        self.label != Label::NoPerf
    }
}
