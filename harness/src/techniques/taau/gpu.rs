//! The GPU part of `taau`: per frame a `scene` render pass at the render size, jittered by the
//! frame's Halton phase (`jitter.rs`); an output-resolution `velocity` pass when the scene has
//! animated objects; the `resolve` compute pass (`resolve.wgsl`, CPU model in
//! `model.rs`) writing the output with its accumulated weight in alpha and the depth of each
//! output pixel's sample; and, with `rcas`, FSR 1's RCAS from the resolved colour to `color`.
//! Colour and depth histories are ping-pong pairs: frame parity k writes pair member k and reads
//! the other.

use std::collections::HashMap;

use glam::{DMat4, Mat4, Vec2};

use super::jitter::{jitter, ndc_offset};
use super::Options;
use crate::gpu::Gpu;
use crate::render::graph::{Graph, PassKind, Plan, TextureDesc};
use crate::render::kit::{
    allocate, bind_group, compute_pipeline, placeholder_texture, record_scene_pass,
};
use crate::render::renderer::{FrameInfo, Renderer};
use crate::render::scene::{SceneGpu, ScenePipeline, View, COLOR_FORMAT, DEPTH_FORMAT};
use crate::render::timers::Timers;
use crate::techniques::fsr1::gpu::{rcas_pass, FsrPass};

pub static RESOLVE_WGSL: &str = include_str!("resolve.wgsl");

/// Format of the per-pixel sample depth kept for the disocclusion test.
pub const HISTORY_DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;

/// The resolved colour pair (written this frame, read as history) and the depth pair.
const RESOLVED: [&str; 2] = ["taa", "taa_history"];
const DEPTHS: [&str; 2] = ["taa_depth", "taa_depth_history"];

/// The pass graph at output `width` x `height`, and whether the resolve reads the velocity
/// buffer.
pub fn graph(options: &Options, width: u32, height: u32, dynamic_scene: bool) -> (Plan, bool) {
    let (lw, lh) = options.render_size(width, height);
    let tex = |format, width, height| TextureDesc {
        format,
        width,
        height,
        samples: 1,
        layers: 1,
    };
    // Without RCAS the resolved colour is the output.
    let resolved = if options.rcas {
        RESOLVED
    } else {
        ["color", "color_history"]
    };
    let mut g = Graph::default();
    g.resource("color_low", tex(COLOR_FORMAT, lw, lh))
        .resource("depth_low", tex(DEPTH_FORMAT, lw, lh))
        .resource("velocity", tex(COLOR_FORMAT, width, height))
        .resource("velocity_depth", tex(DEPTH_FORMAT, width, height))
        .resource(resolved[0], tex(COLOR_FORMAT, width, height))
        .resource(resolved[1], tex(COLOR_FORMAT, width, height))
        .resource(DEPTHS[0], tex(HISTORY_DEPTH_FORMAT, width, height))
        .resource(DEPTHS[1], tex(HISTORY_DEPTH_FORMAT, width, height))
        .pass("scene", PassKind::Render, &[], &["color_low", "depth_low"])
        .pass(
            "velocity",
            PassKind::Render,
            &[],
            &["velocity", "velocity_depth"],
        );
    let use_velocity = options.velocity && dynamic_scene;
    let mut reads = vec!["color_low", "depth_low", resolved[1], DEPTHS[1]];
    if use_velocity {
        reads.push("velocity");
    }
    g.pass(
        "resolve",
        PassKind::Compute,
        &reads,
        &[resolved[0], DEPTHS[0]],
    );
    if options.rcas {
        g.resource("color", tex(COLOR_FORMAT, width, height)).pass(
            "rcas",
            PassKind::Compute,
            &[resolved[0]],
            &["color"],
        );
    }
    g.output("color");
    (
        g.plan().expect("built-in graphs are well formed"),
        use_velocity,
    )
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    prev_from_cur: [[f32; 4]; 4],
    size: [u32; 4],
    jitter: [f32; 4],
    weights: [f32; 4],
    mode: [u32; 4],
}

/// The weight a fill (no history, no sample landing) is given: replaced by the first sample that
/// lands.
pub const FILL_WEIGHT: f32 = 1.0 / 256.0;

/// What the last recorded resolve was given (for the CPU model in tests).
#[derive(Clone, Copy, Debug)]
pub struct LastFrame {
    pub jitter: Vec2,
    pub history_valid: bool,
    pub camera_still: bool,
    pub prev_from_cur: Mat4,
    pub velocity: bool,
}

pub struct TaauGpu {
    plan: Plan,
    textures: HashMap<&'static str, wgpu::Texture>,
    options: Options,
    width: u32,
    height: u32,
    low: (u32, u32),
    /// Names of the resolved colour pair in the plan.
    resolved: [&'static str; 2],
    pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    /// By parity: parity k writes pair member k and reads the other.
    bind_groups: [wgpu::BindGroup; 2],
    /// RCAS by parity (its input alternates with the resolved pair).
    rcas: Option<[FsrPass; 2]>,
    current: usize,
    scene_views: (wgpu::TextureView, wgpu::TextureView),
    velocity_views: Option<(wgpu::TextureView, wgpu::TextureView)>,
    _dummy_velocity: Option<wgpu::Texture>,
    last: Option<LastFrame>,
}

impl TaauGpu {
    pub fn new(
        gpu: &Gpu,
        options: Options,
        width: u32,
        height: u32,
        dynamic_scene: bool,
    ) -> TaauGpu {
        let device = &gpu.device;
        let (plan, use_velocity) = graph(&options, width, height, dynamic_scene);
        let textures = allocate(device, &plan);
        let view = |name: &str| textures[name].create_view(&Default::default());
        let resolved = if options.rcas {
            RESOLVED
        } else {
            ["color", "color_history"]
        };
        let pipeline = compute_pipeline(device, "resolve", RESOLVE_WGSL, "main");
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("taau params"),
            size: std::mem::size_of::<Params>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let dummy =
            (!use_velocity).then(|| placeholder_texture(device, "no velocity", COLOR_FORMAT));
        let velocity_view = match &dummy {
            Some(t) => t.create_view(&Default::default()),
            None => view("velocity"),
        };
        let layout = pipeline.get_bind_group_layout(0);
        let (color_low, depth_low) = (view("color_low"), view("depth_low"));
        let bind_groups = [0, 1].map(|k| {
            bind_group(
                device,
                "resolve",
                &layout,
                &[(0, &params)],
                &[
                    (1, &color_low),
                    (2, &depth_low),
                    (3, &view(resolved[1 - k])),
                    (4, &view(DEPTHS[1 - k])),
                    (5, &velocity_view),
                    (6, &view(resolved[k])),
                    (7, &view(DEPTHS[k])),
                ],
            )
        });
        let rcas = options.rcas_sharpness().map(|s| {
            [0, 1].map(|k| {
                rcas_pass(
                    gpu,
                    (&view(resolved[k]), &view("color")),
                    (width, height),
                    s,
                    true,
                )
            })
        });
        let scene_views = (view("color_low"), view("depth_low"));
        let velocity_views = use_velocity.then(|| (view("velocity"), view("velocity_depth")));
        let low = options.render_size(width, height);
        TaauGpu {
            plan,
            textures,
            options,
            width,
            height,
            low,
            resolved,
            pipeline,
            params,
            bind_groups,
            rcas,
            current: 0,
            scene_views,
            velocity_views,
            _dummy_velocity: dummy,
            last: None,
        }
    }

    /// A texture by resource name (`color_low`, `depth_low`, `velocity`); `resolved` and
    /// `depth` are this frame's resolve outputs, `history` and `depth_history` what it read.
    pub fn texture(&self, name: &str) -> Option<&wgpu::Texture> {
        let k = self.current;
        match name {
            "resolved" => self.textures.get(self.resolved[k]),
            "history" => self.textures.get(self.resolved[1 - k]),
            "depth" => self.textures.get(DEPTHS[k]),
            "depth_history" => self.textures.get(DEPTHS[1 - k]),
            _ => self.textures.get(name),
        }
    }

    pub fn last_frame(&self) -> Option<LastFrame> {
        self.last
    }

    pub fn options(&self) -> Options {
        self.options
    }

    /// The render size.
    pub fn render_size(&self) -> (u32, u32) {
        self.low
    }
}

impl Renderer for TaauGpu {
    fn plan(&self) -> &Plan {
        &self.plan
    }

    fn output(&self) -> &wgpu::Texture {
        match self.rcas {
            Some(_) => &self.textures["color"],
            None => &self.textures[self.resolved[self.current]],
        }
    }

    fn record(
        &mut self,
        gpu: &Gpu,
        scene: &mut SceneGpu,
        timers: &Timers,
        encoder: &mut wgpu::CommandEncoder,
        frame: FrameInfo,
    ) {
        let j = jitter(frame.index, self.options.phases());
        let base = View::whole(frame.time, frame.prev_time);
        scene.write_view(
            &gpu.queue,
            0,
            &View {
                ndc_offset: ndc_offset(j, self.low.0, self.low.1),
                gradient_scale: self.options.gradient_scale(),
                ..base
            },
        );
        record_scene_pass(
            gpu,
            scene,
            timers,
            encoder,
            "scene",
            &self.scene_views.0,
            &self.scene_views.1,
            0,
            ScenePipeline::Forward { samples: 1 },
        );
        let use_velocity = self.velocity_views.is_some();
        if let Some((c, d)) = &self.velocity_views {
            scene.write_view(&gpu.queue, 1, &base);
            record_scene_pass(
                gpu,
                scene,
                timers,
                encoder,
                "velocity",
                c,
                d,
                1,
                ScenePipeline::Velocity,
            );
        }
        let (cur, prev) = scene.view_projections(frame.time, frame.prev_time);
        // A still camera reprojects static content exactly onto itself.
        let camera_still = cur == prev;
        let prev_from_cur = if camera_still {
            DMat4::IDENTITY
        } else {
            prev * cur.inverse()
        };
        let o = &self.options;
        let params = Params {
            prev_from_cur: prev_from_cur.as_mat4().to_cols_array_2d(),
            size: [self.low.0, self.low.1, self.width, self.height],
            jitter: [j.x, j.y, o.clip_gamma, o.depth_tolerance],
            weights: [
                o.max_weight,
                o.moving_weight,
                FILL_WEIGHT,
                f32::from(u8::from(o.hold)),
            ],
            mode: [
                u32::from(frame.history_valid),
                u32::from(use_velocity),
                u32::from(camera_still),
                u32::from(o.clip_still),
            ],
        };
        gpu.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        self.current = (frame.index & 1) as usize;
        self.last = Some(LastFrame {
            jitter: j,
            history_valid: frame.history_valid,
            camera_still,
            prev_from_cur: prev_from_cur.as_mat4(),
            velocity: use_velocity,
        });
        let q = timers.begin("resolve", encoder);
        {
            let mut cp = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("resolve"),
                timestamp_writes: q.compute_pass_timestamp_writes(),
            });
            cp.set_pipeline(&self.pipeline);
            cp.set_bind_group(0, &self.bind_groups[self.current], &[]);
            cp.dispatch_workgroups(self.width.div_ceil(8), self.height.div_ceil(8), 1);
        }
        timers.end(encoder, q);
        if let Some(rcas) = &self.rcas {
            rcas[self.current].record(timers, encoder);
        }
    }
}
