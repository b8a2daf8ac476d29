//! HDR-FLIP: the exposure range from a reference, ACES tone mapping, and the per-pixel maximum
//! of LDR-FLIP over exposures.
//!
//! For: `hdr_exposure_range` and `flip_hdr`. Not for: the LDR-FLIP map itself (see `ldr`).
//!
//! As `FLIP.h`'s `computeExposures` and `evaluate(useHDR = true)` with the default ACES tone
//! mapper (0.6 pre-exposure cancellation), in f32:
//! * `x_max` solves `aces(x) = 0.85`; luminance is `0.2126 R + 0.7152 G + 0.0722 B`;
//! * `start = log2(x_max / Y_max)`, `stop = log2(x_max / Y_median)` with the median at index
//!   `n / 2` of the sorted luminances; `count = max(2, ceil(stop - start))`;
//! * exposure `i` is `start + i * (stop - start) / (count - 1)`; both images are multiplied by
//!   `2^exposure`, tone mapped, clamped to [0,1] and compared with LDR-FLIP; the error map is
//!   the per-pixel maximum over exposures.
//!
//! Degenerate references (documented choices, where FLIP itself misbehaves):
//! * median luminance 0 (more than half the pixels black): floored at `f32::EPSILON`, exactly
//!   as flip-evaluator 1.7 does. `stop` becomes about `log2(0.78 / 1.19e-7) = 22.6`, so many
//!   exposures are evaluated (cost grows with `count`); pass a fixed [`ExposureRange`] instead
//!   when that matters (NVlabs/flip#42).
//! * maximum luminance <= 0 (an all-black reference): also floored at `f32::EPSILON`, so
//!   `start = stop` and `count = 2`. flip-evaluator exits with "Start exposure must be smaller
//!   than stop exposure" here.
//! * non-finite pixels are left out of the range computation (`flip_hdr` refuses them).

use super::ldr::{ldr_flip_map, Source};
use crate::MetricsError;
use crate::{image::check_hdr_pair, HdrImage};
use rayon::prelude::*;

/// The most exposures `flip_hdr` accepts (a guard against ranges that would run for hours).
pub const MAX_EXPOSURES: u32 = 256;

/// The exposures HDR-FLIP evaluates: `count` stops from `start` to `stop` (in log2 units).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ExposureRange {
    pub start: f64,
    pub stop: f64,
    pub count: u32,
}

/// ACES (Narkowicz fit) with FLIP's 0.6 pre-exposure cancellation: numerator and denominator
/// coefficients of `(c^2 t0 + c t1 + t2) / (c^2 t3 + c t4 + t5)`.
pub(crate) fn aces() -> [f32; 6] {
    [
        0.6f32 * 0.6f32 * 2.51f32,
        0.6f32 * 0.03f32,
        0.0,
        0.6f32 * 0.6f32 * 2.43f32,
        0.6f32 * 0.59f32,
        0.14,
    ]
}

/// The input value that ACES maps to 0.85.
fn x_max() -> f32 {
    let tc = aces();
    let t = 0.85f32;
    let a = tc[0] - t * tc[3];
    let b = tc[1] - t * tc[4];
    let c = tc[2] - t * tc[5];
    if a == 0.0 {
        return -c / b;
    }
    let d1 = -0.5f32 * (b / a);
    let d2 = (d1 * d1 - c / a).sqrt();
    d1 + d2
}

fn luminance(p: &[f32]) -> f32 {
    0.2126f32 * p[0] + 0.7152f32 * p[1] + 0.0722f32 * p[2]
}

/// The exposure range FLIP derives from a reference (see the module doc for zero and
/// non-finite luminance). Hold it fixed for every test image diffed against one reference.
pub fn hdr_exposure_range(reference: &HdrImage) -> ExposureRange {
    let mut lum: Vec<f32> = reference
        .data
        .par_chunks_exact(3)
        .with_min_len(4096)
        .map(luminance)
        .filter(|l| l.is_finite())
        .collect();
    let (y_max, y_median) = if lum.is_empty() {
        (0.0, 0.0)
    } else {
        let max = lum.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        let mid = lum.len() / 2;
        let (_, median, _) = lum.select_nth_unstable_by(mid, f32::total_cmp);
        (max, *median)
    };
    let y_max = y_max.max(f32::EPSILON);
    let y_median = y_median.max(f32::EPSILON);
    let xm = x_max();
    let start = (xm / y_max).log2();
    let stop = (xm / y_median).log2();
    let count = 2.0f32.max((stop - start).ceil()) as u32;
    ExposureRange {
        start: start as f64,
        stop: stop as f64,
        count,
    }
}

pub(crate) fn check_range(range: &ExposureRange) -> Result<(), MetricsError> {
    if !range.start.is_finite() || !range.stop.is_finite() || range.start > range.stop {
        return Err(MetricsError::InvalidParameter {
            name: "exposure range",
            value: range.start,
            expected: "finite start <= stop",
        });
    }
    if range.count == 0 || range.count > MAX_EXPOSURES {
        return Err(MetricsError::InvalidParameter {
            name: "exposure count",
            value: range.count as f64,
            expected: "1 ..= 256 exposures",
        });
    }
    Ok(())
}

pub(crate) fn check_finite(image: &HdrImage, which: &'static str) -> Result<(), MetricsError> {
    let count = image.data.par_iter().filter(|v| !v.is_finite()).count();
    if count > 0 {
        return Err(MetricsError::NonFinite {
            image: which,
            count,
        });
    }
    Ok(())
}

/// The factor `2^exposure` each image is multiplied by before tone mapping, one per exposure of
/// `range` (in f32, as `FLIP.h`): `start + i * (stop - start) / (count - 1)`.
pub(crate) fn exposure_multipliers(range: &ExposureRange) -> Vec<f32> {
    let start = range.start as f32;
    let stop = range.stop as f32;
    let step = if range.count > 1 {
        (stop - start) / (range.count - 1) as f32
    } else {
        0.0
    };
    (0..range.count)
        .map(|i| 2.0f32.powf(start + i as f32 * step))
        .collect()
}

/// The HDR-FLIP error map (per-pixel maximum over exposures).
pub(crate) fn hdr_flip_map(
    reference: &HdrImage,
    test: &HdrImage,
    range: &ExposureRange,
    ppd: f32,
) -> Result<Vec<f32>, MetricsError> {
    check_hdr_pair(reference, test)?;
    check_range(range)?;
    check_finite(reference, "reference")?;
    check_finite(test, "test")?;
    let (w, h) = (reference.width as usize, reference.height as usize);
    let tc = aces();
    let tone_map = |img: &HdrImage, m: f32| -> Vec<f32> {
        img.data
            .par_iter()
            .with_min_len(8192)
            .map(|&v| {
                let c = v * m;
                let t = ((c * c) * tc[0] + c * tc[1] + tc[2]) / (c * c * tc[3] + c * tc[4] + tc[5]);
                t.clamp(0.0, 1.0)
            })
            .collect()
    };
    let mut error = vec![0.0f32; w * h];
    for m in exposure_multipliers(range) {
        let (r, t) = rayon::join(|| tone_map(reference, m), || tone_map(test, m));
        let map = ldr_flip_map(Source::Linear(&r), Source::Linear(&t), w, h, ppd);
        error
            .par_iter_mut()
            .zip(map.par_iter())
            .with_min_len(8192)
            .for_each(|(d, &s)| {
                if s > *d {
                    *d = s;
                }
            });
    }
    Ok(error)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(w: u32, h: u32, f: impl Fn(usize) -> f32) -> HdrImage {
        HdrImage {
            width: w,
            height: h,
            data: (0..(w * h * 3) as usize).map(f).collect(),
        }
    }

    #[test]
    fn x_max_maps_to_085() {
        let tc = aces();
        let c = x_max();
        let t = (c * c * tc[0] + c * tc[1] + tc[2]) / (c * c * tc[3] + c * tc[4] + tc[5]);
        assert!((t - 0.85).abs() < 1e-5, "{c} -> {t}");
    }

    #[test]
    fn range_of_a_constant_image() {
        // Y_max = Y_median = 1: start = stop = log2(x_max), two exposures.
        let r = hdr_exposure_range(&img(4, 4, |_| 1.0));
        assert_eq!(r.start, r.stop);
        assert!((r.start - (x_max() as f64).log2()).abs() < 1e-6);
        assert_eq!(r.count, 2);
    }

    #[test]
    fn zero_median_is_floored_at_epsilon() {
        // 9 of 16 pixels black, the rest luminance 4.
        let r = hdr_exposure_range(&img(4, 4, |i| if i / 3 < 9 { 0.0 } else { 4.0 }));
        let xm = x_max();
        assert!((r.start - (xm / 4.0).log2() as f64).abs() < 1e-6);
        assert!((r.stop - (xm / f32::EPSILON).log2() as f64).abs() < 1e-6);
        assert_eq!(r.count, (r.stop as f32 - r.start as f32).ceil() as u32);
    }

    #[test]
    fn black_reference_gives_a_usable_range() {
        let r = hdr_exposure_range(&img(3, 3, |_| 0.0));
        assert_eq!(r.start, r.stop);
        assert_eq!(r.count, 2);
        let nan = hdr_exposure_range(&img(3, 3, |_| f32::NAN));
        assert_eq!(nan, r);
    }
}
