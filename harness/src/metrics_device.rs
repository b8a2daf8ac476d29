//! Where a run's (or `tessera diff`'s) metrics are computed: `metrics_device = "gpu" | "cpu"`.
//!
//! For: choosing the back end (`tessera-metrics-gpu`'s [`MetricsBackend`]s) and opening the GPU
//! one for `tessera diff --gpu`. Not for: the metrics themselves (the two crates) or a run's
//! evaluate step (`run::metrics`, which takes the back end chosen here).
//!
//! Default: the GPU where the adapter is a real GPU. On a software rasteriser (lavapipe,
//! `DeviceType::Cpu`) the "GPU" passes are JIT-compiled CPU work, slower than the CPU reference
//! (measured with the crate's bench: SSIM at 256x144 176 ms on lavapipe against 7 ms on the
//! CPU), so the default there is the CPU; a scenario can still ask for `"gpu"`.

pub use tessera_metrics_gpu::{Backend, CpuMetrics, GpuMetrics, MetricsBackend};

/// The back end a scenario gets when it does not say: GPU unless the adapter is a CPU device.
pub fn default_backend(info: &wgpu::AdapterInfo) -> Backend {
    match info.device_type {
        wgpu::DeviceType::Cpu => Backend::Cpu,
        _ => Backend::Gpu,
    }
}

/// The back end a scenario's metrics run on, on `gpu`: its `metrics_device`, else
/// [`default_backend`].
pub fn chosen(scenario: &crate::scenario::Scenario, gpu: &crate::gpu::Gpu) -> Backend {
    scenario
        .metrics_device
        .unwrap_or_else(|| default_backend(&gpu.adapter.get_info()))
}

impl crate::gpu::Gpu {
    /// The GPU metrics on this device: pipelines compiled on first use, then shared by every
    /// scenario of the run.
    pub fn metrics(&self) -> std::sync::MutexGuard<'_, GpuMetrics> {
        self.metrics
            .get_or_init(|| {
                std::sync::Mutex::new(GpuMetrics::new(&self.device, &self.queue, &self.info.name))
            })
            .lock()
            .unwrap_or_else(|e| e.into_inner())
    }
}

/// The GPU back end on the first adapter by the same rules as `tessera run` (`--adapter`
/// filter, else the best-ranked), for commands that render nothing (`tessera diff --gpu`).
pub fn open_gpu(adapter: Option<&str>) -> Result<GpuMetrics, String> {
    let adapter = crate::gpu::select(adapter).map_err(|e| e.to_string())?;
    let name = adapter.get_info().name;
    let d = tessera_metrics_gpu::open(adapter).map_err(|e| e.to_string())?;
    Ok(GpuMetrics::new(&d.device, &d.queue, &name))
}

/// `tessera diff --gpu` of two files (see `tessera_metrics_gpu::diff_images`).
pub fn diff_images(
    gpu: &mut GpuMetrics,
    reference: &tessera_metrics::LoadedImage,
    test: &tessera_metrics::LoadedImage,
) -> Result<tessera_metrics::DiffReport, String> {
    tessera_metrics_gpu::diff_images(gpu, reference, test).map_err(|e| e.to_string())
}

/// `tessera diff --gpu` of two sequences: per-frame metrics on the GPU, ColorVideoVDP on the CPU.
pub fn diff_sequence_paths(
    gpu: &mut GpuMetrics,
    reference: &std::path::Path,
    test: &std::path::Path,
    settings: &tessera_metrics::CvvdpSettings,
) -> Result<tessera_metrics::SequenceReport, String> {
    let load = tessera_metrics::load_sequence_images;
    let (r, t) = (
        load(reference).map_err(|e| e.to_string())?,
        load(test).map_err(|e| e.to_string())?,
    );
    tessera_metrics::diff_sequences_with(&r, &t, settings, |a, b| {
        tessera_metrics_gpu::diff_images(gpu, a, b)
    })
    .map_err(|e| e.to_string())
}
