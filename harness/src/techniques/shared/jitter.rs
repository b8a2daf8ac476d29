//! TAAU's sub-pixel jitter: the Halton (2, 3) sequence, how many phases a render scale needs, and
//! the projection offset that puts a render pixel's sample where the sequence says. Pure
//! functions, shared by the GPU part, the CPU model and the tests.
//!
//! Conventions: a jitter `j` is in render pixels, x right and y down, relative to the pixel
//! centre, each component in (-0.5, 0.5): render pixel `q` samples the unjittered image at
//! `q + 0.5 + j` (render pixels), i.e. at `(q + 0.5 + j) / scale` output pixels.

use glam::Vec2;

/// The radical inverse of `index` in `base`: the Halton sequence's component (van der Corput).
pub fn halton(mut index: u32, base: u32) -> f32 {
    let mut f = 1.0f64;
    let mut r = 0.0f64;
    while index > 0 {
        f /= base as f64;
        r += f * (index % base) as f64;
        index /= base;
    }
    r as f32
}

/// Phases of the sequence for a render `render_width` pixels wide at an output `display_width`
/// wide: FSR 2's `ffxFsr2GetJitterPhaseCount` (`src/ffx-fsr2-api/ffx_fsr2.cpp`), the f32
/// `8 x (display / render)^2` truncated (DLSS's guide asks for the same 8 x ratio^2): 8 at
/// native width, 18 at 1/1.5, 32 at 1/2. About that many frames fill every output pixel with
/// samples from one whole cycle.
pub fn auto_phases(render_width: u32, display_width: u32) -> u32 {
    let ratio = display_width as f32 / render_width.max(1) as f32;
    ((8.0 * ratio.powi(2)) as u32).max(1)
}

/// The jitter of frame `index` with `phases` phases: Halton (2, 3) from its first point (index
/// 0 is (0, 0), a pixel corner, and is skipped), centred on the pixel.
pub fn jitter(index: u32, phases: u32) -> Vec2 {
    let i = index % phases + 1;
    Vec2::new(halton(i, 2) - 0.5, halton(i, 3) - 0.5)
}

/// The NDC offset (`View::ndc_offset`) that makes a `width` x `height` render sample at jitter
/// `j`: the point seen at pixel `q`'s centre is then the unjittered image at `q + 0.5 + j`
/// (NDC y is up, pixels down).
pub fn ndc_offset(j: Vec2, width: u32, height: u32) -> Vec2 {
    Vec2::new(-2.0 * j.x / width as f32, 2.0 * j.y / height as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halton_2_3_starts_as_published() {
        let h2: Vec<f32> = (1..=8).map(|i| halton(i, 2)).collect();
        assert_eq!(h2, [0.5, 0.25, 0.75, 0.125, 0.625, 0.375, 0.875, 0.0625]);
        let h3: Vec<f32> = (1..=4).map(|i| halton(i, 3)).collect();
        let want = [1.0 / 3.0, 2.0 / 3.0, 1.0 / 9.0, 4.0 / 9.0];
        for (a, b) in h3.iter().zip(want) {
            assert!((a - b).abs() < 1e-7, "{a} {b}");
        }
    }

    #[test]
    fn phases_cover_the_ratio() {
        // FSR 2's table: native 8, Quality (1.5) 18, Balanced (1.7) 23, Performance (2) 32,
        // Ultra Performance (3) 72.
        assert_eq!(auto_phases(1920, 1920), 8);
        assert_eq!(auto_phases(1280, 1920), 18);
        assert_eq!(auto_phases(1129, 1920), 23);
        assert_eq!(auto_phases(960, 1920), 32);
        assert_eq!(auto_phases(640, 1920), 72);
    }

    #[test]
    fn jitter_is_periodic_inside_the_pixel_and_distinct() {
        let phases = 32;
        let js: Vec<Vec2> = (0..phases).map(|i| jitter(i, phases)).collect();
        for (i, j) in js.iter().enumerate() {
            assert!(j.abs().max_element() < 0.5, "{j}");
            assert_eq!(*j, jitter(i as u32 + phases, phases));
            for k in &js[..i] {
                assert_ne!(j, k);
            }
        }
        // Low discrepancy: every quarter of the pixel gets 8 of the 32 samples in x.
        for q in 0..4 {
            let lo = -0.5 + q as f32 * 0.25;
            let n = js.iter().filter(|j| j.x >= lo && j.x < lo + 0.25).count();
            assert_eq!(n, 8, "quarter {q}");
        }
        // The mean is close to the centre.
        let mean = js.iter().copied().sum::<Vec2>() / phases as f32;
        assert!(mean.abs().max_element() < 0.03, "{mean}");
    }

    #[test]
    fn ndc_offset_moves_the_sample_by_the_jitter() {
        // Pixel q's centre in NDC after the remap ndc' = ndc + offset is the unjittered point at
        // q + 0.5 + j.
        let (w, h) = (40u32, 30u32);
        let j = Vec2::new(0.375, -0.125);
        let off = ndc_offset(j, w, h);
        let q = Vec2::new(7.0, 11.0);
        let centre_ndc = Vec2::new(
            (q.x + 0.5) / w as f32 * 2.0 - 1.0,
            1.0 - (q.y + 0.5) / h as f32 * 2.0,
        );
        let unjittered = centre_ndc - off;
        let px = Vec2::new(
            (unjittered.x + 1.0) * 0.5 * w as f32,
            (1.0 - unjittered.y) * 0.5 * h as f32,
        );
        assert!((px - (q + 0.5 + j)).abs().max_element() < 1e-4, "{px}");
    }
}
