//! Technique `checkerboard`: Intel's checkerboard rendering (McFerron & Lake 2018) with
//! mosaiikki's refinements: its parameters and options here, the GPU part in `gpu.rs`, the CPU
//! model of the reconstruction in `model.rs`, its shaders beside them (`*.wgsl`).
//!
//! Defaults trace to the sources: sampling portable; gradients at -1 LOD as Intel's sample code
//! (DDXY_BIAS 0.5), measured better than the white paper's and mosaiikki's -0.5 LOD
//! (`gradient_scale = 0.7071`, kept as the option; issue 26: 28.61 against 40.58 dB on the quality
//! suite's static scene, FLIP 0.0304 against 0.0278 on the city at 1080p);
//! CSO with mosaiikki's tolerance (view units); ASO, where chosen, on Intel's rule (history that
//! moved more than a quarter-resolution texel; mosaiikki's "moved to another 2x2 block" is
//! `aso_motion = "block"`); mosaiikki's differential fill; Intel's unclamped
//! history (mosaiikki's clamps are options); mosaiikki's velocity buffer of the dynamic objects
//! only (`velocity_objects`), with a depth test for static occluders mosaiikki does not need
//! (every object of its scene moves). Issue 26 item 5, on lavapipe: the velocity pass of
//! `scenarios/perf/aso-cso-city.toml` at 320x180 (24 moving cars among static buildings) takes
//! 1.8-2.1 ms instead of 10.3-14.1 ms with every object, frames identical (28.42 dB); on a box
//! moving about 4 px a frame behind a static one at 128x96, 26.88 against 26.91 dB, FLIP 0.0330
//! against 0.0326 (a few pixels a frame at the occluder's edges, where the neighbours' mean mixes
//! both surfaces). On the H200 at 1080p (same city, CSO two-pass): the pass 0.451 against 1.387
//! ms, the frame 3.281 against 4.219 ms (native 5.082), PSNR 36.22 against 36.25 dB
//! (`scenarios/perf/README.md`).

pub mod gpu;
pub mod model;

use super::definition::{BuildContext, Definition, FramePattern, Shader, Target};
use crate::gpu::{Requirements, Unsupported};
use crate::render::graph::Plan;
use crate::render::renderer::Renderer;
use crate::render::scene::{Objects, COLOR_FORMAT, DEPTH_FORMAT};

pub use gpu::{quarter_size, quarter_view, two_pass_jitter, CheckerboardGpu, LastFrame};

crate::choice! {
    /// How the quarter-resolution samples are shaded.
    pub enum Sampling {
        /// Two jittered single-sample renders: the same samples on any adapter.
        TwoPass = "two-pass",
        /// A 2x MSAA target shaded per sample (needs MULTISAMPLE_X2 and standard positions).
        Msaa2x = "msaa2x",
    }
}

crate::choice! {
    /// When a pixel whose history moved to another 2x2 block is taken as occluded.
    pub enum Occlusion {
        /// When its old view depth differs from its neighbours' mean by the tolerance or more.
        Cso = "cso",
        /// Always.
        Aso = "aso",
    }
}

crate::choice! {
    /// Which moved history ASO takes as occluded.
    pub enum AsoMotion {
        /// Moved more than a quarter-resolution texel (2 pixels): Intel's white paper.
        QuarterTexel = "quarter-texel",
        /// Moved to another 2x2 block: mosaiikki's `possiblyOccluded`.
        Block = "block",
    }
}

crate::choice! {
    /// How a missing pixel is filled from its 4 neighbours.
    pub enum Fill {
        Plain = "plain",
        Tonemapped = "tonemapped",
        Differential = "differential",
    }
}

crate::choice! {
    /// How the history is clamped to the neighbours.
    pub enum Clamp {
        None = "none",
        MinMax = "min-max",
        MinMaxConfidence = "min-max-confidence",
    }
}

crate::choice! {
    /// Which objects the velocity pass draws.
    pub enum VelocityObjects {
        /// The dynamic objects only (mosaiikki); static pixels are camera-reprojected.
        Dynamic = "dynamic",
        /// Every object: the buffer is exact where a static object hides a moving one.
        All = "all",
    }
}

impl VelocityObjects {
    /// What the velocity pass draws.
    pub fn objects(self) -> Objects {
        match self {
            VelocityObjects::Dynamic => Objects::Dynamic,
            VelocityObjects::All => Objects::All,
        }
    }
}

impl Fill {
    /// The resolve shader's code (`mode.w`).
    pub fn code(self) -> u32 {
        match self {
            Fill::Plain => 0,
            Fill::Tonemapped => 1,
            Fill::Differential => 2,
        }
    }
}

impl Clamp {
    /// The resolve shader's code (`mode2.x`).
    pub fn code(self) -> u32 {
        match self {
            Clamp::None => 0,
            Clamp::MinMax => 1,
            Clamp::MinMaxConfidence => 2,
        }
    }
}

crate::options! {
    /// A variant's options, typed; the resolve shader's `mode` fields encode them.
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub struct Options {
        sampling: Sampling = choice(
            Sampling::TwoPass,
            "`msaa2x`: 2x MSAA quarter-resolution targets shaded per sample (Intel, mosaiikki); needs `MULTISAMPLE_X2` for rgba16float and depth32float and the standard sample positions (probed once per adapter), else the variant is skipped with the reason. `two-pass`: two single-sample quarter-resolution renders, the projection jittered a quarter of a quarter-resolution pixel each way: the same samples on any adapter, vertex work twice",
        ),
        gradient_scale: f32 = float(
            (0.0, false, 1.0),
            0.5,
            "multiplies screen-space derivatives at quarter resolution (the ground filter's width): 0.5 (the default) is -1 LOD, Intel's sample code (`DDXY_BIAS`), which gives the quarter-resolution footprint exactly native's; 0.7071 is -0.5 LOD, as Intel's white paper (\"Forward Rendering Algorithm\", step 1a: `MipLODBias` of -0.5f) and mosaiikki (\"log2(sqrt(2)) = 0.5\"), measured blurrier against both the native and the converged reference (28.61 against 40.58 dB on scenarios/quality/static.toml); 1 uncorrected",
        ),
        occlusion: Occlusion = choice(
            Occlusion::Cso,
            "a pixel whose history moved to another 2x2 block is occluded (filled spatially) when its old view depth differs from its neighbours' mean by `depth_tolerance` or more (CSO), or always (ASO)",
        ),
        aso_motion: AsoMotion = choice(
            AsoMotion::QuarterTexel,
            "which history ASO assumes occluded: `quarter-texel`, history that moved more than a quarter-resolution texel (2 pixels), as Intel's white paper (\"Assume Shading Occluded\": \"assumes occlusion for any shading information that moved more than a quarter-resolution texel\"); `block`, history that moved to another 2x2 block, as mosaiikki (`possiblyOccluded`: with ASO every moved static pixel is filled spatially)",
        ),
        depth_tolerance: f32 = float(
            (0.0, false, 1.0e9),
            0.01,
            "CSO tolerance in view-space units (mosaiikki's default); also how far behind its neighbours a dynamic surface of the velocity pass may be before a static occluder is assumed (`velocity_objects = \"dynamic\"`)",
        ),
        fill: Fill = choice(
            Fill::Differential,
            "missing pixels from the 4 neighbours: plain mean, mean under AMD's reversible tonemap, or mosaiikki's differential blend",
        ),
        clamp: Clamp = choice(
            Clamp::None,
            "history clamped to the neighbours' min/max (mosaiikki), optionally blended back by depth confidence; `none` as Intel",
        ),
        velocity: bool = flag(
            true,
            "full-resolution velocity pass for dynamic objects; recorded only when the scene has animated objects (otherwise culled)",
        ),
        velocity_objects: VelocityObjects = choice(
            VelocityObjects::Dynamic,
            "what the velocity pass draws: `dynamic` only the objects that move by themselves (mosaiikki, \"Only dynamic objects; for static objects camera reprojection is used in the reconstruction pass\"): no static overdraw in the pass; where its depth is behind this frame's neighbours' mean by `depth_tolerance` or more, a static object hides the moving one and the pixel is camera-reprojected. `all` every object: the buffer is exact there, at the static geometry's cost",
        ),
    }
}

pub struct Checkerboard;

impl Definition for Checkerboard {
    type Options = Options;

    fn name(&self) -> &'static str {
        "checkerboard"
    }

    /// 2x MSAA targets at the standard sample positions for `msaa2x`.
    fn requirements(&self, options: &Options) -> Requirements {
        match options.sampling {
            Sampling::Msaa2x => Requirements::none()
                .msaa(2, COLOR_FORMAT, "rgba16float")
                .msaa(2, DEPTH_FORMAT, "depth32float"),
            Sampling::TwoPass => Requirements::none(),
        }
    }

    /// Even and odd frames shade the two checkerboard parities.
    fn frames(&self, _options: &Options) -> FramePattern {
        FramePattern::Alternating
    }

    fn summary(&self) -> &'static str {
        "Intel's checkerboard rendering with mosaiikki's refinements: half the samples each frame, the other half reprojected"
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
        Ok(Box::new(CheckerboardGpu::new(
            cx.gpu,
            *options,
            t.width,
            t.height,
            t.dynamic_scene,
        )?))
    }

    fn shaders(&self) -> Vec<Shader> {
        use gpu::{MSAA2X_WGSL, RESOLVE_WGSL, TWO_PASS_WGSL};
        vec![
            Shader {
                name: "checkerboard two-pass".into(),
                source: format!("{TWO_PASS_WGSL}\n{RESOLVE_WGSL}"),
                files: vec!["checkerboard/two_pass.wgsl", "checkerboard/resolve.wgsl"],
            },
            Shader {
                name: "checkerboard msaa2x".into(),
                source: format!("{MSAA2X_WGSL}\n{RESOLVE_WGSL}"),
                files: vec!["checkerboard/msaa2x.wgsl", "checkerboard/resolve.wgsl"],
            },
        ]
    }
}
