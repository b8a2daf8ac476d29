//! The GPU part of `checkerboard`: a quarter-resolution frame with two samples per pixel on the
//! full-resolution pixel centres of one checkerboard parity (even frames quadrants {0 = TL,
//! 3 = BR}, odd frames {1 = TR, 2 = BL}, the odd frames shifted one full-resolution pixel right
//! through the projection), then a compute pass that rebuilds every full-resolution pixel from
//! this frame's samples and the previous frame's (`resolve.wgsl`, CPU model
//! in `model.rs`). Sampling is either a 2x MSAA target shaded per sample (Intel, mosaiikki) or two
//! jittered single-sample renders (same samples on any adapter). In a scene with dynamic objects
//! the kit's velocity pass (`render/velocity.rs`) draws them (or every object, with
//! `velocity_objects = "all"`); with the dynamic objects only, the reconstruction also binds that
//! pass's depth to tell a static object in front of a moving one (`resolve.wgsl` step 3).
//!
//! The quarter-resolution targets are one pixel wider than `ceil(W / 2)`, so that odd frames also
//! shade the top-right quadrant of the last block column: every full-resolution pixel is covered
//! every two frames, with no border. The projection is remapped so that full-resolution pixel
//! centres land exactly on the samples (`View::ndc_scale` / `ndc_offset`).

use std::collections::HashMap;

use glam::Vec2;

use super::{AsoMotion, Occlusion, Options, Sampling, VelocityObjects};
use crate::gpu::{Gpu, Unsupported, STANDARD_2X};
use crate::render::graph::{Graph, PassKind, Plan, TextureDesc};
use crate::render::kit::{
    allocate, bind_group, compute_pipeline, record_scene_pass, timed_dispatch, PingPong,
};
use crate::render::renderer::{FrameInfo, Renderer};
use crate::render::scene::{SceneGpu, ScenePipeline, View, COLOR_FORMAT, DEPTH_FORMAT};
use crate::render::timers::Timers;
use crate::render::velocity::{self, VelocityPass, VELOCITY, VELOCITY_DEPTH};

pub static RESOLVE_WGSL: &str = include_str!("resolve.wgsl");
pub static TWO_PASS_WGSL: &str = include_str!("two_pass.wgsl");
pub static MSAA2X_WGSL: &str = include_str!("msaa2x.wgsl");

/// Quarter-resolution texture size for a full resolution: one column wider than half (see the
/// module doc).
pub fn quarter_size(width: u32, height: u32) -> (u32, u32) {
    (width.div_ceil(2) + 1, height.div_ceil(2))
}

/// NDC remap (scale, offset) of a quarter-resolution render for frame `parity`, with `jitter` in
/// quarter-resolution pixels (content shift; y down).
pub fn quarter_view(width: u32, height: u32, parity: u32, jitter: Vec2) -> (Vec2, Vec2) {
    let (qw, qh) = quarter_size(width, height);
    let sx = width as f32 / (2.0 * qw as f32);
    let sy = height as f32 / (2.0 * qh as f32);
    let offset = Vec2::new(
        sx - 1.0 + parity as f32 / qw as f32 + 2.0 * jitter.x / qw as f32,
        1.0 - sy - 2.0 * jitter.y / qh as f32,
    );
    (Vec2::new(sx, sy), offset)
}

/// Content shift that puts a single-sample pixel centre on sample `s`'s standard position.
pub fn two_pass_jitter(sample: usize) -> Vec2 {
    Vec2::new(0.5 - STANDARD_2X[sample][0], 0.5 - STANDARD_2X[sample][1])
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ResolveParams {
    reproject: [[f32; 4]; 4],
    size: [u32; 4],
    mode: [u32; 4],
    mode2: [u32; 4],
    depth: [f32; 4],
}

pub struct CheckerboardGpu {
    plan: Plan,
    textures: HashMap<&'static str, wgpu::Texture>,
    sampling: Sampling,
    gradient_scale: f32,
    options: Options,
    width: u32,
    height: u32,
    pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    /// The reconstruction's bind groups, one per side: the current parity's targets, the other
    /// parity's as history.
    bind_groups: PingPong<wgpu::BindGroup>,
    last: Option<LastFrame>,
    /// Render-target views (colour, depth), made once: two-pass per layer `parity * 2 + sample`,
    /// msaa2x per parity.
    target_views: Vec<(wgpu::TextureView, wgpu::TextureView)>,
    velocity: VelocityPass,
}

/// What the last recorded reconstruction was given (for the CPU model in tests).
#[derive(Clone, Copy, Debug)]
pub struct LastFrame {
    pub parity: u32,
    pub reset: bool,
    pub reproject: glam::Mat4,
    pub velocity: bool,
    pub options: Options,
    pub near: f32,
    pub far: f32,
}

/// Two-pass sampling keeps every sample in one 4-layer array per kind, layer
/// `parity * 2 + sample` (even s0, even s1, odd s0, odd s1): the reconstruction then loads any
/// sample with one fetch and no branch (divergent branches cost every lane on SIMD and CPU
/// adapters). 2x MSAA has no portable multisampled arrays: one texture per parity.
const TWO_PASS_COLOR: &str = "color_samples";
const TWO_PASS_DEPTH: &str = "depth_samples";
const MSAA_TARGETS: [(&str, &str); 2] = [("color_even", "depth_even"), ("color_odd", "depth_odd")];

/// The pass graph of a checkerboard variant, without a GPU (what `tessera` would allocate), and
/// whether the reconstruction reads the velocity buffer.
pub fn graph(options: &Options, width: u32, height: u32, dynamic_scene: bool) -> (Plan, bool) {
    let sampling = options.sampling;
    let (qw, qh) = quarter_size(width, height);
    let samples = if sampling == Sampling::Msaa2x { 2 } else { 1 };
    let q = |format, layers| TextureDesc {
        format,
        width: qw,
        height: qh,
        samples,
        layers,
    };
    let full = |format| TextureDesc {
        format,
        width,
        height,
        samples: 1,
        layers: 1,
    };
    let mut g = Graph::default();
    let mut reads: Vec<&'static str> = Vec::new();
    match sampling {
        Sampling::TwoPass => {
            g.resource(TWO_PASS_COLOR, q(COLOR_FORMAT, 4))
                .resource(TWO_PASS_DEPTH, q(DEPTH_FORMAT, 4));
            for name in ["scene_sample0", "scene_sample1"] {
                g.pass(
                    name,
                    PassKind::Render,
                    &[],
                    &[TWO_PASS_COLOR, TWO_PASS_DEPTH],
                );
            }
            reads.extend([TWO_PASS_COLOR, TWO_PASS_DEPTH]);
        }
        Sampling::Msaa2x => {
            let writes = [
                MSAA_TARGETS[0].0,
                MSAA_TARGETS[0].1,
                MSAA_TARGETS[1].0,
                MSAA_TARGETS[1].1,
            ];
            for (i, w) in writes.iter().enumerate() {
                g.resource(
                    *w,
                    q(
                        if i % 2 == 0 {
                            COLOR_FORMAT
                        } else {
                            DEPTH_FORMAT
                        },
                        1,
                    ),
                );
            }
            g.pass("scene", PassKind::Render, &[], &writes);
            reads.extend(writes);
        }
    }
    velocity::declare(&mut g, width, height);
    // Dynamic objects need the velocity buffer; without them, nothing reads it and it is culled.
    // Drawn for the dynamic objects only, its depth tells where a static object hides them.
    let use_velocity = options.velocity && dynamic_scene;
    if use_velocity {
        reads.push(VELOCITY.name());
        if options.velocity_objects == VelocityObjects::Dynamic {
            reads.push(VELOCITY_DEPTH.name());
        }
    }
    g.resource("color", full(COLOR_FORMAT));
    g.pass("reconstruct", PassKind::Compute, &reads, &["color"])
        .output("color");
    (
        g.plan().expect("built-in graphs are well formed"),
        use_velocity,
    )
}

impl CheckerboardGpu {
    pub fn new(
        gpu: &Gpu,
        options: Options,
        width: u32,
        height: u32,
        dynamic_scene: bool,
    ) -> Result<CheckerboardGpu, Unsupported> {
        // 2x MSAA was checked before the build (`Definition::requirements`).
        let sampling = options.sampling;
        let (plan, use_velocity) = graph(&options, width, height, dynamic_scene);
        let textures = allocate(&gpu.device, &plan);

        let device = &gpu.device;
        let prelude = if sampling == Sampling::Msaa2x {
            MSAA2X_WGSL
        } else {
            TWO_PASS_WGSL
        };
        let source = format!("{prelude}\n{RESOLVE_WGSL}");
        let pipeline = compute_pipeline(device, "reconstruct", &source, "main");
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("reconstruct params"),
            size: std::mem::size_of::<ResolveParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let velocity = VelocityPass::new(device, &plan, &textures);
        debug_assert_eq!(velocity.runs(), use_velocity);
        let output_view = textures["color"].create_view(&Default::default());
        let layout = pipeline.get_bind_group_layout(0);
        let msaa_targets = PingPong::new(MSAA_TARGETS);
        let bind_group = |parity: usize| {
            let view = |name: &str| textures[name].create_view(&Default::default());
            let mut views: Vec<(u32, wgpu::TextureView)> = match sampling {
                Sampling::TwoPass => {
                    let array = |name: &str| {
                        textures[name].create_view(&wgpu::TextureViewDescriptor {
                            dimension: Some(wgpu::TextureViewDimension::D2Array),
                            ..Default::default()
                        })
                    };
                    vec![(1, array(TWO_PASS_COLOR)), (5, array(TWO_PASS_DEPTH))]
                }
                Sampling::Msaa2x => {
                    let (cur, prev) = msaa_targets.at(parity);
                    vec![
                        (1, view(cur.0)),
                        (3, view(prev.0)),
                        (5, view(cur.1)),
                        (7, view(prev.1)),
                    ]
                }
            };
            views.push((9, velocity.binding().clone()));
            views.push((11, velocity.depth_binding().clone()));
            views.push((10, output_view.clone()));
            let views: Vec<(u32, &wgpu::TextureView)> =
                views.iter().map(|(b, v)| (*b, v)).collect();
            bind_group(device, "reconstruct", &layout, &[(0, &params)], &views)
        };
        let bind_groups = PingPong::new([bind_group(0), bind_group(1)]);
        let whole = |name: &str| textures[name].create_view(&Default::default());
        let target_views = match sampling {
            Sampling::Msaa2x => MSAA_TARGETS
                .iter()
                .map(|(c, d)| (whole(c), whole(d)))
                .collect(),
            Sampling::TwoPass => (0..4)
                .map(|layer| {
                    let v = |name: &str| {
                        textures[name].create_view(&wgpu::TextureViewDescriptor {
                            dimension: Some(wgpu::TextureViewDimension::D2),
                            base_array_layer: layer,
                            array_layer_count: Some(1),
                            ..Default::default()
                        })
                    };
                    (v(TWO_PASS_COLOR), v(TWO_PASS_DEPTH))
                })
                .collect(),
        };
        Ok(CheckerboardGpu {
            plan,
            textures,
            sampling,
            gradient_scale: options.gradient_scale,
            options,
            width,
            height,
            pipeline,
            params,
            bind_groups,
            last: None,
            target_views,
            velocity,
        })
    }
}

impl CheckerboardGpu {
    /// A texture of the plan by resource name (`color_even_s0`, `velocity`, ...).
    pub fn texture(&self, name: &str) -> Option<&wgpu::Texture> {
        self.textures.get(name)
    }

    pub fn last_frame(&self) -> Option<LastFrame> {
        self.last
    }
}

impl Renderer for CheckerboardGpu {
    fn plan(&self) -> &Plan {
        &self.plan
    }

    fn output(&self) -> &wgpu::Texture {
        &self.textures["color"]
    }

    fn record(
        &mut self,
        gpu: &Gpu,
        scene: &mut SceneGpu,
        timers: &Timers,
        encoder: &mut wgpu::CommandEncoder,
        frame: FrameInfo,
    ) {
        self.bind_groups.select(frame.index);
        let parity = self.bind_groups.side();
        let (qw, qh) = quarter_size(self.width, self.height);
        let base = View {
            time: frame.time,
            prev_time: frame.prev_time,
            ndc_offset: Vec2::ZERO,
            ndc_scale: Vec2::ONE,
            gradient_scale: self.gradient_scale,
            // `gradient_scale` is its texture LOD bias too (0.7071: Intel's -0.5).
            lod_bias: 0.0,
        };
        match self.sampling {
            Sampling::TwoPass => {
                for (s, name) in [(0usize, "scene_sample0"), (1, "scene_sample1")] {
                    let (scale, offset) =
                        quarter_view(self.width, self.height, parity as u32, two_pass_jitter(s));
                    scene.write_view(
                        &gpu.queue,
                        s as u32,
                        &View {
                            ndc_scale: scale,
                            ndc_offset: offset,
                            ..base
                        },
                    );
                    let layer = parity * 2 + s;
                    let (c, d) = (&self.target_views[layer].0, &self.target_views[layer].1);
                    record_scene_pass(
                        gpu,
                        scene,
                        timers,
                        encoder,
                        name,
                        c,
                        d,
                        s as u32,
                        ScenePipeline::Forward { samples: 1 },
                    );
                }
            }
            Sampling::Msaa2x => {
                let (scale, offset) =
                    quarter_view(self.width, self.height, parity as u32, Vec2::ZERO);
                scene.write_view(
                    &gpu.queue,
                    0,
                    &View {
                        ndc_scale: scale,
                        ndc_offset: offset,
                        ..base
                    },
                );
                let (c, d) = &self.target_views[parity];
                record_scene_pass(
                    gpu,
                    scene,
                    timers,
                    encoder,
                    "scene",
                    c,
                    d,
                    0,
                    ScenePipeline::PerSample { samples: 2 },
                );
            }
        }
        // The whole view (`base` at full resolution, no jitter) in slot 2.
        let o = self.options;
        let use_velocity = self.velocity.record(
            gpu,
            scene,
            timers,
            encoder,
            2,
            frame.time,
            frame.prev_time,
            o.velocity_objects.objects(),
        );
        // Only the dynamic objects drawn: the reconstruction tests for static occluders.
        let occluders = use_velocity && o.velocity_objects == VelocityObjects::Dynamic;
        let (cur, prev) = scene.view_projections(frame.time, frame.prev_time);
        let near_far = scene.near_far();
        let params = ResolveParams {
            reproject: (cur * prev.inverse()).as_mat4().to_cols_array_2d(),
            size: [self.width, self.height, qw, qh],
            mode: [
                parity as u32,
                u32::from(!frame.history_valid),
                u32::from(o.occlusion == Occlusion::Aso),
                o.fill.code(),
            ],
            mode2: [
                o.clamp.code(),
                u32::from(use_velocity),
                u32::from(occluders),
                u32::from(o.aso_motion == AsoMotion::QuarterTexel),
            ],
            depth: [o.depth_tolerance, near_far.0, near_far.1, 0.0],
        };
        gpu.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        self.last = Some(LastFrame {
            parity: parity as u32,
            reset: !frame.history_valid,
            reproject: glam::Mat4::from_cols_array_2d(&params.reproject),
            velocity: use_velocity,
            options: o,
            near: near_far.0,
            far: near_far.1,
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
