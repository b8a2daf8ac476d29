//! Rendering: scene geometry and passes on the GPU, the pass graph, and the techniques built on them.

pub mod adaptive;
pub mod adaptive_model;
pub mod checkerboard;
pub mod checkerboard_2x2;
pub mod checkerboard_2x2_model;
pub mod checkerboard_model;
pub mod graph;
pub mod mesh;
pub mod readback;
pub mod scene;
pub mod technique;
pub mod timers;
