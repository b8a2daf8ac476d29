//! CPU model of the interlace reconstruction (`reconstruct.wgsl`, the default `pattern =
//! "interlaced"`), step for step in f32: the oracle the GPU output is compared with in tests.
//! The shaded pattern (`shaded`) and the quarter-resolution layout (`rows_texel`) are also what
//! the GPU part renders.
//!
//! Not used when rendering.

use glam::{Mat4, Vec2, Vec3, Vec4};

use crate::render::velocity::MOTION_DEPTH_EPSILON;

/// What one reconstruction reads: this frame's two quarter-resolution layers, the previous output
/// and its depth, the velocity buffer if bound, and the frame's constants.
pub struct Inputs<'a> {
    pub width: u32,
    pub height: u32,
    /// Shaded pixels this frame: `(x + y + parity)` even.
    pub parity: u32,
    /// Quarter-resolution size (`quarter_size`).
    pub quarter: (u32, u32),
    /// Two layers (row parity r), each `quarter.0 * quarter.1` RGBA texels, layer 0 first.
    pub rows_color: &'a [Vec4],
    pub rows_depth: &'a [f32],
    /// The previous output and its depth, `width * height`; read only when `history_valid`.
    pub history: &'a [Vec4],
    pub history_depth: &'a [f32],
    /// Full-resolution velocity (xy: current minus previous position, pixels; z > 0.5: covered).
    pub velocity: Option<&'a [Vec4]>,
    /// The motion pass's depth (full resolution, reversed-Z), with `velocity`.
    pub velocity_depth: Option<&'a [f32]>,
    pub prev_from_cur: Mat4,
    pub history_valid: bool,
    /// Nothing can have moved since the previous frame (camera still, no animated objects): the
    /// history at each pixel is its own last shade, confidence 1.
    pub still: bool,
    pub clamp: bool,
    pub near: f32,
    pub far: f32,
    pub depth_tolerance: f32,
    pub coherency_scale: f32,
    pub velocity_scale: f32,
}

/// Where a pixel's colour came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// Shaded this frame.
    Shaded,
    /// The spatial fill (no history, or off screen last frame).
    Fill,
    /// The previous output, reprojected, clamped, blended and weighted.
    History,
}

/// Whether pixel `(x, y)` is shaded on frames of `parity`: a checkerboard, so that every
/// unshaded pixel has four shaded orthogonal neighbours (section 3.3).
pub fn shaded(parity: u32, x: u32, y: u32) -> bool {
    (x + y + parity) & 1 == 0
}

/// The quarter-resolution size for an output `width` x `height`: every shaded pixel of either
/// parity has a texel.
pub fn quarter_size(width: u32, height: u32) -> (u32, u32) {
    (width.div_ceil(2), height.div_ceil(2))
}

/// Where shaded pixel `(x, y)` lives in the quarter-resolution layers: `(i, j, layer)`; layer r
/// holds rows `2j + r`, texel i column `2i + ((r + parity) & 1)`.
pub fn rows_texel(parity: u32, x: i32, y: i32) -> (i32, i32, i32) {
    let r = y & 1;
    let s = (r + parity as i32) & 1;
    ((x - s) >> 1, y >> 1, r)
}

/// WGSL's `mix`: `a * (1 - t) + b * t`.
fn mix(a: Vec4, b: Vec4, t: f32) -> Vec4 {
    a * (1.0 - t) + b * t
}

/// Mirrors a coordinate into `[0, n)` keeping its parity (the shader's `mirror`).
fn mirror(c: i32, n: i32) -> i32 {
    let mut m = c;
    if m < 0 {
        m = -m;
    }
    if m > n - 1 {
        m = 2 * (n - 1) - m;
    }
    m.clamp(0, n - 1)
}

impl Inputs<'_> {
    fn texel_index(&self, x: i32, y: i32) -> usize {
        let (i, j, r) = rows_texel(self.parity, x, y);
        let (qw, qh) = (self.quarter.0 as i32, self.quarter.1 as i32);
        ((r * qh + j) * qw + i) as usize
    }

    fn shaded_color(&self, x: i32, y: i32) -> Vec4 {
        self.rows_color[self.texel_index(x, y)]
    }

    fn shaded_depth(&self, x: i32, y: i32) -> f32 {
        self.rows_depth[self.texel_index(x, y)]
    }

    fn history_at(&self, x: i32, y: i32) -> Vec4 {
        let x = x.clamp(0, self.width as i32 - 1);
        let y = y.clamp(0, self.height as i32 - 1);
        self.history[(y * self.width as i32 + x) as usize]
    }

    fn history_bilinear(&self, pos: Vec2) -> Vec4 {
        let t = pos - 0.5;
        let base = t.floor();
        let f = t - base;
        let (x0, y0) = (base.x as i32, base.y as i32);
        let top = mix(self.history_at(x0, y0), self.history_at(x0 + 1, y0), f.x);
        let bottom = mix(
            self.history_at(x0, y0 + 1),
            self.history_at(x0 + 1, y0 + 1),
            f.x,
        );
        mix(top, bottom, f.y)
    }

    fn linear_depth(&self, d: f32) -> f32 {
        self.near * self.far / (d * (self.far - self.near) + self.near)
    }
}

fn luma(c: Vec4) -> f32 {
    let t = c.truncate() / (1.0 + c.x.max(c.y.max(c.z)));
    t.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

fn difference(a: Vec4, b: Vec4) -> f32 {
    let (la, lb) = (luma(a), luma(b));
    (la - lb).abs() / (la + lb + 1e-4)
}

/// The reconstructed pixel `(x, y)`, its output depth, and where the colour came from.
pub fn reconstruct(inp: &Inputs, x: u32, y: u32) -> (Vec4, f32, Source) {
    let (x, y) = (x as i32, y as i32);
    let (w, h) = (inp.width as i32, inp.height as i32);
    if shaded(inp.parity, x as u32, y as u32) {
        return (
            inp.shaded_color(x, y),
            inp.shaded_depth(x, y),
            Source::Shaded,
        );
    }
    // 1. The four orthogonal neighbours: left, right, up, down.
    let nx = [mirror(x - 1, w), mirror(x + 1, w), x, x];
    let ny = [y, y, mirror(y - 1, h), mirror(y + 1, h)];
    let mut c = [Vec4::ZERO; 4];
    let mut d = [0.0f32; 4];
    let mut closest = 0;
    let (mut lo, mut hi) = (Vec4::splat(1e30), Vec4::splat(-1e30));
    let (mut z_lo, mut z_hi) = (1e30f32, -1e30f32);
    for k in 0..4 {
        c[k] = inp.shaded_color(nx[k], ny[k]);
        d[k] = inp.shaded_depth(nx[k], ny[k]);
        if d[k] > d[closest] {
            closest = k;
        }
        lo = lo.min(c[k]);
        hi = hi.max(c[k]);
        let z = inp.linear_depth(d[k]);
        z_lo = z_lo.min(z);
        z_hi = z_hi.max(z);
    }
    let dh = difference(c[0], c[1]);
    let dv = difference(c[2], c[3]);
    let spatial = if dv < dh {
        0.5 * (c[2] + c[3])
    } else {
        0.5 * (c[0] + c[1])
    };
    let coherency = dh.min(dv);
    let d_near = d[closest];
    if !inp.history_valid {
        return (spatial, d_near, Source::Fill);
    }
    // 2. Motion from the closest neighbour.
    let size = Vec2::new(inp.width as f32, inp.height as f32);
    let centre = Vec2::new(x as f32, y as f32) + 0.5;
    let mut prev_pos = centre;
    let mut dz = 0.0;
    let n = (ny[closest] * w + nx[closest]) as usize;
    let mut v = inp.velocity.map(|v| v[n]).unwrap_or(Vec4::ZERO);
    if let Some(vd) = inp.velocity_depth {
        // A static object in front of the animated one the motion pass drew.
        let vd = vd[n];
        if d_near - vd > MOTION_DEPTH_EPSILON * d_near.max(vd) {
            v.z = 0.0;
        }
    }
    if v.z > 0.5 {
        prev_pos = centre - Vec2::new(v.x, v.y);
    } else if d_near > 0.0 && !inp.still {
        let ndc = Vec4::new(
            centre.x / size.x * 2.0 - 1.0,
            1.0 - centre.y / size.y * 2.0,
            d_near,
            1.0,
        );
        let prev = inp.prev_from_cur * ndc;
        prev_pos = Vec2::new(
            (prev.x / prev.w * 0.5 + 0.5) * size.x,
            (0.5 - prev.y / prev.w * 0.5) * size.y,
        );
        dz = inp.linear_depth(prev.z / prev.w) - inp.linear_depth(d_near);
    }
    let on_screen =
        prev_pos.x >= 0.0 && prev_pos.y >= 0.0 && prev_pos.x < size.x && prev_pos.y < size.y;
    if !on_screen {
        return (spatial, d_near, Source::Fill);
    }
    // 3. The history, clamped; 4. blended back by depth confidence.
    let raw = inp.history_bilinear(prev_pos);
    let mut blended = raw;
    if inp.clamp {
        let clamped = raw.max(lo).min(hi);
        let hp = prev_pos.floor();
        let z_prev = inp.linear_depth(inp.history_depth[(hp.y as i32 * w + hp.x as i32) as usize]);
        let outside = (z_lo + dz - z_prev).max(z_prev - (z_hi + dz)).max(0.0);
        let confidence = if inp.still {
            1.0
        } else {
            (1.0 - outside / (inp.depth_tolerance * z_prev)).clamp(0.0, 1.0)
        };
        blended = mix(clamped, raw, confidence);
    }
    // 5. Colour coherency and velocity weights.
    let w_coh = (coherency / inp.coherency_scale).clamp(0.0, 1.0);
    let w_vel = ((prev_pos - centre).length() / inp.velocity_scale).clamp(0.0, 1.0);
    let out = mix(spatial, blended, 1.0 - w_vel * (1.0 - w_coh));
    (out, d_near, Source::History)
}

/// Every pixel, row-major.
pub fn reconstruct_all(inp: &Inputs) -> Vec<(Vec4, f32, Source)> {
    (0..inp.height)
        .flat_map(|y| (0..inp.width).map(move |x| (x, y)))
        .map(|(x, y)| reconstruct(inp, x, y))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both quarter-resolution layers of frame `parity` from a full-resolution truth.
    fn layers(w: u32, h: u32, parity: u32, truth: impl Fn(u32, u32) -> Vec4) -> Vec<Vec4> {
        let (qw, qh) = quarter_size(w, h);
        let mut out = vec![Vec4::ZERO; (2 * qw * qh) as usize];
        for y in 0..h {
            for x in 0..w {
                if shaded(parity, x, y) {
                    let (i, j, r) = rows_texel(parity, x as i32, y as i32);
                    assert!(i >= 0 && (i as u32) < qw && (j as u32) < qh);
                    out[((r as u32 * qh + j as u32) * qw + i as u32) as usize] = truth(x, y);
                }
            }
        }
        out
    }

    fn inputs<'a>(
        w: u32,
        h: u32,
        parity: u32,
        rows: &'a [Vec4],
        depth: &'a [f32],
        history: &'a [Vec4],
        history_depth: &'a [f32],
    ) -> Inputs<'a> {
        Inputs {
            width: w,
            height: h,
            parity,
            quarter: quarter_size(w, h),
            rows_color: rows,
            rows_depth: depth,
            history,
            history_depth,
            velocity: None,
            velocity_depth: None,
            prev_from_cur: Mat4::IDENTITY,
            history_valid: true,
            still: false,
            clamp: true,
            near: 0.1,
            far: 100.0,
            depth_tolerance: 0.05,
            coherency_scale: 0.1,
            velocity_scale: 4.0,
        }
    }

    #[test]
    fn every_unshaded_pixel_has_four_shaded_neighbours_and_each_pixel_is_shaded_every_two_frames() {
        for (w, h) in [(1u32, 1u32), (2, 3), (5, 4), (7, 7)] {
            for y in 0..h {
                for x in 0..w {
                    assert_ne!(shaded(0, x, y), shaded(1, x, y));
                    for p in [0, 1] {
                        if shaded(p, x, y) || w < 2 || h < 2 {
                            continue;
                        }
                        let (xi, yi, wi, hi) = (x as i32, y as i32, w as i32, h as i32);
                        for (nx, ny) in [
                            (mirror(xi - 1, wi), yi),
                            (mirror(xi + 1, wi), yi),
                            (xi, mirror(yi - 1, hi)),
                            (xi, mirror(yi + 1, hi)),
                        ] {
                            assert!(shaded(p, nx as u32, ny as u32), "{w}x{h} p{p} ({x},{y})");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn a_static_camera_rebuilds_the_previous_frame_exactly_even_where_the_clamp_would_not() {
        let (w, h) = (7u32, 5u32);
        // A one-pixel bright dot at (3, 2), nearer than everything around it (a thin feature alone
        // in its neighbourhood): a clamp to its neighbours would erase it, and its previous depth
        // lies outside their range.
        let dot = |x: u32, y: u32| (x, y) == (3, 2);
        let truth = |x: u32, y: u32| {
            if dot(x, y) {
                Vec4::splat(4.0)
            } else {
                Vec4::new(x as f32 / 8.0, y as f32 / 4.0, 0.5, 1.0)
            }
        };
        let depth_of = |x: u32, y: u32| if dot(x, y) { 0.9 } else { 0.5 };
        let history: Vec<Vec4> = (0..h)
            .flat_map(|y| (0..w).map(move |x| truth(x, y)))
            .collect();
        let history_depth: Vec<f32> = (0..h)
            .flat_map(|y| (0..w).map(move |x| depth_of(x, y)))
            .collect();
        for parity in [0, 1] {
            let rows = layers(w, h, parity, truth);
            let depth: Vec<f32> = layers(w, h, parity, |x, y| Vec4::splat(depth_of(x, y)))
                .iter()
                .map(|d| d.x)
                .collect();
            let mut inp = inputs(w, h, parity, &rows, &depth, &history, &history_depth);
            // Nothing moved (camera still, no animated objects): every pixel exact.
            inp.still = true;
            for (i, (c, _, source)) in reconstruct_all(&inp).into_iter().enumerate() {
                let (x, y) = (i as u32 % w, i as u32 / w);
                assert!(
                    (c - truth(x, y)).abs().max_element() < 1e-5,
                    "parity {parity} pixel {x},{y}: {c}"
                );
                let want = if shaded(parity, x, y) {
                    Source::Shaded
                } else {
                    Source::History
                };
                assert_eq!(source, want);
            }
            // Not known to be still (the same frames from a camera that might have moved): the
            // dot's depth is outside its neighbours' range, so where it is missing it is clamped
            // to them.
            inp.still = false;
            let (c, _, _) = reconstruct(&inp, 3, 2);
            assert_eq!(
                (c - truth(3, 2)).abs().max_element() < 1e-5,
                shaded(parity, 3, 2),
                "parity {parity}: {c}"
            );
        }
    }

    #[test]
    fn depth_disparity_clamps_motion_over_coherent_colour_fills_and_no_history_fills() {
        let (w, h) = (3u32, 3u32);
        // Parity 0: the centre (1, 1) is shaded; take parity 1, where it is missing and its
        // neighbours (1,0), (0,1), (2,1), (1,2) are shaded.
        let truth = |x: u32, y: u32| match (x, y) {
            (0, 1) => Vec4::splat(0.2),
            (2, 1) => Vec4::splat(0.4),
            _ => Vec4::splat(0.3),
        };
        let rows = layers(w, h, 1, truth);
        let depth = vec![0.5; rows.len()];
        let history = vec![Vec4::splat(1.0); 9];
        // History depth at the same view depth: confident, the unclamped history.
        let same = vec![0.5; 9];
        let mut inp = inputs(w, h, 1, &rows, &depth, &history, &same);
        let near = |a: Vec4, b: f32| (a - Vec4::splat(b)).abs().max_element() < 1e-5;
        let (c, d, s) = reconstruct(&inp, 1, 1);
        assert!(
            near(c, 1.0) && d == 0.5 && s == Source::History,
            "{c} {d} {s:?}"
        );
        // History far behind: no confidence, clamped to the neighbours' max.
        let far = vec![0.01; 9];
        inp.history_depth = &far;
        assert!(near(reconstruct(&inp, 1, 1).0, 0.4));
        // Moving 4 px over neighbours whose vertical pair agrees: the vertical pair's mean.
        let velocity = vec![Vec4::new(0.0, -0.5, 1.0, 0.0); 9];
        inp.history_depth = &same;
        inp.velocity = Some(&velocity);
        inp.velocity_scale = 0.5;
        assert!(near(reconstruct(&inp, 1, 1).0, 0.3));
        inp.history_valid = false;
        let (c, _, s) = reconstruct(&inp, 1, 1);
        assert!(near(c, 0.3) && s == Source::Fill);
        // Motion from off screen: fill.
        inp.history_valid = true;
        let off = vec![Vec4::new(9.0, 0.0, 1.0, 0.0); 9];
        inp.velocity = Some(&off);
        assert_eq!(reconstruct(&inp, 1, 1).2, Source::Fill);
    }
}
