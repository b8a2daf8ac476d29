//! Technique `interlace`: temporal interlaced rendering, the checkerboarding that shipped before
//! checkerboards (Rainbow Six Siege's "temporal interlaced rendering" as the depth-based report
//! describes it, `seeds/depth-based-checkerboarding.txt` section 3.3). The sampling is offset row
//! by row so that each frame shades half the pixels in a checkerboard and every unshaded pixel has four shaded orthogonal neighbours; an
//! unshaded pixel takes its motion from the neighbour closest to the camera, the history there is
//! clamped to the neighbours, blended back towards the unclamped value by depth confidence, and
//! weighted against the spatial fill by colour coherency and velocity (`gpu.rs`, `model.rs`,
//! `reconstruct.wgsl`). The scheme Tessera had before issue 26 (whole columns alternating, the
//! history clamped to six neighbours, no confidence or weights; `pattern = "columns"`) was retired
//! with issue 39: it was kept to compare, and it was a second complete technique in this folder.
//! Its last measure is in `scenarios/quality/static.toml`'s notes (29.63 dB against 40.58 on
//! lavapipe).
//!
//! The report gives the steps, not their formulas: the confidence ramp, the coherency measure
//! and the way the two weights combine are this module's reading, documented in the shader.

pub mod gpu;
pub mod model;

use super::definition::{BuildContext, Definition, FramePattern, Shader, Target};
use crate::gpu::Unsupported;
use crate::render::graph::Plan;
use crate::render::renderer::Renderer;

pub use gpu::{rows_view, InterlaceGpu, LastFrame};

crate::options! {
    /// A variant's options, typed.
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub struct Options {
        clamp: bool = flag(
            true,
            "clamp the reprojected colour to the min/max of the four orthogonal shaded neighbours, then blend back towards the unclamped value by depth confidence; off: the history unclamped",
        ),
        depth_tolerance: f32 = float(
            (0.0, false, 1.0e3),
            0.05,
            "how far (relative view depth) the previous depth at the reprojected position may lie outside the neighbours' depth range before the confidence reaches 0 (the clamped history); inside the range the confidence is 1 (the unclamped history)",
        ),
        coherency: f32 = float(
            (0.0, false, 1.0e3),
            0.1,
            "relative luma difference of the more coherent neighbour pair at which the history keeps its full weight in motion; below it a moving pixel leans towards the spatial fill",
        ),
        velocity_scale: f32 = float(
            (0.0, false, 1.0e6),
            4.0,
            "motion in pixels per frame at which the velocity weight is full (over coherent neighbours: the spatial fill); at rest the history",
        ),
        velocity: bool = flag(
            true,
            "object motion from the shared motion provider (`render/velocity.rs`): the dynamic objects only, at full resolution, a static object in front told by depth; recorded only when the scene has animated objects (otherwise culled: the camera reprojects by depth)",
        ),
        gradient_scale: f32 = float(
            (0.0, false, 1.0),
            0.5,
            "multiplies screen-space derivatives of the reduced render (the ground filter's width): it renders at quarter resolution, so 0.5 matches native in x and y (1: uncorrected, blurs)",
        ),
    }
}

pub struct Interlace;

impl Definition for Interlace {
    type Options = Options;

    fn name(&self) -> &'static str {
        "interlace"
    }

    /// Even and odd frames shade the two checkerboard parities.
    fn frames(&self, _options: &Options) -> FramePattern {
        FramePattern::Alternating
    }

    fn summary(&self) -> &'static str {
        "temporal interlaced rendering (Rainbow Six Siege): half the pixels shaded each frame in a checkerboard, the others reprojected by their nearest neighbour's motion, clamped to their four shaded neighbours, blended back by depth confidence and weighted by colour coherency and velocity"
    }

    fn plan(&self, options: &Options, target: Target) -> Plan {
        let (w, h, dynamic) = (target.width, target.height, target.dynamic_scene);
        gpu::graph(options, w, h, dynamic).0
    }

    fn build(
        &self,
        options: &Options,
        cx: &BuildContext<'_>,
    ) -> Result<Box<dyn Renderer>, Unsupported> {
        let t = cx.target;
        let (w, h, dynamic) = (t.width, t.height, t.dynamic_scene);
        Ok(Box::new(InterlaceGpu::new(cx.gpu, *options, w, h, dynamic)))
    }

    fn shaders(&self) -> Vec<Shader> {
        vec![Shader::file(
            "interlace/reconstruct.wgsl",
            gpu::RECONSTRUCT_WGSL,
        )]
    }
}
