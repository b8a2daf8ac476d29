//! Every metric of one reference/test pair at once, for `tessera diff` and `tessera run`, with
//! a JSON form (serde) and an aligned text form.
//!
//! For: bundling and presenting. Not for: computing anything itself (each number comes from its
//! own module) or judging it (gates live in the harness).
//!
//! JSON: infinite PSNR (identical images) is `null`; SSIM is `null` for images smaller than
//! 11x11 (one Gaussian window); the FLIP error map is left out.

use crate::{
    flip_ldr, max_abs_error, mse_luma, mse_rgb, psnr_from_mse, ssim_luma, ssim_rgb, FlipResult,
    MetricsError, Rgb8Image, DATA_RANGE_8BIT, DEFAULT_PIXELS_PER_DEGREE, SSIM_MIN_SIZE,
};
use serde::{Serialize, Serializer};
use std::fmt::Write;

/// All metrics of one pair of 8-bit sRGB images.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DiffReport {
    pub width: u32,
    pub height: u32,
    /// PSNR over RGB, dB; `f64::INFINITY` (JSON `null`) for identical images.
    #[serde(serialize_with = "finite_or_null")]
    pub psnr_rgb: f64,
    /// PSNR of BT.601 luma, dB; `f64::INFINITY` (JSON `null`) for identical images.
    #[serde(serialize_with = "finite_or_null")]
    pub psnr_luma: f64,
    /// MSE over RGB in 8-bit units (average these over frames, then `psnr_from_mse`).
    pub mse_rgb: f64,
    pub mse_luma: f64,
    /// SSIM (Wang 2004 settings), mean of R, G, B; `None` below 11x11 pixels.
    pub ssim_rgb: Option<f64>,
    /// SSIM of BT.601 luma; `None` below 11x11 pixels.
    pub ssim_luma: Option<f64>,
    /// Largest absolute channel difference, 0..=255.
    pub max_abs_error: u8,
    /// Pixels per degree the FLIP numbers were computed at.
    pub pixels_per_degree: f64,
    /// LDR-FLIP pooled statistics (the error map is not serialised).
    pub flip: FlipResult,
}

fn finite_or_null<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
    if v.is_finite() {
        s.serialize_f64(*v)
    } else {
        s.serialize_none()
    }
}

/// Computes every metric at [`DEFAULT_PIXELS_PER_DEGREE`].
pub fn diff(reference: &Rgb8Image, test: &Rgb8Image) -> Result<DiffReport, MetricsError> {
    diff_at(reference, test, DEFAULT_PIXELS_PER_DEGREE)
}

/// Computes every metric, FLIP at `pixels_per_degree`.
pub fn diff_at(
    reference: &Rgb8Image,
    test: &Rgb8Image,
    pixels_per_degree: f64,
) -> Result<DiffReport, MetricsError> {
    let big_enough = reference.width >= SSIM_MIN_SIZE && reference.height >= SSIM_MIN_SIZE;
    // FLIP is the largest job; the pixel metrics and SSIM run beside it.
    let (flip, rest) = rayon::join(
        || flip_ldr(reference, test, pixels_per_degree),
        || -> Result<_, MetricsError> {
            let mse_rgb = mse_rgb(reference, test)?;
            let mse_luma = mse_luma(reference, test)?;
            let max_abs = max_abs_error(reference, test)?;
            let (ssim_rgb, ssim_luma) = if big_enough {
                (
                    Some(ssim_rgb(reference, test)?),
                    Some(ssim_luma(reference, test)?),
                )
            } else {
                (None, None)
            };
            Ok((mse_rgb, mse_luma, max_abs, ssim_rgb, ssim_luma))
        },
    );
    let (mse_rgb, mse_luma, max_abs_error, ssim_rgb, ssim_luma) = rest?;
    Ok(DiffReport {
        width: reference.width,
        height: reference.height,
        psnr_rgb: psnr_from_mse(mse_rgb, DATA_RANGE_8BIT),
        psnr_luma: psnr_from_mse(mse_luma, DATA_RANGE_8BIT),
        mse_rgb,
        mse_luma,
        ssim_rgb,
        ssim_luma,
        max_abs_error,
        pixels_per_degree,
        flip: flip?,
    })
}

impl DiffReport {
    /// Aligned, human-readable lines, one metric per line.
    pub fn to_text(&self) -> String {
        let psnr = |v: f64| {
            if v.is_finite() {
                format!("{v:.3} dB")
            } else {
                "inf (identical)".to_owned()
            }
        };
        let ssim = |v: Option<f64>| match v {
            Some(v) => format!("{v:.6}"),
            None => format!("n/a (needs {SSIM_MIN_SIZE}x{SSIM_MIN_SIZE} pixels)"),
        };
        let f = &self.flip;
        let rows = [
            ("size", format!("{}x{}", self.width, self.height)),
            ("PSNR (RGB)", psnr(self.psnr_rgb)),
            ("PSNR (luma)", psnr(self.psnr_luma)),
            ("MSE (RGB)", format!("{:.4}", self.mse_rgb)),
            ("SSIM (RGB)", ssim(self.ssim_rgb)),
            ("SSIM (luma)", ssim(self.ssim_luma)),
            ("max |error|", format!("{} / 255", self.max_abs_error)),
            (
                "FLIP mean",
                format!("{:.6} at {} ppd", f.mean, self.pixels_per_degree),
            ),
            (
                "FLIP weighted",
                format!(
                    "p50 {:.6}  p95 {:.6}  p99 {:.6}  max {:.6}",
                    f.p50, f.p95, f.p99, f.max
                ),
            ),
        ];
        let mut s = String::new();
        for (label, value) in rows {
            let _ = writeln!(s, "{label:<14} {value}");
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_pair_report() {
        let a = Rgb8Image::filled(12, 12, [10, 20, 30]);
        let r = diff(&a, &a).unwrap();
        assert_eq!(r.psnr_rgb, f64::INFINITY);
        assert_eq!(r.ssim_rgb, Some(1.0));
        assert_eq!(r.flip.mean, 0.0);
        let json = serde_json::to_value(&r).unwrap();
        assert!(json["psnr_rgb"].is_null() && json["psnr_luma"].is_null());
        assert_eq!(json["ssim_rgb"], 1.0);
        assert!(json["flip"].get("error_map").is_none());
        assert_eq!(json["flip"]["mean"], 0.0);
        assert_eq!(
            r.to_text(),
            "size           12x12\n\
             PSNR (RGB)     inf (identical)\n\
             PSNR (luma)    inf (identical)\n\
             MSE (RGB)      0.0000\n\
             SSIM (RGB)     1.000000\n\
             SSIM (luma)    1.000000\n\
             max |error|    0 / 255\n\
             FLIP mean      0.000000 at 67 ppd\n\
             FLIP weighted  p50 0.000000  p95 0.000000  p99 0.000000  max 0.000000\n"
        );
    }

    #[test]
    fn tiny_images_have_no_ssim_but_the_rest() {
        let a = Rgb8Image::filled(3, 2, [0, 0, 0]);
        let b = Rgb8Image::filled(3, 2, [0, 0, 51]);
        let r = diff(&a, &b).unwrap();
        assert_eq!(r.ssim_rgb, None);
        assert_eq!(r.max_abs_error, 51);
        assert!((r.mse_rgb - 51.0 * 51.0 / 3.0).abs() < 1e-9);
        assert!(r.flip.mean > 0.0);
        assert!(serde_json::to_value(&r).unwrap()["ssim_luma"].is_null());
    }

    #[test]
    fn mismatch_is_an_error() {
        let a = Rgb8Image::filled(12, 12, [0; 3]);
        let b = Rgb8Image::filled(12, 13, [0; 3]);
        assert!(matches!(
            diff(&a, &b),
            Err(MetricsError::SizeMismatch { .. })
        ));
    }
}
