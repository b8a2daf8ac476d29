//! [`GpuMetrics`]: the device, the pipelines (made once), the tables, and the buffers that are
//! reused from pair to pair (made once per frame size, grown when a request needs more).
//!
//! For: owning GPU objects and the plumbing every pass shares (uniform slots, output regions,
//! dispatch grids, the one readback per request, timestamps). Not for: what the passes compute
//! (see `pair`, `temporal`, `frame`).

use std::collections::HashMap;

use tessera_metrics::{CvvdpResult, CvvdpSettings, Frames};

use crate::cvvdp::CvvdpState;
use crate::error::GpuMetricsError;
use crate::plumbing::{check_binding, read_buffer, Layout, Region, MAX_TIMED};
use crate::pool::{RunningSums, Ticket};
use crate::shaders::Pipelines;

/// The FLIP kernels of one pixels-per-degree value, on the device.
pub(crate) struct FlipKernels {
    pub buffer: wgpu::Buffer,
    pub rs: u32,
    pub rf: u32,
    pub cmax: f32,
    pub pccmax: f32,
}

/// FLIP's intermediate images for one frame size.
pub(crate) struct FlipBuffers {
    pub width: u32,
    pub height: u32,
    /// Planes (Y, Cx, Cz, gray), vertically filtered colour and features: reference, test.
    pub planes: [wgpu::Buffer; 2],
    pub colour: [wgpu::Buffer; 2],
    pub feature: [wgpu::Buffer; 2],
    /// LDR and HDR error maps.
    pub error: [wgpu::Buffer; 2],
}

/// Timestamp queries around each metric group of a request.
pub(crate) struct Timer {
    pub set: wgpu::QuerySet,
    pub resolve: wgpu::Buffer,
    pub period_ns: f32,
}

/// The GPU back end: metrics of frames that live on `device`.
///
/// Create one per device and keep it: pipelines are compiled here, per-size buffers on the first
/// request of each size (STYLE.md 8). Requests run one at a time (`&mut self`).
pub struct GpuMetrics {
    pub(crate) device: wgpu::Device,
    pub(crate) queue: wgpu::Queue,
    pub(crate) pipelines: Pipelines,
    /// FLIP's sRGB decode table, `encode_srgb8`'s thresholds and the magma map.
    pub(crate) srgb_table: wgpu::Buffer,
    pub(crate) encode_thresholds: wgpu::Buffer,
    pub(crate) magma: wgpu::Buffer,
    pub(crate) kernels: HashMap<u32, FlipKernels>,
    pub(crate) flip: Option<FlipBuffers>,
    /// Uniform slots of a request, written before its submission.
    pub(crate) params: wgpu::Buffer,
    /// Outputs of a request (partials, heat maps) and their readback copy.
    pub(crate) outputs: wgpu::Buffer,
    pub(crate) staging: wgpu::Buffer,
    pub(crate) timer: Option<Timer>,
    pub(crate) adapter_name: String,
    /// GPU milliseconds of the last request's metric groups (empty without timestamps).
    pub(crate) last_gpu_ms: Vec<(&'static str, f64)>,
    /// ColorVideoVDP's pipelines, calibration and last plan, made on its first request.
    pub(crate) cvvdp: Option<Box<CvvdpState>>,
    /// FLIP's flip-evaluator means, summed on the device (`pool`), made on first use.
    pub(crate) running: Option<RunningSums>,
}

impl GpuMetrics {
    /// Compiles the pipelines on `device`. Timestamps are taken when the device has
    /// `TIMESTAMP_QUERY` (see [`GpuMetrics::last_gpu_ms`]).
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, adapter_name: &str) -> GpuMetrics {
        use wgpu::util::DeviceExt;
        let storage = |label: &str, bytes: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytes,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let srgb_table = storage(
            "srgb decode table",
            bytemuck::cast_slice(&tessera_metrics::port::srgb8_to_linear_table()),
        );
        let encode_thresholds = storage(
            "srgb encode thresholds",
            bytemuck::cast_slice(&tessera_metrics::port::srgb8_encode_thresholds()),
        );
        let magma: Vec<u32> = tessera_metrics::port::MAGMA
            .iter()
            .map(|c| c[0] as u32 | (c[1] as u32) << 8 | (c[2] as u32) << 16)
            .collect();
        let magma = storage("magma", bytemuck::cast_slice(&magma));
        let timer = device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY)
            .then(|| Timer {
                set: device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("metrics timestamps"),
                    ty: wgpu::QueryType::Timestamp,
                    count: 2 * MAX_TIMED,
                }),
                resolve: device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("metrics timestamps resolve"),
                    size: 16 * MAX_TIMED as u64,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                }),
                period_ns: queue.get_timestamp_period(),
            });
        GpuMetrics {
            pipelines: Pipelines::new(device),
            srgb_table,
            encode_thresholds,
            magma,
            kernels: HashMap::new(),
            flip: None,
            params: uniform_buffer(device, 4096),
            outputs: output_buffer(device, 4096),
            staging: staging_buffer(device, 4096),
            timer,
            adapter_name: adapter_name.to_string(),
            last_gpu_ms: Vec::new(),
            cvvdp: None,
            running: None,
            device: device.clone(),
            queue: queue.clone(),
        }
    }

    /// The device the metrics run on.
    pub fn device(&self) -> &wgpu::Device {
        &self.device
    }

    /// The adapter's name, as given to [`GpuMetrics::new`].
    pub fn adapter_name(&self) -> &str {
        &self.adapter_name
    }

    /// GPU time of each metric group of the last request, in ms, from timestamp queries around
    /// its compute passes (`pixel` = MSE/PSNR/max-abs/flicker sums, `ssim`, `flip`, `flip-hdr`,
    /// `tde`); empty when the device has no `TIMESTAMP_QUERY`.
    pub fn last_gpu_ms(&self) -> &[(&'static str, f64)] {
        &self.last_gpu_ms
    }

    /// Checks that one binding of `bytes` fits the device's limits.
    pub(crate) fn check_binding(&self, what: &str, bytes: u64) -> Result<(), GpuMetricsError> {
        check_binding(&self.device, what, bytes)
    }

    /// Grows the uniform, output and staging buffers to fit `layout`.
    pub(crate) fn fit(&mut self, layout: &Layout) {
        let p = layout.params.len() as u64;
        if p > self.params.size() {
            self.params = uniform_buffer(&self.device, p.next_power_of_two());
        }
        let o = layout.outputs + 16 * MAX_TIMED as u64;
        if o > self.outputs.size() {
            self.outputs = output_buffer(&self.device, o.next_power_of_two());
            self.staging = staging_buffer(&self.device, o.next_power_of_two());
        }
    }

    /// A uniform binding of slot `offset` of size `T`.
    pub(crate) fn slot<T>(&self, offset: u64) -> wgpu::BindingResource<'_> {
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.params,
            offset,
            size: wgpu::BufferSize::new(size_of::<T>() as u64),
        })
    }

    /// A storage binding of an output region.
    pub(crate) fn out(&self, r: Region) -> wgpu::BindingResource<'_> {
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.outputs,
            offset: r.offset,
            size: wgpu::BufferSize::new(r.size),
        })
    }

    pub(crate) fn bind(
        &self,
        pipeline: &wgpu::ComputePipeline,
        entries: &[wgpu::BindingResource<'_>],
    ) -> wgpu::BindGroup {
        let entries: Vec<wgpu::BindGroupEntry> = entries
            .iter()
            .enumerate()
            .map(|(i, r)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: r.clone(),
            })
            .collect();
        self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &pipeline.get_bind_group_layout(0),
            entries: &entries,
        })
    }

    /// A compute pass for metric group `index` (`name`), timed when timestamps are on.
    pub(crate) fn pass<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        index: u32,
    ) -> wgpu::ComputePass<'e> {
        let timestamp_writes = self.timer.as_ref().filter(|_| index < MAX_TIMED).map(|t| {
            wgpu::ComputePassTimestampWrites {
                query_set: &t.set,
                beginning_of_pass_write_index: Some(2 * index),
                end_of_pass_write_index: Some(2 * index + 1),
            }
        });
        encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: None,
            timestamp_writes,
        })
    }

    /// Writes the uniforms, submits `encoder` with the copy of the outputs (and timestamps), waits,
    /// and returns the output bytes. `timed` names the metric groups recorded, in index order.
    pub(crate) fn finish(
        &mut self,
        layout: &Layout,
        mut encoder: wgpu::CommandEncoder,
        timed: &[&'static str],
    ) -> Result<Vec<u8>, GpuMetricsError> {
        let used = layout.outputs;
        let ts_offset = used;
        let n_timed = (timed.len() as u32).min(MAX_TIMED);
        if let (Some(t), true) = (&self.timer, n_timed > 0) {
            encoder.resolve_query_set(&t.set, 0..2 * n_timed, &t.resolve, 0);
            encoder.copy_buffer_to_buffer(
                &t.resolve,
                0,
                &self.staging,
                ts_offset,
                16 * n_timed as u64,
            );
        }
        if used > 0 {
            encoder.copy_buffer_to_buffer(&self.outputs, 0, &self.staging, 0, used);
        }
        self.queue.write_buffer(&self.params, 0, &layout.params);
        self.queue.submit([encoder.finish()]);
        let read = used
            + if self.timer.is_some() {
                16 * n_timed as u64
            } else {
                0
            };
        let bytes = read_buffer(&self.device, &self.staging, read.max(4))?;
        self.last_gpu_ms.clear();
        if let (Some(t), true) = (&self.timer, n_timed > 0) {
            let stamps: &[u64] =
                bytemuck::cast_slice(&bytes[ts_offset as usize..][..16 * n_timed as usize]);
            for (i, name) in timed.iter().take(n_timed as usize).enumerate() {
                let ticks = stamps[2 * i + 1].wrapping_sub(stamps[2 * i]);
                self.last_gpu_ms
                    .push((name, ticks as f64 * t.period_ns as f64 / 1e6));
            }
        }
        Ok(bytes)
    }
}

/// ColorVideoVDP (`cvvdp`), through the state made on its first request.
impl GpuMetrics {
    /// ColorVideoVDP of `test` against `reference` on the device: the same checks, shots,
    /// per-frame values and maps as `tessera_metrics::cvvdp`, with each shot's pyramid, masking
    /// and spatial pooling computed by compute passes.
    ///
    /// `GpuMetricsError::Unsupported` when the device cannot hold the work (a plane beyond its
    /// binding limit, more temporal taps than the frame ring holds): use the CPU.
    pub fn cvvdp(
        &mut self,
        reference: Frames<'_>,
        test: Frames<'_>,
        settings: &CvvdpSettings,
    ) -> Result<CvvdpResult, GpuMetricsError> {
        crate::cvvdp::evaluate(
            &self.device,
            &self.queue,
            &mut self.cvvdp,
            reference,
            test,
            settings,
        )
    }

    /// GPU ms of each frame of the last [`GpuMetrics::cvvdp`] call, from timestamps around each
    /// frame's passes; empty without `TIMESTAMP_QUERY`.
    pub fn last_cvvdp_frame_ms(&self) -> &[f64] {
        self.cvvdp.as_ref().map_or(&[], |s| s.frame_ms())
    }
}

/// FLIP's flip-evaluator means (`pool`), through the batch made on first use.
impl GpuMetrics {
    fn running(&mut self) -> &mut RunningSums {
        let device = &self.device;
        self.running.get_or_insert_with(|| RunningSums::new(device))
    }

    /// [`RunningSums::make_room`].
    pub(crate) fn make_running_room(
        &mut self,
        count: u32,
        maps: u32,
    ) -> Result<(), GpuMetricsError> {
        let (device, queue) = (self.device.clone(), self.queue.clone());
        self.running().make_room(&device, &queue, count, maps)
    }

    /// [`RunningSums::reserve`].
    pub(crate) fn reserve_running_mean(&mut self) -> (Ticket, u64) {
        self.running().reserve()
    }

    /// [`RunningSums::maps`].
    pub(crate) fn running_maps(&self) -> &wgpu::Buffer {
        self.running.as_ref().expect("reserved first").maps()
    }

    /// [`RunningSums::flush`].
    pub(crate) fn flush_running_means(&mut self) -> Result<(), GpuMetricsError> {
        let (device, queue) = (self.device.clone(), self.queue.clone());
        self.running().flush(&device, &queue)
    }

    /// [`RunningSums::take_mean`].
    pub(crate) fn take_running_mean(&mut self, ticket: Ticket) -> Result<f64, GpuMetricsError> {
        self.running().take_mean(ticket)
    }

    /// [`RunningSums::set_defer`].
    pub(crate) fn defer_running_means(&mut self, on: bool) {
        self.running().set_defer(on)
    }

    /// [`RunningSums::take_handed`].
    pub(crate) fn take_handed_means(&mut self) -> Vec<(Ticket, bool)> {
        self.running().take_handed()
    }
}

fn uniform_buffer(device: &wgpu::Device, size: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("metrics uniforms"),
        size,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

fn output_buffer(device: &wgpu::Device, size: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("metrics outputs"),
        size,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

fn staging_buffer(device: &wgpu::Device, size: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("metrics staging"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}
