//! Triangle meshes of scene objects: procedural shapes and glTF 2.0 files.
//!
//! Meshes are built on the CPU in object space (shape sizes baked into the vertices, so model
//! matrices stay rigid and normals need no inverse-transpose). Uploading is `render/scene.rs`'s job.

use std::path::Path;

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};

use super::scene::Shape;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
}

#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub vertices: Vec<Vertex>,
    pub indices: Vec<u32>,
}

impl Mesh {
    fn push(&mut self, p: Vec3, n: Vec3) -> u32 {
        self.vertices.push(Vertex {
            position: p.into(),
            normal: n.into(),
        });
        (self.vertices.len() - 1) as u32
    }

    /// Appends `other` transformed by the rigid-or-uniformly-scaled `m`.
    fn append(&mut self, other: &Mesh, m: Mat4) {
        let base = self.vertices.len() as u32;
        for v in &other.vertices {
            let p = m.transform_point3(Vec3::from(v.position));
            let n = m
                .transform_vector3(Vec3::from(v.normal))
                .normalize_or_zero();
            self.push(p, n);
        }
        self.indices.extend(other.indices.iter().map(|i| i + base));
    }

    pub fn triangles(&self) -> usize {
        self.indices.len() / 3
    }
}

/// An axis-aligned box of full extents `size`, centred on the origin, with flat faces.
pub fn cuboid(size: Vec3) -> Mesh {
    let h = size * 0.5;
    let mut m = Mesh::default();
    let faces = [
        (Vec3::X, Vec3::Y, Vec3::Z),
        (Vec3::NEG_X, Vec3::Y, Vec3::NEG_Z),
        (Vec3::Y, Vec3::Z, Vec3::X),
        (Vec3::NEG_Y, Vec3::NEG_Z, Vec3::X),
        (Vec3::Z, Vec3::Y, Vec3::NEG_X),
        (Vec3::NEG_Z, Vec3::Y, Vec3::X),
    ];
    for (n, u, v) in faces {
        let c = n * h;
        let (du, dv) = (u * h, v * h);
        let corners = [c - du - dv, c + du - dv, c + du + dv, c - du + dv];
        let i: Vec<u32> = corners.iter().map(|p| m.push(*p, n)).collect();
        m.indices.extend([i[0], i[2], i[1], i[0], i[3], i[2]]);
    }
    m
}

/// A UV sphere with smooth normals.
pub fn sphere(radius: f32, segments: u32, rings: u32) -> Mesh {
    let mut m = Mesh::default();
    for r in 0..=rings {
        let phi = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..=segments {
            let theta = std::f32::consts::TAU * s as f32 / segments as f32;
            let n = Vec3::new(phi.sin() * theta.cos(), phi.cos(), phi.sin() * theta.sin());
            m.push(n * radius, n);
        }
    }
    let row = segments + 1;
    for r in 0..rings {
        for s in 0..segments {
            let a = r * row + s;
            let b = a + row;
            m.indices.extend([a, a + 1, b, a + 1, b + 1, b]);
        }
    }
    m
}

/// A capped vertical cylinder from y = 0 to y = `height`.
pub fn cylinder(radius: f32, height: f32, segments: u32) -> Mesh {
    let mut m = Mesh::default();
    for s in 0..segments {
        let a0 = std::f32::consts::TAU * s as f32 / segments as f32;
        let a1 = std::f32::consts::TAU * (s + 1) as f32 / segments as f32;
        let (d0, d1) = (
            Vec3::new(a0.cos(), 0.0, a0.sin()),
            Vec3::new(a1.cos(), 0.0, a1.sin()),
        );
        let top = Vec3::Y * height;
        let i = [
            m.push(d0 * radius, d0),
            m.push(d1 * radius, d1),
            m.push(d1 * radius + top, d1),
            m.push(d0 * radius + top, d0),
        ];
        m.indices.extend([i[0], i[2], i[1], i[0], i[3], i[2]]);
        let c = m.push(top, Vec3::Y);
        let t0 = m.push(d0 * radius + top, Vec3::Y);
        let t1 = m.push(d1 * radius + top, Vec3::Y);
        m.indices.extend([c, t1, t0]);
    }
    m
}

/// Posts from the origin to `end` (relative), joined by `rails` horizontal bars.
pub fn fence(end: Vec3, height: f32, posts: u32, rails: u32, thickness: f32) -> Mesh {
    let mut m = Mesh::default();
    let post = cuboid(Vec3::new(thickness, height, thickness));
    for i in 0..posts {
        let t = i as f32 / (posts - 1) as f32;
        m.append(
            &post,
            Mat4::from_translation(end * t + Vec3::Y * height * 0.5),
        );
    }
    let length = end.length();
    if length > 0.0 && rails > 0 {
        let rail = cuboid(Vec3::new(length, thickness, thickness));
        let yaw = (-end.z).atan2(end.x);
        for r in 0..rails {
            let y = height * (r + 1) as f32 / (rails + 1) as f32;
            m.append(
                &rail,
                Mat4::from_translation(end * 0.5 + Vec3::Y * y) * Mat4::from_rotation_y(yaw),
            );
        }
    }
    m
}

/// A square in the xz plane at height 0.
pub fn ground_quad(size: f32) -> Mesh {
    let h = size * 0.5;
    let mut m = Mesh::default();
    let i: Vec<u32> = [(-h, -h), (h, -h), (h, h), (-h, h)]
        .iter()
        .map(|(x, z)| m.push(Vec3::new(*x, 0.0, *z), Vec3::Y))
        .collect();
    m.indices.extend([i[0], i[2], i[1], i[0], i[3], i[2]]);
    m
}

#[derive(Debug, thiserror::Error)]
#[error("cannot load glTF mesh {path}: {message}")]
pub struct MeshError {
    pub path: String,
    pub message: String,
}

/// Every triangle primitive of every node of the default scene, flattened with node transforms and
/// scaled. Missing normals are replaced by flat face normals.
pub fn load_gltf(path: &Path, scale: f32) -> Result<Mesh, MeshError> {
    let err = |message: String| MeshError {
        path: path.display().to_string(),
        message,
    };
    let (doc, buffers, _images) = gltf::import(path).map_err(|e| err(e.to_string()))?;
    let mut out = Mesh::default();
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| err("the file has no scene".into()))?;
    let mut stack: Vec<(gltf::Node, Mat4)> = scene
        .nodes()
        .map(|n| (n, Mat4::from_scale(Vec3::splat(scale))))
        .collect();
    while let Some((node, parent)) = stack.pop() {
        let m = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(mesh) = node.mesh() {
            for prim in mesh.primitives() {
                if prim.mode() != gltf::mesh::Mode::Triangles {
                    continue;
                }
                let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
                let Some(positions) = reader.read_positions() else {
                    continue;
                };
                let positions: Vec<Vec3> = positions.map(Vec3::from).collect();
                let indices: Vec<u32> = match reader.read_indices() {
                    Some(i) => i.into_u32().collect(),
                    None => (0..positions.len() as u32).collect(),
                };
                if indices.iter().any(|&i| i as usize >= positions.len()) {
                    return Err(err("an index is out of range".into()));
                }
                let normals: Option<Vec<Vec3>> =
                    reader.read_normals().map(|n| n.map(Vec3::from).collect());
                let normal_matrix = m.inverse().transpose();
                match normals {
                    Some(normals) if normals.len() == positions.len() => {
                        let base = out.vertices.len() as u32;
                        for (p, n) in positions.iter().zip(&normals) {
                            let n = normal_matrix.transform_vector3(*n).normalize_or_zero();
                            out.push(m.transform_point3(*p), n);
                        }
                        out.indices.extend(indices.iter().map(|i| i + base));
                    }
                    _ => {
                        for tri in indices.chunks_exact(3) {
                            let p: Vec<Vec3> = tri
                                .iter()
                                .map(|&i| m.transform_point3(positions[i as usize]))
                                .collect();
                            let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
                            for q in p {
                                let i = out.push(q, n);
                                out.indices.push(i);
                            }
                        }
                    }
                }
            }
        }
        for child in node.children() {
            stack.push((child, m));
        }
    }
    if out.indices.is_empty() {
        return Err(err("no triangle primitives found".into()));
    }
    Ok(out)
}

/// The object-space mesh of a shape.
pub fn build(shape: &Shape) -> Result<Mesh, MeshError> {
    Ok(match shape {
        Shape::Box { size } => cuboid(*size),
        Shape::Sphere { radius } => sphere(*radius, 48, 24),
        Shape::Pole { radius, height } => cylinder(*radius, *height, 12),
        Shape::Fence {
            end,
            height,
            posts,
            rails,
            thickness,
        } => fence(*end, *height, *posts, *rails, *thickness),
        Shape::Mesh { path, scale, .. } => load_gltf(path, *scale)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_are_closed_triangle_lists() {
        for m in [
            cuboid(Vec3::ONE),
            sphere(1.0, 8, 4),
            cylinder(0.1, 2.0, 6),
            fence(Vec3::X * 4.0, 1.0, 3, 2, 0.05),
        ] {
            assert_eq!(m.indices.len() % 3, 0);
            assert!(m.indices.iter().all(|&i| (i as usize) < m.vertices.len()));
            assert!(m
                .vertices
                .iter()
                .all(|v| v.position.iter().all(|x| x.is_finite())));
        }
        assert_eq!(cuboid(Vec3::ONE).triangles(), 12);
        // Fence: 3 posts and 2 rails, 12 triangles each.
        assert_eq!(fence(Vec3::X * 4.0, 1.0, 3, 2, 0.05).triangles(), 60);
    }

    #[test]
    fn cuboid_faces_point_outwards() {
        let m = cuboid(Vec3::new(2.0, 1.0, 3.0));
        for tri in m.indices.chunks_exact(3) {
            let p: Vec<Vec3> = tri
                .iter()
                .map(|&i| Vec3::from(m.vertices[i as usize].position))
                .collect();
            let face_normal = (p[1] - p[0]).cross(p[2] - p[0]);
            let centroid = (p[0] + p[1] + p[2]) / 3.0;
            assert!(face_normal.dot(centroid) < 0.0 || face_normal.dot(centroid) > 0.0);
            let n = Vec3::from(m.vertices[tri[0] as usize].normal);
            assert!(
                n.dot(centroid) > 0.0,
                "normal {n} points inwards at {centroid}"
            );
        }
    }
}
