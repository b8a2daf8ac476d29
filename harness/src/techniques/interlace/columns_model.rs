//! CPU model of the column-interlace reconstruction (`pattern = "columns"`, `columns.wgsl`), step for
//! step in f32: the oracle the GPU output is compared with in tests.
//!
//! Not used when rendering.

use glam::{Mat4, Vec2, Vec4};

/// What one reconstruction reads: this frame's half-resolution colour and depth, the previous
/// output, the velocity buffer if bound, and the frame's constants.
pub struct Inputs<'a> {
    pub width: u32,
    pub height: u32,
    /// Shaded columns this frame: x = 2i + parity.
    pub parity: u32,
    pub half_width: u32,
    /// `half_width * height` RGBA texels.
    pub half_color: &'a [Vec4],
    pub half_depth: &'a [f32],
    /// The previous output, `width * height`; read only when `history_valid`.
    pub history: &'a [Vec4],
    /// Full-resolution velocity (xy: current minus previous position, pixels; z > 0.5: covered).
    pub velocity: Option<&'a [Vec4]>,
    pub prev_from_cur: Mat4,
    pub history_valid: bool,
    pub clamp: bool,
}

/// Where a pixel's colour came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// Shaded this frame.
    Shaded,
    /// The mean of its left and right neighbours (no history, or off screen last frame).
    Fill,
    /// The previous output, reprojected (and clamped when on).
    History,
}

impl Inputs<'_> {
    fn half_at(&self, i: i32, y: i32) -> Vec4 {
        let i = i.clamp(0, self.half_width as i32 - 1);
        let y = y.clamp(0, self.height as i32 - 1);
        self.half_color[(y * self.half_width as i32 + i) as usize]
    }

    fn depth_at(&self, i: i32, y: i32) -> f32 {
        let i = i.clamp(0, self.half_width as i32 - 1);
        let y = y.clamp(0, self.height as i32 - 1);
        self.half_depth[(y * self.half_width as i32 + i) as usize]
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
}

/// WGSL's `mix`: `a * (1 - t) + b * t`.
fn mix(a: Vec4, b: Vec4, t: f32) -> Vec4 {
    a * (1.0 - t) + b * t
}

/// Whether column `x` is shaded on frames of `parity`.
pub fn shaded(parity: u32, x: u32) -> bool {
    (x as i32 - parity as i32) & 1 == 0
}

/// The half-resolution width for an output `width` wide: every column of either parity has a
/// texel (`ceil(width / 2)`).
pub fn half_width(width: u32) -> u32 {
    width.div_ceil(2)
}

/// The reconstructed pixel `(x, y)` and where it came from.
pub fn reconstruct(inp: &Inputs, x: u32, y: u32) -> (Vec4, Source) {
    let p = inp.parity as i32;
    let (x, y) = (x as i32, y as i32);
    if (x - p) & 1 == 0 {
        return (inp.half_at((x - p) >> 1, y), Source::Shaded);
    }
    let il = (x - 1 - p) >> 1;
    let ir = il + 1;
    let left = inp.half_at(il, y);
    let right = inp.half_at(ir, y);
    let fill = 0.5 * (left + right);
    if !inp.history_valid {
        return (fill, Source::Fill);
    }
    let size = Vec2::new(inp.width as f32, inp.height as f32);
    let centre = Vec2::new(x as f32, y as f32) + 0.5;
    let mut prev_pos = centre;
    let v = inp
        .velocity
        .map(|v| v[(y * inp.width as i32 + x) as usize])
        .unwrap_or(Vec4::ZERO);
    if v.z > 0.5 {
        prev_pos = centre - Vec2::new(v.x, v.y);
    } else {
        let d = inp.depth_at(il, y).max(inp.depth_at(ir, y));
        if d > 0.0 {
            let ndc = Vec4::new(
                centre.x / size.x * 2.0 - 1.0,
                1.0 - centre.y / size.y * 2.0,
                d,
                1.0,
            );
            let prev = inp.prev_from_cur * ndc;
            prev_pos = Vec2::new(
                (prev.x / prev.w * 0.5 + 0.5) * size.x,
                (0.5 - prev.y / prev.w * 0.5) * size.y,
            );
        }
    }
    let on_screen =
        prev_pos.x >= 0.0 && prev_pos.y >= 0.0 && prev_pos.x < size.x && prev_pos.y < size.y;
    if !on_screen {
        return (fill, Source::Fill);
    }
    let mut h = inp.history_bilinear(prev_pos);
    if inp.clamp {
        let mut lo = left.min(right);
        let mut hi = left.max(right);
        for dy in [-1, 1] {
            let a = inp.half_at(il, y + dy);
            let b = inp.half_at(ir, y + dy);
            lo = lo.min(a.min(b));
            hi = hi.max(a.max(b));
        }
        h = h.max(lo).min(hi);
    }
    (h, Source::History)
}

/// Every pixel, row-major.
pub fn reconstruct_all(inp: &Inputs) -> Vec<(Vec4, Source)> {
    (0..inp.height)
        .flat_map(|y| (0..inp.width).map(move |x| (x, y)))
        .map(|(x, y)| reconstruct(inp, x, y))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A half-resolution frame whose texel i of row y holds the colour of full column 2i + p.
    fn half(width: u32, height: u32, parity: u32, truth: impl Fn(u32, u32) -> Vec4) -> Vec<Vec4> {
        let hw = half_width(width);
        (0..height)
            .flat_map(|y| (0..hw).map(move |i| (i, y)))
            .map(|(i, y)| truth(2 * i + parity, y))
            .collect()
    }

    #[test]
    fn columns_alternate_and_every_column_is_shaded_every_two_frames() {
        for width in [1u32, 2, 5, 8] {
            for x in 0..width {
                assert_ne!(shaded(0, x), shaded(1, x));
                assert!(x / 2 < half_width(width) || !shaded(0, x));
            }
        }
    }

    #[test]
    fn a_static_camera_rebuilds_the_previous_frame_exactly() {
        let (w, h) = (7u32, 3u32);
        let truth = |x: u32, y: u32| Vec4::new(x as f32 / 8.0, y as f32 / 4.0, 0.5, 1.0);
        let history: Vec<Vec4> = (0..h)
            .flat_map(|y| (0..w).map(move |x| truth(x, y)))
            .collect();
        for parity in [0, 1] {
            let hc = half(w, h, parity, truth);
            let depth = vec![0.5; hc.len()];
            let inp = Inputs {
                width: w,
                height: h,
                parity,
                half_width: half_width(w),
                half_color: &hc,
                half_depth: &depth,
                history: &history,
                velocity: None,
                prev_from_cur: Mat4::IDENTITY,
                history_valid: true,
                clamp: true,
            };
            for (i, (c, source)) in reconstruct_all(&inp).into_iter().enumerate() {
                let (x, y) = (i as u32 % w, i as u32 / w);
                // Column 0 on odd frames has one shaded neighbour (column 1), which bounds it.
                let want = if parity == 1 && x == 0 {
                    Vec4::new(truth(1, y).x, truth(0, y).y, 0.5, 1.0)
                } else {
                    truth(x, y)
                };
                // The depth round trip through the identity matrices is exact to f32 rounding.
                assert!(
                    (c - want).abs().max_element() < 1e-5,
                    "parity {parity} pixel {x},{y}: {c} against {want}"
                );
                let want = if shaded(parity, x) {
                    Source::Shaded
                } else {
                    Source::History
                };
                assert_eq!(source, want);
            }
        }
    }

    #[test]
    fn no_history_fills_from_the_left_and_right_and_history_is_clamped() {
        let (w, h) = (4u32, 1u32);
        let hc = vec![Vec4::splat(0.2), Vec4::splat(0.4)];
        let depth = vec![0.5; 2];
        let history = vec![Vec4::splat(1.0); 4];
        let mut inp = Inputs {
            width: w,
            height: h,
            parity: 0,
            half_width: 2,
            half_color: &hc,
            half_depth: &depth,
            history: &history,
            velocity: None,
            prev_from_cur: Mat4::IDENTITY,
            history_valid: false,
            clamp: true,
        };
        assert_eq!(reconstruct(&inp, 1, 0), (Vec4::splat(0.3), Source::Fill));
        // The last column's right neighbour is clamped to the last texel.
        assert_eq!(reconstruct(&inp, 3, 0), (Vec4::splat(0.4), Source::Fill));
        inp.history_valid = true;
        assert_eq!(reconstruct(&inp, 1, 0), (Vec4::splat(0.4), Source::History));
        inp.clamp = false;
        assert_eq!(reconstruct(&inp, 1, 0), (Vec4::splat(1.0), Source::History));
        // Motion from off screen: fill.
        let velocity = vec![Vec4::new(5.0, 0.0, 1.0, 0.0); 4];
        inp.velocity = Some(&velocity);
        assert_eq!(reconstruct(&inp, 1, 0), (Vec4::splat(0.3), Source::Fill));
    }
}
