//! `tessera compare <run-a> <run-b>`: the Markdown a pull request would show, comparing run B
//! (new) against run A (base), and whether B regressed.
//!
//! Rules (also in `ci/README.md`):
//!
//! - **GPU time.** Per variant, the per-frame GPU times are the sums over passes of each measured
//!   frame's raw sample (`passes[].samples_ms`). B is **slower** (a regression) or **faster** when
//!   both hold: a two-sided Mann-Whitney U test on the two sets of frames gives p < 0.01 (so each
//!   run's own spread counts: a few noisy frames cannot make a verdict), and the medians differ by
//!   at least `--threshold-pct` (5% by default; a real but tiny change is not worth a red mark).
//!   Otherwise the change is **within noise**. The test is exact for up to 20 frames per run
//!   without ties, else the normal approximation with tie correction; with 4 frames or fewer per
//!   run no p-value reaches 0.01, so short runs never produce a time verdict.
//! - **Different adapters or drivers** (name, backend, driver or driver info differ): times are
//!   not compared in milliseconds. Each frame is divided by the median of that run's `native`
//!   variant in the same scenario and the same test runs on those relative costs, so a verdict
//!   means the speedup against native changed; `native` itself is the baseline.
//! - **CPU adapters** (`device_type` `cpu`, i.e. lavapipe, in either run): timings measure CPU
//!   work and the machine's load, so time verdicts are shown but never count as regressions.
//! - **Quality.** PSNR, SSIM and FLIP aggregates got **worse** or **better** when they moved by more
//!   than 0.1 dB, 0.001 and 0.001 in that direction (references are rendered in the same run, so
//!   these are not noisy; the tolerance absorbs rounding). Infinite PSNR (identical frames) is
//!   larger than any finite value. A worse metric is a regression.
//! - **Status.** A variant that failed (or failed a gate) in B but not in A is a regression; one
//!   that was ok in A and is skipped in B is a regression on the same adapter (on another adapter
//!   a skip is what that adapter supports) — both are shown in the status column. Scenarios and
//!   variants present in one run only are listed, never a regression.
//!
//! The analysis ([`analysis`]) and the Markdown ([`markdown`]) are pure functions of the records;
//! only [`load`] touches the disk. Not for: storing history or change-point detection (that is the
//! dashboard's job, over many runs).

pub mod analysis;
pub mod load;
pub mod markdown;
/// The significance test, shared with the dashboard through `tessera-results`.
pub use tessera_results::stats;

pub use analysis::{compare, Comparison, Options};
pub use load::{load_run, LoadError, Run};

/// The Markdown comparison of run `b` against run `a`; see the module doc for the rules.
pub fn to_markdown(a: &Run, b: &Run, opts: &Options) -> String {
    markdown::render(&compare(a, b, opts))
}
