//! NVIDIA FLIP (LDR-FLIP and HDR-FLIP), reimplemented from `FLIP.h` of flip-evaluator 1.7.
//!
//! For: the FLIP error map of a reference/test pair, its pooled statistics and its magma
//! heatmap. Not for: deciding pass/fail (the harness's gates read [`FlipResult`]).
//!
//! Layout: `color` (colour spaces), `filters` (kernels), `ldr` (the error map), `hdr` (exposure
//! range, tone mapping, maximum over exposures), `pool` (mean and weighted percentiles),
//! `magma` (the heatmap LUT).

pub(crate) mod color;
mod fastmath;
pub(crate) mod filters;
pub(crate) mod hdr;
mod ldr;
pub(crate) mod magma;
pub(crate) mod pool;

pub use hdr::{hdr_exposure_range, ExposureRange, MAX_EXPOSURES};

use crate::image::check_pair;
use crate::srgb::srgb8_to_linear_table;
use crate::{HdrImage, MetricsError, Rgb8Image};
use rayon::prelude::*;
use serde::Serialize;

/// Pixels per degree used when a caller has no viewing condition of its own: 67.0, nv-flip's
/// `DEFAULT_PIXELS_PER_DEGREE` (the value wgpu's FLIP thresholds were set with).
/// flip-evaluator's own default is `pixels_per_degree(0.7, 3840.0, 0.7)` = 67.0206; at both
/// values the kernels have the same radii (10 and 9 pixels) and pooled results differ by a few
/// 1e-5 at most.
pub const DEFAULT_PIXELS_PER_DEGREE: f64 = 67.0;

/// FLIP's viewing condition to pixels per degree: `distance * (resolution_x / width) * pi /
/// 180`, in f32 as FLIP computes it (`pixels_per_degree(0.7, 3840.0, 0.7)` is flip-evaluator's
/// default, 67.0206).
pub fn pixels_per_degree(distance_m: f64, resolution_x: f64, monitor_width_m: f64) -> f64 {
    #[allow(clippy::excessive_precision, clippy::approx_constant)]
    const PI: f32 = 3.14159265358979;
    let (d, r, w) = (
        distance_m as f32,
        resolution_x as f32,
        monitor_width_m as f32,
    );
    (d * (r / w) * (PI / 180.0f32)) as f64
}

/// A FLIP error map and its pooled statistics.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FlipResult {
    /// Mean of the error map (the value FLIP's authors recommend reporting), accumulated in f32
    /// as flip-evaluator and nv-flip do (see `exact_mean`).
    pub mean: f64,
    /// Mean accumulated in f64; differs from `mean` by up to ~3e-3 on a 1080p map with large
    /// errors, and by less than 1e-6 on typical ones.
    pub exact_mean: f64,
    /// Weighted percentiles, as `FlipPool::getPercentile(p, weighted = true)`.
    pub p50: f64,
    pub p95: f64,
    pub p99: f64,
    /// Largest per-pixel error.
    pub max: f64,
    /// Per-pixel error in [0,1], row-major, `width * height` values.
    #[serde(skip)]
    pub error_map: Vec<f32>,
    pub width: u32,
    pub height: u32,
}

impl FlipResult {
    pub(crate) fn from_map(error_map: Vec<f32>, width: u32, height: u32) -> Self {
        let pooled = pool::pool(&error_map, &[0.5, 0.95, 0.99]);
        FlipResult {
            mean: pooled.mean,
            exact_mean: pooled.exact_mean,
            p50: pooled.percentiles[0],
            p95: pooled.percentiles[1],
            p99: pooled.percentiles[2],
            max: pooled.max,
            error_map,
            width,
            height,
        }
    }

    /// Weighted percentile `p` in [0,1] of the error map (same definition as `p50`..`p99`).
    pub fn weighted_percentile(&self, p: f64) -> f64 {
        pool::pool(&self.error_map, &[p]).percentiles[0]
    }
}

pub(crate) fn check_ppd(ppd: f64) -> Result<f32, MetricsError> {
    // The upper bound keeps the kernels (radius ~0.14 * ppd) a sane size.
    if !(ppd.is_finite() && ppd > 0.0 && ppd <= 10_000.0) {
        return Err(MetricsError::InvalidParameter {
            name: "pixels_per_degree",
            value: ppd,
            expected: "a finite number in (0, 10000]",
        });
    }
    Ok(ppd as f32)
}

/// LDR-FLIP of two sRGB-encoded 8-bit images at `pixels_per_degree`.
///
/// Identical images give an all-zero map (mean, percentiles and max 0).
pub fn flip_ldr(
    reference: &Rgb8Image,
    test: &Rgb8Image,
    pixels_per_degree: f64,
) -> Result<FlipResult, MetricsError> {
    check_pair(reference, test)?;
    let ppd = check_ppd(pixels_per_degree)?;
    let table = srgb8_to_linear_table();
    let (w, h) = (reference.width, reference.height);
    let map = ldr::ldr_flip_map(
        ldr::Source::Srgb8(&reference.data, &table),
        ldr::Source::Srgb8(&test.data, &table),
        w as usize,
        h as usize,
        ppd,
    );
    Ok(FlipResult::from_map(map, w, h))
}

/// HDR-FLIP of two linear RGB images over the exposures of `range` (compute it once per
/// reference with [`hdr_exposure_range`] and reuse it for every test image).
pub fn flip_hdr(
    reference: &HdrImage,
    test: &HdrImage,
    range: &ExposureRange,
    pixels_per_degree: f64,
) -> Result<FlipResult, MetricsError> {
    let ppd = check_ppd(pixels_per_degree)?;
    let map = hdr::hdr_flip_map(reference, test, range, ppd)?;
    Ok(FlipResult::from_map(map, reference.width, reference.height))
}

/// The error map through FLIP's magma colour map, as FLIP's tool writes it to PNG.
pub fn flip_heatmap(result: &FlipResult) -> Rgb8Image {
    let data = result
        .error_map
        .par_iter()
        .with_min_len(8192)
        .flat_map_iter(|&e| {
            // FLIP: colorMap.get(int(v * 255 + 0.5) % 256); `as` saturates NaN to 0.
            let i = (e * 255.0f32 + 0.5f32) as i32;
            magma::MAGMA_LUT[i.rem_euclid(256) as usize]
        })
        .collect();
    Rgb8Image {
        width: result.width,
        height: result.height,
        data,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pattern(w: u32, h: u32, seed: u32) -> Rgb8Image {
        let mut s = seed;
        let mut data = Vec::new();
        for y in 0..h {
            for x in 0..w {
                s = s.wrapping_mul(1664525).wrapping_add(1013904223);
                let noise = s >> 27;
                data.push(((x * 255) / w + noise) as u8);
                data.push(((y * 255) / h) as u8);
                data.push(if (x / 4 + y / 4) % 2 == 0 { 200 } else { 30 });
            }
        }
        Rgb8Image {
            width: w,
            height: h,
            data,
        }
    }

    #[test]
    fn identical_images_give_zero() {
        let a = pattern(37, 23, 1);
        let r = flip_ldr(&a, &a, DEFAULT_PIXELS_PER_DEGREE).unwrap();
        assert!(r.error_map.iter().all(|&e| e == 0.0));
        assert_eq!(
            (r.mean, r.p50, r.p95, r.p99, r.max),
            (0.0, 0.0, 0.0, 0.0, 0.0)
        );
        let hm = flip_heatmap(&r);
        assert_eq!(&hm.data[..3], &[0, 0, 4]);
    }

    #[test]
    fn black_vs_white_is_the_maximum_colour_error() {
        // Flat images: no features, so the error is the remapped colour difference
        // HyAB(white, black)^0.7 = 100^0.7 = 25.1, above pc * cmax (cmax = 41.1), so it lands
        // in (0.95, 1]: 0.95 + (25.1 - 0.4 cmax) / (0.6 cmax) * 0.05.
        let a = Rgb8Image::filled(16, 16, [0, 0, 0]);
        let b = Rgb8Image::filled(16, 16, [255, 255, 255]);
        let r = flip_ldr(&a, &b, DEFAULT_PIXELS_PER_DEGREE).unwrap();
        let cmax = color::max_distance() as f64;
        let cd = 100f64.powf(0.7);
        let expected = 0.95 + (cd - 0.4 * cmax) / (0.6 * cmax) * 0.05;
        assert!((r.mean - expected).abs() < 1e-4, "{} vs {expected}", r.mean);
        assert!((r.max - expected).abs() < 1e-4);
    }

    #[test]
    fn errors_are_in_unit_range_and_symmetric_in_size() {
        let a = pattern(40, 30, 1);
        let b = pattern(40, 30, 2);
        let r = flip_ldr(&a, &b, 40.0).unwrap();
        assert!(r.error_map.iter().all(|e| (0.0..=1.0).contains(e)));
        assert!(r.mean > 0.0 && r.p50 <= r.p95 && r.p95 <= r.p99 && r.p99 <= r.max);
        assert_eq!(r.error_map.len(), 1200);
    }

    #[test]
    fn bad_inputs_are_errors() {
        let a = pattern(8, 8, 1);
        let b = pattern(8, 9, 1);
        assert!(matches!(
            flip_ldr(&a, &b, 67.0),
            Err(MetricsError::SizeMismatch { .. })
        ));
        for ppd in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                flip_ldr(&a, &a, ppd),
                Err(MetricsError::InvalidParameter { .. })
            ));
        }
        let one = pattern(1, 1, 3);
        assert!(flip_ldr(&one, &pattern(1, 1, 4), 67.0).is_ok());
    }

    #[test]
    fn ppd_of_flip_evaluators_viewing_condition() {
        assert!((pixels_per_degree(0.7, 3840.0, 0.7) - 67.0206).abs() < 1e-4);
    }

    #[test]
    fn hdr_identical_is_zero_and_nan_is_an_error() {
        let a = HdrImage {
            width: 8,
            height: 8,
            data: (0..192).map(|i| i as f32 * 0.1).collect(),
        };
        let range = hdr_exposure_range(&a);
        let r = flip_hdr(&a, &a, &range, 67.0).unwrap();
        assert_eq!(r.max, 0.0);
        let mut b = a.clone();
        b.data[5] = f32::NAN;
        assert!(matches!(
            flip_hdr(&a, &b, &range, 67.0),
            Err(MetricsError::NonFinite { count: 1, .. })
        ));
        let bad = ExposureRange {
            start: 1.0,
            stop: 0.0,
            count: 2,
        };
        assert!(flip_hdr(&a, &a, &bad, 67.0).is_err());
    }
}
