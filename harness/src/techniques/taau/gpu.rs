//! The GPU part of `taau`: per frame a `scene` render pass at the render size, jittered by the
//! frame's Halton phase (`shared/jitter.rs`); the shared motion provider's `velocity` pass
//! (`render/velocity.rs`) when the scene has animated objects: the dynamic objects only, at the
//! render size, through the same jittered view as the scene pass; the `resolve` compute pass (`resolve.wgsl`, CPU model in
//! `model.rs`) writing the output with its accumulated weight in alpha and the depth of each
//! output pixel's sample; and, with `rcas`, FSR 1's RCAS (`shared/rcas.rs`) from the resolved colour to `color`.
//! Colour and depth histories are one ping-pong pair of sides (`kit::PingPong`): frame parity k
//! writes side k's colour and depth and reads the other's.

use std::collections::HashMap;

use glam::{DMat4, Mat4, Vec2};

use super::Options;
use crate::gpu::Gpu;
use crate::render::graph::{Graph, PassKind, Plan, Res, TextureDesc};
use crate::render::kit::{
    allocate, bind_group, compute_pipeline, record_scene_pass, timed_dispatch, PingPong, TextureMap,
};
use crate::render::renderer::{FrameInfo, Renderer};
use crate::render::scene::{Objects, SceneGpu, ScenePipeline, View, COLOR_FORMAT, DEPTH_FORMAT};
use crate::render::timers::Timers;
use crate::render::velocity::{self, VelocityPass, VELOCITY, VELOCITY_DEPTH};
use crate::techniques::shared::jitter::{jitter, ndc_offset};
use crate::techniques::shared::rcas::{rcas_pass, FsrPass};

pub static RESOLVE_WGSL: &str = include_str!("resolve.wgsl");

/// Format of the per-pixel sample depth kept for the disocclusion test.
pub const HISTORY_DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;

/// The render-size scene targets.
const COLOR_LOW: Res = Res::new("color_low");
const DEPTH_LOW: Res = Res::new("depth_low");
/// The output.
const COLOR: Res = Res::new("color");
/// The resolved colour pair (written this frame, read as history) with RCAS after it; without
/// RCAS the resolve writes the output pair itself.
const RESOLVED: [Res; 2] = [Res::new("taa"), Res::new("taa_history")];
const OUTPUTS: [Res; 2] = [COLOR, Res::new("color_history")];
/// The sample-depth pair.
const DEPTHS: [Res; 2] = [Res::new("taa_depth"), Res::new("taa_depth_history")];

/// The pair the resolve writes and reads: its own with RCAS, else the output pair.
fn resolved_pair(options: &Options) -> [Res; 2] {
    if options.rcas {
        RESOLVED
    } else {
        OUTPUTS
    }
}

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
    let resolved = resolved_pair(options);
    let mut g = Graph::default();
    g.resource(COLOR_LOW, tex(COLOR_FORMAT, lw, lh))
        .resource(DEPTH_LOW, tex(DEPTH_FORMAT, lw, lh))
        .pass("scene", PassKind::Render, &[], &[COLOR_LOW, DEPTH_LOW]);
    // Object motion at the render size: the resolve reads it at the sample it takes.
    velocity::declare(&mut g, lw, lh);
    g.resource(resolved[0], tex(COLOR_FORMAT, width, height))
        .resource(resolved[1], tex(COLOR_FORMAT, width, height))
        .resource(DEPTHS[0], tex(HISTORY_DEPTH_FORMAT, width, height))
        .resource(DEPTHS[1], tex(HISTORY_DEPTH_FORMAT, width, height));
    let use_velocity = options.velocity && dynamic_scene;
    let mut reads = vec![COLOR_LOW, DEPTH_LOW, resolved[1], DEPTHS[1]];
    if use_velocity {
        reads.extend([VELOCITY, VELOCITY_DEPTH]);
    }
    g.pass(
        "resolve",
        PassKind::Compute,
        &reads,
        &[resolved[0], DEPTHS[0]],
    );
    if options.rcas {
        g.resource(COLOR, tex(COLOR_FORMAT, width, height)).pass(
            "rcas",
            PassKind::Compute,
            &[resolved[0]],
            &[COLOR],
        );
    }
    g.output(COLOR);
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
    pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    /// The history pair: frame parity k writes side k and reads the other.
    sides: PingPong<Side>,
    scene_views: (wgpu::TextureView, wgpu::TextureView),
    velocity: VelocityPass,
    last: Option<LastFrame>,
}

/// What one side of the history pair is: the colour and depth the resolve writes (the other
/// side's read as history), its bind group, and RCAS from its colour to the output.
struct Side {
    resolved: Res,
    depth: Res,
    resolve: wgpu::BindGroup,
    rcas: Option<FsrPass>,
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
        let view = |res: Res| textures.view(res);
        let resolved = resolved_pair(&options);
        let pipeline = compute_pipeline(device, "resolve", RESOLVE_WGSL, "main");
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("taau params"),
            size: std::mem::size_of::<Params>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let velocity = VelocityPass::new(device, &plan, &textures);
        debug_assert_eq!(velocity.runs(), use_velocity);
        let layout = pipeline.get_bind_group_layout(0);
        let (color_low, depth_low) = (view(COLOR_LOW), view(DEPTH_LOW));
        let (colors, depths) = (PingPong::new(resolved), PingPong::new(DEPTHS));
        let side = |k: usize| {
            let (resolved, history) = colors.at(k);
            let (depth, depth_history) = depths.at(k);
            let resolve = bind_group(
                device,
                "resolve",
                &layout,
                &[(0, &params)],
                &[
                    (1, &color_low),
                    (2, &depth_low),
                    (3, &view(*history)),
                    (4, &view(*depth_history)),
                    (5, velocity.binding()),
                    (6, &view(*resolved)),
                    (7, &view(*depth)),
                    (8, velocity.depth_binding()),
                ],
            );
            let rcas = options.rcas_sharpness().map(|s| {
                rcas_pass(
                    gpu,
                    (&view(*resolved), &view(COLOR)),
                    (width, height),
                    s,
                    true,
                )
            });
            Side {
                resolved: *resolved,
                depth: *depth,
                resolve,
                rcas,
            }
        };
        let sides = PingPong::new([side(0), side(1)]);
        let scene_views = (view(COLOR_LOW), view(DEPTH_LOW));
        let low = options.render_size(width, height);
        TaauGpu {
            plan,
            textures,
            options,
            width,
            height,
            low,
            pipeline,
            params,
            sides,
            scene_views,
            velocity,
            last: None,
        }
    }

    /// A texture by resource name (`color_low`, `depth_low`, `velocity`); `resolved` and
    /// `depth` are this frame's resolve outputs, `history` and `depth_history` what it read.
    pub fn texture(&self, name: &str) -> Option<&wgpu::Texture> {
        let (current, history) = (self.sides.current(), self.sides.history());
        match name {
            "resolved" => self.textures.get(current.resolved.name()),
            "history" => self.textures.get(history.resolved.name()),
            "depth" => self.textures.get(current.depth.name()),
            "depth_history" => self.textures.get(history.depth.name()),
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
        let side = self.sides.current();
        match side.rcas {
            Some(_) => self.textures.texture(COLOR),
            None => self.textures.texture(side.resolved),
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
        let j = jitter(frame.index, self.options.phases(self.width));
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
        // The dynamic objects only, in the scene pass's jittered view (slot 0): where the
        // motion pass's depth equals the scene's, the sample shows a dynamic object; where the
        // scene's is nearer, a static object hides it and the camera reprojects the sample.
        let use_velocity =
            self.velocity
                .record_in(gpu, scene, timers, encoder, 0, Objects::Dynamic);
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
                f32::from(u8::from(o.freeze_converged)),
            ],
            mode: [
                u32::from(frame.history_valid),
                u32::from(use_velocity),
                u32::from(camera_still),
                u32::from(!o.clip_moving_only),
            ],
        };
        gpu.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        self.sides.select(frame.index);
        self.last = Some(LastFrame {
            jitter: j,
            history_valid: frame.history_valid,
            camera_still,
            prev_from_cur: prev_from_cur.as_mat4(),
            velocity: use_velocity,
        });
        let side = self.sides.current();
        timed_dispatch(
            encoder,
            timers,
            "resolve",
            &self.pipeline,
            &[&side.resolve],
            [self.width.div_ceil(8), self.height.div_ceil(8)],
        );
        if let Some(rcas) = &side.rcas {
            rcas.record(timers, encoder);
        }
    }
}
