//! CPU model of RCAS (robust contrast-adaptive sharpening, `ffx_fsr1.h` v1.0.2 `FsrRcasF`), step
//! for step with `rcas.wgsl`, and the perceptual encoding FSR 1's passes work in (finite,
//! non-negative, SRTM, gamma 2.0). Shared by `fsr1` (EASU's input and RCAS), `taau` and `fsr2`
//! (RCAS after their resolve); tests compare it with the GPU pass. In f32 like the shader; not
//! for speed.

use glam::{IVec2, Vec3, Vec4};

const F16_MAX: f32 = 65504.0;
/// `FSR_RCAS_LIMIT` of `ffx_fsr1.h`.
pub const RCAS_LIMIT: f32 = 0.25 - 1.0 / 16.0;

pub fn max3(c: Vec3) -> f32 {
    c.max_element()
}

/// Linear radiance to EASU's input space: finite and non-negative, SRTM, gamma 2.0.
pub fn encode(c: Vec3) -> Vec3 {
    let f = Vec3::from_array(
        c.to_array()
            .map(|x| if x >= 0.0 { x.min(F16_MAX) } else { 0.0 }),
    );
    let t = f / (max3(f) + 1.0);
    Vec3::new(t.x.sqrt(), t.y.sqrt(), t.z.sqrt())
}

/// The inverse of [`encode`] (SRTM inverse with its 1/32768 floor).
pub fn decode(p: Vec3) -> Vec3 {
    let t = p * p;
    t / (1.0 - max3(t)).max(1.0 / 32768.0)
}

/// An image of `width` x `height` texels, row-major, clamped to the edge when read.
pub struct Image<'a> {
    pub width: u32,
    pub height: u32,
    pub texels: &'a [Vec4],
}

impl Image<'_> {
    /// The texel at `p`, clamped to the edge.
    pub fn at(&self, p: IVec2) -> Vec3 {
        let x = p.x.clamp(0, self.width as i32 - 1) as usize;
        let y = p.y.clamp(0, self.height as i32 - 1) as usize;
        self.texels[y * self.width as usize + x].truncate()
    }
}

/// One channel's lobe limit (`ffx_fsr1.h` v1.0.2, `FsrRcasF` "Limiters"): the ring's minimum
/// `mn4` and maximum `mx4` bounded by the centre tap `e` (v1.0.2's fix; v1.0 read the ring only).
pub fn rcas_lobe(mn4: f32, mx4: f32, e: f32) -> f32 {
    let hit_min = if mx4 > 0.0 {
        mn4.min(e) / (4.0 * mx4)
    } else {
        0.0
    };
    let hit_max = if mn4 < 1.0 {
        (1.0 - mx4.max(e)) / (4.0 * mn4 - 4.0)
    } else {
        0.0
    };
    (-hit_min).max(hit_max)
}

/// The five taps of RCAS's cross (b, d, e, f, h) at `p`, encoded per tap for a linear input.
fn rcas_taps(src: &Image, linear_input: bool, p: IVec2) -> [Vec3; 5] {
    [(0, -1), (-1, 0), (0, 0), (1, 0), (0, 1)].map(|(dx, dy)| {
        let c = src.at(p + IVec2::new(dx, dy));
        if linear_input {
            encode(c)
        } else {
            c
        }
    })
}

/// RCAS's negative lobe for the cross `[b, d, e, f, h]` at the linear `sharpness`.
fn rcas_lobe_of(taps: &[Vec3; 5], sharpness: f32) -> f32 {
    let [b, d, e, f, h] = *taps;
    let mn4 = b.min(d).min(f.min(h));
    let mx4 = b.max(d).max(f.max(h));
    let lobes = Vec3::new(
        rcas_lobe(mn4.x, mx4.x, e.x),
        rcas_lobe(mn4.y, mx4.y, e.y),
        rcas_lobe(mn4.z, mx4.z, e.z),
    );
    max3(lobes).clamp(-RCAS_LIMIT, 0.0) * sharpness
}

/// The cross filter with `lobe`, before the decode and before any clamp.
fn rcas_filter(taps: &[Vec3; 5], lobe: f32) -> Vec3 {
    let [b, d, e, f, h] = *taps;
    (lobe * (b + d + h + f) + e) / (4.0 * lobe + 1.0)
}

/// RCAS at pixel `(x, y)` of `src`, with the linear `sharpness` (exp2(-stops)): the negative
/// lobe and the decoded linear colour. `src` is EASU's perceptual output, or (`linear_input`) a
/// linear image encoded per tap (`taau`'s RCAS). The filtered value is clamped to [0, 1] before
/// the decode as the shader does: v1.0.2's limiter keeps it there in exact arithmetic, the clamp
/// only absorbs f32 rounding.
pub fn rcas(src: &Image, sharpness: f32, linear_input: bool, x: u32, y: u32) -> (f32, Vec3) {
    let taps = rcas_taps(src, linear_input, IVec2::new(x as i32, y as i32));
    let lobe = rcas_lobe_of(&taps, sharpness);
    let pix = rcas_filter(&taps, lobe).clamp(Vec3::ZERO, Vec3::ONE);
    (lobe, decode(pix))
}

/// RCAS's encoded output at `(x, y)` of a perceptual `src` with no clamp: what the limiter alone
/// achieves (tests check it stays within [0, 1]).
pub fn rcas_unclamped(src: &Image, sharpness: f32, x: u32, y: u32) -> Vec3 {
    let taps = rcas_taps(src, false, IVec2::new(x as i32, y as i32));
    rcas_filter(&taps, rcas_lobe_of(&taps, sharpness))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rcas_sharpens_a_step_and_never_overshoots() {
        // A step in a 3x1 ring: the centre moves away from its neighbours' mean.
        let row = [0.2f32, 0.5, 0.8];
        let texels: Vec<Vec4> = (0..9).map(|i| Vec4::splat(row[i % 3])).collect();
        let src = Image {
            width: 3,
            height: 3,
            texels: &texels,
        };
        let (lobe, _) = rcas(&src, 1.0, false, 1, 1);
        assert!((-RCAS_LIMIT..0.0).contains(&lobe), "{lobe}");
        // Sharpness 0 linear (infinitely many stops): identity.
        let (lobe0, c0) = rcas(&src, 0.0, false, 1, 1);
        assert_eq!(lobe0, 0.0);
        assert!((c0 - decode(Vec3::splat(0.5))).abs().max_element() < 1e-6);
        // A flat ring: no sharpening possible without clipping at 0 or 1.
        let flat = vec![Vec4::splat(0.0); 9];
        let (l, c) = rcas(
            &Image {
                width: 3,
                height: 3,
                texels: &flat,
            },
            1.0,
            false,
            1,
            1,
        );
        assert_eq!((l, c), (0.0, Vec3::ZERO));
    }

    #[test]
    fn an_isolated_peak_stays_within_one_encoded() {
        // ffx_fsr1.h v1.0.2's case: a centre of 0.8 encoded over a ring of 0.5, sharpness 0.2
        // stops. v1.0's ring-only limiter gave 1.364 encoded (about 61,000 linear after the
        // decode); v1.0.2's bounds the lobe by the centre too: 0.960.
        let mut texels = vec![Vec4::splat(0.5); 9];
        texels[4] = Vec4::splat(0.8);
        let src = Image {
            width: 3,
            height: 3,
            texels: &texels,
        };
        let sharpness = (-0.2f32).exp2();
        let raw = rcas_unclamped(&src, sharpness, 1, 1);
        assert!(raw.max_element() <= 1.0, "{raw}");
        assert!((raw.x - 0.960).abs() < 1e-3, "{raw}");
        // Sharpened (above the centre), and its decode finite and modest.
        assert!(raw.x > 0.8, "{raw}");
        let (_, c) = rcas(&src, sharpness, false, 1, 1);
        assert!(c.max_element() < 30.0, "{c}");
        // The mirror case, an isolated pit: no output below 0.
        let mut pit = vec![Vec4::splat(0.5); 9];
        pit[4] = Vec4::splat(0.05);
        let raw = rcas_unclamped(
            &Image {
                width: 3,
                height: 3,
                texels: &pit,
            },
            1.0,
            1,
            1,
        );
        assert!(raw.min_element() >= 0.0, "{raw}");
    }

    #[test]
    fn rcas_never_leaves_zero_to_one_before_the_decode() {
        // Every cross of taps from a coarse grid over [0, 1), at full sharpness.
        let levels = [0.0f32, 0.1, 0.45, 0.8, 0.99];
        for &e in &levels {
            for &lo in &levels {
                for &hi in &levels {
                    let mut texels = vec![Vec4::splat(lo); 9];
                    texels[4] = Vec4::splat(e);
                    texels[1] = Vec4::splat(hi);
                    texels[5] = Vec4::new(hi, lo, e, 1.0);
                    let src = Image {
                        width: 3,
                        height: 3,
                        texels: &texels,
                    };
                    let raw = rcas_unclamped(&src, 1.0, 1, 1);
                    assert!(
                        raw.min_element() >= -1e-6 && raw.max_element() <= 1.0 + 1e-6,
                        "e {e} ring {lo}..{hi}: {raw}"
                    );
                }
            }
        }
    }
}
