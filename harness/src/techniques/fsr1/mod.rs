//! Technique `fsr1`: AMD FidelityFX Super Resolution 1 (`ffx_fsr1.h` of FidelityFX FSR v1.0.2, MIT): the scene
//! rendered at a fraction of the output resolution, upscaled by EASU (edge-adaptive spatial
//! upsampling) and sharpened by RCAS (robust contrast-adaptive sharpening), both compute passes.
//! Parameters here, the GPU part in `gpu.rs`, the CPU model in `model.rs`, the shader in
//! `fsr1.wgsl` (its header states the input contract and every deviation).
//!
//! Input contract, as AMD states it: EASU wants anti-aliased, perceptually encoded colour in
//! [0, 1] (the integration guide, `docs/FidelityFX-FSR-Overview-Integration.pdf`: "FSR 1.0
//! applied on a non anti-aliased input image will likely return poor results"; place it after
//! TAA or MSAA and tonemapping); RCAS is undefined for negative input. By default
//! (`input = "msaa4x"`) the scene pass renders 4x MSAA at the render size and resolves it (the
//! hardware's box average) before EASU: MSAA is the anti-aliasing that lavapipe and every
//! measured GPU offer at one pass, and its cost is in the `scene` pass's time.
//! `input = "aliased"` feeds EASU the one-sample render, FSR 1 as a user without an AA pass
//! would get it, against AMD's contract, and says so in its variant name. The linear HDR render
//! is made finite and non-negative, reversibly tonemapped (AMD's SRTM) and gamma-2.0 encoded per
//! tap; the output is decoded back to linear.
//!
//! Mip bias: AMD's integration guide gives -0.38 / -0.58 / -0.79 / -1.0 for the four modes
//! (log2 of the render scale for any other); the harness's textured content is the ground's
//! analytically filtered pattern, whose filter width (screen-space derivatives) is multiplied by
//! 2^bias (`View::gradient_scale`) when `mip_bias` is on.

pub mod gpu;
pub mod model;

use super::definition::{BuildContext, Definition, Shader, Target};
use crate::gpu::{Requirements, Unsupported};
use crate::render::graph::Plan;
use crate::render::renderer::Renderer;
use crate::render::scene::{COLOR_FORMAT, DEPTH_FORMAT};

use crate::techniques::shared::rcas::RCAS_WGSL;
pub use gpu::{Fsr1Gpu, FSR1_WGSL};

crate::choice! {
    /// AMD's quality modes (per-axis ratios 1.3, 1.5, 1.7, 2.0), or `custom`: `scale` as given.
    pub enum Mode {
        Custom = "custom",
        UltraQuality = "ultra-quality",
        Quality = "quality",
        Balanced = "balanced",
        Performance = "performance",
    }
}

impl Mode {
    /// The render scale (fraction of the output per axis) and mip bias of a quality mode; None
    /// for `custom`.
    pub fn preset(self) -> Option<(f64, f64)> {
        match self {
            Mode::Custom => None,
            Mode::UltraQuality => Some((1.0 / 1.3, -0.38)),
            Mode::Quality => Some((1.0 / 1.5, -0.58)),
            Mode::Balanced => Some((1.0 / 1.7, -0.79)),
            Mode::Performance => Some((0.5, -1.0)),
        }
    }
}

crate::choice! {
    /// What EASU is fed.
    pub enum Input {
        Msaa4x = "msaa4x",
        Aliased = "aliased",
    }
}

crate::options! {
    /// A variant's options, typed; what the passes take is derived from them
    /// ([`Options::render_scale`], [`Options::rcas_sharpness`], [`Options::gradient_scale`]).
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub struct Options {
        /// The quality mode (`custom`: `scale` as given).
        mode: Mode = choice(
            Mode::Custom,
            "AMD's quality mode: `ultra-quality` (render scale 1/1.3, mip bias -0.38), `quality` (1/1.5, -0.58), `balanced` (1/1.7, -0.79), `performance` (1/2, -1.0); a mode sets the scale and `scale` must stay at its default; `custom`: `scale`, mip bias log2(scale)",
        ),
        scale: f64 = float(
            (0.25, true, 1.0),
            0.5,
            "render width and height as a fraction of the output resolution (EASU's quality range is 1x to 4x in area: 0.5 to 1 per axis; 0.25 is allowed)",
        ),
        sharpness: f32 = float(
            (0.0, true, 8.0),
            0.2,
            "RCAS sharpness in stops below the maximum (FsrRcasCon: 0 is the sharpest, each stop halves it; AMD's default 0.2)",
        ),
        rcas: bool = flag(
            true,
            "run RCAS after EASU (a second compute pass); off: EASU alone",
        ),
        input: Input = choice(
            Input::Msaa4x,
            "what EASU is fed: `msaa4x` the render-size scene with 4x MSAA, resolved (anti-aliased, as AMD's integration guide asks: \"FSR 1.0 applied on a non anti-aliased input image will likely return poor results\"); `aliased` one sample per pixel, against that contract (FSR 1 as a user without an AA pass gets it)",
        ),
        mip_bias: bool = flag(
            true,
            "apply the mode's mip bias to the ground pattern's filter width (derivatives times 2^bias); off: the reduced-resolution render's own derivatives",
        ),
    }
}

impl Options {
    /// The render scale per axis and the mip bias: the mode's preset, or `scale` and its log2.
    fn scale_and_bias(&self) -> (f64, f64) {
        self.mode
            .preset()
            .unwrap_or((self.scale, self.scale.log2()))
    }

    /// Render scale per axis.
    pub fn render_scale(&self) -> f64 {
        self.scale_and_bias().0
    }

    /// Whether `scale` was left at its default (a mode sets it).
    pub fn scale_is_default(&self) -> bool {
        self.scale == Options::default().scale
    }

    /// RCAS sharpness in stops, when RCAS runs.
    pub fn rcas_sharpness(&self) -> Option<f32> {
        self.rcas.then_some(self.sharpness)
    }

    /// Multiplier of the scene's screen-space derivatives (2^mip bias, or 1).
    pub fn gradient_scale(&self) -> f32 {
        if self.mip_bias {
            self.scale_and_bias().1.exp2() as f32
        } else {
            1.0
        }
    }

    /// The render size at output `width` x `height`.
    pub fn render_size(&self, width: u32, height: u32) -> (u32, u32) {
        let scale = self.render_scale();
        let s = |n: u32| ((n as f64 * scale).round() as u32).max(1);
        (s(width), s(height))
    }
}

pub struct Fsr1;

impl Definition for Fsr1 {
    type Options = Options;

    fn name(&self) -> &'static str {
        "fsr1"
    }

    fn summary(&self) -> &'static str {
        "AMD FidelityFX Super Resolution 1: render at a fraction of the output resolution, upscale with EASU, sharpen with RCAS (compute passes)"
    }

    fn check(&self, options: &Options) -> Result<(), String> {
        let mode = options.mode;
        if mode != Mode::Custom && !options.scale_is_default() {
            return Err(format!(
                "`mode = \"{}\"` sets the render scale; leave `scale` out or use `mode = \"custom\"`",
                mode.name()
            ));
        }
        Ok(())
    }

    /// 4x MSAA scene targets with `input = "msaa4x"`.
    fn requirements(&self, options: &Options) -> Requirements {
        match options.input {
            Input::Msaa4x => Requirements::none()
                .msaa(4, COLOR_FORMAT, "rgba16float")
                .msaa(4, DEPTH_FORMAT, "depth32float"),
            Input::Aliased => Requirements::none(),
        }
    }

    fn plan(&self, options: &Options, target: Target) -> Plan {
        gpu::graph(options, target.width, target.height)
    }

    fn build(
        &self,
        options: &Options,
        cx: &BuildContext<'_>,
    ) -> Result<Box<dyn Renderer>, Unsupported> {
        Ok(Box::new(Fsr1Gpu::new(
            cx.gpu,
            *options,
            cx.target.width,
            cx.target.height,
        )))
    }

    fn shaders(&self) -> Vec<Shader> {
        vec![
            Shader {
                name: "fsr1/fsr1.wgsl".to_string(),
                source: gpu::module(),
                files: vec!["shared/rcas.wgsl", "fsr1/fsr1.wgsl"],
            },
            Shader::file("shared/rcas.wgsl", RCAS_WGSL),
        ]
    }
}
