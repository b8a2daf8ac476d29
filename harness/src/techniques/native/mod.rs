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

pub struct Native;

impl Definition for Native {
    /// `native` has no parameters.
    type Options = ();

    fn name(&self) -> &'static str {
        NAME
    }

    fn summary(&self) -> &'static str {
        "full-resolution forward rendering: the reference and the baseline"
    }

    fn plan(&self, _options: &(), target: Target) -> Plan {
        gpu::forward_graph(target.width, target.height, None)
    }

    fn build(
        &self,
        _options: &(),
        cx: &BuildContext<'_>,
    ) -> Result<Box<dyn Renderer>, Unsupported> {
        let t = cx.target;
        Ok(Box::new(Forward::new(cx.gpu, t.width, t.height, None)))
    }

    fn shaders(&self) -> Vec<Shader> {
        vec![
            Shader::file("scene.wgsl", crate::render::scene::SCENE_WGSL),
            Shader::file("native/downsample.wgsl", gpu::DOWNSAMPLE_WGSL),
            Shader::file("native/accumulate.wgsl", converged::ACCUMULATE_WGSL),
        ]
    }
}
