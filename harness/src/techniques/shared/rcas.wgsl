// RCAS (robust contrast-adaptive sharpening) as a compute pass, and the perceptual encoding FSR 1's
// passes work in: written from AMD's MIT reference `ffx_fsr1.h` as released in FidelityFX FSR
// v1.0.2 (GPUOpen-Effects/FidelityFX-FSR commit a21ffb8, whose one change is RCAS's limiter
// bounded by the centre pixel; sections "NON-PACKED 32-BIT VERSION" of RCAS and "[SRTM] SIMPLE
// REVERSIBLE TONE-MAPPER"). Shared by `fsr1` (its module is this file followed by
// `fsr1/fsr1.wgsl`, whose EASU uses the bindings and encoding below), and by `taau`, which runs
// this file alone as its RCAS pass over its linear resolved output (`fsr2` runs AMD's FSR 2
// RCAS instead, `fsr2/rcas.wgsl`). CPU model:
// `techniques/shared/rcas_model.rs`.
//
// RCAS works in SRTM + gamma 2.0 space (finite, non-negative; c / (max3(c) + 1), then sqrt) and
// decodes its output back to linear. Differences from the reference, all deliberate: taps are
// `textureLoad`s clamped to the edge; approximate reciprocals are exact divisions with the zero
// cases made explicit (the limiters are 0 where their denominator is 0); no FP16 path, no 8x8
// remapping of invocations; the filtered value is clamped to [0, 1] before the decode (v1.0.2's
// limiter keeps it there in exact arithmetic, the clamp absorbs f32 rounding).

struct Params {
    // x, y: input (render) size; z, w: output size.
    size: vec4<u32>,
    // x: RCAS sharpness as a linear amount, exp2(-stops) (FsrRcasCon); y: 1 when RCAS runs after
    // EASU (EASU then writes perceptual values), 0 when EASU writes the linear output itself;
    // z: 1 when RCAS's input is linear and is encoded per tap (`taau`'s RCAS after its resolve).
    rcas: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var src: texture_2d<f32>;
@group(0) @binding(2) var dst: texture_storage_2d<rgba16float, write>;

// Largest finite f16: the scene targets are Rgba16Float.
const F16_MAX: f32 = 65504.0;
// RCAS's limit of the negative lobe (ffx_fsr1.h FSR_RCAS_LIMIT): "the limit of providing
// unnatural results for sharpening".
const RCAS_LIMIT: f32 = 0.25 - 1.0 / 16.0;

fn max3(c: vec3<f32>) -> f32 {
    return max(c.r, max(c.g, c.b));
}

// Linear radiance to EASU's input space: finite, non-negative, SRTM, gamma 2.0.
fn encode(c: vec3<f32>) -> vec3<f32> {
    // `c >= 0` is false for NaN: NaN and negatives become 0.
    let finite = select(vec3<f32>(0.0), min(c, vec3<f32>(F16_MAX)), c >= vec3<f32>(0.0));
    return sqrt(finite / (max3(finite) + 1.0));
}

// The inverse of `encode` (SRTM inverse, FsrSrtmInvF, with its 1/32768 floor).
fn decode(p: vec3<f32>) -> vec3<f32> {
    let t = p * p;
    return t / max(1.0 / 32768.0, 1.0 - max3(t));
}

fn load_easu(p: vec2<i32>) -> vec3<f32> {
    let size = vec2<i32>(params.size.zw);
    let c = textureLoad(src, clamp(p, vec2<i32>(0), size - 1), 0).rgb;
    if params.rcas.z > 0.5 {
        return encode(c);
    }
    return c;
}

// One channel's lobe limit (ffx_fsr1.h v1.0.2, FsrRcasF "Limiters"): the negative lobe weight at
// which the cross filter would clip below 0 or above 1. v1.0.2's one fix bounds both with the
// centre tap `e` as well as the ring (`hitMin = min(mn4, e) / (4 mx4)`,
// `hitMax = (1 - max(mx4, e)) / (4 mn4 - 4)`); v1.0's ring-only limiter let an isolated peak
// (`e` above every ring tap) leave [0, 1], which the SRTM decode turns into huge radiance.
fn rcas_lobe(mn4: f32, mx4: f32, e: f32) -> f32 {
    var hit_min = 0.0;
    if mx4 > 0.0 {
        hit_min = min(mn4, e) / (4.0 * mx4);
    }
    var hit_max = 0.0;
    if mn4 < 1.0 {
        hit_max = (1.0 - max(mx4, e)) / (4.0 * mn4 - 4.0);
    }
    return max(-hit_min, hit_max);
}

// RCAS: the 5-tap cross
//    b
//  d e f
//    h
// with the negative lobe solved so that the output cannot clip, limited, times the sharpness.
// No noise removal (FSR_RCAS_DENOISE off, as in AMD's default).
@compute @workgroup_size(8, 8)
fn rcas(@builtin(global_invocation_id) id: vec3<u32>) {
    let out_size = params.size.zw;
    if id.x >= out_size.x || id.y >= out_size.y {
        return;
    }
    let p = vec2<i32>(id.xy);
    let b = load_easu(p + vec2<i32>(0, -1));
    let d = load_easu(p + vec2<i32>(-1, 0));
    let e = load_easu(p);
    let f = load_easu(p + vec2<i32>(1, 0));
    let h = load_easu(p + vec2<i32>(0, 1));
    let mn4 = min(min(b, d), min(f, h));
    let mx4 = max(max(b, d), max(f, h));
    let lobe_rgb = vec3<f32>(
        rcas_lobe(mn4.r, mx4.r, e.r),
        rcas_lobe(mn4.g, mx4.g, e.g),
        rcas_lobe(mn4.b, mx4.b, e.b),
    );
    let lobe = max(-RCAS_LIMIT, min(max3(lobe_rgb), 0.0)) * params.rcas.x;
    // In exact arithmetic v1.0.2's limiter keeps `pix` in [0, 1]; the clamp only absorbs f32
    // rounding, so the decode never sees 1 + epsilon (where `1 - max3` would reach its floor).
    let pix = clamp((lobe * (b + d + h + f) + e) / (4.0 * lobe + 1.0), vec3<f32>(0.0), vec3<f32>(1.0));
    textureStore(dst, id.xy, vec4<f32>(decode(pix), 1.0));
}
