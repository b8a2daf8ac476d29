//! CPU model of `fsr1`'s EASU, step for step with `fsr1.wgsl`: the input encoding (shared with
//! RCAS, `shared/rcas_model.rs`), EASU's edge direction, length and tap weights, its deringing;
//! tests compare it with the GPU passes on real frames. In f32 like the shader; not for speed.

use glam::{IVec2, Vec2, Vec3};

pub use crate::techniques::shared::rcas_model::{decode, encode, Image};

fn luma2(c: Vec3) -> f32 {
    c.z * 0.5 + (c.x * 0.5 + c.y)
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

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec4;

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
}
