// Adaptive shading's rate pass (Yang et al. 2019, seeds/nvidia-adaptive-shading.txt, sections
// 3 to 5) and the neighbour filter (section 5.4). One workgroup of 32 threads per 16x16 tile, 8
// pixels per thread (section 5.1): reproject the previous frame's output by the per-pixel motion
// (section 5.1), take its luma (Eq. 25), reduce the error estimate of Eq. 2 (L2 form, x and y
// apart), the average luma, the minimum motion (section 4.1) and the disoccluded pixels
// (depth-based rejection, 5.1), then decide the tile's rate (Eq. 15, 20 to 22, 24, hysteresis of
// 5.4). CPU model: model.rs in this folder.

struct RateParams {
    // width, height, tiles across, tiles down
    size: vec4<u32>,
    // x: mode (0 content-motion, 1 content, 2 motion); y: history valid; z: 4x4 allowed
    mode: vec4<u32>,
    // t, l, k, e
    t: vec4<f32>,
    // x: hysteresis epsilon, y: disocclusion tolerance, z: near, w: far
    more: vec4<f32>,
}

@group(0) @binding(0) var<uniform> rp: RateParams;
@group(0) @binding(1) var prev_color: texture_2d<f32>;
// This frame's motion: xy in pixels (current - previous, y down); z: the surface's expected
// previous depth; w: 1. Read only where `depth` says something is drawn (the hardware path's
// pre-pass does not clear it).
@group(0) @binding(2) var motion: texture_2d<f32>;
@group(0) @binding(3) var prev_depth: texture_depth_2d;
@group(0) @binding(4) var prev_state: texture_2d<f32>;
@group(0) @binding(5) var state_out: texture_storage_2d<rg32float, write>;
@group(0) @binding(6) var rates_out: texture_storage_2d<r32uint, write>;
// This frame's depth (G-buffer or depth pre-pass; reversed-Z, cleared to 0): a pixel is covered
// where it is not 0.
@group(0) @binding(9) var depth: texture_depth_2d;

// Eq. 25.
fn luma(c: vec3<f32>) -> f32 {
    return 0.299 * c.r + 0.587 * c.g + 0.114 * c.b;
}

// Eq. 20 and 21 (fits of the motion factors).
fn b_half(v: f32) -> f32 {
    return pow(1.0 / (1.0 + pow(1.05 * v, 3.10)), 0.35);
}

fn b_quarter(v: f32, k: f32) -> f32 {
    return k * pow(1.0 / (1.0 + pow(0.55 * v, 2.41)), 0.49);
}

fn view_depth(d: f32) -> f32 {
    let near = rp.more.z;
    let far = rp.more.w;
    return near * far / (near + d * (far - near));
}

// The tile's rate from its reduced sums (x, y: Eq. 2's squared differences, z: luma, w:
// disoccluded pixels) and minimum motion: Eq. 15, 20 to 22, 24 and the hysteresis of 5.4.
fn decide(t_xy: vec2<i32>, total: vec4<f32>, vmin: vec2<f32>) {
    let size = vec2<i32>(rp.size.xy);
    if rp.mode.y == 0u {
        // No history (first frame, camera cut): full rate everywhere.
        textureStore(rates_out, t_xy, vec4<u32>(0u));
        textureStore(state_out, t_xy, vec4<f32>(-1.0, -1.0, 0.0, 0.0));
        return;
    }
    let tw = f32(min(size.x - t_xy.x * 16, 16));
    let th = f32(min(size.y - t_xy.y * 16, 16));
    let pairs = vec2<f32>((tw - 1.0) * th, tw * (th - 1.0));
    var err = vec2<f32>(0.0);
    if pairs.x > 0.0 {
        err.x = sqrt(total.x / pairs.x);
    }
    if pairs.y > 0.0 {
        err.y = sqrt(total.y / pairs.y);
    }
    let avg = total.z / (tw * th);
    var v = vmin;
    if v.x > 1e29 {
        v.x = 0.0;
    }
    if v.y > 1e29 {
        v.y = 0.0;
    }
    let t = rp.t.x;
    let den = avg + rp.t.y;
    let k = rp.t.z;
    let prev = textureLoad(prev_state, t_xy, 0).xy;
    var rel_half = vec2<f32>(0.0);
    var rate = vec2<u32>(0u);
    for (var a = 0; a < 2; a = a + 1) {
        var bh = 1.0;
        var bq = k;
        if rp.mode.x != 1u {
            bh = b_half(v[a]);
            bq = b_quarter(v[a], k);
        }
        var rel = 0.0;
        if rp.mode.x == 2u {
            // Eq. 24: the relative error bounded by e.
            rel = rp.t.w;
        } else if den > 0.0 {
            rel = err[a] / den;
        }
        let rh = bh * rel;
        let rq = bq * rel;
        // Section 5.4's hysteresis against the tile's previous rate on this axis: a rise of the
        // predicted error to a finer rate must pass t(1 + eps), a fall to a coarser rate
        // t(1 - eps).
        var th = t;
        var tq = t;
        if prev[a] >= 0.0 {
            let eps = rp.more.x;
            th = select(t * (1.0 + eps), t * (1.0 - eps), prev[a] < 0.5);
            tq = select(t * (1.0 - eps), t * (1.0 + eps), prev[a] > 1.5);
        }
        rel_half[a] = rh;
        rate[a] = 1u;
        if rh >= th {
            rate[a] = 0u;
        } else if rq < tq {
            rate[a] = 2u;
        }
    }
    // Section 3.4: no 4x4 by default; quarter rate stays on the axis with the smaller error.
    if rate.x == 2u && rate.y == 2u && rp.mode.z == 0u {
        if rel_half.x >= rel_half.y {
            rate.x = 1u;
        } else {
            rate.y = 1u;
        }
    }
    // No 4x1 or 1x4 region (D3D12's rates, as the NVIDIA-derived shaders do): 4x1 -> 2x1.
    if rate.x == 2u && rate.y == 0u {
        rate.x = 1u;
    }
    if rate.y == 2u && rate.x == 0u {
        rate.y = 1u;
    }
    // Section 5.1: tiles with pixels that cannot be reprojected are shaded at full rate.
    if total.w > 0.0 {
        rate = vec2<u32>(0u);
    }
    textureStore(rates_out, t_xy, vec4<u32>(rate.x | (rate.y << 2u), 0u, 0u, 0u));
    textureStore(state_out, t_xy, vec4<f32>(vec2<f32>(rate), 0.0, 0.0));
}

// Section 5.1's layout: 32 threads per tile, each owning 8 pixels, here a column of 8: thread
// (x, h) owns pixels (x, 8h) to (x, 8h + 7) of the tile. Each sums its pixels in order, then the
// 32 partial sums are reduced (the CPU model reduces them as a tree, as `rate_shared.wgsl` does).
// The entry point, which loops over the thread's pixels (`read_pixel`), exchanges lumas between
// threads and reduces the sums, is one of two files appended to this one: `rate_shared.wgsl`
// (workgroup memory and barriers, any adapter) or `rate_subgroup.wgsl` (subgroup operations, where
// a subgroup holds the whole tile).
//
// Measured on an H200 at 3840x2160 (rates pass alone, shared-memory entry point): this layout
// 0.106 ms; one thread per pixel for the reads (256 threads, 32 summing) 0.135 ms; the reads
// batched eight per thread in arrays 0.196 ms (register pressure lowers occupancy below the 32
// one-warp tiles per SM this layout reaches); two tiles per workgroup (two warps, to lift that
// limit) 0.109-0.119 ms. Reads without branches: depth and motion are loaded together
// (coordinates clamped, results selected), the reprojected colour and depth right after, so a
// thread's 32 loads form two dependent levels instead of three per pixel. H200, 3840x2160 (runs
// 20261202T1301-1303Z): 0.100 ms on the engine and the Table 2 pan against 0.106 / 0.116 ms with
// the loads inside `if`s; the same with two tiles per workgroup: 0.104 ms.

// What the rate pass reads of one pixel: its luma after reprojection (0 outside the frame),
// whether it is covered and disoccluded, and its motion.
struct Pixel {
    l: f32,
    covered: bool,
    disoccluded: f32,
    m: vec2<f32>,
}

// Pixel p of this frame (`inside` the frame or not): reproject the previous output by the motion
// (5.1), luma (Eq. 25), disocclusion by depth. The loads have no branches: depth and motion at
// clamped coordinates first, then the reprojected colour and depth.
fn read_pixel(p: vec2<i32>) -> Pixel {
    let size = vec2<i32>(rp.size.xy);
    let inside = all(p < size);
    let pc = min(p, size - 1);
    let d = textureLoad(depth, pc, 0);
    let m_raw = textureLoad(motion, pc, 0);
    let covered = inside && d > 0.0;
    let m = select(vec4<f32>(0.0), m_raw, covered);
    let q = floor(vec2<f32>(p) + 0.5 - m.xy);
    let on_screen = all(q >= vec2<f32>(0.0)) && all(q < vec2<f32>(size));
    let c = vec2<i32>(min(max(q, vec2<f32>(0.0)), vec2<f32>(size - 1)));
    let col = textureLoad(prev_color, c, 0).rgb;
    let pd = textureLoad(prev_depth, c, 0);
    let prev = view_depth(pd);
    let expected = view_depth(m.z);
    let occluded = !on_screen || abs(prev - expected) > rp.more.y * expected;
    var out: Pixel;
    out.l = select(0.0, luma(max(col, vec3<f32>(0.0))), inside);
    out.covered = covered;
    out.disoccluded = select(0.0, 1.0, covered && occluded);
    out.m = m.xy;
    return out;
}

// Eq. 2's term for a pair of neighbouring lumas: ((I_i - I_{i-1}) / 2)^2.
fn pair(a: f32, b: f32) -> f32 {
    let d = (a - b) * 0.5;
    return d * d;
}

// Section 5.4's filter as its own pass (the software path; the hardware path filters in its
// attachment pass): `filtered_code` of `rate_filter.wgsl`, appended to this module.
@group(0) @binding(7) var rates_in: texture_2d<u32>;
@group(0) @binding(8) var rates_filtered: texture_storage_2d<r32uint, write>;

@compute @workgroup_size(8, 8)
fn filter_rates(@builtin(global_invocation_id) id: vec3<u32>) {
    let tiles = vec2<i32>(rp.size.zw);
    let t = vec2<i32>(id.xy);
    if t.x >= tiles.x || t.y >= tiles.y {
        return;
    }
    textureStore(rates_filtered, t, vec4<u32>(filtered_code(t, tiles), 0u, 0u, 0u));
}
