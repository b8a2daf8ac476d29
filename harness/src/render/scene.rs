//! A scene on the GPU: geometry uploaded once, per-frame uniforms, and the forward `scene` pass.
//!
//! Positions are made camera-relative on the CPU in f64 (objects, lights, previous camera), so a
//! camera a million units from the origin keeps sub-millimetre precision. Depth is reversed-Z:
//! near maps to 1, far to 0, cleared to 0, compared with `Greater`; with Depth32Float this keeps
//! precision from near = 1e-4 to far = 1e7. Techniques call [`SceneGpu::write_view`] once per view
//! slot and frame, then [`SceneGpu::draw`] inside their render passes.
//!
//! Procedural shapes and `materials = "color"` meshes are drawn as before with the scene's own
//! colours; glTF files with `materials = "file"` and the generated city are textured models
//! (`world/material.rs`, drawn by `material.rs`), drawn after them in the same passes with the same objects buffer.

use std::collections::HashMap;

use bytemuck::{Pod, Zeroable};
use glam::{DMat4, DVec3, Vec2, Vec4};

use super::material::{instance_runs, MaterialGpu};
use crate::world::city;
use crate::world::geometry::{Draw, Geometry};
use crate::world::material::{Model, Placement};
use crate::world::mesh::{MeshError, Vertex};
use crate::world::scene::{CameraPose, GroundFilter, Light, Stage};

pub use super::formats::{ScenePipeline, COLOR_FORMAT, DEPTH_FORMAT, SCENE_WGSL};
pub const MAX_LIGHTS: usize = 8;
/// Views (camera + jitter combinations) a technique may render per frame.
pub const VIEW_SLOTS: u64 = 4;
const SLOT_STRIDE: u64 = 1024;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuLight {
    position_or_direction: [f32; 4],
    radiance: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuFrame {
    view_proj: [[f32; 4]; 4],
    prev_view_proj: [[f32; 4]; 4],
    jitter: [f32; 4],
    camera_mod: [f32; 4],
    background: [f32; 4],
    params: [f32; 4],
    ground: [f32; 4],
    ground_a: [f32; 4],
    ground_b: [f32; 4],
    counts: [u32; 4],
    lights: [GpuLight; MAX_LIGHTS],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuObject {
    model: [[f32; 4]; 4],
    prev_model: [[f32; 4]; 4],
    color: [f32; 4],
    emissive: [f32; 4],
    /// x: injected non-finite value (0 none, 1 NaN, 2 +Inf); yzw unused.
    flags: [f32; 4],
}

/// What a technique asks of one view of the scene.
#[derive(Clone, Copy, Debug)]
pub struct View {
    /// Scene time of this frame and of the previous one (for motion).
    pub time: f64,
    pub prev_time: f64,
    /// Viewport remap after projection, `ndc' = ndc * scale + offset`: the identity for a target
    /// showing the whole frame; techniques use it to jitter and to render parts of the frame.
    pub ndc_offset: Vec2,
    pub ndc_scale: Vec2,
    /// Multiplies screen-space derivatives of the ground pattern and of texture coordinates (1 at
    /// native resolution; a technique rendering at a reduced density corrects with it).
    pub gradient_scale: f32,
    /// Texture LOD bias in mip levels on top of `gradient_scale` (texture gradients are scaled by
    /// 2^lod_bias): an upscaler's -log2(output / render). 0 by default.
    pub lod_bias: f32,
}

impl View {
    /// The whole frame at output resolution, unjittered: what `native`, the velocity pass and
    /// the G-buffer passes render.
    pub fn whole(time: f64, prev_time: f64) -> View {
        View {
            time,
            prev_time,
            ndc_offset: Vec2::ZERO,
            ndc_scale: Vec2::ONE,
            gradient_scale: 1.0,
            lod_bias: 0.0,
        }
    }
}

/// Which of the scene's objects a pass draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Objects {
    /// Every object.
    All,
    /// Only the objects that move by themselves (animated scene objects, the city's moving
    /// vehicles); the ground, still objects and parked vehicles are left out.
    Dynamic,
}

/// The scene's buffers and draws, for a pass recorded outside wgpu ([`SceneGpu::raw_draw`]):
/// vertices (position, normal: two `Float32x3`), `u32` indices, group 0 of `scene.wgsl` (binding 0
/// the frame uniforms at `frame_offset`, binding 1 the objects), and per object (its instance
/// index) the first index, index count and base vertex.
pub struct RawDraw<'a> {
    pub vertex: &'a wgpu::Buffer,
    pub index: &'a wgpu::Buffer,
    pub frame: &'a wgpu::Buffer,
    pub frame_offset: u64,
    pub frame_size: u64,
    pub objects: &'a wgpu::Buffer,
    pub vertex_stride: u32,
    pub draws: Vec<(u32, u32, i32)>,
}

pub struct SceneGpu {
    /// The scenario's scene, camera and size: nothing else of it (`world/scene.rs`).
    stage: Stage,
    vertex_buffer: wgpu::Buffer,
    index_buffer: wgpu::Buffer,
    draws: Vec<Draw>,
    frame_buffer: wgpu::Buffer,
    object_buffer: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    layout: wgpu::PipelineLayout,
    module: wgpu::ShaderModule,
    pipelines: HashMap<ScenePipeline, wgpu::RenderPipeline>,
    /// Textured models (glTF materials, the city), when the scene has any.
    materials: Option<MaterialGpu>,
    /// The city's objects, after the scenario's in the objects buffer.
    city_objects: Vec<city::CityObject>,
    /// Per object of the objects buffer (its instance index): whether it moves by itself; what
    /// `write_objects` marks for the shaders (`emissive.a`) and `Objects::Dynamic` draws.
    dynamic: Vec<bool>,
    pub triangles: usize,
    /// Bytes of geometry and uniform buffers and of textures with their mip chains, shared by
    /// every variant.
    pub buffer_bytes: u64,
}

impl SceneGpu {
    /// Builds geometry (loading glTF files, generating the city and every texture's mip chain)
    /// and GPU objects once per scenario (`&Scenario` gives its [`Stage`]).
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        stage: impl Into<Stage>,
    ) -> Result<SceneGpu, MeshError> {
        let scenario: Stage = stage.into();
        let Geometry {
            mut vertices,
            mut indices,
            draws,
            models,
            city_objects,
            dynamic,
            triangles,
        } = Geometry::build(&scenario.scene)?;
        // Empty scenes still need valid (non-zero-sized) buffers.
        if vertices.is_empty() {
            vertices.push(Vertex {
                position: [0.0; 3],
                normal: [0.0, 1.0, 0.0],
            });
            indices.extend([0, 0, 0]);
        }
        use wgpu::util::DeviceExt;
        let vertex_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("scene vertices"),
            contents: bytemuck::cast_slice(&vertices),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let index_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("scene indices"),
            contents: bytemuck::cast_slice(&indices),
            usage: wgpu::BufferUsages::INDEX,
        });
        let frame_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("scene frame uniforms"),
            size: SLOT_STRIDE * VIEW_SLOTS,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let object_count = (draws.len() + city_objects.len()).max(1) as u64;
        let object_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("scene objects"),
            size: object_count * std::mem::size_of::<GpuObject>() as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bgl = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("scene"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: true,
                        min_binding_size: wgpu::BufferSize::new(
                            std::mem::size_of::<GpuFrame>() as u64
                        ),
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Storage { read_only: true },
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
            ],
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("scene"),
            layout: &bgl,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &frame_buffer,
                        offset: 0,
                        size: wgpu::BufferSize::new(std::mem::size_of::<GpuFrame>() as u64),
                    }),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: object_buffer.as_entire_binding(),
                },
            ],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("scene"),
            bind_group_layouts: &[Some(&bgl)],
            immediate_size: 0,
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("scene.wgsl"),
            source: wgpu::ShaderSource::Wgsl(SCENE_WGSL.into()),
        });
        let materials = (!models.is_empty()).then(|| {
            let refs: Vec<(&Model, Vec<Placement>)> =
                models.iter().map(|(m, p)| (m, p.clone())).collect();
            MaterialGpu::new(device, queue, &bgl, &refs, scenario.scene.anisotropy)
        });
        let triangles = triangles + materials.as_ref().map_or(0, |m| m.triangles);
        let buffer_bytes = vertex_buffer.size()
            + index_buffer.size()
            + frame_buffer.size()
            + object_buffer.size()
            + materials.as_ref().map_or(0, |m| m.bytes);
        Ok(SceneGpu {
            stage: scenario,
            vertex_buffer,
            index_buffer,
            draws,
            frame_buffer,
            object_buffer,
            bind_group,
            layout,
            module,
            pipelines: HashMap::new(),
            materials,
            city_objects,
            dynamic,
            triangles,
            buffer_bytes,
        })
    }

    /// Whether the scene has textured models (glTF materials or the city): techniques that
    /// shade without the scene's forward pipelines cannot draw them.
    pub fn has_materials(&self) -> bool {
        self.materials.is_some()
    }

    /// Whether a light moves or turns (`animation` on a light): shading changes where nothing
    /// moves, so "camera still, nothing animated" no longer means "the history is exact".
    pub fn lights_animated(&self) -> bool {
        self.stage.scene.has_animated_lights()
    }

    /// The textured models, for passes recorded outside wgpu that draw them themselves
    /// (`techniques/adaptive_shading/raw_material.rs`: [`MaterialGpu::raw`] and its draw order).
    pub fn materials(&self) -> Option<&MaterialGpu> {
        self.materials.as_ref()
    }

    /// A pipeline of the scene shader, built on first use.
    pub fn pipeline(
        &mut self,
        device: &wgpu::Device,
        kind: ScenePipeline,
    ) -> &wgpu::RenderPipeline {
        if let Some(m) = &mut self.materials {
            m.prepare(device, kind);
        }
        let (layout, module) = (&self.layout, &self.module);
        self.pipelines.entry(kind).or_insert_with(|| {
            let (vs, fs, samples, label) = match kind {
                ScenePipeline::Forward { samples } => ("vs_main", "fs_main", samples, "scene"),
                ScenePipeline::PerSample { samples } => (
                    "vs_main_sample",
                    "fs_main_sample",
                    samples,
                    "scene per sample",
                ),
                ScenePipeline::Velocity => ("vs_velocity", "fs_velocity", 1, "velocity"),
            };
            let targets = [Some(COLOR_FORMAT.into())];
            scene_pipeline(device, layout, module, (vs, fs), samples, label, &targets)
        })
    }

    /// A single-sample pipeline drawing the scene's geometry with the scene's bindings but another
    /// shader `module` (which includes `scene.wgsl`) and colour `targets`: for techniques with their
    /// own scene pass, such as adaptive shading's G-buffer. Not cached: the caller keeps it.
    pub fn custom_pipeline(
        &self,
        device: &wgpu::Device,
        label: &str,
        module: &wgpu::ShaderModule,
        entry_points: (&str, &str),
        targets: &[Option<wgpu::ColorTargetState>],
    ) -> wgpu::RenderPipeline {
        scene_pipeline(
            device,
            &self.layout,
            module,
            entry_points,
            1,
            label,
            targets,
        )
    }

    /// View `slot`'s frame uniforms, for binding in compute passes that shade (group 0, binding 0
    /// of `scene.wgsl`, without the render passes' dynamic offset).
    pub fn frame_binding(&self, slot: u32) -> wgpu::BindingResource<'_> {
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.frame_buffer,
            offset: slot as u64 * SLOT_STRIDE,
            size: wgpu::BufferSize::new(std::mem::size_of::<GpuFrame>() as u64),
        })
    }

    /// The objects (group 0, binding 1 of `scene.wgsl`), for compute passes that shade.
    pub fn objects_binding(&self) -> wgpu::BindingResource<'_> {
        self.object_buffer.as_entire_binding()
    }

    /// Current and previous view-projection, both relative to the current camera position (f64).
    pub fn view_projections(&self, time: f64, prev_time: f64) -> (DMat4, DMat4) {
        let s = &self.stage;
        let pose = s.camera.pose_at(time);
        let prev = s.camera.pose_at(prev_time);
        let aspect = s.width as f64 / s.height as f64;
        let vp = |p: &CameraPose| -> DMat4 {
            let proj = reversed_z_projection(
                p.fov_degrees as f64,
                aspect,
                s.camera.near as f64,
                s.camera.far as f64,
            );
            proj * rotation_view(p)
        };
        let eye = pose.position;
        (
            vp(&pose),
            vp(&prev) * DMat4::from_translation(eye - prev.position),
        )
    }

    /// Writes object matrices for `time` relative to the camera at `time`. Call once per frame.
    pub fn write_objects(&self, queue: &wgpu::Queue, time: f64, prev_time: f64) {
        let pose = self.stage.camera.pose_at(time);
        let eye = pose.position;
        let rel = |m: DMat4| {
            (DMat4::from_translation(-eye) * m)
                .as_mat4()
                .to_cols_array_2d()
        };
        // The shaders' dynamic mark (`emissive.a` 2, above 1.5) from the same list the passes of
        // the dynamic objects draw by (`dynamic`, in this buffer's order).
        let mark = |i: usize| if self.dynamic[i] { 2.0 } else { 0.0 };
        let mut objects = Vec::new();
        if let Some(g) = &self.stage.scene.ground {
            // The quad follows the camera in x and z; the pattern is anchored in world space, so
            // the point seen on it now was at the same world position last frame: its previous
            // model is this frame's (motion passes then give the ground the camera's motion, not
            // the quad's, which is zero on a pan).
            let m = rel(DMat4::from_translation(DVec3::new(
                eye.x,
                g.height as f64,
                eye.z,
            )));
            objects.push(GpuObject {
                model: m,
                prev_model: m,
                color: [1.0, 1.0, 1.0, 0.05],
                emissive: [0.0, 0.0, 0.0, 1.0],
                flags: [0.0; 4],
            });
        }
        for o in &self.stage.scene.objects {
            objects.push(GpuObject {
                model: rel(o.model_at(time)),
                prev_model: rel(o.model_at(prev_time)),
                color: o.color.extend(o.specular).into(),
                emissive: o.emissive.extend(mark(objects.len())).into(),
                flags: [o.inject.map_or(0.0, |i| i.code()), 0.0, 0.0, 0.0],
            });
        }
        for c in &self.city_objects {
            objects.push(GpuObject {
                model: rel(c.model_at(time)),
                prev_model: rel(c.model_at(prev_time)),
                color: [1.0, 1.0, 1.0, 0.0],
                emissive: [0.0, 0.0, 0.0, mark(objects.len())],
                flags: [0.0; 4],
            });
        }
        if let Some(m) = &self.materials {
            if m.has_blend() {
                m.sort(|object, center| {
                    glam::Mat4::from_cols_array_2d(&objects[object as usize].model)
                        .transform_point3(center)
                });
            }
        }
        if !objects.is_empty() {
            queue.write_buffer(&self.object_buffer, 0, bytemuck::cast_slice(&objects));
        }
    }

    /// Writes the uniforms of view `slot` (0..VIEW_SLOTS) for this frame.
    pub fn write_view(&self, queue: &wgpu::Queue, slot: u32, view: &View) {
        assert!((slot as u64) < VIEW_SLOTS, "view slot {slot} out of range");
        let s = &self.stage;
        let pose = s.camera.pose_at(view.time);
        let jitter = Vec4::new(
            view.ndc_offset.x,
            view.ndc_offset.y,
            view.ndc_scale.x,
            view.ndc_scale.y,
        );
        let eye = pose.position;
        let (cur_vp, prev_vp) = self.view_projections(view.time, view.prev_time);
        let (ground, filter, checker) = match &s.scene.ground {
            Some(g) => (
                Some(g),
                if g.filter == GroundFilter::Box {
                    1.0
                } else {
                    0.0
                },
                g.checker_size as f64,
            ),
            None => (None, 0.0, 1.0),
        };
        let period = 2.0 * checker;
        let camera_mod = [
            eye.x.rem_euclid(period) as f32,
            0.0,
            eye.z.rem_euclid(period) as f32,
            0.0,
        ];
        let mut lights = [GpuLight {
            position_or_direction: [0.0; 4],
            radiance: [0.0; 4],
        }; MAX_LIGHTS];
        for (i, l) in s.scene.lights.iter().take(MAX_LIGHTS).enumerate() {
            lights[i] = match l.at(view.time) {
                Light::Directional {
                    direction,
                    color,
                    intensity,
                    ..
                } => GpuLight {
                    position_or_direction: direction.extend(0.0).into(),
                    radiance: (color * intensity).extend(0.0).into(),
                },
                Light::Point {
                    position,
                    color,
                    intensity,
                    ..
                } => GpuLight {
                    position_or_direction: (position.as_dvec3() - eye).as_vec3().extend(1.0).into(),
                    radiance: (color * intensity).extend(0.0).into(),
                },
            };
        }
        let (view_proj, prev_view_proj) = (
            cur_vp.as_mat4().to_cols_array_2d(),
            prev_vp.as_mat4().to_cols_array_2d(),
        );
        // The camera did not move: static geometry has exactly zero motion (see `vs_velocity`).
        let camera_still = u32::from(view_proj == prev_view_proj);
        let frame = GpuFrame {
            view_proj,
            prev_view_proj,
            jitter: jitter.into(),
            camera_mod,
            background: s.scene.background.extend(1.0).into(),
            params: [
                s.scene.ambient,
                s.scene.shading_cost as f32,
                view.gradient_scale,
                filter,
            ],
            ground: [
                checker as f32,
                ground.map(|g| g.filter_epsilon).unwrap_or(0.0),
                view.lod_bias,
                0.0,
            ],
            ground_a: ground
                .map(|g| g.colors[0].extend(1.0).into())
                .unwrap_or([0.0; 4]),
            ground_b: ground
                .map(|g| g.colors[1].extend(1.0).into())
                .unwrap_or([0.0; 4]),
            counts: [
                s.scene.lights.len().min(MAX_LIGHTS) as u32,
                s.width,
                s.height,
                camera_still,
            ],
            lights,
        };
        queue.write_buffer(
            &self.frame_buffer,
            slot as u64 * SLOT_STRIDE,
            bytemuck::bytes_of(&frame),
        );
    }

    /// The camera's near and far planes.
    pub fn near_far(&self) -> (f32, f32) {
        (self.stage.camera.near, self.stage.camera.far)
    }

    /// Clear colour of the scene pass (linear radiance).
    pub fn clear_color(&self) -> wgpu::Color {
        let b = self.stage.scene.background;
        wgpu::Color {
            r: b.x as f64,
            g: b.y as f64,
            b: b.z as f64,
            a: 1.0,
        }
    }

    /// What a pass recorded outside wgpu needs to draw the scene itself (hardware variable-rate
    /// shading, `techniques/adaptive_shading/raw_pass.rs`): the buffers, view `slot`'s frame uniforms and one draw per object.
    pub fn raw_draw(&self, slot: u32) -> RawDraw<'_> {
        RawDraw {
            vertex: &self.vertex_buffer,
            index: &self.index_buffer,
            frame: &self.frame_buffer,
            frame_offset: slot as u64 * SLOT_STRIDE,
            frame_size: std::mem::size_of::<GpuFrame>() as u64,
            objects: &self.object_buffer,
            vertex_stride: std::mem::size_of::<Vertex>() as u32,
            draws: self
                .draws
                .iter()
                .map(|d| (d.first_index, d.index_count, d.base_vertex))
                .collect(),
        }
    }

    /// Draws every object with view `slot` into the current render pass with the pipelines of
    /// `kind` ([`SceneGpu::pipeline`] first): the untextured objects, then the textured models.
    pub fn draw_kind(&self, pass: &mut wgpu::RenderPass<'_>, kind: ScenePipeline, slot: u32) {
        self.draw_objects(pass, kind, slot, Objects::All);
    }

    /// [`SceneGpu::draw_kind`] for the `objects` asked for only: a velocity pass of the dynamic
    /// objects leaves the static ones (and their overdraw) out.
    pub fn draw_objects(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        kind: ScenePipeline,
        slot: u32,
        objects: Objects,
    ) {
        let only = self.selection(objects);
        self.draw_selected(pass, &self.pipelines[&kind], slot, only);
        if let Some(m) = &self.materials {
            m.draw(
                pass,
                kind,
                &self.bind_group,
                (slot as u64 * SLOT_STRIDE) as u32,
                only,
            );
        }
    }

    /// Draws every untextured object with view `slot` into the current render pass with
    /// `pipeline` (a technique's own scene shader; textured models are [`SceneGpu::draw_kind`]'s).
    pub fn draw(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        pipeline: &wgpu::RenderPipeline,
        slot: u32,
    ) {
        self.draw_selected(pass, pipeline, slot, None);
    }

    /// Per object, whether `objects` takes it (`None`: every object).
    fn selection(&self, objects: Objects) -> Option<&[bool]> {
        match objects {
            Objects::All => None,
            Objects::Dynamic => Some(&self.dynamic),
        }
    }

    /// The untextured draws of the objects `only` takes (`None`: all).
    fn draw_selected(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        pipeline: &wgpu::RenderPipeline,
        slot: u32,
        only: Option<&[bool]>,
    ) {
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.bind_group, &[(slot as u64 * SLOT_STRIDE) as u32]);
        pass.set_vertex_buffer(0, self.vertex_buffer.slice(..));
        pass.set_index_buffer(self.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
        for (i, d) in self.draws.iter().enumerate() {
            if d.index_count == 0 {
                continue; // a textured object's slot
            }
            let i = i as u32;
            for instances in instance_runs(i..i + 1, only) {
                pass.draw_indexed(
                    d.first_index..d.first_index + d.index_count,
                    d.base_vertex,
                    instances,
                );
            }
        }
    }
}

/// A scene render pipeline: the scene's vertex layout, reversed-Z depth test, no culling.
fn scene_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    (vs, fs): (&str, &str),
    samples: u32,
    label: &str,
    targets: &[Option<wgpu::ColorTargetState>],
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(vs),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<Vertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3],
            })],
        },
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(fs),
            compilation_options: Default::default(),
            targets,
        }),
        primitive: wgpu::PrimitiveState {
            cull_mode: None,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
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

/// Camera rotation only (the translation is applied per object in f64).
fn rotation_view(p: &CameraPose) -> DMat4 {
    let dir = (p.target - p.position).normalize();
    let up = if dir.y.abs() > 0.999 {
        DVec3::Z
    } else {
        DVec3::Y
    };
    DMat4::look_to_rh(DVec3::ZERO, dir, up)
}

/// Right-handed perspective with reversed depth: view depth `near` maps to 1, `far` to 0.
pub fn reversed_z_projection(fov_degrees: f64, aspect: f64, near: f64, far: f64) -> DMat4 {
    DMat4::perspective_rh(fov_degrees.to_radians(), aspect, far, near)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reversed_z_maps_near_to_one_and_far_to_zero_at_extreme_ranges() {
        for (near, far) in [(0.1, 1000.0), (1e-4, 1e7)] {
            let p = reversed_z_projection(60.0, 16.0 / 9.0, near, far);
            let depth = |d: f64| {
                let c = p * glam::DVec4::new(0.0, 0.0, -d, 1.0);
                c.z / c.w
            };
            assert!((depth(near) - 1.0).abs() < 1e-9);
            assert!(depth(far).abs() < 1e-9);
            // Monotonic and still distinguishable in f32 between 1000 and 1001 units.
            let (a, b) = (depth(1000.0) as f32, depth(1001.0) as f32);
            assert!(a > b, "{a} {b}");
        }
    }
}
