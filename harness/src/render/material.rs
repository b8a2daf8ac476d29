//! Textured materials on the GPU: the scene's textured draws ([`MaterialGpu`]) of the world's
//! models (`world/material.rs`: [`Model`], [`Material`], [`Placement`]).
//!
//! A model's parts are drawn instanced: each [`Placement`] names a part and a run of consecutive
//! scene objects (their model matrices and motion are `scene.rs`'s object buffer), so the city's
//! hundreds of buildings are a few draws. Opaque draws go first, then alpha-tested (`MASK`,
//! discarded below `alphaCutoff`), then blended (`BLEND`, depth test without depth writes, sorted
//! back to front per frame by each draw's centre). The velocity pass draws opaque and
//! alpha-tested surfaces only: a blended surface has no one motion. A pass may draw a subset of
//! the scene objects ([`instance_runs`]: a dynamic-only velocity pass).
//!
//! Shading is `shaders/material/material.wgsl`, appended to `scene.wgsl` (same frame uniforms,
//! lights and objects); each material picks the GGX metallic-roughness BRDF or Blinn-Phong.
//! Passes recorded outside wgpu (hardware VRS's raw Vulkan passes) draw the same draws from
//! [`MaterialGpu::raw`] and [`MaterialGpu::draw_order`].
//! Not here: what a model is, reading glTF files, the city (`world/`), mip levels (`mips.rs`).

use std::collections::HashMap;
use std::ops::Range;
use std::sync::Mutex;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::formats::{ScenePipeline, COLOR_FORMAT, DEPTH_FORMAT};
use super::mips::MipGenerator;
use super::texture;
use crate::world::material::{
    AlphaMode, Brdf, Material, MaterialVertex, Model, Placement, UvTransform,
};
use crate::world::texture::{bytes_with_mips, Image, SamplerDesc};

pub static MATERIAL_WGSL: &str = include_str!("../../../shaders/material/material.wgsl");

/// `scene.wgsl` with the textured-material entry points appended, as the GPU compiles it.
pub fn material_wgsl() -> String {
    format!("{}\n{MATERIAL_WGSL}", super::formats::SCENE_WGSL)
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuMaterial {
    base_color: [f32; 4],
    emissive: [f32; 4],
    /// x metallic, y roughness, z alpha cutoff, w normal scale.
    pbr: [f32; 4],
    /// x occlusion strength, y BRDF (0 Blinn-Phong, 1 GGX), z Blinn-Phong specular, w alpha mode
    /// (0 opaque, 1 mask, 2 blend).
    mode: [f32; 4],
    /// Per slot, the two rows of its uv transform.
    uv: [[f32; 4]; 10],
}

/// How a draw's fragments reach the target: its pipeline family (glTF `alphaMode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Class {
    Opaque,
    Mask,
    Blend,
}

struct Draw {
    first_index: u32,
    index_count: u32,
    base_vertex: i32,
    bind_group: usize,
    class: Class,
    first_object: u32,
    object_count: u32,
    center: Vec3,
}

/// What a material bind group holds, kept for passes recorded outside wgpu ([`RawMaterials`]).
struct GroupResources {
    uniform: wgpu::Buffer,
    views: Vec<wgpu::TextureView>,
    samplers: [SamplerDesc; 5],
}

/// One material bind group's resources, for a pass recorded outside wgpu: binding 0 the uniform
/// buffer (whole), bindings 1..=5 the views of [`SLOTS`](crate::world::material::SLOTS), bindings 6..=10 their samplers (as
/// [`SamplerDesc::descriptor`] makes them, anisotropy applied).
pub struct RawMaterial<'a> {
    pub uniform: &'a wgpu::Buffer,
    pub views: Vec<&'a wgpu::TextureView>,
    pub samplers: [SamplerDesc; 5],
}

/// One textured draw: `index_count` indices from `first_index` (+ `base_vertex`), instances
/// `first_object..+object_count` (scene objects), with material bind group `material`.
#[derive(Clone, Copy, Debug)]
pub struct RawMaterialDraw {
    pub first_index: u32,
    pub index_count: u32,
    pub base_vertex: i32,
    pub material: usize,
    pub class: Class,
    pub first_object: u32,
    pub object_count: u32,
}

/// The textured draws for a pass recorded outside wgpu (hardware variable-rate shading,
/// `techniques/adaptive_shading/raw_material.rs`): vertices ([`MaterialVertex`], four attributes
/// at offsets 0, 12, 24, 32), `u32` indices, the material bind groups' resources, the draws (in
/// [`MaterialGpu::draw_order`] each frame), and every sampled texture (to move into the
/// shader-read state before such a pass).
pub struct RawMaterials<'a> {
    pub vertex: &'a wgpu::Buffer,
    pub index: &'a wgpu::Buffer,
    pub vertex_stride: u32,
    pub uniform_size: u64,
    pub materials: Vec<RawMaterial<'a>>,
    pub draws: Vec<RawMaterialDraw>,
    pub textures: Vec<&'a wgpu::Texture>,
}

/// The scene's textured geometry, materials and textures on the GPU, and their pipelines.
pub struct MaterialGpu {
    vertex_buffer: wgpu::Buffer,
    index_buffer: wgpu::Buffer,
    bind_groups: Vec<wgpu::BindGroup>,
    /// Per bind group, what it binds (for [`MaterialGpu::raw`]).
    groups: Vec<GroupResources>,
    /// Every texture the bind groups sample: the models' and the default 1x1 ones.
    textures: Vec<wgpu::Texture>,
    draws: Vec<Draw>,
    layout: wgpu::PipelineLayout,
    module: wgpu::ShaderModule,
    pipelines: HashMap<(ScenePipeline, Class), wgpu::RenderPipeline>,
    /// Draw order of this frame: opaque, alpha-tested, then blended back to front.
    order: Mutex<Vec<usize>>,
    pub triangles: usize,
    /// Bytes of vertex, index and material buffers and of textures with their mip chains.
    pub bytes: u64,
}

impl MaterialGpu {
    /// Uploads `models` (each with its placements), generating every texture's mip chain, with
    /// samplers at most `anisotropy`x anisotropic. `scene_layout` is group 0 of `scene.wgsl`.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene_layout: &wgpu::BindGroupLayout,
        models: &[(&Model, Vec<Placement>)],
        anisotropy: u16,
    ) -> MaterialGpu {
        use wgpu::util::DeviceExt;
        let mut vertices: Vec<MaterialVertex> = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        let mut mips = MipGenerator::new(device);
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("material textures"),
        });
        let layout = material_layout(device);
        let mut samplers: HashMap<SamplerDesc, wgpu::Sampler> = HashMap::new();
        let defaults: Vec<wgpu::Texture> = [
            [255, 255, 255, 255],
            [255, 255, 255, 255],
            [128, 128, 255, 255],
            [255, 255, 255, 255],
            [255, 255, 255, 255],
        ]
        .iter()
        .enumerate()
        .map(|(i, t)| {
            texture::upload(
                device,
                queue,
                &mut mips,
                &mut encoder,
                &Image::texel(*t),
                Material::slot_encoding(i),
                "default material texture",
            )
        })
        .collect();
        let mut bytes = 0u64;
        let mut bind_groups = Vec::new();
        let mut groups = Vec::new();
        let mut all_textures = Vec::new();
        let mut draws = Vec::new();
        let mut triangles = 0usize;
        for (model, placements) in models {
            let base_vertex = vertices.len() as i32;
            let first_index = indices.len() as u32;
            vertices.extend_from_slice(&model.vertices);
            indices.extend_from_slice(&model.indices);
            let textures: Vec<wgpu::Texture> = model
                .images
                .iter()
                .map(|(img, enc)| {
                    bytes += bytes_with_mips(img);
                    texture::upload(
                        device,
                        queue,
                        &mut mips,
                        &mut encoder,
                        img,
                        *enc,
                        &model.name,
                    )
                })
                .collect();
            let first_group = bind_groups.len();
            for m in &model.materials {
                let uniform = gpu_material(m);
                let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("material"),
                    contents: bytemuck::bytes_of(&uniform),
                    usage: wgpu::BufferUsages::UNIFORM,
                });
                bytes += buffer.size();
                let views: Vec<wgpu::TextureView> = (0..5)
                    .map(|i| match &m.textures[i] {
                        Some(t) => textures[t.image].create_view(&Default::default()),
                        None => defaults[i].create_view(&Default::default()),
                    })
                    .collect();
                for t in m.textures.iter() {
                    let desc = t.map_or(SamplerDesc::DEFAULT, |t| t.sampler);
                    let desc = SamplerDesc {
                        anisotropy: anisotropy.max(1),
                        ..desc
                    };
                    samplers.entry(desc).or_insert_with(|| desc.create(device));
                }
                let sampler_of = |i: usize| {
                    let desc = m.textures[i].map_or(SamplerDesc::DEFAULT, |t| t.sampler);
                    &samplers[&SamplerDesc {
                        anisotropy: anisotropy.max(1),
                        ..desc
                    }]
                };
                let mut entries = vec![wgpu::BindGroupEntry {
                    binding: 0,
                    resource: buffer.as_entire_binding(),
                }];
                for (i, v) in views.iter().enumerate() {
                    entries.push(wgpu::BindGroupEntry {
                        binding: 1 + i as u32,
                        resource: wgpu::BindingResource::TextureView(v),
                    });
                }
                for i in 0..5 {
                    entries.push(wgpu::BindGroupEntry {
                        binding: 6 + i as u32,
                        resource: wgpu::BindingResource::Sampler(sampler_of(i)),
                    });
                }
                bind_groups.push(device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("material"),
                    layout: &layout,
                    entries: &entries,
                }));
                let sampler_descs = std::array::from_fn(|i| SamplerDesc {
                    anisotropy: anisotropy.max(1),
                    ..m.textures[i].map_or(SamplerDesc::DEFAULT, |t| t.sampler)
                });
                groups.push(GroupResources {
                    uniform: buffer,
                    views,
                    samplers: sampler_descs,
                });
            }
            all_textures.extend(textures);
            for p in placements {
                for prim in &model.parts[p.part] {
                    triangles += (prim.index_count / 3) as usize * p.count as usize;
                    draws.push(Draw {
                        first_index: first_index + prim.first_index,
                        index_count: prim.index_count,
                        base_vertex,
                        bind_group: first_group + prim.material,
                        class: match model.materials[prim.material].alpha {
                            AlphaMode::Opaque => Class::Opaque,
                            AlphaMode::Mask { .. } => Class::Mask,
                            AlphaMode::Blend => Class::Blend,
                        },
                        first_object: p.first_object,
                        object_count: p.count,
                        center: prim.center,
                    });
                }
            }
        }
        queue.submit([encoder.finish()]);
        all_textures.extend(defaults);
        if vertices.is_empty() {
            vertices.push(MaterialVertex::default());
            indices.extend([0, 0, 0]);
        }
        let vertex_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("material vertices"),
            contents: bytemuck::cast_slice(&vertices),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let index_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("material indices"),
            contents: bytemuck::cast_slice(&indices),
            usage: wgpu::BufferUsages::INDEX,
        });
        bytes += vertex_buffer.size() + index_buffer.size();
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("material"),
            bind_group_layouts: &[Some(scene_layout), Some(&layout)],
            immediate_size: 0,
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("material.wgsl"),
            source: wgpu::ShaderSource::Wgsl(material_wgsl().into()),
        });
        let mut order: Vec<usize> = (0..draws.len()).collect();
        order.sort_by_key(|&i| draws[i].class);
        MaterialGpu {
            vertex_buffer,
            index_buffer,
            bind_groups,
            groups,
            textures: all_textures,
            draws,
            layout: pipeline_layout,
            module,
            pipelines: HashMap::new(),
            order: Mutex::new(order),
            triangles,
            bytes,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.draws.is_empty()
    }

    /// This frame's draw order (indices into [`RawMaterials::draws`]): opaque, alpha-tested, then
    /// blended back to front as [`MaterialGpu::sort`] left it.
    pub fn draw_order(&self) -> Vec<usize> {
        self.order.lock().expect("draw order lock").clone()
    }

    /// The textured draws and the resources they bind, for a pass recorded outside wgpu.
    pub fn raw(&self) -> RawMaterials<'_> {
        RawMaterials {
            vertex: &self.vertex_buffer,
            index: &self.index_buffer,
            vertex_stride: std::mem::size_of::<MaterialVertex>() as u32,
            uniform_size: std::mem::size_of::<GpuMaterial>() as u64,
            materials: self
                .groups
                .iter()
                .map(|g| RawMaterial {
                    uniform: &g.uniform,
                    views: g.views.iter().collect(),
                    samplers: g.samplers,
                })
                .collect(),
            draws: self
                .draws
                .iter()
                .map(|d| RawMaterialDraw {
                    first_index: d.first_index,
                    index_count: d.index_count,
                    base_vertex: d.base_vertex,
                    material: d.bind_group,
                    class: d.class,
                    first_object: d.first_object,
                    object_count: d.object_count,
                })
                .collect(),
            textures: self.textures.iter().collect(),
        }
    }

    /// Whether any draw is alpha-blended.
    pub fn has_blend(&self) -> bool {
        self.draws.iter().any(|d| d.class == Class::Blend)
    }

    /// Sorts this frame's blended draws back to front: `center_of(object, center)` is a draw
    /// centre's camera-relative position for its first object.
    pub fn sort(&self, center_of: impl Fn(u32, Vec3) -> Vec3) {
        let mut order = self.order.lock().expect("draw order lock");
        let key = |i: usize| {
            let d = &self.draws[i];
            center_of(d.first_object, d.center).length()
        };
        let (front, mut blend): (Vec<usize>, Vec<usize>) = order
            .iter()
            .partition(|&&i| self.draws[i].class != Class::Blend);
        blend.sort_by(|&a, &b| key(b).total_cmp(&key(a)));
        *order = front.into_iter().chain(blend).collect();
    }

    /// Builds the pipelines `kind` draws with (call before the render pass).
    pub fn prepare(&mut self, device: &wgpu::Device, kind: ScenePipeline) {
        for class in [Class::Opaque, Class::Mask, Class::Blend] {
            if kind == ScenePipeline::Velocity && class == Class::Blend {
                continue;
            }
            let (layout, module) = (&self.layout, &self.module);
            self.pipelines
                .entry((kind, class))
                .or_insert_with(|| pipeline(device, layout, module, kind, class));
        }
    }

    /// Draws the textured objects `only` takes (per scene object; `None`: all) with view bind
    /// group `scene_group` (group 0, at `offset`) into the current pass, with the pipelines of
    /// `kind` ([`MaterialGpu::prepare`] first).
    pub fn draw(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        kind: ScenePipeline,
        scene_group: &wgpu::BindGroup,
        offset: u32,
        only: Option<&[bool]>,
    ) {
        if self.draws.is_empty() {
            return;
        }
        pass.set_bind_group(0, scene_group, &[offset]);
        pass.set_vertex_buffer(0, self.vertex_buffer.slice(..));
        pass.set_index_buffer(self.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
        let order = self.order.lock().expect("draw order lock");
        let mut current: Option<Class> = None;
        for &i in order.iter() {
            let d = &self.draws[i];
            let Some(p) = self.pipelines.get(&(kind, d.class)) else {
                continue; // blended surfaces in the velocity pass
            };
            if current != Some(d.class) {
                pass.set_pipeline(p);
                current = Some(d.class);
            }
            let mut runs =
                instance_runs(d.first_object..d.first_object + d.object_count, only).peekable();
            if runs.peek().is_none() {
                continue; // none of its instances is taken
            }
            pass.set_bind_group(1, &self.bind_groups[d.bind_group], &[]);
            for instances in runs {
                pass.draw_indexed(
                    d.first_index..d.first_index + d.index_count,
                    d.base_vertex,
                    instances,
                );
            }
        }
    }
}

/// The runs of consecutive scene objects in `objects` that `only` takes (per scene object;
/// `None`: the whole range): the instance ranges of a draw restricted to them. A placement mixes
/// static and moving objects (the city's parked and moving cars of one colour), so a draw of
/// the dynamic objects only may become several.
pub fn instance_runs(
    objects: Range<u32>,
    only: Option<&[bool]>,
) -> impl Iterator<Item = Range<u32>> + '_ {
    let taken = move |i: u32| only.is_none_or(|o| o.get(i as usize).copied().unwrap_or(false));
    let mut next = objects.start;
    std::iter::from_fn(move || {
        while next < objects.end && !taken(next) {
            next += 1;
        }
        let start = next;
        while next < objects.end && taken(next) {
            next += 1;
        }
        (start < next).then_some(start..next)
    })
}

fn gpu_material(m: &Material) -> GpuMaterial {
    let mut uv = [[0.0; 4]; 10];
    for (i, t) in m.textures.iter().enumerate() {
        let rows = t.map_or(UvTransform::IDENTITY, |t| t.transform).rows();
        uv[2 * i] = rows[0];
        uv[2 * i + 1] = rows[1];
    }
    let (cutoff, mode) = match m.alpha {
        AlphaMode::Opaque => (0.0, 0.0),
        AlphaMode::Mask { cutoff } => (cutoff, 1.0),
        AlphaMode::Blend => (0.0, 2.0),
    };
    GpuMaterial {
        base_color: m.base_color.into(),
        emissive: m.emissive.extend(0.0).into(),
        pbr: [m.metallic, m.roughness, cutoff, m.normal_scale],
        mode: [
            m.occlusion_strength,
            match m.brdf {
                Brdf::BlinnPhong => 0.0,
                Brdf::Ggx => 1.0,
            },
            m.specular,
            mode,
        ],
        uv,
    }
}

fn material_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let mut entries = vec![wgpu::BindGroupLayoutEntry {
        binding: 0,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<GpuMaterial>() as u64),
        },
        count: None,
    }];
    for i in 0..5 {
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: 1 + i,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: true },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        });
    }
    for i in 0..5 {
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: 6 + i,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
            count: None,
        });
    }
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("material"),
        entries: &entries,
    })
}

fn pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    kind: ScenePipeline,
    class: Class,
) -> wgpu::RenderPipeline {
    let (vs, fs, samples) = match (kind, class) {
        (ScenePipeline::Forward { samples }, Class::Opaque) => {
            ("vs_material", "fs_material", samples)
        }
        (ScenePipeline::Forward { samples }, _) => ("vs_material", "fs_material_alpha", samples),
        (ScenePipeline::PerSample { samples }, Class::Opaque) => {
            ("vs_material_sample", "fs_material_sample", samples)
        }
        (ScenePipeline::PerSample { samples }, _) => {
            ("vs_material_sample", "fs_material_sample_alpha", samples)
        }
        (ScenePipeline::Velocity, Class::Opaque) => {
            ("vs_material_velocity", "fs_material_velocity", 1)
        }
        (ScenePipeline::Velocity, _) => ("vs_material_velocity", "fs_material_velocity_mask", 1),
    };
    let blend = class == Class::Blend;
    let target = wgpu::ColorTargetState {
        format: COLOR_FORMAT,
        blend: blend.then_some(wgpu::BlendState::ALPHA_BLENDING),
        write_mask: wgpu::ColorWrites::ALL,
    };
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(match class {
            Class::Opaque => "material opaque",
            Class::Mask => "material alpha-tested",
            Class::Blend => "material blended",
        }),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(vs),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<MaterialVertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![
                    0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Float32x4
                ],
            })],
        },
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(fs),
            compilation_options: Default::default(),
            targets: &[Some(target)],
        }),
        primitive: wgpu::PrimitiveState {
            cull_mode: None,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(!blend),
            depth_compare: Some(wgpu::CompareFunction::Greater),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: wgpu::MultisampleState {
            count: samples,
            ..Default::default()
        },
        multiview_mask: None,
        cache: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn instance_runs_split_a_draw_into_the_taken_objects() {
        let runs = |r: Range<u32>, only| instance_runs(r, only).collect::<Vec<_>>();
        assert_eq!(runs(2..6, None), vec![2..6]);
        // Objects 0..8: 1, 3, 4 and 7 taken; 8 and beyond are not in the list (not taken).
        let taken = [false, true, false, true, true, false, false, true];
        assert_eq!(runs(0..10, Some(&taken)), vec![1..2, 3..5, 7..8]);
        assert_eq!(runs(4..7, Some(&taken)), vec![4..5]);
        assert!(runs(5..7, Some(&taken)).is_empty());
    }
}
