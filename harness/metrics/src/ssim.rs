//! Single-scale SSIM as Wang et al. 2004 define it (`ssim_index.m`), computed the way
//! scikit-image's `structural_similarity(..., gaussian_weights=True, sigma=1.5,
//! use_sample_covariance=False, data_range=255)` computes it.
//!
//! For: SSIM of 8-bit RGB (mean of per-channel SSIM) and of BT.601 luma. Not for: MS-SSIM, or
//! scikit-image's *default* settings (7x7 uniform window, sample covariance), which give
//! different numbers.
//!
//! Settings: an 11-tap Gaussian, sigma 1.5 (scipy's kernel: `exp(-x^2 / (2 sigma^2))`,
//! normalised to sum 1, radius `int(3.5 * 1.5 + 0.5) = 5`), K1 = 0.01, K2 = 0.03, L = 255,
//! population (co)variances `E[xy] - E[x]E[y]`, and the mean over the *valid* region: the
//! 5-pixel border that scikit-image crops is never computed, so no padding mode matters. All
//! arithmetic is f64, like scikit-image's.

use crate::image::check_pair;
use crate::luma::luma_plane;
use crate::{MetricsError, Rgb8Image};
use rayon::prelude::*;

/// Gaussian window radius: 11 taps.
pub(crate) const RADIUS: usize = 5;
pub(crate) const TAPS: usize = 2 * RADIUS + 1;
const SIGMA: f64 = 1.5;
pub(crate) const K1: f64 = 0.01;
pub(crate) const K2: f64 = 0.03;
const DATA_RANGE: f64 = 255.0;

/// The smallest width and height SSIM accepts (one full window).
pub const SSIM_MIN_SIZE: u32 = TAPS as u32;

/// Mean of the per-channel SSIMs of R, G and B (8-bit values, data range 255).
pub fn ssim_rgb(reference: &Rgb8Image, test: &Rgb8Image) -> Result<f64, MetricsError> {
    check_pair(reference, test)?;
    check_size(reference.width, reference.height)?;
    let mut sum = 0.0;
    for channel in 0..3 {
        let r = channel_plane(reference, channel);
        let t = channel_plane(test, channel);
        sum += ssim_plane(
            &r,
            &t,
            reference.width as usize,
            reference.height as usize,
            DATA_RANGE,
        );
    }
    Ok(sum / 3.0)
}

/// SSIM of the BT.601 luma planes (unrounded, data range 255; see the `luma` module).
pub fn ssim_luma(reference: &Rgb8Image, test: &Rgb8Image) -> Result<f64, MetricsError> {
    check_pair(reference, test)?;
    check_size(reference.width, reference.height)?;
    let r = luma_plane(reference);
    let t = luma_plane(test);
    Ok(ssim_plane(
        &r,
        &t,
        reference.width as usize,
        reference.height as usize,
        DATA_RANGE,
    ))
}

pub(crate) fn check_size(width: u32, height: u32) -> Result<(), MetricsError> {
    if width < SSIM_MIN_SIZE || height < SSIM_MIN_SIZE {
        return Err(MetricsError::TooSmall {
            metric: "SSIM",
            min: SSIM_MIN_SIZE,
            width,
            height,
        });
    }
    Ok(())
}

/// One channel as f32 (exact for 8-bit values, half the memory traffic of f64).
fn channel_plane(image: &Rgb8Image, channel: usize) -> Vec<f32> {
    image
        .data
        .par_chunks(3)
        .with_min_len(4096)
        .map(|p| p[channel] as f32)
        .collect()
}

/// scipy's `_gaussian_kernel1d(sigma, 0, radius)`.
pub(crate) fn gaussian_window() -> [f64; TAPS] {
    let mut w = [0.0; TAPS];
    let s2 = SIGMA * SIGMA;
    for (i, v) in w.iter_mut().enumerate() {
        let x = i as f64 - RADIUS as f64;
        *v = (-0.5 / s2 * (x * x)).exp();
    }
    let sum: f64 = w.iter().sum();
    for v in &mut w {
        *v /= sum;
    }
    w
}

/// Scratch rows for one output row: the five vertically filtered moments over all columns.
struct Rows {
    v: [Vec<f64>; 5],
}

/// Mean SSIM of two planes of `w * h` samples (both at least 11x11) over the valid region.
///
/// Each output row is filtered vertically first (11 input rows to one row of five moments),
/// then horizontally, so the working set stays in cache; rows run in parallel and their sums
/// are added in row order, so the result does not depend on the thread count.
pub(crate) fn ssim_plane<T>(x: &[T], y: &[T], w: usize, h: usize, data_range: f64) -> f64
where
    T: Copy + Into<f64> + Send + Sync,
{
    let g = gaussian_window();
    let out_w = w - 2 * RADIUS;
    let row_sums: Vec<f64> = (RADIUS..h - RADIUS)
        .into_par_iter()
        .map_init(
            || Rows {
                v: std::array::from_fn(|_| vec![0.0; w]),
            },
            |rows, row| row_sum(rows, x, y, w, row - RADIUS, &g, data_range),
        )
        .collect();
    row_sums.iter().sum::<f64>() / (out_w * (h - 2 * RADIUS)) as f64
}

/// SSIM summed over one output row, with AVX2 when the CPU has it (same arithmetic, no FMA).
fn row_sum<T: Copy + Into<f64>>(
    rows: &mut Rows,
    x: &[T],
    y: &[T],
    w: usize,
    top: usize,
    g: &[f64; TAPS],
    data_range: f64,
) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, checked just above.
        return unsafe { row_sum_avx2(rows, x, y, w, top, g, data_range) };
    }
    row_sum_generic(rows, x, y, w, top, g, data_range)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn row_sum_avx2<T: Copy + Into<f64>>(
    rows: &mut Rows,
    x: &[T],
    y: &[T],
    w: usize,
    top: usize,
    g: &[f64; TAPS],
    data_range: f64,
) -> f64 {
    row_sum_generic(rows, x, y, w, top, g, data_range)
}

#[inline(always)]
fn row_sum_generic<T: Copy + Into<f64>>(
    rows: &mut Rows,
    x: &[T],
    y: &[T],
    w: usize,
    top: usize,
    g: &[f64; TAPS],
    data_range: f64,
) -> f64 {
    let c1 = (K1 * data_range) * (K1 * data_range);
    let c2 = (K2 * data_range) * (K2 * data_range);
    let out_w = w - 2 * RADIUS;
    // Vertical 11-tap pass of x, y, x*x, y*y and x*y, all columns.
    let [mx, my, mxx, myy, mxy] = &mut rows.v;
    for v in [&mut *mx, &mut *my, &mut *mxx, &mut *myy, &mut *mxy] {
        v.fill(0.0);
    }
    for (k, &wk) in g.iter().enumerate() {
        let xr = &x[(top + k) * w..][..w];
        let yr = &y[(top + k) * w..][..w];
        for c in 0..w {
            let a: f64 = xr[c].into();
            let b: f64 = yr[c].into();
            mx[c] += wk * a;
            my[c] += wk * b;
            mxx[c] += wk * (a * a);
            myy[c] += wk * (b * b);
            mxy[c] += wk * (a * b);
        }
    }
    // Horizontal pass over the valid columns, accumulating in registers, and the SSIM terms.
    let mut sum = 0.0;
    for c in 0..out_w {
        let (mut ux, mut uy, mut uxx, mut uyy, mut uxy) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for (k, &wk) in g.iter().enumerate() {
            ux += wk * mx[c + k];
            uy += wk * my[c + k];
            uxx += wk * mxx[c + k];
            uyy += wk * myy[c + k];
            uxy += wk * mxy[c + k];
        }
        let vx = uxx - ux * ux;
        let vy = uyy - uy * uy;
        let vxy = uxy - ux * uy;
        let a1 = 2.0 * ux * uy + c1;
        let a2 = 2.0 * vxy + c2;
        let b1 = ux * ux + uy * uy + c1;
        let b2 = vx + vy + c2;
        sum += (a1 * a2) / (b1 * b2);
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gradient(w: u32, h: u32) -> Rgb8Image {
        let mut data = Vec::new();
        for y in 0..h {
            for x in 0..w {
                data.extend_from_slice(&[(x * 7 + y) as u8, (y * 5) as u8, ((x * y) % 251) as u8]);
            }
        }
        Rgb8Image {
            width: w,
            height: h,
            data,
        }
    }

    #[test]
    fn identical_images_give_exactly_one() {
        let a = gradient(40, 23);
        assert_eq!(ssim_rgb(&a, &a).unwrap(), 1.0);
        assert_eq!(ssim_luma(&a, &a).unwrap(), 1.0);
        let flat = Rgb8Image::filled(11, 11, [9, 200, 255]);
        assert_eq!(ssim_rgb(&flat, &flat).unwrap(), 1.0);
    }

    #[test]
    fn window_is_scipys() {
        let g = gaussian_window();
        assert!((g.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        // scipy.ndimage._filters._gaussian_kernel1d(1.5, 0, 5)[5]
        assert!((g[5] - 0.266_011_724_861_794_36).abs() < 1e-15, "{}", g[5]);
    }

    #[test]
    fn two_flat_images_hand_computed() {
        // 11x11 flat images: one valid window, zero variance, so SSIM is the luminance term
        // (2 * 100 * 110 + C1) / (100^2 + 110^2 + C1) with C1 = 2.55^2.
        let a = Rgb8Image::filled(11, 11, [100, 100, 100]);
        let b = Rgb8Image::filled(11, 11, [110, 110, 110]);
        let c1 = 2.55f64 * 2.55;
        let expected = (2.0 * 100.0 * 110.0 + c1) / (100.0f64 * 100.0 + 110.0 * 110.0 + c1);
        assert!((ssim_rgb(&a, &b).unwrap() - expected).abs() < 1e-12);
        assert!((ssim_luma(&a, &b).unwrap() - expected).abs() < 1e-12);
    }

    #[test]
    fn too_small_and_mismatched_are_errors() {
        let a = Rgb8Image::filled(10, 20, [0; 3]);
        assert!(matches!(
            ssim_rgb(&a, &a),
            Err(MetricsError::TooSmall { min: 11, .. })
        ));
        let b = Rgb8Image::filled(20, 20, [0; 3]);
        let c = Rgb8Image::filled(20, 21, [0; 3]);
        assert!(matches!(
            ssim_luma(&b, &c),
            Err(MetricsError::SizeMismatch { .. })
        ));
    }
}
