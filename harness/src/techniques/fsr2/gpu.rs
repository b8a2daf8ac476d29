//! The GPU part of `fsr2`: per frame a `scene` render pass at the render size jittered by AMD's
//! sequence; the shared motion provider's `velocity` pass when the scene has animated objects;
//! then AMD's dispatch order (ffx_fsr2.cpp `fsr2Dispatch`) as compute passes: `motion` (the
//! engine's motion vectors), `luminance_pyramid` and `auto_exposure`, `reconstruct`,
//! `depth_clip`, `lock`, `accumulate` and, with sharpening, `rcas`. Textures in the pass graph;
//! three small buffers beside it (the exposure, the reconstructed previous depth as atomics, the
//! new locks), as AMD keeps them in UAVs. History pairs (the accumulated colour, lock status,
//! luma history, dilated motion) as `kit::PingPong`.

use std::collections::HashMap;

use glam::{DMat4, Vec2};

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

pub static COMMON_WGSL: &str = include_str!("common.wgsl");
pub static MOTION_WGSL: &str = include_str!("motion.wgsl");
pub static LUMINANCE_WGSL: &str = include_str!("luminance.wgsl");
pub static RECONSTRUCT_WGSL: &str = include_str!("reconstruct.wgsl");
pub static DEPTH_CLIP_WGSL: &str = include_str!("depth_clip.wgsl");
pub static LOCK_WGSL: &str = include_str!("lock.wgsl");
pub static ACCUMULATE_WGSL: &str = include_str!("accumulate.wgsl");
pub static RCAS_WGSL: &str = include_str!("rcas.wgsl");

/// Every pass file, each compiled after `common.wgsl`.
pub static PASSES: &[(&str, &str)] = &[
    ("fsr2/motion.wgsl", MOTION_WGSL),
    ("fsr2/luminance.wgsl", LUMINANCE_WGSL),
    ("fsr2/reconstruct.wgsl", RECONSTRUCT_WGSL),
    ("fsr2/depth_clip.wgsl", DEPTH_CLIP_WGSL),
    ("fsr2/lock.wgsl", LOCK_WGSL),
    ("fsr2/accumulate.wgsl", ACCUMULATE_WGSL),
    ("fsr2/rcas.wgsl", RCAS_WGSL),
];

/// A pass file's module as the GPU compiles it: `common.wgsl` then the pass.
pub fn module(pass: &str) -> String {
    format!("{COMMON_WGSL}\n{pass}")
}

/// The shading-change mip (FFX_FSR2_SHADING_CHANGE_MIP_LEVEL): texels of 2^(level + 1) render
/// pixels per axis.
pub const LUMA_MIP_LEVEL: u32 = 4;

const COLOR_LOW: Res = Res::new("color_low");
const DEPTH_LOW: Res = Res::new("depth_low");
const MOTION: Res = Res::new("motion");
const LUMA_MIP: Res = Res::new("luma_mip");
const DILATED_DEPTH: Res = Res::new("dilated_depth");
const DILATED_MOTION: [Res; 2] = [
    Res::new("dilated_motion"),
    Res::new("dilated_motion_history"),
];
const LOCK_LUMA: Res = Res::new("lock_luma");
const PREPARED: Res = Res::new("prepared_color");
const REACTIVE: Res = Res::new("dilated_reactive");
const INTERNAL: [Res; 2] = [Res::new("internal_color"), Res::new("internal_history")];
const LOCK_STATUS: [Res; 2] = [Res::new("lock_status"), Res::new("lock_status_history")];
const LUMA_HISTORY: [Res; 2] = [Res::new("luma_history"), Res::new("luma_history_prev")];
const COLOR: Res = Res::new("color");
/// The three storage buffers (exposure, reconstructed previous depth, new locks) as the graph
/// sees them: 1x1 stand-ins that order and keep the passes that write and read them (the graph
/// knows textures only); the buffers themselves are made beside it.
const EXPOSURE: Res = Res::new("exposure");
const RECONSTRUCTED_DEPTH: Res = Res::new("reconstructed_depth");
const NEW_LOCKS: Res = Res::new("new_locks");

/// The shading-change mip's size at render size `low` (AMD's `lumaMipDimensions`).
pub fn luma_mip_size(low: (u32, u32)) -> (u32, u32) {
    let div = 2u32 << LUMA_MIP_LEVEL;
    ((low.0 / div).max(1), (low.1 / div).max(1))
}

/// The pass graph at output `width` x `height`, and whether `motion` reads the velocity buffer.
pub fn graph(options: &Options, width: u32, height: u32, dynamic_scene: bool) -> (Plan, bool) {
    let (lw, lh) = options.render_size(width, height);
    let tex = |format, width, height| TextureDesc {
        format,
        width,
        height,
        samples: 1,
        layers: 1,
    };
    use wgpu::TextureFormat::{R32Float, Rg32Float, Rgba16Float};
    let (mw, mh) = luma_mip_size((lw, lh));
    let mut g = Graph::default();
    g.resource(COLOR_LOW, tex(COLOR_FORMAT, lw, lh))
        .resource(DEPTH_LOW, tex(DEPTH_FORMAT, lw, lh))
        .pass("scene", PassKind::Render, &[], &[COLOR_LOW, DEPTH_LOW]);
    velocity::declare(&mut g, lw, lh);
    let use_velocity = options.velocity && dynamic_scene;
    let mut motion_reads = vec![DEPTH_LOW];
    if use_velocity {
        motion_reads.extend([VELOCITY, VELOCITY_DEPTH]);
    }
    g.resource(MOTION, tex(Rg32Float, lw, lh)).pass(
        "motion",
        PassKind::Compute,
        &motion_reads,
        &[MOTION],
    );
    g.resource(LUMA_MIP, tex(R32Float, mw, mh))
        .pass(
            "luminance_pyramid",
            PassKind::Compute,
            &[COLOR_LOW],
            &[LUMA_MIP],
        )
        .resource(EXPOSURE, tex(R32Float, 1, 1))
        .pass("auto_exposure", PassKind::Compute, &[LUMA_MIP], &[EXPOSURE]);
    for r in DILATED_MOTION {
        g.resource(r, tex(Rg32Float, lw, lh));
    }
    g.resource(DILATED_DEPTH, tex(R32Float, lw, lh))
        .resource(LOCK_LUMA, tex(R32Float, lw, lh))
        .resource(RECONSTRUCTED_DEPTH, tex(R32Float, 1, 1))
        .pass(
            "reconstruct",
            PassKind::Compute,
            &[DEPTH_LOW, MOTION, COLOR_LOW, EXPOSURE],
            &[
                DILATED_DEPTH,
                DILATED_MOTION[0],
                LOCK_LUMA,
                RECONSTRUCTED_DEPTH,
            ],
        );
    g.resource(PREPARED, tex(Rgba16Float, lw, lh))
        .resource(REACTIVE, tex(Rg32Float, lw, lh))
        .pass(
            "depth_clip",
            PassKind::Compute,
            &[
                DILATED_DEPTH,
                DILATED_MOTION[0],
                DILATED_MOTION[1],
                MOTION,
                COLOR_LOW,
                EXPOSURE,
                RECONSTRUCTED_DEPTH,
            ],
            &[PREPARED, REACTIVE],
        );
    g.resource(NEW_LOCKS, tex(R32Float, 1, 1)).pass(
        "lock",
        PassKind::Compute,
        &[LOCK_LUMA, RECONSTRUCTED_DEPTH],
        &[NEW_LOCKS],
    );
    for r in INTERNAL.iter().chain(&LOCK_STATUS).chain(&LUMA_HISTORY) {
        g.resource(*r, tex(Rgba16Float, width, height));
    }
    g.pass(
        "accumulate",
        PassKind::Compute,
        &[
            PREPARED,
            DILATED_MOTION[0],
            REACTIVE,
            INTERNAL[1],
            LOCK_STATUS[1],
            LUMA_HISTORY[1],
            LUMA_MIP,
            EXPOSURE,
            NEW_LOCKS,
        ],
        &[INTERNAL[0], LOCK_STATUS[0], LUMA_HISTORY[0]],
    );
    if options.sharpening {
        g.resource(COLOR, tex(COLOR_FORMAT, width, height)).pass(
            "rcas",
            PassKind::Compute,
            &[INTERNAL[0], EXPOSURE],
            &[COLOR],
        );
        g.output(COLOR);
    } else {
        g.output(INTERNAL[0]);
    }
    (
        g.plan().expect("built-in graphs are well formed"),
        use_velocity,
    )
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    size: [u32; 4],
    jitter: [f32; 4],
    depth_to_view: [f32; 4],
    mode: [u32; 4],
    luma: [u32; 4],
    prev_from_cur: [[f32; 4]; 4],
}

/// AMD's `DeviceToViewSpaceTransformFactors` for a reversed, finite projection
/// (ffx_fsr2.cpp `setupDeviceDepthToViewSpaceDepthParams`): `near`, `far`, and the projection's
/// x and y scales `a` = cot(fov/2) / aspect and `b` = cot(fov/2).
pub fn depth_to_view(near: f32, far: f32, a: f32, b: f32) -> [f32; 4] {
    // Inverted: fMin = far, fMax = near.
    let (f_min, f_max) = (far, near);
    let q = f_max / (f_min - f_max);
    [-q, q * f_min, 1.0 / a, 1.0 / b]
}

/// What one frame side binds: the pipelines' bind groups that differ by parity.
struct Side {
    reconstruct: wgpu::BindGroup,
    depth_clip: wgpu::BindGroup,
    accumulate: wgpu::BindGroup,
    rcas: Option<wgpu::BindGroup>,
    output: Res,
}

struct Pipelines {
    motion: wgpu::ComputePipeline,
    luminance: wgpu::ComputePipeline,
    exposure: wgpu::ComputePipeline,
    reconstruct: wgpu::ComputePipeline,
    depth_clip: wgpu::ComputePipeline,
    lock: wgpu::ComputePipeline,
    accumulate: wgpu::ComputePipeline,
    /// With sharpening only.
    rcas: Option<wgpu::ComputePipeline>,
}

pub struct Fsr2Gpu {
    plan: Plan,
    textures: HashMap<&'static str, wgpu::Texture>,
    options: Options,
    width: u32,
    height: u32,
    low: (u32, u32),
    params: wgpu::Buffer,
    pipelines: Pipelines,
    /// Bind groups that do not change with the frame's parity.
    motion: wgpu::BindGroup,
    luminance: wgpu::BindGroup,
    exposure: wgpu::BindGroup,
    lock: wgpu::BindGroup,
    sides: PingPong<Side>,
    scene_views: (wgpu::TextureView, wgpu::TextureView),
    velocity: VelocityPass,
    last_jitter: Vec2,
}

impl Fsr2Gpu {
    pub fn new(
        gpu: &Gpu,
        options: Options,
        width: u32,
        height: u32,
        dynamic_scene: bool,
    ) -> Fsr2Gpu {
        use wgpu::util::DeviceExt;
        let device = &gpu.device;
        let (plan, use_velocity) = graph(&options, width, height, dynamic_scene);
        let textures = allocate(device, &plan);
        let view = |res: Res| textures.view(res);
        let low = options.render_size(width, height);
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("fsr2 params"),
            size: std::mem::size_of::<Params>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let storage = |label: &str, contents: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        // The exposure starts "reset" (an average above AMD's smoothing threshold).
        let exposure_buf = storage("fsr2 exposure", bytemuck::cast_slice(&[1.0f32, 1e9]));
        let reconstructed = storage(
            "fsr2 reconstructed previous depth",
            &vec![0u8; (low.0 * low.1 * 4) as usize],
        );
        let new_locks = storage("fsr2 new locks", &vec![0u8; (width * height * 4) as usize]);
        let pipe =
            |source: &str, entry: &str| compute_pipeline(device, entry, &module(source), entry);
        let pipelines = Pipelines {
            motion: pipe(MOTION_WGSL, "motion"),
            luminance: pipe(LUMINANCE_WGSL, "luminance_pyramid"),
            exposure: pipe(LUMINANCE_WGSL, "auto_exposure"),
            reconstruct: pipe(RECONSTRUCT_WGSL, "reconstruct"),
            depth_clip: pipe(DEPTH_CLIP_WGSL, "depth_clip"),
            lock: pipe(LOCK_WGSL, "lock"),
            accumulate: pipe(ACCUMULATE_WGSL, "accumulate"),
            rcas: options.sharpening.then(|| pipe(RCAS_WGSL, "rcas")),
        };
        // AMD's `cbRCAS` (ffx_fsr2.cpp `fsr2Dispatch`: `FsrRcasCon` of `-2 sharpness + 2` stops).
        let rcas_config = options.rcas_stops().map(|stops| {
            let linear = (-stops).exp2();
            let half = u32::from(half::f16::from_f32(linear).to_bits());
            let con = [linear.to_bits(), half | (half << 16), 0, 0];
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("fsr2 rcas config"),
                contents: bytemuck::cast_slice(&con),
                usage: wgpu::BufferUsages::UNIFORM,
            })
        });
        let velocity = VelocityPass::new(device, &plan, &textures);
        debug_assert_eq!(velocity.runs(), use_velocity);
        let layout = |p: &wgpu::ComputePipeline| p.get_bind_group_layout(0);
        let motion = bind_group(
            device,
            "motion",
            &layout(&pipelines.motion),
            &[(0, &params)],
            &[
                (1, &view(DEPTH_LOW)),
                (2, velocity.binding()),
                (3, velocity.depth_binding()),
                (4, &view(MOTION)),
            ],
        );
        let luminance = bind_group(
            device,
            "luminance_pyramid",
            &layout(&pipelines.luminance),
            &[(0, &params)],
            &[(1, &view(COLOR_LOW)), (2, &view(LUMA_MIP))],
        );
        let exposure = bind_group(
            device,
            "auto_exposure",
            &layout(&pipelines.exposure),
            &[(0, &params), (4, &exposure_buf)],
            &[(3, &view(LUMA_MIP))],
        );
        let lock = bind_group(
            device,
            "lock",
            &layout(&pipelines.lock),
            &[(0, &params), (2, &new_locks), (3, &reconstructed)],
            &[(1, &view(LOCK_LUMA))],
        );
        let (motions, internals) = (PingPong::new(DILATED_MOTION), PingPong::new(INTERNAL));
        let (locks, lumas) = (PingPong::new(LOCK_STATUS), PingPong::new(LUMA_HISTORY));
        let side = |k: usize| {
            let (motion_cur, motion_prev) = motions.at(k);
            let (internal_cur, internal_prev) = internals.at(k);
            let (lock_cur, lock_prev) = locks.at(k);
            let (luma_cur, luma_prev) = lumas.at(k);
            let reconstruct = bind_group(
                device,
                "reconstruct",
                &layout(&pipelines.reconstruct),
                &[(0, &params), (4, &exposure_buf), (8, &reconstructed)],
                &[
                    (1, &view(DEPTH_LOW)),
                    (2, &view(MOTION)),
                    (3, &view(COLOR_LOW)),
                    (5, &view(DILATED_DEPTH)),
                    (6, &view(*motion_cur)),
                    (7, &view(LOCK_LUMA)),
                ],
            );
            let depth_clip = bind_group(
                device,
                "depth_clip",
                &layout(&pipelines.depth_clip),
                &[(0, &params), (6, &exposure_buf), (7, &reconstructed)],
                &[
                    (1, &view(DILATED_DEPTH)),
                    (2, &view(*motion_cur)),
                    (3, &view(*motion_prev)),
                    (4, &view(MOTION)),
                    (5, &view(COLOR_LOW)),
                    (8, &view(PREPARED)),
                    (9, &view(REACTIVE)),
                ],
            );
            let accumulate = bind_group(
                device,
                "accumulate",
                &layout(&pipelines.accumulate),
                &[(0, &params), (8, &exposure_buf), (9, &new_locks)],
                &[
                    (1, &view(PREPARED)),
                    (2, &view(*motion_cur)),
                    (3, &view(REACTIVE)),
                    (4, &view(*internal_prev)),
                    (5, &view(*lock_prev)),
                    (6, &view(*luma_prev)),
                    (7, &view(LUMA_MIP)),
                    (10, &view(*internal_cur)),
                    (11, &view(*lock_cur)),
                    (12, &view(*luma_cur)),
                ],
            );
            let rcas = pipelines
                .rcas
                .as_ref()
                .zip(rcas_config.as_ref())
                .map(|(p, con)| {
                    bind_group(
                        device,
                        "rcas",
                        &layout(p),
                        &[(0, &params), (2, &exposure_buf), (4, con)],
                        &[(1, &view(*internal_cur)), (3, &view(COLOR))],
                    )
                });
            let output = if rcas.is_some() { COLOR } else { *internal_cur };
            Side {
                reconstruct,
                depth_clip,
                accumulate,
                rcas,
                output,
            }
        };
        let sides = PingPong::new([side(0), side(1)]);
        let scene_views = (view(COLOR_LOW), view(DEPTH_LOW));
        Fsr2Gpu {
            plan,
            textures,
            options,
            width,
            height,
            low,
            params,
            pipelines,
            motion,
            luminance,
            exposure,
            lock,
            sides,
            scene_views,
            velocity,
            last_jitter: Vec2::ZERO,
        }
    }

    /// A texture of the plan by resource name (`color_low`, `motion`, `prepared_color`, ...);
    /// `internal` is this frame's accumulated colour.
    pub fn texture(&self, name: &str) -> Option<&wgpu::Texture> {
        match name {
            "internal" => self.textures.get(self.sides.current().output.name()),
            _ => self.textures.get(name),
        }
    }

    /// The render size.
    pub fn render_size(&self) -> (u32, u32) {
        self.low
    }

    /// The last frame's jitter, AMD's `ffxFsr2GetJitterOffset`.
    pub fn last_jitter(&self) -> Vec2 {
        self.last_jitter
    }
}

impl Renderer for Fsr2Gpu {
    fn plan(&self) -> &Plan {
        &self.plan
    }

    fn output(&self) -> &wgpu::Texture {
        self.textures.texture(self.sides.current().output)
    }

    fn record(
        &mut self,
        gpu: &Gpu,
        scene: &mut SceneGpu,
        timers: &Timers,
        encoder: &mut wgpu::CommandEncoder,
        frame: FrameInfo,
    ) {
        // AMD's offset J: the projection moves by (2 J.x / w, -2 J.y / h), so render pixel q
        // sees the unjittered image at q + 0.5 - J (the shared `ndc_offset` takes -J).
        let amd_jitter = jitter(frame.index, self.options.phases(self.width));
        let base = View::whole(frame.time, frame.prev_time);
        scene.write_view(
            &gpu.queue,
            0,
            &View {
                ndc_offset: ndc_offset(-amd_jitter, self.low.0, self.low.1),
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
        let use_velocity =
            self.velocity
                .record_in(gpu, scene, timers, encoder, 0, Objects::Dynamic);
        let (cur, prev) = scene.view_projections(frame.time, frame.prev_time);
        let camera_still = cur == prev;
        let prev_from_cur = if camera_still {
            DMat4::IDENTITY
        } else {
            prev * cur.inverse()
        };
        // The projection's x and y scales: the rows of a rotation scaled by them.
        let a = cur.row(0).truncate().length() as f32;
        let b = cur.row(1).truncate().length() as f32;
        let (near, far) = scene.near_far();
        let dt = ((frame.time - frame.prev_time) as f32).clamp(0.0, 1.0);
        let (mw, mh) = luma_mip_size(self.low);
        let params = Params {
            size: [self.low.0, self.low.1, self.width, self.height],
            jitter: [
                amd_jitter.x,
                amd_jitter.y,
                dt,
                self.options.phases(self.width) as f32,
            ],
            depth_to_view: depth_to_view(near, far, a, b),
            mode: [
                u32::from(!frame.history_valid),
                u32::from(use_velocity),
                u32::from(camera_still),
                u32::from(self.options.auto_exposure),
            ],
            luma: [mw, mh, LUMA_MIP_LEVEL, 0],
            prev_from_cur: prev_from_cur.as_mat4().to_cols_array_2d(),
        };
        gpu.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        self.last_jitter = amd_jitter;
        self.sides.select(frame.index);
        let side = self.sides.current();
        let p = &self.pipelines;
        let low = [self.low.0.div_ceil(8), self.low.1.div_ceil(8)];
        let high = [self.width.div_ceil(8), self.height.div_ceil(8)];
        timed_dispatch(encoder, timers, "motion", &p.motion, &[&self.motion], low);
        timed_dispatch(
            encoder,
            timers,
            "luminance_pyramid",
            &p.luminance,
            &[&self.luminance],
            [mw, mh],
        );
        timed_dispatch(
            encoder,
            timers,
            "auto_exposure",
            &p.exposure,
            &[&self.exposure],
            [1, 1],
        );
        timed_dispatch(
            encoder,
            timers,
            "reconstruct",
            &p.reconstruct,
            &[&side.reconstruct],
            low,
        );
        timed_dispatch(
            encoder,
            timers,
            "depth_clip",
            &p.depth_clip,
            &[&side.depth_clip],
            low,
        );
        timed_dispatch(encoder, timers, "lock", &p.lock, &[&self.lock], low);
        timed_dispatch(
            encoder,
            timers,
            "accumulate",
            &p.accumulate,
            &[&side.accumulate],
            high,
        );
        if let (Some(pipeline), Some(group)) = (&p.rcas, &side.rcas) {
            timed_dispatch(encoder, timers, "rcas", pipeline, &[group], high);
        }
    }
}
