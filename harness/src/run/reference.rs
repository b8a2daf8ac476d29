//! The reference a scenario's variants are diffed against: rendered first (the ground truth or a
//! separate native render), or taken over from the native variant's own frames.
//!
//! Not here: metrics (`metrics.rs`), which variant is the reference (`scenario.rs`).

pub use super::captured::ReferenceFrames;
use super::frames;
use super::output::first_line;
use crate::gpu::Gpu;
use crate::render::renderer::{Renderer, Unsupported};
use crate::render::scene::SceneGpu;
use crate::scenario::{MetricKind, Reference, Scenario};
use crate::techniques::{self, BuildContext, Target};

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
    let supersample = match scenario.reference {
        Reference::GroundTruth { supersample } => Some(supersample),
        _ => None,
    };
    let target = Target::new(scenario.width, scenario.height, false);
    let built: Result<Box<dyn Renderer>, Unsupported> =
        techniques::reference(supersample, &BuildContext::new(gpu, scene, target));
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
            first_line(&e.to_string())
        ));
    }
    result
}
