//! Techniques `adaptive-shading` and `native-deferred`: NVIDIA's content and motion adaptive
//! shading (Yang et al. 2019, `seeds/nvidia-adaptive-shading.txt`) on software variable-rate
//! shading, and its baseline, the same deferred path at 1x1 everywhere. Parameters here, the GPU
//! part in `gpu.rs`, the CPU model of rate selection in `model.rs`, shaders in
//! this folder (`*.wgsl`).
//!
//! Scenes with textured materials (glTF files, the city) are drawn by the hardware path (its raw
//! passes draw the scene's material draws: `raw_material.rs`, `vrs_material.wgsl`); the software
//! path and `native-deferred` are skipped on them ([`Definition::textured`]: the G-buffer carries
//! no texture coordinates or materials).
//!
//! Defaults are the paper's: t = 0.15 and l = 0.05 (section 6), k = 2.13 (Eq. 14), e = 0.1
//! (section 4.2's example), 4x4 off (section 3.4), the 2x neighbour filter on (section 5.4). The
//! paper gives no value for the hysteresis epsilon nor for the depth-rejection tolerance (section
//! 5.1 cites Nehab et al.): those defaults are ours.

pub mod attachment;
pub mod gpu;
pub mod hardware;
pub mod model;
pub mod raw_material;
pub mod raw_pass;
mod raw_pipeline;

use super::definition::{BuildContext, Definition, Shader, Target, Technique};
use crate::gpu::{Extension, Requirements, Unsupported};
use crate::render::graph::Plan;
use crate::render::renderer::Renderer;
use crate::techniques::Variant;

pub use gpu::{graph, rate_image, AdaptiveGpu, LastFrame};
pub use hardware::{HardwareGpu, Rates};
pub use model::{CoarseSample, Mode, RateParams};

crate::choice! {
    /// Where `adaptive-shading` shades at its rates (parameter `vrs`).
    pub enum Vrs {
        /// A G-buffer, then a compute pass per coarse pixel (`gpu.rs`): runs on every adapter.
        Software = "software",
        /// The forward pass with a fragment-shading-rate attachment (`hardware.rs`).
        Hardware = "hardware",
    }
}

crate::choice! {
    /// The rate of every tile of `native-vrs` (parameter `rate`).
    pub enum FixedRate {
        R1x1 = "1x1",
        R2x2 = "2x2",
        R4x4 = "4x4",
    }
}

impl FixedRate {
    pub fn size(self) -> (u32, u32) {
        match self {
            FixedRate::R1x1 => (1, 1),
            FixedRate::R2x2 => (2, 2),
            FixedRate::R4x4 => (4, 4),
        }
    }
}

/// Rate-selection parameters of an `adaptive-shading` variant.
pub fn rate_params(v: &Variant) -> RateParams {
    Options::from_variant(v).rates()
}

/// The rate selection a variant runs: its parameters for `adaptive-shading`, `None` (every tile at
/// 1x1, no rate pass) for `native-deferred`.
pub fn rates_of(v: &Variant) -> Option<RateParams> {
    (v.technique.name() == Technique::name(&AdaptiveShading)).then(|| rate_params(v))
}

crate::options! {
    /// An `adaptive-shading` variant's options: where it shades at its rates (`vrs`), and the rate
    /// selection ([`Options::rates`]).
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub struct Options {
        vrs: Vrs = choice(
            Vrs::Software,
            "`software`: a G-buffer pass, then a compute pass shading once per coarse pixel and object (runs everywhere; never faster than `native`); `hardware`: the forward pass drawn with a fragment-shading-rate attachment filled from the rates (VK_KHR_fragment_shading_rate through raw Vulkan beside wgpu; in the paper's order, section 5: a depth pre-pass writes this frame's motion, the rate pass reprojects the previous output by it, then the frame is shaded at those rates); draws textured materials (glTF files, the city) as `native` does, alpha-tested ones tested in the pre-pass, blended ones last at the attachment's rates; skipped on adapters without the extension and its attachment feature. Compare with `native-vrs`, the same pipeline at 1x1. `software` cannot draw textured materials (its G-buffer has no texture coordinates): skipped on such scenes",
        ),
        threshold: f32 = float(
            (0.0, false, 100.0),
            0.15,
            "sensitivity threshold t of the just-noticeable-difference threshold t (I_avg + l) (Eq. 15; the paper's value). Sweep it for the paper's Fig. 10 (error against average shading rate)",
        ),
        env_luma: f32 = float(
            (0.0, true, 100.0),
            0.05,
            "environment luminance l (Eq. 15; the paper's value)",
        ),
        k: f32 = float(
            (0.0, false, 100.0),
            2.13,
            "quarter-rate error over half-rate error (Eq. 14); also the scale of the quarter-rate motion factor (Eq. 21)",
        ),
        mode: Mode = choice(
            Mode::ContentMotion,
            "`content-motion`: Eq. 22, the error estimate scaled by the motion factors b_H, b_Q (Eq. 20, 21) of the tile's minimum motion per axis; `content`: Eq. 16, no motion factors; `motion`: standalone motion-adaptive shading (Eq. 24), no error estimate, the relative error taken as `max_error`",
        ),
        max_error: f32 = float(
            (0.0, false, 100.0),
            0.1,
            "`motion` mode only: the bound e on the relative error (Eq. 24); 0.1 as the paper's example (section 4.2: with t = 0.03, half rate from 2.86 px/frame, quarter from 9.49)",
        ),
        hysteresis: f32 = float(
            (0.0, true, 0.99),
            0.2,
            "epsilon of the thresholds t(1 + epsilon) and t(1 - epsilon) (section 5.4; the paper gives no value; 0 turns it off. A tile shaded coarsely shows about sqrt 2 more error estimate next frame than at full rate (replicated pixels step at coarse-pixel borders: the feedback loop of section 5.4), so without hysteresis rates oscillate frame to frame on a static scene: on a small `detailed.toml` flicker was 0.53 at epsilon 0, 0.19 at 0.1, 0.055 at 0.2 and above, native 0.052), a Schmitt trigger on each tile's previous rate per axis (before the neighbour filter): a rise of the predicted error to a finer rate must pass t(1 + epsilon), a fall to a coarser rate t(1 - epsilon)",
        ),
        neighbour_filter: bool = flag(
            true,
            "section 5.4's filter limiting neighbouring tiles (8-neighbourhood) to a 2x rate difference per axis, quarter raised to half: a `rate_filter` pass on the software path, applied by `rate_attachment` as it reads the codes on the hardware path",
        ),
        allow_4x4: bool = flag(
            false,
            "quarter rate on both axes at once; off in the paper (section 3.4): the axis with the larger error gets half rate",
        ),
        coarse_sample: CoarseSample = choice(
            CoarseSample::Centre,
            "where the shading pass shades a coarse pixel: `centre` as hardware VRS does (the paper's setting): at the mean of the G-buffer attributes of the object's pixels in it, with the ground filter's derivatives scaled across it (coarse pixels blur rather than alias); `pixel`: at the G-buffer sample of its shading pixel (the centre pixel, or the object's first pixel in it), replicated (a native sample: smaller error against a `native` reference where native itself aliases)",
        ),
        disocclusion_tolerance: f32 = float(
            (0.0, false, 1.0e9),
            0.05,
            "depth-based rejection (section 5.1): a covered pixel whose reprojected position is off screen, or whose previous-frame view depth differs from its surface's by more than this fraction, is disoccluded, and its tile shaded at 1x1",
        ),
    }
}

impl Options {
    /// The rate selection (everything but `vrs`), as the model and the shaders take it.
    pub fn rates(&self) -> RateParams {
        RateParams {
            threshold: self.threshold,
            env_luma: self.env_luma,
            k: self.k,
            mode: self.mode,
            max_error: self.max_error,
            hysteresis: self.hysteresis,
            neighbour_filter: self.neighbour_filter,
            allow_4x4: self.allow_4x4,
            disocclusion_tolerance: self.disocclusion_tolerance,
            coarse_sample: self.coarse_sample,
        }
    }
}

crate::options! {
    /// A `native-vrs` variant's options: every tile's rate.
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub struct FixedOptions {
        rate: FixedRate = choice(
            FixedRate::R1x1,
            "every tile's fragment size: `1x1` is the full-rate baseline of `adaptive-shading` with `vrs = \"hardware\"` (the same pipeline without rates), `2x2` and `4x4` the fixed-rate extremes",
        ),
    }
}

/// What the hardware path needs: VK_KHR_fragment_shading_rate with attachment rates.
fn hardware_requirements() -> Requirements {
    Requirements::none().extension(Extension::FragmentShadingRate)
}

/// The rate pass's two modules (workgroup-memory and subgroup entry points, `gpu::rate_source`).
fn rate_shaders() -> [Shader; 2] {
    [false, true].map(|wide| Shader {
        name: format!("adaptive rates{}", if wide { " (subgroups)" } else { "" }),
        source: gpu::rate_source(wide),
        files: vec![
            "adaptive_shading/rate.wgsl",
            "adaptive_shading/rate_filter.wgsl",
            if wide {
                "adaptive_shading/rate_subgroup.wgsl"
            } else {
                "adaptive_shading/rate_shared.wgsl"
            },
        ],
    })
}

fn shaders() -> Vec<Shader> {
    let mut v = Vec::from(rate_shaders());
    v.extend([Shader {
        name: "adaptive shade".into(),
        source: gpu::shade_source(),
        files: vec!["scene.wgsl", "adaptive_shading/shade.wgsl"],
    }]);
    v
}

fn hardware_shaders() -> Vec<Shader> {
    let mut v = Vec::from(rate_shaders());
    v.extend([
        Shader {
            name: "adaptive rate attachment".into(),
            source: hardware::attachment_source(),
            files: vec![
                "adaptive_shading/attachment.wgsl",
                "adaptive_shading/rate_filter.wgsl",
            ],
        },
        Shader {
            name: "adaptive vrs".into(),
            source: hardware::vrs_source(),
            files: vec!["scene.wgsl", "adaptive_shading/vrs.wgsl"],
        },
        Shader {
            name: "adaptive vrs material".into(),
            source: hardware::vrs_material_source(),
            files: vec![
                "scene.wgsl",
                "material/material.wgsl",
                "adaptive_shading/vrs_material.wgsl",
            ],
        },
    ]);
    v
}

/// Why the deferred path (`vrs = "software"`, `native-deferred`) does not draw scenes with
/// textured materials (glTF `materials = "file"`, the city): its G-buffer carries no texture
/// coordinates, tangents or materials, and its compute shading pass has no texture gradients.
/// The hardware path (`vrs = "hardware"`, `native-vrs`) draws them (`raw_material.rs`).
fn deferred_untextured(name: &str) -> Result<(), String> {
    Err(format!(
        "{name} cannot draw textured materials: its G-buffer carries no texture coordinates or materials (the hardware path, `vrs = \"hardware\"` / `native-vrs`, draws them)"
    ))
}

/// The hardware path on `gpu`, or why this adapter cannot run it (its requirements were met, so
/// the caps are there).
fn build_hardware(rates: Rates, cx: &BuildContext<'_>) -> Result<Box<dyn Renderer>, Unsupported> {
    let (gpu, t) = (cx.gpu, cx.target);
    match &gpu.vrs {
        Ok(caps) => HardwareGpu::new(gpu, caps, rates, cx.scene, t.width, t.height)
            .map(|hw| Box::new(hw) as Box<dyn Renderer>)
            .map_err(Unsupported),
        Err(reason) => Err(Unsupported(reason.clone())),
    }
}

/// The attachment texel size a plan assumes without a GPU (the H200's, and the paper's tile).
const PLAN_TEXEL: [u32; 2] = [model::TILE, model::TILE];

pub struct AdaptiveShading;

impl Definition for AdaptiveShading {
    type Options = Options;

    fn name(&self) -> &'static str {
        "adaptive-shading"
    }

    /// The rates read the previous frame's output (1 frame) and, with hysteresis, the previous
    /// frame's rates as well (1 more: the Schmitt trigger of section 5.4 settles after it).
    fn convergence(&self, options: &Options, _width: u32) -> u32 {
        if options.hysteresis > 0.0 {
            2
        } else {
            1
        }
    }

    fn requirements(&self, options: &Options) -> Requirements {
        match options.vrs {
            Vrs::Software => Requirements::none(),
            Vrs::Hardware => hardware_requirements(),
        }
    }

    /// Each path against its own full-rate pipeline: `native-deferred` (software), `native-vrs`
    /// at 1x1 (hardware).
    fn baseline(&self, options: &Options) -> Option<&'static str> {
        Some(match options.vrs {
            Vrs::Software => Technique::name(&NativeDeferred),
            Vrs::Hardware => Technique::name(&NativeVrs),
        })
    }

    fn summary(&self) -> &'static str {
        "NVIDIA's content and motion adaptive shading on software variable-rate shading: a rate per 16x16 tile from the previous frame"
    }

    fn check(&self, options: &Options) -> Result<(), String> {
        if options.vrs == Vrs::Hardware && options.coarse_sample == CoarseSample::Pixel {
            return Err("`coarse_sample = \"pixel\"` needs `vrs = \"software\"`: hardware variable-rate shading shades each coarse pixel at its centre".into());
        }
        Ok(())
    }

    fn textured(&self, options: &Options) -> Result<(), String> {
        match options.vrs {
            Vrs::Software => deferred_untextured("adaptive-shading with `vrs = \"software\"`"),
            Vrs::Hardware => Ok(()),
        }
    }

    fn plan(&self, options: &Options, target: Target) -> Plan {
        let p = options.rates();
        match options.vrs {
            Vrs::Software => graph(Some(&p), target.width, target.height),
            Vrs::Hardware => {
                hardware::graph(&Rates::Adaptive(p), target.width, target.height, PLAN_TEXEL)
            }
        }
    }

    fn build(
        &self,
        options: &Options,
        cx: &BuildContext<'_>,
    ) -> Result<Box<dyn Renderer>, Unsupported> {
        let t = cx.target;
        if options.vrs == Vrs::Hardware {
            return build_hardware(Rates::Adaptive(options.rates()), cx);
        }
        Ok(Box::new(AdaptiveGpu::new(
            cx.gpu,
            Some(options.rates()),
            t.width,
            t.height,
        )))
    }

    fn shaders(&self) -> Vec<Shader> {
        let mut all = shaders();
        all.extend(hardware_shaders());
        all
    }
}

pub struct NativeVrs;

impl Definition for NativeVrs {
    type Options = FixedOptions;

    fn name(&self) -> &'static str {
        "native-vrs"
    }

    fn requirements(&self, _options: &FixedOptions) -> Requirements {
        hardware_requirements()
    }

    fn summary(&self) -> &'static str {
        "the hardware path of `adaptive-shading` (`vrs = \"hardware\"`) with every tile at one fixed rate: at `1x1` the same pipeline without rates (its full-rate baseline), at `2x2` and `4x4` the fixed-rate extremes; draws textured materials; needs VK_KHR_fragment_shading_rate"
    }

    fn plan(&self, options: &FixedOptions, target: Target) -> Plan {
        let (rx, ry) = options.rate.size();
        hardware::graph(
            &Rates::Fixed(rx, ry),
            target.width,
            target.height,
            PLAN_TEXEL,
        )
    }

    fn build(
        &self,
        options: &FixedOptions,
        cx: &BuildContext<'_>,
    ) -> Result<Box<dyn Renderer>, Unsupported> {
        let (rx, ry) = options.rate.size();
        build_hardware(Rates::Fixed(rx, ry), cx)
    }

    fn shaders(&self) -> Vec<Shader> {
        hardware_shaders()
    }
}

pub struct NativeDeferred;

impl Definition for NativeDeferred {
    /// `native-deferred` has no parameters.
    type Options = ();

    fn name(&self) -> &'static str {
        "native-deferred"
    }

    fn summary(&self) -> &'static str {
        "the deferred path of `adaptive-shading` with every tile at 1x1: a full-resolution G-buffer pass, then a compute pass shading every pixel with the forward path's shading function (bitwise the same image as `native` on lavapipe); the baseline of `adaptive-shading` in software (`speedup.native-deferred`; in hardware it is `native-vrs`)"
    }

    fn textured(&self, _options: &()) -> Result<(), String> {
        deferred_untextured("native-deferred")
    }

    fn plan(&self, _options: &(), target: Target) -> Plan {
        graph(None, target.width, target.height)
    }

    fn build(
        &self,
        _options: &(),
        cx: &BuildContext<'_>,
    ) -> Result<Box<dyn Renderer>, Unsupported> {
        let t = cx.target;
        Ok(Box::new(AdaptiveGpu::new(cx.gpu, None, t.width, t.height)))
    }

    fn shaders(&self) -> Vec<Shader> {
        shaders()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_models_defaults_are_the_parameters_defaults() {
        let v = Variant::with_defaults(&AdaptiveShading);
        assert_eq!(rate_params(&v), RateParams::default());
    }
}
