//! Pixel-wise error metrics: MSE, PSNR and the largest absolute difference.
//!
//! For: the metrics that compare each value with its counterpart and nothing else. Not for:
//! windowed or perceptual metrics (see `ssim` and `flip`).
//!
//! PSNR follows scikit-image's `peak_signal_noise_ratio`: `10 log10(range^2 / MSE)` with the MSE
//! over all pixels *and* channels, computed in f64.

use crate::image::check_pair;
use crate::luma::luma_plane;
use crate::{MetricsError, Rgb8Image};
use rayon::prelude::*;

/// Data range of 8-bit images.
pub const DATA_RANGE_8BIT: f64 = 255.0;

/// Rows per parallel job: large enough that scheduling is cheap, small enough for two cores.
const CHUNK: usize = 1 << 15;

/// Mean squared error over pixels and channels in 8-bit units.
pub fn mse_rgb(reference: &Rgb8Image, test: &Rgb8Image) -> Result<f64, MetricsError> {
    check_pair(reference, test)?;
    // Integer sums are exact: a chunk of 2^15 values sums to at most 2^15 * 255^2 < 2^32.
    let sum: u64 = reference
        .data
        .par_chunks(CHUNK)
        .zip(test.data.par_chunks(CHUNK))
        .map(|(r, t)| {
            r.iter()
                .zip(t)
                .map(|(&a, &b)| {
                    let d = a as i32 - b as i32;
                    (d * d) as u64
                })
                .sum::<u64>()
        })
        .sum();
    Ok(sum as f64 / reference.data.len() as f64)
}

/// Mean squared error of the BT.601 luma planes (see `luma`), in 8-bit units.
pub fn mse_luma(reference: &Rgb8Image, test: &Rgb8Image) -> Result<f64, MetricsError> {
    check_pair(reference, test)?;
    let r = luma_plane(reference);
    let t = luma_plane(test);
    let sum: f64 = r
        .par_chunks(CHUNK)
        .zip(t.par_chunks(CHUNK))
        .map(|(r, t)| r.iter().zip(t).map(|(a, b)| (a - b) * (a - b)).sum::<f64>())
        .sum();
    Ok(sum / r.len() as f64)
}

/// PSNR in dB from a mean squared error: `10 log10(range^2 / mse)`. `mse == 0` gives
/// `f64::INFINITY`.
pub fn psnr_from_mse(mse: f64, data_range: f64) -> f64 {
    if mse == 0.0 {
        return f64::INFINITY;
    }
    10.0 * (data_range * data_range / mse).log10()
}

/// PSNR over all pixels and channels, data range 255. Identical images give `f64::INFINITY`.
pub fn psnr_rgb(reference: &Rgb8Image, test: &Rgb8Image) -> Result<f64, MetricsError> {
    Ok(psnr_from_mse(mse_rgb(reference, test)?, DATA_RANGE_8BIT))
}

/// PSNR of the BT.601 luma planes, data range 255. Identical images give `f64::INFINITY`.
pub fn psnr_luma(reference: &Rgb8Image, test: &Rgb8Image) -> Result<f64, MetricsError> {
    Ok(psnr_from_mse(mse_luma(reference, test)?, DATA_RANGE_8BIT))
}

/// Largest absolute difference of any channel of any pixel, in 8-bit units.
pub fn max_abs_error(reference: &Rgb8Image, test: &Rgb8Image) -> Result<u8, MetricsError> {
    check_pair(reference, test)?;
    Ok(reference
        .data
        .par_chunks(CHUNK)
        .zip(test.data.par_chunks(CHUNK))
        .map(|(r, t)| {
            r.iter()
                .zip(t)
                .map(|(&a, &b)| a.abs_diff(b))
                .max()
                .unwrap_or(0)
        })
        .max()
        .unwrap_or(0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(w: u32, h: u32, data: Vec<u8>) -> Rgb8Image {
        Rgb8Image {
            width: w,
            height: h,
            data,
        }
    }

    #[test]
    fn identical_images_give_infinite_psnr_and_zero_errors() {
        let a = img(2, 1, vec![1, 2, 3, 250, 128, 0]);
        assert_eq!(mse_rgb(&a, &a).unwrap(), 0.0);
        assert_eq!(psnr_rgb(&a, &a).unwrap(), f64::INFINITY);
        assert_eq!(psnr_luma(&a, &a).unwrap(), f64::INFINITY);
        assert_eq!(max_abs_error(&a, &a).unwrap(), 0);
    }

    #[test]
    fn hand_computed_two_pixel_example() {
        let a = img(2, 1, vec![0, 0, 0, 100, 100, 100]);
        let b = img(2, 1, vec![10, 0, 0, 100, 100, 97]);
        // squared errors 100 + 9 over 6 values
        let mse = mse_rgb(&a, &b).unwrap();
        assert_eq!(mse, 109.0 / 6.0);
        let psnr = psnr_rgb(&a, &b).unwrap();
        assert!((psnr - 10.0 * (255.0f64 * 255.0 * 6.0 / 109.0).log10()).abs() < 1e-12);
        assert_eq!(max_abs_error(&a, &b).unwrap(), 10);
        // luma differences: 0.299*10 = 2.99 and 0.114*3 = 0.342
        let ml = mse_luma(&a, &b).unwrap();
        assert!((ml - (2.99f64.powi(2) + 0.342f64.powi(2)) / 2.0).abs() < 1e-12);
    }

    #[test]
    fn black_vs_white_is_zero_db() {
        let a = Rgb8Image::filled(3, 2, [0, 0, 0]);
        let b = Rgb8Image::filled(3, 2, [255, 255, 255]);
        assert_eq!(psnr_rgb(&a, &b).unwrap(), 0.0);
        assert_eq!(max_abs_error(&a, &b).unwrap(), 255);
    }

    #[test]
    fn size_mismatch_is_an_error() {
        let a = Rgb8Image::filled(3, 2, [0, 0, 0]);
        let b = Rgb8Image::filled(2, 3, [0, 0, 0]);
        let e = psnr_rgb(&a, &b).unwrap_err();
        assert!(matches!(e, MetricsError::SizeMismatch { .. }), "{e}");
        assert_eq!(
            e.to_string(),
            "image sizes differ: reference is 3x2, test is 2x3; both images of a comparison must \
             have the same size"
        );
        assert!(max_abs_error(&a, &b).is_err());
        assert!(psnr_luma(&a, &b).is_err());
    }

    #[test]
    fn bad_buffers_are_errors_not_panics() {
        let a = img(2, 2, vec![0; 11]);
        assert!(matches!(
            mse_rgb(&a, &a),
            Err(MetricsError::BadBufferLength { .. })
        ));
        let e = img(0, 5, vec![]);
        assert!(matches!(
            mse_rgb(&e, &e),
            Err(MetricsError::EmptyImage { .. })
        ));
    }

    #[test]
    fn psnr_from_mse_matches_definition() {
        assert_eq!(psnr_from_mse(0.0, 255.0), f64::INFINITY);
        assert!((psnr_from_mse(1.0, 1.0) - 0.0).abs() < 1e-15);
        assert!((psnr_from_mse(65.025, 255.0) - 30.0).abs() < 1e-12);
    }
}
