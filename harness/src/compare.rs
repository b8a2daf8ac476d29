//! `tessera compare <run-a> <run-b>`: the Markdown a pull request would show, comparing run B
//! (new) against run A (base), and whether B regressed (exit 1).
//!
//! The comparison is `tessera_results::compare`, the engine the dashboard's compare page and API
//! use too; its rules are written down once, in `results/COMPARISON.md` (time: a Mann-Whitney U
//! test with a Hodges-Lehmann shift and its 99% interval, "too few frames" where the sample
//! sizes cannot reach p < 0.01, baselines found per variant, metrics by their measure's
//! direction, a baseline's change counted once, on the baseline). This module only reads the two
//! folders ([`load`]) and hands them over. Not for: storing history or change-point detection
//! (that is the dashboard's job, over many runs).

pub mod load;

pub use load::{load_run, LoadError, Run};
pub use tessera_results::compare::{markdown, Comparison, Options, Verdict};

/// Compares run `b` (new) against run `a` (base).
pub fn compare(a: &Run, b: &Run, opts: &Options) -> Comparison {
    tessera_results::compare::compare(a.into(), b.into(), opts)
}

/// The Markdown comparison of run `b` against run `a`.
pub fn to_markdown(a: &Run, b: &Run, opts: &Options) -> String {
    markdown::render(&compare(a, b, opts))
}
