//! The one error type of this crate.
//!
//! For: every way a GPU metric can refuse its input or fail on the device. Not for: results
//! (identical images still give an infinite PSNR).

/// Why a GPU metric could not be computed.
#[derive(Debug, thiserror::Error)]
pub enum GpuMetricsError {
    /// The input is invalid for the metric: the same checks and messages as the CPU back end.
    #[error(transparent)]
    Metrics(#[from] tessera_metrics::MetricsError),
    /// The device cannot hold the work at this size (a buffer beyond its binding limit); the
    /// caller should use the CPU back end.
    #[error("the GPU metrics cannot run on this device: {0}; use metrics_device = \"cpu\"")]
    Unsupported(String),
    /// No adapter was found, or none matched the filter.
    #[error("no GPU adapter for the metrics{}: available: {available}", wanted.as_ref().map(|w| format!(" matches \"{w}\"")).unwrap_or_default())]
    NoAdapter {
        wanted: Option<String>,
        available: String,
    },
    /// The device could not be opened.
    #[error("cannot open a device on {adapter}: {source}")]
    RequestDevice {
        adapter: String,
        source: wgpu::RequestDeviceError,
    },
    /// Reading results back from the device failed (device lost, out of memory).
    #[error("reading GPU metric results back failed: {0}")]
    Readback(String),
    /// A texture given as a frame has a format the encode pass cannot read.
    #[error("frame texture format {0:?} is not supported; use Rgba16Float or Rgba32Float")]
    TextureFormat(wgpu::TextureFormat),
}
