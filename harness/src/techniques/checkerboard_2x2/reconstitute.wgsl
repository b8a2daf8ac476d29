// `checkerboard-2x2`, pass `reconstitute`: rebuilds the frame from the half that the scene pass
// shaded (2x2 blocks with (bx + by) & 1 == parity) and the previous frame, by motion reprojection.
//
// Source: seeds/depth-based-checkerboarding.txt, sections 5.3.3 (reconstitution by motion
// reprojection, one invocation per 2x2 block), 5.3.4 (uniform colour clamp between the two shaded
// direct neighbours, Figure 7), 5.3.5 (conditional clamp: no clamp below a motion threshold),
// 5.3.7 (blended clamp by linear depth difference, bidirectional, mid-point of the two blends) and
// 5.3.8 (motion coherency: clamp when a neighbour's previous motion disagrees). Where the report is
// silent (first frame, borders, reprojection off screen) the choice is marked "not in the report".
// The CPU model in harness/src/render/checkerboard_2x2_model.rs mirrors this file step by step.
//
// One invocation handles a pair of horizontally adjacent blocks (2 i, 2 i + 1) of one block row:
// exactly one of them is masked this frame. It copies the shaded block to the output and
// reconstitutes the masked one, so every invocation does the same work (no checkerboard of idle
// lanes) and the output holds the whole frame.

struct Params {
    // xy: output size in pixels; z: parity of the blocks shaded this frame; w: 1 when history must
    // not be read (first frame, camera cut).
    frame: vec4<u32>,
    // x: clamp (0 none, 1 uniform, 2 conditional, 3 blended); y: motion coherency (0 or 1).
    mode: vec4<u32>,
    // x: motion threshold (pixels per frame), y: blend min, z: blend max (linear depth in [0, 1]).
    limits: vec4<f32>,
    // x: near, y: far (the camera's planes, for linearising depth; 5.3.7).
    planes: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: Params;
// This frame: the scene pass's colour and depth (masked blocks at the clear colour and depth 1.0).
@group(0) @binding(1) var scene_color: texture_2d<f32>;
@group(0) @binding(2) var scene_depth: texture_depth_2d;
// This frame's motion (pixels, current minus previous, y down) on the masked blocks.
@group(0) @binding(3) var motion: texture_2d<f32>;
// The previous frame's output, scene depth and motion.
@group(0) @binding(4) var history_color: texture_2d<f32>;
@group(0) @binding(5) var history_depth: texture_depth_2d;
@group(0) @binding(6) var history_motion: texture_2d<f32>;
@group(0) @binding(7) var output: texture_storage_2d<rgba16float, write>;

// NaN and ±Inf, by their bits (a fast-math compiler may fold `x != x` away).
fn finite(c: vec3<f32>) -> bool {
    let e = bitcast<vec3<u32>>(c) & vec3<u32>(0x7f800000u);
    return all(e != vec3<u32>(0x7f800000u));
}

fn inside(p: vec2<i32>) -> bool {
    return all(p >= vec2<i32>(0)) && all(p < vec2<i32>(params.frame.xy));
}

// The direct neighbour of coordinate `c` across the edge of its block (which starts at `start`):
// on the pixel's own side (Figure 7); at the image border, the one across the block's other edge
// (not in the report); -1 if neither exists (an image one block wide).
fn neighbour(c: i32, start: i32, extent: i32) -> i32 {
    let own = select(start + 2, start - 1, c == start);
    let other = select(start - 1, start + 2, c == start);
    if own >= 0 && own < extent {
        return own;
    }
    if other >= 0 && other < extent {
        return other;
    }
    return -1;
}

// Linear depth in [0, 1] between near and far, from reversed-Z depth (5.3.7 linearises with the
// camera's planes; "10% of the available depth space" for 0.1).
fn linear01(d: f32) -> f32 {
    let n = params.planes.x;
    let f = params.planes.y;
    let z = n * f / (d * (f - n) + n);
    return (z - n) / (f - n);
}

// 5.3.7: weight of the clamped colour from one direction's depth difference: 0 below the minimum
// blend difference, then proportional to the difference over the maximum, 1 from the maximum on.
fn clamp_weight(difference: f32) -> f32 {
    if difference < params.limits.y {
        return 0.0;
    }
    return min(difference / params.limits.z, 1.0);
}

fn reconstitute(p: vec2<i32>) -> vec3<f32> {
    let size = vec2<i32>(params.frame.xy);
    let start = (p >> vec2<u32>(1u)) * 2;
    // The two shaded direct neighbours (Figure 7): horizontal h, vertical v. One missing (image
    // border): the other stands for both.
    var h = vec2<i32>(neighbour(p.x, start.x, size.x), p.y);
    var v = vec2<i32>(p.x, neighbour(p.y, start.y, size.y));
    let has_h = h.x >= 0;
    let has_v = v.y >= 0;
    if !has_h && !has_v {
        // Nothing shaded nearby (an image of one block): history if any, else the clear colour.
        if params.frame.w == 0u {
            let prev = vec2<i32>(floor(vec2<f32>(p) + 0.5 - textureLoad(motion, p, 0).xy));
            if inside(prev) {
                let c = textureLoad(history_color, prev, 0).rgb;
                if finite(c) {
                    return c;
                }
            }
        }
        return textureLoad(scene_color, p, 0).rgb;
    }
    if !has_h {
        h = v;
    }
    if !has_v {
        v = h;
    }
    var ch = textureLoad(scene_color, h, 0).rgb;
    var cv = textureLoad(scene_color, v, 0).rgb;
    // Stability (issue 8, not in the report): a non-finite neighbour stands aside for the other,
    // so NaN or Inf never spreads into a finite pixel; both non-finite means the pixel is inside
    // such a region and stays non-finite.
    if !finite(ch) && finite(cv) {
        ch = cv;
    }
    if !finite(cv) && finite(ch) {
        cv = ch;
    }
    // No history (first frame, camera cut): the neighbours' mean (5.2's "neighbour colour
    // averages", the first step before reprojection).
    if params.frame.w != 0u {
        return 0.5 * (ch + cv);
    }
    // 5.3.3: the colour this pixel's geometry had last frame, at the end of its motion vector: the
    // pixel containing that point, unfiltered (the report names no filter). With slow motion it
    // was shaded last frame (blocks alternate); after an odd number of blocks it was itself
    // reconstituted.
    let m = textureLoad(motion, p, 0).xy;
    let prev = vec2<i32>(floor(vec2<f32>(p) + 0.5 - m));
    if !inside(prev) {
        // Came from off screen: no history to take (not in the report): the neighbours' mean.
        return 0.5 * (ch + cv);
    }
    let reprojected = textureLoad(history_color, prev, 0).rgb;
    if !finite(reprojected) {
        // A non-finite history is not used (stability, as above): the neighbours' mean.
        return 0.5 * (ch + cv);
    }
    let clamp_mode = params.mode.x;
    // Both neighbours non-finite: no range to clamp to; the finite history as it is.
    if clamp_mode == 0u || !finite(ch) {
        return reprojected;
    }
    // 5.3.4: clamp to the range of the two shaded neighbours.
    let clamped = clamp(reprojected, min(ch, cv), max(ch, cv));
    if clamp_mode == 1u {
        return clamped;
    }
    // 5.3.5: no clamp for (nearly) still pixels ...
    let threshold = params.limits.x;
    var clamp_on = length(m) > threshold;
    // 5.3.8: ... unless a neighbour's previous motion disagrees with this pixel's (motion history
    // at the neighbours, which were masked, so had motion rendered, last frame).
    if params.mode.y != 0u && !clamp_on {
        let mh = textureLoad(history_motion, h, 0).xy;
        let mv = textureLoad(history_motion, v, 0).xy;
        clamp_on = length(mh - m) > threshold || length(mv - m) > threshold;
    }
    if !clamp_on {
        return reprojected;
    }
    if clamp_mode == 2u {
        return clamped;
    }
    // 5.3.7: blended, bidirectionally: the reprojected depth (previous frame's depth at the end of
    // the motion vector) against each neighbour's depth; each direction blends the reprojected
    // colour towards the clamped one by its weight; the output is the mid-point of the two.
    let dp = linear01(textureLoad(history_depth, prev, 0));
    let wh = clamp_weight(abs(dp - linear01(textureLoad(scene_depth, h, 0))));
    let wv = clamp_weight(abs(dp - linear01(textureLoad(scene_depth, v, 0))));
    return 0.5 * (mix(reprojected, clamped, wh) + mix(reprojected, clamped, wv));
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<i32>(params.frame.xy);
    let blocks = (size + 1) / 2;
    let by = i32(id.y);
    let first = 2 * i32(id.x);
    if by >= blocks.y || first >= blocks.x {
        return;
    }
    // Masked blocks have (bx + by) & 1 != parity.
    let masked_offset = i32((u32(by) + params.frame.z + 1u) & 1u);
    let masked = vec2<i32>(first + masked_offset, by) * 2;
    let shaded = vec2<i32>(first + 1 - masked_offset, by) * 2;
    for (var q = 0; q < 4; q = q + 1) {
        let o = vec2<i32>(q & 1, q >> 1u);
        let s = shaded + o;
        if inside(s) {
            textureStore(output, s, vec4<f32>(textureLoad(scene_color, s, 0).rgb, 1.0));
        }
        let r = masked + o;
        if inside(r) {
            textureStore(output, r, vec4<f32>(reconstitute(r), 1.0));
        }
    }
}
