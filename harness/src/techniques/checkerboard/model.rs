//! CPU model of the checkerboard reconstruction (`resolve.wgsl`), step for
//! step, in f32: the oracle the GPU output is compared with in tests.
//!
//! Not used when rendering. Inputs are the quarter-resolution samples of the current and previous
//! frame (as read back from the two-pass targets), the velocity buffer and its depth, and the
//! parameters the shader receives.

use glam::{Mat4, Vec2, Vec3, Vec4};

use super::{AsoMotion, Clamp, Fill, Occlusion, Options, VelocityObjects};

/// One frame's quarter-resolution samples: colour and reversed-Z depth per sample index.
#[derive(Clone, Debug)]
pub struct Samples {
    pub width: u32,
    pub height: u32,
    pub color: [Vec<Vec4>; 2],
    pub depth: [Vec<f32>; 2],
}

/// Everything the shader reads.
pub struct Inputs<'a> {
    pub width: u32,
    pub height: u32,
    pub parity: u32,
    pub reset: bool,
    pub options: Options,
    pub near: f32,
    pub far: f32,
    /// Previous frame's NDC to current clip space.
    pub reproject: Mat4,
    pub current: &'a Samples,
    pub previous: &'a Samples,
    /// Full-resolution velocity (pixels, y down; z = 1 on dynamic objects), if recorded.
    pub velocity: Option<&'a [Vec4]>,
    /// The velocity pass's reversed-Z depth (full resolution, 0 where it drew nothing): needed
    /// with `velocity_objects = "dynamic"` and a velocity buffer, for the static-occluder test.
    pub velocity_depth: Option<&'a [f32]>,
}

fn is_current(inp: &Inputs, q: u32) -> bool {
    let even_quadrant = q == 0 || q == 3;
    even_quadrant == (inp.parity == 0)
}

fn quadrant(x: i32, y: i32) -> u32 {
    (x & 1) as u32 + 2 * (y & 1) as u32
}

/// Intel's readFromQuadrant: (quarter pixel, sample) of quadrant q of block (bx, by).
fn quadrant_source(bx: i32, by: i32, q: u32) -> (i32, i32, usize) {
    match q {
        0 => (bx, by, 1),
        1 => (bx + 1, by, 1),
        _ => (bx, by, 0),
    }
}

fn samples_for<'a>(inp: &'a Inputs, q: u32) -> &'a Samples {
    if is_current(inp, q) {
        inp.current
    } else {
        inp.previous
    }
}

fn color_at(inp: &Inputs, x: i32, y: i32) -> Vec4 {
    let q = quadrant(x, y);
    let (sx, sy, s) = quadrant_source(x >> 1, y >> 1, q);
    let set = samples_for(inp, q);
    set.color[s][(sy as u32 * set.width + sx as u32) as usize]
}

fn depth_at(inp: &Inputs, x: i32, y: i32) -> f32 {
    let q = quadrant(x, y);
    let (sx, sy, s) = quadrant_source(x >> 1, y >> 1, q);
    let set = samples_for(inp, q);
    set.depth[s][(sy as u32 * set.width + sx as u32) as usize]
}

fn linear_depth(inp: &Inputs, d: f32) -> f32 {
    inp.near * inp.far / (d * (inp.far - inp.near) + inp.near)
}

fn tonemap(c: Vec3) -> Vec3 {
    c / (1.0 + c.max_element())
}

fn untonemap(c: Vec3) -> Vec3 {
    c / (1.0 - c.max_element()).max(1e-6)
}

const OFFSETS: [(i32, i32); 4] = [(0, -1), (0, 1), (-1, 0), (1, 0)];

fn inside(inp: &Inputs, x: i32, y: i32) -> bool {
    x >= 0 && y >= 0 && x < inp.width as i32 && y < inp.height as i32
}

struct Neighbourhood {
    c: [Vec3; 4],
    /// On screen and finite.
    valid: [bool; 4],
    count: f32,
    lo: Vec3,
    hi: Vec3,
    /// A non-finite neighbour's colour, when one was left out.
    non_finite: Option<Vec3>,
}

fn neighbourhood(inp: &Inputs, x: i32, y: i32, tonemapped: bool) -> Neighbourhood {
    let mut n = Neighbourhood {
        c: [Vec3::ZERO; 4],
        valid: [false; 4],
        count: 0.0,
        lo: Vec3::splat(3.0e38),
        hi: Vec3::splat(-3.0e38),
        non_finite: None,
    };
    for (i, (dx, dy)) in OFFSETS.into_iter().enumerate() {
        let (px, py) = (x + dx, y + dy);
        n.valid[i] = inside(inp, px, py);
        if n.valid[i] {
            let mut c = color_at(inp, px, py).truncate();
            // Non-finite neighbours are left out (the shader's stability rule).
            if !c.is_finite() {
                n.valid[i] = false;
                n.non_finite = Some(c);
                continue;
            }
            if tonemapped {
                c = tonemap(c);
            }
            n.c[i] = c;
            n.lo = n.lo.min(c);
            n.hi = n.hi.max(c);
            n.count += 1.0;
        }
    }
    n
}

fn neighbour_depth(inp: &Inputs, x: i32, y: i32) -> f32 {
    let (mut sum, mut count) = (0.0f32, 0.0f32);
    for (dx, dy) in OFFSETS {
        if inside(inp, x + dx, y + dy) {
            sum += linear_depth(inp, depth_at(inp, x + dx, y + dy));
            count += 1.0;
        }
    }
    sum / count.max(1.0)
}

fn fill(inp: &Inputs, n: &Neighbourhood) -> Vec3 {
    if inp.options.fill == Fill::Differential && n.valid.iter().all(|v| *v) {
        let wv = 1.0 / (n.c[0] - n.c[1]).length().max(0.001);
        let wh = 1.0 / (n.c[2] - n.c[3]).length().max(0.001);
        return 0.5 * (wv * (n.c[0] + n.c[1]) + wh * (n.c[2] + n.c[3])) / (wv + wh);
    }
    let mut sum = Vec3::ZERO;
    for i in 0..4 {
        if n.valid[i] {
            sum += n.c[i];
        }
    }
    sum / n.count.max(1.0)
}

fn finish(c: Vec3, tonemapped: bool) -> Vec4 {
    if tonemapped {
        untonemap(c).extend(1.0)
    } else {
        c.extend(1.0)
    }
}

/// How a pixel was reconstructed (for tests and debugging).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    Current,
    /// Spatial fill: reset, off screen, jitter cancelled, or occluded.
    Fill,
    History,
}

fn filled(inp: &Inputs, x: i32, y: i32) -> (Vec4, Source) {
    let tonemapped = inp.options.fill != Fill::Plain;
    let n = neighbourhood(inp, x, y, tonemapped);
    if let (0.0, Some(c)) = (n.count, n.non_finite) {
        // Inside a non-finite region: it stays non-finite.
        return (c.extend(1.0), Source::Fill);
    }
    (finish(fill(inp, &n), tonemapped), Source::Fill)
}

/// Where a missing pixel's content was last frame came from (the shader's step 3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Motion {
    /// The velocity buffer (a dynamic object).
    Velocity,
    /// Camera reprojection of the previous sample's depth (static content, or a static object
    /// in front of a dynamic one in a dynamic-only velocity buffer).
    Camera,
}

/// Step 3: the previous position (full-resolution pixels) of missing pixel (x, y), and how it
/// was found.
pub fn previous_position(inp: &Inputs, x: i32, y: i32) -> (Vec2, Motion) {
    let size = Vec2::new(inp.width as f32, inp.height as f32);
    let centre = Vec2::new(x as f32, y as f32) + 0.5;
    let i = (y as u32 * inp.width + x as u32) as usize;
    let v = inp.velocity.map(|v| v[i]).unwrap_or(Vec4::ZERO);
    let mut dynamic = inp.velocity.is_some() && v.z > 0.5;
    // A dynamic-only buffer says nothing of static occluders: where the dynamic surface is behind
    // this frame's neighbours by the tolerance, a static object hides it (`resolve.wgsl`).
    if dynamic && inp.options.velocity_objects == VelocityObjects::Dynamic {
        let depth = inp
            .velocity_depth
            .expect("velocity_depth is needed with velocity_objects = \"dynamic\"")[i];
        let behind = linear_depth(inp, depth) - neighbour_depth(inp, x, y);
        dynamic = behind < inp.options.depth_tolerance;
    }
    if dynamic {
        return (centre - v.truncate().truncate(), Motion::Velocity);
    }
    let d = depth_at(inp, x, y);
    let ndc = Vec4::new(
        centre.x / size.x * 2.0 - 1.0,
        1.0 - centre.y / size.y * 2.0,
        d,
        1.0,
    );
    let now = inp.reproject * ndc;
    let now_px = Vec2::new(
        (now.x / now.w * 0.5 + 0.5) * size.x,
        (0.5 - now.y / now.w * 0.5) * size.y,
    );
    (centre - (now_px - centre), Motion::Camera)
}

/// The reconstructed colour of full-resolution pixel (x, y) and how it was made.
pub fn reconstruct(inp: &Inputs, x: i32, y: i32) -> (Vec4, Source) {
    let q = quadrant(x, y);
    if is_current(inp, q) {
        return (color_at(inp, x, y), Source::Current);
    }
    if inp.reset {
        return filled(inp, x, y);
    }
    let (prev_pos, _) = previous_position(inp, x, y);
    let (px, py) = (prev_pos.x.floor() as i32, prev_pos.y.floor() as i32);
    if !inside(inp, px, py) || is_current(inp, quadrant(px, py)) {
        return filled(inp, x, y);
    }
    let moved_block = (px >> 1) != (x >> 1) || (py >> 1) != (y >> 1);
    let confidence_clamp = inp.options.clamp == Clamp::MinMaxConfidence;
    let deviation = if (moved_block && inp.options.occlusion != Occlusion::Aso) || confidence_clamp
    {
        (neighbour_depth(inp, x, y) - linear_depth(inp, depth_at(inp, px, py))).abs()
    } else {
        0.0
    };
    let occluded = match inp.options.occlusion {
        Occlusion::Cso => moved_block && deviation >= inp.options.depth_tolerance,
        Occlusion::Aso => match inp.options.aso_motion {
            AsoMotion::QuarterTexel => {
                let centre = Vec2::new(x as f32, y as f32) + 0.5;
                (prev_pos - centre).length() > 2.0
            }
            AsoMotion::Block => moved_block,
        },
    };
    if occluded {
        return filled(inp, x, y);
    }
    let history = color_at(inp, px, py);
    if !history.truncate().is_finite() {
        return filled(inp, x, y);
    }
    if inp.options.clamp == Clamp::None {
        return (history, Source::History);
    }
    let tonemapped = inp.options.fill != Fill::Plain;
    let n = neighbourhood(inp, x, y, tonemapped);
    if n.count == 0.0 {
        return (history, Source::History);
    }
    let mut h = history.truncate();
    if tonemapped {
        h = tonemap(h);
    }
    let clamped = h.clamp(n.lo, n.hi);
    h = if confidence_clamp {
        let d = deviation - inp.options.depth_tolerance;
        clamped.lerp(h, (d * d).clamp(0.0, 1.0))
    } else {
        clamped
    };
    (finish(h, tonemapped), Source::History)
}

/// The whole frame, row-major.
pub fn reconstruct_all(inp: &Inputs) -> Vec<(Vec4, Source)> {
    let mut out = Vec::with_capacity((inp.width * inp.height) as usize);
    for y in 0..inp.height as i32 {
        for x in 0..inp.width as i32 {
            out.push(reconstruct(inp, x, y));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::{quarter_size, quarter_view, two_pass_jitter};
    use super::*;
    use crate::gpu::STANDARD_2X;

    /// Exhaustive coverage (notes section 2, "Coverage theorem"): with the quarter-resolution
    /// remap, the odd-frame shift and the standard positions, every sample lands on a
    /// full-resolution pixel centre, and two frames cover every pixel exactly once.
    #[test]
    fn two_frames_cover_every_full_resolution_pixel_once() {
        for (w, h) in [(8u32, 6u32), (7, 5), (1, 1), (3, 2)] {
            let (qw, qh) = quarter_size(w, h);
            let mut hits = vec![0u32; (w * h) as usize];
            for parity in 0..2 {
                let (scale, offset) = quarter_view(w, h, parity, Vec2::ZERO);
                for qy in 0..qh {
                    for qx in 0..qw {
                        for pos in STANDARD_2X {
                            // Sample position in quarter NDC, mapped back to full-resolution pixels.
                            let q_ndc = Vec2::new(
                                (qx as f32 + pos[0]) / qw as f32 * 2.0 - 1.0,
                                1.0 - (qy as f32 + pos[1]) / qh as f32 * 2.0,
                            );
                            let ndc = (q_ndc - offset) / scale;
                            let px = (ndc.x + 1.0) * 0.5 * w as f32;
                            let py = (1.0 - ndc.y) * 0.5 * h as f32;
                            assert!(
                                (px.rem_euclid(1.0) - 0.5).abs() < 1e-4
                                    && (py.rem_euclid(1.0) - 0.5).abs() < 1e-4,
                                "sample at ({px}, {py})"
                            );
                            let (x, y) = (px.floor() as i32, py.floor() as i32);
                            if x >= 0 && y >= 0 && x < w as i32 && y < h as i32 {
                                // It is the quadrant this parity shades, read back where Intel's map says.
                                let q = quadrant(x, y);
                                assert_eq!(
                                    q == 0 || q == 3,
                                    parity == 0,
                                    "parity {parity} shaded quadrant {q}"
                                );
                                let s = if pos == STANDARD_2X[0] { 0 } else { 1 };
                                assert_eq!(
                                    quadrant_source(x >> 1, y >> 1, q),
                                    (qx as i32, qy as i32, s)
                                );
                                hits[(y as u32 * w + x as u32) as usize] += 1;
                            }
                        }
                    }
                }
            }
            assert!(hits.iter().all(|&n| n == 1), "{w}x{h}: {hits:?}");
        }
    }

    #[test]
    fn two_pass_jitter_moves_the_pixel_centre_onto_each_standard_position() {
        for (s, position) in STANDARD_2X.iter().enumerate() {
            let centre_sees = Vec2::splat(0.5) - two_pass_jitter(s);
            assert_eq!(centre_sees, Vec2::from(*position));
        }
    }

    fn flat(w: u32, h: u32, color: impl Fn(u32, u32, usize) -> Vec4, depth: f32) -> Samples {
        let (qw, qh) = quarter_size(w, h);
        let mk = |s: usize| {
            (0..qh)
                .flat_map(|y| (0..qw).map(move |x| (x, y)))
                .map(|(x, y)| color(x, y, s))
                .collect()
        };
        Samples {
            width: qw,
            height: qh,
            color: [mk(0), mk(1)],
            depth: [
                vec![depth; (qw * qh) as usize],
                vec![depth; (qw * qh) as usize],
            ],
        }
    }

    fn options(fill: Fill, clamp: Clamp) -> Options {
        Options {
            occlusion: Occlusion::Cso,
            fill,
            clamp,
            depth_tolerance: 0.01,
            ..Options::default()
        }
    }

    #[test]
    fn static_history_fills_the_other_parity_exactly() {
        let (w, h) = (6, 4);
        // Every full-res pixel has its own colour; the samples hold them where the map says.
        let truth = |x: u32, y: u32| Vec4::new(x as f32 / 8.0, y as f32 / 8.0, 0.25, 1.0);
        let even = flat(
            w,
            h,
            |qx, qy, s| {
                if s == 1 {
                    truth(2 * qx, 2 * qy)
                } else {
                    truth(2 * qx + 1, 2 * qy + 1)
                }
            },
            0.5,
        );
        let odd = flat(
            w,
            h,
            |qx, qy, s| {
                if s == 1 {
                    truth((2 * qx).wrapping_sub(1), 2 * qy)
                } else {
                    truth(2 * qx, 2 * qy + 1)
                }
            },
            0.5,
        );
        for (parity, cur, prev) in [(0, &even, &odd), (1, &odd, &even)] {
            let inp = Inputs {
                width: w,
                height: h,
                parity,
                reset: false,
                options: options(Fill::Differential, Clamp::None),
                near: 0.1,
                far: 100.0,
                reproject: Mat4::IDENTITY,
                current: cur,
                previous: prev,
                velocity: None,
                velocity_depth: None,
            };
            for (i, (c, src)) in reconstruct_all(&inp).into_iter().enumerate() {
                let (x, y) = (i as u32 % w, i as u32 / w);
                assert_eq!(
                    c.truncate(),
                    truth(x, y).truncate(),
                    "pixel ({x}, {y}) parity {parity} from {src:?}"
                );
                assert_ne!(src, Source::Fill);
            }
        }
    }

    #[test]
    fn reset_fills_from_neighbours_and_fill_modes_differ_at_edges() {
        let (w, h) = (4, 4);
        let white = flat(w, h, |_, _, _| Vec4::ONE, 0.5);
        let inp = Inputs {
            width: w,
            height: h,
            parity: 0,
            reset: true,
            options: options(Fill::Plain, Clamp::None),
            near: 0.1,
            far: 100.0,
            reproject: Mat4::IDENTITY,
            current: &white,
            previous: &white,
            velocity: None,
            velocity_depth: None,
        };
        let (c, src) = reconstruct(&inp, 1, 0);
        assert_eq!(src, Source::Fill);
        assert_eq!(c, Vec4::ONE);
        // A vertical edge: left neighbours black, right white. Differential blending favours the
        // smoother (vertical) pair; the plain mean mixes across the edge.
        let edge = flat(
            w,
            h,
            |qx, _, s| {
                if 2 * qx + (1 - s as u32) > 2 {
                    Vec4::ONE
                } else {
                    Vec4::new(0.0, 0.0, 0.0, 1.0)
                }
            },
            0.5,
        );
        let mut inp = Inputs {
            current: &edge,
            previous: &edge,
            ..inp
        };
        let plain = reconstruct(&inp, 2, 1).0;
        inp.options = options(Fill::Differential, Clamp::None);
        let differential = reconstruct(&inp, 2, 1).0;
        assert_ne!(plain, differential);
    }

    #[test]
    fn motion_that_cancels_the_jitter_is_missing() {
        let (w, h) = (8, 4);
        let c = flat(w, h, |_, _, _| Vec4::new(0.5, 0.5, 0.5, 1.0), 0.5);
        // Content moved one pixel right: the pixel was one to the left last frame, in a quadrant the
        // previous (odd) frame did not shade.
        let velocity: Vec<Vec4> = vec![Vec4::new(1.0, 0.0, 1.0, 0.0); (w * h) as usize];
        // The moving surface is the one the samples show (not behind a static occluder).
        let velocity_depth = vec![0.5; (w * h) as usize];
        let inp = Inputs {
            width: w,
            height: h,
            parity: 0,
            reset: false,
            options: options(Fill::Plain, Clamp::None),
            near: 0.1,
            far: 100.0,
            reproject: Mat4::IDENTITY,
            current: &c,
            previous: &c,
            velocity: Some(&velocity),
            velocity_depth: Some(&velocity_depth),
        };
        assert_eq!(reconstruct(&inp, 3, 0).1, Source::Fill);
        // Two pixels: the quadrant matches again, the block differs, depths agree: history.
        let velocity: Vec<Vec4> = vec![Vec4::new(2.0, 0.0, 1.0, 0.0); (w * h) as usize];
        let inp = Inputs {
            velocity: Some(&velocity),
            ..inp
        };
        assert_eq!(reconstruct(&inp, 3, 0).1, Source::History);
        // ASO as mosaiikki assumes the pixel moved to another block occluded ...
        let aso = |aso_motion| Options {
            occlusion: Occlusion::Aso,
            aso_motion,
            ..options(Fill::Plain, Clamp::None)
        };
        let block = Inputs {
            options: aso(AsoMotion::Block),
            ..inp
        };
        assert_eq!(reconstruct(&block, 3, 0).1, Source::Fill);
        // ... as Intel only beyond a quarter-resolution texel: 2 px is not more than one.
        let intel = Inputs {
            options: aso(AsoMotion::QuarterTexel),
            ..inp
        };
        assert_eq!(reconstruct(&intel, 3, 0).1, Source::History);
        let velocity: Vec<Vec4> = vec![Vec4::new(4.0, 0.0, 1.0, 0.0); (w * h) as usize];
        let far = Inputs {
            velocity: Some(&velocity),
            ..intel
        };
        assert_eq!(reconstruct(&far, 5, 0).1, Source::Fill);
        let far_no_aso = Inputs {
            options: options(Fill::Plain, Clamp::None),
            ..far
        };
        assert_eq!(reconstruct(&far_no_aso, 5, 0).1, Source::History);
    }

    #[test]
    fn a_dynamic_surface_behind_its_neighbours_is_camera_reprojected_with_a_dynamic_only_buffer() {
        let (w, h) = (8, 4);
        let n = (w * h) as usize;
        // This frame's samples at reversed-Z 0.5 (view depth ~0.2); the velocity buffer says
        // "dynamic, 2 px right" everywhere; the camera is still.
        let c = flat(w, h, |_, _, _| Vec4::new(0.5, 0.5, 0.5, 1.0), 0.5);
        let velocity = vec![Vec4::new(2.0, 0.0, 1.0, 0.0); n];
        let at = |depth: f32| vec![depth; n];
        let (same, behind, in_front) = (at(0.5), at(0.01), at(0.9));
        let inp = |objects, velocity_depth| Inputs {
            width: w,
            height: h,
            parity: 0,
            reset: false,
            options: Options {
                velocity_objects: objects,
                ..options(Fill::Plain, Clamp::None)
            },
            near: 0.1,
            far: 100.0,
            reproject: Mat4::IDENTITY,
            current: &c,
            previous: &c,
            velocity: Some(&velocity),
            velocity_depth,
        };
        let centre = Vec2::new(3.5, 0.5);
        let moved = (centre - Vec2::new(2.0, 0.0), Motion::Velocity);
        let dynamic = VelocityObjects::Dynamic;
        // The dynamic surface is what the neighbours show, or in front of them: its velocity.
        assert_eq!(previous_position(&inp(dynamic, Some(&same)), 3, 0), moved);
        assert_eq!(
            previous_position(&inp(dynamic, Some(&in_front)), 3, 0),
            moved
        );
        // Far behind them (view depth ~10 against ~0.2): a static object hides it, camera path.
        assert_eq!(
            previous_position(&inp(dynamic, Some(&behind)), 3, 0),
            (centre, Motion::Camera)
        );
        assert_eq!(
            reconstruct(&inp(dynamic, Some(&behind)), 3, 0).1,
            Source::History
        );
        // With every object in the buffer it is exact: the velocity, whatever its depth says.
        assert_eq!(
            previous_position(&inp(VelocityObjects::All, Some(&behind)), 3, 0),
            moved
        );
        assert_eq!(
            previous_position(&inp(VelocityObjects::All, None), 3, 0),
            moved
        );
    }
}
