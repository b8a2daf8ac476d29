//! The reference a scenario's variants are diffed against: rendered first (the ground truth or a
//! separate native render), or taken over from the native variant's own frames.
//!
//! Not here: metrics (`metrics.rs`), which variant is the reference (`scenario.rs`).

pub use super::captured::ReferenceFrames;
use super::frames;
use super::plan::Plan;
use super::rendered;
use super::sequence::in_error_scope;
use crate::gpu::Gpu;
use crate::render::renderer::{Renderer, Unsupported};
use crate::render::scene::SceneGpu;
use crate::scenario::Reference;
use crate::techniques::{self, BuildContext, Target};

/// Renders the scenario's separate reference (ground truth, or native when the native variant
/// is not in the scenario).
pub fn render(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    plan: &Plan<'_>,
    on_frame: &mut dyn FnMut(),
) -> Result<ReferenceFrames, String> {
    let scenario = plan.scenario;
    let rendered = in_error_scope(gpu, || {
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
        match built {
            Err(Unsupported(reason)) => Err(format!("no reference: {reason}")),
            Ok(mut t) => {
                // The ground truth, converged or supersampled, keeps no history: its measured
                // frames alone, once. (A motion-blurred capture and a native reference go through
                // the whole sequence.)
                let history_free = matches!(
                    scenario.reference,
                    Reference::GroundTruth { .. } | Reference::Converged { .. }
                ) && !scenario.motion_blur;
                let keep = plan.keep(true);
                let rendered = if history_free {
                    frames::render_history_free(gpu, scene, scenario, t.as_mut(), keep, on_frame)
                } else {
                    frames::render_keeping(gpu, scene, scenario, t.as_mut(), keep, on_frame)
                };
                rendered
                    .map(|mut r| {
                        rendered::append_hashes(&scenario.name, "(reference)", &r.hashes);
                        ReferenceFrames::take(&mut r)
                    })
                    .map_err(|e| format!("reference render failed: {e}"))
            }
        }
    });
    rendered.unwrap_or_else(|e| Err(format!("reference render failed: {e}")))
}
