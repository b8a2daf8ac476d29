//! sRGB transfer functions (IEC 61966-2-1) between 8-bit encoded values and linear floats.
//!
//! For: `encode_srgb8` (how the harness turns linear frames into displayable images) and the
//! decode table FLIP uses. Not for: tone mapping (HDR-FLIP has its own tone mappers).

use crate::{HdrImage, Rgb8Image};
use rayon::prelude::*;

/// sRGB-encoded value in [0,1] to linear, IEC 61966-2-1 piecewise curve (as FLIP's `sRGB2LinearRGB`).
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear value to sRGB-encoded in [0,1], IEC 61966-2-1 (no clamping).
pub fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// Linear float -> sRGB 8-bit: clamp to [0,1], IEC 61966-2-1 encode, round to nearest.
///
/// NaN is treated as 0 (it clamps to black), so a frame with injected NaN still encodes.
pub fn encode_srgb8(hdr: &HdrImage) -> Rgb8Image {
    let data = hdr
        .data
        .par_iter()
        .with_min_len(4096)
        .map(|&v| encode_srgb8_value(v))
        .collect();
    Rgb8Image {
        width: hdr.width,
        height: hdr.height,
        data,
    }
}

/// One value of [`encode_srgb8`].
#[inline]
pub(crate) fn encode_srgb8_value(v: f32) -> u8 {
    let c = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    (linear_to_srgb(c) * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8
}

/// Linear value of every 8-bit sRGB code, computed in f32 exactly as FLIP does (`v / 255`, then
/// the piecewise curve).
pub(crate) fn srgb8_to_linear_table() -> [f32; 256] {
    let mut t = [0.0f32; 256];
    for (i, v) in t.iter_mut().enumerate() {
        *v = srgb_to_linear(i as f32 / 255.0);
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn encode_known_values() {
        let hdr = HdrImage {
            width: 5,
            height: 1,
            data: vec![
                0.0,
                1.0,
                0.5, // 0, 255, 188 (0.5 linear is 0.7354 encoded -> 187.5 -> 188)
                -1.0,
                2.0,
                f32::NAN, // clamped
                0.0031308,
                0.18,
                0.214, // toe edge -> 10; 0.18 -> 118; 0.214 -> 127
                1e-3,
                0.05,
                0.9,
                0.25,
                0.75,
                0.1,
            ],
        };
        let ldr = encode_srgb8(&hdr);
        assert_eq!(
            ldr.data,
            vec![0, 255, 188, 0, 255, 0, 10, 118, 127, 3, 63, 243, 137, 225, 89]
        );
    }

    #[test]
    fn decode_roundtrips_through_encode() {
        let table = srgb8_to_linear_table();
        let hdr = HdrImage {
            width: 256,
            height: 1,
            data: (0..256).flat_map(|i| [table[i]; 3]).collect(),
        };
        let ldr = encode_srgb8(&hdr);
        for i in 0..256 {
            assert_eq!(ldr.data[i * 3] as usize, i);
        }
    }
}
