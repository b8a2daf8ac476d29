//! Forward rendering on the GPU: one `scene` pass at some resolution, optionally followed by a
//! compute pass that resamples it to the output ([`Resample`]): `native`, `upscale` (its own
//! resample pass) and the ground-truth reference (NxN supersampled, box-downsampled).

use std::collections::HashMap;

use crate::gpu::Gpu;
use crate::render::graph::{Graph, PassKind, Plan, TextureDesc};
use crate::render::kit::{allocate, compute_pipeline, record_scene_pass, timed_dispatch};
use crate::render::renderer::{FrameInfo, Renderer, Unsupported};
use crate::render::scene::{SceneGpu, ScenePipeline, View, COLOR_FORMAT, DEPTH_FORMAT};
use crate::render::timers::Timers;

pub static DOWNSAMPLE_WGSL: &str = include_str!("downsample.wgsl");

/// A compute pass that turns the forward render into the `width` x `height` output: its pass
/// name and the names of the render's colour and depth targets.
#[derive(Clone, Copy, Debug)]
pub struct Resample {
    pub pass: &'static str,
    pub color: &'static str,
    pub depth: &'static str,
    pub width: u32,
    pub height: u32,
}

/// Makes the resample pass's pipeline and bind group from the render's colour target and the
/// output texture.
pub type MakeResample = Box<
    dyn FnOnce(&Gpu, &wgpu::Texture, &wgpu::Texture) -> (wgpu::ComputePipeline, wgpu::BindGroup),
>;

/// Forward rendering at some resolution, optionally followed by a resampling compute pass.
pub struct Forward {
    plan: Plan,
    textures: HashMap<&'static str, wgpu::Texture>,
    resample: Option<(wgpu::ComputePipeline, wgpu::BindGroup, [u32; 2])>,
    /// The scene pass's colour and depth targets, made once.
    scene_views: (wgpu::TextureView, wgpu::TextureView),
    /// What the scene pass draws: shaded colour, or (`velocity_only`) screen motion.
    kind: ScenePipeline,
    /// Texture LOD bias of the scene pass ([`View::lod_bias`]).
    lod_bias: f32,
    /// The motion pass's targets (motion, its depth), when it is rendered.
    motion: Option<(wgpu::TextureView, wgpu::TextureView)>,
}

/// [`forward_graph`] at output resolution with the motion pass after the scene pass (`native`'s
/// `motion_pass`): the velocity pipeline into `motion`, which leaves the frame as the depth-based
/// report's renderer hands it to later effects (section 6), so it is an output, not culled.
pub fn forward_graph_with_motion(width: u32, height: u32) -> Plan {
    let tex = |format| TextureDesc {
        format,
        width,
        height,
        samples: 1,
        layers: 1,
    };
    let mut g = Graph::default();
    g.resource("color", tex(COLOR_FORMAT))
        .resource("depth", tex(DEPTH_FORMAT))
        .resource("motion", tex(COLOR_FORMAT))
        .resource("motion_depth", tex(DEPTH_FORMAT))
        .pass("scene", PassKind::Render, &[], &["color", "depth"])
        .pass("motion", PassKind::Render, &[], &["motion", "motion_depth"])
        .output("color")
        .output("motion");
    g.plan().expect("built-in graphs are well formed")
}

/// The pass graph of forward rendering at `width` x `height`, resampled by `resample` if any.
pub fn forward_graph(width: u32, height: u32, resample: Option<&Resample>) -> Plan {
    let tex = |format, width, height| TextureDesc {
        format,
        width,
        height,
        samples: 1,
        layers: 1,
    };
    let mut g = Graph::default();
    match resample {
        None => {
            g.resource("color", tex(COLOR_FORMAT, width, height))
                .resource("depth", tex(DEPTH_FORMAT, width, height))
                .pass("scene", PassKind::Render, &[], &["color", "depth"])
                .output("color");
        }
        Some(r) => {
            // Rendered at another resolution, then resampled to the output by a compute pass.
            g.resource(r.color, tex(COLOR_FORMAT, width, height))
                .resource(r.depth, tex(DEPTH_FORMAT, width, height))
                .resource("color", tex(COLOR_FORMAT, r.width, r.height))
                .pass("scene", PassKind::Render, &[], &[r.color, r.depth])
                .pass(r.pass, PassKind::Compute, &[r.color], &["color"])
                .output("color");
        }
    }
    g.plan().expect("built-in graphs are well formed")
}

impl Forward {
    /// Forward rendering at `width` x `height`, resampled to the output when `resample` is given.
    pub fn new(
        gpu: &Gpu,
        width: u32,
        height: u32,
        resample: Option<(Resample, MakeResample)>,
    ) -> Forward {
        let plan = forward_graph(width, height, resample.as_ref().map(|(r, _)| r));
        let textures = allocate(&gpu.device, &plan);
        let resample = resample.map(|(r, make)| {
            let (pipeline, bind_group) = make(gpu, &textures[r.color], &textures["color"]);
            (pipeline, bind_group, [r.width, r.height])
        });
        let writes = &plan.passes[0].writes;
        let scene_views = (
            textures[writes[0]].create_view(&Default::default()),
            textures[writes[1]].create_view(&Default::default()),
        );
        Forward {
            plan,
            textures,
            resample,
            scene_views,
            kind: ScenePipeline::Forward { samples: 1 },
            lod_bias: 0.0,
            motion: None,
        }
    }

    /// The same with the motion pass (a forward render at output resolution only).
    pub fn with_motion_pass(self, gpu: &Gpu) -> Forward {
        let (w, h) = (
            self.textures["color"].width(),
            self.textures["color"].height(),
        );
        let plan = forward_graph_with_motion(w, h);
        let textures = allocate(&gpu.device, &plan);
        let view = |name: &str| textures[name].create_view(&Default::default());
        let scene_views = (view("color"), view("depth"));
        let motion = Some((view("motion"), view("motion_depth")));
        Forward {
            plan,
            textures,
            scene_views,
            motion,
            ..self
        }
    }

    /// The same, sampling textures `lod_bias` mip levels sharper (negative) or blurrier: an
    /// upscaler's -log2(output / render), so textures keep the output's detail.
    pub fn with_lod_bias(self, lod_bias: f32) -> Forward {
        Forward { lod_bias, ..self }
    }

    /// The velocity pass alone at output resolution (the `tde` metric's exact motion): `output()`
    /// is the motion target, [`Forward::depth`] its depth.
    pub fn velocity_only(gpu: &Gpu, width: u32, height: u32) -> Forward {
        Forward {
            kind: ScenePipeline::Velocity,
            ..Forward::new(gpu, width, height, None)
        }
    }

    /// The scene pass's depth target.
    pub fn depth(&self) -> &wgpu::Texture {
        &self.textures[self.plan.passes[0].writes[1]]
    }
}

/// The ground-truth reference: native at `supersample`x the resolution per axis, box-downsampled.
pub fn ground_truth(
    gpu: &Gpu,
    width: u32,
    height: u32,
    supersample: u32,
) -> Result<Box<dyn Renderer>, Unsupported> {
    gpu.check_size(width * supersample, height * supersample)
        .map_err(|u| {
            Unsupported(format!(
                "ground-truth reference ({supersample}x{supersample} supersampled): {}",
                u.0
            ))
        })?;
    let resample = Resample {
        pass: "downsample",
        color: "color_ss",
        depth: "depth_ss",
        width,
        height,
    };
    let make: MakeResample =
        Box::new(move |gpu, src, dst| downsample_pipeline(gpu, src, dst, supersample));
    Ok(Box::new(Forward::new(
        gpu,
        width * supersample,
        height * supersample,
        Some((resample, make)),
    )))
}

impl Renderer for Forward {
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
        let view = View {
            lod_bias: self.lod_bias,
            ..View::whole(frame.time, frame.prev_time)
        };
        scene.write_view(&gpu.queue, 0, &view);
        record_scene_pass(
            gpu,
            scene,
            timers,
            encoder,
            "scene",
            &self.scene_views.0,
            &self.scene_views.1,
            0,
            self.kind,
        );
        if let Some((motion, motion_depth)) = &self.motion {
            record_scene_pass(
                gpu,
                scene,
                timers,
                encoder,
                "motion",
                motion,
                motion_depth,
                0,
                ScenePipeline::Velocity,
            );
        }
        if let Some((pipeline, bind_group, [w, h])) = &self.resample {
            let name = self.plan.passes[1].name;
            let size = [w.div_ceil(8), h.div_ceil(8)];
            timed_dispatch(encoder, timers, name, pipeline, &[bind_group], size);
        }
    }
}

fn downsample_pipeline(
    gpu: &Gpu,
    src: &wgpu::Texture,
    dst: &wgpu::Texture,
    factor: u32,
) -> (wgpu::ComputePipeline, wgpu::BindGroup) {
    use wgpu::util::DeviceExt;
    let device = &gpu.device;
    let pipeline = compute_pipeline(device, "downsample", DOWNSAMPLE_WGSL, "main");
    let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("downsample params"),
        contents: bytemuck::cast_slice(&[factor, 0, 0, 0]),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("downsample"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&src.create_view(&Default::default())),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(&dst.create_view(&Default::default())),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: params.as_entire_binding(),
            },
        ],
    });
    (pipeline, bind_group)
}
