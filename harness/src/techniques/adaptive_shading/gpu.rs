//! The GPU part of `adaptive-shading` and `native-deferred`: NVIDIA's content and motion adaptive
//! shading (Yang et al. 2019, `seeds/nvidia-adaptive-shading.txt`) on software variable-rate
//! shading, and its baseline.
//!
//! Each frame: a `gbuffer` render pass at full resolution (what `shade_surface` in `scene.wgsl`
//! needs per pixel, plus per-pixel motion); a `rates` compute pass choosing a rate per 16x16 tile
//! from the previous frame's output (`rate.wgsl`, CPU model in
//! `model.rs`); optionally the `rate_filter` pass (section 5.4); and a `shade` compute pass
//! shading once per coarse pixel and object (`shade.wgsl`). `native-deferred` is
//! the same G-buffer and shading pass at 1x1 everywhere, with no rate pass, no motion and no
//! history. Outputs and depth buffers are ping-ponged: the rate pass reads the previous frame's.
//!
//! Not here: the forward shading function (scene.wgsl), result files (run/).

use std::collections::HashMap;

use tessera_metrics::Rgb8Image;

use super::model::{self, CoarseSample, RateParams, TILE};
use crate::gpu::Gpu;
use crate::render::graph::{Graph, PassKind, Plan, TextureDesc};
use crate::render::kit::{
    allocate, bind_group, compute_pipeline, placeholder_texture, timed_dispatch, PingPong,
};
use crate::render::readback::read_texture_raw;
use crate::render::renderer::{FrameExtras, FrameInfo, FrameValue, Renderer};
use crate::render::scene::{SceneGpu, View, COLOR_FORMAT, DEPTH_FORMAT};
use crate::render::timers::Timers;

pub static RATE_WGSL: &str = include_str!("rate.wgsl");
/// The rate pass's entry point for any adapter (workgroup memory, barriers).
pub static RATE_SHARED_WGSL: &str = include_str!("rate_shared.wgsl");
/// The rate pass's entry point where a subgroup holds a tile (shuffles, subgroup sums).
pub static RATE_SUBGROUP_WGSL: &str = include_str!("rate_subgroup.wgsl");
/// Section 5.4's neighbour filter, appended to the modules that filter.
pub static RATE_FILTER_WGSL: &str = include_str!("rate_filter.wgsl");

/// The rate pass's module: `rate.wgsl` and the filter, with the subgroup entry point where `wide`
/// (see [`wide_subgroups`]), the workgroup-memory one otherwise.
pub fn rate_source(wide: bool) -> String {
    if wide {
        format!("{RATE_WGSL}\n{RATE_FILTER_WGSL}\n{RATE_SUBGROUP_WGSL}")
    } else {
        format!("{RATE_WGSL}\n{RATE_FILTER_WGSL}\n{RATE_SHARED_WGSL}")
    }
}

/// Whether the rate pass can reduce a tile's 32 threads inside one subgroup: the device has
/// subgroup operations and no subgroup is narrower than 32 invocations (NVIDIA 32, AMD 32 or 64;
/// lavapipe's 8 and Intel's 8 to 32 take the workgroup-memory path). The two measured on an H200:
/// `scenarios/adaptive/README.md`, "Rate pass at 4K".
pub fn wide_subgroups(gpu: &Gpu) -> bool {
    gpu.device.features().contains(wgpu::Features::SUBGROUP)
        && gpu.adapter.get_info().subgroup_min_size >= 32
}
pub static SHADE_WGSL: &str = include_str!("shade.wgsl");

/// `scene.wgsl` with the G-buffer and shading entry points appended.
pub fn shade_source() -> String {
    format!("{}\n{SHADE_WGSL}", crate::render::scene::SCENE_WGSL)
}

const GBUF_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// Motion in pixels and the previous reversed-Z depth: f16 keeps sub-pixel motion to 1024 px and
/// depth near the far plane (near 0) finely enough for the 5% rejection, at half the bandwidth of
/// the rate pass's largest input.
pub(super) const MOTION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
pub(super) const RATE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
pub(super) const STATE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;
const GBUFFER: [&str; 3] = ["gbuf_position", "gbuf_normal", "gbuf_detail"];
pub(super) const COLORS: [&str; 2] = ["color0", "color1"];
pub(super) const DEPTHS: [&str; 2] = ["depth0", "depth1"];
pub(super) const STATES: [&str; 2] = ["rate_state0", "rate_state1"];

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct RateUniforms {
    size: [u32; 4],
    mode: [u32; 4],
    t: [f32; 4],
    more: [f32; 4],
}

/// The pass graph at `width` x `height` (no GPU needed): what runs and what is allocated;
/// `rates`: the rate selection of `adaptive-shading`, `None` for `native-deferred`.
pub fn graph(rates: Option<&RateParams>, width: u32, height: u32) -> Plan {
    let params = rates;
    let (tw, th) = model::tiles(width, height);
    let tex = |format, width, height| TextureDesc {
        format,
        width,
        height,
        samples: 1,
        layers: 1,
    };
    let mut g = Graph::default();
    for name in GBUFFER {
        g.resource(name, tex(GBUF_FORMAT, width, height));
    }
    let mut gbuffer_writes: Vec<&'static str> = GBUFFER.to_vec();
    let parities = if params.is_some() { 2 } else { 1 };
    for p in 0..parities {
        g.resource(COLORS[p], tex(COLOR_FORMAT, width, height))
            .resource(DEPTHS[p], tex(DEPTH_FORMAT, width, height));
        gbuffer_writes.push(DEPTHS[p]);
    }
    let mut shade_reads: Vec<&'static str> = GBUFFER.to_vec();
    if let Some(p) = &params {
        g.resource("motion", tex(MOTION_FORMAT, width, height))
            .resource("rates", tex(RATE_FORMAT, tw, th));
        for s in STATES {
            g.resource(s, tex(STATE_FORMAT, tw, th));
        }
        gbuffer_writes.push("motion");
        g.pass("gbuffer", PassKind::Render, &[], &gbuffer_writes);
        let reads = [
            COLORS[0], COLORS[1], "motion", DEPTHS[0], DEPTHS[1], STATES[0], STATES[1],
        ];
        if p.neighbour_filter {
            g.resource("rates_raw", tex(RATE_FORMAT, tw, th));
            g.pass(
                "rates",
                PassKind::Compute,
                &reads,
                &["rates_raw", STATES[0], STATES[1]],
            );
            g.pass("rate_filter", PassKind::Compute, &["rates_raw"], &["rates"]);
        } else {
            g.pass(
                "rates",
                PassKind::Compute,
                &reads,
                &["rates", STATES[0], STATES[1]],
            );
        }
        shade_reads.push("rates");
        g.pass("shade", PassKind::Compute, &shade_reads, &COLORS);
        g.output(COLORS[0]).output(COLORS[1]);
    } else {
        g.pass("gbuffer", PassKind::Render, &[], &gbuffer_writes);
        g.pass("shade", PassKind::Compute, &shade_reads, &[COLORS[0]]);
        g.output(COLORS[0]);
    }
    g.plan().expect("built-in graphs are well formed")
}

/// The rate pass and its filter (where it is its own pass), with bind groups per frame parity.
pub(super) struct RatePass {
    params: RateParams,
    uniforms: wgpu::Buffer,
    pipeline: wgpu::ComputePipeline,
    /// One per side: the previous frame's colour, depth and rate state as history.
    bind_groups: PingPong<wgpu::BindGroup>,
    filter: Option<(wgpu::ComputePipeline, wgpu::BindGroup)>,
}

impl RatePass {
    /// The rate pass (and filter) reading the resources `view` names: `color0`/`color1`,
    /// `depth0`/`depth1` (the previous frame's by parity, and this frame's for coverage), `motion`,
    /// `rate_state0`/`1`, and writing `rates` (through `rates_raw` and the filter pass with the
    /// filter), or only `rates_raw` where a later pass filters (`own_filter` false: the hardware
    /// path's attachment pass).
    pub(super) fn new(
        gpu: &Gpu,
        params: RateParams,
        own_filter: bool,
        view: &dyn Fn(&str) -> wgpu::TextureView,
    ) -> RatePass {
        let device = &gpu.device;
        let source = rate_source(wide_subgroups(gpu));
        let pipeline = compute_pipeline(device, "rates", &source, "main");
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("rate params"),
            size: std::mem::size_of::<RateUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let raw = if params.neighbour_filter || !own_filter {
            "rates_raw"
        } else {
            "rates"
        };
        let layout = pipeline.get_bind_group_layout(0);
        let (colors, depths, states) = (
            PingPong::new(COLORS),
            PingPong::new(DEPTHS),
            PingPong::new(STATES),
        );
        let bind_group = |side: usize| {
            let views = [
                (1, view(colors.at(side).1)),
                (2, view("motion")),
                (3, view(depths.at(side).1)),
                (4, view(states.at(side).1)),
                (5, view(states.at(side).0)),
                (6, view(raw)),
                (9, view(depths.at(side).0)),
            ];
            let views: Vec<(u32, &wgpu::TextureView)> =
                views.iter().map(|(b, v)| (*b, v)).collect();
            bind_group(device, "rates", &layout, &[(0, &uniforms)], &views)
        };
        let bind_groups = PingPong::new([bind_group(0), bind_group(1)]);
        let filter = (params.neighbour_filter && own_filter).then(|| {
            let pipeline = compute_pipeline(device, "rate_filter", &source, "filter_rates");
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("rate_filter"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: uniforms.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 7,
                        resource: wgpu::BindingResource::TextureView(&view("rates_raw")),
                    },
                    wgpu::BindGroupEntry {
                        binding: 8,
                        resource: wgpu::BindingResource::TextureView(&view("rates")),
                    },
                ],
            });
            (pipeline, bind_group)
        });
        RatePass {
            params,
            uniforms,
            pipeline,
            bind_groups,
            filter,
        }
    }

    /// Records the rate pass (and filter) of a frame of `parity` at `width` x `height`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn record(
        &self,
        gpu: &Gpu,
        scene: &SceneGpu,
        timers: &Timers,
        encoder: &mut wgpu::CommandEncoder,
        parity: usize,
        history: bool,
        width: u32,
        height: u32,
    ) -> LastFrame {
        let (tw, th) = model::tiles(width, height);
        let (near, far) = scene.near_far();
        let p = self.params;
        let u = RateUniforms {
            size: [width, height, tw, th],
            mode: [p.mode.code(), u32::from(history), u32::from(p.allow_4x4), 0],
            t: [p.threshold, p.env_luma, p.k, p.max_error],
            more: [p.hysteresis, p.disocclusion_tolerance, near, far],
        };
        gpu.queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&u));
        timed_dispatch(
            encoder,
            timers,
            "rates",
            &self.pipeline,
            &[self.bind_groups.at(parity).0],
            [tw, th],
        );
        if let Some((pipeline, group)) = &self.filter {
            timed_dispatch(
                encoder,
                timers,
                "rate_filter",
                pipeline,
                &[group],
                [tw.div_ceil(8), th.div_ceil(8)],
            );
        }
        LastFrame {
            parity,
            history,
            params: p,
            near,
            far,
        }
    }
}

/// What the last recorded rate pass was given (for the CPU model in tests).
#[derive(Clone, Copy, Debug)]
pub struct LastFrame {
    pub parity: usize,
    pub history: bool,
    pub params: RateParams,
    pub near: f32,
    pub far: f32,
}

pub struct AdaptiveGpu {
    plan: Plan,
    textures: HashMap<&'static str, wgpu::Texture>,
    width: u32,
    height: u32,
    rate: Option<RatePass>,
    module: wgpu::ShaderModule,
    shade_pipeline: wgpu::ComputePipeline,
    _shade_uniforms: wgpu::Buffer,
    /// Per side: group 1 of the shading pass (output color0 or color1), the G-buffer depth and
    /// the output's name; without history both sides are side 0's.
    sides: PingPong<Side>,
    /// Made on the first frame, when the scene is known: G-buffer pipeline, shading group 0.
    scene_objects: Option<(wgpu::RenderPipeline, wgpu::BindGroup)>,
    /// G-buffer colour targets.
    gbuffer_views: Vec<wgpu::TextureView>,
    counters: wgpu::Buffer,
    counters_readback: wgpu::Buffer,
    _dummy_rates: Option<wgpu::Texture>,
    last: Option<LastFrame>,
}

/// What one side of [`AdaptiveGpu`]'s history pair writes.
struct Side {
    shade_group: wgpu::BindGroup,
    depth_view: wgpu::TextureView,
    color: &'static str,
}

impl AdaptiveGpu {
    /// `rates`: the rate selection of `adaptive-shading`, `None` for `native-deferred`.
    pub fn new(gpu: &Gpu, rates: Option<RateParams>, width: u32, height: u32) -> AdaptiveGpu {
        let params = rates;
        let history = params.is_some();
        let plan = graph(params.as_ref(), width, height);
        let textures = allocate(&gpu.device, &plan);
        let device = &gpu.device;
        let view = |name: &str| textures[name].create_view(&Default::default());

        let source = shade_source();
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("adaptive shade"),
            source: wgpu::ShaderSource::Wgsl(source.as_str().into()),
        });
        let shade_pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("shade"),
            layout: None,
            module: &module,
            entry_point: Some("shade_main"),
            compilation_options: Default::default(),
            cache: None,
        });
        use wgpu::util::DeviceExt;
        let shade_uniforms = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("shade params"),
            contents: bytemuck::cast_slice(&[
                width,
                height,
                u32::from(!history),
                u32::from(params.is_some_and(|p| p.coarse_sample == CoarseSample::Pixel)),
            ]),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let counters = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("shade counters"),
            size: 8,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let counters_readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("shade counters readback"),
            size: 8,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let dummy_rates = (!history).then(|| placeholder_texture(device, "no rates", RATE_FORMAT));
        let rates_view = match &dummy_rates {
            Some(t) => t.create_view(&Default::default()),
            None => view("rates"),
        };
        let shade_layout = shade_pipeline.get_bind_group_layout(1);
        let side = |p: usize| {
            let shade_group = {
                let views = [
                    (1, view(GBUFFER[0])),
                    (2, view(GBUFFER[1])),
                    (3, view(GBUFFER[2])),
                    (4, rates_view.clone()),
                    (5, view(COLORS[p])),
                ];
                let views: Vec<(u32, &wgpu::TextureView)> =
                    views.iter().map(|(b, v)| (*b, v)).collect();
                bind_group(
                    device,
                    "shade",
                    &shade_layout,
                    &[(0, &shade_uniforms), (6, &counters)],
                    &views,
                )
            };
            Side {
                shade_group,
                depth_view: view(DEPTHS[p]),
                color: COLORS[p],
            }
        };
        let sides = PingPong::new([side(0), side(usize::from(history))]);

        let rate = params.map(|params| RatePass::new(gpu, params, true, &view));

        let mut gbuffer_views: Vec<wgpu::TextureView> = GBUFFER.iter().map(|n| view(n)).collect();
        if history {
            gbuffer_views.push(view("motion"));
        }
        AdaptiveGpu {
            plan,
            textures,
            width,
            height,
            rate,
            module,
            shade_pipeline,
            _shade_uniforms: shade_uniforms,
            sides,
            scene_objects: None,
            gbuffer_views,
            counters,
            counters_readback,
            _dummy_rates: dummy_rates,
            last: None,
        }
    }

    /// A texture of the plan by resource name (`motion`, `rates`, `color0`, ...).
    pub fn texture(&self, name: &str) -> Option<&wgpu::Texture> {
        self.textures.get(name)
    }

    pub fn last_frame(&self) -> Option<LastFrame> {
        self.last
    }

    /// Shades and covered pixels of the last submitted frame (blocks until it is done).
    pub fn counters(&self, gpu: &Gpu) -> [u32; 2] {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&self.counters, 0, &self.counters_readback, 0, 8);
        gpu.queue.submit([encoder.finish()]);
        let slice = self.counters_readback.slice(..);
        slice.map_async(wgpu::MapMode::Read, |_| {});
        let _ = gpu.device.poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: None,
        });
        let out = match slice.get_mapped_range() {
            Ok(data) => {
                let v: &[u32] = bytemuck::cast_slice(&data);
                [v[0], v[1]]
            }
            Err(_) => [0, 0],
        };
        self.counters_readback.unmap();
        out
    }

    /// The rate codes of the last frame's tiles (after the filter).
    pub fn rates(&self, gpu: &Gpu) -> Option<Vec<u32>> {
        let t = self.textures.get("rates")?;
        Some(bytemuck::cast_slice(&read_texture_raw(gpu, t)).to_vec())
    }

    fn gbuffer_pass(&self, encoder: &mut wgpu::CommandEncoder, scene: &SceneGpu, timers: &Timers) {
        let (pipeline, _) = self.scene_objects.as_ref().expect("made before");
        let attachments: Vec<Option<wgpu::RenderPassColorAttachment>> = self
            .gbuffer_views
            .iter()
            .map(|v| {
                Some(wgpu::RenderPassColorAttachment {
                    view: v,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })
            })
            .collect();
        let q = timers.begin("gbuffer", encoder);
        {
            let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("gbuffer"),
                color_attachments: &attachments,
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.sides.current().depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(0.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: q.render_pass_timestamp_writes(),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            timers.begin_stats(&mut rp, "gbuffer");
            scene.draw(&mut rp, pipeline, 0);
            timers.end_stats(&mut rp, "gbuffer");
        }
        timers.end(encoder, q);
    }
}

impl Renderer for AdaptiveGpu {
    fn plan(&self) -> &Plan {
        &self.plan
    }

    fn output(&self) -> &wgpu::Texture {
        &self.textures[self.sides.current().color]
    }

    fn record(
        &mut self,
        gpu: &Gpu,
        scene: &mut SceneGpu,
        timers: &Timers,
        encoder: &mut wgpu::CommandEncoder,
        frame: FrameInfo,
    ) {
        let device = &gpu.device;
        if self.scene_objects.is_none() {
            let mut targets: Vec<Option<wgpu::ColorTargetState>> =
                GBUFFER.iter().map(|_| Some(GBUF_FORMAT.into())).collect();
            if self.rate.is_some() {
                targets.push(Some(MOTION_FORMAT.into()));
            }
            let fs = if self.rate.is_some() {
                "fs_gbuffer_motion"
            } else {
                "fs_gbuffer"
            };
            let pipeline = scene.custom_pipeline(
                device,
                "gbuffer",
                &self.module,
                ("vs_gbuffer", fs),
                &targets,
            );
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("shade scene"),
                layout: &self.shade_pipeline.get_bind_group_layout(0),
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: scene.frame_binding(0),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: scene.objects_binding(),
                    },
                ],
            });
            self.scene_objects = Some((pipeline, group));
        }
        self.sides.select(frame.index);
        scene.write_view(&gpu.queue, 0, &View::whole(frame.time, frame.prev_time));
        self.gbuffer_pass(encoder, scene, timers);
        let (tw, th) = model::tiles(self.width, self.height);
        if let Some(r) = &self.rate {
            self.last = Some(r.record(
                gpu,
                scene,
                timers,
                encoder,
                self.sides.side(),
                frame.history_valid,
                self.width,
                self.height,
            ));
        }
        encoder.clear_buffer(&self.counters, 0, None);
        let (_, scene_group) = self.scene_objects.as_ref().expect("made above");
        timed_dispatch(
            encoder,
            timers,
            "shade",
            &self.shade_pipeline,
            &[scene_group, &self.sides.current().shade_group],
            [tw, th],
        );
    }

    fn frame_extras(&mut self, gpu: &Gpu, frame: &Rgb8Image, image: bool) -> FrameExtras {
        let [shades, covered] = self.counters(gpu);
        let mut extras = FrameExtras::default();
        // Shades over native's (one per covered pixel); 1 where nothing is drawn.
        let rate = if covered > 0 {
            shades as f64 / covered as f64
        } else {
            1.0
        };
        extras
            .values
            .push(FrameValue::lower("shading-rate", rate, ""));
        if image {
            if let Some(codes) = self.rates(gpu) {
                extras.images.push(("rate", rate_image(frame, &codes)));
            }
        }
        extras
    }
}

/// The frame in grey with each tile tinted by its shading-region size, as the paper's Fig. 1 (c).
pub fn rate_image(frame: &Rgb8Image, codes: &[u32]) -> Rgb8Image {
    let mut img = frame.clone();
    let (tw, _) = model::tiles(img.width, img.height);
    for y in 0..img.height {
        for x in 0..img.width {
            let i = ((y * img.width + x) * 3) as usize;
            let px = &mut img.data[i..i + 3];
            let grey = (0.299 * px[0] as f32 + 0.587 * px[1] as f32 + 0.114 * px[2] as f32) as u8;
            let code = codes
                .get(((y / TILE) * tw + x / TILE) as usize)
                .copied()
                .unwrap_or(0);
            let tint = model::rate_color(code);
            for c in 0..3 {
                px[c] = match tint {
                    Some(t) => ((grey as u16 + t[c] as u16) / 2) as u8,
                    None => grey,
                };
            }
        }
    }
    img
}

#[cfg(test)]
mod tests {
    use super::*;
    use model::encode;
    use tessera_metrics::{encode_srgb8, HdrImage};

    #[test]
    fn rate_image_tints_coarse_tiles_only() {
        // Two tiles side by side, mid grey: 1x1 stays grey, 2x2 is tinted green (Fig. 1's code).
        let frame = encode_srgb8(&HdrImage {
            width: 32,
            height: 16,
            data: vec![0.2; 32 * 16 * 3],
        });
        let img = rate_image(&frame, &[encode(1, 1), encode(2, 2)]);
        let px = |x: usize| &img.data[x * 3..x * 3 + 3];
        assert!(px(3)[0] == px(3)[1] && px(3)[1] == px(3)[2], "{:?}", px(3));
        assert!(
            px(20)[1] > px(20)[0] && px(20)[1] > px(20)[2],
            "{:?}",
            px(20)
        );
    }
}
