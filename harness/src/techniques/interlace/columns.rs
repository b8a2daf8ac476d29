//! The GPU part of `interlace` with `pattern = "columns"` (the scheme before issue 26): per frame (parity `p = index & 1`) a `scene` render pass at half
//! width whose texel i of each row samples full-resolution column 2i + p at its pixel centre (the
//! projection remapped, `View::ndc_scale` / `ndc_offset`); a full-resolution `velocity` pass when
//! the scene has animated objects; and a `reconstruct` compute pass writing every full-resolution
//! pixel (`columns.wgsl`, CPU model in `columns_model.rs`). The output and the
//! previous output are a ping-pong pair (`color` / `color_history`).

use std::collections::HashMap;

use glam::Vec2;

use super::columns_model::half_width;
use super::Options;
use crate::gpu::Gpu;
use crate::render::graph::{Graph, PassKind, Plan, TextureDesc};
use crate::render::kit::{
    allocate, bind_group, compute_pipeline, placeholder_texture, record_scene_pass, timed_dispatch,
    PingPong,
};
use crate::render::renderer::{FrameInfo, Renderer};
use crate::render::scene::{SceneGpu, ScenePipeline, View, COLOR_FORMAT, DEPTH_FORMAT};
use crate::render::timers::Timers;

pub static COLUMNS_WGSL: &str = include_str!("columns.wgsl");

/// The output pair: written this frame, read as history.
const OUTPUTS: [&str; 2] = ["color", "color_history"];

/// The pass graph at `width` x `height`, and whether the reconstruction reads the velocity
/// buffer (animated objects and the `velocity` option).
pub fn graph(options: &Options, width: u32, height: u32, dynamic_scene: bool) -> (Plan, bool) {
    let tex = |format, width| TextureDesc {
        format,
        width,
        height,
        samples: 1,
        layers: 1,
    };
    let hw = half_width(width);
    let mut g = Graph::default();
    g.resource("half_color", tex(COLOR_FORMAT, hw))
        .resource("half_depth", tex(DEPTH_FORMAT, hw))
        .resource("velocity", tex(COLOR_FORMAT, width))
        .resource("velocity_depth", tex(DEPTH_FORMAT, width))
        .resource(OUTPUTS[0], tex(COLOR_FORMAT, width))
        .resource(OUTPUTS[1], tex(COLOR_FORMAT, width))
        .pass(
            "scene",
            PassKind::Render,
            &[],
            &["half_color", "half_depth"],
        )
        .pass(
            "velocity",
            PassKind::Render,
            &[],
            &["velocity", "velocity_depth"],
        );
    let use_velocity = options.velocity && dynamic_scene;
    let mut reads = vec!["half_color", "half_depth", OUTPUTS[1]];
    if use_velocity {
        reads.push("velocity");
    }
    g.pass("reconstruct", PassKind::Compute, &reads, &[OUTPUTS[0]])
        .output(OUTPUTS[0]);
    (
        g.plan().expect("built-in graphs are well formed"),
        use_velocity,
    )
}

/// NDC remap (scale, offset) of the half-width render for frame `parity`: texel i's centre
/// samples full-resolution column 2i + parity's centre.
pub fn half_view(width: u32, parity: u32) -> (Vec2, Vec2) {
    let hw = half_width(width) as f32;
    let sx = width as f32 / (2.0 * hw);
    (
        Vec2::new(sx, 1.0),
        Vec2::new(sx - 1.0 + (0.5 - parity as f32) / hw, 0.0),
    )
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    prev_from_cur: [[f32; 4]; 4],
    size: [u32; 4],
    mode: [u32; 4],
}

/// What the last recorded reconstruction was given (for the CPU model in tests).
#[derive(Clone, Copy, Debug)]
pub struct LastFrame {
    pub parity: u32,
    pub history_valid: bool,
    pub prev_from_cur: glam::Mat4,
    pub velocity: bool,
    pub clamp: bool,
}

pub struct ColumnsGpu {
    plan: Plan,
    textures: HashMap<&'static str, wgpu::Texture>,
    options: Options,
    width: u32,
    height: u32,
    pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    /// By parity: parity k writes `OUTPUTS[k]` and reads the other as history.
    bind_groups: PingPong<wgpu::BindGroup>,
    scene_views: (wgpu::TextureView, wgpu::TextureView),
    velocity_views: Option<(wgpu::TextureView, wgpu::TextureView)>,
    _dummy_velocity: Option<wgpu::Texture>,
    last: Option<LastFrame>,
}

impl ColumnsGpu {
    pub fn new(
        gpu: &Gpu,
        options: Options,
        width: u32,
        height: u32,
        dynamic_scene: bool,
    ) -> ColumnsGpu {
        let device = &gpu.device;
        let (plan, use_velocity) = graph(&options, width, height, dynamic_scene);
        let textures = allocate(device, &plan);
        let view = |name: &str| textures[name].create_view(&Default::default());
        let pipeline = compute_pipeline(device, "reconstruct", COLUMNS_WGSL, "main");
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("interlace params"),
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
        let (half_color, half_depth) = (view("half_color"), view("half_depth"));
        let bind_groups = [0, 1].map(|k| {
            let (out, history) = (view(OUTPUTS[k]), view(OUTPUTS[1 - k]));
            bind_group(
                device,
                "reconstruct",
                &layout,
                &[(0, &params)],
                &[
                    (1, &half_color),
                    (2, &half_depth),
                    (3, &history),
                    (4, &velocity_view),
                    (5, &out),
                ],
            )
        });
        let scene_views = (view("half_color"), view("half_depth"));
        let velocity_views = use_velocity.then(|| (view("velocity"), view("velocity_depth")));
        ColumnsGpu {
            plan,
            textures,
            options,
            width,
            height,
            pipeline,
            params,
            bind_groups: PingPong::new(bind_groups),
            scene_views,
            velocity_views,
            _dummy_velocity: dummy,
            last: None,
        }
    }

    /// A texture of the plan by resource name (`half_color`, `velocity`, ...); `history` is the
    /// output the last frame read.
    pub fn texture(&self, name: &str) -> Option<&wgpu::Texture> {
        match name {
            "history" => self.textures.get(OUTPUTS[1 - self.bind_groups.side()]),
            _ => self.textures.get(name),
        }
    }

    pub fn last_frame(&self) -> Option<LastFrame> {
        self.last
    }
}

impl Renderer for ColumnsGpu {
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
        let (scale, offset) = half_view(self.width, parity);
        let base = View::whole(frame.time, frame.prev_time);
        scene.write_view(
            &gpu.queue,
            0,
            &View {
                ndc_scale: scale,
                ndc_offset: offset,
                gradient_scale: self.options.gradient_scale,
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
        let params = Params {
            prev_from_cur: (prev * cur.inverse()).as_mat4().to_cols_array_2d(),
            size: [self.width, self.height, half_width(self.width), parity],
            mode: [
                u32::from(frame.history_valid),
                u32::from(use_velocity),
                u32::from(self.options.clamp),
                0,
            ],
        };
        gpu.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        self.bind_groups.select(parity);
        self.last = Some(LastFrame {
            parity,
            history_valid: frame.history_valid,
            prev_from_cur: glam::Mat4::from_cols_array_2d(&params.prev_from_cur),
            velocity: use_velocity,
            clamp: self.options.clamp,
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
