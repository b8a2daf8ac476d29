//! Technique `fsr2`: AMD FidelityFX Super Resolution 2.2 (GPUOpen-Effects/FidelityFX-FSR2 v2.2.1,
//! MIT), its passes written in WGSL from AMD's shaders (`src/ffx-fsr2-api/shaders/`), one file
//! per pass citing the header and function it follows: `luminance.wgsl` (the luminance pyramid
//! and auto exposure, a plain reduction in place of SPD), `reconstruct.wgsl` (reconstruct and
//! dilate depth and motion), `depth_clip.wgsl`, `lock.wgsl`, `accumulate.wgsl` (reproject and
//! accumulate with Lanczos-2 upsampling) and `rcas.wgsl` (AMD's FSR 2 RCAS). Its inputs are
//! what an engine gives it: colour and depth at the render size, motion vectors at the render
//! size (`motion.wgsl`: the cameras' from depth, dynamic objects' from the shared motion
//! provider `render/velocity.rs`), AMD's jitter (`ffxFsr2GetJitterOffset` over
//! `ffxFsr2GetJitterPhaseCount`, `techniques/shared/jitter.rs`) and AMD's mip bias,
//! log2(render / display) - 1. Parameters here, the GPU part in `gpu.rs`; what departs from
//! AMD's code is listed in `README.md` beside this file. No reactive or transparency mask is
//! given (the scenes have no alpha-blended materials).

pub mod gpu;

use super::definition::{BuildContext, Definition, Shader, Target};
use crate::gpu::Unsupported;
use crate::render::graph::Plan;
use crate::render::renderer::Renderer;
use crate::techniques::shared::jitter;

pub use gpu::Fsr2Gpu;

crate::choice! {
    /// AMD's quality modes (`FfxFsr2QualityMode`: per-axis ratios 1.5, 1.7, 2.0, 3.0), or
    /// `custom`: `scale` as given.
    pub enum Mode {
        Custom = "custom",
        Quality = "quality",
        Balanced = "balanced",
        Performance = "performance",
        UltraPerformance = "ultra-performance",
    }
}

impl Mode {
    /// The render scale of a mode (`ffxFsr2GetUpscaleRatioFromQualityMode`); None for `custom`.
    pub fn scale(self) -> Option<f64> {
        match self {
            Mode::Custom => None,
            Mode::Quality => Some(1.0 / 1.5),
            Mode::Balanced => Some(1.0 / 1.7),
            Mode::Performance => Some(0.5),
            Mode::UltraPerformance => Some(1.0 / 3.0),
        }
    }
}

crate::options! {
    /// A variant's options, typed; what the passes take is derived from them
    /// ([`Options::render_scale`], [`Options::phases`], [`Options::gradient_scale`]).
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub struct Options {
        mode: Mode = choice(
            Mode::Quality,
            "AMD's quality mode: `quality` (render scale 1/1.5), `balanced` (1/1.7), `performance` (1/2), `ultra-performance` (1/3); a mode sets the scale and `scale` must stay at its default; `custom`: `scale`",
        ),
        scale: f64 = float(
            (0.25, true, 1.0),
            0.5,
            "render width and height as a fraction of the output resolution, with `mode = \"custom\"`",
        ),
        sharpening: bool = flag(
            true,
            "run RCAS after the accumulation (AMD's `enableSharpening`; AMD's sample turns it on)",
        ),
        sharpness: f32 = float(
            (0.0, true, 1.0),
            0.8,
            "RCAS sharpness as AMD's API takes it, 0 to 1 (1 the sharpest); RCAS gets 2 - 2 x sharpness stops (ffx_fsr2.cpp). 0.8: AMD's sample",
        ),
        auto_exposure: bool = flag(
            true,
            "AMD's FFX_FSR2_ENABLE_AUTO_EXPOSURE: the exposure from the luminance pyramid's average log luma; off: exposure 1",
        ),
        velocity: bool = flag(
            true,
            "object motion from the shared motion provider (`render/velocity.rs`) where the scene has animated objects; off: the cameras' motion only",
        ),
        mip_bias: f64 = float(
            (-4.0, true, 1.0),
            -1.0,
            "texture LOD bias relative to the output resolution: AMD's -1 (the integration guide's log2(render / display) - 1 in the render's terms) samples textures one mip finer than a native render; 0 samples them at the native render's level",
        ),
    }
}

impl Options {
    /// Render scale per axis: the mode's, or `scale`.
    pub fn render_scale(&self) -> f64 {
        self.mode.scale().unwrap_or(self.scale)
    }

    /// The render size at output `width` x `height` (`ffxFsr2GetRenderResolutionFromQualityMode`
    /// truncates; rounded here like the other upscalers, so the rows match).
    pub fn render_size(&self, width: u32, height: u32) -> (u32, u32) {
        let scale = self.render_scale();
        let s = |n: u32| ((n as f64 * scale).round() as u32).max(1);
        (s(width), s(height))
    }

    /// AMD's phase count at output `width` (`ffxFsr2GetJitterPhaseCount`).
    pub fn phases(&self, width: u32) -> u32 {
        jitter::auto_phases(self.render_size(width, 1).0, width)
    }

    /// Multiplier of the render's screen-space derivatives for the mip bias relative to the
    /// output, AMD's log2(render / display) - 1 relative to the render by default: scale x
    /// 2^mip_bias of the render's own.
    pub fn gradient_scale(&self) -> f32 {
        (self.render_scale() * self.mip_bias.exp2()) as f32
    }

    /// RCAS's sharpness in stops (ffx_fsr2.cpp: `-2 * sharpness + 2`), when it runs.
    pub fn rcas_stops(&self) -> Option<f32> {
        self.sharpening.then_some(2.0 - 2.0 * self.sharpness)
    }
}

pub struct Fsr2;

impl Definition for Fsr2 {
    type Options = Options;

    fn name(&self) -> &'static str {
        "fsr2"
    }

    fn summary(&self) -> &'static str {
        "AMD FidelityFX Super Resolution 2.2 in WGSL: luminance pyramid and auto exposure, reconstruct and dilate, depth clip, locks, reproject and accumulate with Lanczos-2 upsampling, RCAS; AMD's jitter, phase count and mip bias; render-size motion from the cameras and the shared motion provider"
    }

    /// One whole cycle of AMD's jitter (18 phases at Quality, 32 at Performance).
    fn convergence(&self, options: &Options, width: u32) -> u32 {
        options.phases(width)
    }

    fn check(&self, options: &Options) -> Result<(), String> {
        if options.mode != Mode::Custom && options.scale != Options::default().scale {
            return Err(format!(
                "`mode = \"{}\"` sets the render scale; leave `scale` out or use `mode = \"custom\"`",
                options.mode.name()
            ));
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
        Ok(Box::new(Fsr2Gpu::new(
            cx.gpu,
            *options,
            t.width,
            t.height,
            t.dynamic_scene,
        )))
    }

    fn shaders(&self) -> Vec<Shader> {
        gpu::PASSES
            .iter()
            .map(|(file, source)| Shader {
                name: file.to_string(),
                source: gpu::module(source),
                files: vec!["fsr2/common.wgsl", file],
            })
            .collect()
    }
}
