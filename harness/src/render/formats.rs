//! What every draw of the scene agrees on: the colour and depth formats of its targets, the scene
//! shader, and which of its pipelines a draw uses. Its own module so that the scene
//! (`scene.rs`) and the textured materials (`material.rs`) share it without importing each other.
//! Not for buffers or draws: those are `scene.rs`'s.

pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

pub static SCENE_WGSL: &str = include_str!("../../../shaders/scene.wgsl");

/// The scene shader's pipelines.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ScenePipeline {
    /// `fs_main`, shaded once per pixel.
    Forward { samples: u32 },
    /// `fs_main_sample`, shaded once per sample (checkerboard's 2x MSAA sampling).
    PerSample { samples: u32 },
    /// `fs_velocity`: screen motion in pixels, z = 1 on dynamic objects.
    Velocity,
}
