//! What rendering captures for evaluation: a reference's frames ([`ReferenceFrames`]) and what a
//! variant's metrics are computed from ([`MetricInputs`]). Both the reference render
//! (`reference.rs`) and a variant's (`frames.rs`, `scenario.rs`) end here; metrics
//! (`evaluate.rs`, `cvvdp.rs`) and images (`images.rs`) read only this.
//!
//! Frames are on the CPU (`frames`, `hdr`) when the CPU needs them (the CPU metrics,
//! ColorVideoVDP, HDR-FLIP's exposure ranges), and on the device (`gpu`) for the GPU metrics;
//! the saved frames' images are always on the CPU (`saved`).
//!
//! Not for: rendering, metrics, saving.

use tessera_metrics::{ExposureRange, HdrImage, Rgb8Image};
use tessera_metrics_gpu::GpuFrame;

use super::motion;
use super::rendered::Rendered;

/// Frames a reference render produced, in measured-frame order.
pub struct ReferenceFrames {
    pub frames: Vec<Rgb8Image>,
    /// Linear frames and their HDR-FLIP exposure ranges, when `flip-hdr` is asked for: the range
    /// of each reference frame is held fixed for every variant diffed against it.
    pub hdr: Vec<HdrImage>,
    pub exposures: Vec<ExposureRange>,
    /// Non-finite pixels per frame (what the scene injected, as the reference renders it).
    pub masks: Vec<Option<Vec<u64>>>,
    /// Non-finite channel values per frame.
    pub non_finite: Vec<u64>,
    /// The frames on the device, when the metrics run there.
    pub gpu: Vec<GpuFrame>,
    /// The saved frames' sRGB images (measured-frame index, image).
    pub saved: Vec<(u32, Rgb8Image)>,
    /// Per measured frame, the digest of its 8-bit output (`Rendered::digests`).
    pub digests: Vec<String>,
}

impl ReferenceFrames {
    /// Takes the frames of a render (its other fields stay).
    pub fn take(r: &mut Rendered) -> Self {
        let hdr = std::mem::take(&mut r.hdr_frames);
        let exposures = hdr
            .iter()
            .map(tessera_metrics::hdr_exposure_range)
            .collect();
        ReferenceFrames {
            frames: std::mem::take(&mut r.frames),
            hdr,
            exposures,
            masks: std::mem::take(&mut r.non_finite_masks),
            non_finite: std::mem::take(&mut r.non_finite_counts),
            gpu: std::mem::take(&mut r.gpu_frames),
            saved: std::mem::take(&mut r.saved),
            digests: std::mem::take(&mut r.digests),
        }
    }
}

/// What a variant's metrics are computed from.
pub struct MetricInputs<'a> {
    pub reference: &'a ReferenceFrames,
    pub test: &'a [Rgb8Image],
    pub test_hdr: &'a [HdrImage],
    /// The test's frames on the device (empty when they were read back instead).
    pub test_gpu: &'a [GpuFrame],
    /// Non-finite channel values per test frame.
    pub test_non_finite: &'a [u64],
    pub motion: &'a Result<Vec<Option<motion::MotionField>>, String>,
}
