//! Per-pass GPU measurements: timestamps through wgpu-profiler and fragment-shader invocations
//! through pipeline-statistics queries.
//!
//! Both are optional and typed: without the feature the value is `None`, never zero. This module
//! only collects raw numbers per frame; summaries are made in `run/`.

use std::collections::BTreeMap;

use wgpu_profiler::{GpuProfiler, GpuProfilerQuery, GpuProfilerSettings};

/// Raw measurements of one frame.
#[derive(Clone, Debug, Default)]
pub struct FrameMeasurements {
    /// Milliseconds per pass; absent without timestamps.
    pub gpu_ms: BTreeMap<String, f64>,
    /// Fragment-shader invocations per render pass; absent without pipeline statistics.
    pub fragment_invocations: BTreeMap<String, u64>,
}

pub struct Timers {
    profiler: GpuProfiler,
    timestamps: bool,
    stats: Option<Stats>,
    /// The device counts pipeline statistics.
    pipeline_statistics: bool,
    /// Pipeline statistics are counted only while enabled (the capture phase, one frame at a time).
    stats_enabled: bool,
}

/// Frames the profiler may have in flight before it drops the oldest; callers keep fewer.
pub const MAX_PENDING_FRAMES: usize = 4;

struct Stats {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
    /// Render passes in query-index order.
    passes: Vec<&'static str>,
}

#[derive(Debug, thiserror::Error)]
#[error("cannot create the GPU profiler: {0}")]
pub struct TimerError(String);

impl Timers {
    /// `render_passes`: the render passes that may record pipeline statistics, in a fixed order.
    pub fn new(
        device: &wgpu::Device,
        render_passes: &[&'static str],
    ) -> Result<Timers, TimerError> {
        let timestamps = device.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        let settings = GpuProfilerSettings {
            enable_timer_queries: timestamps,
            enable_debug_groups: false,
            max_num_pending_frames: MAX_PENDING_FRAMES,
        };
        let profiler = GpuProfiler::new(device, settings).map_err(|e| TimerError(e.to_string()))?;
        let stats = (device
            .features()
            .contains(wgpu::Features::PIPELINE_STATISTICS_QUERY)
            && !render_passes.is_empty())
        .then(|| {
            let n = render_passes.len() as u32;
            let size = n as u64 * 8;
            Stats {
                set: device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("fragment invocations"),
                    ty: wgpu::QueryType::PipelineStatistics(
                        wgpu::PipelineStatisticsTypes::FRAGMENT_SHADER_INVOCATIONS,
                    ),
                    count: n,
                }),
                resolve: device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("statistics resolve"),
                    size,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                }),
                readback: device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("statistics readback"),
                    size,
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                }),
                passes: render_passes.to_vec(),
            }
        });
        Ok(Timers {
            profiler,
            timestamps,
            stats,
            pipeline_statistics: device
                .features()
                .contains(wgpu::Features::PIPELINE_STATISTICS_QUERY),
            stats_enabled: false,
        })
    }

    pub fn has_timestamps(&self) -> bool {
        self.timestamps
    }

    /// Whether fragment-shader invocations are being counted (the adapter has pipeline
    /// statistics and [`Timers::enable_stats`] turned them on).
    pub fn stats_enabled(&self) -> bool {
        self.stats_enabled && self.pipeline_statistics
    }

    /// Counts fragment-shader invocations from now on (frames must then be collected one by one
    /// with [`Timers::read_stats`], since there is one readback buffer).
    pub fn enable_stats(&mut self, enabled: bool) {
        self.stats_enabled = enabled;
    }

    /// Opens a timer for a pass; use its `render_pass_timestamp_writes` or
    /// `compute_pass_timestamp_writes` in the pass descriptor, then [`Timers::end`].
    pub fn begin(
        &self,
        name: &'static str,
        encoder: &mut wgpu::CommandEncoder,
    ) -> GpuProfilerQuery {
        self.profiler.begin_pass_query(name, encoder)
    }

    /// Opens a timer around commands recorded on the encoder outside any pass (copies): timestamps
    /// written into the encoder (needs `TIMESTAMP_QUERY_INSIDE_ENCODERS`, else untimed). Close
    /// with [`Timers::end`] on the same encoder.
    pub fn begin_encoder(
        &self,
        name: &'static str,
        encoder: &mut wgpu::CommandEncoder,
    ) -> GpuProfilerQuery {
        self.profiler.begin_query(name, encoder)
    }

    pub fn end(&self, encoder: &mut wgpu::CommandEncoder, query: GpuProfilerQuery) {
        self.profiler.end_query(encoder, query);
    }

    /// Starts counting fragment-shader invocations of render pass `name`.
    pub fn begin_stats(&self, pass: &mut wgpu::RenderPass<'_>, name: &str) {
        if let Some(s) = self.stats.as_ref().filter(|_| self.stats_enabled) {
            if let Some(i) = s.passes.iter().position(|p| *p == name) {
                pass.begin_pipeline_statistics_query(&s.set, i as u32);
            }
        }
    }

    pub fn end_stats(&self, pass: &mut wgpu::RenderPass<'_>, name: &str) {
        if let Some(s) = self.stats.as_ref().filter(|_| self.stats_enabled) {
            if s.passes.contains(&name) {
                pass.end_pipeline_statistics_query();
            }
        }
    }

    /// Resolves this frame's queries; call after the last pass, before `finish`.
    pub fn resolve(&mut self, encoder: &mut wgpu::CommandEncoder) {
        self.profiler.resolve_queries(encoder);
        if let Some(s) = self.stats.as_ref().filter(|_| self.stats_enabled) {
            let n = s.passes.len() as u32;
            encoder.resolve_query_set(&s.set, 0..n, &s.resolve, 0);
            encoder.copy_buffer_to_buffer(&s.resolve, 0, &s.readback, 0, s.resolve.size());
        }
    }

    /// Call once after each frame's submission.
    pub fn end_frame(&mut self) {
        // Only fails on unclosed or unresolved queries, which `record` and `resolve` rule out.
        let _ = self.profiler.end_frame();
    }

    /// Pass times of the oldest finished frame not yet collected, if its queries are readable
    /// (after a poll). Empty when the adapter has no timestamps.
    pub fn try_collect(&mut self, queue: &wgpu::Queue) -> Option<BTreeMap<String, f64>> {
        let results = self
            .profiler
            .process_finished_frame(queue.get_timestamp_period())?;
        let mut out = BTreeMap::new();
        for r in results {
            if let Some(t) = r.time {
                *out.entry(r.label.clone()).or_default() += (t.end - t.start) * 1000.0;
            }
        }
        Some(out)
    }

    /// Fragment-shader invocations of the last frame (statistics enabled, frame submitted).
    pub fn read_stats(&mut self, device: &wgpu::Device) -> BTreeMap<String, u64> {
        let mut out = BTreeMap::new();
        let Some(s) = self.stats.as_ref().filter(|_| self.stats_enabled) else {
            return out;
        };
        let slice = s.readback.slice(..);
        slice.map_async(wgpu::MapMode::Read, |_| {});
        let _ = device.poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: None,
        });
        if let Ok(data) = slice.get_mapped_range() {
            let counts: &[u64] = bytemuck::cast_slice(&data);
            for (name, c) in s.passes.iter().zip(counts) {
                out.insert(name.to_string(), *c);
            }
        }
        s.readback.unmap();
        out
    }
}
