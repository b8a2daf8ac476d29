//! Metrics of one reference/test pair on the device: the request, the passes it records, and
//! the values that come back.
//!
//! For: PSNR/MSE (RGB and luma), max-abs-error, SSIM (RGB and luma), LDR-FLIP and HDR-FLIP with
//! their heat maps, recorded into one command buffer, submitted once, read back once. Not for:
//! sequences (see `temporal` for flicker and TDE, `backend` for whole runs).
//!
//! Reductions are deterministic: every pass writes one partial per workgroup (a fixed-order tree
//! in workgroup memory), and the partials are added on the CPU in workgroup order, in u64 for the
//! integer sums (MSE and max-abs are exact, bit for bit the CPU's) and f64 for the float ones.

use serde::{Deserialize, Serialize};
use tessera_metrics::{ExposureRange, Rgb8Image};

use crate::context::GpuMetrics;
use crate::context::{FlipBuffers, FlipKernels};
use crate::error::GpuMetricsError;
use crate::frame::GpuFrame;
use crate::plumbing::{unpack, Grid1, Layout, Region};

/// Where a metric was computed: recorded with every result (`metrics_device` in a scenario).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Backend {
    Cpu,
    Gpu,
}

impl Backend {
    pub const ALL: [Backend; 2] = [Backend::Gpu, Backend::Cpu];

    pub fn name(self) -> &'static str {
        match self {
            Backend::Cpu => "cpu",
            Backend::Gpu => "gpu",
        }
    }

    /// `"gpu"` or `"cpu"`; anything else is an error that lists them.
    pub fn parse(s: &str) -> Result<Backend, String> {
        Backend::ALL
            .into_iter()
            .find(|b| b.name() == s)
            .ok_or_else(|| format!("unknown metrics device \"{s}\"; allowed: \"gpu\", \"cpu\""))
    }
}

impl std::fmt::Display for Backend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Which metrics of a pair to compute.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PairRequest {
    pub mse_rgb: bool,
    pub mse_luma: bool,
    pub max_abs: bool,
    pub ssim_rgb: bool,
    pub ssim_luma: bool,
    pub flip: Option<FlipRequest>,
    pub flip_hdr: Option<FlipHdrRequest>,
}

impl PairRequest {
    /// Every 8-bit metric, and LDR-FLIP at `ppd` (no heat map).
    pub fn all_ldr(ppd: f64) -> PairRequest {
        PairRequest {
            mse_rgb: true,
            mse_luma: true,
            max_abs: true,
            ssim_rgb: true,
            ssim_luma: true,
            flip: Some(FlipRequest {
                pixels_per_degree: ppd,
                heatmap: false,
                pooling: FlipPooling::Exact,
            }),
            flip_hdr: None,
        }
    }
}

/// LDR-FLIP at a viewing condition, with or without its heat map.
#[derive(Debug, Clone, PartialEq)]
pub struct FlipRequest {
    pub pixels_per_degree: f64,
    pub heatmap: bool,
    pub pooling: FlipPooling,
}

/// How the GPU pools FLIP's error map into its mean.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum FlipPooling {
    /// The exact mean, on the device (f32 partials per workgroup, summed in f64): only two
    /// floats per workgroup come back.
    #[default]
    Exact,
    /// Pooled as flip-evaluator and the CPU back end pool it: an f32 running sum in row-major
    /// order (`FlipResult::mean`), bit for bit, summed on the device (`pool.rs`: one workgroup
    /// adds one map in order; a sequence's maps are summed side by side). Keeps the value
    /// continuous with CPU results where FLIP's f32 drift is large (up to ~3e-3 at 1080p);
    /// nothing but the sum comes back.
    FlipEvaluator,
    /// As [`FlipPooling::FlipEvaluator`], pooled on the CPU from the error map, which comes back
    /// (`FlipValues::error_map`): for callers that need the whole map (`tessera diff`'s
    /// percentiles). Costs a readback of 4 bytes per pixel.
    ErrorMap,
}

/// HDR-FLIP over an exposure range (from the reference: `tessera_metrics::hdr_exposure_range`).
#[derive(Debug, Clone, PartialEq)]
pub struct FlipHdrRequest {
    pub range: ExposureRange,
    pub pixels_per_degree: f64,
    pub heatmap: bool,
    pub pooling: FlipPooling,
}

/// FLIP's pooled values (and heat map) of one pair.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FlipValues {
    /// The mean error, pooled as `pooling` says. The CPU back end always pools as
    /// flip-evaluator (`FlipResult::mean`). Exact and running means differ by less than 1e-6 on
    /// typical maps, by up to ~3e-3 on a 1080p map of large errors (the f32 drift).
    pub mean: f64,
    /// The exact mean (f64 sum of the per-pixel errors).
    pub exact_mean: f64,
    pub pooling: FlipPooling,
    pub max: f64,
    #[serde(skip)]
    pub heatmap: Option<Rgb8Image>,
    /// The per-pixel errors, when they came back (GPU with `FlipPooling::ErrorMap`).
    #[serde(skip)]
    pub error_map: Option<Vec<f32>>,
}

/// The values of a [`PairRequest`]; `None` for what was not requested.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PairValues {
    pub backend: Backend,
    pub mse_rgb: Option<f64>,
    pub mse_luma: Option<f64>,
    pub max_abs: Option<u8>,
    pub ssim_rgb: Option<f64>,
    pub ssim_luma: Option<f64>,
    pub flip: Option<FlipValues>,
    pub flip_hdr: Option<FlipValues>,
}

impl PairValues {
    pub(crate) fn empty(backend: Backend) -> PairValues {
        PairValues {
            backend,
            mse_rgb: None,
            mse_luma: None,
            max_abs: None,
            ssim_rgb: None,
            ssim_luma: None,
            flip: None,
            flip_hdr: None,
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct Params1 {
    pub count: u32,
    pub groups_x: u32,
    pub _p: [u32; 2],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct SsimParams {
    width: u32,
    height: u32,
    channel: u32,
    groups_x: u32,
    c1: f32,
    c2: f32,
    _p: [u32; 2],
    w: [f32; 12],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct PlanesHdrParams {
    count: u32,
    groups_x: u32,
    multiplier: f32,
    _p: u32,
    t: [f32; 8],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct VerticalParams {
    width: u32,
    height: u32,
    rs: u32,
    rf: u32,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct HorizontalParams {
    width: u32,
    height: u32,
    rs: u32,
    rf: u32,
    mode: u32,
    cmax: f32,
    pccmax: f32,
    pt_over_pccmax: f32,
}

/// The sums of the pixel pass, added over workgroups.
pub(crate) struct PixelSums {
    pub sq_rgb: u64,
    pub sq_luma_millis: u128,
    pub max_abs: u32,
    pub sum_abs: u64,
}

pub(crate) fn pixel_sums(words: &[u32]) -> PixelSums {
    let mut s = PixelSums {
        sq_rgb: 0,
        sq_luma_millis: 0,
        max_abs: 0,
        sum_abs: 0,
    };
    for p in words.chunks_exact(6) {
        s.sq_rgb += p[0] as u64;
        s.sq_luma_millis += ((p[1] as u128) << 18) + ((p[2] as u128) << 10) + p[3] as u128;
        s.max_abs = s.max_abs.max(p[4]);
        s.sum_abs += p[5] as u64;
    }
    s
}

fn words(bytes: &[u8], r: Region) -> &[u32] {
    bytemuck::cast_slice(&bytes[r.offset as usize..][..r.size as usize])
}

fn floats(bytes: &[u8], r: Region) -> &[f32] {
    bytemuck::cast_slice(&bytes[r.offset as usize..][..r.size as usize])
}

/// The pooled values of a reduce pass's partials (sum, max per workgroup).
fn pooled(partials: &[f32], count: usize) -> (f64, f64) {
    let mut sum = 0.0f64;
    let mut max = 0.0f32;
    for p in partials.chunks_exact(2) {
        sum += p[0] as f64;
        max = max.max(p[1]);
    }
    (sum / count as f64, max as f64)
}

/// Where a requested FLIP's outputs go.
struct FlipPlan {
    /// Uniform slots: planes (two per exposure), vertical, horizontal (one per exposure).
    planes: Vec<[u64; 2]>,
    vertical: u64,
    horizontal: Vec<u64>,
    reduce: u64,
    partials: Region,
    heatmap: Option<Region>,
    /// The error map's copy, for `FlipPooling::ErrorMap`.
    map: Option<Region>,
    /// The running sum's slot (ticket, byte offset), for `FlipPooling::FlipEvaluator`.
    running: Option<(crate::pool::Ticket, u64)>,
    ppd_key: u32,
    multipliers: Vec<f32>,
}

impl GpuMetrics {
    /// Computes `request` for `reference` vs `test` (same size) in one submission.
    pub fn evaluate(
        &mut self,
        reference: &GpuFrame,
        test: &GpuFrame,
        request: &PairRequest,
    ) -> Result<PairValues, GpuMetricsError> {
        let (w, h) = (reference.width, reference.height);
        if (test.width, test.height) != (w, h) {
            return Err(tessera_metrics::MetricsError::SizeMismatch {
                ref_width: w,
                ref_height: h,
                test_width: test.width,
                test_height: test.height,
            }
            .into());
        }
        if request.ssim_rgb || request.ssim_luma {
            tessera_metrics::port::ssim_check_size(w, h)?;
        }
        let n = w * h;
        let grid = Grid1::new(n);
        let mut layout = Layout::default();

        // Layout: the pixel pass.
        let pixel = (request.mse_rgb || request.mse_luma || request.max_abs).then(|| {
            let slot = layout.param(&Params1 {
                count: n,
                groups_x: grid.x,
                _p: [0; 2],
            });
            (slot, layout.output(24 * grid.groups() as u64))
        });

        // SSIM: channels 0..2 for RGB, 3 for luma.
        let ssim_grid = (
            w.saturating_sub(10).div_ceil(16),
            h.saturating_sub(10).div_ceil(16),
        );
        let mut ssim = Vec::new();
        let channels: Vec<u32> = [
            (request.ssim_rgb, vec![0, 1, 2]),
            (request.ssim_luma, vec![3]),
        ]
        .into_iter()
        .filter(|(on, _)| *on)
        .flat_map(|(_, c)| c)
        .collect();
        let window = tessera_metrics::port::ssim_window();
        let mut wts = [0.0f32; 12];
        for (d, s) in wts.iter_mut().zip(window) {
            *d = s as f32;
        }
        for c in channels {
            let range = if c == 3 { 255_000.0 } else { 255.0 };
            let c1 = (tessera_metrics::port::SSIM_K1 * range).powi(2) as f32;
            let c2 = (tessera_metrics::port::SSIM_K2 * range).powi(2) as f32;
            let slot = layout.param(&SsimParams {
                width: w,
                height: h,
                channel: c,
                groups_x: ssim_grid.0,
                c1,
                c2,
                _p: [0; 2],
                w: wts,
            });
            let out = layout.output(4 * (ssim_grid.0 * ssim_grid.1) as u64);
            ssim.push((c, slot, out));
        }

        // FLIP (LDR, then HDR); room for their running sums first (see `pool`).
        let running_maps = [
            request.flip.as_ref().map(|f| f.pooling),
            request.flip_hdr.as_ref().map(|f| f.pooling),
        ]
        .iter()
        .filter(|p| **p == Some(FlipPooling::FlipEvaluator))
        .count() as u32;
        if running_maps > 0 {
            self.make_running_room(n, running_maps)?;
        }
        let mut flips: Vec<(bool, FlipPlan)> = Vec::new();
        if let Some(f) = &request.flip {
            let ppd = tessera_metrics::port::flip_check_ppd(f.pixels_per_degree)?;
            flips.push((
                false,
                self.plan_flip(&mut layout, (w, h), ppd, vec![1.0], f.heatmap, f.pooling)?,
            ));
        }
        if let Some(f) = &request.flip_hdr {
            let (Some(_), Some(_)) = (&reference.hdr, &test.hdr) else {
                return Err(tessera_metrics::MetricsError::KindMismatch {
                    reference: if reference.hdr.is_some() {
                        "HDR"
                    } else {
                        "LDR"
                    },
                    test: if test.hdr.is_some() { "HDR" } else { "LDR" },
                }
                .into());
            };
            let ppd = tessera_metrics::port::flip_check_ppd(f.pixels_per_degree)?;
            let m = tessera_metrics::port::flip_exposure_multipliers(&f.range);
            check_range(&f.range)?;
            flips.push((
                true,
                self.plan_flip(&mut layout, (w, h), ppd, m, f.heatmap, f.pooling)?,
            ));
        }

        self.fit(&layout);
        let mut encoder = self.device.create_command_encoder(&Default::default());
        let mut timed: Vec<&'static str> = Vec::new();

        if let Some((slot, out)) = pixel {
            let bind = self.bind(
                &self.pipelines.pixel,
                &[
                    self.slot::<Params1>(slot),
                    reference.ldr.as_entire_binding(),
                    test.ldr.as_entire_binding(),
                    self.out(out),
                ],
            );
            let mut pass = self.pass(&mut encoder, timed.len() as u32);
            pass.set_pipeline(&self.pipelines.pixel);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(grid.x, grid.y, 1);
            drop(pass);
            timed.push("pixel");
        }
        if !ssim.is_empty() {
            let binds: Vec<wgpu::BindGroup> = ssim
                .iter()
                .map(|&(_, slot, out)| {
                    self.bind(
                        &self.pipelines.ssim,
                        &[
                            self.slot::<SsimParams>(slot),
                            reference.ldr.as_entire_binding(),
                            test.ldr.as_entire_binding(),
                            self.out(out),
                        ],
                    )
                })
                .collect();
            let mut pass = self.pass(&mut encoder, timed.len() as u32);
            pass.set_pipeline(&self.pipelines.ssim);
            for b in &binds {
                pass.set_bind_group(0, b, &[]);
                pass.dispatch_workgroups(ssim_grid.0, ssim_grid.1, 1);
            }
            drop(pass);
            timed.push("ssim");
        }
        for (hdr, plan) in &flips {
            self.record_flip(
                &mut encoder,
                timed.len() as u32,
                reference,
                test,
                *hdr,
                plan,
            );
            timed.push(if *hdr { "flip-hdr" } else { "flip" });
        }

        let bytes = self.finish(&layout, encoder, &timed)?;

        let mut values = PairValues::empty(Backend::Gpu);
        if let Some((_, out)) = pixel {
            let s = pixel_sums(words(&bytes, out));
            let count = n as f64;
            if request.mse_rgb {
                values.mse_rgb = Some(s.sq_rgb as f64 / (3.0 * count));
            }
            if request.mse_luma {
                values.mse_luma = Some(s.sq_luma_millis as f64 / 1e6 / count);
            }
            if request.max_abs {
                values.max_abs = Some(s.max_abs as u8);
            }
        }
        let valid = (w.saturating_sub(10) as f64) * (h.saturating_sub(10) as f64);
        let mut rgb = 0.0;
        for &(c, _, out) in &ssim {
            let mean = floats(&bytes, out).iter().map(|&v| v as f64).sum::<f64>() / valid;
            if c == 3 {
                values.ssim_luma = Some(mean);
            } else {
                rgb += mean;
            }
        }
        if request.ssim_rgb {
            values.ssim_rgb = Some(rgb / 3.0);
        }
        let defer = self.running.as_ref().is_some_and(|r| r.defer);
        if !defer && flips.iter().any(|(_, p)| p.running.is_some()) {
            self.flush_running_means()?;
        }
        for (hdr, plan) in &flips {
            let (exact_mean, max) = pooled(floats(&bytes, plan.partials), n as usize);
            let heatmap = plan.heatmap.map(|r| unpack(words(&bytes, r), w, h));
            let error_map = plan.map.map(|r| floats(&bytes, r)[..n as usize].to_vec());
            let (mean, pooling) = match (&error_map, plan.running) {
                (Some(m), _) => (
                    tessera_metrics::port::flip_running_mean(m),
                    FlipPooling::ErrorMap,
                ),
                // Filled in by the caller that deferred it (`backend`'s sequence).
                (None, Some((ticket, _))) if defer => {
                    if let Some(r) = self.running.as_mut() {
                        r.handed.push((ticket, *hdr));
                    }
                    (f64::NAN, FlipPooling::FlipEvaluator)
                }
                (None, Some((ticket, _))) => {
                    (self.take_running_mean(ticket)?, FlipPooling::FlipEvaluator)
                }
                (None, None) => (exact_mean, FlipPooling::Exact),
            };
            let v = FlipValues {
                error_map,
                mean,
                exact_mean,
                pooling,
                max,
                heatmap,
            };
            if *hdr {
                values.flip_hdr = Some(v);
            } else {
                values.flip = Some(v);
            }
        }
        Ok(values)
    }

    fn plan_flip(
        &mut self,
        layout: &mut Layout,
        (w, h): (u32, u32),
        ppd: f32,
        multipliers: Vec<f32>,
        heatmap: bool,
        pooling: FlipPooling,
    ) -> Result<FlipPlan, GpuMetricsError> {
        let n = w * h;
        self.ensure_flip(w, h)?;
        let k = self.ensure_kernels(ppd);
        let grid = Grid1::new(n);
        let aces = tessera_metrics::port::flip_aces();
        let planes = multipliers
            .iter()
            .map(|&m| {
                [0, 1].map(|_| {
                    layout.param(&PlanesHdrParams {
                        count: n,
                        groups_x: grid.x,
                        multiplier: m,
                        _p: 0,
                        t: [
                            aces[0], aces[1], aces[2], 0.0, aces[3], aces[4], aces[5], 0.0,
                        ],
                    })
                })
            })
            .collect();
        let vertical = layout.param(&VerticalParams {
            width: w,
            height: h,
            rs: k.rs,
            rf: k.rf,
        });
        let horizontal = (0..multipliers.len())
            .map(|i| {
                layout.param(&HorizontalParams {
                    width: w,
                    height: h,
                    rs: k.rs,
                    rf: k.rf,
                    mode: (i > 0) as u32,
                    cmax: k.cmax,
                    pccmax: k.pccmax,
                    pt_over_pccmax: tessera_metrics::port::FLIP_PT / k.pccmax,
                })
            })
            .collect();
        let reduce = layout.param(&Params1 {
            count: n,
            groups_x: grid.x,
            _p: [0; 2],
        });
        let partials = layout.output(8 * grid.groups() as u64);
        let heatmap = heatmap.then(|| layout.output(4 * n as u64));
        let map = (pooling == FlipPooling::ErrorMap).then(|| layout.output(4 * n as u64));
        let running = (pooling == FlipPooling::FlipEvaluator).then(|| self.reserve_running_mean());
        Ok(FlipPlan {
            map,
            running,
            planes,
            vertical,
            horizontal,
            reduce,
            partials,
            heatmap,
            ppd_key: ppd.to_bits(),
            multipliers,
        })
    }

    fn ensure_kernels(&mut self, ppd: f32) -> &FlipKernels {
        let device = &self.device;
        self.kernels.entry(ppd.to_bits()).or_insert_with(|| {
            use wgpu::util::DeviceExt;
            let s = tessera_metrics::port::flip_spatial_kernels(ppd);
            let f = tessera_metrics::port::flip_feature_kernels(ppd);
            let data: Vec<f32> = s.iter().chain(f.iter()).flatten().copied().collect();
            let cmax = tessera_metrics::port::flip_cmax();
            FlipKernels {
                buffer: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("flip kernels"),
                    contents: bytemuck::cast_slice(&data),
                    usage: wgpu::BufferUsages::STORAGE,
                }),
                rs: (s[0].len() / 2) as u32,
                rf: (f[0].len() / 2) as u32,
                cmax,
                pccmax: tessera_metrics::port::FLIP_PC * cmax,
            }
        })
    }

    fn ensure_flip(&mut self, w: u32, h: u32) -> Result<(), GpuMetricsError> {
        if self
            .flip
            .as_ref()
            .is_some_and(|f| (f.width, f.height) == (w, h))
        {
            return Ok(());
        }
        let n = w as u64 * h as u64;
        self.check_binding("FLIP's intermediate images", 16 * n)?;
        self.flip = None;
        let make = |label| {
            self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 16 * n,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            })
        };
        let error = |label| {
            self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 4 * n,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        };
        self.flip = Some(FlipBuffers {
            width: w,
            height: h,
            planes: [make("flip planes ref"), make("flip planes test")],
            colour: [make("flip colour ref"), make("flip colour test")],
            feature: [make("flip feature ref"), make("flip feature test")],
            error: [error("flip error ldr"), error("flip error hdr")],
        });
        Ok(())
    }

    fn record_flip(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timer_index: u32,
        reference: &GpuFrame,
        test: &GpuFrame,
        hdr: bool,
        plan: &FlipPlan,
    ) {
        let fb = self.flip.as_ref().expect("planned");
        let k = &self.kernels[&plan.ppd_key];
        let p = &self.pipelines;
        let (w, h) = (fb.width, fb.height);
        let n = w * h;
        let grid = Grid1::new(n);
        let error = &fb.error[hdr as usize];
        let frames = [reference, test];
        let vertical: Vec<wgpu::BindGroup> = (0..2)
            .map(|i| {
                self.bind(
                    &p.vertical,
                    &[
                        self.slot::<VerticalParams>(plan.vertical),
                        k.buffer.as_entire_binding(),
                        fb.planes[i].as_entire_binding(),
                        fb.colour[i].as_entire_binding(),
                        fb.feature[i].as_entire_binding(),
                    ],
                )
            })
            .collect();
        let mut pass = self.pass(encoder, timer_index);
        for (e, &_m) in plan.multipliers.iter().enumerate() {
            for (i, frame) in frames.iter().enumerate() {
                let bind = if hdr {
                    let src = frame.hdr.as_ref().expect("checked");
                    self.bind(
                        &p.planes_hdr,
                        &[
                            self.slot::<PlanesHdrParams>(plan.planes[e][i]),
                            src.as_entire_binding(),
                            fb.planes[i].as_entire_binding(),
                        ],
                    )
                } else {
                    self.bind(
                        &p.planes_ldr,
                        &[
                            self.slot::<Params1>(plan.planes[e][i]),
                            frame.ldr.as_entire_binding(),
                            self.srgb_table.as_entire_binding(),
                            fb.planes[i].as_entire_binding(),
                        ],
                    )
                };
                pass.set_pipeline(if hdr { &p.planes_hdr } else { &p.planes_ldr });
                pass.set_bind_group(0, &bind, &[]);
                pass.dispatch_workgroups(grid.x, grid.y, 1);
            }
            pass.set_pipeline(&p.vertical);
            for b in &vertical {
                pass.set_bind_group(0, b, &[]);
                pass.dispatch_workgroups(w.div_ceil(16), h.div_ceil(16), 1);
            }
            let bind = self.bind(
                &p.horizontal,
                &[
                    self.slot::<HorizontalParams>(plan.horizontal[e]),
                    k.buffer.as_entire_binding(),
                    fb.colour[0].as_entire_binding(),
                    fb.feature[0].as_entire_binding(),
                    fb.colour[1].as_entire_binding(),
                    fb.feature[1].as_entire_binding(),
                    error.as_entire_binding(),
                ],
            );
            pass.set_pipeline(&p.horizontal);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(w.div_ceil(16), h.div_ceil(16), 1);
        }
        let bind = self.bind(
            &p.reduce,
            &[
                self.slot::<Params1>(plan.reduce),
                error.as_entire_binding(),
                self.out(plan.partials),
            ],
        );
        pass.set_pipeline(&p.reduce);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(grid.x, grid.y, 1);
        if let Some(r) = plan.heatmap {
            let bind = self.bind(
                &p.heatmap,
                &[
                    self.slot::<Params1>(plan.reduce),
                    error.as_entire_binding(),
                    self.magma.as_entire_binding(),
                    self.out(r),
                ],
            );
            pass.set_pipeline(&p.heatmap);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(grid.x, grid.y, 1);
        }
        drop(pass);
        if let Some(r) = plan.map {
            encoder.copy_buffer_to_buffer(error, 0, &self.outputs, r.offset, 4 * n as u64);
        }
        if let Some((_, offset)) = plan.running {
            encoder.copy_buffer_to_buffer(error, 0, self.running_maps(), offset, 4 * n as u64);
        }
    }
}

/// The exposure-range checks of `flip_hdr` (its messages).
fn check_range(range: &ExposureRange) -> Result<(), GpuMetricsError> {
    // `flip_hdr_check` also checks images; ranges alone are checked with a 1x1 probe pair.
    let probe = tessera_metrics::HdrImage {
        width: 1,
        height: 1,
        data: vec![0.0; 3],
    };
    tessera_metrics::port::flip_hdr_check(&probe, &probe, range)?;
    Ok(())
}
