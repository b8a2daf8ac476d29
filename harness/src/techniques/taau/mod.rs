//! Technique `taau`: temporal anti-aliasing with upsampling, from the published design (Yang, Liu,
//! Salvi, "A Survey of Temporal Antialiasing Techniques", Eurographics STAR 2020) with Bevy's TAA
//! resolve (`crates/bevy_anti_alias/src/taa/taa.wgsl`) as a readable reference: the projection
//! jittered by Halton (2, 3) over FSR 2's phase count (`shared/jitter.rs`), the previous output
//! reprojected by the cameras and the shared motion provider (`render/velocity.rs`), fetched
//! with Catmull-Rom, rectified by YCoCg variance clipping every frame, rejected on disocclusion
//! and cuts, accumulated as a running mean that never stops (each new sample blended in with at
//! least 1/(1 + `max_weight`), Bevy's `MIN_HISTORY_BLEND_RATE`); optionally sharpened by FSR 1's
//! RCAS. `scale = 1` is native TAA (what shipped engines call "native + TAA"), `scale < 1`
//! upsamples. The still-scene accumulator it was before (no clip where nothing moved, no new
//! sample once converged) stays as the options `clip_moving_only` and `freeze_converged`.
//! Parameters here, the GPU part in `gpu.rs`, the CPU model in `model.rs`, the shader in
//! `resolve.wgsl`.
//!
//! A basic TAAU, not FSR 2: against FSR 2 (`src/ffx-fsr2-api/shaders/`) it lacks dilated motion
//! (`ffx_fsr2_reconstruct_dilated_velocity_and_previous_depth.h`: the nearest depth's motion of
//! the 3x3 neighbourhood; here each sample's own), Lanczos upsampling (`ffx_fsr2_upsample.h`: a
//! Lanczos-2 spread of every render sample over the output pixels around it; here a box, a
//! sample updates only the output pixel it lands in), locks (`ffx_fsr2_lock.h`: thin features
//! protected from rectification), reactive and transparency-and-composition masks, the luminance
//! pyramid's exposure and shading-change detection, and depth-clip disocclusion
//! (`ffx_fsr2_depth_clip.h`; here a 3x3 previous-depth test). Read its row as a basic TAAU.
//!
//! Requirements (as Bevy states them for its TAA): the scene pass jittered (`View::ndc_offset`),
//! depth, and motion vectors: the camera's from depth, dynamic objects' from the motion
//! provider's pass at the render size, recorded only when the scene has animated objects.

pub mod gpu;
pub mod model;

use super::definition::{BuildContext, Definition, Shader, Target};
use crate::gpu::Unsupported;
use crate::render::graph::Plan;
use crate::render::renderer::Renderer;
use crate::techniques::shared::jitter;
use crate::techniques::shared::rcas::RCAS_WGSL;

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
            "a whole number: jitter phases of the Halton (2, 3) sequence before it repeats; 0: ceil(8 x (1/scale)^2), FSR 2's `ffxFsr2GetJitterPhaseCount` (8 at scale 1, 32 at scale 0.5); also the frames the history needs before it is steady (the variant's declared convergence)",
        ),
        clip_gamma: f32 = float(
            (0.0, false, 8.0),
            1.0,
            "variance clipping box: mean +- gamma x sigma of the 3x3 render neighbourhood in YCoCg (Salvi: 1)",
        ),
        clip_moving_only: bool = flag(
            false,
            "still-scene accumulator, not a shipped TAA: clip the history only where something moved (camera, object, disocclusion); a still pixel keeps its history unclipped, so thin geometry that some jitter phases miss converges instead of flickering, and a change of shading without motion (a moving light) ghosts. Off, the default, as Bevy's TAA and FSR 2: the history is rectified every frame",
        ),
        depth_tolerance: f32 = float(
            (0.0, true, 1.0),
            0.05,
            "disocclusion: the history is dropped when the sample's previous reversed-Z depth differs from every one of the 3x3 previous depths around it by more than this fraction of the larger",
        ),
        max_weight: f32 = float(
            (1.0, true, 4096.0),
            8.0,
            "cap of the accumulated sample weight: the running mean becomes an exponential one, each landing sample blended in with at least 1/(1 + max_weight), a shipped TAA's minimum blend weight (8: 0.11, about Bevy's DEFAULT_HISTORY_BLEND_RATE 0.1; FSR 2 takes the history at weight 1 against its Lanczos sample weight). On scenarios/quality/moving-light.toml (lavapipe) 32 lagged the light by 0.76 dB PSNR below native, 8 by 0.07 dB, with no loss on the same scene under a still light (36.88 against 36.93 dB)",
        ),
        moving_weight: f32 = float(
            (0.0, true, 4096.0),
            8.0,
            "cap of the history's weight where anything moved (Bevy resets to a blend of about 0.1 on motion)",
        ),
        freeze_converged: bool = flag(
            false,
            "still-scene accumulator, not a shipped TAA: a still pixel (nothing moved, nothing disoccluded) whose history holds `max_weight` samples takes no new sample: accumulation stops there, as a path tracer's does, and with as many `phases` as `max_weight` the image is the mean of one whole jitter cycle, still as native's, but a change of shading without motion (a moving light) never reaches it. Off, the default, as every shipped TAA: each frame blends in at least 1/(1 + max_weight) of the new sample",
        ),
        mip_bias: f64 = float(
            (-4.0, true, 1.0),
            -1.0,
            "texture LOD bias relative to the output resolution (FSR 2's guide: -1, log2(render/display) - 1 in the render's terms): the render's derivatives (the ground filter's width) times scale x 2^mip_bias",
        ),
        velocity: bool = flag(
            true,
            "object motion from the shared motion provider (`render/velocity.rs`): the dynamic objects only, at the render size in the scene pass's jittered view, a static object in front told by depth; recorded only when the scene has animated objects (otherwise culled: the camera reprojects by depth)",
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
    /// Jitter phases at an output `width` pixels wide: `phases`, or with 0 FSR 2's count for
    /// the render width ([`jitter::auto_phases`]).
    pub fn phases(&self, width: u32) -> u32 {
        match self.phases as u32 {
            0 => jitter::auto_phases(self.render_size(width, 1).0, width),
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
        "temporal anti-aliasing with upsampling, a basic TAAU (no dilated motion, Lanczos upsampling, locks or reactive masks, unlike FSR 2): Halton (2, 3) jitter over FSR 2's phase count, history reprojected by the cameras and the render-size motion of dynamic objects (Catmull-Rom), YCoCg variance clipping every frame, disocclusion and cut resets, a running mean with a minimum blend weight; optional RCAS; scale 1 is native TAA"
    }

    /// One whole cycle of its jitter: at FSR 2's phase count every output pixel has taken
    /// samples from all its phases (32 at scale 0.5, 8 at scale 1).
    fn convergence(&self, options: &Options, width: u32) -> u32 {
        options.phases(width)
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
        vec![
            Shader::file("taau/resolve.wgsl", RESOLVE_WGSL),
            Shader::file("shared/rcas.wgsl", RCAS_WGSL),
        ]
    }
}
