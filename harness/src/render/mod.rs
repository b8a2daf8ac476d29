//! Rendering infrastructure that knows no technique: the scene on the GPU (`scene.rs`, `mesh.rs`),
//! the pass graph, per-pass timers, readback, the [`renderer::Renderer`] interface the run loop
//! drives, and a kit of GPU helpers techniques build with. Techniques are in `techniques/`.

pub mod graph;
pub mod kit;
pub mod mesh;
pub mod readback;
pub mod renderer;
pub mod scene;
pub mod timers;
