//! Technique `interlace`: temporal interlaced rendering, the checkerboarding that shipped before
//! checkerboards (Rainbow Six Siege's "temporal interlaced rendering" as the depth-based report
//! describes it, `seeds/depth-based-checkerboarding.txt` section 3.3): each frame shades alternate
//! pixel columns at half width; the other columns are the previous output reprojected through the
//! camera and the velocity buffer, clamped to the shaded neighbours. Parameters here, the GPU
//! part in `gpu.rs`, the CPU model in `model.rs`, the shader beside them (`reconstruct.wgsl`).
//!
//! Simpler than the report's account of Siege: no confidence blend back towards the unclamped
//! colour, no colour-coherency or velocity weights, a bilinear history fetch.

pub mod gpu;
pub mod model;

use super::definition::{BuildContext, Definition, FramePattern, Shader, Target};
use crate::gpu::Unsupported;
use crate::render::graph::Plan;
use crate::render::renderer::Renderer;

pub use gpu::{half_view, InterlaceGpu, LastFrame};

crate::options! {
    /// A variant's options, typed.
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub struct Options {
        clamp: bool = flag(
            true,
            "clamp the reprojected colour to the min/max of the six shaded neighbours (left and right columns, rows y-1 to y+1), as Siege clamps to its neighbours; off: the history unclamped",
        ),
        velocity: bool = flag(
            true,
            "full-resolution velocity pass for animated objects; recorded only when the scene has some (otherwise culled: the camera reprojects by depth)",
        ),
        gradient_scale: f32 = float(
            (0.0, false, 1.0),
            1.0,
            "multiplies screen-space derivatives of the half-width render (the ground filter's width): 1 uncorrected (x derivatives twice native's: blurs horizontally), 0.5 matches native in x and halves y",
        ),
    }
}

pub struct Interlace;

impl Definition for Interlace {
    type Options = Options;

    fn name(&self) -> &'static str {
        "interlace"
    }

    /// Even and odd frames shade the even and odd pixel columns.
    fn frames(&self, _options: &Options) -> FramePattern {
        FramePattern::Alternating
    }

    fn summary(&self) -> &'static str {
        "temporal interlaced rendering: alternate pixel columns shaded at half width each frame, the others reprojected from the previous output and clamped to their shaded neighbours"
    }

    fn plan(&self, options: &Options, target: Target) -> Plan {
        gpu::graph(options, target.width, target.height, target.dynamic_scene).0
    }

    fn build(
        &self,
        options: &Options,
        cx: &BuildContext<'_>,
    ) -> Result<Box<dyn Renderer>, Unsupported> {
        let t = cx.target;
        Ok(Box::new(InterlaceGpu::new(
            cx.gpu,
            *options,
            t.width,
            t.height,
            t.dynamic_scene,
        )))
    }

    fn shaders(&self) -> Vec<Shader> {
        vec![Shader::file(
            "interlace/reconstruct.wgsl",
            gpu::RECONSTRUCT_WGSL,
        )]
    }
}
