//! `tessera diff --gpu`: the same [`DiffReport`] as `tessera_metrics::diff_images`, with PSNR,
//! MSE, max-abs, SSIM and FLIP's error map computed on the device; the map is read back and
//! pooled by the CPU's own pooling, so FLIP's mean and weighted percentiles are defined exactly
//! as on the CPU.
//!
//! For: image pairs and, through `tessera_metrics::diff_sequences_with`, sequences. Not for:
//! 16-bit PNG pairs' 16-bit metrics (8-bit only on the GPU: those pairs use the CPU report) or
//! ColorVideoVDP (CPU).

use tessera_metrics::{
    hdr_exposure_range, psnr_from_mse, DiffReport, LoadedImage, Rgb8Image, DATA_RANGE_8BIT,
    DEFAULT_PIXELS_PER_DEGREE,
};

use crate::context::GpuMetrics;
use crate::error::GpuMetricsError;
use crate::pair::{FlipHdrRequest, FlipPooling, FlipRequest, PairRequest};

/// [`DiffReport`] of two decoded files on the GPU (16-bit PNG pairs and mixed kinds: the CPU's
/// report or error).
pub fn diff_images(
    gpu: &mut GpuMetrics,
    reference: &LoadedImage,
    test: &LoadedImage,
) -> Result<DiffReport, GpuMetricsError> {
    use LoadedImage::{Hdr, Ldr};
    match (reference, test) {
        (Ldr(r), Ldr(t)) => diff_ldr(gpu, r, t, None),
        (Hdr(r), Hdr(t)) => {
            let (rl, tl) = (
                tessera_metrics::encode_srgb8(r),
                tessera_metrics::encode_srgb8(t),
            );
            diff_ldr(gpu, &rl, &tl, Some((r, t)))
        }
        _ => Ok(tessera_metrics::diff_images(reference, test)?),
    }
}

fn diff_ldr(
    gpu: &mut GpuMetrics,
    r: &Rgb8Image,
    t: &Rgb8Image,
    hdr: Option<(&tessera_metrics::HdrImage, &tessera_metrics::HdrImage)>,
) -> Result<DiffReport, GpuMetricsError> {
    tessera_metrics::port::check_pair(r, t)?;
    let big_enough =
        r.width >= tessera_metrics::SSIM_MIN_SIZE && r.height >= tessera_metrics::SSIM_MIN_SIZE;
    let ppd = DEFAULT_PIXELS_PER_DEGREE;
    let range = hdr.map(|(rh, _)| hdr_exposure_range(rh));
    if let (Some((rh, th)), Some(range)) = (hdr, &range) {
        tessera_metrics::port::flip_hdr_check(rh, th, range)?;
    }
    let request = PairRequest {
        mse_rgb: true,
        mse_luma: true,
        max_abs: true,
        ssim_rgb: big_enough,
        ssim_luma: big_enough,
        flip: Some(FlipRequest {
            pixels_per_degree: ppd,
            heatmap: false,
            pooling: FlipPooling::ErrorMap,
        }),
        flip_hdr: range.map(|range| FlipHdrRequest {
            range,
            pixels_per_degree: ppd,
            heatmap: false,
            pooling: FlipPooling::ErrorMap,
        }),
    };
    let rf = gpu.upload(r, hdr.map(|h| h.0))?;
    let tf = gpu.upload(t, hdr.map(|h| h.1))?;
    let v = gpu.evaluate(&rf, &tf, &request)?;
    let result = |f: Option<crate::pair::FlipValues>| {
        f.and_then(|f| f.error_map)
            .map(|m| tessera_metrics::port::flip_result_from_map(m, r.width, r.height))
            .ok_or_else(|| GpuMetricsError::Readback("FLIP error map missing".into()))
    };
    let mse_rgb = v.mse_rgb.unwrap_or_default();
    let mse_luma = v.mse_luma.unwrap_or_default();
    Ok(DiffReport {
        width: r.width,
        height: r.height,
        psnr_rgb: psnr_from_mse(mse_rgb, DATA_RANGE_8BIT),
        psnr_luma: psnr_from_mse(mse_luma, DATA_RANGE_8BIT),
        mse_rgb,
        mse_luma,
        ssim_rgb: v.ssim_rgb,
        ssim_luma: v.ssim_luma,
        max_abs_error: v.max_abs.unwrap_or_default(),
        pixels_per_degree: ppd,
        flip: result(v.flip)?,
        bit_depth: 8,
        flip_hdr: match v.flip_hdr {
            Some(f) => Some(result(Some(f))?),
            None => None,
        },
        exposure_range: range,
    })
}
