//! The hardware path of `adaptive-shading` (`vrs = "hardware"`) and `native-vrs`: NVIDIA's rates
//! driving VK_KHR_fragment_shading_rate, as in the paper (Yang et al. 2019, section 5), beside the
//! software path of `gpu.rs`.
//!
//! Each frame of `adaptive-shading`, in the paper's order of work (section 5: the rate pass runs
//! right after the depth pre-pass, with this frame's motion, and the frame is shaded at the rates
//! it computes): `motion_prepass` (raw Vulkan, `raw_pass.rs`) clears and draws this frame's depth
//! and writes its motion (the software G-buffer's motion); `rates` reprojects the previous output
//! by that motion, with depth rejection against the previous depth (the same rate shader as the
//! software path, `rate.wgsl`); `rate_attachment` applies section 5.4's neighbour filter to the
//! per-tile codes and turns them into attachment texels (`attachment.wgsl`, CPU model in
//! `attachment.rs`), storing the filtered codes as `rates`;
//! `scene_vrs` clears the colour and shades, `fs_main`'s shading, at those rates (depth test
//! EQUAL against the pre-pass). `native-vrs` is one raw render pass with a constant attachment
//! (every tile 1x1, 2x2 or 4x4): colour and depth cleared, a depth-only pre-pass, the same shading
//! draw; it needs no motion, as `native` has none. No pass only clears: the clears are the render
//! passes' load ops, as in `native`'s forward pass.
//!
//! Textured materials (glTF files, the city) are drawn in the same raw passes after the untextured
//! objects (`raw_material.rs`, `vrs_material.wgsl`): opaque and alpha-tested draws in the pre-pass
//! (the alpha test there, at full rate) and in the shading pass (EQUAL), blended draws last in the
//! shading pass, sorted back to front as `native` sorts them, depth test without writes, at the
//! attachment's rates. Their textures are moved into RESOURCE (SHADER_READ_ONLY_OPTIMAL) before
//! each raw pass, with the targets. Blended draws shade over opaque surfaces, so on a scene with
//! them `invocations-over-model` is above 1 by their invocations.
//!
//! Timing: each raw pass is timed by wgpu-profiler timestamps written at the end of the encoder
//! before it and at the start of the one submitted right after it, in the same submission; their
//! fragment-shader invocations come from the raw passes' own pipeline-statistics queries
//! (`self_counted` passes of the plan, reported by [`Renderer::own_statistics`]).

use std::collections::{BTreeMap, HashMap};

use tessera_metrics::Rgb8Image;

use super::attachment::{self as att, Attachment};
use super::gpu::{
    LastFrame, RatePass, COLORS, DEPTHS, MOTION_FORMAT, RATE_FORMAT, STATES, STATE_FORMAT,
};
use super::model::{self, RateParams};
use super::raw_pass::{RawVrsPass, Shaders, Targets};
use crate::gpu::vrs::VrsCaps;
use crate::gpu::Gpu;
use crate::render::graph::{Graph, PassKind, Plan, TextureDesc};
use crate::render::kit::{allocate, bind_group, compute_pipeline, timed_dispatch, PingPong};
use crate::render::readback::read_texture_raw;
use crate::render::renderer::{FrameExtras, FrameInfo, FrameValue, Renderer};
use crate::render::scene::{SceneGpu, COLOR_FORMAT, DEPTH_FORMAT};
use crate::render::timers::Timers;

pub static VRS_WGSL: &str = include_str!("vrs.wgsl");
pub static VRS_MATERIAL_WGSL: &str = include_str!("vrs_material.wgsl");
pub static ATTACHMENT_WGSL: &str = include_str!("attachment.wgsl");

/// The attachment pass's module: `attachment.wgsl` and section 5.4's filter.
pub fn attachment_source() -> String {
    format!("{ATTACHMENT_WGSL}\n{}", super::gpu::RATE_FILTER_WGSL)
}

/// `scene.wgsl` with the hardware path's forward entry points appended.
pub fn vrs_source() -> String {
    format!("{}\n{VRS_WGSL}", crate::render::scene::SCENE_WGSL)
}

/// `scene.wgsl` + `material.wgsl` with the hardware path's entry points for textured draws
/// appended (`vrs_material.wgsl`).
pub fn vrs_material_source() -> String {
    format!(
        "{}\n{VRS_MATERIAL_WGSL}",
        crate::render::material::material_wgsl()
    )
}

/// The pass drawn with variable-rate shading (timed and counted like every pass).
pub const SCENE_PASS: &str = "scene_vrs";
/// `adaptive-shading`'s depth pre-pass writing this frame's motion, before the rate pass.
pub const PREPASS: &str = "motion_prepass";

/// What decides the rates of the hardware path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Rates {
    /// NVIDIA's rate selection from the previous frame (`adaptive-shading`).
    Adaptive(RateParams),
    /// Every tile at `rx` x `ry` (`native-vrs`; 1x1 is the full-rate baseline).
    Fixed(u32, u32),
}

/// The attachment's texel size on an adapter (16x16 where offered).
pub fn texel_of(caps: &VrsCaps) -> [u32; 2] {
    att::texel_size(caps.texel_min, caps.texel_max)
}

/// The pass graph at `width` x `height` with attachment texels of `texel` pixels (no GPU needed).
pub fn graph(rates: &Rates, width: u32, height: u32, texel: [u32; 2]) -> Plan {
    let tex = |format, width, height| TextureDesc {
        format,
        width,
        height,
        samples: 1,
        layers: 1,
    };
    let (tw, th) = model::tiles(width, height);
    let (aw, ah) = att::attachment_size(width, height, texel);
    let mut g = Graph::default();
    // The attachment: an R8_UINT image made by raw_pass.rs (wgpu cannot give it the usage).
    g.resource("attachment", tex(wgpu::TextureFormat::R8Uint, aw, ah));
    match rates {
        Rates::Adaptive(_) => {
            g.resource("motion", tex(MOTION_FORMAT, width, height));
            for i in 0..2 {
                g.resource(COLORS[i], tex(COLOR_FORMAT, width, height))
                    .resource(DEPTHS[i], tex(DEPTH_FORMAT, width, height))
                    .resource(STATES[i], tex(STATE_FORMAT, tw, th));
            }
            g.resource("rates", tex(RATE_FORMAT, tw, th))
                .resource("rates_raw", tex(RATE_FORMAT, tw, th));
            g.pass(
                PREPASS,
                PassKind::Render,
                &[],
                &["motion", DEPTHS[0], DEPTHS[1]],
            )
            .self_counted();
            let reads = [
                COLORS[0], COLORS[1], "motion", DEPTHS[0], DEPTHS[1], STATES[0], STATES[1],
            ];
            g.pass(
                "rates",
                PassKind::Compute,
                &reads,
                &["rates_raw", STATES[0], STATES[1]],
            );
            // Section 5.4's filter (where it is on) is applied by the attachment pass as it reads
            // the codes, which it stores as `rates`: one dispatch less than the software path.
            g.pass(
                "rate_attachment",
                PassKind::Compute,
                &["rates_raw"],
                &["attachment", "rates"],
            );
            g.pass(
                SCENE_PASS,
                PassKind::Render,
                &["attachment", DEPTHS[0], DEPTHS[1]],
                &[COLORS[0], COLORS[1]],
            )
            .self_counted();
            g.output(COLORS[0]).output(COLORS[1]);
        }
        Rates::Fixed(..) => {
            g.resource(COLORS[0], tex(COLOR_FORMAT, width, height))
                .resource(DEPTHS[0], tex(DEPTH_FORMAT, width, height));
            g.pass(
                SCENE_PASS,
                PassKind::Render,
                &["attachment"],
                &[COLORS[0], DEPTHS[0]],
            )
            .self_counted();
            g.output(COLORS[0]);
        }
    }
    g.plan().expect("built-in graphs are well formed")
}

/// The rate-to-attachment compute pass.
struct AttachmentPass {
    pipeline: wgpu::ComputePipeline,
    group: wgpu::BindGroup,
    /// Threads: one per four attachment texels and one per tile, whichever are more.
    threads: u32,
}

pub struct HardwareGpu {
    plan: Plan,
    textures: HashMap<&'static str, wgpu::Texture>,
    width: u32,
    height: u32,
    rates: Rates,
    texel: [u32; 2],
    table: [u8; 16],
    attachment_size: [u32; 2],
    rate: Option<RatePass>,
    attachment_pass: Option<AttachmentPass>,
    /// The attachment's bytes, tightly packed, copied into the raw image each frame.
    staging: wgpu::Buffer,
    staging_readback: wgpu::Buffer,
    /// Built with the renderer, from the scene in the build context (a failure is the build's
    /// error, before any frame is rendered); `None` only while [`HardwareGpu::new`] runs.
    raw: Option<RawVrsPass>,
    /// Whether the shading pass has the rate attachment (see [`HardwareGpu::without_rates`]).
    rated: bool,
    parities: usize,
    /// The side (colour and depth target pair, raw-pass targets) frame `i` writes: the kit's
    /// ping-pong of the two sides when the rates read the previous frame, one side otherwise
    /// (`native-vrs`: both entries 0).
    sides: PingPong<usize>,
    last: Option<LastFrame>,
}

impl HardwareGpu {
    /// The hardware path on `gpu` drawing `scene`, with its raw Vulkan pass built (why not, in
    /// words, when that fails on an adapter that offers the extension: a driver problem or a bug,
    /// found before any frame is rendered).
    pub fn new(
        gpu: &Gpu,
        caps: &VrsCaps,
        rates: Rates,
        scene: &SceneGpu,
        width: u32,
        height: u32,
    ) -> Result<HardwareGpu, String> {
        HardwareGpu::build(gpu, Some(caps), rates, scene, width, height)
    }

    /// The same passes on any Vulkan adapter, without the extension: the shading pass has no
    /// rate attachment (every pixel shaded once, whatever `rates` computes), so the raw Vulkan
    /// drawing (pre-passes, the textured draws, the targets' states) is tested where hardware
    /// VRS is missing (lavapipe; `tests/vrs.rs`). Not a technique's renderer.
    pub fn without_rates(
        gpu: &Gpu,
        rates: Rates,
        scene: &SceneGpu,
        width: u32,
        height: u32,
    ) -> Result<HardwareGpu, String> {
        HardwareGpu::build(gpu, None, rates, scene, width, height)
    }

    fn build(
        gpu: &Gpu,
        caps: Option<&VrsCaps>,
        rates: Rates,
        scene: &SceneGpu,
        width: u32,
        height: u32,
    ) -> Result<HardwareGpu, String> {
        let device = &gpu.device;
        let texel = caps.map_or([model::TILE, model::TILE], texel_of);
        let table = att::code_table(caps.map_or(&[[1, 1]][..], |c| &c.fragment_sizes));
        let plan = graph(&rates, width, height, texel);
        let mut wgpu_plan = plan.clone();
        wgpu_plan.resources.retain(|r| r.name != "attachment");
        let textures = allocate(device, &wgpu_plan);
        let (aw, ah) = att::attachment_size(width, height, texel);
        let words = (aw * ah).div_ceil(4);
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("rate attachment bytes"),
            size: words as u64 * 4,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let staging_readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("rate attachment readback"),
            size: words as u64 * 4,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let view = |name: &str| textures[name].create_view(&Default::default());
        let (rate, attachment_pass, parities) = match rates {
            Rates::Adaptive(p) => {
                let rate = RatePass::new(gpu, p, false, &view);
                let pipeline =
                    compute_pipeline(device, "rate_attachment", &attachment_source(), "main");
                use wgpu::util::DeviceExt;
                let (tw, th) = model::tiles(width, height);
                let filter = u32::from(p.neighbour_filter);
                let mut u: Vec<u32> = vec![tw, th, aw, ah, texel[0], texel[1], filter, 0];
                u.extend(table.iter().map(|&t| t as u32));
                let uniforms = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("rate attachment params"),
                    contents: bytemuck::cast_slice(&u),
                    usage: wgpu::BufferUsages::UNIFORM,
                });
                let group = bind_group(
                    device,
                    "rate_attachment",
                    &pipeline.get_bind_group_layout(0),
                    &[(0, &uniforms), (2, &staging)],
                    &[(1, &view("rates_raw")), (3, &view("rates"))],
                );
                (
                    Some(rate),
                    Some(AttachmentPass {
                        pipeline,
                        group,
                        threads: words.max(tw * th),
                    }),
                    2,
                )
            }
            Rates::Fixed(rx, ry) => {
                let a = att::uniform(width, height, texel, rx, ry, &table);
                gpu.queue.write_buffer(&staging, 0, &padded(&a.data));
                (None, None, 1)
            }
        };
        let mut hw = HardwareGpu {
            plan,
            textures,
            width,
            height,
            rates,
            texel,
            table,
            attachment_size: [aw, ah],
            rate,
            attachment_pass,
            staging,
            staging_readback,
            raw: None,
            rated: caps.is_some(),
            parities,
            sides: PingPong::new([0, parities - 1]),
            last: None,
        };
        hw.initialise(gpu);
        hw.raw = Some(
            hw.make_raw(gpu, scene)
                .map_err(|e| format!("the hardware VRS pass could not be built: {e}"))?,
        );
        Ok(hw)
    }

    pub fn last_frame(&self) -> Option<LastFrame> {
        self.last
    }

    /// A texture of the plan by resource name (`motion`, `rates`, `color0`, ...).
    pub fn texture(&self, name: &str) -> Option<&wgpu::Texture> {
        self.textures.get(name)
    }

    /// The rate codes of the last frame's tiles (after the filter); `None` for fixed rates.
    pub fn rates(&self, gpu: &Gpu) -> Option<Vec<u32>> {
        let t = self.textures.get("rates")?;
        Some(bytemuck::cast_slice(&read_texture_raw(gpu, t)).to_vec())
    }

    /// The attachment the last frame was drawn with, as the GPU filled it.
    pub fn attachment(&self, gpu: &Gpu) -> Attachment {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(
            &self.staging,
            0,
            &self.staging_readback,
            0,
            self.staging.size(),
        );
        gpu.queue.submit([encoder.finish()]);
        let slice = self.staging_readback.slice(..);
        slice.map_async(wgpu::MapMode::Read, |_| {});
        let _ = gpu.device.poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: None,
        });
        let [aw, ah] = self.attachment_size;
        let data = match slice.get_mapped_range() {
            Ok(d) => d[..(aw * ah) as usize].to_vec(),
            Err(_) => vec![0; (aw * ah) as usize],
        };
        self.staging_readback.unmap();
        Attachment {
            width: aw,
            height: ah,
            texel: self.texel,
            data,
        }
    }

    /// What the CPU model makes of rate codes: the attachment (per-tile codes through the
    /// adapter's mapping).
    pub fn model_attachment(&self, codes: &[u32]) -> Attachment {
        let (tw, th) = model::tiles(self.width, self.height);
        match self.rates {
            Rates::Adaptive(_) => att::attachment(
                codes,
                tw,
                th,
                self.width,
                self.height,
                self.texel,
                &self.table,
            ),
            Rates::Fixed(rx, ry) => {
                att::uniform(self.width, self.height, self.texel, rx, ry, &self.table)
            }
        }
    }

    /// Covered pixels of the last frame (its depth is not the clear value, 0).
    pub fn coverage(&self, gpu: &Gpu) -> Vec<bool> {
        let raw = read_texture_raw(gpu, &self.textures[DEPTHS[*self.sides.current()]]);
        let depth: &[f32] = bytemuck::cast_slice(&raw);
        depth.iter().map(|&d| d > 0.0).collect()
    }

    /// Fragment-shader invocations of the last frame's `scene_vrs` pass (frame completed).
    pub fn invocations(&self) -> Option<u64> {
        self.raw.as_ref()?.invocations().0
    }

    fn make_raw(&mut self, gpu: &Gpu, scene: &SceneGpu) -> Result<RawVrsPass, String> {
        let source = vrs_source();
        let adaptive = matches!(self.rates, Rates::Adaptive(_));
        let materials = scene.materials().map(|m| m.raw());
        let material_source = materials.as_ref().map(|_| vrs_material_source());
        let targets: Vec<Targets> = (0..self.parities)
            .map(|p| Targets {
                color: &self.textures[COLORS[p]],
                depth: &self.textures[DEPTHS[p]],
                motion: adaptive.then(|| &self.textures["motion"]),
            })
            .collect();
        RawVrsPass::new(
            &gpu.device,
            &gpu.adapter,
            &Shaders {
                wgsl: &source,
                vertex: "vs_vrs",
                fragment: "fs_vrs",
                motion_fragment: adaptive.then_some("fs_vrs_motion"),
                material: material_source.as_deref(),
            },
            &targets,
            [self.width, self.height],
            self.rated.then_some(self.texel),
            self.attachment_size,
            &self.staging,
            &scene.raw_draw(0),
            materials.as_ref(),
        )
    }

    /// Clears every target once in wgpu, when the renderer is built: wgpu then counts them as
    /// initialised and never clears them lazily before a read (which would wipe what the raw
    /// passes wrote, unseen by wgpu), and tracks them in the attachment states the raw passes
    /// begin and end in.
    fn initialise(&self, gpu: &Gpu) {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        for p in 0..self.parities {
            let color = self.textures[COLORS[p]].create_view(&Default::default());
            let depth = self.textures[DEPTHS[p]].create_view(&Default::default());
            let motion = self
                .textures
                .get("motion")
                .filter(|_| p == 0)
                .map(|t| t.create_view(&Default::default()));
            let target = |view| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })
            };
            let mut colors = vec![target(&color)];
            if let Some(m) = &motion {
                colors.push(target(m));
            }
            encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("initialise vrs targets"),
                color_attachments: &colors,
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(0.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
        }
        gpu.queue.submit([encoder.finish()]);
    }

    /// Moves this frame's `color` (if asked), `motion` (if asked and present) and depth into
    /// the states the raw render passes begin and end in (COLOR_TARGET, DEPTH_STENCIL_WRITE),
    /// and the textured draws' textures into RESOURCE (SHADER_READ_ONLY_OPTIMAL).
    fn transition(&self, encoder: &mut wgpu::CommandEncoder, color: bool, motion: bool) {
        let state = |texture, state| wgpu::TextureTransition {
            texture,
            selector: None,
            state,
        };
        let mut t = vec![state(
            &self.textures[DEPTHS[*self.sides.current()]],
            wgpu::TextureUses::DEPTH_STENCIL_WRITE,
        )];
        if color {
            t.push(state(
                &self.textures[COLORS[*self.sides.current()]],
                wgpu::TextureUses::COLOR_TARGET,
            ));
        }
        if let Some(m) = self.textures.get("motion").filter(|_| motion) {
            t.push(state(m, wgpu::TextureUses::COLOR_TARGET));
        }
        encoder.transition_resources(std::iter::empty(), t.into_iter());
        // The textured draws' textures into the state their raw descriptors say.
        if let Some(raw) = &self.raw {
            raw.transition_materials(encoder);
        }
    }
}

/// `bytes` padded with zeros to a multiple of 4 (buffer writes).
fn padded(bytes: &[u8]) -> Vec<u8> {
    let mut v = bytes.to_vec();
    v.resize(bytes.len().div_ceil(4) * 4, 0);
    v
}

impl Renderer for HardwareGpu {
    fn plan(&self) -> &Plan {
        &self.plan
    }

    fn output(&self) -> &wgpu::Texture {
        &self.textures[COLORS[*self.sides.current()]]
    }

    fn record(
        &mut self,
        gpu: &Gpu,
        scene: &mut SceneGpu,
        timers: &Timers,
        encoder: &mut wgpu::CommandEncoder,
        frame: FrameInfo,
    ) {
        self.sides.select(frame.index);
        let side = *self.sides.current();
        scene.write_view(
            &gpu.queue,
            0,
            &crate::render::scene::View::whole(frame.time, frame.prev_time),
        );
        let c = scene.clear_color();
        let background = [c.r as f32, c.g as f32, c.b as f32, c.a as f32];
        // wgpu forbids raw and wgpu commands in one encoder: what was recorded so far, each raw
        // pass between the wgpu work around it, and the closing timestamp go out in one
        // submission, in order; the caller's encoder is replaced by a fresh one for what follows
        // (query resolution).
        let device = &gpu.device;
        let fresh = || device.create_command_encoder(&Default::default());
        let mut submit = Vec::new();
        let mut wgpu_work = std::mem::replace(encoder, fresh());
        // This frame's order of the textured draws (blended ones sorted back to front).
        let order = scene
            .materials()
            .map(|m| m.draw_order())
            .unwrap_or_default();
        if let (Some(r), Some(a)) = (&self.rate, &self.attachment_pass) {
            // 1. This frame's depth and motion (alpha-tested draws sample their textures).
            self.transition(&mut wgpu_work, false, true);
            let q = timers.begin_encoder(PREPASS, &mut wgpu_work);
            submit.push(std::mem::replace(&mut wgpu_work, fresh()).finish());
            let mut raw = fresh();
            if let Some(raw_pass) = self.raw.as_mut() {
                raw_pass.record_prepass(&mut raw, side, &order);
            }
            submit.push(raw.finish());
            timers.end(&mut wgpu_work, q);
            // 2. The rates from the previous output reprojected by that motion.
            self.last = Some(r.record(
                gpu,
                scene,
                timers,
                &mut wgpu_work,
                side,
                frame.history_valid,
                self.width,
                self.height,
            ));
            timed_dispatch(
                &mut wgpu_work,
                timers,
                "rate_attachment",
                &a.pipeline,
                &[&a.group],
                [a.threads.div_ceil(64), 1],
            );
        }
        // 3. The frame shaded at the rates.
        self.transition(&mut wgpu_work, true, false);
        let q = timers.begin_encoder(SCENE_PASS, &mut wgpu_work);
        submit.push(wgpu_work.finish());
        let mut raw = fresh();
        if let Some(raw_pass) = self.raw.as_mut() {
            raw_pass.record_shade(&mut raw, side, background, &order);
        }
        submit.push(raw.finish());
        let mut after = fresh();
        timers.end(&mut after, q);
        submit.push(after.finish());
        gpu.queue.submit(submit);
    }

    fn own_statistics(&mut self, _gpu: &Gpu) -> BTreeMap<String, u64> {
        let Some(raw) = self.raw.as_ref() else {
            return BTreeMap::new();
        };
        let (shade, prepass) = raw.invocations();
        let mut out = BTreeMap::new();
        if let Some(n) = shade {
            out.insert(SCENE_PASS.to_string(), n);
        }
        if let Some(n) = prepass {
            out.insert(PREPASS.to_string(), n);
        }
        out
    }

    fn frame_extras(&mut self, gpu: &Gpu, frame: &Rgb8Image, image: bool) -> FrameExtras {
        let mut extras = FrameExtras::default();
        let (w, h) = (self.width, self.height);
        let coverage = self.coverage(gpu);
        let covered = coverage.iter().filter(|&&c| c).count() as u64;
        let codes = self.rates(gpu);
        // The model's attachment from the rate pass's own codes through the CPU model of the
        // filter the attachment pass applies (section 5.4), so that the check below covers both.
        let model_codes = match (self.rates, self.textures.get("rates_raw")) {
            (Rates::Adaptive(p), Some(raw)) if p.neighbour_filter => {
                let raw: Vec<u32> = bytemuck::cast_slice(&read_texture_raw(gpu, raw)).to_vec();
                let (tw, th) = model::tiles(w, h);
                Some(model::neighbour_filter(&raw, tw, th))
            }
            _ => codes.clone(),
        };
        let model = self.model_attachment(model_codes.as_deref().unwrap_or(&[]));
        let shades = att::shades(&model, w, h, &|x, y| coverage[(y * w + x) as usize]);
        // The CPU model's shades over covered pixels, as the software path reports its rate.
        let rate = att::rate(shades, covered);
        extras
            .values
            .push(FrameValue::lower("shading-rate", rate, ""));
        let model_shades = FrameValue::lower("model-shades", shades as f64, "count");
        extras.values.push(model_shades);
        // The pass's own invocations are its `pass.scene_vrs.fragment_invocations` (counted like
        // any pass's, through `Renderer::own_statistics`); their ratio to the model is this check.
        if let Some(n) = self.invocations() {
            let ratio = n as f64 / shades.max(1) as f64;
            extras
                .values
                .push(FrameValue::neither("invocations-over-model", ratio, "x"));
        }
        // The attachment the GPU used against the model's from the same rate-pass codes.
        let gpu_attachment = self.attachment(gpu);
        let differ = gpu_attachment
            .data
            .iter()
            .zip(&model.data)
            .filter(|(a, b)| a != b)
            .count();
        let differ = differ as f64;
        extras.values.push(FrameValue::lower(
            "attachment-texels-differing",
            differ,
            "count",
        ));
        if image {
            if let Some(codes) = codes {
                extras
                    .images
                    .push(("rate", super::gpu::rate_image(frame, &codes)));
            }
        }
        extras
    }
}
