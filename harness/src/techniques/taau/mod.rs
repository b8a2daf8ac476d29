//! Technique `taau`: temporal anti-aliasing with upsampling, from the published design (Yang, Liu,
//! Salvi, "A Survey of Temporal Antialiasing Techniques", Eurographics STAR 2020) with Bevy's TAA
//! resolve as a readable reference: the projection jittered by Halton (2, 3) (`jitter.rs`), the
//! previous output reprojected by the cameras and a velocity pass, fetched with Catmull-Rom,
//! rectified by YCoCg variance clipping where anything moved, rejected on disocclusion and cuts,
//! accumulated as a running mean; optionally sharpened by FSR 1's RCAS. `scale = 1` is native
//! TAA (what shipped engines call "native + TAA"), `scale < 1` upsamples. Parameters here, the
//! GPU part in `gpu.rs`, the CPU model in `model.rs`, the shader in `resolve.wgsl`.
//!
//! Requirements (as Bevy states them for its TAA): the scene pass jittered (`View::ndc_offset`),
//! depth, and motion vectors: the camera's from depth, dynamic objects' from the velocity pass,
//! recorded only when the scene has animated objects.

pub mod gpu;
pub mod jitter;
pub mod model;

use super::definition::{BuildContext, Definition, Shader, Target};
use crate::gpu::Unsupported;
use crate::render::graph::Plan;
use crate::render::renderer::Renderer;

pub use gpu::{LastFrame, TaauGpu, RESOLVE_WGSL};

crate::options! {
    /// A variant's options, typed; what the passes take is derived from them
    /// ([`Options::phases`], [`Options::gradient_scale`], [`Options::rcas_sharpness`]).
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub struct Options {
        scale: f64 = float(
            (0.25, true, 1.0),
            1.0,
            "render width and height as a fraction of the output resolution: 1 is native-resolution TAA, below 1 upsamples",
        ),
        phases: f64 = float(
            (0.0, true, 1024.0),
            0.0,
            "a whole number: jitter phases of the Halton (2, 3) sequence before it repeats; 0: max(32, 8 x (1/scale)^2) (DLSS's guide asks for 8 x ratio^2; 32 matches the converged reference)",
        ),
        clip_gamma: f32 = float(
            (0.0, false, 8.0),
            1.0,
            "variance clipping box: mean +- gamma x sigma of the 3x3 render neighbourhood in YCoCg (Salvi: 1)",
        ),
        clip_still: bool = flag(
            false,
            "clip the history also where nothing moved (still camera, static object, no disocclusion); off: a still pixel keeps its history, so thin geometry that some jitter phases miss converges instead of flickering",
        ),
        depth_tolerance: f32 = float(
            (0.0, true, 1.0),
            0.05,
            "disocclusion: the history is dropped when the sample's previous reversed-Z depth differs from every one of the 3x3 previous depths around it by more than this fraction of the larger",
        ),
        max_weight: f32 = float(
            (1.0, true, 4096.0),
            32.0,
            "cap of the accumulated sample weight: the running mean becomes an exponential one with factor 1/(1 + max_weight)",
        ),
        moving_weight: f32 = float(
            (0.0, true, 4096.0),
            8.0,
            "cap of the history's weight where anything moved (Bevy resets to a blend of about 0.1 on motion)",
        ),
        hold: bool = flag(
            true,
            "a still pixel (nothing moved, nothing disoccluded) whose history holds `max_weight` samples keeps it: accumulation stops there, as a path tracer's does, and with as many `phases` as `max_weight` the image is the mean of one whole jitter cycle, still as native's; off: the mean goes on as an exponential one and a still image keeps changing a little every frame",
        ),
        mip_bias: f64 = float(
            (-4.0, true, 1.0),
            -1.0,
            "texture LOD bias relative to the output resolution (FSR 2's guide: -1, log2(render/display) - 1 in the render's terms): the render's derivatives (the ground filter's width) times scale x 2^mip_bias",
        ),
        velocity: bool = flag(
            true,
            "output-resolution velocity pass for animated objects; recorded only when the scene has some (otherwise culled: the camera reprojects by depth)",
        ),
        rcas: bool = flag(
            false,
            "sharpen the resolved output with FSR 1's RCAS (`sharpness` stops), after the history is written",
        ),
        sharpness: f32 = float(
            (0.0, true, 8.0),
            0.2,
            "RCAS sharpness in stops below the maximum, when `rcas` is on",
        ),
    }
}

impl Options {
    /// Jitter phases: `phases`, or with 0 the automatic count for the scale.
    pub fn phases(&self) -> u32 {
        match self.phases as u32 {
            0 => jitter::auto_phases(self.scale),
            n => n,
        }
    }

    /// Multiplier of the render's screen-space derivatives: scale x 2^mip_bias.
    pub fn gradient_scale(&self) -> f32 {
        (self.scale * self.mip_bias.exp2()) as f32
    }

    /// RCAS sharpness in stops, when RCAS runs.
    pub fn rcas_sharpness(&self) -> Option<f32> {
        self.rcas.then_some(self.sharpness)
    }

    /// The render size at output `width` x `height`.
    pub fn render_size(&self, width: u32, height: u32) -> (u32, u32) {
        let s = |n: u32| ((n as f64 * self.scale).round() as u32).max(1);
        (s(width), s(height))
    }
}

pub struct Taau;

impl Definition for Taau {
    type Options = Options;

    fn name(&self) -> &'static str {
        "taau"
    }

    fn summary(&self) -> &'static str {
        "temporal anti-aliasing with upsampling: Halton (2, 3) jitter, history reprojected by the cameras and a velocity pass (Catmull-Rom), YCoCg variance clipping where anything moved, disocclusion and cut resets, a running mean; optional RCAS; scale 1 is native TAA"
    }

    fn check(&self, options: &Options) -> Result<(), String> {
        let phases = options.phases;
        if phases.fract() != 0.0 {
            return Err(format!("`phases` must be a whole number, not {phases}"));
        }
        if options.moving_weight > options.max_weight {
            return Err("`moving_weight` must not exceed `max_weight`".to_string());
        }
        Ok(())
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
        Ok(Box::new(TaauGpu::new(
            cx.gpu,
            *options,
            t.width,
            t.height,
            t.dynamic_scene,
        )))
    }

    fn shaders(&self) -> Vec<Shader> {
        vec![Shader::file("taau/resolve.wgsl", RESOLVE_WGSL)]
    }
}
