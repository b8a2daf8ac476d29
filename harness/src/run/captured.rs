//! What rendering captures for evaluation: a reference's frames ([`ReferenceFrames`]) and what a
//! variant's metrics are computed from ([`MetricInputs`]). Both the reference render
//! (`reference.rs`) and a variant's (`frames.rs`, `scenario.rs`) end here; metrics
//! (`metrics.rs`, `cvvdp.rs`) and images (`images.rs`) read only this.
//!
//! Not for: rendering, metrics, saving.

use tessera_metrics::{ExposureRange, HdrImage, Rgb8Image};

use super::motion;

/// Frames a reference render produced, in measured-frame order.
pub struct ReferenceFrames {
    pub frames: Vec<Rgb8Image>,
    /// Linear frames and their HDR-FLIP exposure ranges, when `flip-hdr` is asked for: the range
    /// of each reference frame is held fixed for every variant diffed against it.
    pub hdr: Vec<HdrImage>,
    pub exposures: Vec<ExposureRange>,
    /// Non-finite pixels per frame (what the scene injected, as the reference renders it).
    pub masks: Vec<Option<Vec<u64>>>,
}

impl ReferenceFrames {
    pub fn new(frames: Vec<Rgb8Image>, hdr: Vec<HdrImage>, masks: Vec<Option<Vec<u64>>>) -> Self {
        let exposures = hdr
            .iter()
            .map(tessera_metrics::hdr_exposure_range)
            .collect();
        ReferenceFrames {
            frames,
            hdr,
            exposures,
            masks,
        }
    }
}

/// What a variant's metrics are computed from.
pub struct MetricInputs<'a> {
    pub reference: &'a ReferenceFrames,
    pub test: &'a [Rgb8Image],
    pub test_hdr: &'a [HdrImage],
    pub motion: &'a Result<Vec<Option<motion::MotionField>>, String>,
}
