//! Tessera's image metrics as WGSL compute passes, on the device that rendered the frames:
//! PSNR/MSE (RGB and luma), max-abs-error, SSIM (RGB and luma), LDR-FLIP and HDR-FLIP with heat
//! maps, static-scene flicker and TDE, and ColorVideoVDP (`GpuMetrics::cvvdp`), each computing the same definition as its CPU
//! reference in `tessera-metrics` (which stays the fallback), within the tolerances the
//! cross-check tests assert.
//!
//! For: metric values of frames on a device, and one interface ([`MetricsBackend`]) over both
//! back ends. Not for: rendering, timing the rendered work, or deciding pass/fail. See the crate
//! README for the passes, their precision and the measured agreement.

mod backend;
mod context;
mod cvvdp;
mod device;
mod diff;
mod error;
mod frame;
mod pair;
mod plumbing;
mod pool;
mod shaders;
mod temporal;

pub use backend::{CpuMetrics, MetricsBackend, Pair, Sequence, SequenceValues};
pub use context::GpuMetrics;
pub use device::{open, select_adapter, MetricsDevice};
pub use diff::diff_images;
pub use error::GpuMetricsError;
pub use frame::GpuFrame;
pub use pair::{
    Backend, FlipHdrRequest, FlipPooling, FlipRequest, FlipValues, PairRequest, PairValues,
};
