//! The reference a scenario's variants are diffed against: rendered first (the ground truth or a
//! separate native render), or taken over from the native variant's own frames.
//!
//! Not here: metrics (`metrics.rs`), which variant is the reference (`scenario.rs`).

pub use super::captured::ReferenceFrames;
use super::frames::{self, Keep};
use super::output::first_line;
use crate::gpu::Gpu;
use crate::render::renderer::{Renderer, Unsupported};
use crate::render::scene::SceneGpu;
use crate::scenario::{MetricKind, Reference, Scenario};
use crate::techniques::{self, BuildContext, Target};

/// Linear frames are kept only for HDR-FLIP, and for `cvvdp` on an HDR display.
pub fn keep_hdr(scenario: &Scenario) -> bool {
    scenario.metrics.contains(&MetricKind::FlipHdr)
        || (scenario.metrics.contains(&MetricKind::Cvvdp) && super::cvvdp::uses_linear(scenario))
}

/// What a render keeps of its frames for the metrics, on the device (`on_gpu`: the GPU metrics)
/// or on the CPU; `reference`: the render is the reference. Without a reference nothing is kept
/// but the saved frames' images. With the GPU metrics the CPU keeps only what the CPU still
/// reads: the 8-bit frames for ColorVideoVDP, linear frames for ColorVideoVDP on an HDR display
/// and, of the reference, for HDR-FLIP's exposure ranges.
pub fn keep(scenario: &Scenario, on_gpu: bool, reference: bool) -> Keep {
    if !scenario.needs_reference() {
        return Keep::default();
    }
    if !on_gpu {
        return Keep::cpu(keep_hdr(scenario));
    }
    let cvvdp = scenario.metrics.contains(&MetricKind::Cvvdp);
    let cvvdp_linear = cvvdp && super::cvvdp::uses_linear(scenario);
    Keep {
        frames: cvvdp,
        hdr: cvvdp_linear || (reference && keep_hdr(scenario)),
        gpu: true,
        gpu_hdr: keep_hdr(scenario),
    }
}

/// Renders the scenario's separate reference (ground truth, or native when the native variant
/// is not in the scenario).
pub fn render(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    scenario: &Scenario,
    on_gpu: bool,
    on_frame: &mut dyn FnMut(),
) -> Result<ReferenceFrames, String> {
    let validation = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let supersample = match scenario.reference {
        Reference::GroundTruth { supersample } => Some(supersample),
        _ => None,
    };
    let target = Target::new(scenario.width, scenario.height, false);
    let cx = BuildContext::new(gpu, scene, target);
    let built: Result<Box<dyn Renderer>, Unsupported> = match scenario.reference {
        Reference::Converged { samples } => techniques::converged_reference(samples, &cx),
        _ => techniques::reference(supersample, &cx),
    };
    let result = match built {
        Err(Unsupported(reason)) => Err(format!("no reference: {reason}")),
        Ok(mut t) => frames::render_keeping(
            gpu,
            scene,
            scenario,
            t.as_mut(),
            keep(scenario, on_gpu, true),
            on_frame,
        )
        .map(|mut r| {
            super::frames::append_hashes(&scenario.name, "(reference)", &r.hashes);
            ReferenceFrames::take(&mut r)
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
