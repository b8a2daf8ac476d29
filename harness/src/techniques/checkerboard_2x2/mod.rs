//! Technique `checkerboard-2x2`: the depth-based report's 2x2 checkerboarding
//! (`seeds/depth-based-checkerboarding.txt`, sections 5.3.1 to 5.3.8): its parameters and options
//! here, the GPU part in `gpu.rs`, the CPU model of the reconstitution in `model.rs`, shaders
//! beside them (`*.wgsl`).
//!
//! Defaults are the report's final implementation (sections 5.3.4 to 5.3.8): blended clamping
//! with motion coherency, its small-motion constant and its blend limits. Motion is in pixels per
//! frame; depth differences are in linear depth normalised to [0, 1] between the camera's near
//! and far planes (section 5.3.7).

pub mod gpu;
pub mod model;

use super::definition::{BuildContext, Definition, FramePattern, Shader, Target};
use crate::gpu::Unsupported;
use crate::render::graph::Plan;
use crate::render::renderer::Renderer;

pub use gpu::{
    graph, workgroups, Bindings, Checkerboard2x2Gpu, FrameParams, LastFrame, Reconstitution,
};

crate::choice! {
    /// The report's clamp modes (5.3.3 to 5.3.7).
    pub enum Clamp {
        None = "none",
        Uniform = "uniform",
        Conditional = "conditional",
        Blended = "blended",
    }
}

impl Clamp {
    /// The reconstitution shader's code (`mode.x`).
    pub fn code(self) -> u32 {
        match self {
            Clamp::None => 0,
            Clamp::Uniform => 1,
            Clamp::Conditional => 2,
            Clamp::Blended => 3,
        }
    }

    /// Conditional and blended clamp only where the pixel moves (5.3.5).
    pub fn is_conditional(self) -> bool {
        matches!(self, Clamp::Conditional | Clamp::Blended)
    }
}

crate::choice! {
    /// How each frame's depth buffers get their mask (5.3.2, 5.3.6).
    pub enum Precondition {
        Copy = "copy",
        Draw = "draw",
    }
}

crate::options! {
    /// Reconstitution options (the variant's parameters).
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub struct Options {
        clamp: Clamp = choice(
            Clamp::Blended,
            "the reprojected colour against the range (min/max) of the masked pixel's two shaded direct neighbours: never clamped (report 5.3.3), always (5.3.4), only where the pixel moves more than `motion_threshold` (5.3.5), or conditional with the clamp blended back by depth difference (5.3.7, the report's final version)",
        ),
        /// Pixels per frame; conditional and blended clamp only above it (5.3.5).
        motion_threshold: f32 = float(
            (0.0, true, 1.0e9),
            1.0e-7,
            "pixels per frame; `conditional` and `blended` do not clamp a pixel moving less than this (the report's 0.0000001: only rounding-level motion escapes the clamp)",
        ),
        /// Linear depth differences in [0, 1] (5.3.7).
        blend_min: f32 = float(
            (0.0, true, 1.0),
            0.005,
            "`blended`: linear depth difference (normalised to [0, 1] between the camera's `near` and `far`) between the reprojected depth and a neighbour's below which that direction keeps the reprojected colour (the report's minimum blend difference); less than `blend_max`",
        ),
        blend_max: f32 = float(
            (0.0, false, 1.0),
            0.1,
            "`blended`: the clamp weight of a direction is its difference / `blend_max`, capped at 1 (the report's maximum blend difference); the two directions' blends are averaged",
        ),
        precondition: Precondition = choice(
            Precondition::Copy,
            "how the scene and motion depth buffers get this frame's block mask: `copy` (the report's 5.3.6: \"depth creation is moved to application startup\"), a copy of a whole pre-conditioned standby buffer drawn once at start-up; `draw`, a depth-only full-screen pass each frame that clears and writes the masked blocks' nearest depth (5.3.2's mask pass; no standby buffers). Same buffers, same frames. On an H200 at 1920x1080 the copy takes 0.154 ms, the `frag_depth` pass 0.302 ms, the mask as two triangles per block 2.17 ms",
        ),
        motion_coherency: bool = flag(
            true,
            "`conditional` and `blended`: also clamp where a shaded neighbour's previous motion differs from the pixel's motion by more than `motion_threshold` (5.3.8); keeps the motion history (otherwise not allocated)",
        ),
    }
}

impl Options {
    /// The blended clamp compares the reprojected depth with the neighbours' (5.3.7).
    pub fn reads_depth_history(&self) -> bool {
        self.clamp == Clamp::Blended
    }

    /// Motion coherency only matters where clamping is conditional (5.3.8).
    pub fn reads_motion_history(&self) -> bool {
        self.motion_coherency && self.clamp.is_conditional()
    }
}

pub struct Checkerboard2x2;

impl Definition for Checkerboard2x2 {
    type Options = Options;

    fn name(&self) -> &'static str {
        "checkerboard-2x2"
    }

    /// Even and odd frames shade the two halves of the 2x2 block mask.
    fn frames(&self, _options: &Options) -> FramePattern {
        FramePattern::Alternating
    }

    fn summary(&self) -> &'static str {
        "the depth-based report's 2x2 checkerboarding: masked blocks rejected by a pre-conditioned depth buffer, reconstituted by motion reprojection"
    }

    fn check(&self, options: &Options) -> Result<(), String> {
        let (min, max) = (options.blend_min, options.blend_max);
        if min >= max {
            return Err(format!(
                "blend_min ({min}) must be less than blend_max ({max}): depth differences between them blend the clamp in"
            ));
        }
        Ok(())
    }

    /// The report's baseline renders the same motion pass (section 6: "both have a motion
    /// pass"): `native` with `motion_pass = true`, where the scenario has it.
    fn baseline(&self, _options: &Options) -> Option<&'static str> {
        Some(super::native::WITH_MOTION_PASS)
    }

    fn plan(&self, options: &Options, target: Target) -> Plan {
        graph(target.width, target.height, options)
            .plan()
            .expect("built-in graphs are well formed")
    }

    fn build(
        &self,
        options: &Options,
        cx: &BuildContext<'_>,
    ) -> Result<Box<dyn Renderer>, Unsupported> {
        let t = cx.target;
        Ok(Box::new(Checkerboard2x2Gpu::with_options(
            cx.gpu, *options, t.width, t.height,
        )))
    }

    fn shaders(&self) -> Vec<Shader> {
        vec![
            Shader::file("checkerboard_2x2/mask.wgsl", gpu::MASK_WGSL),
            Shader::file("checkerboard_2x2/reconstitute.wgsl", gpu::RECONSTITUTE_WGSL),
        ]
    }
}
