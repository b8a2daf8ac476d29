//! Textured materials on the CPU: what a model is ([`Model`]: vertices with texture coordinates
//! and tangents, glTF 2.0 metallic-roughness [`Material`]s, their images, parts) and where its
//! parts are drawn ([`Placement`]: a run of consecutive scene objects). Built by the glTF loader
//! (`gltf_model.rs`) and the city (`city.rs`); drawn by `render/material.rs`.

use bytemuck::{Pod, Zeroable};
use glam::{Mat3, Vec2, Vec3, Vec4};

use super::texture::{Encoding, Image, SamplerDesc};

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct MaterialVertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    /// glTF `TEXCOORD_0`.
    pub uv: [f32; 2],
    /// xyz: tangent (along +u); w: handedness of the bitangent (+1 or -1). Zero: no tangent.
    pub tangent: [f32; 4],
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaMode {
    Opaque,
    /// Alpha test: fragments with base-colour alpha below the cutoff are discarded.
    Mask {
        cutoff: f32,
    },
    Blend,
}

/// Which BRDF a material is shaded with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Brdf {
    /// The procedural scenes' shading (Lambert plus a Blinn-Phong lobe of exponent 48).
    BlinnPhong,
    /// glTF 2.0's metallic-roughness model: GGX distribution, height-correlated Smith
    /// visibility, Schlick Fresnel, Lambert diffuse (glTF 2.0 spec, appendix B).
    Ggx,
}

/// An affine map of texture coordinates (`KHR_texture_transform`): offset, rotation (radians,
/// counter-clockwise in uv) and scale, applied as translation * rotation * scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    pub offset: Vec2,
    pub rotation: f32,
    pub scale: Vec2,
}

impl UvTransform {
    pub const IDENTITY: UvTransform = UvTransform {
        offset: Vec2::ZERO,
        rotation: 0.0,
        scale: Vec2::ONE,
    };

    /// The two rows of the 2x3 matrix, as the shader reads them.
    pub fn rows(&self) -> [[f32; 4]; 2] {
        let (s, c) = self.rotation.sin_cos();
        // The extension's rotation matrix is [cos sin; -sin cos].
        let m = Mat3::from_cols(
            Vec3::new(c * self.scale.x, -s * self.scale.x, 0.0),
            Vec3::new(s * self.scale.y, c * self.scale.y, 0.0),
            Vec3::new(self.offset.x, self.offset.y, 1.0),
        );
        [
            [m.x_axis.x, m.y_axis.x, m.z_axis.x, 0.0],
            [m.x_axis.y, m.y_axis.y, m.z_axis.y, 0.0],
        ]
    }
}

/// One texture slot of a material: which of the model's images, sampled how.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    pub image: usize,
    pub sampler: SamplerDesc,
    pub transform: UvTransform,
}

/// The texture slots, in the order of the shader's bindings.
pub const SLOTS: [&str; 5] = [
    "base colour",
    "metallic-roughness",
    "normal",
    "occlusion",
    "emissive",
];

/// A material: glTF 2.0's metallic-roughness parameters and textures.
#[derive(Clone, Debug)]
pub struct Material {
    pub name: String,
    /// Linear RGBA, multiplied with the base-colour texture.
    pub base_color: Vec4,
    pub metallic: f32,
    pub roughness: f32,
    /// Linear radiance (emissive strength applied), multiplied with the emissive texture.
    pub emissive: Vec3,
    pub normal_scale: f32,
    pub occlusion_strength: f32,
    pub alpha: AlphaMode,
    pub brdf: Brdf,
    /// Blinn-Phong's specular weight (unused by GGX).
    pub specular: f32,
    /// Per slot of [`SLOTS`]: base colour (sRGB), metallic-roughness (B metal, G rough), normal
    /// (tangent space), occlusion (R), emissive (sRGB).
    pub textures: [Option<TextureRef>; 5],
}

impl Material {
    /// glTF's default material (a primitive that names none): white, fully metallic and rough.
    pub fn gltf_default() -> Material {
        Material {
            name: "default".into(),
            base_color: Vec4::ONE,
            metallic: 1.0,
            roughness: 1.0,
            emissive: Vec3::ZERO,
            normal_scale: 1.0,
            occlusion_strength: 1.0,
            alpha: AlphaMode::Opaque,
            brdf: Brdf::Ggx,
            specular: 0.0,
            textures: [None; 5],
        }
    }

    /// The encoding slot `i`'s image is uploaded with.
    pub fn slot_encoding(i: usize) -> Encoding {
        if i == 0 || i == 4 {
            Encoding::Srgb
        } else {
            Encoding::Linear
        }
    }
}

/// A range of a model's indices drawn with one material.
#[derive(Clone, Debug)]
pub struct Primitive {
    pub first_index: u32,
    pub index_count: u32,
    pub material: usize,
    /// Centre of its bounds in the part's space: the sort key of blended draws.
    pub center: Vec3,
}

/// Textured geometry: vertices and indices (relative to the model's first vertex), the images
/// its materials sample (each with the encoding it is uploaded in), and parts (lists of
/// primitives) that placements instance.
#[derive(Clone, Debug, Default)]
pub struct Model {
    pub name: String,
    pub vertices: Vec<MaterialVertex>,
    pub indices: Vec<u32>,
    pub images: Vec<(Image, Encoding)>,
    pub materials: Vec<Material>,
    pub parts: Vec<Vec<Primitive>>,
}

impl Model {
    pub fn triangles(&self) -> usize {
        self.indices.len() / 3
    }
}

/// `count` instances of a model's `part`, drawn as scene objects `first_object..+count`.
#[derive(Clone, Copy, Debug)]
pub struct Placement {
    pub part: usize,
    pub first_object: u32,
    pub count: u32,
}

/// Per-vertex tangents from positions, normals and texture coordinates (Lengyel's method:
/// per-triangle tangents accumulated per vertex, Gram-Schmidt against the normal, handedness from
/// -dP/dv). Vertices without a usable uv gradient keep a zero tangent (no normal mapping).
pub fn generate_tangents(vertices: &mut [MaterialVertex], indices: &[u32]) {
    let mut tan = vec![Vec3::ZERO; vertices.len()];
    let mut bit = vec![Vec3::ZERO; vertices.len()];
    for tri in indices.chunks_exact(3) {
        let [a, b, c] = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
        let (p0, p1, p2) = (
            Vec3::from(vertices[a].position),
            Vec3::from(vertices[b].position),
            Vec3::from(vertices[c].position),
        );
        let (t0, t1, t2) = (
            Vec2::from(vertices[a].uv),
            Vec2::from(vertices[b].uv),
            Vec2::from(vertices[c].uv),
        );
        let (e1, e2) = (p1 - p0, p2 - p0);
        let (d1, d2) = (t1 - t0, t2 - t0);
        let det = d1.x * d2.y - d2.x * d1.y;
        if det.abs() < 1e-20 {
            continue;
        }
        let r = 1.0 / det;
        let du = (e1 * d2.y - e2 * d1.y) * r;
        let dv = (e2 * d1.x - e1 * d2.x) * r;
        for i in [a, b, c] {
            tan[i] += du;
            bit[i] += dv;
        }
    }
    for (i, v) in vertices.iter_mut().enumerate() {
        let n = Vec3::from(v.normal);
        let t = (tan[i] - n * n.dot(tan[i])).normalize_or_zero();
        if t == Vec3::ZERO {
            v.tangent = [0.0; 4];
            continue;
        }
        // glTF's v grows down the image and a normal map's +y points up it: the bitangent is
        // -dP/dv, and w says whether it is n x t (+1) or its opposite.
        let w = if n.cross(t).dot(bit[i]) > 0.0 {
            -1.0
        } else {
            1.0
        };
        v.tangent = [t.x, t.y, t.z, w];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tangents_follow_increasing_u_with_handedness() {
        // A quad in the xy plane, normal +z, u along +x, v along -y (glTF's v points down).
        let v = |x: f32, y: f32, u: f32, w: f32| MaterialVertex {
            position: [x, y, 0.0],
            normal: [0.0, 0.0, 1.0],
            uv: [u, w],
            tangent: [0.0; 4],
        };
        let mut verts = vec![
            v(0.0, 0.0, 0.0, 1.0),
            v(1.0, 0.0, 1.0, 1.0),
            v(1.0, 1.0, 1.0, 0.0),
            v(0.0, 1.0, 0.0, 0.0),
        ];
        generate_tangents(&mut verts, &[0, 1, 2, 0, 2, 3]);
        for t in &verts {
            assert!((Vec3::from_slice(&t.tangent[..3]) - Vec3::X).length() < 1e-5);
            // Bitangent along -v = +y = n x t: right-handed.
            assert_eq!(t.tangent[3], 1.0);
        }
        // Mirrored u: the tangent flips, the handedness too.
        for t in verts.iter_mut() {
            t.uv[0] = 1.0 - t.uv[0];
        }
        generate_tangents(&mut verts, &[0, 1, 2, 0, 2, 3]);
        assert!((Vec3::from_slice(&verts[0].tangent[..3]) + Vec3::X).length() < 1e-5);
        assert_eq!(verts[0].tangent[3], -1.0);
    }

    #[test]
    fn uv_transform_rows_match_the_extension() {
        let t = UvTransform {
            offset: Vec2::new(0.5, 0.25),
            rotation: std::f32::consts::FRAC_PI_2,
            scale: Vec2::new(2.0, 3.0),
        };
        let r = t.rows();
        let apply = |uv: Vec2| {
            Vec2::new(
                r[0][0] * uv.x + r[0][1] * uv.y + r[0][2],
                r[1][0] * uv.x + r[1][1] * uv.y + r[1][2],
            )
        };
        // Scale (1, 0) -> (2, 0); rotate by [cos sin; -sin cos] at 90 degrees -> (0, -2); offset.
        let p = apply(Vec2::X);
        assert!((p - Vec2::new(0.5, -1.75)).length() < 1e-5, "{p}");
        let p = apply(Vec2::Y);
        assert!((p - Vec2::new(3.5, 0.25)).length() < 1e-5, "{p}");
    }
}
