// `taau` technique, pass `resolve`: temporal anti-aliasing with upsampling, one invocation per
// output pixel. Follows the published design as Yang, Liu and Salvi survey it ("A Survey of
// Temporal Antialiasing Techniques", Eurographics STAR 2020: section 3 jitter and accumulation,
// 4 reprojection and resampling, 5 history rectification, 6 upsampling) with Bevy's TAA resolve
// (crates/bevy_anti_alias/src/taa/taa.wgsl, MIT / Apache) as a readable reference:
//
// 1. The current sample: the render pixel q whose jittered sample lies nearest this output
//    pixel; it *lands* here when its position (q + 0.5 + jitter) / scale falls inside this pixel
//    (a box reconstruction filter: at scale 1 every frame's sample lands, so a still camera
//    accumulates the box-filtered pixel, the converged reference's estimate).
// 2. Motion: dynamic objects from the shared motion provider's velocity pass
//    (render/velocity.rs: the dynamic objects only, at the render size, rasterised in the same
//    jittered view as the scene pass, motion in output pixels), read at the sample's render
//    pixel q and trusted where its depth equals the scene's there (within MOTION_DEPTH_EPSILON;
//    a nearer scene depth is a static object in front); everything else from the sample's depth
//    through the cameras (prev_from_cur). A still camera on a static object is exactly still (no
//    rounding noise).
// 3. History: Catmull-Rom (4x4 taps) of the previous output at the previous position (survey
//    4.2; Bevy uses 5 bilinear taps for the same filter), its accumulated weight at the nearest
//    texel. No history on a cut, off screen, or where every one of the 3x3 previous depths around
//    it is nearer than the sample's previous depth by more than `depth_tolerance` (relative, in
//    reversed-Z): what covered this surface last frame has gone (disocclusion, survey 5.1
//    "geometry-based"). A nearer surface appearing is not a disocclusion: on a still camera it is
//    a sub-pixel feature that this jitter phase hits and others miss, and is kept. Where one of
//    those nearer previous depths was a dynamic object (the depth history marks them, +2), the
//    pixel counts as moving: an animated object left it, and its colour must be clipped away.
// 4. Rectification every frame, as Bevy's TAA and FSR 2 do: variance clipping in YCoCg (Salvi
//    2016, survey 5.2.2) of the history towards the centre of mean +- gamma * sigma of the 3x3
//    render neighbourhood; where anything moved the weight is also capped to `moving_weight` (a
//    faster response, Bevy's reset on motion). With `clip_moving_only` (the still-scene
//    accumulator, mode.w = 0) a pixel where nothing moved and nothing was disoccluded keeps its
//    history as is (thin geometry that one jitter phase misses is not erased; a change of
//    shading without motion ghosts).
// 5. Blend as a running mean: out = mix(history, sample, w / (W + w)), W the accumulated weight
//    (capped at `max_weight`), w = 1 where the sample lands, else 0; with no history and no
//    landing sample the nearest sample is taken with a weight of 1/256, replaced by the first
//    sample that lands. By default the mean goes on as an exponential one once W reaches
//    `max_weight`: each landing sample is blended in with at least 1/(1 + max_weight) (Bevy's
//    MIN_HISTORY_BLEND_RATE), so a change of shading without motion reaches the output. With
//    `freeze_converged` (mode: weights.w = 1), a still pixel whose history holds `max_weight`
//    samples keeps it (progressive accumulation that stops, as a path tracer's does: with as
//    many phases as `max_weight`, the mean of one whole cycle of the jitter).
//
// Deliberate differences from Bevy: linear colour throughout (no reversible tonemap: the
// running mean then equals the reference's mean of linear samples), no closest-depth motion
// dilation, upsampling, a depth disocclusion test, a per-pixel sample count instead of Bevy's
// confidence ramp. Input samples are made finite and non-negative (NaN and negatives to 0, +Inf
// to the f16 maximum) so a non-finite pixel never enters the history.
//
// The CPU model in harness/src/techniques/taau/model.rs mirrors this file step by step.

struct Params {
    // Current output clip space (unjittered) to the previous frame's (f64 on the CPU, then f32).
    prev_from_cur: mat4x4<f32>,
    // x, y: render size; z, w: output size.
    size: vec4<u32>,
    // xy: this frame's jitter in render pixels; z: clip gamma; w: depth tolerance.
    jitter: vec4<f32>,
    // x: max weight; y: moving weight; z: 1/256 fill weight; w: 1 to freeze converged still pixels.
    weights: vec4<f32>,
    // x: history valid; y: velocity bound; z: camera still; w: clip still pixels too (0 with
    // `clip_moving_only`).
    mode: vec4<u32>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var color_low: texture_2d<f32>;
@group(0) @binding(2) var depth_low: texture_depth_2d;
@group(0) @binding(3) var history: texture_2d<f32>;
@group(0) @binding(4) var depth_history: texture_2d<f32>;
@group(0) @binding(5) var velocity: texture_2d<f32>;
@group(0) @binding(6) var out_color: texture_storage_2d<rgba16float, write>;
@group(0) @binding(7) var out_depth: texture_storage_2d<r32float, write>;
// The motion pass's depth (reversed-Z, render size, 0 where it drew nothing).
@group(0) @binding(8) var velocity_depth: texture_depth_2d;

// How much nearer (relative, reversed-Z) the scene's depth may be than the motion pass's at the
// same sample before a static object is taken to hide the dynamic one: both passes rasterise
// the same triangles in the same view, and differ only by the rounding of two vertex transforms
// (`view_proj * model * p` against `view_proj * (model * p)`).
const MOTION_DEPTH_EPSILON: f32 = 1e-4;

const F16_MAX: f32 = 65504.0;

fn sanitize(c: vec3<f32>) -> vec3<f32> {
    return select(vec3<f32>(0.0), min(c, vec3<f32>(F16_MAX)), c >= vec3<f32>(0.0));
}

fn low_at(q: vec2<i32>) -> vec3<f32> {
    let c = clamp(q, vec2<i32>(0), vec2<i32>(params.size.xy) - 1);
    return sanitize(textureLoad(color_low, c, 0).rgb);
}

fn history_at(p: vec2<i32>) -> vec4<f32> {
    let c = clamp(p, vec2<i32>(0), vec2<i32>(params.size.zw) - 1);
    return textureLoad(history, c, 0);
}

fn depth_history_at(p: vec2<i32>) -> f32 {
    let c = clamp(p, vec2<i32>(0), vec2<i32>(params.size.zw) - 1);
    return textureLoad(depth_history, c, 0).r;
}

// Playdead's YCoCg, as Bevy uses it.
fn to_ycocg(c: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(
        c.r * 0.25 + c.g * 0.5 + c.b * 0.25,
        c.r * 0.5 - c.b * 0.5,
        -c.r * 0.25 + c.g * 0.5 - c.b * 0.25,
    );
}

fn from_ycocg(c: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(c.x + c.y - c.z, c.x + c.z, c.x - c.y - c.z);
}

// Catmull-Rom weights of the four taps around a fraction f in [0, 1).
fn catmull_rom(f: f32) -> vec4<f32> {
    return vec4<f32>(
        f * (-0.5 + f * (1.0 - 0.5 * f)),
        1.0 + f * f * (-2.5 + 1.5 * f),
        f * (0.5 + f * (2.0 - 1.5 * f)),
        f * f * (-0.5 + 0.5 * f),
    );
}

// The previous output's colour at a position in output pixels (centres at +0.5), 4x4 taps,
// edges clamped; negative ringing clamped to 0.
fn history_catmull_rom(pos: vec2<f32>) -> vec3<f32> {
    let t = pos - 0.5;
    let base = floor(t);
    let f = t - base;
    let wx = catmull_rom(f.x);
    let wy = catmull_rom(f.y);
    let b = vec2<i32>(base);
    var sum = vec3<f32>(0.0);
    for (var y = 0; y < 4; y++) {
        var row = vec3<f32>(0.0);
        for (var x = 0; x < 4; x++) {
            row += history_at(b + vec2<i32>(x - 1, y - 1)).rgb * wx[x];
        }
        sum += row * wy[y];
    }
    return max(sum, vec3<f32>(0.0));
}

// Variance clipping towards the box centre (Bevy's clip_towards_aabb_center). Bevy's extent floor
// is an absolute 1e-8; here it is 1e-3 of the box centre's luma (plus 1e-6): on grey content the
// chroma box is flat and the history's chroma is rounding noise (about 1e-7 of the luma, and not
// the same noise on every GPU), which an absolute floor turns into a clip of the whole colour
// onto the box centre.
fn clip_towards_centre(h: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>) -> vec3<f32> {
    let centre = 0.5 * (hi + lo);
    let extent = 0.5 * (hi - lo) + (1e-3 * abs(centre.x) + 1e-6);
    let v = h - centre;
    let m = max(abs(v.x / extent.x), max(abs(v.y / extent.y), abs(v.z / extent.z)));
    if m > 1.0 {
        return centre + v / m;
    }
    return h;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let out_size = params.size.zw;
    if id.x >= out_size.x || id.y >= out_size.y {
        return;
    }
    let low_size = vec2<f32>(params.size.xy);
    let size = vec2<f32>(out_size);
    let scale = low_size / size;
    let j = params.jitter.xy;
    let centre = vec2<f32>(id.xy) + 0.5;
    // 1. The nearest current sample and whether it lands in this pixel.
    let q = clamp(vec2<i32>(floor(centre * scale - j)), vec2<i32>(0), vec2<i32>(params.size.xy) - 1);
    let sample_pos = (vec2<f32>(q) + 0.5 + j) / scale;
    let lands = all(floor(sample_pos) == vec2<f32>(id.xy));
    let current = low_at(q);
    let depth = textureLoad(depth_low, q, 0);

    // 2. Motion: where this pixel's content was last frame, and its expected previous depth.
    var prev_pos = centre;
    var prev_depth = depth;
    var moving = false;
    var v = vec4<f32>(0.0);
    var dynamic_here = false;
    if params.mode.y != 0u {
        v = textureLoad(velocity, q, 0);
        let vd = textureLoad(velocity_depth, q, 0);
        if depth - vd > MOTION_DEPTH_EPSILON * max(depth, vd) {
            v.z = 0.0;
        }
    }
    if v.z > 0.5 {
        dynamic_here = true;
        prev_pos = centre - v.xy;
        prev_depth = v.w;
        moving = any(v.xy != vec2<f32>(0.0));
    } else if params.mode.z == 0u {
        let ndc = vec4<f32>(sample_pos.x / size.x * 2.0 - 1.0, 1.0 - sample_pos.y / size.y * 2.0, depth, 1.0);
        let prev = params.prev_from_cur * ndc;
        let prev_sample = vec2<f32>((prev.x / prev.w * 0.5 + 0.5) * size.x, (0.5 - prev.y / prev.w * 0.5) * size.y);
        prev_pos = centre - (sample_pos - prev_sample);
        prev_depth = prev.z / prev.w;
        moving = true;
    }

    // 3. The history, if there is one for this content.
    var weight = 0.0;
    var hist = vec3<f32>(0.0);
    // False for NaN positions.
    let on_screen = all(prev_pos >= vec2<f32>(0.0)) && all(prev_pos < size);
    if params.mode.x != 0u && on_screen {
        let pp = vec2<i32>(floor(prev_pos));
        var matched = false;
        var left = false;
        for (var dy = -1; dy <= 1; dy++) {
            for (var dx = -1; dx <= 1; dx++) {
                let packed = depth_history_at(pp + vec2<i32>(dx, dy));
                let dynamic_there = packed >= 2.0;
                let d = select(packed, packed - 2.0, dynamic_there);
                let nearer = d - prev_depth > params.jitter.w * max(d, prev_depth);
                matched = matched || !nearer;
                left = left || (nearer && dynamic_there);
            }
        }
        moving = moving || left;
        // On a still camera static content is disoccluded only by an animated object leaving:
        // elsewhere "every neighbour was nearer" is a silhouette the jitter crossed.
        let can_disocclude = params.mode.z == 0u || dynamic_here || left;
        if matched || !can_disocclude {
            weight = history_at(pp).a;
            hist = history_catmull_rom(prev_pos);
        }
    }

    // 4. Rectification where anything moved.
    if weight > 0.0 && (moving || params.mode.w != 0u) {
        var m1 = vec3<f32>(0.0);
        var m2 = vec3<f32>(0.0);
        for (var dy = -1; dy <= 1; dy++) {
            for (var dx = -1; dx <= 1; dx++) {
                let s = to_ycocg(low_at(q + vec2<i32>(dx, dy)));
                m1 += s;
                m2 += s * s;
            }
        }
        let mean = m1 / 9.0;
        let sigma = sqrt(max(m2 / 9.0 - mean * mean, vec3<f32>(0.0)));
        let gamma = params.jitter.z;
        hist = max(from_ycocg(clip_towards_centre(to_ycocg(hist), mean - gamma * sigma, mean + gamma * sigma)), vec3<f32>(0.0));
        if moving {
            weight = min(weight, params.weights.y);
        }
    }

    // 5. Blend.
    weight = min(weight, params.weights.x);
    var w = select(0.0, 1.0, lands);
    if weight == 0.0 && !lands {
        w = params.weights.z;
    }
    // A still pixel that holds `max_weight` samples keeps them (`freeze_converged`).
    if params.weights.w > 0.5 && !moving && weight >= params.weights.x {
        w = 0.0;
    }
    let total = weight + w;
    var out = hist;
    if w > 0.0 {
        out = mix(hist, current, w / total);
    }
    textureStore(out_color, id.xy, vec4<f32>(out, min(total, params.weights.x)));
    textureStore(out_depth, id.xy, vec4<f32>(select(depth, depth + 2.0, dynamic_here), 0.0, 0.0, 0.0));
}
