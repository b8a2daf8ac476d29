//! CPU model of adaptive shading's rate selection (`rate.wgsl`), step for step in
//! f32, in the shader's order (the same tree reductions): the oracle the GPU rates are compared
//! with in tests, and the place where the paper's equations can be checked without a GPU.
//!
//! Not used when rendering. Equations and sections are those of Yang et al. 2019
//! (`seeds/nvidia-adaptive-shading.txt`).

/// Side of a screen tile in pixels (section 5.1: one 16x16 tile per shading-rate texel).
pub const TILE: u32 = 16;

crate::choice! {
    /// How rates are chosen (parameter `mode`).
    pub enum Mode {
        /// Eq. 22: the error estimate scaled by the motion factors of Eq. 20 and 21.
        ContentMotion = "content-motion",
        /// Eq. 16: the error estimate alone (b_H = 1, b_Q = k).
        Content = "content",
        /// Eq. 24: standalone motion-adaptive shading, the relative error taken as `max_error`.
        Motion = "motion",
    }
}

impl Mode {
    pub fn code(self) -> u32 {
        match self {
            Mode::ContentMotion => 0,
            Mode::Content => 1,
            Mode::Motion => 2,
        }
    }
}

/// Rate-selection parameters, as the scenario gives them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RateParams {
    /// Sensitivity threshold t (Eq. 15).
    pub threshold: f32,
    /// Environment luminance l (Eq. 15).
    pub env_luma: f32,
    /// Quarter-rate factor k (Eq. 14, 21).
    pub k: f32,
    pub mode: Mode,
    /// e of Eq. 24 (mode `Motion`).
    pub max_error: f32,
    /// Hysteresis epsilon (section 5.4).
    pub hysteresis: f32,
    pub neighbour_filter: bool,
    pub allow_4x4: bool,
    /// Relative view-depth difference beyond which a reprojected pixel is disoccluded.
    pub disocclusion_tolerance: f32,
    /// Where the shading pass shades a coarse pixel (not part of rate selection).
    pub coarse_sample: CoarseSample,
}

crate::choice! {
    /// Where a coarse pixel is shaded (parameter `coarse_sample`).
    pub enum CoarseSample {
        /// At its centre, with derivatives across it, as hardware VRS shades.
        Centre = "centre",
        /// At its shading pixel's own G-buffer sample (a native sample, replicated).
        Pixel = "pixel",
    }
}

impl Default for RateParams {
    fn default() -> Self {
        RateParams {
            threshold: 0.15,
            env_luma: 0.05,
            k: 2.13,
            mode: Mode::ContentMotion,
            max_error: 0.1,
            hysteresis: 0.2,
            neighbour_filter: true,
            allow_4x4: false,
            disocclusion_tolerance: 0.05,
            coarse_sample: CoarseSample::Centre,
        }
    }
}

/// Luma of linear RGB, Eq. 25.
pub fn luma(rgb: [f32; 3]) -> f32 {
    0.299 * rgb[0] + 0.587 * rgb[1] + 0.114 * rgb[2]
}

/// Motion factor of half-rate error at `v` pixels per frame, the fit of Eq. 20.
pub fn b_half(v: f32) -> f32 {
    (1.0 / (1.0 + (1.05 * v).powf(3.10))).powf(0.35)
}

/// Motion factor of quarter-rate error, the fit of Eq. 21 (`k` = 2.13 in the paper).
pub fn b_quarter(v: f32, k: f32) -> f32 {
    k * (1.0 / (1.0 + (0.55 * v).powf(2.41))).powf(0.49)
}

/// Shading rate of one axis: 1 (full), 2 (half) or 4 (quarter) pixels per shade.
pub type AxisRate = u32;

/// Eq. 22 on one axis in relative form: `rel_half` = b_H(v) E / (I_avg + l) and `rel_quarter` =
/// b_Q(v) E / (I_avg + l) against the thresholds of the full/half boundary `t_half` and of the
/// half/quarter boundary `t_quarter` (both t without hysteresis: Eq. 15 divided through by
/// I_avg + l). Full when b_H E >= tau (the `>=` of Eq. 16 and both public codes).
pub fn axis_rate(rel_half: f32, rel_quarter: f32, t_half: f32, t_quarter: f32) -> AxisRate {
    if rel_half >= t_half {
        1
    } else if rel_quarter < t_quarter {
        4
    } else {
        2
    }
}

/// Section 5.4's hysteresis as thresholds (full/half, half/quarter) given the axis's previous
/// rate (log2; negative: none): a rise of the predicted error to a finer rate must pass
/// t(1 + eps), a fall to a coarser rate t(1 - eps).
pub fn hysteresis_thresholds(t: f32, eps: f32, prev: f32) -> (f32, f32) {
    if prev < 0.0 {
        return (t, t);
    }
    let half = if prev < 0.5 {
        t * (1.0 - eps)
    } else {
        t * (1.0 + eps)
    };
    let quarter = if prev > 1.5 {
        t * (1.0 + eps)
    } else {
        t * (1.0 - eps)
    };
    (half, quarter)
}

/// A tile's rate as stored in the rate texture: log2 of the x rate in bits 0-1, of y in bits 2-3.
pub fn encode(rx: AxisRate, ry: AxisRate) -> u32 {
    rx.trailing_zeros() | (ry.trailing_zeros() << 2)
}

pub fn decode(code: u32) -> (AxisRate, AxisRate) {
    (1 << (code & 3), 1 << ((code >> 2) & 3))
}

/// What the rate pass reduces over one tile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TileStats {
    /// Error estimate E of Eq. 2 (L2 form) in x and y.
    pub error: [f32; 2],
    /// Average luma I_avg of the reprojected previous frame.
    pub avg_luma: f32,
    /// Minimum |motion| over the tile's covered pixels, per axis (section 4.1: the minimum
    /// velocity; 0 when nothing is covered).
    pub min_motion: [f32; 2],
    /// Pixels that could not be reprojected (off screen or rejected by depth).
    pub disoccluded: u32,
}

/// Inputs of the rate pass for a whole frame.
pub struct Inputs<'a> {
    pub width: u32,
    pub height: u32,
    /// Previous frame's output, linear RGBA per pixel.
    pub prev_color: &'a [[f32; 4]],
    /// Per pixel: motion in pixels (current minus previous, y down), the surface's expected
    /// previous reversed-Z depth, 1; read only where `depth` is covered.
    pub motion: &'a [[f32; 4]],
    /// This frame's reversed-Z depth (G-buffer or depth pre-pass): covered where not 0.
    pub depth: &'a [f32],
    /// Previous frame's reversed-Z depth.
    pub prev_depth: &'a [f32],
    /// Previous frame's per-tile state (decided log2 rate per axis; negative: none).
    pub prev_state: &'a [[f32; 2]],
    pub near: f32,
    pub far: f32,
    /// False on the first frame and after a cut: every tile at full rate.
    pub history: bool,
    pub params: RateParams,
}

/// View depth of a reversed-Z depth value (near maps to 1, far to 0).
pub fn view_depth(d: f32, near: f32, far: f32) -> f32 {
    near * far / (near + d * (far - near))
}

/// In-place tree reduction over 32 values, as the shader's workgroup does.
fn reduce<T: Copy>(v: &mut [T; 32], op: impl Fn(T, T) -> T) -> T {
    let mut stride = 16;
    while stride > 0 {
        for i in 0..stride {
            v[i] = op(v[i], v[i + stride]);
        }
        stride /= 2;
    }
    v[0]
}

/// The reductions of one tile (the rate pass's workgroup: 32 threads, thread (x, h) summing the
/// pixels (x, 8h) to (x, 8h + 7) in order, then a tree over the threads).
pub fn tile_stats(inp: &Inputs, tx: u32, ty: u32) -> TileStats {
    let (w, h) = (inp.width as i32, inp.height as i32);
    let pixel = |i: usize| {
        (
            tx as i32 * 16 + (i % 16) as i32,
            ty as i32 * 16 + (i / 16) as i32,
        )
    };
    let inside = |i: usize| {
        let (px, py) = pixel(i);
        px < w && py < h
    };
    let mut lum = [0f32; 256];
    let mut sums = [[0f32; 4]; 32];
    let mut mins = [[1e30f32; 2]; 32];
    for t in 0..32usize {
        let (x, half) = (t % 16, t / 16);
        for k in 0..8 {
            let i = (half * 8 + k) * 16 + x;
            if !inside(i) {
                continue;
            }
            let (px, py) = pixel(i);
            let covered = inp.depth[(py * w + px) as usize] > 0.0;
            let m = if covered {
                inp.motion[(py * w + px) as usize]
            } else {
                [0.0; 4]
            };
            let qx = (px as f32 + 0.5 - m[0]).floor();
            let qy = (py as f32 + 0.5 - m[1]).floor();
            let on_screen = qx >= 0.0 && qy >= 0.0 && qx < w as f32 && qy < h as f32;
            let (cx, cy) = (
                (qx.max(0.0) as i32).min(w - 1),
                (qy.max(0.0) as i32).min(h - 1),
            );
            let c = inp.prev_color[(cy * w + cx) as usize];
            lum[i] = luma([c[0].max(0.0), c[1].max(0.0), c[2].max(0.0)]);
            if covered {
                mins[t] = [mins[t][0].min(m[0].abs()), mins[t][1].min(m[1].abs())];
                let occluded = if on_screen {
                    let prev =
                        view_depth(inp.prev_depth[(cy * w + cx) as usize], inp.near, inp.far);
                    let expected = view_depth(m[2], inp.near, inp.far);
                    (prev - expected).abs() > inp.params.disocclusion_tolerance * expected
                } else {
                    true
                };
                sums[t][3] += if occluded { 1.0 } else { 0.0 };
            }
        }
    }
    for (t, s) in sums.iter_mut().enumerate() {
        let (x, half) = (t % 16, t / 16);
        for k in 0..8 {
            let ly = half * 8 + k;
            let i = ly * 16 + x;
            if !inside(i) {
                continue;
            }
            // Eq. 2: ((I_i - I_{i-1}) / 2)^2 over neighbouring pairs inside the tile.
            if x >= 1 {
                let d = (lum[i] - lum[i - 1]) * 0.5;
                s[0] += d * d;
            }
            if ly >= 1 {
                let d = (lum[i] - lum[i - 16]) * 0.5;
                s[1] += d * d;
            }
            s[2] += lum[i];
        }
    }
    let s = reduce(&mut sums, |a, b| {
        [a[0] + b[0], a[1] + b[1], a[2] + b[2], a[3] + b[3]]
    });
    let mn = reduce(&mut mins, |a, b| [a[0].min(b[0]), a[1].min(b[1])]);
    let tw = (w - tx as i32 * 16).min(16) as f32;
    let th = (h - ty as i32 * 16).min(16) as f32;
    let pairs_x = (tw - 1.0) * th;
    let pairs_y = tw * (th - 1.0);
    let err = |sum: f32, pairs: f32| {
        if pairs > 0.0 {
            (sum / pairs).sqrt()
        } else {
            0.0
        }
    };
    TileStats {
        error: [err(s[0], pairs_x), err(s[1], pairs_y)],
        avg_luma: s[2] / (tw * th),
        min_motion: [
            if mn[0] > 1e29 { 0.0 } else { mn[0] },
            if mn[1] > 1e29 { 0.0 } else { mn[1] },
        ],
        disoccluded: s[3] as u32,
    }
}

/// One tile's decision before the neighbour filter: (rate code, state to keep, margin). The state
/// is the decided log2 rate per axis (negative without history), the previous rate of the next
/// frame's hysteresis. The margin is the smallest relative distance of a compared value from its
/// threshold: where it is tiny, f32 rounding on the GPU may decide the other way.
pub fn select(stats: &TileStats, prev_state: [f32; 2], history: bool, p: &RateParams) -> Decision {
    if !history {
        return Decision {
            code: encode(1, 1),
            state: [-1.0, -1.0],
            margin: f32::INFINITY,
        };
    }
    let den = stats.avg_luma + p.env_luma;
    let mut rel_half = [0f32; 2];
    let mut rel_quarter = [0f32; 2];
    let mut rates = [1u32; 2];
    let mut margin = f32::INFINITY;
    for a in 0..2 {
        let v = stats.min_motion[a];
        let (bh, bq) = match p.mode {
            Mode::Content => (1.0, p.k),
            _ => (b_half(v), b_quarter(v, p.k)),
        };
        let rel = match p.mode {
            Mode::Motion => p.max_error,
            _ => {
                if den > 0.0 {
                    stats.error[a] / den
                } else {
                    0.0
                }
            }
        };
        rel_half[a] = bh * rel;
        rel_quarter[a] = bq * rel;
        let (th, tq) = hysteresis_thresholds(p.threshold, p.hysteresis, prev_state[a]);
        rates[a] = axis_rate(rel_half[a], rel_quarter[a], th, tq);
        margin = margin
            .min((rel_half[a] - th).abs() / th)
            .min((rel_quarter[a] - tq).abs() / tq);
    }
    let (mut rx, mut ry) = (rates[0], rates[1]);
    // Section 3.4: no 4x4 by default; keep quarter rate on the axis with the smaller error.
    if rx == 4 && ry == 4 && !p.allow_4x4 {
        if rel_half[0] >= rel_half[1] {
            rx = 2;
        } else {
            ry = 2;
        }
    }
    // No 4x1 or 1x4 shading region (D3D12's rates, as the NVIDIA-derived shaders): 4x1 -> 2x1.
    if rx == 4 && ry == 1 {
        rx = 2;
    }
    if ry == 4 && rx == 1 {
        ry = 2;
    }
    if stats.disoccluded > 0 {
        (rx, ry) = (1, 1);
    }
    Decision {
        code: encode(rx, ry),
        state: [rx.trailing_zeros() as f32, ry.trailing_zeros() as f32],
        margin,
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Decision {
    pub code: u32,
    pub state: [f32; 2],
    pub margin: f32,
}

/// Section 5.4's filter: per axis, a tile's rate is at most twice the lowest rate among its eight
/// neighbours (quarter next to full becomes half).
pub fn neighbour_filter(codes: &[u32], tiles_x: u32, tiles_y: u32) -> Vec<u32> {
    let mut out = Vec::with_capacity(codes.len());
    for ty in 0..tiles_y as i32 {
        for tx in 0..tiles_x as i32 {
            let c = codes[(ty * tiles_x as i32 + tx) as usize];
            let (mut lx, mut ly) = (c & 3, (c >> 2) & 3);
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let (nx, ny) = (tx + dx, ty + dy);
                    if nx < 0 || ny < 0 || nx >= tiles_x as i32 || ny >= tiles_y as i32 {
                        continue;
                    }
                    let n = codes[(ny * tiles_x as i32 + nx) as usize];
                    lx = lx.min((n & 3) + 1);
                    ly = ly.min(((n >> 2) & 3) + 1);
                }
            }
            out.push(lx | (ly << 2));
        }
    }
    out
}

/// Tiles across and down for a resolution.
pub fn tiles(width: u32, height: u32) -> (u32, u32) {
    (width.div_ceil(TILE), height.div_ceil(TILE))
}

/// Every tile's decision (before the filter) and the final rate codes.
pub fn rates_all(inp: &Inputs) -> (Vec<Decision>, Vec<u32>) {
    let (tx, ty) = tiles(inp.width, inp.height);
    let mut decisions = Vec::new();
    for y in 0..ty {
        for x in 0..tx {
            let s = tile_stats(inp, x, y);
            let prev = inp.prev_state[(y * tx + x) as usize];
            decisions.push(select(&s, prev, inp.history, &inp.params));
        }
    }
    let codes: Vec<u32> = decisions.iter().map(|d| d.code).collect();
    let out = if inp.params.neighbour_filter {
        neighbour_filter(&codes, tx, ty)
    } else {
        codes
    };
    (decisions, out)
}

/// Fig. 1's colour code by shading-region size (pixels per shade): 1 none, 2 blue, 4 green,
/// 8 yellow, 16 red; blended half-way over the frame's grey.
pub fn rate_color(code: u32) -> Option<[u8; 3]> {
    let (rx, ry) = decode(code);
    match rx * ry {
        1 => None,
        2 => Some([40, 90, 255]),
        4 => Some([30, 200, 60]),
        8 => Some([250, 220, 30]),
        _ => Some([240, 40, 30]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rate_codes_round_trip() {
        for rx in [1, 2, 4] {
            for ry in [1, 2, 4] {
                assert_eq!(decode(encode(rx, ry)), (rx, ry));
            }
        }
    }

    #[test]
    fn neighbour_filter_raises_quarter_next_to_full() {
        // Row of three tiles: 4x4 next to 1x1 becomes 2x2; 2x1 next to 1x1 stays.
        let codes = [encode(4, 4), encode(1, 1), encode(2, 1)];
        let out = neighbour_filter(&codes, 3, 1);
        assert_eq!(
            out.iter().map(|c| decode(*c)).collect::<Vec<_>>(),
            [(2, 2), (1, 1), (2, 1)]
        );
    }
}
