//! Image error metrics for Tessera, computed on the CPU exactly as their reference
//! implementations compute them: PSNR/MSE as scikit-image, SSIM as Wang et al. 2004 (scikit-image
//! with `gaussian_weights=True, sigma=1.5, use_sample_covariance=False`), and NVIDIA FLIP (LDR and
//! HDR) as the `flip-evaluator` package; ColorVideoVDP (JOD) of frame sequences through the
//! `colorvideovdp` crate, as PyPI's `cvvdp` 0.5.7.
//!
//! For: numbers from a reference/test pair of frames or sequences, loading and saving the images they come
//! from, and summarising per-frame series. Not for: rendering, GPU work or deciding pass/fail
//! (gates belong to the harness). See the crate README for exact settings and measured
//! agreement with the reference implementations.

mod cvvdp;
mod deep;
mod error;
mod flip;
mod image;
mod io;
mod luma;
mod pixel;
pub mod port;
mod report;
mod sequence;
mod series;
mod srgb;
mod ssim;
mod temporal;

pub use cvvdp::{
    cvvdp, cvvdp_heatmap, cvvdp_with, display_names, CpuPredictor, CustomDisplay, CvvdpResult,
    CvvdpSettings, DisplaySpec, DistortionMap, Frames, Shot, ShotJod, ShotPrediction,
    ShotPredictor, DEFAULT_DISPLAY, DEFAULT_HDR_WHITE, PAPER_27IN_4K, PAPER_27IN_4K_PPD,
};
pub use deep::{mse_luma16, mse_rgb16, ssim_luma16, ssim_rgb16, Rgb16Image, DATA_RANGE_16BIT};
pub use error::MetricsError;
pub use flip::{
    flip_hdr, flip_heatmap, flip_ldr, hdr_exposure_range, pixels_per_degree, ExposureRange,
    FlipResult, DEFAULT_PIXELS_PER_DEGREE, MAX_EXPOSURES,
};
pub use image::{HdrImage, Rgb8Image};
pub use io::{load_image, save_png, LoadedImage, SUPPORTED_INPUTS};
pub use luma::LUMA_WEIGHTS;
pub use pixel::{
    max_abs_error, mse_luma, mse_rgb, psnr_from_mse, psnr_luma, psnr_rgb, DATA_RANGE_8BIT,
};
pub use report::{diff, diff_at, diff_images, DiffReport};
pub use sequence::{
    diff_sequence_paths, diff_sequences, diff_sequences_with, load_sequence, load_sequence_images,
    SequenceReport,
};
pub use series::{series_stats, SeriesStats};
pub use srgb::{encode_srgb8, linear_to_srgb, srgb_to_linear};
pub use ssim::{ssim_luma, ssim_rgb, SSIM_MIN_SIZE};
pub use temporal::temporal_difference_error;
