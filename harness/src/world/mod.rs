//! The world a scenario draws, on the CPU: the scene and camera track (`scene.rs`, the validated
//! types a scenario builds), meshes of procedural shapes (`mesh.rs`), glTF 2.0 files as textured
//! models (`gltf_model.rs`), the generated city (`city.rs`), what a textured model is
//! (`material.rs`, `texture.rs`), and all of a scene's geometry in the renderer's object order
//! (`geometry.rs`). The ground floor of rendering: no GPU code, and it imports nothing of the
//! harness above it (not `scenario/`, `render/`, `techniques/` or `run/`); `scenario/` builds
//! it, `render/` draws it.

pub mod city;
pub mod geometry;
pub mod gltf_model;
pub mod material;
pub mod mesh;
pub mod scene;
pub mod texture;
