//! Technique `native`: full-resolution forward rendering, the default reference and the baseline
//! of every speedup. Its forward path ([`gpu::Forward`]) also serves `upscale` and the
//! ground-truth reference.

pub mod converged;
pub mod gpu;

use super::definition::{Shader, Target, Technique};
use crate::gpu::Gpu;
use crate::params::Variant;
use crate::render::graph::Plan;
use crate::render::renderer::{Renderer, Unsupported};

pub use gpu::{ground_truth, Forward};

/// The name other parts of the harness know `native` by: the reference and the baseline.
pub const NAME: &str = "native";

pub struct Native;

impl Technique for Native {
    fn name(&self) -> &'static str {
        NAME
    }

    fn summary(&self) -> &'static str {
        "full-resolution forward rendering: the reference and the baseline"
    }

    fn plan(&self, _variant: &Variant, target: Target) -> Plan {
        gpu::forward_graph(target.width, target.height, None)
    }

    fn build(
        &self,
        gpu: &Gpu,
        _variant: &Variant,
        target: Target,
    ) -> Result<Box<dyn Renderer>, Unsupported> {
        Ok(Box::new(Forward::new(
            gpu,
            target.width,
            target.height,
            None,
        )))
    }

    fn shaders(&self) -> Vec<Shader> {
        vec![
            Shader::file("scene.wgsl", crate::render::scene::SCENE_WGSL),
            Shader::file("native/downsample.wgsl", gpu::DOWNSAMPLE_WGSL),
            Shader::file("native/accumulate.wgsl", converged::ACCUMULATE_WGSL),
        ]
    }
}
