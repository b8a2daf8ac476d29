// `fsr2` technique: what every pass shares (prepended to each pass file to make its module):
// the uniforms and the helpers of AMD FidelityFX FSR 2.2.1 (GPUOpen-Effects/FidelityFX-FSR2,
// MIT, src/ffx-fsr2-api/shaders/ffx_fsr2_common.h and ffx_fsr2_sample.h), written from them,
// f32 only (AMD's FFX_HALF 0 path). Conventions as AMD's: uv in [0, 1] with y down; motion in
// uv from the current position to the previous one (`fUv + fMotionVector` is where the content
// was); `jitter` is AMD's `Jitter()`, the offset `ffxFsr2GetJitterOffset` returns, so render
// pixel q saw the unjittered image at q + 0.5 - jitter; depth reversed (FFX_FSR2_OPTION_INVERTED_DEPTH 1,
// far plane finite); colour HDR linear (FFX_FSR2_OPTION_HDR_COLOR_INPUT 1), pre-exposure 1.

struct Params {
    // x, y: render size; z, w: display size.
    size: vec4<u32>,
    // xy: Jitter() in render pixels; z: seconds since the last frame (DeltaTime, clamped to
    // [0, 1]); w: jitter phase count (JitterSequenceLength).
    jitter: vec4<f32>,
    // DeviceToViewSpaceTransformFactors (ffx_fsr2.cpp setupDeviceDepthToViewSpaceDepthParams).
    depth_to_view: vec4<f32>,
    // x: 1 on a reset frame (FrameIndex() == 0: the first frame, a cut); y: 1 when the shared
    // motion provider's buffer is bound; z: 1 when the camera is still; w: 1 with auto exposure.
    mode: vec4<u32>,
    // The luminance mip used for shading change (LumaMipDimensions) in xy; z: its level.
    luma: vec4<u32>,
    // Current output clip space (unjittered) to the previous frame's.
    prev_from_cur: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> params: Params;

const FSR2_FP16_MAX: f32 = 65504.0;
const FSR2_EPSILON: f32 = 1e-3;
const FSR2_TONEMAP_EPSILON: f32 = 1.0 / 65504.0;
const FSR2_FLT_MAX: f32 = 3.402823466e+38;
const RECONSTRUCTED_DEPTH_WEIGHT_THRESHOLD: f32 = 0.01;
const UPSAMPLE_LANCZOS_WEIGHT_SCALE: f32 = 1.0 / 12.0;
const MAX_ACCUMULATION_LANCZOS_WEIGHT: f32 = 1.0;
const AVERAGE_LANCZOS_WEIGHT_PER_FRAME: f32 = 0.74 / 12.0;
const RESET_AUTO_EXPOSURE_AVERAGE_SMOOTHING: f32 = 1e8;

fn render_size() -> vec2<f32> {
    return vec2<f32>(params.size.xy);
}

fn display_size() -> vec2<f32> {
    return vec2<f32>(params.size.zw);
}

fn jitter() -> vec2<f32> {
    return params.jitter.xy;
}

// DownscaleFactor(): render size over display size.
fn downscale_factor() -> vec2<f32> {
    return render_size() / display_size();
}

fn saturate(x: f32) -> f32 {
    return clamp(x, 0.0, 1.0);
}

fn rgb_to_ycocg(c: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(
        0.25 * c.r + 0.5 * c.g + 0.25 * c.b,
        0.5 * c.r - 0.5 * c.b,
        -0.25 * c.r + 0.5 * c.g - 0.25 * c.b,
    );
}

fn ycocg_to_rgb(c: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(c.x + c.y - c.z, c.x + c.z, c.x - c.y - c.z);
}

fn rgb_to_luma(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// RGBToPerceivedLuma: CIE L* / 100.
fn rgb_to_perceived_luma(c: vec3<f32>) -> f32 {
    let l = rgb_to_luma(c);
    var p = 0.0;
    if l <= 216.0 / 24389.0 {
        p = l * (24389.0 / 27.0);
    } else {
        p = pow(l, 1.0 / 3.0) * 116.0 - 16.0;
    }
    return p * 0.01;
}

fn tonemap(c: vec3<f32>) -> vec3<f32> {
    return c / (max(max(0.0, c.r), max(c.g, c.b)) + 1.0);
}

fn inverse_tonemap(c: vec3<f32>) -> vec3<f32> {
    return c / max(FSR2_TONEMAP_EPSILON, 1.0 - max(c.r, max(c.g, c.b)));
}

fn min_divided_by_max(a: f32, b: f32) -> f32 {
    let m = max(a, b);
    if m != 0.0 {
        return min(a, b) / m;
    }
    return 0.0;
}

// ClampLoad: the offset position clamped to the texture on the side it moves towards.
fn clamp_load(p: vec2<i32>, off: vec2<i32>, size: vec2<i32>) -> vec2<i32> {
    var r = p + off;
    if off.x < 0 { r.x = max(r.x, 0); }
    if off.x > 0 { r.x = min(r.x, size.x - 1); }
    if off.y < 0 { r.y = max(r.y, 0); }
    if off.y > 0 { r.y = min(r.y, size.y - 1); }
    return r;
}

// ClampUv: a uv kept half a texel inside a `texture_size` region of a `resource_size` texture.
fn clamp_uv(uv: vec2<f32>, texture_size: vec2<f32>, resource_size: vec2<f32>) -> vec2<f32> {
    let l = uv * texture_size;
    return max(vec2<f32>(0.5), min(l, texture_size - 0.5)) / resource_size;
}

fn is_on_screen(p: vec2<i32>, size: vec2<i32>) -> bool {
    return all(vec2<u32>(p) < vec2<u32>(size));
}

// ComputeHrPosFromLrPos: the display pixel a render pixel's sample fell in.
fn hr_pos_from_lr_pos(lr: vec2<i32>) -> vec2<i32> {
    let jittered = vec2<f32>(lr) + 0.5 - jitter();
    return vec2<i32>(floor(jittered / render_size() * display_size()));
}

// GetViewSpaceDepth.
fn view_space_depth(device_depth: f32) -> f32 {
    let f = params.depth_to_view;
    return f.y / (device_depth - f.x);
}

// ComputeNdc and GetViewSpacePosition.
fn view_space_position(p: vec2<i32>, size: vec2<i32>, device_depth: f32) -> vec3<f32> {
    let f = params.depth_to_view;
    let z = view_space_depth(device_depth);
    let ndc = vec2<f32>(p) / vec2<f32>(size) * vec2<f32>(2.0, -2.0) + vec2<f32>(-1.0, 1.0);
    return vec3<f32>(f.z * ndc.x * z, f.w * ndc.y * z, z);
}

// PrepareRgb with pre-exposure 1.
fn prepare_rgb(c: vec3<f32>, exposure: f32) -> vec3<f32> {
    return clamp(c * exposure, vec3<f32>(0.0), vec3<f32>(FSR2_FP16_MAX));
}

// GetBilinearSamplingData: the top-left texel and the weights of the four around `uv`.
struct Bilinear {
    base: vec2<i32>,
    weights: vec4<f32>,
}

fn bilinear_data(uv: vec2<f32>, size: vec2<f32>) -> Bilinear {
    let px = uv * size - 0.5;
    let f = fract(px);
    return Bilinear(
        vec2<i32>(floor(px)),
        vec4<f32>((1.0 - f.x) * (1.0 - f.y), f.x * (1.0 - f.y), (1.0 - f.x) * f.y, f.x * f.y),
    );
}

// Offsets of GetBilinearSamplingData's four weights, in order.
fn bilinear_offset(i: i32) -> vec2<i32> {
    return vec2<i32>(i & 1, i >> 1);
}

// Lanczos2 (reference, clamped at 2).
fn lanczos2(x_in: f32) -> f32 {
    let x = min(abs(x_in), 2.0);
    let pi = 3.141592653589793;
    if abs(x) < FSR2_EPSILON {
        return 1.0;
    }
    return (sin(pi * x) / (pi * x)) * (sin(0.5 * pi * x) / (0.5 * pi * x));
}

// Lanczos2ApproxSq: FSR 1's polynomial, of x squared (at most 4).
fn lanczos2_approx_sq(x2_in: f32) -> f32 {
    let x2 = min(x2_in, 4.0);
    let a = (2.0 / 5.0) * x2 - 1.0;
    let b = (1.0 / 4.0) * x2 - 1.0;
    return ((25.0 / 16.0) * a * a - (25.0 / 16.0 - 1.0)) * (b * b);
}

// The uv -> texel and fraction of DeclareCustomTextureSample: base clamped to [0, size].
fn custom_sample_pos(uv: vec2<f32>, size: vec2<f32>) -> vec4<f32> {
    let px = clamp(uv * size - 0.5, vec2<f32>(0.0), size);
    return vec4<f32>(floor(px), fract(px));
}
