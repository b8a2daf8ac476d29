// Interlace reconstruction, Rainbow Six Siege's temporal interlaced rendering as the depth-based
// report describes it (seeds/depth-based-checkerboarding.txt section 3.3, after Mansouri 2016).
//
// This frame (parity p) shaded the full-resolution pixels with (x + y + p) even: "offsetting the
// sampling of the true render [...] provides every non-shaded pixel with four fully shaded
// orthogonally adjacent neighbours". They come from two quarter-resolution renders, layer r of
// `rows_color` / `rows_depth` holding rows y = 2j + r, texel i at column x = 2i + ((r + p) & 1).
// Every other pixel, in the report's order:
//   1. its four neighbours' colour and depth (borders mirrored onto a shaded pixel);
//   2. motion from the neighbour closest to the camera: its velocity where it covers an animated
//      object (the shared motion provider's pass, render/velocity.rs, draws the dynamic objects
//      only; where its depth lies behind the neighbour's shaded depth by more than
//      MOTION_DEPTH_EPSILON, a static object hides the animated one there), else the camera
//      reprojection of the pixel centre at that neighbour's depth;
//   3. the previous output at that position (bilinear), clamped to the neighbours' min/max;
//   4. confidence from the previous depth there against the best estimate of the pixel's depth
//      now: 1 when it lies within the neighbours' view-depth range (shifted by the neighbour's own
//      change of depth), falling to 0 at `depth_tolerance` (relative) outside; the result blended
//      back towards the unclamped history by it. Where nothing can have moved (camera still, no
//      animated objects: `mode.w`), the pixel's depth now is its previous depth exactly, so the
//      disparity is 0 and the confidence 1: the history, the pixel's own shade of last frame, is
//      taken as it is (a still scene rebuilds native, thin features alone in their neighbourhood
//      included, which any clamp to the neighbours would erase);
//   5. weighted against the spatial fill (the mean of the more coherent opposite pair) by the
//      colour coherency (the smaller relative luma difference of the two pairs) and the velocity
//      magnitude: history weight 1 - w_vel * (1 - w_coh). At rest, or across incoherent
//      neighbours (edges, detail), the history; moving over coherent colour, the fill.
// No history (first frame, cut) or a position off screen last frame: the spatial fill.
// The output depth (`depth_out`) is each pixel's depth (unshaded: the closest neighbour's), the
// next frame's previous depth.
//
// The CPU model in harness/src/techniques/interlace/model.rs mirrors this file step by step.

struct Params {
    // Current full-resolution clip space to the previous frame's (f64 on the CPU, then f32).
    prev_from_cur: mat4x4<f32>,
    // x, y: output size; z: quarter-resolution width; w: parity p.
    size: vec4<u32>,
    // x: history valid; y: velocity buffer bound; z: clamp on; w: nothing moved (camera still, no
    // animated objects).
    mode: vec4<u32>,
    // x: near; y: far; z: depth_tolerance (relative); w: unused.
    depth: vec4<f32>,
    // x: coherency scale (relative luma difference); y: velocity scale (pixels); zw: unused.
    weights: vec4<f32>,
};

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var rows_color: texture_2d_array<f32>;
@group(0) @binding(2) var rows_depth: texture_depth_2d_array;
@group(0) @binding(3) var history: texture_2d<f32>;
@group(0) @binding(4) var history_depth: texture_2d<f32>;
@group(0) @binding(5) var velocity: texture_2d<f32>;
@group(0) @binding(6) var output: texture_storage_2d<rgba16float, write>;
@group(0) @binding(7) var depth_out: texture_storage_2d<r32float, write>;
// The motion pass's depth (reversed-Z, full resolution, 0 where it drew nothing).
@group(0) @binding(8) var velocity_depth: texture_depth_2d;

// `render::velocity::MOTION_DEPTH_EPSILON`: how much nearer (relative, reversed-Z) the shaded
// depth may be than the motion pass's at the same pixel centre before a static object is taken
// to hide the animated one (the two passes differ only by rounding there).
const MOTION_DEPTH_EPSILON: f32 = 1e-4;

// Mirror a coordinate into [0, n): -1 -> 1, n -> n - 2 (keeps the parity, so a neighbour of an
// unshaded pixel stays a shaded pixel). n = 1: 0.
fn mirror(c: i32, n: i32) -> i32 {
    var m = c;
    if m < 0 {
        m = -m;
    }
    if m > n - 1 {
        m = 2 * (n - 1) - m;
    }
    return clamp(m, 0, n - 1);
}

// Where shaded pixel (x, y) lives in the quarter-resolution layers: (i, j, layer).
fn rows_texel(x: i32, y: i32) -> vec3<i32> {
    let r = y & 1;
    let s = (r + i32(params.size.w)) & 1;
    return vec3<i32>((x - s) >> 1, y >> 1, r);
}

fn shaded_color(x: i32, y: i32) -> vec4<f32> {
    let t = rows_texel(x, y);
    return textureLoad(rows_color, t.xy, t.z, 0);
}

fn shaded_depth(x: i32, y: i32) -> f32 {
    let t = rows_texel(x, y);
    return textureLoad(rows_depth, t.xy, t.z, 0);
}

fn history_at(x: i32, y: i32) -> vec4<f32> {
    let c = vec2<i32>(clamp(x, 0, i32(params.size.x) - 1), clamp(y, 0, i32(params.size.y) - 1));
    return textureLoad(history, c, 0);
}

// Bilinear sample of the previous output at a pixel position (pixel centres at +0.5), edges
// clamped.
fn history_bilinear(pos: vec2<f32>) -> vec4<f32> {
    let t = pos - 0.5;
    let base = floor(t);
    let f = t - base;
    let x0 = i32(base.x);
    let y0 = i32(base.y);
    let top = mix(history_at(x0, y0), history_at(x0 + 1, y0), f.x);
    let bottom = mix(history_at(x0, y0 + 1), history_at(x0 + 1, y0 + 1), f.x);
    return mix(top, bottom, f.y);
}

// View-space distance from reversed-Z depth (near -> 1, far -> 0).
fn linear_depth(d: f32) -> f32 {
    let near = params.depth.x;
    let far = params.depth.y;
    return near * far / (d * (far - near) + near);
}

// Luma of the colour under AMD's reversible tonemap (bounded, so HDR highlights do not swamp
// the coherency).
fn luma(c: vec4<f32>) -> f32 {
    let t = c.rgb / (1.0 + max(c.r, max(c.g, c.b)));
    return dot(t, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// Relative luma difference of two colours, 0 (equal) to 2.
fn difference(a: vec4<f32>, b: vec4<f32>) -> f32 {
    let la = luma(a);
    let lb = luma(b);
    return abs(la - lb) / (la + lb + 1e-4);
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.size.x || id.y >= params.size.y {
        return;
    }
    let p = i32(params.size.w);
    let x = i32(id.x);
    let y = i32(id.y);
    let w = i32(params.size.x);
    let h = i32(params.size.y);
    // Shaded this frame: as rendered.
    if ((x + y + p) & 1) == 0 {
        textureStore(output, id.xy, shaded_color(x, y));
        textureStore(depth_out, id.xy, vec4<f32>(shaded_depth(x, y), 0.0, 0.0, 0.0));
        return;
    }
    // 1. The four orthogonal neighbours: left, right, up, down.
    var nx = array<i32, 4>(mirror(x - 1, w), mirror(x + 1, w), x, x);
    var ny = array<i32, 4>(y, y, mirror(y - 1, h), mirror(y + 1, h));
    var c: array<vec4<f32>, 4>;
    var d: array<f32, 4>;
    var closest = 0;
    var lo = vec4<f32>(1e30);
    var hi = vec4<f32>(-1e30);
    var z_lo = 1e30;
    var z_hi = -1e30;
    for (var k = 0; k < 4; k += 1) {
        c[k] = shaded_color(nx[k], ny[k]);
        d[k] = shaded_depth(nx[k], ny[k]);
        // Reversed-Z: the larger depth is nearer; ties keep the first.
        if d[k] > d[closest] {
            closest = k;
        }
        lo = min(lo, c[k]);
        hi = max(hi, c[k]);
        let z = linear_depth(d[k]);
        z_lo = min(z_lo, z);
        z_hi = max(z_hi, z);
    }
    // The spatial fill: the mean of the more coherent opposite pair (horizontal on ties).
    let dh = difference(c[0], c[1]);
    let dv = difference(c[2], c[3]);
    var spatial = 0.5 * (c[0] + c[1]);
    if dv < dh {
        spatial = 0.5 * (c[2] + c[3]);
    }
    let coherency = min(dh, dv);
    var out = spatial;
    let d_near = d[closest];
    if params.mode.x != 0u {
        // 2. Motion from the closest neighbour.
        let size = vec2<f32>(params.size.xy);
        let centre = vec2<f32>(f32(x), f32(y)) + 0.5;
        var prev_pos = centre;
        var dz = 0.0;
        var v = vec4<f32>(0.0);
        if params.mode.y != 0u {
            let n = vec2<i32>(nx[closest], ny[closest]);
            v = textureLoad(velocity, n, 0);
            let vd = textureLoad(velocity_depth, n, 0);
            if d_near - vd > MOTION_DEPTH_EPSILON * max(d_near, vd) {
                v.z = 0.0;
            }
        }
        let still = params.mode.w != 0u;
        if v.z > 0.5 {
            prev_pos = centre - v.xy;
        } else if d_near > 0.0 && !still {
            let ndc = vec4<f32>(centre.x / size.x * 2.0 - 1.0, 1.0 - centre.y / size.y * 2.0, d_near, 1.0);
            let prev = params.prev_from_cur * ndc;
            prev_pos = vec2<f32>((prev.x / prev.w * 0.5 + 0.5) * size.x, (0.5 - prev.y / prev.w * 0.5) * size.y);
            // The neighbour's own change of view depth since last frame.
            dz = linear_depth(prev.z / prev.w) - linear_depth(d_near);
        }
        // On screen last frame (false for NaN).
        if all(prev_pos >= vec2<f32>(0.0)) && all(prev_pos < size) {
            // 3. The history there, clamped to the neighbours.
            let raw = history_bilinear(prev_pos);
            var blended = raw;
            if params.mode.z != 0u {
                let clamped = min(max(raw, lo), hi);
                // 4. Confidence from the previous depth at that position.
                let hp = vec2<i32>(floor(prev_pos));
                let z_prev = linear_depth(textureLoad(history_depth, hp, 0).x);
                let outside = max(max(z_lo + dz - z_prev, z_prev - (z_hi + dz)), 0.0);
                var confidence = clamp(1.0 - outside / (params.depth.z * z_prev), 0.0, 1.0);
                if still {
                    confidence = 1.0;
                }
                blended = mix(clamped, raw, confidence);
            }
            // 5. Colour coherency and velocity weights.
            let w_coh = clamp(coherency / params.weights.x, 0.0, 1.0);
            let w_vel = clamp(length(prev_pos - centre) / params.weights.y, 0.0, 1.0);
            out = mix(spatial, blended, 1.0 - w_vel * (1.0 - w_coh));
        }
    }
    textureStore(output, id.xy, out);
    textureStore(depth_out, id.xy, vec4<f32>(d_near, 0.0, 0.0, 0.0));
}
