//! What one A/B attempt reports: the measures of one variant of a run (the same store keys the
//! dashboard's series use, from `tessera_results::measure::points`) and a digest of its compared
//! frames.
//!
//! Not for: running or comparing (the dashboard's `ab` module compares the samples).

use std::path::Path;

use sha2::{Digest, Sha256};
use tessera_results::queue::Sample;
use tessera_results::{ScenarioResult, VariantResult};

/// A digest of the frames a result compared: SHA-256 over its per-frame digests
/// (`frame_digests`, every measured frame), or for results without them over its saved output
/// frames in frame order. `None` when the result has neither. The one place that says what
/// "the frames changed" reads.
pub fn frames_digest(run_dir: &Path, result: &VariantResult) -> Option<String> {
    // Every compared frame's digest, as the result records them (`frame_digests`, results
    // README "Frame digests"): one hash over them all, so any changed frame changes it.
    if !result.frame_digests.is_empty() {
        let mut h = Sha256::new();
        for (i, d) in result.frame_digests.iter().enumerate() {
            h.update((i as u32).to_le_bytes());
            h.update(d.as_bytes());
        }
        return Some(h.finalize().iter().map(|b| format!("{b:02x}")).collect());
    }
    // Results written before frame digests: the saved output PNGs.
    let mut frames: Vec<_> = result
        .images
        .iter()
        .filter(|i| i.kind == "output")
        .collect();
    if frames.is_empty() {
        return None;
    }
    frames.sort_by_key(|i| i.frame);
    frames.dedup_by_key(|i| i.frame);
    let mut h = Sha256::new();
    for f in frames {
        h.update(f.frame.to_le_bytes());
        match std::fs::read(run_dir.join(&f.path)) {
            Ok(bytes) => h.update(&bytes),
            Err(_) => return None,
        }
    }
    Some(
        h.finalize()
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect::<String>(),
    )
}

/// The sample of `variant` (or of the first variant) among `scenario`'s results; `None` when
/// the scenario has no such variant.
pub fn sample(
    run_dir: &Path,
    scenario: &ScenarioResult,
    variant: Option<&str>,
    arm: usize,
    seq: usize,
) -> Option<Sample> {
    let r = match variant {
        Some(v) => scenario.results.iter().find(|r| r.variant == v)?,
        None => scenario.results.first()?,
    };
    let measures = tessera_results::measure::points(&scenario.results, r)
        .into_iter()
        .map(|p| (p.key, p.value))
        .collect();
    Some(Sample {
        arm,
        seq,
        measures,
        frames_digest: frames_digest(run_dir, r),
    })
}
