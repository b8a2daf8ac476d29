//! Technique `native`: full-resolution forward rendering, the default reference and the baseline
//! of every speedup. Its forward path ([`gpu::Forward`]) also serves `upscale` and the
//! ground-truth reference.

pub mod converged;
pub mod gpu;

use super::definition::{BuildContext, Definition, Shader, Target};
use crate::render::graph::Plan;
use crate::render::renderer::{Renderer, Unsupported};

pub use gpu::{ground_truth, Forward};

/// The name other parts of the harness know `native` by: the reference and the baseline.
pub const NAME: &str = "native";

/// The variant `native` with the motion pass, by name: checkerboard-2x2's baseline (the
/// depth-based report's, section 6), found by that name where a scenario has it.
pub const WITH_MOTION_PASS: &str = "native[motion_pass=true]";

crate::options! {
    /// A variant's options, typed.
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub struct Options {
        motion_pass: bool = flag(
            false,
            "also render the full-resolution motion pass (the scene's velocity pipeline, as checkerboard-2x2 draws it on its inverse mask), whose output leaves the frame for other effects (motion blur, TAA): the depth-based report's baseline (section 6: standard rendering and 2x2 checkerboarding both have a motion pass), so that 2x2's speedup is not charged for a pass its baseline also pays",
        ),
    }
}

pub struct Native;

impl Definition for Native {
    type Options = Options;

    fn name(&self) -> &'static str {
        NAME
    }

    fn summary(&self) -> &'static str {
        "full-resolution forward rendering: the reference and the baseline"
    }

    fn plan(&self, options: &Options, target: Target) -> Plan {
        if options.motion_pass {
            gpu::forward_graph_with_motion(target.width, target.height)
        } else {
            gpu::forward_graph(target.width, target.height, None)
        }
    }

    fn build(
        &self,
        options: &Options,
        cx: &BuildContext<'_>,
    ) -> Result<Box<dyn Renderer>, Unsupported> {
        let t = cx.target;
        let forward = Forward::new(cx.gpu, t.width, t.height, None);
        Ok(Box::new(if options.motion_pass {
            forward.with_motion_pass(cx.gpu)
        } else {
            forward
        }))
    }

    fn shaders(&self) -> Vec<Shader> {
        vec![
            Shader::file("scene.wgsl", crate::render::scene::SCENE_WGSL),
            Shader::file("native/downsample.wgsl", gpu::DOWNSAMPLE_WGSL),
            Shader::file("native/accumulate.wgsl", converged::ACCUMULATE_WGSL),
        ]
    }
}
