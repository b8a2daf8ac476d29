//! Techniques: one folder each (its definition and options, its GPU part, its CPU model, its
//! shaders), and the registry that lists them.
//!
//! A folder depends on `params`, `render/` (infrastructure that knows no technique), `world/`
//! and `gpu`; `registry.rs` depends on the folders; nothing here depends on `run/` or on
//! scenarios (only on what they draw, `world/`, mostly through `render/`). `upscale` reuses `native`'s forward
//! path. What the run loop needs of the reference and of exact motion is asked here, by role
//! ([`is_reference`], [`reference`], [`MotionPass`]), so `run/` names no technique.

pub mod adaptive_shading;
pub mod checkerboard;
pub mod checkerboard_2x2;
pub mod definition;
pub mod docs;
pub mod fsr1;
pub mod fsr2;
pub mod interlace;
pub mod native;
pub mod options;
pub mod registry;
pub mod shared;
pub mod taau;
pub mod upscale;

pub use definition::{
    variant_name, BuildContext, Definition, FramePattern, Shader, Target, Technique, Variant,
};
pub use options::DeclaredOptions;
pub use registry::{by_name, names, ALL};

use crate::gpu::{Gpu, Requirements};
use crate::render::graph::Plan;
use crate::render::renderer::{Renderer, Unsupported};

/// The pass graph of `variant` at `target`, without a GPU.
pub fn plan(variant: &Variant, target: Target) -> Plan {
    variant.technique.plan(variant, target)
}

/// What `variant` needs of an adapter, without a GPU.
pub fn requirements(variant: &Variant) -> Requirements {
    variant.technique.requirements(variant)
}

/// Why `variant` may be skipped, in words, without a GPU: its [`Requirements`], each as the skip
/// reason says it, and where it is skipped (`tessera validate`, the plan). Empty when every
/// adapter can run it.
pub fn skip_reasons(variant: &Variant) -> Vec<String> {
    let r = requirements(variant);
    let where_ = if r.hardware_only() {
        "skipped without a GPU that offers it"
    } else {
        "skipped on adapters without it"
    };
    r.describe()
        .into_iter()
        .map(|need| format!("{need} ({where_})"))
        .collect()
}

/// Why `variant` is skipped on `scene` on every adapter (it cannot draw the scene's textured
/// models), for `tessera validate`; `None` when it draws the scene.
pub fn scene_skip_reason(variant: &Variant, scene: &crate::world::scene::Scene) -> Option<String> {
    if !scene.has_textured_models() {
        return None;
    }
    variant.technique.textured(variant).err()
}

/// Builds `variant` in `cx`: unsupported when the adapter's texture size limit is exceeded, when
/// it lacks one of the variant's [`Requirements`], when it cannot draw the scene's textured
/// models, or when the technique says so.
pub fn build(variant: &Variant, cx: &BuildContext<'_>) -> Result<Box<dyn Renderer>, Unsupported> {
    cx.gpu.check_size(cx.target.width, cx.target.height)?;
    requirements(variant).check(cx.gpu)?;
    if cx.scene.has_materials() {
        variant.technique.textured(variant).map_err(Unsupported)?;
    }
    variant.technique.build(variant, cx)
}

/// Whether `variant` is the technique a `reference = "native"` scenario is diffed against.
pub fn is_reference(variant: &Variant) -> bool {
    variant.technique.name() == native::NAME
}

/// Whether `name`, a recorded result's technique or variant name, is the reference technique's
/// (`native` has no parameters: its one variant carries its name). What `run/` asks of results
/// by role, so it names no technique.
pub fn is_reference_name(name: &str) -> bool {
    name == native::NAME
}

/// The reference renderer: native at the target, or with `supersample` the ground truth (native
/// at `supersample`x per axis, box-downsampled).
pub fn reference(
    supersample: Option<u32>,
    cx: &BuildContext<'_>,
) -> Result<Box<dyn Renderer>, Unsupported> {
    match supersample {
        Some(n) => native::ground_truth(cx.gpu, cx.target.width, cx.target.height, n),
        None => build(&Variant::with_defaults(&native::Native), cx),
    }
}

/// The converged reference: `samples` jittered renders per frame at the target's size, averaged
/// (`native/converged.rs`).
pub fn converged_reference(
    samples: u32,
    cx: &BuildContext<'_>,
) -> Result<Box<dyn Renderer>, Unsupported> {
    native::converged::converged(cx.gpu, cx.target.width, cx.target.height, samples)
}

/// The scene's exact motion: the velocity pass alone at output resolution (what the `tde`
/// metric reads): [`MotionPass::motion`] is the motion target, [`MotionPass::depth`] its depth.
pub struct MotionPass(native::Forward);

impl MotionPass {
    pub fn new(gpu: &Gpu, width: u32, height: u32) -> MotionPass {
        MotionPass(native::Forward::velocity_only(gpu, width, height))
    }

    /// What the run loop records each frame.
    pub fn renderer(&mut self) -> &mut dyn Renderer {
        &mut self.0
    }

    pub fn motion(&self) -> &wgpu::Texture {
        self.0.output()
    }

    pub fn depth(&self) -> &wgpu::Texture {
        self.0.depth()
    }
}

/// Every WGSL module of every technique (and the adapter probe's), for validation without a
/// GPU.
pub fn shaders() -> Vec<Shader> {
    let mut all = vec![
        Shader::file("sample_positions.wgsl", crate::gpu::PROBE_WGSL),
        // Textured materials and their mip chains (`render/material.rs`, `render/mips.rs`),
        // drawn by every technique that uses the scene's forward pipelines.
        Shader {
            name: "material".into(),
            source: crate::render::material::material_wgsl(),
            files: vec!["scene.wgsl", "material/material.wgsl"],
        },
        Shader::file("material/mips.wgsl", crate::render::mips::MIPS_WGSL),
        // The run loop's per-frame NaN / coverage check on frames kept on the GPU.
        Shader::file(
            "frame_check.wgsl",
            crate::render::frame_check::FRAME_CHECK_WGSL,
        ),
        // The motion-blurred comparison (`reference.motion_blur`, `run/motion_blur.rs`).
        Shader::file(
            "motion_blur.wgsl",
            crate::render::motion_blur::MOTION_BLUR_WGSL,
        ),
    ];
    for t in ALL {
        all.extend(t.shaders());
    }
    all
}
