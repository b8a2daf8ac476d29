//! glTF 2.0 files as textured [`Model`]s: every triangle primitive of the default scene's node
//! hierarchy (node transforms baked into the vertices, scaled), its metallic-roughness material,
//! textures, samplers and `KHR_texture_transform`s.
//!
//! A file Tessera cannot draw as its author meant is an error naming the file and what is wrong
//! (a missing buffer or image file, an index out of range, attribute arrays of different lengths,
//! a node that is its own ancestor, a required extension it does not implement, a second texture
//! coordinate set), never a silently different picture. Not here: the untextured mesh path of
//! `materials = "color"` (`mesh.rs`), the GPU side (`render/material.rs`).

use std::collections::HashMap;
use std::path::Path;

use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};

use super::material::{
    generate_tangents, AlphaMode, Brdf, Material, MaterialVertex, Model, Primitive, TextureRef,
    UvTransform,
};
use super::mesh::MeshError;
use super::texture::{Encoding, Image, SamplerDesc, Wrap};

/// Required extensions the loader implements (anything else in `extensionsRequired` is refused).
pub const SUPPORTED_EXTENSIONS: [&str; 2] =
    ["KHR_texture_transform", "KHR_materials_emissive_strength"];

/// Loads `path` as one model of one part (every primitive), scaled by `scale`.
pub fn load(path: &Path, scale: f32) -> Result<Model, MeshError> {
    let err = |message: String| MeshError {
        path: path.display().to_string(),
        message,
    };
    let gltf::Gltf {
        document: doc,
        blob,
    } = gltf::Gltf::open(path).map_err(|e| err(e.to_string()))?;
    for ext in doc.extensions_required() {
        if !SUPPORTED_EXTENSIONS.contains(&ext) {
            return Err(err(format!(
                "the file requires extension {ext}, which Tessera does not implement (supported: {})",
                SUPPORTED_EXTENSIONS.join(", ")
            )));
        }
    }
    let base = path.parent().unwrap_or(Path::new("."));
    let missing = |what: &str, i: usize, uri: &str| -> Option<MeshError> {
        if uri.starts_with("data:") {
            return None;
        }
        let file = base.join(percent_decode(uri));
        (!file.is_file()).then(|| {
            err(format!(
                "{what} {i} refers to {uri}, which does not exist ({})",
                file.display()
            ))
        })
    };
    for b in doc.buffers() {
        if let gltf::buffer::Source::Uri(uri) = b.source() {
            if let Some(e) = missing("buffer", b.index(), uri) {
                return Err(e);
            }
        }
    }
    for im in doc.images() {
        if let gltf::image::Source::Uri { uri, .. } = im.source() {
            if let Some(e) = missing("image", im.index(), uri) {
                return Err(e);
            }
        }
    }
    let buffers = gltf::import_buffers(&doc, Some(base), blob).map_err(|e| err(e.to_string()))?;
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| err("the file has no scene".into()))?;

    let mut model = Model {
        name: path.display().to_string(),
        ..Default::default()
    };
    // Images are decoded only when a material uses them, once per encoding.
    let mut image_index: HashMap<(usize, Encoding), usize> = HashMap::new();
    let mut decoded: HashMap<usize, Image> = HashMap::new();
    let mut material_index: HashMap<Option<usize>, usize> = HashMap::new();
    let mut primitives = Vec::new();

    let root = Mat4::from_scale(Vec3::splat(scale));
    let mut stack: Vec<(gltf::Node, Mat4, Vec<usize>)> =
        scene.nodes().map(|n| (n, root, Vec::new())).collect();
    while let Some((node, parent, ancestors)) = stack.pop() {
        if ancestors.contains(&node.index()) {
            return Err(err(format!("node {} is its own ancestor", node.index())));
        }
        let m = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(mesh) = node.mesh() {
            for (pi, prim) in mesh.primitives().enumerate() {
                if prim.mode() != gltf::mesh::Mode::Triangles {
                    continue;
                }
                let at = format!("mesh {} primitive {pi}", mesh.index());
                let material = prim.material();
                let mi = match material_index.get(&material.index()) {
                    Some(&i) => i,
                    None => {
                        let mat = read_material(
                            &material,
                            base,
                            &buffers,
                            &mut decoded,
                            &mut image_index,
                            &mut model.images,
                        )
                        .map_err(err)?;
                        model.materials.push(mat);
                        material_index.insert(material.index(), model.materials.len() - 1);
                        model.materials.len() - 1
                    }
                };
                let needs_tangents = model.materials[mi].textures[2].is_some();
                let p = read_primitive(&prim, &buffers, m, needs_tangents, &mut model)
                    .map_err(|e| err(format!("{at}: {e}")))?;
                if let Some((first_index, index_count, center)) = p {
                    primitives.push(Primitive {
                        first_index,
                        index_count,
                        material: mi,
                        center,
                    });
                }
            }
        }
        let mut chain = ancestors;
        chain.push(node.index());
        for child in node.children() {
            stack.push((child, m, chain.clone()));
        }
    }
    if primitives.is_empty() {
        return Err(err("no triangle primitives found".into()));
    }
    model.parts.push(primitives);
    Ok(model)
}

/// Appends one primitive's vertices and indices: its first index, count and bounds centre.
fn read_primitive(
    prim: &gltf::Primitive,
    buffers: &[gltf::buffer::Data],
    m: Mat4,
    needs_tangents: bool,
    model: &mut Model,
) -> Result<Option<(u32, u32, Vec3)>, String> {
    let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let Some(positions) = reader.read_positions() else {
        return Ok(None);
    };
    let positions: Vec<Vec3> = positions.map(Vec3::from).collect();
    let n = positions.len();
    let indices: Vec<u32> = match reader.read_indices() {
        Some(i) => i.into_u32().collect(),
        None => (0..n as u32).collect(),
    };
    if let Some(bad) = indices.iter().find(|&&i| i as usize >= n) {
        return Err(format!(
            "index {bad} is out of range (the primitive has {n} vertices)"
        ));
    }
    if !indices.len().is_multiple_of(3) {
        return Err(format!(
            "{} indices do not make whole triangles",
            indices.len()
        ));
    }
    let check = |name: &str, len: usize| {
        if len == n {
            Ok(())
        } else {
            Err(format!("{name} has {len} entries but POSITION has {n}"))
        }
    };
    let normals: Option<Vec<Vec3>> = reader.read_normals().map(|v| v.map(Vec3::from).collect());
    if let Some(v) = &normals {
        check("NORMAL", v.len())?;
    }
    let uvs: Option<Vec<Vec2>> = reader
        .read_tex_coords(0)
        .map(|v| v.into_f32().map(Vec2::from).collect());
    if let Some(v) = &uvs {
        check("TEXCOORD_0", v.len())?;
    }
    let tangents: Option<Vec<Vec4>> = reader.read_tangents().map(|v| v.map(Vec4::from).collect());
    if let Some(v) = &tangents {
        check("TANGENT", v.len())?;
    }
    if positions.iter().any(|p| !p.is_finite()) {
        return Err("POSITION has non-finite values".into());
    }
    let normal_matrix = Mat3::from_mat4(m).inverse().transpose();
    let linear = Mat3::from_mat4(m);
    let first_vertex = model.vertices.len() as u32;
    let first_index = model.indices.len() as u32;
    let mut lo = Vec3::splat(f32::MAX);
    let mut hi = Vec3::splat(f32::MIN);
    let mut vertex = |i: usize, flat: Option<Vec3>| {
        let p = m.transform_point3(positions[i]);
        lo = lo.min(p);
        hi = hi.max(p);
        let normal = match (flat, &normals) {
            (Some(f), _) => f,
            (None, Some(ns)) => (normal_matrix * ns[i]).normalize_or_zero(),
            (None, None) => Vec3::Y,
        };
        let tangent = match (&tangents, flat) {
            (Some(t), None) => (linear * t[i].truncate())
                .normalize_or_zero()
                .extend(t[i].w.signum()),
            _ => Vec4::ZERO,
        };
        MaterialVertex {
            position: p.into(),
            normal: normal.into(),
            uv: uvs.as_ref().map_or([0.0; 2], |u| u[i].into()),
            tangent: tangent.into(),
        }
    };
    let mut vertices = Vec::new();
    let mut local_indices = Vec::new();
    if normals.is_some() {
        for i in 0..n {
            vertices.push(vertex(i, None));
        }
        local_indices.extend(indices.iter().copied());
    } else {
        // No normals: flat face normals (glTF 2.0, "Meshes"), one vertex per corner.
        for tri in indices.chunks_exact(3) {
            let p: Vec<Vec3> = tri
                .iter()
                .map(|&i| m.transform_point3(positions[i as usize]))
                .collect();
            let f = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
            for &i in tri {
                local_indices.push(vertices.len() as u32);
                vertices.push(vertex(i as usize, Some(f)));
            }
        }
    }
    if needs_tangents && (tangents.is_none() || normals.is_none()) && uvs.is_some() {
        generate_tangents(&mut vertices, &local_indices);
    }
    model.vertices.extend(vertices);
    model
        .indices
        .extend(local_indices.iter().map(|i| i + first_vertex));
    let count = model.indices.len() as u32 - first_index;
    Ok(Some((first_index, count, (lo + hi) * 0.5)))
}

#[allow(clippy::too_many_arguments)]
fn read_material(
    material: &gltf::Material,
    base: &Path,
    buffers: &[gltf::buffer::Data],
    decoded: &mut HashMap<usize, Image>,
    image_index: &mut HashMap<(usize, Encoding), usize>,
    images: &mut Vec<(Image, Encoding)>,
) -> Result<Material, String> {
    let name = material
        .name()
        .map(str::to_string)
        .or_else(|| material.index().map(|i| format!("material {i}")))
        .unwrap_or_else(|| "default".into());
    let pbr = material.pbr_metallic_roughness();
    let mut slot = |slot: usize,
                    texture: Option<(gltf::Texture, u32, UvTransform)>|
     -> Result<Option<TextureRef>, String> {
        let Some((texture, tex_coord, transform)) = texture else {
            return Ok(None);
        };
        if tex_coord != 0 {
            return Err(format!(
                "material {name:?}: its {} texture uses TEXCOORD_{tex_coord}; only TEXCOORD_0 is supported",
                super::material::SLOTS[slot]
            ));
        }
        let source = texture.source();
        let encoding = Material::slot_encoding(slot);
        let key = (source.index(), encoding);
        let image = match image_index.get(&key) {
            Some(&i) => i,
            None => {
                if let std::collections::hash_map::Entry::Vacant(slot) =
                    decoded.entry(source.index())
                {
                    let data = gltf::image::Data::from_source(source.source(), Some(base), buffers)
                        .map_err(|e| format!("image {}: {e}", source.index()))?;
                    slot.insert(to_rgba8(&data));
                }
                images.push((decoded[&source.index()].clone(), encoding));
                image_index.insert(key, images.len() - 1);
                images.len() - 1
            }
        };
        Ok(Some(TextureRef {
            image,
            sampler: sampler(&texture.sampler()),
            transform,
        }))
    };
    let base_tex = slot(0, info(pbr.base_color_texture()))?;
    let mr_tex = slot(1, info(pbr.metallic_roughness_texture()))?;
    let normal = material.normal_texture();
    let normal_scale = normal.as_ref().map_or(1.0, |n| n.scale());
    let normal_tex = slot(
        2,
        normal.map(|n| (n.texture(), n.tex_coord(), UvTransform::IDENTITY)),
    )?;
    let occlusion = material.occlusion_texture();
    let occlusion_strength = occlusion.as_ref().map_or(1.0, |o| o.strength());
    let occlusion_tex = slot(
        3,
        occlusion.map(|o| (o.texture(), o.tex_coord(), UvTransform::IDENTITY)),
    )?;
    let emissive_tex = slot(4, info(material.emissive_texture()))?;
    let strength = material.emissive_strength().unwrap_or(1.0);
    Ok(Material {
        name,
        base_color: Vec4::from(pbr.base_color_factor()),
        metallic: pbr.metallic_factor(),
        roughness: pbr.roughness_factor(),
        emissive: Vec3::from(material.emissive_factor()) * strength,
        normal_scale,
        occlusion_strength,
        alpha: match material.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Mask => AlphaMode::Mask {
                cutoff: material.alpha_cutoff().unwrap_or(0.5),
            },
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        },
        brdf: Brdf::Ggx,
        specular: 0.0,
        textures: [base_tex, mr_tex, normal_tex, occlusion_tex, emissive_tex],
    })
}

/// A texture slot's texture, texture coordinate set and `KHR_texture_transform`.
fn info(i: Option<gltf::texture::Info<'_>>) -> Option<(gltf::Texture<'_>, u32, UvTransform)> {
    i.map(|i| {
        let t = i
            .texture_transform()
            .map(|t| UvTransform {
                offset: Vec2::from(t.offset()),
                rotation: t.rotation(),
                scale: Vec2::from(t.scale()),
            })
            .unwrap_or(UvTransform::IDENTITY);
        let tex_coord = i
            .texture_transform()
            .and_then(|t| t.tex_coord())
            .unwrap_or(i.tex_coord());
        (i.texture(), tex_coord, t)
    })
}

fn sampler(s: &gltf::texture::Sampler) -> SamplerDesc {
    use gltf::texture::{MagFilter, MinFilter, WrappingMode};
    let wrap = |w: WrappingMode| match w {
        WrappingMode::ClampToEdge => Wrap::Clamp,
        WrappingMode::MirroredRepeat => Wrap::Mirror,
        WrappingMode::Repeat => Wrap::Repeat,
    };
    // No filter in the file: trilinear (the spec leaves it to the implementation).
    let (min_linear, mipmap) = match s.min_filter() {
        None | Some(MinFilter::LinearMipmapLinear) => (true, Some(true)),
        Some(MinFilter::Nearest) => (false, None),
        Some(MinFilter::Linear) => (true, None),
        Some(MinFilter::NearestMipmapNearest) => (false, Some(false)),
        Some(MinFilter::LinearMipmapNearest) => (true, Some(false)),
        Some(MinFilter::NearestMipmapLinear) => (false, Some(true)),
    };
    SamplerDesc {
        wrap_u: wrap(s.wrap_s()),
        wrap_v: wrap(s.wrap_t()),
        mag_linear: s.mag_filter() != Some(MagFilter::Nearest),
        min_linear,
        mipmap,
        anisotropy: 1,
    }
}

/// Any decoded glTF image as RGBA8 (16-bit channels keep their high byte; float channels are
/// clamped to [0, 1]; missing channels are 0, alpha 1).
fn to_rgba8(d: &gltf::image::Data) -> Image {
    use gltf::image::Format;
    let texels = (d.width * d.height) as usize;
    let mut out = Vec::with_capacity(4 * texels);
    let (channels, bytes): (usize, usize) = match d.format {
        Format::R8 => (1, 1),
        Format::R8G8 => (2, 1),
        Format::R8G8B8 => (3, 1),
        Format::R8G8B8A8 => (4, 1),
        Format::R16 => (1, 2),
        Format::R16G16 => (2, 2),
        Format::R16G16B16 => (3, 2),
        Format::R16G16B16A16 => (4, 2),
        Format::R32G32B32FLOAT => (3, 4),
        Format::R32G32B32A32FLOAT => (4, 4),
    };
    if channels == 4 && bytes == 1 {
        return Image {
            width: d.width,
            height: d.height,
            rgba8: d.pixels.clone(),
        };
    }
    let stride = channels * bytes;
    for t in 0..texels {
        let texel = &d.pixels[t * stride..(t + 1) * stride];
        let channel = |c: usize| -> u8 {
            let v = &texel[c * bytes..(c + 1) * bytes];
            match bytes {
                1 => v[0],
                2 => (u16::from_ne_bytes([v[0], v[1]]) >> 8) as u8,
                _ => {
                    let f = f32::from_le_bytes([v[0], v[1], v[2], v[3]]);
                    (f.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
                }
            }
        };
        for c in 0..4 {
            out.push(if c < channels {
                channel(c)
            } else if c == 3 {
                255
            } else if channels == 1 {
                // Grey: replicate into green and blue.
                channel(0)
            } else {
                0
            });
        }
    }
    Image {
        width: d.width,
        height: d.height,
        rgba8: out,
    }
}

/// `%20` and friends in relative URIs (glTF URIs are percent-encoded).
fn percent_decode(uri: &str) -> String {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            if let Ok(v) = u8::from_str_radix(&uri[i + 1..i + 3], 16) {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}
