//! ColorVideoVDP on the GPU: the model of the `colorvideovdp` crate 0.1.1 (display model, DKL,
//! temporal channels over the frame history, Laplacian pyramid, castleCSF, cross-channel masking,
//! pooling to JOD) as WGSL compute passes, with per-frame JOD, the transient channel and the
//! distortion maps of chosen frames.
//!
//! For: `GpuMetrics::cvvdp` ([`evaluate`]), the same call and result as `tessera_metrics::cvvdp` (which stays
//! the reference and the fallback); everything around a shot's prediction (checks, camera cuts,
//! per-frame pooling) is tessera-metrics' own, through its `ShotPredictor` seam. Not for: PQ,
//! HLG or gamma-encoded input (the harness has 8-bit sRGB and linear frames), or the reference's
//! symmetric temporal padding (the harness uses the default, replicate).
//!
//! Precision: f32 on the device, every step in the CPU's operation order; per-pixel powers and
//! logarithms use the device's `pow`/`exp2`/`log2` (a few ulp from the CPU's libm). Spatial
//! pooling sums f32 per 16x16 workgroup in a fixed tree and the workgroups in f64 on the CPU in
//! order (the CPU sums every pixel in f64), so a value is bitwise repeatable on one adapter.
//! `tests/cvvdp_cross_check.rs` measures the agreement (well inside 0.001 JOD).

mod model;
mod plan;

use tessera_metrics::{
    CvvdpResult, CvvdpSettings, Frames, MetricsError, Shot, ShotPrediction, ShotPredictor,
};

use crate::error::GpuMetricsError;
use crate::plumbing::read_buffer;
use crate::shaders::pipeline;
use model::{safe_pow, Decode, Model};
use plan::{Plan, PlanKey};

const COMMON: &str = include_str!("../../shaders/cvvdp/common.wgsl");
const CSF: &str = include_str!("../../shaders/cvvdp/csf.wgsl");
const INPUT: &str = include_str!("../../shaders/cvvdp/input.wgsl");
const INPUT_LDR: &str = include_str!("../../shaders/cvvdp/input_ldr.wgsl");
const INPUT_HDR: &str = include_str!("../../shaders/cvvdp/input_hdr.wgsl");
const REDUCE: &str = include_str!("../../shaders/cvvdp/reduce.wgsl");
const EXPAND: &str = include_str!("../../shaders/cvvdp/expand.wgsl");
const CHANNEL: &str = include_str!("../../shaders/cvvdp/channel.wgsl");
const BLUR: &str = include_str!("../../shaders/cvvdp/blur.wgsl");
const DIFF: &str = include_str!("../../shaders/cvvdp/diff.wgsl");
const BASE_MEAN: &str = include_str!("../../shaders/cvvdp/base_mean.wgsl");
const BASE_CHANNEL: &str = include_str!("../../shaders/cvvdp/base_channel.wgsl");
const MAP_BAND: &str = include_str!("../../shaders/cvvdp/map_band.wgsl");
const MAP_JOD: &str = include_str!("../../shaders/cvvdp/map_jod.wgsl");

/// Every pass's full source (the shared functions prepended), by label.
pub(crate) fn sources() -> Vec<(&'static str, String)> {
    let with = |parts: &[&str]| parts.join("\n");
    vec![
        ("cvvdp input ldr", with(&[COMMON, INPUT_LDR, INPUT])),
        ("cvvdp input hdr", with(&[COMMON, INPUT_HDR, INPUT])),
        ("cvvdp reduce", with(&[COMMON, REDUCE])),
        ("cvvdp expand", with(&[COMMON, EXPAND])),
        ("cvvdp channel", with(&[COMMON, CSF, CHANNEL])),
        ("cvvdp blur", with(&[COMMON, BLUR])),
        ("cvvdp diff", with(&[COMMON, DIFF])),
        ("cvvdp base mean", with(&[COMMON, BASE_MEAN])),
        ("cvvdp base channel", with(&[COMMON, CSF, BASE_CHANNEL])),
        ("cvvdp map band", with(&[COMMON, MAP_BAND])),
        ("cvvdp map jod", with(&[COMMON, MAP_JOD])),
    ]
}

/// The ColorVideoVDP pipelines, made on first use.
pub(crate) struct CvvdpPipelines {
    pub input_ldr: wgpu::ComputePipeline,
    pub input_hdr: wgpu::ComputePipeline,
    pub reduce: wgpu::ComputePipeline,
    pub expand: wgpu::ComputePipeline,
    pub channel: wgpu::ComputePipeline,
    pub blur: wgpu::ComputePipeline,
    pub diff: wgpu::ComputePipeline,
    pub base_mean: wgpu::ComputePipeline,
    pub base_channel: wgpu::ComputePipeline,
    pub map_band: wgpu::ComputePipeline,
    pub map_jod: wgpu::ComputePipeline,
}

impl CvvdpPipelines {
    fn new(device: &wgpu::Device) -> CvvdpPipelines {
        let s = sources();
        let p = |i: usize| pipeline(device, s[i].0, &s[i].1);
        CvvdpPipelines {
            input_ldr: p(0),
            input_hdr: p(1),
            reduce: p(2),
            expand: p(3),
            channel: p(4),
            blur: p(5),
            diff: p(6),
            base_mean: p(7),
            base_channel: p(8),
            map_band: p(9),
            map_jod: p(10),
        }
    }
}

/// What `GpuMetrics` keeps for ColorVideoVDP between calls: pipelines, calibration, the last
/// plan (a run evaluates every variant at one size and display, so it is reused).
pub(crate) struct CvvdpState {
    pipelines: CvvdpPipelines,
    model: Model,
    plan: Option<Plan>,
    /// GPU ms of each frame of the last call (timestamps; empty without them).
    frame_ms: Vec<f64>,
}

/// Frames whose partials are read back together.
const BATCH: usize = 16;

/// ColorVideoVDP of `test` against `reference` on `device`, keeping pipelines, calibration and
/// the last plan in `state` (made on the first call): the same checks, shots, per-frame values
/// and maps as `tessera_metrics::cvvdp`, with each shot's pyramid, masking and spatial pooling
/// computed by compute passes.
///
/// `GpuMetricsError::Unsupported` when the device cannot hold the work (a plane beyond its
/// binding limit, more temporal taps than the frame ring holds): use the CPU.
pub(crate) fn evaluate(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    state: &mut Option<Box<CvvdpState>>,
    reference: Frames<'_>,
    test: Frames<'_>,
    settings: &CvvdpSettings,
) -> Result<CvvdpResult, GpuMetricsError> {
    if let Some(s) = state {
        s.frame_ms.clear();
    }
    let mut predictor = Predictor {
        device,
        queue,
        state,
    };
    tessera_metrics::cvvdp_with(reference, test, settings, &mut predictor)
}

impl CvvdpState {
    /// GPU ms of each frame of the last call, from timestamps around each frame's passes; empty
    /// without `TIMESTAMP_QUERY`.
    pub fn frame_ms(&self) -> &[f64] {
        &self.frame_ms
    }
}

struct Predictor<'a> {
    device: &'a wgpu::Device,
    queue: &'a wgpu::Queue,
    state: &'a mut Option<Box<CvvdpState>>,
}

/// Frame `i` as the ring's texels: packed 8-bit pixels, or RGBA floats; converted in row bands on
/// the machine's cores (a 4K frame is 8.3 million pixels, converted twice per frame pair).
fn texels(frames: &Frames<'_>, i: usize) -> Texels {
    match frames {
        Frames::Srgb(f) => {
            let image = &f[i];
            let mut out = vec![0u32; image.data.len() / 3];
            in_bands(&image.data, 3, &mut out, 1, |src, dst| {
                for (p, d) in src.chunks_exact(3).zip(dst) {
                    *d = p[0] as u32 | (p[1] as u32) << 8 | (p[2] as u32) << 16;
                }
            });
            Texels::Packed(out)
        }
        Frames::Linear { frames, .. } => {
            let image = &frames[i];
            let mut out = vec![0f32; image.data.len() / 3 * 4];
            in_bands(&image.data, 3, &mut out, 4, |src, dst| {
                for (p, d) in src.chunks_exact(3).zip(dst.chunks_exact_mut(4)) {
                    d.copy_from_slice(&[p[0], p[1], p[2], 0.0]);
                }
            });
            Texels::Floats(out)
        }
    }
}

/// A frame's texels as the ring takes them.
enum Texels {
    Packed(Vec<u32>),
    Floats(Vec<f32>),
}

impl Texels {
    fn bytes(&self) -> &[u8] {
        match self {
            Texels::Packed(v) => bytemuck::cast_slice(v),
            Texels::Floats(v) => bytemuck::cast_slice(v),
        }
    }
}

/// `f(source band, destination band)` over pixel bands of `src` (`src_px` values a pixel) and
/// `dst` (`dst_px` values a pixel), one band per core.
fn in_bands<S: Sync, D: Send>(
    src: &[S],
    src_px: usize,
    dst: &mut [D],
    dst_px: usize,
    f: impl Fn(&[S], &mut [D]) + Sync,
) {
    let pixels = dst.len() / dst_px;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let band = pixels.div_ceil(threads.max(1)).max(1 << 16);
    std::thread::scope(|scope| {
        for (s, d) in src.chunks(band * src_px).zip(dst.chunks_mut(band * dst_px)) {
            let f = &f;
            scope.spawn(move || f(s, d));
        }
    });
}

fn size(frames: &Frames<'_>) -> (u32, u32) {
    match frames {
        Frames::Srgb(f) => (f[0].width, f[0].height),
        Frames::Linear { frames, .. } => (frames[0].width, frames[0].height),
    }
}

impl ShotPredictor for Predictor<'_> {
    type Error = GpuMetricsError;

    /// One shot, inside error scopes: a device that runs out of memory or refuses the work makes
    /// the shot `Unsupported` (the caller falls back to the CPU) instead of a panic.
    fn predict(&mut self, shot: &Shot<'_>) -> Result<ShotPrediction, GpuMetricsError> {
        let device = self.device.clone();
        let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let result = self.predict_on_device(shot);
        let errors = [
            pollster::block_on(validation.pop()),
            pollster::block_on(oom.pop()),
        ];
        if let Some(e) = errors.into_iter().flatten().next() {
            if let Some(s) = self.state.as_mut() {
                s.plan = None;
            }
            return Err(unsupported(&format!("the device failed the work: {e}")));
        }
        result
    }
}

impl Predictor<'_> {
    fn predict_on_device(&mut self, shot: &Shot<'_>) -> Result<ShotPrediction, GpuMetricsError> {
        let (device, queue) = (self.device, self.queue);
        if self.state.is_none() {
            *self.state = Some(Box::new(CvvdpState {
                pipelines: CvvdpPipelines::new(device),
                model: Model::load()?,
                plan: None,
                frame_ms: Vec::new(),
            }));
        }
        let timer = device.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        let period_ns = queue.get_timestamp_period() as f64;
        let state = self.state.as_mut().ok_or_else(|| unsupported("no state"))?;
        let (width, height) = size(&shot.test);
        let frames = shot.frames.len();
        let (white, linear) = match shot.test {
            Frames::Linear { white, .. } => (white as f32, true),
            Frames::Srgb(_) => (1.0, false),
        };
        let photo = &shot.model.photometry;
        let ppd = shot.model.geometry.pixels_per_degree();
        let key = PlanKey {
            width,
            height,
            linear,
            video: frames > 1,
            fps: if frames > 1 { shot.fps.to_bits() } else { 0 },
            ppd: ppd.to_bits(),
            photometry: [
                photo.peak_luminance,
                photo.contrast,
                photo.ambient_illuminance,
                photo.reflectivity,
                photo.exposure,
            ]
            .map(f64::to_bits),
            white: white.to_bits(),
        };
        if state.plan.as_ref().is_none_or(|p| p.key != key) {
            state.plan = None;
            state.plan = Some(Plan::new(
                device,
                queue,
                &state.pipelines,
                &state.model,
                key,
                &Decode::new(photo),
                ppd,
                shot.fps,
                white,
            )?);
        }
        let plan = state.plan.as_ref().ok_or_else(|| unsupported("no plan"))?;
        let (channels, bands) = (plan.channels, plan.bands);
        let batch = BATCH.min(frames);
        let frame_bytes = (plan.frame_partials * 4) as u64;
        let stamps_offset = batch as u64 * frame_bytes;
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("cvvdp partials staging"),
            size: stamps_offset + 16 * batch as u64,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let map_staging = (!shot.map_frames.is_empty()).then(|| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("cvvdp map staging"),
                size: width as u64 * height as u64 * 4,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        });
        let queries = timer.then(|| {
            let set = device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("cvvdp timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * batch as u32,
            });
            let resolve = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("cvvdp timestamps resolve"),
                size: 16 * batch as u64,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            (set, resolve)
        });

        let mut quality = vec![0.0_f32; channels * frames * bands];
        let mut maps = Vec::new();
        let beta = state.model.p.beta;
        let mut pending = 0;
        for k in 0..frames {
            let f = shot.frames.start + k;
            let (test, reference) = (texels(&shot.test, f), texels(&shot.reference, f));
            plan.upload_frame(queue, k, test.bytes(), reference.bytes());
            let slot = k % batch;
            let wants_map = shot.map_frames.contains(&f);
            let mut encoder = device.create_command_encoder(&Default::default());
            plan.record_frame(
                &mut encoder,
                wants_map,
                queries.as_ref().map(|(set, _)| (set, 2 * slot as u32)),
            );
            plan.copy_partials(&mut encoder, &staging, slot as u64 * frame_bytes);
            if let (true, Some(ms)) = (wants_map, &map_staging) {
                plan.copy_map(&mut encoder, ms);
            }
            let last_of_batch = slot == batch - 1 || k == frames - 1;
            if let (true, Some((set, resolve))) = (last_of_batch, &queries) {
                let n = slot as u32 + 1;
                encoder.resolve_query_set(set, 0..2 * n, resolve, 0);
                encoder.copy_buffer_to_buffer(resolve, 0, &staging, stamps_offset, 16 * n as u64);
            }
            queue.submit([encoder.finish()]);
            pending += 1;
            if let (true, Some(ms)) = (wants_map, &map_staging) {
                let bytes = read_buffer(device, ms, width as u64 * height as u64 * 4)?;
                maps.push((f, bytemuck::pod_collect_to_vec::<u8, f32>(&bytes)));
            }
            if !last_of_batch {
                continue;
            }
            let bytes = read_buffer(device, &staging, stamps_offset + 16 * pending as u64)?;
            for s in 0..pending {
                let frame = k + 1 - pending + s;
                let partials: Vec<f32> = bytemuck::pod_collect_to_vec(
                    &bytes[s * frame_bytes as usize..(s + 1) * frame_bytes as usize],
                );
                for r in &plan.partials {
                    let sum: f64 = partials[r.offset..r.offset + r.count]
                        .iter()
                        .map(|&x| x as f64)
                        .sum();
                    // plane.rs `norm_in_place`: the mean power, then its root.
                    let q = safe_pow((sum / r.pixels as f64) as f32, 1.0 / beta);
                    quality[(r.channel * frames + frame) * bands + r.band] = q;
                }
            }
            if queries.is_some() {
                let stamps: Vec<u64> =
                    bytemuck::pod_collect_to_vec(&bytes[stamps_offset as usize..][..16 * pending]);
                for s in 0..pending {
                    let ticks = stamps[2 * s + 1].wrapping_sub(stamps[2 * s]);
                    state.frame_ms.push(ticks as f64 * period_ns / 1e6);
                }
            }
            pending = 0;
        }
        if quality.iter().any(|v| !v.is_finite())
            || maps.iter().any(|(_, m)| m.iter().any(|v| !v.is_finite()))
        {
            return Err(MetricsError::Cvvdp {
                reason: "numerical failure (a non-finite value on the GPU)".into(),
            }
            .into());
        }
        Ok(ShotPrediction {
            jod: None,
            quality_per_channel: quality,
            channels,
            bands,
            maps,
        })
    }
}

fn unsupported(what: &str) -> GpuMetricsError {
    GpuMetricsError::Unsupported(format!("ColorVideoVDP: {what}"))
}
