//! CPU model of the `checkerboard-2x2` reconstitution (`reconstitute.wgsl`),
//! step for step, in f32: the oracle the GPU output is compared with in tests.
//!
//! Not used when rendering. Inputs are full-resolution images as the shader reads them (the scene
//! pass's colour and depth, this frame's motion, the previous output, depth and motion) and the
//! parameters it receives.

use glam::{IVec2, Vec2, Vec3, Vec4};

use super::gpu::FrameParams;
use super::Clamp;

/// Everything the shader reads, row-major, `width * height` entries each.
pub struct Inputs<'a> {
    pub frame: FrameParams,
    pub scene_color: &'a [Vec4],
    /// Reversed-Z depth of the scene pass (1.0 in masked blocks).
    pub scene_depth: &'a [f32],
    /// Pixels per frame, current minus previous position, y down.
    pub motion: &'a [Vec4],
    pub history_color: &'a [Vec4],
    pub history_depth: &'a [f32],
    pub history_motion: &'a [Vec4],
}

/// How a pixel was made (for tests and debugging).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// Shaded this frame.
    Shaded,
    /// The neighbours' mean: no history, or the motion points off screen.
    Fill,
    /// The previous output at the end of the motion vector, unclamped.
    Reprojected,
    /// Clamped to the neighbours (uniform or conditional clamp, or a blend that used weights).
    Clamped,
    /// Blended clamp (5.3.7) where the clamp applied.
    Blended,
    /// No shaded neighbour at all (an image one block wide and high).
    Isolated,
}

impl<'a> Inputs<'a> {
    fn index(&self, p: IVec2) -> usize {
        (p.y as u32 * self.frame.width + p.x as u32) as usize
    }

    fn inside(&self, p: IVec2) -> bool {
        p.x >= 0 && p.y >= 0 && p.x < self.frame.width as i32 && p.y < self.frame.height as i32
    }

    fn linear01(&self, d: f32) -> f32 {
        let (n, f) = (self.frame.near, self.frame.far);
        let z = n * f / (d * (f - n) + n);
        (z - n) / (f - n)
    }

    fn clamp_weight(&self, difference: f32) -> f32 {
        if difference < self.frame.options.blend_min {
            return 0.0;
        }
        (difference / self.frame.options.blend_max).min(1.0)
    }

    fn prev(&self, p: IVec2) -> IVec2 {
        let m = self.motion[self.index(p)].truncate().truncate();
        let q = (p.as_vec2() + Vec2::splat(0.5) - m).floor();
        IVec2::new(q.x as i32, q.y as i32)
    }
}

fn neighbour(c: i32, start: i32, extent: i32) -> i32 {
    let (own, other) = if c == start {
        (start - 1, start + 2)
    } else {
        (start + 2, start - 1)
    };
    if own >= 0 && own < extent {
        own
    } else if other >= 0 && other < extent {
        other
    } else {
        -1
    }
}

/// Whether block (bx, by) is shaded at `parity`.
pub fn shaded(parity: u32, x: i32, y: i32) -> bool {
    (((x >> 1) + (y >> 1)) as u32 & 1) == parity
}

/// The reconstituted colour of masked pixel `p` and how it was made.
fn reconstitute(inp: &Inputs, p: IVec2) -> (Vec3, Source) {
    let f = &inp.frame;
    let o = &f.options;
    let rgb = |v: &[Vec4], q: IVec2| v[inp.index(q)].truncate();
    let start = IVec2::new(p.x >> 1, p.y >> 1) * 2;
    let mut h = IVec2::new(neighbour(p.x, start.x, f.width as i32), p.y);
    let mut v = IVec2::new(p.x, neighbour(p.y, start.y, f.height as i32));
    let (has_h, has_v) = (h.x >= 0, v.y >= 0);
    if !has_h && !has_v {
        if !f.reset {
            let prev = inp.prev(p);
            if inp.inside(prev) && rgb(inp.history_color, prev).is_finite() {
                return (rgb(inp.history_color, prev), Source::Isolated);
            }
        }
        return (rgb(inp.scene_color, p), Source::Isolated);
    }
    if !has_h {
        h = v;
    }
    if !has_v {
        v = h;
    }
    let (mut ch, mut cv) = (rgb(inp.scene_color, h), rgb(inp.scene_color, v));
    // The shader's stability rule: a non-finite neighbour stands aside for a finite one.
    if !ch.is_finite() && cv.is_finite() {
        ch = cv;
    }
    if !cv.is_finite() && ch.is_finite() {
        cv = ch;
    }
    let fill = 0.5 * (ch + cv);
    if f.reset {
        return (fill, Source::Fill);
    }
    let m = inp.motion[inp.index(p)].truncate().truncate();
    let prev = inp.prev(p);
    if !inp.inside(prev) {
        return (fill, Source::Fill);
    }
    let reprojected = rgb(inp.history_color, prev);
    if !reprojected.is_finite() {
        return (fill, Source::Fill);
    }
    if o.clamp == Clamp::None || !ch.is_finite() {
        return (reprojected, Source::Reprojected);
    }
    let clamped = reprojected.clamp(ch.min(cv), ch.max(cv));
    if o.clamp == Clamp::Uniform {
        return (clamped, Source::Clamped);
    }
    let threshold = o.motion_threshold;
    let mut clamp_on = m.length() > threshold;
    if o.motion_coherency && !clamp_on {
        let mh = inp.history_motion[inp.index(h)].truncate().truncate();
        let mv = inp.history_motion[inp.index(v)].truncate().truncate();
        clamp_on = (mh - m).length() > threshold || (mv - m).length() > threshold;
    }
    if !clamp_on {
        return (reprojected, Source::Reprojected);
    }
    if o.clamp == Clamp::Conditional {
        return (clamped, Source::Clamped);
    }
    let dp = inp.linear01(inp.history_depth[inp.index(prev)]);
    let wh = inp.clamp_weight((dp - inp.linear01(inp.scene_depth[inp.index(h)])).abs());
    let wv = inp.clamp_weight((dp - inp.linear01(inp.scene_depth[inp.index(v)])).abs());
    (
        0.5 * (reprojected.lerp(clamped, wh) + reprojected.lerp(clamped, wv)),
        Source::Blended,
    )
}

/// The whole output frame, row-major, with how each pixel was made.
pub fn reconstitute_all(inp: &Inputs) -> Vec<(Vec4, Source)> {
    let f = &inp.frame;
    let mut out = Vec::with_capacity((f.width * f.height) as usize);
    for y in 0..f.height as i32 {
        for x in 0..f.width as i32 {
            let p = IVec2::new(x, y);
            if shaded(f.parity, x, y) {
                out.push((
                    inp.scene_color[inp.index(p)].truncate().extend(1.0),
                    Source::Shaded,
                ));
            } else {
                let (c, s) = reconstitute(inp, p);
                out.push((c.extend(1.0), s));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::Options;
    use super::*;

    fn frame(width: u32, height: u32, parity: u32, clamp: Clamp) -> FrameParams {
        FrameParams {
            width,
            height,
            parity,
            reset: false,
            options: Options {
                clamp,
                motion_threshold: 1e-7,
                blend_min: 0.005,
                blend_max: 0.1,
                precondition: super::super::Precondition::Draw,
                motion_coherency: true,
            },
            near: 0.1,
            far: 10.1,
        }
    }

    #[test]
    fn neighbours_are_across_the_block_edge_on_the_pixels_side_and_mirror_at_borders() {
        // Block starting at 2: pixel 2's neighbour is 1, pixel 3's is 4.
        assert_eq!(neighbour(2, 2, 8), 1);
        assert_eq!(neighbour(3, 2, 8), 4);
        // At the left border pixel 0 takes 2; at the right border (width 4) pixel 3 takes 1.
        assert_eq!(neighbour(0, 0, 8), 2);
        assert_eq!(neighbour(3, 2, 4), 1);
        // One block wide: none.
        assert_eq!(neighbour(0, 0, 2), -1);
        assert_eq!(neighbour(1, 0, 1), -1);
    }

    #[test]
    fn parity_alternates_blocks_in_a_checkerboard() {
        assert!(shaded(0, 0, 0) && shaded(0, 1, 1) && !shaded(0, 2, 0) && !shaded(0, 0, 3));
        assert!(shaded(0, 2, 2) && shaded(1, 2, 0) && !shaded(1, 3, 3));
    }

    /// A 4x2 frame: block 0 shaded (parity 0), block 1 masked; history and scene colours chosen so
    /// that each clamp mode gives a different answer for pixel (2, 0).
    #[test]
    fn each_clamp_mode_follows_the_report() {
        let w = 4;
        let n = 8;
        let mut scene_color = vec![Vec4::ZERO; n];
        // Shaded neighbours of (2, 0): h = (1, 0); v mirrors to... (2, 0) has no vertical
        // neighbour in a 2-row image, so v = h. Make (1, 0) grey 0.5.
        scene_color[1] = Vec4::new(0.5, 0.5, 0.5, 1.0);
        let mut history_color = vec![Vec4::ZERO; n];
        history_color[2] = Vec4::new(0.9, 0.1, 0.5, 1.0);
        let motion = vec![Vec4::ZERO; n];
        let mut history_motion = vec![Vec4::ZERO; n];
        let scene_depth = vec![0.5; n];
        let history_depth = vec![0.5; n];
        let run = |clamp, motion: &[Vec4], history_motion: &[Vec4], history_depth: &[f32]| {
            let inp = Inputs {
                frame: frame(w, 2, 0, clamp),
                scene_color: &scene_color,
                scene_depth: &scene_depth,
                motion,
                history_color: &history_color,
                history_depth,
                history_motion,
            };
            reconstitute_all(&inp)[2]
        };
        let hist = Vec3::new(0.9, 0.1, 0.5);
        let grey = Vec3::splat(0.5);
        assert_eq!(
            run(Clamp::None, &motion, &history_motion, &history_depth),
            (hist.extend(1.0), Source::Reprojected)
        );
        assert_eq!(
            run(Clamp::Uniform, &motion, &history_motion, &history_depth),
            (grey.extend(1.0), Source::Clamped)
        );
        // Still and coherent: conditional and blended keep the reprojection (5.3.5).
        for c in [Clamp::Conditional, Clamp::Blended] {
            assert_eq!(
                run(c, &motion, &history_motion, &history_depth).1,
                Source::Reprojected
            );
        }
        // A neighbour moved last frame: coherency turns the clamp on (5.3.8).
        history_motion[1] = Vec4::new(3.0, 0.0, 0.0, 1.0);
        assert_eq!(
            run(Clamp::Conditional, &motion, &history_motion, &history_depth),
            (grey.extend(1.0), Source::Clamped)
        );
        // Blended with equal depths: weight 0, the reprojection survives the clamp (5.3.7).
        let (c, s) = run(Clamp::Blended, &motion, &history_motion, &history_depth);
        assert_eq!((c.truncate(), s), (hist, Source::Blended));
        // Blended with a depth difference of half the maximum: halfway to the clamp.
        let inp_depth = {
            let f = frame(w, 2, 0, Clamp::Blended);
            // Linear depth 0.05 above the neighbours' (0.5 reversed-Z at near 0.1, far 10.1).
            let lin = |d: f32| {
                let z = f.near * f.far / (d * (f.far - f.near) + f.near);
                (z - f.near) / (f.far - f.near)
            };
            let target = lin(0.5) + 0.05;
            let z = f.near + target * (f.far - f.near);
            (f.near * f.far / z - f.near) / (f.far - f.near)
        };
        let mut deeper = history_depth.clone();
        deeper[2] = inp_depth;
        let (c, _) = run(Clamp::Blended, &motion, &history_motion, &deeper);
        let expected = hist.lerp(grey, 0.5);
        assert!((c.truncate() - expected).abs().max_element() < 1e-4, "{c}");
    }
}
