//! CPU model of `taau`'s resolve, step for step with `resolve.wgsl`: which render
//! sample an output pixel takes and whether it lands, the reprojection, the disocclusion test,
//! the Catmull-Rom history fetch, YCoCg variance clipping and the running-mean blend. Tests
//! compare it with the GPU output on real frames. In f32 like the shader; not for speed.

use glam::{IVec2, Mat4, Vec2, Vec3, Vec4};

use crate::render::velocity::MOTION_DEPTH_EPSILON;

const F16_MAX: f32 = 65504.0;

/// Everything one resolve reads.
#[derive(Clone, Copy)]
pub struct Inputs<'a> {
    pub low: (u32, u32),
    pub out: (u32, u32),
    pub jitter: Vec2,
    pub color_low: &'a [Vec4],
    pub depth_low: &'a [f32],
    /// The previous resolve's output: colour and accumulated weight (alpha).
    pub history: &'a [Vec4],
    pub depth_history: &'a [f32],
    /// The motion provider's velocity and depth at the render size (`low`), if recorded.
    pub velocity: Option<&'a [Vec4]>,
    pub velocity_depth: Option<&'a [f32]>,
    pub prev_from_cur: Mat4,
    pub history_valid: bool,
    pub camera_still: bool,
    /// Clip where nothing moved too (the default; off with `clip_moving_only`).
    pub clip_still: bool,
    pub clip_gamma: f32,
    pub depth_tolerance: f32,
    pub max_weight: f32,
    pub moving_weight: f32,
    pub fill_weight: f32,
    /// Still pixels at `max_weight` keep their history (`freeze_converged`).
    pub freeze_converged: bool,
}

/// What the resolve did at one pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// No usable history (first frame, cut, off screen, disoccluded).
    Reset,
    /// The history as reprojected, not rectified.
    History,
    /// The history clipped to the neighbourhood (something moved, or `clip_still`).
    Clipped,
}

/// One output pixel: its colour and weight (alpha), its sample's depth as the depth history
/// keeps it ([`pack_depth`]), whether the sample landed, what happened to the history, and
/// where the history was read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resolved {
    pub color: Vec4,
    pub depth: f32,
    pub lands: bool,
    pub source: Source,
    pub prev_pos: Vec2,
    pub prev_depth: f32,
}

/// The depth history's encoding: reversed-Z depth (0 to 1), plus 2 where the pixel showed a
/// dynamic (animated) object.
pub fn pack_depth(depth: f32, dynamic: bool) -> f32 {
    if dynamic {
        depth + 2.0
    } else {
        depth
    }
}

/// The inverse of [`pack_depth`].
pub fn unpack_depth(packed: f32) -> (f32, bool) {
    if packed >= 2.0 {
        (packed - 2.0, true)
    } else {
        (packed, false)
    }
}

pub fn sanitize(c: Vec3) -> Vec3 {
    Vec3::from_array(
        c.to_array()
            .map(|x| if x >= 0.0 { x.min(F16_MAX) } else { 0.0 }),
    )
}

pub fn to_ycocg(c: Vec3) -> Vec3 {
    Vec3::new(
        c.x * 0.25 + c.y * 0.5 + c.z * 0.25,
        c.x * 0.5 - c.z * 0.5,
        -c.x * 0.25 + c.y * 0.5 - c.z * 0.25,
    )
}

pub fn from_ycocg(c: Vec3) -> Vec3 {
    Vec3::new(c.x + c.y - c.z, c.x + c.z, c.x - c.y - c.z)
}

/// Catmull-Rom weights of the four taps around a fraction `f` in [0, 1).
pub fn catmull_rom(f: f32) -> [f32; 4] {
    [
        f * (-0.5 + f * (1.0 - 0.5 * f)),
        1.0 + f * f * (-2.5 + 1.5 * f),
        f * (0.5 + f * (2.0 - 1.5 * f)),
        f * f * (-0.5 + 0.5 * f),
    ]
}

/// Clips `h` (YCoCg) towards the centre of the box `lo`..`hi` (Bevy's `clip_towards_aabb_center`,
/// with the extent floored at 1e-3 of the centre's luma: the shader says why).
pub fn clip_towards_centre(h: Vec3, lo: Vec3, hi: Vec3) -> Vec3 {
    let centre = 0.5 * (hi + lo);
    let extent = 0.5 * (hi - lo) + (1e-3 * centre.x.abs() + 1e-6);
    let v = h - centre;
    let m = (v / extent).abs().max_element();
    if m > 1.0 {
        centre + v / m
    } else {
        h
    }
}

impl Inputs<'_> {
    fn low_at(&self, q: IVec2) -> Vec3 {
        let c = q.clamp(
            IVec2::ZERO,
            IVec2::new(self.low.0 as i32 - 1, self.low.1 as i32 - 1),
        );
        sanitize(self.color_low[(c.y as u32 * self.low.0 + c.x as u32) as usize].truncate())
    }

    fn out_index(&self, p: IVec2) -> usize {
        let c = p.clamp(
            IVec2::ZERO,
            IVec2::new(self.out.0 as i32 - 1, self.out.1 as i32 - 1),
        );
        (c.y as u32 * self.out.0 + c.x as u32) as usize
    }

    fn history_catmull_rom(&self, pos: Vec2) -> Vec3 {
        let t = pos - 0.5;
        let base = t.floor();
        let f = t - base;
        let (wx, wy) = (catmull_rom(f.x), catmull_rom(f.y));
        let b = base.as_ivec2();
        let mut sum = Vec3::ZERO;
        for (y, wy) in wy.iter().enumerate() {
            let mut row = Vec3::ZERO;
            for (x, wx) in wx.iter().enumerate() {
                let p = b + IVec2::new(x as i32 - 1, y as i32 - 1);
                row += self.history[self.out_index(p)].truncate() * *wx;
            }
            sum += row * *wy;
        }
        sum.max(Vec3::ZERO)
    }
}

/// The resolve at output pixel `(x, y)`.
pub fn resolve(inp: &Inputs, x: u32, y: u32) -> Resolved {
    let low_size = Vec2::new(inp.low.0 as f32, inp.low.1 as f32);
    let size = Vec2::new(inp.out.0 as f32, inp.out.1 as f32);
    let scale = low_size / size;
    let j = inp.jitter;
    let centre = Vec2::new(x as f32, y as f32) + 0.5;
    // 1. The nearest current sample and whether it lands here.
    let q = (centre * scale - j).floor().as_ivec2().clamp(
        IVec2::ZERO,
        IVec2::new(inp.low.0 as i32 - 1, inp.low.1 as i32 - 1),
    );
    let sample_pos = (q.as_vec2() + 0.5 + j) / scale;
    let lands = sample_pos.floor() == Vec2::new(x as f32, y as f32);
    let current = inp.low_at(q);
    let depth = inp.depth_low[(q.y as u32 * inp.low.0 + q.x as u32) as usize];
    let mut dynamic_here = false;

    // 2. Motion.
    let mut prev_pos = centre;
    let mut prev_depth = depth;
    let mut moving = false;
    let qi = (q.y as u32 * inp.low.0 + q.x as u32) as usize;
    let mut v = inp.velocity.map_or(Vec4::ZERO, |v| v[qi]);
    if let Some(vd) = inp.velocity_depth {
        // A static object in front of the dynamic one the motion pass drew.
        let vd = vd[qi];
        if depth - vd > MOTION_DEPTH_EPSILON * depth.max(vd) {
            v.z = 0.0;
        }
    }
    if v.z > 0.5 {
        dynamic_here = true;
        prev_pos = centre - Vec2::new(v.x, v.y);
        prev_depth = v.w;
        moving = v.x != 0.0 || v.y != 0.0;
    } else if !inp.camera_still {
        let ndc = Vec4::new(
            sample_pos.x / size.x * 2.0 - 1.0,
            1.0 - sample_pos.y / size.y * 2.0,
            depth,
            1.0,
        );
        let prev = inp.prev_from_cur * ndc;
        let prev_sample = Vec2::new(
            (prev.x / prev.w * 0.5 + 0.5) * size.x,
            (0.5 - prev.y / prev.w * 0.5) * size.y,
        );
        prev_pos = centre - (sample_pos - prev_sample);
        prev_depth = prev.z / prev.w;
        moving = true;
    }

    // 3. History.
    let mut weight = 0.0f32;
    let mut hist = Vec3::ZERO;
    let on_screen =
        prev_pos.x >= 0.0 && prev_pos.y >= 0.0 && prev_pos.x < size.x && prev_pos.y < size.y;
    if inp.history_valid && on_screen {
        let pp = prev_pos.floor().as_ivec2();
        let mut matched = false;
        let mut left = false;
        for dy in -1..=1 {
            for dx in -1..=1 {
                let (d, dynamic) =
                    unpack_depth(inp.depth_history[inp.out_index(pp + IVec2::new(dx, dy))]);
                let nearer = d - prev_depth > inp.depth_tolerance * d.max(prev_depth);
                matched |= !nearer;
                left |= nearer && dynamic;
            }
        }
        moving |= left;
        // On a still camera static content is disoccluded only by an animated object leaving.
        let can_disocclude = !inp.camera_still || dynamic_here || left;
        if matched || !can_disocclude {
            weight = inp.history[inp.out_index(pp)].w;
            hist = inp.history_catmull_rom(prev_pos);
        }
    }
    let mut source = if weight > 0.0 {
        Source::History
    } else {
        Source::Reset
    };

    // 4. Rectification.
    if weight > 0.0 && (moving || inp.clip_still) {
        let mut m1 = Vec3::ZERO;
        let mut m2 = Vec3::ZERO;
        for dy in -1..=1 {
            for dx in -1..=1 {
                let s = to_ycocg(inp.low_at(q + IVec2::new(dx, dy)));
                m1 += s;
                m2 += s * s;
            }
        }
        let mean = m1 / 9.0;
        let sigma = (m2 / 9.0 - mean * mean).max(Vec3::ZERO);
        let sigma = Vec3::new(sigma.x.sqrt(), sigma.y.sqrt(), sigma.z.sqrt());
        let g = inp.clip_gamma;
        hist = from_ycocg(clip_towards_centre(
            to_ycocg(hist),
            mean - g * sigma,
            mean + g * sigma,
        ))
        .max(Vec3::ZERO);
        if moving {
            weight = weight.min(inp.moving_weight);
        }
        source = Source::Clipped;
    }

    // 5. Blend.
    weight = weight.min(inp.max_weight);
    let mut w = if lands { 1.0 } else { 0.0 };
    if weight == 0.0 && !lands {
        w = inp.fill_weight;
    }
    if inp.freeze_converged && !moving && weight >= inp.max_weight {
        w = 0.0;
    }
    let total = weight + w;
    let out = if w > 0.0 {
        hist.lerp(current, w / total)
    } else {
        hist
    };
    Resolved {
        color: out.extend(total.min(inp.max_weight)),
        depth: pack_depth(depth, dynamic_here),
        lands,
        source,
        prev_pos,
        prev_depth,
    }
}

/// The resolve of every output pixel, row-major.
pub fn resolve_all(inp: &Inputs) -> Vec<Resolved> {
    (0..inp.out.1)
        .flat_map(|y| (0..inp.out.0).map(move |x| (x, y)))
        .map(|(x, y)| resolve(inp, x, y))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ycocg_round_trips() {
        for c in [Vec3::new(0.1, 0.7, 0.3), Vec3::new(5.0, 0.0, 2.0)] {
            assert!((from_ycocg(to_ycocg(c)) - c).abs().max_element() < 1e-6);
        }
    }

    #[test]
    fn catmull_rom_interpolates_and_sums_to_one() {
        assert_eq!(catmull_rom(0.0), [0.0, 1.0, 0.0, 0.0]);
        for f in [0.1f32, 0.5, 0.9] {
            let s: f32 = catmull_rom(f).iter().sum();
            assert!((s - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn grey_rounding_noise_in_chroma_does_not_clip() {
        // A grey box (flat chroma) and a grey history whose chroma is rounding noise.
        let lo = Vec3::new(0.5, 0.0, 0.0);
        let hi = Vec3::new(1.5, 0.0, 0.0);
        let h = Vec3::new(0.7, 1e-7, -1e-7);
        assert_eq!(clip_towards_centre(h, lo, hi), h);
    }

    #[test]
    fn clipping_moves_outside_points_onto_the_box_only() {
        let (lo, hi) = (Vec3::ZERO, Vec3::ONE);
        let inside = Vec3::splat(0.3);
        assert_eq!(clip_towards_centre(inside, lo, hi), inside);
        // Onto the box, which the extent floor (1e-3 of the centre's luma) widens a little.
        let c = clip_towards_centre(Vec3::new(3.0, 0.5, 0.5), lo, hi);
        assert!(
            (c - Vec3::new(1.0, 0.5, 0.5)).abs().max_element() < 2e-3,
            "{c}"
        );
    }

    fn flat_inputs<'a>(
        color: &'a [Vec4],
        depth: &'a [f32],
        history: &'a [Vec4],
        depth_history: &'a [f32],
    ) -> Inputs<'a> {
        Inputs {
            low: (4, 4),
            out: (4, 4),
            jitter: Vec2::new(0.25, -0.125),
            color_low: color,
            depth_low: depth,
            history,
            depth_history,
            velocity: None,
            velocity_depth: None,
            prev_from_cur: Mat4::IDENTITY,
            history_valid: true,
            camera_still: true,
            clip_still: false,
            clip_gamma: 1.0,
            depth_tolerance: 0.05,
            max_weight: 32.0,
            moving_weight: 8.0,
            fill_weight: 1.0 / 256.0,
            freeze_converged: true,
        }
    }

    #[test]
    fn a_still_pixel_takes_the_running_mean_and_a_disoccluded_one_resets() {
        let color = vec![Vec4::new(1.0, 1.0, 1.0, 1.0); 16];
        let depth = vec![0.5; 16];
        let history = vec![Vec4::new(0.0, 0.0, 0.0, 3.0); 16];
        let same = vec![0.5; 16];
        let r = resolve(&flat_inputs(&color, &depth, &history, &same), 1, 2);
        assert!(r.lands);
        assert_eq!(r.source, Source::History);
        // 3 samples of 0, one of 1.
        assert!(
            (r.color - Vec4::new(0.25, 0.25, 0.25, 4.0))
                .abs()
                .max_element()
                < 1e-6
        );
        // Last frame a nearer surface covered everything around: on a moving camera,
        // disoccluded, reset; on a still one static content cannot be, the history is kept.
        let other = vec![0.9; 16];
        let moving = Inputs {
            camera_still: false,
            ..flat_inputs(&color, &depth, &history, &other)
        };
        let r = resolve(&moving, 1, 2);
        assert_eq!(r.source, Source::Reset);
        assert_eq!(r.color, Vec4::new(1.0, 1.0, 1.0, 1.0));
        let still = resolve(&flat_inputs(&color, &depth, &history, &other), 1, 2);
        assert_eq!(still.source, Source::History);
        // A cut: reset.
        let mut cut = flat_inputs(&color, &depth, &history, &same);
        cut.history_valid = false;
        assert_eq!(resolve(&cut, 1, 2).source, Source::Reset);
    }

    #[test]
    fn upsampling_lands_one_sample_per_render_pixel() {
        let color = vec![Vec4::ONE; 4];
        let depth = vec![0.5; 4];
        let history = vec![Vec4::ZERO; 16];
        let dh = vec![0.5; 16];
        let inp = Inputs {
            low: (2, 2),
            ..flat_inputs(&color, &depth, &history, &dh)
        };
        let all = resolve_all(&inp);
        assert_eq!(all.iter().filter(|r| r.lands).count(), 4);
        // No history and no sample: the nearest sample at the fill weight.
        let fill = all.iter().find(|r| !r.lands).unwrap();
        assert_eq!(fill.color, Vec4::new(1.0, 1.0, 1.0, 1.0 / 256.0));
    }
}
