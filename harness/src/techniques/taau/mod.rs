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
use crate::params::{Param, ParamSpec};
use crate::render::graph::Plan;
use crate::render::renderer::Renderer;
use crate::techniques::Variant;

pub use gpu::{LastFrame, TaauGpu, RESOLVE_WGSL};

pub static SCALE: Param<f64> = Param::float(
    "scale",
    (0.25, true, 1.0),
    1.0,
    "render width and height as a fraction of the output resolution: 1 is native-resolution TAA, below 1 upsamples",
);
pub static PHASES: Param<f64> = Param::float(
    "phases",
    (0.0, true, 1024.0),
    0.0,
    "a whole number: jitter phases of the Halton (2, 3) sequence before it repeats; 0: max(32, 8 x (1/scale)^2) (DLSS's guide asks for 8 x ratio^2; 32 matches the converged reference)",
);
pub static CLIP_GAMMA: Param<f64> = Param::float(
    "clip_gamma",
    (0.0, false, 8.0),
    1.0,
    "variance clipping box: mean +- gamma x sigma of the 3x3 render neighbourhood in YCoCg (Salvi: 1)",
);
pub static CLIP_STILL: Param<bool> = Param::flag(
    "clip_still",
    false,
    "clip the history also where nothing moved (still camera, static object, no disocclusion); off: a still pixel keeps its history, so thin geometry that some jitter phases miss converges instead of flickering",
);
pub static DEPTH_TOLERANCE: Param<f64> = Param::float(
    "depth_tolerance",
    (0.0, true, 1.0),
    0.05,
    "disocclusion: the history is dropped when the sample's previous reversed-Z depth differs from every one of the 3x3 previous depths around it by more than this fraction of the larger",
);
pub static MAX_WEIGHT: Param<f64> = Param::float(
    "max_weight",
    (1.0, true, 4096.0),
    32.0,
    "cap of the accumulated sample weight: the running mean becomes an exponential one with factor 1/(1 + max_weight)",
);
pub static MOVING_WEIGHT: Param<f64> = Param::float(
    "moving_weight",
    (0.0, true, 4096.0),
    8.0,
    "cap of the history's weight where anything moved (Bevy resets to a blend of about 0.1 on motion)",
);
pub static HOLD: Param<bool> = Param::flag(
    "hold",
    true,
    "a still pixel (nothing moved, nothing disoccluded) whose history holds `max_weight` samples keeps it: accumulation stops there, as a path tracer's does, and with as many `phases` as `max_weight` the image is the mean of one whole jitter cycle, still as native's; off: the mean goes on as an exponential one and a still image keeps changing a little every frame",
);
pub static MIP_BIAS: Param<f64> = Param::float(
    "mip_bias",
    (-4.0, true, 1.0),
    -1.0,
    "texture LOD bias relative to the output resolution (FSR 2's guide: -1, log2(render/display) - 1 in the render's terms): the render's derivatives (the ground filter's width) times scale x 2^mip_bias",
);
pub static VELOCITY: Param<bool> = Param::flag(
    "velocity",
    true,
    "output-resolution velocity pass for animated objects; recorded only when the scene has some (otherwise culled: the camera reprojects by depth)",
);
pub static RCAS: Param<bool> = Param::flag(
    "rcas",
    false,
    "sharpen the resolved output with FSR 1's RCAS (`sharpness` stops), after the history is written",
);
pub static SHARPNESS: Param<f64> = Param::float(
    "sharpness",
    (0.0, true, 8.0),
    0.2,
    "RCAS sharpness in stops below the maximum, when `rcas` is on",
);
static PARAMS: [&ParamSpec; 12] = [
    &SCALE.spec,
    &PHASES.spec,
    &CLIP_GAMMA.spec,
    &CLIP_STILL.spec,
    &DEPTH_TOLERANCE.spec,
    &MAX_WEIGHT.spec,
    &MOVING_WEIGHT.spec,
    &HOLD.spec,
    &MIP_BIAS.spec,
    &VELOCITY.spec,
    &RCAS.spec,
    &SHARPNESS.spec,
];

/// A variant's options, typed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    pub scale: f64,
    /// `phases` as given (0: automatic), kept for the whole-number check.
    pub phases_param: f64,
    pub phases: u32,
    pub clip_gamma: f32,
    pub clip_still: bool,
    pub depth_tolerance: f32,
    pub max_weight: f32,
    pub moving_weight: f32,
    pub hold: bool,
    /// Multiplier of the render's screen-space derivatives.
    pub gradient_scale: f32,
    pub velocity: bool,
    /// RCAS sharpness in stops, when RCAS runs.
    pub sharpness: Option<f32>,
}

impl Options {
    pub fn from_variant(v: &Variant) -> Options {
        let scale = v.get(&SCALE);
        let phases = match v.get(&PHASES) as u32 {
            0 => jitter::auto_phases(scale),
            n => n,
        };
        Options {
            scale,
            phases_param: v.get(&PHASES),
            phases,
            clip_gamma: v.get(&CLIP_GAMMA) as f32,
            clip_still: v.get(&CLIP_STILL),
            depth_tolerance: v.get(&DEPTH_TOLERANCE) as f32,
            max_weight: v.get(&MAX_WEIGHT) as f32,
            moving_weight: v.get(&MOVING_WEIGHT) as f32,
            hold: v.get(&HOLD),
            gradient_scale: (scale * v.get(&MIP_BIAS).exp2()) as f32,
            velocity: v.get(&VELOCITY),
            sharpness: v.get(&RCAS).then(|| v.get(&SHARPNESS) as f32),
        }
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

    fn params(&self) -> &'static [&'static ParamSpec] {
        &PARAMS
    }

    fn options(&self, variant: &Variant) -> Options {
        Options::from_variant(variant)
    }

    fn check(&self, options: &Options) -> Result<(), String> {
        let phases = options.phases_param;
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
