//! The GPU part of `checkerboard-2x2`: the depth-based report's 2x2 checkerboarding
//! (`seeds/depth-based-checkerboarding.txt`, sections 5.3.1 to 5.3.8), at full resolution.
//!
//! Per frame (parity `p = index & 1`):
//! 1. `precondition` (copy): the scene depth starts as a copy of one of two pre-conditioned depth
//!    buffers, "white" on even frames and "black" on odd ones, whose masked 2x2 blocks hold the
//!    nearest depth (5.3.6; drawn once at build time by `mask.wgsl`, 5.3.2).
//! 2. `scene` (render): the ordinary forward pipeline, depth loaded, not cleared: the early depth
//!    test rejects every fragment of a masked block, so about half the pixels are shaded. The
//!    fragment shader writes no `frag_depth` (early-Z stays on); the depth *attachment* is still
//!    written in the free blocks, for visibility among scene triangles and because the report keeps
//!    that depth as history for the blended clamp (5.3.7, "Previous Frame Depth Cache").
//! 3. `motion_precondition` (copy) and `motion` (render): the motion pass (the scene's velocity
//!    pipeline: current minus previous screen position, pixels) on the inverse mask, so motion is
//!    rendered only where the frame will be reconstituted (5.3.6).
//! 4. `reconstitute` (compute, one invocation per pair of blocks): copies the shaded blocks and
//!    rebuilds the masked ones by motion reprojection into the previous output, with the report's
//!    clamps (`reconstitute.wgsl`; CPU model in
//!    `model.rs`).
//!
//! History. The report copies the back buffer, depth and motion into caches at the end of each
//! frame (5.3.3, 5.3.7, 5.3.8). Here each of those is a ping-pong pair instead (`color` /
//! `color_history`, `depth` / `depth_history`, `motion` / `motion_history`): the same memory, no
//! copies. A pair's history half is allocated only when read: depth history for `blended`, motion
//! history for motion coherency under `conditional` or `blended`. The reconstituted output cannot
//! be written into the scene's render target in place (a texture cannot be sampled and stored in
//! one dispatch in portable wgpu), so `scene_color` is one colour target more than the report's.

use std::collections::HashMap;

use super::{Options, Precondition};
use crate::gpu::Gpu;
use crate::render::graph::{Graph, PassKind, Plan, TextureDesc};
use crate::render::kit::{
    allocate_with, bind_group, compute_pipeline, placeholder_texture, record_scene_pass_on,
    timed_dispatch, PingPong,
};
use crate::render::renderer::{FrameInfo, Renderer};
use crate::render::scene::{Objects, SceneGpu, ScenePipeline, View, COLOR_FORMAT, DEPTH_FORMAT};
use crate::render::timers::Timers;

pub static MASK_WGSL: &str = include_str!("mask.wgsl");
pub static RECONSTITUTE_WGSL: &str = include_str!("reconstitute.wgsl");

/// The pass graph at `width` x `height`: pure bookkeeping, so the memory of every resource can be
/// checked without a GPU. Resource names by role; see the module doc for the ping-pong pairs.
pub fn graph(width: u32, height: u32, options: &Options) -> Graph {
    let full = |format| TextureDesc {
        format,
        width,
        height,
        samples: 1,
        layers: 1,
    };
    let mut g = Graph::default();
    let copy = options.precondition == Precondition::Copy;
    if copy {
        g.resource("depth_white", full(DEPTH_FORMAT))
            .resource("depth_black", full(DEPTH_FORMAT));
    }
    g.resource("depth", full(DEPTH_FORMAT))
        .resource("depth_history", full(DEPTH_FORMAT))
        .resource("scene_color", full(COLOR_FORMAT))
        .resource("motion_depth", full(DEPTH_FORMAT))
        .resource("motion", full(COLOR_FORMAT))
        .resource("motion_history", full(COLOR_FORMAT))
        .resource("color", full(COLOR_FORMAT))
        .resource("color_history", full(COLOR_FORMAT));
    // `copy` reads the standby checks; `draw` writes the mask itself (a render pass).
    let (checks, kind): (&[&str], _) = if copy {
        (&["depth_white", "depth_black"], PassKind::Copy)
    } else {
        (&[], PassKind::Render)
    };
    g.pass("precondition", kind, checks, &["depth"])
        .pass(
            "scene",
            PassKind::Render,
            &["depth"],
            &["scene_color", "depth"],
        )
        .pass("motion_precondition", kind, checks, &["motion_depth"])
        .pass(
            "motion",
            PassKind::Render,
            &["motion_depth"],
            &["motion", "motion_depth"],
        );
    let mut reads = vec!["scene_color", "motion", "color_history"];
    if options.reads_depth_history() {
        reads.extend(["depth", "depth_history"]);
    }
    if options.reads_motion_history() {
        reads.push("motion_history");
    }
    g.pass("reconstitute", PassKind::Compute, &reads, &["color"])
        .output("color");
    g
}

/// What the reconstitution shader is told about a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameParams {
    pub width: u32,
    pub height: u32,
    /// Parity of the blocks shaded this frame: block (bx, by) was shaded when (bx + by) & 1 == parity.
    pub parity: u32,
    /// No history to read (first frame, camera cut).
    pub reset: bool,
    pub options: Options,
    pub near: f32,
    pub far: f32,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuParams {
    frame: [u32; 4],
    mode: [u32; 4],
    limits: [f32; 4],
    planes: [f32; 4],
}

impl From<&FrameParams> for GpuParams {
    fn from(f: &FrameParams) -> GpuParams {
        let o = &f.options;
        GpuParams {
            frame: [f.width, f.height, f.parity, u32::from(f.reset)],
            mode: [o.clamp.code(), u32::from(o.motion_coherency), 0, 0],
            limits: [o.motion_threshold, o.blend_min, o.blend_max, 0.0],
            planes: [f.near, f.far, 0.0, 0.0],
        }
    }
}

/// The textures the reconstitution reads and writes (views of the right formats and sizes).
pub struct Bindings<'a> {
    pub scene_color: &'a wgpu::TextureView,
    pub scene_depth: &'a wgpu::TextureView,
    pub motion: &'a wgpu::TextureView,
    pub history_color: &'a wgpu::TextureView,
    pub history_depth: &'a wgpu::TextureView,
    pub history_motion: &'a wgpu::TextureView,
    pub output: &'a wgpu::TextureView,
}

/// The `reconstitute` compute pass on its own: used by the technique, and by tests on synthetic
/// inputs.
pub struct Reconstitution {
    pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
}

impl Reconstitution {
    pub fn new(device: &wgpu::Device) -> Reconstitution {
        Reconstitution {
            pipeline: compute_pipeline(device, "reconstitute", RECONSTITUTE_WGSL, "main"),
            params: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("reconstitute params"),
                size: std::mem::size_of::<GpuParams>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
        }
    }

    pub fn bind_group(&self, device: &wgpu::Device, b: &Bindings) -> wgpu::BindGroup {
        let views = [
            b.scene_color,
            b.scene_depth,
            b.motion,
            b.history_color,
            b.history_depth,
            b.history_motion,
            b.output,
        ];
        let views: Vec<(u32, &wgpu::TextureView)> = views
            .iter()
            .enumerate()
            .map(|(i, v)| (i as u32 + 1, *v))
            .collect();
        bind_group(
            device,
            "reconstitute",
            &self.pipeline.get_bind_group_layout(0),
            &[(0, &self.params)],
            &views,
        )
    }

    /// Writes this frame's parameters (ordered before the next submission).
    pub fn write_params(&self, queue: &wgpu::Queue, frame: &FrameParams) {
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&GpuParams::from(frame)));
    }

    /// Records the pass, timed as `reconstitute`.
    pub fn record(
        &self,
        timers: &Timers,
        encoder: &mut wgpu::CommandEncoder,
        bind_group: &wgpu::BindGroup,
        width: u32,
        height: u32,
    ) {
        let (pairs, rows) = workgroups(width, height);
        let (pipeline, groups) = (&self.pipeline, [bind_group]);
        timed_dispatch(
            encoder,
            timers,
            "reconstitute",
            pipeline,
            &groups,
            [pairs, rows],
        );
    }
}

/// Workgroups (8x8 invocations, one invocation per pair of blocks) covering the frame.
pub fn workgroups(width: u32, height: u32) -> (u32, u32) {
    let (bw, bh) = (width.div_ceil(2), height.div_ceil(2));
    (bw.div_ceil(2).div_ceil(8), bh.div_ceil(8))
}

/// What the last recorded frame gave the reconstitution (for the CPU model in tests).
#[derive(Clone, Copy, Debug)]
pub struct LastFrame {
    pub params: FrameParams,
}

/// A ping-pong pair by role: index 0 is the resource `name`, 1 is `name_history` (the same
/// texture when the history is not kept).
const PAIRS: [(&str, &str); 3] = [
    ("color", "color_history"),
    ("depth", "depth_history"),
    ("motion", "motion_history"),
];

pub struct Checkerboard2x2Gpu {
    plan: Plan,
    textures: HashMap<&'static str, wgpu::Texture>,
    options: Options,
    width: u32,
    height: u32,
    reconstitution: Reconstitution,
    /// Bind groups, one per side (which half of each pair is current).
    bind_groups: PingPong<wgpu::BindGroup>,
    /// Stand-ins bound where a history is not kept (never read then).
    _dummies: Vec<wgpu::Texture>,
    /// Render-target views per side: (scene colour, scene depth, motion, motion depth).
    views: PingPong<[wgpu::TextureView; 4]>,
    /// `precondition = "draw"`: the white and black mask pipelines (`mask.wgsl`).
    masks: Option<[wgpu::RenderPipeline; 2]>,
    last: Option<LastFrame>,
}

impl Checkerboard2x2Gpu {
    pub fn new(
        gpu: &Gpu,
        variant: &crate::techniques::Variant,
        width: u32,
        height: u32,
    ) -> Checkerboard2x2Gpu {
        Self::with_options(gpu, Options::from_variant(variant), width, height)
    }

    pub fn with_options(
        gpu: &Gpu,
        options: Options,
        width: u32,
        height: u32,
    ) -> Checkerboard2x2Gpu {
        let device = &gpu.device;
        let plan = graph(width, height, &options)
            .plan()
            .expect("built-in graphs are well formed");
        // Depth textures are filled by copies (pre-conditioning): every texture is a copy target.
        let textures = allocate_with(device, &plan, wgpu::TextureUsages::COPY_DST);
        let masks = mask_pipelines(gpu);
        let masks = match (textures.get("depth_white"), textures.get("depth_black")) {
            (Some(white), Some(black)) => {
                draw_checks(gpu, &masks, white, black);
                None
            }
            _ => Some(masks),
        };

        let dummy = |format| placeholder_texture(device, "no history", format);
        let mut dummies = Vec::new();
        // Per pair: [current view, history view] for parity 0; swapped for parity 1.
        let mut pair_views: Vec<[wgpu::TextureView; 2]> = Vec::new();
        for (cur, hist) in PAIRS {
            let a = textures[cur].create_view(&Default::default());
            match textures.get(hist) {
                Some(t) => pair_views.push([a, t.create_view(&Default::default())]),
                None => {
                    // Not kept: the current texture serves both parities; the history binding
                    // gets a stand-in of the same format.
                    let d = dummy(textures[cur].format());
                    let dv = d.create_view(&Default::default());
                    dummies.push(d);
                    pair_views.push([a.clone(), dv]);
                }
            }
        }
        let kept = |hist: &str| textures.contains_key(hist);
        let view = |name: &str| textures[name].create_view(&Default::default());
        let (scene_color, motion_depth) = (view("scene_color"), view("motion_depth"));
        let reconstitution = Reconstitution::new(device);
        let by_parity = |parity: usize| {
            // Which view of pair i is current (c) and which is history (h) at this parity.
            let pick = |i: usize, hist: &str| -> (wgpu::TextureView, wgpu::TextureView) {
                let [a, b] = &pair_views[i];
                if kept(hist) && parity == 1 {
                    (b.clone(), a.clone())
                } else {
                    (a.clone(), b.clone())
                }
            };
            (
                pick(0, PAIRS[0].1),
                pick(1, PAIRS[1].1),
                pick(2, PAIRS[2].1),
            )
        };
        let mut bind_groups = Vec::new();
        let mut views = Vec::new();
        for parity in 0..2 {
            let (color, depth, motion) = by_parity(parity);
            bind_groups.push(reconstitution.bind_group(
                device,
                &Bindings {
                    scene_color: &scene_color,
                    scene_depth: &depth.0,
                    motion: &motion.0,
                    history_color: &color.1,
                    history_depth: &depth.1,
                    history_motion: &motion.1,
                    output: &color.0,
                },
            ));
            views.push([
                scene_color.clone(),
                depth.0.clone(),
                motion.0.clone(),
                motion_depth.clone(),
            ]);
        }
        let [b0, b1]: [wgpu::BindGroup; 2] = bind_groups.try_into().ok().unwrap();
        let [v0, v1]: [[wgpu::TextureView; 4]; 2] = views.try_into().ok().unwrap();
        Checkerboard2x2Gpu {
            plan,
            textures,
            options,
            width,
            height,
            reconstitution,
            bind_groups: PingPong::new([b0, b1]),
            _dummies: dummies,
            views: PingPong::new([v0, v1]),
            masks,
            last: None,
        }
    }

    pub fn last_frame(&self) -> Option<LastFrame> {
        self.last
    }

    /// The texture that played resource `role` (`color`, `depth_history`, `scene_color`, ...) in
    /// the last recorded frame.
    pub fn texture(&self, role: &str) -> Option<&wgpu::Texture> {
        let parity = self.last.map(|l| l.params.parity).unwrap_or(0);
        for (cur, hist) in PAIRS {
            if role != cur && role != hist {
                continue;
            }
            if !self.textures.contains_key(hist) {
                return (role == cur).then(|| &self.textures[cur]);
            }
            let first = (role == cur) == (parity == 0);
            return Some(&self.textures[if first { cur } else { hist }]);
        }
        self.textures.get(role)
    }

    /// Physical texture of a pair member at `parity` (0: `cur`, 1: `hist` when kept).
    fn pair_texture(&self, pair: usize, parity: usize) -> &wgpu::Texture {
        let (cur, hist) = PAIRS[pair];
        match self.textures.get(hist) {
            Some(h) if parity == 1 => h,
            _ => &self.textures[cur],
        }
    }
}

impl Renderer for Checkerboard2x2Gpu {
    fn plan(&self) -> &Plan {
        &self.plan
    }

    fn output(&self) -> &wgpu::Texture {
        let parity = self.last.map(|l| l.params.parity).unwrap_or(0) as usize;
        self.pair_texture(0, parity)
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
        self.views.select(frame.index);
        let parity = self.bind_groups.side();
        // One view serves both render passes: no jitter, full resolution.
        scene.write_view(&gpu.queue, 0, &View::whole(frame.time, frame.prev_time));
        let [scene_color, depth, motion, motion_depth] = self.views.current();
        // The scene depth starts as this frame's check pattern (white on even frames), the
        // motion depth as the other one (the inverse mask): drawn now, or copied from the
        // standby buffers (5.3.6).
        let (check, inverse) = (parity, 1 - parity);
        self.precondition(
            timers,
            encoder,
            "precondition",
            check,
            depth,
            self.pair_texture(1, parity),
        );
        record_scene_pass_on(
            gpu,
            scene,
            timers,
            encoder,
            (
                "scene",
                0,
                ScenePipeline::Forward { samples: 1 },
                Objects::All,
            ),
            scene_color,
            depth,
            wgpu::LoadOp::Load,
        );
        self.precondition(
            timers,
            encoder,
            "motion_precondition",
            inverse,
            motion_depth,
            &self.textures["motion_depth"],
        );
        record_scene_pass_on(
            gpu,
            scene,
            timers,
            encoder,
            ("motion", 0, ScenePipeline::Velocity, Objects::All),
            motion,
            motion_depth,
            wgpu::LoadOp::Load,
        );
        let (near, far) = scene.near_far();
        let params = FrameParams {
            width: self.width,
            height: self.height,
            parity: parity as u32,
            reset: !frame.history_valid,
            options: self.options,
            near,
            far,
        };
        self.reconstitution.write_params(&gpu.queue, &params);
        self.reconstitution.record(
            timers,
            encoder,
            self.bind_groups.current(),
            self.width,
            self.height,
        );
        self.last = Some(LastFrame { params });
    }
}

/// The white and black mask pipelines of `mask.wgsl` (5.3.2): a full-screen triangle writing, with
/// depth compare Always, the nearest depth in masked blocks and the clear value in free ones.
fn mask_pipelines(gpu: &Gpu) -> [wgpu::RenderPipeline; 2] {
    let device = &gpu.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("checkerboard_2x2_mask.wgsl"),
        source: wgpu::ShaderSource::Wgsl(MASK_WGSL.into()),
    });
    ["fs_white", "fs_black"].map(|entry| {
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(entry),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_fullscreen"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                targets: &[],
            }),
            primitive: Default::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Always),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            multiview_mask: None,
            cache: None,
        })
    })
}

/// Records the depth-only pass that clears `view` and draws mask `pipeline` over it, timed as
/// `name` when `timers` are given.
fn draw_mask(
    encoder: &mut wgpu::CommandEncoder,
    timers: Option<&Timers>,
    name: &'static str,
    pipeline: &wgpu::RenderPipeline,
    view: &wgpu::TextureView,
) {
    let q = timers.map(|t| t.begin(name, encoder));
    {
        let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(name),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(0.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: q.as_ref().and_then(|q| q.render_pass_timestamp_writes()),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        rp.set_pipeline(pipeline);
        rp.draw(0..3, 0..1);
    }
    if let (Some(t), Some(q)) = (timers, q) {
        t.end(encoder, q);
    }
}

/// Draws the white and black standby checks once (5.3.2, moved to start-up in 5.3.6).
fn draw_checks(
    gpu: &Gpu,
    masks: &[wgpu::RenderPipeline; 2],
    white: &wgpu::Texture,
    black: &wgpu::Texture,
) {
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("checkerboard-2x2 checks"),
        });
    for (texture, pipeline) in [white, black].into_iter().zip(masks) {
        let view = texture.create_view(&Default::default());
        draw_mask(&mut encoder, None, "checks", pipeline, &view);
    }
    gpu.queue.submit([encoder.finish()]);
}

impl Checkerboard2x2Gpu {
    /// Gives a depth target (`view` of `texture`) check pattern `check` (0 white, 1 black): drawn
    /// by the mask pass (`draw`) or copied from its standby buffer (`copy`), timed as `name`.
    fn precondition(
        &self,
        timers: &Timers,
        encoder: &mut wgpu::CommandEncoder,
        name: &'static str,
        check: usize,
        view: &wgpu::TextureView,
        texture: &wgpu::Texture,
    ) {
        match &self.masks {
            Some(masks) => draw_mask(encoder, Some(timers), name, &masks[check], view),
            None => {
                let standby = [&self.textures["depth_white"], &self.textures["depth_black"]];
                copy_depth(timers, encoder, name, standby[check], texture);
            }
        }
    }
}

/// Copies a whole pre-conditioned depth buffer into a pass's depth target, timed as `name`.
fn copy_depth(
    timers: &Timers,
    encoder: &mut wgpu::CommandEncoder,
    name: &'static str,
    src: &wgpu::Texture,
    dst: &wgpu::Texture,
) {
    let q = timers.begin_encoder(name, encoder);
    encoder.copy_texture_to_texture(src.as_image_copy(), dst.as_image_copy(), src.size());
    timers.end(encoder, q);
}
