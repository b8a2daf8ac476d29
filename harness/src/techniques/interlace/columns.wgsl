// Column-interlace reconstruction (`pattern = "columns"`; temporal interlaced rendering, Rainbow Six Siege as the depth-based
// report describes it, seeds/depth-based-checkerboarding.txt section 3.3): this frame shaded the
// full-resolution columns of parity `p` at half width; every other column is the previous output
// reprojected through the camera (the nearer of its two shaded neighbours' depth) or the
// velocity buffer, sampled bilinearly, and clamped to the min/max of its six shaded neighbours
// (left and right columns, rows y-1..y+1). No history (first frame, cut) or a position that was
// off screen: the mean of the left and right neighbours.
//
// The CPU model in harness/src/techniques/interlace/columns_model.rs mirrors this file step by step.

struct Params {
    // Current full-resolution clip space to the previous frame's (f64 on the CPU, then f32).
    prev_from_cur: mat4x4<f32>,
    // x, y: output size; z: half-resolution width; w: parity p (shaded columns x = 2i + p).
    size: vec4<u32>,
    // x: history valid; y: velocity buffer bound; z: clamp on.
    mode: vec4<u32>,
};

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var half_color: texture_2d<f32>;
@group(0) @binding(2) var half_depth: texture_depth_2d;
@group(0) @binding(3) var history: texture_2d<f32>;
@group(0) @binding(4) var velocity: texture_2d<f32>;
@group(0) @binding(5) var output: texture_storage_2d<rgba16float, write>;

// Half-resolution texel `i` of row `y`, both clamped to the texture: at the borders a missing
// column takes its one shaded neighbour twice.
fn half_at(i: i32, y: i32) -> vec4<f32> {
    let c = vec2<i32>(clamp(i, 0, i32(params.size.z) - 1), clamp(y, 0, i32(params.size.y) - 1));
    return textureLoad(half_color, c, 0);
}

fn depth_at(i: i32, y: i32) -> f32 {
    let c = vec2<i32>(clamp(i, 0, i32(params.size.z) - 1), clamp(y, 0, i32(params.size.y) - 1));
    return textureLoad(half_depth, c, 0);
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

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.size.x || id.y >= params.size.y {
        return;
    }
    let p = i32(params.size.w);
    let x = i32(id.x);
    let y = i32(id.y);
    // 1. Shaded this frame: the half-resolution texel as is.
    if ((x - p) & 1) == 0 {
        textureStore(output, id.xy, half_at((x - p) >> 1, y));
        return;
    }
    // 2. Missing: its left and right neighbours were shaded (floor division by 2).
    let il = (x - 1 - p) >> 1;
    let ir = il + 1;
    let left = half_at(il, y);
    let right = half_at(ir, y);
    var out = 0.5 * (left + right);
    if params.mode.x != 0u {
        // 3. Where was it last frame? Dynamic objects: the velocity buffer (current minus
        //    previous position, pixels). Otherwise the camera: the nearer neighbour's depth
        //    (reversed-Z: the larger) unprojected here and projected with the previous camera.
        let size = vec2<f32>(params.size.xy);
        let centre = vec2<f32>(f32(x), f32(y)) + 0.5;
        var prev_pos = centre;
        var v = vec4<f32>(0.0);
        if params.mode.y != 0u {
            v = textureLoad(velocity, vec2<i32>(x, y), 0);
        }
        if v.z > 0.5 {
            prev_pos = centre - v.xy;
        } else {
            let d = max(depth_at(il, y), depth_at(ir, y));
            if d > 0.0 {
                let ndc = vec4<f32>(centre.x / size.x * 2.0 - 1.0, 1.0 - centre.y / size.y * 2.0, d, 1.0);
                let prev = params.prev_from_cur * ndc;
                prev_pos = vec2<f32>((prev.x / prev.w * 0.5 + 0.5) * size.x, (0.5 - prev.y / prev.w * 0.5) * size.y);
            }
        }
        // 4. On screen last frame (false for NaN): the history, clamped to the neighbours.
        if all(prev_pos >= vec2<f32>(0.0)) && all(prev_pos < size) {
            var h = history_bilinear(prev_pos);
            if params.mode.z != 0u {
                var lo = min(left, right);
                var hi = max(left, right);
                for (var dy = -1; dy <= 1; dy += 2) {
                    let a = half_at(il, y + dy);
                    let b = half_at(ir, y + dy);
                    lo = min(lo, min(a, b));
                    hi = max(hi, max(a, b));
                }
                h = min(max(h, lo), hi);
            }
            out = h;
        }
    }
    textureStore(output, id.xy, out);
}
