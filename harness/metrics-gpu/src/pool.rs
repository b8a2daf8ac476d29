//! FLIP's mean pooled as flip-evaluator pools it (`FlipPooling::FlipEvaluator`), on the device:
//! the f32 running sum of the error map in row-major order (`shaders/running_sum.wgsl`), so
//! the map never comes back and the value is bit for bit the CPU's `FlipResult::mean`.
//!
//! The sum is sequential by definition (each step's rounding depends on the sum before it), so
//! one workgroup sums one map; maps are batched, and a batch is summed side by side in one
//! dispatch. A single pair's request sums its maps at once; a sequence defers them
//! ([`RunningSums::set_defer`]) and sums every frame's maps together at its end. Not
//! for: the exact mean (`reduce.wgsl`) or recording FLIP's passes (`pair`).

use std::collections::HashMap;

use wgpu::util::DeviceExt;

use crate::error::GpuMetricsError;
use crate::plumbing::{check_binding, read_buffer};

/// Maps per batch, at most.
const MAX_MAPS: u64 = 64;
/// Bytes of a batch, at most (also capped by the device's limits).
const MAX_BATCH_BYTES: u64 = 1 << 30;

/// A running mean waiting for its batch to be summed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) struct Ticket(u64);

/// The batch of error maps and the sums that came back.
pub(crate) struct RunningSums {
    pipeline: wgpu::ComputePipeline,
    /// Values per map of the current buffers.
    count: u32,
    stride: u64,
    capacity: u32,
    maps: wgpu::Buffer,
    sums: wgpu::Buffer,
    staging: wgpu::Buffer,
    /// Tickets of the maps copied into the batch, by slot.
    queued: Vec<Ticket>,
    next: u64,
    /// Summed, not yet taken: the sum and the value count.
    done: HashMap<Ticket, (f32, u32)>,
    /// Whether requests leave their means to a later [`RunningSums::flush`].
    pub defer: bool,
    /// Means a deferred request left (ticket, HDR-FLIP), in order, until taken.
    pub handed: Vec<(Ticket, bool)>,
}

fn stride_of(count: u32) -> u64 {
    (4 * count as u64).div_ceil(256) * 256
}

impl RunningSums {
    /// An empty batch on `device` (its buffers are sized by the first `make_room`).
    pub fn new(device: &wgpu::Device) -> RunningSums {
        let buffer = |size: u64, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("flip running sums"),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        RunningSums {
            pipeline: crate::shaders::pipeline(
                device,
                "flip running sum",
                crate::shaders::RUNNING_SUM,
            ),
            count: 0,
            stride: 256,
            capacity: 1,
            maps: buffer(256, wgpu::BufferUsages::STORAGE),
            sums: buffer(256, wgpu::BufferUsages::STORAGE),
            staging: buffer(256, wgpu::BufferUsages::MAP_READ),
            queued: Vec::new(),
            next: 0,
            done: HashMap::new(),
            defer: false,
            handed: Vec::new(),
        }
    }

    /// Makes room in the batch for `maps` error maps of `count` values: sums the batch first
    /// when it is too full or holds maps of another size. Call before a request reserves its
    /// slots, so that nothing is summed between a reservation and its copy.
    pub fn make_room(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        count: u32,
        maps: u32,
    ) -> Result<(), GpuMetricsError> {
        let full = self.queued.len() as u32 + maps > self.capacity;
        if !self.queued.is_empty() && (self.count != count || full) {
            self.flush(device, queue)?;
        }
        let stride = stride_of(count);
        check_binding(device, "a FLIP error map", stride)?;
        let limits = device.limits();
        let budget = MAX_BATCH_BYTES
            .min(limits.max_storage_buffer_binding_size)
            .min(limits.max_buffer_size);
        // Two at least: a request may pool LDR-FLIP and HDR-FLIP.
        let capacity = (budget / stride).clamp(2, MAX_MAPS) as u32;
        let r = self;
        if r.count != count {
            r.count = count;
            r.stride = stride;
            r.capacity = capacity;
            let buffer = |label, size: u64, usage| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size,
                    usage,
                    mapped_at_creation: false,
                })
            };
            use wgpu::BufferUsages as U;
            r.maps = buffer(
                "flip running maps",
                stride * capacity as u64,
                U::STORAGE | U::COPY_DST,
            );
            let sums = (4 * capacity as u64).max(16);
            r.sums = buffer("flip running sums", sums, U::STORAGE | U::COPY_SRC);
            r.staging = buffer("flip running staging", sums, U::MAP_READ | U::COPY_DST);
        }
        Ok(())
    }

    /// A slot for one error map of the size [`RunningSums::make_room`] made room for: its
    /// ticket and the byte offset to copy the map to (in [`RunningSums::maps`]).
    pub fn reserve(&mut self) -> (Ticket, u64) {
        let r = self;
        debug_assert!((r.queued.len() as u32) < r.capacity, "room made first");
        let ticket = Ticket(r.next);
        r.next += 1;
        let offset = r.queued.len() as u64 * r.stride;
        r.queued.push(ticket);
        (ticket, offset)
    }

    /// The batch buffer error maps are copied into (at a reserved offset).
    pub fn maps(&self) -> &wgpu::Buffer {
        &self.maps
    }

    /// Sums every map of the batch (one submission, one small readback).
    pub fn flush(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<(), GpuMetricsError> {
        let r = self;
        if r.queued.is_empty() {
            return Ok(());
        }
        let n = r.queued.len() as u32;
        let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("flip running params"),
            contents: bytemuck::cast_slice(&[r.count, (r.stride / 4) as u32, 0, 0]),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("flip running sum"),
            layout: &r.pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: params.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: r.maps.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: r.sums.as_entire_binding(),
                },
            ],
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&r.pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(n, 1, 1);
        }
        encoder.copy_buffer_to_buffer(&r.sums, 0, &r.staging, 0, 4 * n as u64);
        queue.submit([encoder.finish()]);
        let bytes = read_buffer(device, &r.staging, 4 * n as u64)?;
        let sums: &[f32] = bytemuck::cast_slice(&bytes);
        let count = r.count;
        for (t, &s) in r.queued.drain(..).zip(sums) {
            r.done.insert(t, (s, count));
        }
        Ok(())
    }

    /// The mean of a summed map (`flush` first), as `flip_running_mean` divides: in f32, by the
    /// value count.
    pub fn take_mean(&mut self, ticket: Ticket) -> Result<f64, GpuMetricsError> {
        let (sum, count) = self
            .done
            .remove(&ticket)
            .ok_or_else(|| GpuMetricsError::Readback("a FLIP running mean went missing".into()))?;
        Ok((sum / count as f32) as f64)
    }

    /// While `on`, requests leave their flip-evaluator means to [`RunningSums::flush`] (their
    /// `mean` is NaN until the caller fills it in from [`RunningSums::take_handed`]).
    pub fn set_defer(&mut self, on: bool) {
        let r = self;
        r.defer = on;
        if !on {
            r.handed.clear();
        }
    }

    /// The means the last deferred request left: (ticket, HDR-FLIP).
    pub fn take_handed(&mut self) -> Vec<(Ticket, bool)> {
        std::mem::take(&mut self.handed)
    }
}
