//! The reference a scenario's variants are diffed against: rendered first (the ground truth or a
//! separate native render), or taken over from the native variant's own frames.
//!
//! Not here: metrics (`metrics.rs`), which variant is the reference (`scenario.rs`).

use tessera_metrics::{ExposureRange, HdrImage, Rgb8Image};

use super::frames;
use crate::gpu::Gpu;
use crate::params::Variant;
use crate::render::renderer::{Renderer, Unsupported};
use crate::render::scene::SceneGpu;
use crate::scenario::{MetricKind, Reference, Scenario};
use crate::techniques::{self, native, Target};

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

/// Linear frames are kept only for HDR-FLIP.
/// Linear frames are kept only for HDR-FLIP, and for `cvvdp` on an HDR display.
pub fn keep_hdr(scenario: &Scenario) -> bool {
    scenario.metrics.contains(&MetricKind::FlipHdr)
        || (scenario.metrics.contains(&MetricKind::Cvvdp) && super::cvvdp::uses_linear(scenario))
}

/// Renders the scenario's separate reference (ground truth, or native when the native variant
/// is not in the scenario).
pub fn render(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    scenario: &Scenario,
    on_frame: &mut dyn FnMut(),
) -> Result<ReferenceFrames, String> {
    let validation = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let built: Result<Box<dyn Renderer>, Unsupported> = match scenario.reference {
        Reference::GroundTruth { supersample } => {
            native::ground_truth(gpu, scenario.width, scenario.height, supersample)
        }
        Reference::Converged { samples } => {
            native::converged::converged(gpu, scenario.width, scenario.height, samples)
        }
        _ => techniques::build(
            gpu,
            &Variant::with_defaults(&native::Native),
            Target {
                width: scenario.width,
                height: scenario.height,
                dynamic_scene: false,
            },
        ),
    };
    let result = match built {
        Err(Unsupported(reason)) => Err(format!("no reference: {reason}")),
        Ok(mut t) => frames::render(
            gpu,
            scene,
            scenario,
            t.as_mut(),
            true,
            keep_hdr(scenario),
            on_frame,
        )
        .map(|r| {
            super::frames::append_hashes(&scenario.name, "(reference)", &r.hashes);
            ReferenceFrames::new(r.frames, r.hdr_frames, r.non_finite_masks)
        })
        .map_err(|e| format!("reference render failed: {e}")),
    };
    if let Some(e) = pollster::block_on(validation.pop()) {
        return Err(format!(
            "reference render failed: GPU error: {}",
            super::scenario::first_line(&e.to_string())
        ));
    }
    result
}
