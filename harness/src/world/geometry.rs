//! A scene's geometry on the CPU, in the order of the objects buffer the renderer fills: the
//! ground quad, the scenario's objects (procedural shapes and `materials = "color"` meshes, one
//! vertex and index list with a draw per object; a textured glTF object keeps its slot as an
//! empty draw and becomes a model), then the generated city's objects and model. What
//! `render/scene.rs` uploads; the upload itself (and any GPU object) is not here.

use super::city::{self, CityObject};
use super::gltf_model;
use super::material::{Model, Placement};
use super::mesh::{self, Mesh, MeshError, Vertex};
use super::scene::{Scene, Shape};

/// A draw: one object's index range.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Draw {
    pub first_index: u32,
    pub index_count: u32,
    pub base_vertex: i32,
}

/// Everything a scene draws, built once per scenario.
#[derive(Debug)]
pub struct Geometry {
    /// The untextured meshes' vertices, one after the other.
    pub vertices: Vec<Vertex>,
    /// Their indices, relative to each draw's `base_vertex`.
    pub indices: Vec<u32>,
    /// Per object of the ground and the scenario (its instance index): its index range.
    pub draws: Vec<Draw>,
    /// Textured models (glTF materials, the city) with the objects that instance their parts.
    pub models: Vec<(Model, Vec<Placement>)>,
    /// The city's objects, after the scenario's in the objects buffer.
    pub city_objects: Vec<CityObject>,
    /// Per object of the objects buffer: whether it moves by itself.
    pub dynamic: Vec<bool>,
    /// Triangles of the untextured meshes (a model counts its own).
    pub triangles: usize,
}

impl Geometry {
    /// Builds `scene`'s geometry: loads its glTF files and generates the city.
    pub fn build(scene: &Scene) -> Result<Geometry, MeshError> {
        let mut meshes: Vec<Mesh> = Vec::new();
        if let Some(g) = &scene.ground {
            meshes.push(mesh::ground_quad(g.size));
        }
        // Textured objects keep their slot in the objects buffer (an empty untextured mesh) and
        // are drawn by the material path.
        let mut models: Vec<(Model, Vec<Placement>)> = Vec::new();
        for o in &scene.objects {
            match &o.shape {
                Shape::Mesh {
                    path,
                    scale,
                    textured: true,
                } => {
                    let placement = Placement {
                        part: 0,
                        first_object: meshes.len() as u32,
                        count: 1,
                    };
                    models.push((gltf_model::load(path, *scale)?, vec![placement]));
                    meshes.push(Mesh::default());
                }
                shape => meshes.push(mesh::build(shape)?),
            }
        }
        let mut city_objects = Vec::new();
        if let Some(c) = &scene.city {
            let generated = city::generate(c, meshes.len() as u32);
            city_objects = generated.objects;
            models.push((generated.model, generated.placements));
        }
        // In the objects buffer's order (`write_objects`): the ground (static: it follows the
        // camera, its pattern stays in world space), the scenario's objects (textured ones too),
        // the city's.
        let dynamic: Vec<bool> = (scene.ground.iter().map(|_| false))
            .chain(scene.objects.iter().map(|o| o.animation.is_some()))
            .chain(city_objects.iter().map(|c| c.is_dynamic()))
            .collect();
        let mut vertices: Vec<Vertex> = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        let mut draws = Vec::new();
        for m in &meshes {
            draws.push(Draw {
                first_index: indices.len() as u32,
                index_count: m.indices.len() as u32,
                base_vertex: vertices.len() as i32,
            });
            vertices.extend_from_slice(&m.vertices);
            indices.extend_from_slice(&m.indices);
        }
        let triangles = indices.len() / 3;
        Ok(Geometry {
            vertices,
            indices,
            draws,
            models,
            city_objects,
            dynamic,
            triangles,
        })
    }
}
