//! Every metric of one reference/test pair at once, for `tessera diff` and `tessera run`, with
//! a JSON form (serde) and an aligned text form.
//!
//! For: bundling and presenting. Not for: computing anything itself (each number comes from its
//! own module) or judging it (gates live in the harness).
//!
//! JSON: infinite PSNR (identical images) is `null`; SSIM is `null` for images smaller than
//! 11x11 (one Gaussian window); the FLIP error map is left out.

use crate::{
    encode_srgb8, flip_hdr, flip_ldr, hdr_exposure_range, max_abs_error, mse_luma, mse_luma16,
    mse_rgb, mse_rgb16, psnr_from_mse, ssim_luma, ssim_luma16, ssim_rgb, ssim_rgb16, ExposureRange,
    FlipResult, LoadedImage, MetricsError, Rgb16Image, Rgb8Image, DATA_RANGE_16BIT,
    DATA_RANGE_8BIT, DEFAULT_PIXELS_PER_DEGREE, SSIM_MIN_SIZE,
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
    /// Bits per channel of PSNR, MSE and SSIM: 8, or 16 when both inputs are 16-bit PNGs (data
    /// range 65535; an 8-bit input beside a 16-bit one is expanded exactly, `v * 257`). FLIP and
    /// max |error| always use the 8-bit values.
    pub bit_depth: u8,
    /// HDR-FLIP of linear inputs (`.hdr`, `.exr`), with the exposure range from the reference;
    /// absent for PNG. The other metrics then use the sRGB encoding of the inputs (clamped).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub flip_hdr: Option<FlipResult>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub exposure_range: Option<ExposureRange>,
}

/// Every metric of two decoded files: 8-bit or 16-bit PNG, or linear HDR (both of one kind).
pub fn diff_images(
    reference: &LoadedImage,
    test: &LoadedImage,
) -> Result<DiffReport, MetricsError> {
    use LoadedImage::{Hdr, Ldr, Ldr16};
    match (reference, test) {
        (Ldr(r), Ldr(t)) => diff(r, t),
        (Hdr(r), Hdr(t)) => {
            let mut report = diff(&encode_srgb8(r), &encode_srgb8(t))?;
            let range = hdr_exposure_range(r);
            report.flip_hdr = Some(flip_hdr(r, t, &range, DEFAULT_PIXELS_PER_DEGREE)?);
            report.exposure_range = Some(range);
            Ok(report)
        }
        (Ldr16(_) | Ldr(_), Ldr16(_) | Ldr(_)) => {
            let deep = |i: &LoadedImage| match i {
                Ldr16(i) => i.clone(),
                Ldr(i) => Rgb16Image::from_rgb8(i),
                Hdr(_) => unreachable!("matched above"),
            };
            let (r, t) = (deep(reference), deep(test));
            let mut report = diff(&r.to_rgb8(), &t.to_rgb8())?;
            report.bit_depth = 16;
            report.mse_rgb = mse_rgb16(&r, &t)?;
            report.mse_luma = mse_luma16(&r, &t)?;
            report.psnr_rgb = psnr_from_mse(report.mse_rgb, DATA_RANGE_16BIT);
            report.psnr_luma = psnr_from_mse(report.mse_luma, DATA_RANGE_16BIT);
            if report.ssim_rgb.is_some() {
                report.ssim_rgb = Some(ssim_rgb16(&r, &t)?);
                report.ssim_luma = Some(ssim_luma16(&r, &t)?);
            }
            Ok(report)
        }
        (r, t) => Err(MetricsError::KindMismatch {
            reference: r.kind(),
            test: t.kind(),
        }),
    }
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
        bit_depth: 8,
        flip_hdr: None,
        exposure_range: None,
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
        if self.bit_depth != 8 {
            let _ = writeln!(
                s,
                "{:<14} PSNR, MSE and SSIM at {} bits (data range 65535)",
                "bit depth", self.bit_depth
            );
        }
        if let (Some(f), Some(r)) = (&self.flip_hdr, &self.exposure_range) {
            let _ = writeln!(
                s,
                "{:<14} {:.6} (exposures {:.3} to {:.3} stops, {} steps)",
                "HDR-FLIP mean", f.mean, r.start, r.stop, r.count
            );
            let _ = writeln!(
                s,
                "{:<14} p50 {:.6}  p95 {:.6}  p99 {:.6}  max {:.6}",
                "HDR-FLIP wtd", f.p50, f.p95, f.p99, f.max
            );
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
