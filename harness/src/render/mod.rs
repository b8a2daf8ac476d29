//! Rendering infrastructure that knows no technique: the world (`crate::world`) on the GPU
//! (`scene.rs`; textured models: `material.rs`, `texture.rs`, `mips.rs`),
//! the pass graph, per-pass timers, readback, the [`renderer::Renderer`] interface the run loop
//! drives, and a kit of GPU helpers techniques build with (`kit.rs`; the optional velocity pass,
//! `velocity.rs`). Techniques are in `techniques/`.

pub mod formats;
pub mod frame_check;
pub mod graph;
pub mod kit;
pub mod material;
pub mod mips;
pub mod motion_blur;
pub mod readback;
pub mod renderer;
pub mod scene;
pub mod texture;
pub mod timers;
pub mod velocity;
