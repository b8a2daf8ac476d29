//! The GPU part of `interlace` with the default `pattern = "interlaced"` (section 3.3's offset
//! sampling): per frame (parity `p = index & 1`) two quarter-resolution `scene` passes, layer r
//! of `rows_color` / `rows_depth` shading rows `2j + r` at columns `2i + ((r + p) & 1)` (the
//! projection remapped, `View::ndc_scale` / `ndc_offset`), so the shaded pixels form a
//! checkerboard; the shared motion provider's `velocity` pass (`render/velocity.rs`: the
//! dynamic objects only, at full resolution) when the scene has animated objects; and a
//! `reconstruct` compute pass writing every full-resolution pixel and its depth
//! (`reconstruct.wgsl`, CPU model in `model.rs`). The output and its depth are ping-pong pairs
//! with the previous frame's (`color` / `color_history`, `depth` / `depth_history`).
//!
//! Siege renders the pattern in one half-width pass with an MSAA trick; two single-sample
//! quarter-resolution passes shade the same pixels on any adapter, at twice the vertex work.

use std::collections::HashMap;

use glam::Vec2;

use super::model::quarter_size;
use super::Options;
use crate::gpu::Gpu;
use crate::render::graph::{Graph, PassKind, Plan, TextureDesc};
use crate::render::kit::{
    allocate, bind_group, compute_pipeline, record_scene_pass, timed_dispatch, PingPong,
};
use crate::render::renderer::{FrameInfo, Renderer};
use crate::render::scene::{Objects, SceneGpu, ScenePipeline, View, COLOR_FORMAT, DEPTH_FORMAT};
use crate::render::timers::Timers;
use crate::render::velocity::{self, VelocityPass, VELOCITY, VELOCITY_DEPTH};

pub static RECONSTRUCT_WGSL: &str = include_str!("reconstruct.wgsl");

/// The output pair and the output depth pair: written this frame, read as history.
const OUTPUTS: [&str; 2] = ["color", "color_history"];
const DEPTHS: [&str; 2] = ["depth", "depth_history"];
/// The format of the output depth (reversed-Z, as the scene's).
const OUT_DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;
const SCENE_PASSES: [&str; 2] = ["scene_even_rows", "scene_odd_rows"];

/// The pass graph at `width` x `height`, and whether the reconstruction reads the velocity
/// buffer (animated objects and the `velocity` option).
pub fn graph(options: &Options, width: u32, height: u32, dynamic_scene: bool) -> (Plan, bool) {
    let (qw, qh) = quarter_size(width, height);
    let q = |format| TextureDesc {
        format,
        width: qw,
        height: qh,
        samples: 1,
        layers: 2,
    };
    let full = |format| TextureDesc {
        format,
        width,
        height,
        samples: 1,
        layers: 1,
    };
    let mut g = Graph::default();
    g.resource("rows_color", q(COLOR_FORMAT))
        .resource("rows_depth", q(DEPTH_FORMAT))
        .resource(OUTPUTS[0], full(COLOR_FORMAT))
        .resource(OUTPUTS[1], full(COLOR_FORMAT))
        .resource(DEPTHS[0], full(OUT_DEPTH_FORMAT))
        .resource(DEPTHS[1], full(OUT_DEPTH_FORMAT));
    for name in SCENE_PASSES {
        g.pass(name, PassKind::Render, &[], &["rows_color", "rows_depth"]);
    }
    velocity::declare(&mut g, width, height);
    let use_velocity = options.velocity && dynamic_scene;
    let mut reads = vec!["rows_color", "rows_depth", OUTPUTS[1], DEPTHS[1]];
    if use_velocity {
        reads.extend([VELOCITY.name(), VELOCITY_DEPTH.name()]);
    }
    g.pass(
        "reconstruct",
        PassKind::Compute,
        &reads,
        &[OUTPUTS[0], DEPTHS[0]],
    )
    .output(OUTPUTS[0]);
    (
        g.plan().expect("built-in graphs are well formed"),
        use_velocity,
    )
}

/// NDC remap (scale, offset) of layer `row` (0 even rows, 1 odd rows) on frame `parity`:
/// texel (i, j)'s centre samples the centre of full-resolution pixel
/// `(2i + ((row + parity) & 1), 2j + row)`.
pub fn rows_view(width: u32, height: u32, parity: u32, row: u32) -> (Vec2, Vec2) {
    let (qw, qh) = quarter_size(width, height);
    let (qw, qh) = (qw as f32, qh as f32);
    let sx = width as f32 / (2.0 * qw);
    let sy = height as f32 / (2.0 * qh);
    let column = ((row + parity) & 1) as f32;
    (
        Vec2::new(sx, sy),
        Vec2::new(
            sx - 1.0 + (0.5 - column) / qw,
            1.0 - sy - (0.5 - row as f32) / qh,
        ),
    )
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    prev_from_cur: [[f32; 4]; 4],
    size: [u32; 4],
    mode: [u32; 4],
    depth: [f32; 4],
    weights: [f32; 4],
}

/// What the last recorded reconstruction was given (for the CPU model in tests).
#[derive(Clone, Copy, Debug)]
pub struct LastFrame {
    pub parity: u32,
    pub history_valid: bool,
    pub still: bool,
    pub prev_from_cur: glam::Mat4,
    pub velocity: bool,
    pub near: f32,
    pub far: f32,
}

pub struct InterlaceGpu {
    plan: Plan,
    textures: HashMap<&'static str, wgpu::Texture>,
    options: Options,
    width: u32,
    height: u32,
    pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    /// By parity: parity k writes `OUTPUTS[k]`, `DEPTHS[k]` and reads the others as history.
    bind_groups: PingPong<wgpu::BindGroup>,
    /// Render views of the two layers (colour, depth).
    row_views: [(wgpu::TextureView, wgpu::TextureView); 2],
    velocity: VelocityPass,
    /// The scene has animated objects (so something may move with the camera still).
    dynamic_scene: bool,
    last: Option<LastFrame>,
}

impl InterlaceGpu {
    pub fn new(
        gpu: &Gpu,
        options: Options,
        width: u32,
        height: u32,
        dynamic_scene: bool,
    ) -> InterlaceGpu {
        let device = &gpu.device;
        let (plan, use_velocity) = graph(&options, width, height, dynamic_scene);
        let textures = allocate(device, &plan);
        let view = |name: &str| textures[name].create_view(&Default::default());
        let array = |name: &str| {
            textures[name].create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            })
        };
        let layer = |name: &str, l: u32| {
            textures[name].create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2),
                base_array_layer: l,
                array_layer_count: Some(1),
                ..Default::default()
            })
        };
        let pipeline = compute_pipeline(device, "reconstruct", RECONSTRUCT_WGSL, "main");
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("interlace params"),
            size: std::mem::size_of::<Params>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let velocity = VelocityPass::new(device, &plan, &textures);
        debug_assert_eq!(velocity.runs(), use_velocity);
        let bgl = pipeline.get_bind_group_layout(0);
        let (rows_color, rows_depth) = (array("rows_color"), array("rows_depth"));
        let bind_groups = [0, 1].map(|k| {
            bind_group(
                device,
                "reconstruct",
                &bgl,
                &[(0, &params)],
                &[
                    (1, &rows_color),
                    (2, &rows_depth),
                    (3, &view(OUTPUTS[1 - k])),
                    (4, &view(DEPTHS[1 - k])),
                    (5, velocity.binding()),
                    (6, &view(OUTPUTS[k])),
                    (7, &view(DEPTHS[k])),
                    (8, velocity.depth_binding()),
                ],
            )
        });
        let row_views = [0, 1].map(|l| (layer("rows_color", l), layer("rows_depth", l)));
        InterlaceGpu {
            plan,
            textures,
            options,
            width,
            height,
            pipeline,
            params,
            bind_groups: PingPong::new(bind_groups),
            row_views,
            velocity,
            dynamic_scene,
            last: None,
        }
    }

    /// A texture of the plan by resource name (`rows_color`, `velocity`, ...); `history` and
    /// `history_depth` are the output and depth the last frame read, `depth_out` the depth it
    /// wrote.
    pub fn texture(&self, name: &str) -> Option<&wgpu::Texture> {
        let read = 1 - self.bind_groups.side();
        match name {
            "depth_out" => self.textures.get(DEPTHS[1 - read]),
            "history" => self.textures.get(OUTPUTS[read]),
            "history_depth" => self.textures.get(DEPTHS[read]),
            _ => self.textures.get(name),
        }
    }

    pub fn last_frame(&self) -> Option<LastFrame> {
        self.last
    }
}

impl Renderer for InterlaceGpu {
    fn plan(&self) -> &Plan {
        &self.plan
    }

    fn output(&self) -> &wgpu::Texture {
        &self.textures[OUTPUTS[self.bind_groups.side()]]
    }

    fn record(
        &mut self,
        gpu: &Gpu,
        scene: &mut SceneGpu,
        timers: &Timers,
        encoder: &mut wgpu::CommandEncoder,
        frame: FrameInfo,
    ) {
        let parity = frame.index & 1;
        let base = View::whole(frame.time, frame.prev_time);
        for (row, name) in SCENE_PASSES.into_iter().enumerate() {
            let (scale, offset) = rows_view(self.width, self.height, parity, row as u32);
            scene.write_view(
                &gpu.queue,
                row as u32,
                &View {
                    ndc_scale: scale,
                    ndc_offset: offset,
                    gradient_scale: self.options.gradient_scale,
                    ..base
                },
            );
            let (c, d) = &self.row_views[row];
            record_scene_pass(
                gpu,
                scene,
                timers,
                encoder,
                name,
                c,
                d,
                row as u32,
                ScenePipeline::Forward { samples: 1 },
            );
        }
        // The dynamic objects only; the reconstruction tells a static object in front of one
        // by comparing the motion pass's depth with the shaded neighbour's.
        let use_velocity = self.velocity.record(
            gpu,
            scene,
            timers,
            encoder,
            2,
            frame.time,
            frame.prev_time,
            Objects::Dynamic,
        );
        let (cur, prev) = scene.view_projections(frame.time, frame.prev_time);
        // Nothing can have changed: the camera is where it was, nothing is animated, no light
        // moves.
        let still = cur == prev && !self.dynamic_scene && !scene.lights_animated();
        let (near, far) = scene.near_far();
        let o = &self.options;
        let params = Params {
            prev_from_cur: (prev * cur.inverse()).as_mat4().to_cols_array_2d(),
            size: [
                self.width,
                self.height,
                quarter_size(self.width, self.height).0,
                parity,
            ],
            mode: [
                u32::from(frame.history_valid),
                u32::from(use_velocity),
                u32::from(o.clamp),
                u32::from(still),
            ],
            depth: [near, far, o.depth_tolerance, 0.0],
            weights: [o.coherency, o.velocity_scale, 0.0, 0.0],
        };
        gpu.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        self.bind_groups.select(parity);
        self.last = Some(LastFrame {
            parity,
            history_valid: frame.history_valid,
            still,
            prev_from_cur: glam::Mat4::from_cols_array_2d(&params.prev_from_cur),
            velocity: use_velocity,
            near,
            far,
        });
        timed_dispatch(
            encoder,
            timers,
            "reconstruct",
            &self.pipeline,
            &[self.bind_groups.current()],
            [self.width.div_ceil(8), self.height.div_ceil(8)],
        );
    }
}
