//! CPU model of `fsr1`, step for step with `fsr1.wgsl`: the input encoding, EASU's
//! edge direction, length and tap weights, its deringing, and RCAS's lobe; tests compare it with
//! the GPU passes on real frames. In f32 like the shader; not for speed.

use glam::{IVec2, Vec2, Vec3, Vec4};

const F16_MAX: f32 = 65504.0;
/// `FSR_RCAS_LIMIT` of `ffx_fsr1.h`.
pub const RCAS_LIMIT: f32 = 0.25 - 1.0 / 16.0;

fn max3(c: Vec3) -> f32 {
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

fn luma2(c: Vec3) -> f32 {
    c.z * 0.5 + (c.x * 0.5 + c.y)
}

/// An image of `width` x `height` texels, row-major, clamped to the edge when read.
pub struct Image<'a> {
    pub width: u32,
    pub height: u32,
    pub texels: &'a [Vec4],
}

impl Image<'_> {
    fn at(&self, p: IVec2) -> Vec3 {
        let x = p.x.clamp(0, self.width as i32 - 1) as usize;
        let y = p.y.clamp(0, self.height as i32 - 1) as usize;
        self.texels[y * self.width as usize + x].truncate()
    }
}

/// One axis's edge length (`FsrEasuSetF`): 0 on a gradient reversal, 1 on a monotonic gradient,
/// squared; 0 where the neighbourhood is flat.
pub fn axis_length(a: f32, c: f32, e: f32) -> f32 {
    let m = (e - c).abs().max((c - a).abs());
    let d = (e - a).abs();
    let l = if m > 0.0 {
        (d / m).clamp(0.0, 1.0)
    } else {
        0.0
    };
    l * l
}

/// What EASU decided at one output pixel: the kernel's direction (unit, or (1, y) where the
/// gradient is flat), its length before shaping (0 to 2), and the result in perceptual space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Easu {
    pub dir: Vec2,
    pub len: f32,
    pub color: Vec3,
}

/// The kernel's shape: direction, anisotropic length, negative lobe and clip point.
#[derive(Clone, Copy, Debug)]
pub struct Kernel {
    pub dir: Vec2,
    pub len2: Vec2,
    pub lob: f32,
    pub clp: f32,
}

pub fn kernel(dir: Vec2, len: f32) -> Kernel {
    let r2 = dir.dot(dir);
    let dir = if r2 < 1.0 / 32768.0 {
        Vec2::new(1.0, dir.y)
    } else {
        dir / r2.sqrt()
    };
    let len = len * 0.5;
    let len = len * len;
    let stretch = dir.dot(dir) / dir.x.abs().max(dir.y.abs());
    let len2 = Vec2::new(1.0 + (stretch - 1.0) * len, 1.0 - 0.5 * len);
    let lob = 0.5 + ((1.0 / 4.0 - 0.04) - 0.5) * len;
    Kernel {
        dir,
        len2,
        lob,
        clp: 1.0 / lob,
    }
}

/// `FsrEasuTapF`'s weight of a tap at `off` from the resolve position.
pub fn weight(off: Vec2, k: &Kernel) -> f32 {
    let v = Vec2::new(
        off.x * k.dir.x + off.y * k.dir.y,
        off.x * -k.dir.y + off.y * k.dir.x,
    ) * k.len2;
    let d2 = v.dot(v).min(k.clp);
    let wb = 2.0 / 5.0 * d2 - 1.0;
    let wa = k.lob * d2 - 1.0;
    let wb = 25.0 / 16.0 * (wb * wb) - (25.0 / 16.0 - 1.0);
    wb * (wa * wa)
}

/// EASU at output pixel `(x, y)` of an `out` sized output from the linear render `src`.
pub fn easu(src: &Image, out: (u32, u32), x: u32, y: u32) -> Easu {
    let scale =
        Vec2::new(src.width as f32, src.height as f32) / Vec2::new(out.0 as f32, out.1 as f32);
    let pp = Vec2::new(x as f32, y as f32) * scale + (0.5 * scale - 0.5);
    let fp = pp.floor();
    let pp = pp - fp;
    let f0 = fp.as_ivec2();
    let tap = |dx: i32, dy: i32| encode(src.at(f0 + IVec2::new(dx, dy)));
    // b c / e f g h / i j k l / n o
    let (b, c) = (tap(0, -1), tap(1, -1));
    let (e, f, g, h) = (tap(-1, 0), tap(0, 0), tap(1, 0), tap(2, 0));
    let (i, j, k, l) = (tap(-1, 1), tap(0, 1), tap(1, 1), tap(2, 1));
    let (n, o) = (tap(0, 2), tap(1, 2));
    let [bl, cl, el, fl, gl, hl, il, jl, kl, ll, nl, ol] =
        [b, c, e, f, g, h, i, j, k, l, n, o].map(luma2);
    let mut dir = Vec2::ZERO;
    let mut len = 0.0f32;
    let mut set = |w: f32, a: f32, b: f32, c: f32, d: f32, e: f32| {
        dir += Vec2::new(d - b, e - a) * w;
        len += (axis_length(b, c, d) + axis_length(a, c, e)) * w;
    };
    set((1.0 - pp.x) * (1.0 - pp.y), bl, el, fl, gl, jl);
    set(pp.x * (1.0 - pp.y), cl, fl, gl, hl, kl);
    set((1.0 - pp.x) * pp.y, fl, il, jl, kl, nl);
    set(pp.x * pp.y, gl, jl, kl, ll, ol);
    let kern = kernel(dir, len);
    let taps = [
        ((0.0, -1.0), b),
        ((1.0, -1.0), c),
        ((-1.0, 1.0), i),
        ((0.0, 1.0), j),
        ((0.0, 0.0), f),
        ((-1.0, 0.0), e),
        ((1.0, 1.0), k),
        ((2.0, 1.0), l),
        ((2.0, 0.0), h),
        ((1.0, 0.0), g),
        ((1.0, 2.0), o),
        ((0.0, 2.0), n),
    ];
    let mut sum = Vec3::ZERO;
    let mut wsum = 0.0;
    for ((ox, oy), col) in taps {
        let w = weight(Vec2::new(ox, oy) - pp, &kern);
        sum += col * w;
        wsum += w;
    }
    let lo = f.min(g).min(j.min(k));
    let hi = f.max(g).max(j.max(k));
    Easu {
        dir: kern.dir,
        len,
        color: (sum / wsum).max(lo).min(hi),
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
    fn encode_is_reversible_and_bounded() {
        for c in [
            Vec3::ZERO,
            Vec3::new(0.2, 0.5, 0.9),
            Vec3::new(3.0, 0.1, 40.0),
            Vec3::splat(1000.0),
        ] {
            let p = encode(c);
            assert!(p.max_element() < 1.0 && p.min_element() >= 0.0, "{p}");
            let back = decode(p);
            assert!(
                (back - c).abs().max_element() <= 1e-3 * c.max_element().max(1.0),
                "{c} {back}"
            );
        }
        // Not finite or negative: 0, and +Inf at most the f16 maximum.
        assert_eq!(encode(Vec3::new(f32::NAN, -1.0, 0.0)), Vec3::ZERO);
        assert!(encode(Vec3::splat(f32::INFINITY)).is_finite());
    }

    #[test]
    fn easu_of_a_flat_image_is_that_colour() {
        let texels = vec![Vec4::new(0.3, 0.6, 0.1, 1.0); 16];
        let src = Image {
            width: 4,
            height: 4,
            texels: &texels,
        };
        for (x, y) in [(0, 0), (3, 5), (7, 7)] {
            let e = easu(&src, (8, 8), x, y);
            assert_eq!(e.len, 0.0);
            let back = decode(e.color);
            assert!((back - Vec3::new(0.3, 0.6, 0.1)).abs().max_element() < 1e-5);
        }
    }

    #[test]
    fn easu_follows_a_vertical_edge() {
        // Left half dark, right half bright: the gradient is along x, the edge vertical.
        let texels: Vec<Vec4> = (0..64)
            .map(|i| {
                if i % 8 < 4 {
                    Vec4::splat(0.05)
                } else {
                    Vec4::splat(0.8)
                }
            })
            .collect();
        let src = Image {
            width: 8,
            height: 8,
            texels: &texels,
        };
        let e = easu(&src, (16, 16), 7, 8);
        assert!(e.dir.x.abs() > 0.99 && e.dir.y.abs() < 1e-3, "{:?}", e.dir);
        assert!(e.len > 0.9, "{}", e.len);
        // Deringed: within the 2x2 nearest texels' range.
        let c = decode(e.color).x;
        assert!((0.05 - 1e-4..=0.8 + 1e-4).contains(&c), "{c}");
    }

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
