//! Techniques on the GPU: each builds its pass graph, allocates what the plan keeps, and records
//! its passes per frame with a timer (and fragment-invocation counter) per pass.
//!
//! Implemented here: `native` (full-resolution forward; reference and baseline), `upscale` (render
//! at a scale factor, then bilinear or nearest upscale) and the ground-truth reference (NxN
//! supersampled native, box-downsampled). What a technique *is* (its parameters) lives in
//! `technique.rs`; running frames and collecting results is `run/`'s job.

use std::collections::HashMap;

use super::graph::{Graph, PassKind, Plan, TextureDesc};
use super::scene::{SceneGpu, ScenePipeline, View, COLOR_FORMAT, DEPTH_FORMAT};
use super::timers::Timers;
use crate::gpu::Gpu;
use crate::technique::{TechniqueKind, Variant};

/// Per-frame facts a technique needs.
#[derive(Clone, Copy, Debug)]
pub struct FrameInfo {
    /// Frame number from the first warm-up frame.
    pub index: u32,
    pub time: f64,
    pub prev_time: f64,
    /// False on the first frame and after a camera cut: techniques must not read history.
    pub history_valid: bool,
}

/// Why a variant cannot run on this adapter: reported as status `skipped`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Unsupported(pub String);

pub trait Technique {
    fn plan(&self) -> &Plan;
    /// The full-resolution Rgba16Float output of the frame.
    fn output(&self) -> &wgpu::Texture;
    fn record(
        &mut self,
        gpu: &Gpu,
        scene: &mut SceneGpu,
        timers: &Timers,
        encoder: &mut wgpu::CommandEncoder,
        frame: FrameInfo,
    );
    /// Per-frame values and images beyond the output, asked for after each captured frame has
    /// been submitted and waited for (never between timed frames): e.g. adaptive shading's
    /// average shading rate and shading-rate image. `frame` is the frame's output as read back;
    /// `image`: whether this frame is saved (make images only then). None by default.
    fn frame_extras(
        &mut self,
        _gpu: &Gpu,
        _frame: &tessera_metrics::HdrImage,
        _image: bool,
    ) -> FrameExtras {
        FrameExtras::default()
    }
}

/// What [`Technique::frame_extras`] reports for one frame.
#[derive(Clone, Debug, Default)]
pub struct FrameExtras {
    /// Named values (e.g. `shading-rate`): each becomes a metric of the variant's own frames.
    pub values: Vec<(&'static str, f64)>,
    /// Named images (image kinds, e.g. `rate`: a shading-rate image), saved next to the frame's as
    /// `<variant>-<kind>-fNNN.png`.
    pub images: Vec<(&'static str, tessera_metrics::Rgb8Image)>,
}

/// Builds the GPU side of a variant at `width` x `height`.
/// `dynamic_scene`: whether anything moves by itself (techniques that need motion add passes).
pub fn build(
    gpu: &Gpu,
    variant: &Variant,
    width: u32,
    height: u32,
    dynamic_scene: bool,
) -> Result<Box<dyn Technique>, Unsupported> {
    check_size(gpu, width, height)?;
    Ok(match variant.technique {
        TechniqueKind::Native | TechniqueKind::Upscale => {
            let (w, h, resolve) = forward_setup(variant, width, height);
            Box::new(Forward::new(gpu, w, h, resolve))
        }
        TechniqueKind::Checkerboard => Box::new(super::checkerboard::Checkerboard::new(
            gpu,
            variant,
            width,
            height,
            dynamic_scene,
        )?),
        TechniqueKind::AdaptiveShading | TechniqueKind::NativeDeferred => {
            Box::new(super::adaptive::Adaptive::new(gpu, variant, width, height))
        }
        TechniqueKind::Checkerboard2x2 => Box::new(super::checkerboard_2x2::Checkerboard2x2::new(
            gpu, variant, width, height,
        )),
    })
}

/// Render size and resolve of a forward variant (`native`, `upscale`).
fn forward_setup(variant: &Variant, width: u32, height: u32) -> (u32, u32, Resolve) {
    if variant.technique != TechniqueKind::Upscale {
        return (width, height, Resolve::None);
    }
    let s = variant.float("scale");
    let lw = ((width as f64 * s).round() as u32).max(1);
    let lh = ((height as f64 * s).round() as u32).max(1);
    let filter = match variant.choice("filter") {
        "nearest" => wgpu::FilterMode::Nearest,
        _ => wgpu::FilterMode::Linear,
    };
    (
        lw,
        lh,
        Resolve::Upscale {
            width,
            height,
            filter,
        },
    )
}

/// The pass graph a variant would run at `width` x `height`, without a GPU: which passes run,
/// which are culled, what is allocated. `tessera` builds the same graph when it renders.
pub fn plan(variant: &Variant, width: u32, height: u32, dynamic_scene: bool) -> Plan {
    match variant.technique {
        TechniqueKind::Native | TechniqueKind::Upscale => {
            let (w, h, resolve) = forward_setup(variant, width, height);
            forward_graph(w, h, resolve)
        }
        TechniqueKind::Checkerboard => {
            super::checkerboard::graph(variant, width, height, dynamic_scene).0
        }
        TechniqueKind::Checkerboard2x2 => {
            let options = super::checkerboard_2x2::Options::from_variant(variant);
            super::checkerboard_2x2::graph(width, height, &options)
                .plan()
                .expect("built-in graphs are well formed")
        }
        TechniqueKind::AdaptiveShading | TechniqueKind::NativeDeferred => {
            super::adaptive::graph(variant, width, height)
        }
    }
}

/// The ground-truth reference: native at `supersample`x the resolution per axis, box-downsampled.
pub fn ground_truth(
    gpu: &Gpu,
    width: u32,
    height: u32,
    supersample: u32,
) -> Result<Box<dyn Technique>, Unsupported> {
    check_size(gpu, width * supersample, height * supersample).map_err(|u| {
        Unsupported(format!(
            "ground-truth reference ({supersample}x{supersample} supersampled): {}",
            u.0
        ))
    })?;
    Ok(Box::new(Forward::new(
        gpu,
        width * supersample,
        height * supersample,
        Resolve::Downsample {
            width,
            height,
            factor: supersample,
        },
    )))
}

fn check_size(gpu: &Gpu, width: u32, height: u32) -> Result<(), Unsupported> {
    let max = gpu.max_dimension();
    if width > max || height > max {
        return Err(Unsupported(format!(
            "{width}x{height} exceeds the adapter's maximum texture size {max}"
        )));
    }
    Ok(())
}

/// How the forward render becomes the full-resolution output.
#[derive(Clone, Copy, Debug)]
enum Resolve {
    /// Rendered at output resolution.
    None,
    Upscale {
        width: u32,
        height: u32,
        filter: wgpu::FilterMode,
    },
    Downsample {
        width: u32,
        height: u32,
        factor: u32,
    },
}

/// Forward rendering at some resolution, optionally followed by a resampling compute pass.
pub struct Forward {
    plan: Plan,
    textures: HashMap<&'static str, wgpu::Texture>,
    resample: Option<(wgpu::ComputePipeline, wgpu::BindGroup, [u32; 2])>,
    /// The scene pass's colour and depth targets, made once.
    scene_views: (wgpu::TextureView, wgpu::TextureView),
    /// What the scene pass draws: shaded colour, or (`velocity_only`) screen motion.
    kind: ScenePipeline,
}

/// The pass graph of forward rendering at `width` x `height` with `resolve`.
fn forward_graph(width: u32, height: u32, resolve: Resolve) -> Plan {
    let tex = |format, width, height| TextureDesc {
        format,
        width,
        height,
        samples: 1,
        layers: 1,
    };
    let mut g = Graph::default();
    match resolve {
        Resolve::None => {
            g.resource("color", tex(COLOR_FORMAT, width, height))
                .resource("depth", tex(DEPTH_FORMAT, width, height))
                .pass("scene", PassKind::Render, &[], &["color", "depth"])
                .output("color");
        }
        Resolve::Upscale {
            width: ow,
            height: oh,
            ..
        }
        | Resolve::Downsample {
            width: ow,
            height: oh,
            ..
        } => {
            // Rendered at another resolution, then resampled to the output by a compute pass.
            let (color, depth, pass) = match resolve {
                Resolve::Upscale { .. } => ("color_low", "depth_low", "upscale"),
                _ => ("color_ss", "depth_ss", "downsample"),
            };
            g.resource(color, tex(COLOR_FORMAT, width, height))
                .resource(depth, tex(DEPTH_FORMAT, width, height))
                .resource("color", tex(COLOR_FORMAT, ow, oh))
                .pass("scene", PassKind::Render, &[], &[color, depth])
                .pass(pass, PassKind::Compute, &[color], &["color"])
                .output("color");
        }
    }
    g.plan().expect("built-in graphs are well formed")
}

impl Forward {
    fn new(gpu: &Gpu, width: u32, height: u32, resolve: Resolve) -> Forward {
        let plan = forward_graph(width, height, resolve);
        let textures = allocate(&gpu.device, &plan);
        let resample = match resolve {
            Resolve::None => None,
            Resolve::Upscale {
                width: ow,
                height: oh,
                filter,
            } => Some(upscale_pipeline(
                gpu,
                &textures["color_low"],
                &textures["color"],
                filter,
                [ow, oh],
            )),
            Resolve::Downsample {
                width: ow,
                height: oh,
                factor,
            } => Some(downsample_pipeline(
                gpu,
                &textures["color_ss"],
                &textures["color"],
                factor,
                [ow, oh],
            )),
        };
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
        }
    }

    /// The velocity pass alone at output resolution (the `tde` metric's exact motion): `output()`
    /// is the motion target, [`Forward::depth`] its depth.
    pub fn velocity_only(gpu: &Gpu, width: u32, height: u32) -> Forward {
        Forward {
            kind: ScenePipeline::Velocity,
            ..Forward::new(gpu, width, height, Resolve::None)
        }
    }

    /// The scene pass's depth target.
    pub fn depth(&self) -> &wgpu::Texture {
        &self.textures[self.plan.passes[0].writes[1]]
    }
}

impl Technique for Forward {
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
        let view = View::whole(frame.time, frame.prev_time);
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
        if let Some((pipeline, bind_group, [w, h])) = &self.resample {
            let name = self.plan.passes[1].name;
            let q = timers.begin(name, encoder);
            {
                let mut cp = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some(name),
                    timestamp_writes: q.compute_pass_timestamp_writes(),
                });
                cp.set_pipeline(pipeline);
                cp.set_bind_group(0, bind_group, &[]);
                cp.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
            }
            timers.end(encoder, q);
        }
    }
}

/// Allocates every texture the plan keeps.
pub fn allocate(device: &wgpu::Device, plan: &Plan) -> HashMap<&'static str, wgpu::Texture> {
    allocate_with(device, plan, wgpu::TextureUsages::empty())
}

/// [`allocate`], every texture also with `extra` usages (e.g. `COPY_DST` for textures a
/// technique fills by copying).
pub fn allocate_with(
    device: &wgpu::Device,
    plan: &Plan,
    extra: wgpu::TextureUsages,
) -> HashMap<&'static str, wgpu::Texture> {
    plan.resources
        .iter()
        .map(|r| {
            let d = &r.desc;
            let mut usage = wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | extra;
            if d.samples == 1 {
                usage |= wgpu::TextureUsages::COPY_SRC;
                if !d.format.is_depth_stencil_format() {
                    usage |= wgpu::TextureUsages::STORAGE_BINDING;
                }
            }
            let t = device.create_texture(&wgpu::TextureDescriptor {
                label: Some(r.name),
                size: wgpu::Extent3d {
                    width: d.width,
                    height: d.height,
                    depth_or_array_layers: d.layers,
                },
                mip_level_count: 1,
                sample_count: d.samples,
                dimension: wgpu::TextureDimension::D2,
                format: d.format,
                usage,
                view_formats: &[],
            });
            (r.name, t)
        })
        .collect()
}

/// The forward `scene` pass into `color` and `depth`, timed and counted.
#[allow(clippy::too_many_arguments)]
pub fn record_scene_pass(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    timers: &Timers,
    encoder: &mut wgpu::CommandEncoder,
    name: &'static str,
    color_view: &wgpu::TextureView,
    depth_view: &wgpu::TextureView,
    slot: u32,
    kind: ScenePipeline,
) {
    record_scene_pass_on(
        gpu,
        scene,
        timers,
        encoder,
        (name, slot, kind),
        color_view,
        depth_view,
        wgpu::LoadOp::Clear(0.0),
    );
}

/// [`record_scene_pass`] with the depth buffer's load op: `Load` draws over a pre-conditioned
/// depth buffer (checkerboard-2x2's masks), `Clear(0.0)` starts from the far plane (reversed-Z).
#[allow(clippy::too_many_arguments)]
pub fn record_scene_pass_on(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    timers: &Timers,
    encoder: &mut wgpu::CommandEncoder,
    (name, slot, kind): (&'static str, u32, ScenePipeline),
    color_view: &wgpu::TextureView,
    depth_view: &wgpu::TextureView,
    depth_load: wgpu::LoadOp<f32>,
) {
    // Velocity targets hold motion, not colour: nothing drawn means no motion.
    let clear = match kind {
        ScenePipeline::Velocity => wgpu::Color::TRANSPARENT,
        _ => scene.clear_color(),
    };
    let pipeline = scene.pipeline(&gpu.device, kind).clone();
    let q = timers.begin(name, encoder);
    {
        let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(name),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: color_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(clear),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: depth_load,
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: q.render_pass_timestamp_writes(),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        timers.begin_stats(&mut rp, name);
        scene.draw(&mut rp, &pipeline, slot);
        timers.end_stats(&mut rp, name);
    }
    timers.end(encoder, q);
}

/// A 1x1 texture bound where a technique's optional input (a history, a velocity buffer) is not
/// kept, so one bind group layout serves with and without it.
pub fn placeholder_texture(
    device: &wgpu::Device,
    label: &str,
    format: wgpu::TextureFormat,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: 1,
            height: 1,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    })
}

/// A bind group of whole buffers and texture views, each at its binding number.
pub fn bind_group(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: &[(u32, &wgpu::Buffer)],
    views: &[(u32, &wgpu::TextureView)],
) -> wgpu::BindGroup {
    let mut entries: Vec<wgpu::BindGroupEntry> = buffers
        .iter()
        .map(|(binding, b)| wgpu::BindGroupEntry {
            binding: *binding,
            resource: b.as_entire_binding(),
        })
        .collect();
    entries.extend(views.iter().map(|(binding, v)| wgpu::BindGroupEntry {
        binding: *binding,
        resource: wgpu::BindingResource::TextureView(v),
    }));
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}

/// A compute pipeline with an automatic layout from WGSL `source`.
pub fn compute_pipeline(
    device: &wgpu::Device,
    label: &str,
    source: &str,
    entry_point: &str,
) -> wgpu::ComputePipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: None,
        module: &module,
        entry_point: Some(entry_point),
        compilation_options: Default::default(),
        cache: None,
    })
}

static UPSCALE_WGSL: &str = include_str!("../../../shaders/upscale.wgsl");
static DOWNSAMPLE_WGSL: &str = include_str!("../../../shaders/downsample.wgsl");

fn upscale_pipeline(
    gpu: &Gpu,
    src: &wgpu::Texture,
    dst: &wgpu::Texture,
    filter: wgpu::FilterMode,
    size: [u32; 2],
) -> (wgpu::ComputePipeline, wgpu::BindGroup, [u32; 2]) {
    let device = &gpu.device;
    let pipeline = compute_pipeline(device, "upscale", UPSCALE_WGSL, "main");
    let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("upscale"),
        mag_filter: filter,
        min_filter: filter,
        address_mode_u: wgpu::AddressMode::ClampToEdge,
        address_mode_v: wgpu::AddressMode::ClampToEdge,
        ..Default::default()
    });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("upscale"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&src.create_view(&Default::default())),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::Sampler(&sampler),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: wgpu::BindingResource::TextureView(&dst.create_view(&Default::default())),
            },
        ],
    });
    (pipeline, bind_group, size)
}

fn downsample_pipeline(
    gpu: &Gpu,
    src: &wgpu::Texture,
    dst: &wgpu::Texture,
    factor: u32,
    size: [u32; 2],
) -> (wgpu::ComputePipeline, wgpu::BindGroup, [u32; 2]) {
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
    (pipeline, bind_group, size)
}

/// Every WGSL module the harness builds, composed as the GPU sees it (name, source), and the
/// files under `shaders/` they are made of; for validation without a GPU.
pub fn shader_sources() -> Vec<(String, String, Vec<&'static str>)> {
    use super::checkerboard::{MSAA2X_WGSL, PROBE_WGSL, RESOLVE_WGSL, TWO_PASS_WGSL};
    vec![
        (
            "scene.wgsl".into(),
            super::scene::SCENE_WGSL.into(),
            vec!["scene.wgsl"],
        ),
        (
            "upscale.wgsl".into(),
            UPSCALE_WGSL.into(),
            vec!["upscale.wgsl"],
        ),
        (
            "downsample.wgsl".into(),
            DOWNSAMPLE_WGSL.into(),
            vec!["downsample.wgsl"],
        ),
        (
            "sample_positions.wgsl".into(),
            PROBE_WGSL.into(),
            vec!["sample_positions.wgsl"],
        ),
        (
            "checkerboard two-pass".into(),
            format!("{TWO_PASS_WGSL}\n{RESOLVE_WGSL}"),
            vec!["checkerboard_two_pass.wgsl", "checkerboard_resolve.wgsl"],
        ),
        (
            "checkerboard msaa2x".into(),
            format!("{MSAA2X_WGSL}\n{RESOLVE_WGSL}"),
            vec!["checkerboard_msaa2x.wgsl", "checkerboard_resolve.wgsl"],
        ),
        (
            "adaptive_rate.wgsl".into(),
            super::adaptive::RATE_WGSL.into(),
            vec!["adaptive_rate.wgsl"],
        ),
        (
            "adaptive shade".into(),
            super::adaptive::shade_source(),
            vec!["scene.wgsl", "adaptive_shade.wgsl"],
        ),
        (
            "checkerboard-2x2 mask".into(),
            super::checkerboard_2x2::MASK_WGSL.into(),
            vec!["checkerboard_2x2_mask.wgsl"],
        ),
        (
            "checkerboard-2x2 reconstitute".into(),
            super::checkerboard_2x2::RECONSTITUTE_WGSL.into(),
            vec!["checkerboard_2x2_reconstitute.wgsl"],
        ),
    ]
}
