//! Temporal difference error (TDE), `../shared/notes/metrics.md` section 3.3, item 1:
//!
//! `TDE_t = mean_{p in M_t} | (T_t - W_t(T_{t-1})) - (R_t - W_t(R_{t-1})) |`
//!
//! For: how differently a technique's output changes from frame to frame than the reference's
//! does, with the renderer's exact motion `W_t` (zero when the technique changes exactly as the
//! reference; with a static camera `W` is the identity). Not for: finding the motion or the valid
//! mask `M_t` (disocclusion, off screen): the harness renders them and passes them in.
//!
//! Choices recorded here: values are the sRGB-encoded 8-bit RGB of the frames (as PSNR and
//! flicker), the mean runs over valid pixels and the three channels, and `W_t` samples the
//! previous frame bilinearly at `p - motion(p)` (pixel centres at `i + 0.5`, clamped to the edge).

use crate::image::check_pair;
use crate::{MetricsError, Rgb8Image};

/// Bilinear sample of channel `c` at continuous pixel position (x, y), centres at `i + 0.5`.
fn bilinear(img: &Rgb8Image, x: f32, y: f32, c: usize) -> f64 {
    let (w, h) = (img.width as i64, img.height as i64);
    let fx = (x - 0.5).clamp(0.0, (w - 1) as f32);
    let fy = (y - 0.5).clamp(0.0, (h - 1) as f32);
    let (x0, y0) = (fx.floor() as i64, fy.floor() as i64);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (ax, ay) = ((fx - x0 as f32) as f64, (fy - y0 as f32) as f64);
    let at = |x: i64, y: i64| img.data[((y * w + x) * 3) as usize + c] as f64;
    let top = at(x0, y0) * (1.0 - ax) + at(x1, y0) * ax;
    let bottom = at(x0, y1) * (1.0 - ax) + at(x1, y1) * ax;
    top * (1.0 - ay) + bottom * ay
}

/// TDE of one frame, in 8-bit units. `motion[p]` is the screen motion of pixel `p` from the
/// previous frame to this one in pixels (x right, y down); `valid[p]` is `M_t`. `None` when no
/// pixel is valid.
pub fn temporal_difference_error(
    test_prev: &Rgb8Image,
    test: &Rgb8Image,
    reference_prev: &Rgb8Image,
    reference: &Rgb8Image,
    motion: &[[f32; 2]],
    valid: &[bool],
) -> Result<Option<f64>, MetricsError> {
    check_pair(reference, test)?;
    check_pair(reference, test_prev)?;
    check_pair(reference, reference_prev)?;
    let n = reference.pixel_count();
    for (what, actual) in [("motion field", motion.len()), ("valid mask", valid.len())] {
        if actual != n {
            return Err(MetricsError::PerPixelLength {
                what,
                expected: n,
                actual,
            });
        }
    }
    let w = reference.width as usize;
    let (mut sum, mut count) = (0.0f64, 0u64);
    for (i, (m, _)) in motion
        .iter()
        .zip(valid)
        .enumerate()
        .filter(|(_, (_, v))| **v)
    {
        let x = (i % w) as f32 + 0.5 - m[0];
        let y = (i / w) as f32 + 0.5 - m[1];
        for c in 0..3 {
            let dt = test.data[i * 3 + c] as f64 - bilinear(test_prev, x, y, c);
            let dr = reference.data[i * 3 + c] as f64 - bilinear(reference_prev, x, y, c);
            sum += (dt - dr).abs();
        }
        count += 3;
    }
    Ok((count > 0).then(|| sum / count as f64))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 3]) -> Rgb8Image {
        let mut data = Vec::new();
        for y in 0..h {
            for x in 0..w {
                data.extend(f(x, y));
            }
        }
        Rgb8Image {
            width: w,
            height: h,
            data,
        }
    }

    fn ramp(shift: u32) -> impl Fn(u32, u32) -> [u8; 3] {
        move |x, y| [((x + shift) * 20) as u8, (y * 30) as u8, 7]
    }

    #[test]
    fn a_technique_that_changes_as_the_reference_has_zero_error() {
        // Content moves 1 px right per frame in both; the test is offset by a constant error.
        let r0 = image(8, 6, ramp(0));
        let r1 = image(8, 6, |x, y| ramp(0)(x.saturating_sub(1), y));
        let t0 = image(8, 6, |x, y| ramp(0)(x, y).map(|v| v.saturating_add(3)));
        let t1 = image(8, 6, |x, y| {
            ramp(0)(x.saturating_sub(1), y).map(|v| v.saturating_add(3))
        });
        let motion = vec![[1.0, 0.0]; 48];
        let valid: Vec<bool> = (0..48).map(|i| i % 8 != 0).collect();
        let tde = temporal_difference_error(&t0, &t1, &r0, &r1, &motion, &valid).unwrap();
        assert_eq!(tde, Some(0.0));
    }

    #[test]
    fn flicker_the_reference_does_not_have_is_measured() {
        // Static reference; the test alternates by 4 levels on every channel: TDE 4.
        let r = image(4, 4, ramp(0));
        let t0 = image(4, 4, ramp(0));
        let t1 = image(4, 4, |x, y| ramp(0)(x, y).map(|v| v + 4));
        let motion = vec![[0.0, 0.0]; 16];
        let valid = vec![true; 16];
        let tde = temporal_difference_error(&t0, &t1, &r, &r, &motion, &valid).unwrap();
        assert_eq!(tde, Some(4.0));
        // Masked pixels do not count; no valid pixel gives no value.
        let none = vec![false; 16];
        assert_eq!(
            temporal_difference_error(&t0, &t1, &r, &r, &motion, &none).unwrap(),
            None
        );
    }

    #[test]
    fn sub_pixel_motion_interpolates() {
        // Half a pixel of motion on a horizontal ramp of slope 20: the warp reads halfway.
        let r0 = image(6, 2, ramp(0));
        let motion = vec![[0.5, 0.0]; 12];
        let mut valid = vec![true; 12];
        valid[0] = false;
        valid[6] = false;
        // Reference static, test identical to it: the warped previous frame is 10 lower, in both.
        let tde = temporal_difference_error(&r0, &r0, &r0, &r0, &motion, &valid).unwrap();
        assert_eq!(tde, Some(0.0));
        let t1 = image(6, 2, |x, y| ramp(0)(x, y).map(|v| v.saturating_add(1)));
        let tde = temporal_difference_error(&r0, &t1, &r0, &r0, &motion, &valid).unwrap();
        assert!((tde.unwrap() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn mismatched_inputs_are_errors() {
        let a = image(4, 4, ramp(0));
        let b = image(4, 3, ramp(0));
        assert!(temporal_difference_error(&a, &a, &a, &b, &[[0.0; 2]; 16], &[true; 16]).is_err());
        assert!(temporal_difference_error(&a, &a, &a, &a, &[[0.0; 2]; 3], &[true; 16]).is_err());
    }
}
