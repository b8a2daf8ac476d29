//! Techniques: one folder each (its definition and options, its GPU part, its CPU model; its
//! shaders under `shaders/<folder>/`), and the registry that lists them.
//!
//! A folder depends on `params`, `render/` (infrastructure that knows no technique) and `gpu`;
//! `registry.rs` depends on the folders; nothing here depends on `run/`. `upscale` reuses
//! `native`'s forward path.

pub mod adaptive_shading;
pub mod checkerboard;
pub mod checkerboard_2x2;
pub mod definition;
pub mod docs;
pub mod interlace;
pub mod native;
pub mod registry;
pub mod upscale;

pub use definition::{Shader, Target, Technique};
pub use registry::{by_name, names, ALL};

use crate::gpu::Gpu;
use crate::params::Variant;
use crate::render::graph::Plan;
use crate::render::renderer::{Renderer, Unsupported};

/// The pass graph of `variant` at `target`, without a GPU.
pub fn plan(variant: &Variant, target: Target) -> Plan {
    variant.technique.plan(variant, target)
}

/// Builds `variant` on `gpu` at `target`: unsupported when the adapter's texture size limit is
/// exceeded or the technique says so.
pub fn build(
    gpu: &Gpu,
    variant: &Variant,
    target: Target,
) -> Result<Box<dyn Renderer>, Unsupported> {
    gpu.check_size(target.width, target.height)?;
    variant.technique.build(gpu, variant, target)
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
    ];
    for t in ALL {
        all.extend(t.shaders());
    }
    all
}
