//! The constants, kernels and checks a second implementation of these metrics needs so that it
//! computes *the same* numbers: the WGSL port in `tessera-metrics-gpu` takes every weight, table
//! and threshold from here instead of restating them.
//!
//! For: sharing definitions with other back ends. Not for: computing a metric (call the metric
//! functions of this crate for that).

use crate::{ExposureRange, HdrImage, MetricsError, Rgb8Image};

/// SSIM: the 11-tap Gaussian window (sigma 1.5, scipy's kernel, sums to 1) and K1, K2.
pub fn ssim_window() -> [f64; 11] {
    crate::ssim::gaussian_window()
}
pub const SSIM_K1: f64 = crate::ssim::K1;
pub const SSIM_K2: f64 = crate::ssim::K2;
/// Rows and columns of border SSIM never computes (the window radius).
pub const SSIM_RADIUS: u32 = crate::ssim::RADIUS as u32;

/// SSIM's size check (`MetricsError::TooSmall` below 11x11).
pub fn ssim_check_size(width: u32, height: u32) -> Result<(), MetricsError> {
    crate::ssim::check_size(width, height)
}

/// FLIP's separated CSF kernels at `ppd`: Y, Cx, and Cz's two Gaussians, each `2r + 1` taps.
pub fn flip_spatial_kernels(ppd: f32) -> [Vec<f32>; 4] {
    let f = crate::flip::filters::spatial_filters(ppd);
    [f.y, f.cx, f.cz1, f.cz2]
}

/// FLIP's feature kernels at `ppd`: Gaussian, first and second derivative, `2r + 1` taps each.
pub fn flip_feature_kernels(ppd: f32) -> [Vec<f32>; 3] {
    let f = crate::flip::filters::feature_filters(ppd);
    [f.g, f.dg, f.ddg]
}

/// FLIP's `cmax` (HyAB^qc of Hunt-adjusted green vs blue) and the remap constants qc, pc, pt.
pub fn flip_cmax() -> f32 {
    crate::flip::color::max_distance()
}
pub const FLIP_QC: f32 = crate::flip::color::QC;
pub const FLIP_PC: f32 = crate::flip::color::PC;
pub const FLIP_PT: f32 = crate::flip::color::PT;

/// The pixels-per-degree check of `flip_ldr`/`flip_hdr`, returning the value as f32.
pub fn flip_check_ppd(ppd: f64) -> Result<f32, MetricsError> {
    crate::flip::check_ppd(ppd)
}

/// `FlipResult::mean` of an error map: the f32 running sum in row-major order over the count,
/// in f32, as flip-evaluator pools.
pub fn flip_running_mean(error_map: &[f32]) -> f64 {
    if error_map.is_empty() {
        return 0.0;
    }
    (crate::flip::pool::running_sum(error_map) / error_map.len() as f32) as f64
}

/// A [`crate::FlipResult`] from an error map computed elsewhere, pooled exactly as `flip_ldr`
/// pools its own (f32 running mean, weighted percentiles, max).
pub fn flip_result_from_map(error_map: Vec<f32>, width: u32, height: u32) -> crate::FlipResult {
    crate::FlipResult::from_map(error_map, width, height)
}

/// ACES (FLIP's default tone mapper, 0.6 pre-exposure cancellation):
/// `(c^2 t0 + c t1 + t2) / (c^2 t3 + c t4 + t5)`.
pub fn flip_aces() -> [f32; 6] {
    crate::flip::hdr::aces()
}

/// `2^exposure` for every exposure of `range`, as `flip_hdr` computes them.
pub fn flip_exposure_multipliers(range: &ExposureRange) -> Vec<f32> {
    crate::flip::hdr::exposure_multipliers(range)
}

/// `flip_hdr`'s input checks: same size, valid range, finite pixels.
pub fn flip_hdr_check(
    reference: &HdrImage,
    test: &HdrImage,
    range: &ExposureRange,
) -> Result<(), MetricsError> {
    crate::image::check_hdr_pair(reference, test)?;
    crate::flip::hdr::check_range(range)?;
    crate::flip::hdr::check_finite(reference, "reference")?;
    crate::flip::hdr::check_finite(test, "test")
}

/// The same-size and buffer-length checks every 8-bit pair metric runs.
pub fn check_pair(reference: &Rgb8Image, test: &Rgb8Image) -> Result<(), MetricsError> {
    crate::image::check_pair(reference, test)
}

/// FLIP's magma colour map as its tool writes it (`int(e * 255 + 0.5) % 256` indexes it).
pub const MAGMA: [[u8; 3]; 256] = crate::flip::magma::MAGMA_LUT;

/// The linear value of every 8-bit sRGB code, as FLIP decodes it.
pub fn srgb8_to_linear_table() -> [f32; 256] {
    crate::srgb::srgb8_to_linear_table()
}

/// For every code `k` in 1..=255, the smallest non-negative f32 that [`crate::encode_srgb8`]
/// encodes to `k` or more: a shader that counts the thresholds at or below a value encodes
/// exactly as the CPU does (the encoder is monotonic; checked over all f16 values by the GPU
/// crate's tests). Index 0 is 0.0.
pub fn srgb8_encode_thresholds() -> [f32; 256] {
    let encode = crate::srgb::encode_srgb8_value;
    let mut t = [0.0f32; 256];
    for (k, slot) in t.iter_mut().enumerate().skip(1) {
        // Binary search over the bit patterns of [0, 1], which order like the values.
        let (mut lo, mut hi) = (0u32, 1.0f32.to_bits());
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            if encode(f32::from_bits(mid)) >= k as u8 {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        *slot = f32::from_bits(lo);
    }
    t
}
