//! 16-bit sRGB-encoded images (16-bit PNG): PSNR and SSIM at their own precision, data range
//! 65535, with the same definitions as the 8-bit metrics (scikit-image's `data_range=65535`).
//!
//! For: comparing frames saved at 16 bits without first rounding them to 8. Not for: FLIP, whose
//! LDR input is 8-bit sRGB (`tessera diff` rounds 16-bit images to 8 bits for it).

use crate::luma::LUMA_WEIGHTS;
use crate::ssim::{check_size, ssim_plane};
use crate::{MetricsError, Rgb8Image};
use rayon::prelude::*;

/// Data range of 16-bit images.
pub const DATA_RANGE_16BIT: f64 = 65535.0;

/// A 16-bit sRGB-encoded RGB image, row-major, top row first, 3 values per pixel.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Rgb16Image {
    pub width: u32,
    pub height: u32,
    pub data: Vec<u16>,
}

impl Rgb16Image {
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Rounded to 8 bits, `round(v * 255 / 65535)`: what FLIP and PNG previews use.
    pub fn to_rgb8(&self) -> Rgb8Image {
        Rgb8Image {
            width: self.width,
            height: self.height,
            data: self
                .data
                .iter()
                .map(|&v| crate::io::round_16_to_8(v))
                .collect(),
        }
    }

    /// The exact 16-bit expansion of an 8-bit image (`v * 257`).
    pub fn from_rgb8(image: &Rgb8Image) -> Rgb16Image {
        Rgb16Image {
            width: image.width,
            height: image.height,
            data: image.data.iter().map(|&v| v as u16 * 257).collect(),
        }
    }
}

fn check(reference: &Rgb16Image, test: &Rgb16Image) -> Result<(), MetricsError> {
    crate::image::check_same_size(reference.width, reference.height, test.width, test.height)?;
    for img in [reference, test] {
        crate::image::check_layout(img.width, img.height, img.data.len())?;
    }
    Ok(())
}

/// Mean squared error over pixels and channels, in 16-bit units.
pub fn mse_rgb16(reference: &Rgb16Image, test: &Rgb16Image) -> Result<f64, MetricsError> {
    check(reference, test)?;
    let sum: f64 = reference
        .data
        .par_chunks(1 << 15)
        .zip(test.data.par_chunks(1 << 15))
        .map(|(r, t)| {
            // Exact: each square is below 2^32 and a chunk's sum below 2^47.
            r.iter()
                .zip(t)
                .map(|(&a, &b)| {
                    let d = a as i64 - b as i64;
                    (d * d) as u64
                })
                .sum::<u64>() as f64
        })
        .sum();
    Ok(sum / reference.data.len() as f64)
}

fn luma16(image: &Rgb16Image) -> Vec<f64> {
    image
        .data
        .par_chunks(3)
        .with_min_len(4096)
        .map(|p| {
            LUMA_WEIGHTS[0] * p[0] as f64
                + LUMA_WEIGHTS[1] * p[1] as f64
                + LUMA_WEIGHTS[2] * p[2] as f64
        })
        .collect()
}

/// Mean squared error of the BT.601 luma planes, in 16-bit units.
pub fn mse_luma16(reference: &Rgb16Image, test: &Rgb16Image) -> Result<f64, MetricsError> {
    check(reference, test)?;
    let (r, t) = (luma16(reference), luma16(test));
    Ok(r.iter()
        .zip(&t)
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        / r.len() as f64)
}

/// Mean of the per-channel SSIMs, data range 65535 (settings as `ssim_rgb`).
pub fn ssim_rgb16(reference: &Rgb16Image, test: &Rgb16Image) -> Result<f64, MetricsError> {
    check(reference, test)?;
    check_size(reference.width, reference.height)?;
    let (w, h) = (reference.width as usize, reference.height as usize);
    let plane = |img: &Rgb16Image, c: usize| -> Vec<f32> {
        img.data
            .iter()
            .skip(c)
            .step_by(3)
            .map(|&v| v as f32)
            .collect()
    };
    let mut sum = 0.0;
    for c in 0..3 {
        sum += ssim_plane(
            &plane(reference, c),
            &plane(test, c),
            w,
            h,
            DATA_RANGE_16BIT,
        );
    }
    Ok(sum / 3.0)
}

/// SSIM of the BT.601 luma planes, data range 65535.
pub fn ssim_luma16(reference: &Rgb16Image, test: &Rgb16Image) -> Result<f64, MetricsError> {
    check(reference, test)?;
    check_size(reference.width, reference.height)?;
    let (w, h) = (reference.width as usize, reference.height as usize);
    Ok(ssim_plane(
        &luma16(reference),
        &luma16(test),
        w,
        h,
        DATA_RANGE_16BIT,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pattern(w: u32, h: u32, seed: u32) -> Rgb8Image {
        let mut data = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let v = (x * 37 + y * 11 + seed * 7) ^ (x * y);
                data.extend_from_slice(&[
                    (v % 256) as u8,
                    ((v / 3) % 256) as u8,
                    ((x + seed) * 9 % 256) as u8,
                ]);
            }
        }
        Rgb8Image {
            width: w,
            height: h,
            data,
        }
    }

    /// Scaling values and data range by 257 changes no ratio: the 16-bit expansion of an 8-bit
    /// pair has the 8-bit pair's SSIM and PSNR (to rounding), so the data range is threaded
    /// through correctly.
    #[test]
    fn the_16_bit_expansion_of_an_8_bit_pair_has_its_ssim_and_psnr() {
        let (a, b) = (pattern(24, 17, 0), pattern(24, 17, 3));
        let (a16, b16) = (Rgb16Image::from_rgb8(&a), Rgb16Image::from_rgb8(&b));
        let s8 = crate::ssim_rgb(&a, &b).unwrap();
        let s16 = ssim_rgb16(&a16, &b16).unwrap();
        assert!((s8 - s16).abs() < 1e-12, "{s8} {s16}");
        assert!(s8 < 0.99, "the pair must differ: {s8}");
        let l8 = crate::ssim_luma(&a, &b).unwrap();
        let l16 = ssim_luma16(&a16, &b16).unwrap();
        assert!((l8 - l16).abs() < 1e-12, "{l8} {l16}");
        let p8 = crate::psnr_from_mse(crate::mse_rgb(&a, &b).unwrap(), 255.0);
        let p16 = crate::psnr_from_mse(mse_rgb16(&a16, &b16).unwrap(), DATA_RANGE_16BIT);
        assert!((p8 - p16).abs() < 1e-9, "{p8} {p16}");
        let q8 = crate::psnr_from_mse(crate::mse_luma(&a, &b).unwrap(), 255.0);
        let q16 = crate::psnr_from_mse(mse_luma16(&a16, &b16).unwrap(), DATA_RANGE_16BIT);
        assert!((q8 - q16).abs() < 1e-9, "{q8} {q16}");
    }

    /// Differences below one 8-bit step are seen at 16 bits and lost at 8.
    #[test]
    fn sub_8_bit_differences_count() {
        let a = Rgb16Image::from_rgb8(&pattern(16, 16, 1));
        let mut b = a.clone();
        for v in b.data.iter_mut().step_by(5) {
            *v = v.saturating_add(100);
        }
        assert_eq!(a.to_rgb8(), b.to_rgb8());
        let mse = mse_rgb16(&a, &b).unwrap();
        assert!(mse > 0.0);
        assert!(ssim_rgb16(&a, &b).unwrap() < 1.0);
        assert_eq!(ssim_rgb16(&a, &a).unwrap(), 1.0);
    }
}
