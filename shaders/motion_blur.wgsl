// Motion blur of a compared frame (`reference.motion_blur`, harness/src/run/motion_blur.rs), as
// seeds/nvidia-adaptive-shading.txt models it: "LCD persistence induced motion blur has the same
// effect as applying a directional box filter to the displayed image. The width of box filter is
// equal to the velocity in units of pixels/frame" (section 4), and Fig. 9 compares quality "with
// an in-engine motion blur effect enabled", the filter matched "to the per-frame pixel motion
// footprint".
//
// Each pixel averages the frame at N points evenly spaced over the segment of its own motion
// centred on it (a gather, as engines' motion blur reads it), N = ceil(|v|) + 1, so that the
// points are at most a pixel apart; no blur where |v| < 0.5 px, where the motion is not finite,
// or on a frame with no previous frame in its shot. Linear light (the renderer's float output),
// bilinear between pixel centres, clamped at the borders.

struct Params {
    size: vec2<u32>,
    // 0: copy (no previous frame), 1: blur.
    enabled: u32,
    _p: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var src: texture_2d<f32>;
// The velocity pass's target: xy the motion in pixels from the previous frame (x right, y down).
@group(0) @binding(2) var motion: texture_2d<f32>;
@group(0) @binding(3) var dst: texture_storage_2d<rgba16float, write>;

// Motion longer than this many pixels is blurred over this many points (spaced wider).
const MAX_TAPS: u32 = 129u;

fn load(p: vec2<i32>) -> vec4<f32> {
    return textureLoad(src, clamp(p, vec2<i32>(0), vec2<i32>(params.size) - 1), 0);
}

// The frame at `x` (pixel units, centres at +0.5), bilinear.
fn bilinear(x: vec2<f32>) -> vec4<f32> {
    let q = x - 0.5;
    let i = vec2<i32>(floor(q));
    let f = q - floor(q);
    let top = mix(load(i), load(i + vec2<i32>(1, 0)), f.x);
    let bottom = mix(load(i + vec2<i32>(0, 1)), load(i + vec2<i32>(1, 1)), f.x);
    return mix(top, bottom, f.y);
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= params.size) {
        return;
    }
    let p = vec2<i32>(id.xy);
    var v = vec2<f32>(0.0);
    if params.enabled != 0u {
        v = textureLoad(motion, p, 0).xy;
    }
    let len = length(v);
    // `!(len >= 0.5)` is also true for a NaN motion.
    if !(len >= 0.5) || len > 1e6 {
        textureStore(dst, p, textureLoad(src, p, 0));
        return;
    }
    let taps = min(u32(ceil(len)) + 1u, MAX_TAPS);
    let centre = vec2<f32>(p) + 0.5;
    var sum = vec4<f32>(0.0);
    for (var i = 0u; i < taps; i = i + 1u) {
        let t = f32(i) / f32(taps - 1u) - 0.5;
        sum = sum + bilinear(centre + v * t);
    }
    textureStore(dst, p, sum / f32(taps));
}
