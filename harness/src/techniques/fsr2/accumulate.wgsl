// `fsr2` pass `accumulate`: AMD's reproject and accumulate pass (ffx_fsr2_accumulate.h,
// Accumulate; entry ffx_fsr2_accumulate_pass.glsl; with ffx_fsr2_reproject.h,
// ffx_fsr2_upsample.h and ffx_fsr2_postprocess_lock_status.h), one invocation per display pixel:
// the history reprojected by the dilated motion and read through a Lanczos-2 4x4 filter with
// deringing (ReprojectHistoryColor, HistorySample), the lock status read bilinearly and updated
// with new locks and the shading change of the luminance mip (ReprojectHistoryLockStatus,
// UpdateLockStatus), the render samples spread over the display pixel by Lanczos-2
// (ComputeUpsampledColorAndWeight, FFX_FSR2_OPTION_UPSAMPLE_USE_LANCZOS_TYPE 2, the
// approximation) with a variance box, luma instability from four frames of luma history
// (ComputeLumaInstabilityFactor), rectification (RectifyHistory) and the blend in tonemapped
// space (Accumulate, HDR input), lock lifetime (FinalizeLockStatus) and the temporal reactive
// factor kept in the history's alpha (ComputeTemporalReactiveFactor).
//
// The 3x3 of the upsample's 4x4 is unrolled by hand and fused with its loads (AMD loads nine
// samples into a private array first: the spilling hazard of a naga port). Hardware-sampler
// reads (depth clip, reactive masks, luma history, luma mip) are bilinear reads written out,
// clamped to the edge, as a linear clamp sampler does.

@group(0) @binding(1) var prepared: texture_2d<f32>;
@group(0) @binding(2) var dilated_motion: texture_2d<f32>;
@group(0) @binding(3) var reactive: texture_2d<f32>;
@group(0) @binding(4) var history: texture_2d<f32>;
@group(0) @binding(5) var lock_status_in: texture_2d<f32>;
@group(0) @binding(6) var luma_history_in: texture_2d<f32>;
@group(0) @binding(7) var luma_mip: texture_2d<f32>;
@group(0) @binding(8) var<storage, read> exposure_buf: vec2<f32>;
@group(0) @binding(9) var<storage, read_write> new_locks: array<f32>;
@group(0) @binding(10) var color_out: texture_storage_2d<rgba16float, write>;
@group(0) @binding(11) var lock_status_out: texture_storage_2d<rgba16float, write>;
@group(0) @binding(12) var luma_history_out: texture_storage_2d<rgba16float, write>;

fn exposure() -> f32 {
    return select(1.0, exposure_buf.x, params.mode.w != 0u);
}

fn load_clamped(t: texture_2d<f32>, p: vec2<i32>, size: vec2<i32>) -> vec4<f32> {
    return textureLoad(t, clamp(p, vec2<i32>(0), size - 1), 0);
}

// A linear clamp-to-edge sampler's read of `t` (`size` texels) at `uv`.
fn bilinear(t: texture_2d<f32>, uv: vec2<f32>, size: vec2<i32>) -> vec4<f32> {
    let px = uv * vec2<f32>(size) - 0.5;
    let b = vec2<i32>(floor(px));
    let f = fract(px);
    let top = mix(load_clamped(t, b, size), load_clamped(t, b + vec2<i32>(1, 0), size), f.x);
    let bottom = mix(load_clamped(t, b + vec2<i32>(0, 1), size), load_clamped(t, b + vec2<i32>(1, 1), size), f.x);
    return mix(top, bottom, f.y);
}

// DeclareCustomTextureSample with the bilinear fetch (SampleLockStatus).
fn custom_bilinear(t: texture_2d<f32>, uv: vec2<f32>, size: vec2<i32>) -> vec4<f32> {
    let s = custom_sample_pos(uv, vec2<f32>(size));
    let b = vec2<i32>(s.xy);
    let f = s.zw;
    let top = mix(load_clamped(t, b, size), load_clamped(t, b + vec2<i32>(1, 0), size), f.x);
    let bottom = mix(load_clamped(t, b + vec2<i32>(0, 1), size), load_clamped(t, b + vec2<i32>(1, 1), size), f.x);
    return mix(top, bottom, f.y);
}

// The Lanczos2 (reference) interpolation of four taps at fraction `t` (ffx_fsr2_sample.h).
fn lanczos2_4(c0: vec4<f32>, c1: vec4<f32>, c2: vec4<f32>, c3: vec4<f32>, t: f32) -> vec4<f32> {
    let w0 = lanczos2(-1.0 - t);
    let w1 = lanczos2(-0.0 - t);
    let w2 = lanczos2(1.0 - t);
    let w3 = lanczos2(2.0 - t);
    return (w0 * c0 + w1 * c1 + w2 * c2 + w3 * c3) / (w0 + w1 + w2 + w3);
}

fn history_row(b: vec2<i32>, y: i32, fx: f32, size: vec2<i32>) -> vec4<f32> {
    return lanczos2_4(
        load_clamped(history, b + vec2<i32>(-1, y), size),
        load_clamped(history, b + vec2<i32>(0, y), size),
        load_clamped(history, b + vec2<i32>(1, y), size),
        load_clamped(history, b + vec2<i32>(2, y), size),
        fx,
    );
}

// HistorySample: Lanczos2 over 4x4 texels, deringed to the central 2x2.
fn history_sample(uv: vec2<f32>) -> vec4<f32> {
    let size = vec2<i32>(params.size.zw);
    let s = custom_sample_pos(uv, display_size());
    let b = vec2<i32>(s.xy);
    let f = s.zw;
    let c = lanczos2_4(
        history_row(b, -1, f.x, size),
        history_row(b, 0, f.x, size),
        history_row(b, 1, f.x, size),
        history_row(b, 2, f.x, size),
        f.y,
    );
    let c11 = load_clamped(history, b, size);
    let c21 = load_clamped(history, b + vec2<i32>(1, 0), size);
    let c12 = load_clamped(history, b + vec2<i32>(0, 1), size);
    let c22 = load_clamped(history, b + vec2<i32>(1, 1), size);
    return clamp(c, min(min(c11, c21), min(c12, c22)), max(max(c11, c21), max(c12, c22)));
}

struct Common {
    hr: vec2<i32>,
    hr_uv: vec2<f32>,
    lr_uv_hw: vec2<f32>,
    motion: vec2<f32>,
    reprojected_uv: vec2<f32>,
    hr_velocity: f32,
    depth_clip: f32,
    dilated_reactive: f32,
    accumulation_mask: f32,
    reset: bool,
    existing: bool,
    new_sample: bool,
}

fn is_uv_inside(uv: vec2<f32>) -> bool {
    return uv.x >= 0.0 && uv.x <= 1.0 && uv.y >= 0.0 && uv.y <= 1.0;
}

// InitParams.
fn init_params(hr: vec2<i32>) -> Common {
    var c: Common;
    let rs = vec2<i32>(params.size.xy);
    c.hr = hr;
    c.hr_uv = (vec2<f32>(hr) + 0.5) / display_size();
    c.lr_uv_hw = clamp_uv(c.hr_uv + jitter() / render_size(), render_size(), render_size());
    // GetMotionVector with FFX_FSR2_OPTION_LOW_RESOLUTION_MOTION_VECTORS.
    c.motion = load_clamped(dilated_motion, vec2<i32>(c.hr_uv * render_size()), rs).xy;
    c.hr_velocity = length(c.motion * display_size());
    c.reprojected_uv = c.hr_uv + c.motion;
    c.existing = is_uv_inside(c.reprojected_uv);
    c.depth_clip = saturate(bilinear(prepared, c.lr_uv_hw, rs).w);
    let masks = bilinear(reactive, c.lr_uv_hw, rs).xy;
    c.dilated_reactive = masks.x;
    c.accumulation_mask = masks.y;
    c.reset = params.mode.x != 0u;
    c.new_sample = !c.existing || c.reset;
    return c;
}

// GetShadingChangeLuma.
fn shading_change_luma(uv_in: vec2<f32>) -> f32 {
    let div = f32(2u << params.luma.z);
    let mip_render_size = vec2<f32>(vec2<i32>(render_size() / div));
    let dims = vec2<i32>(params.luma.xy);
    let uv = clamp_uv(uv_in, mip_render_size, vec2<f32>(dims));
    let l = exposure() * exp(bilinear(luma_mip, uv, dims).r);
    return pow(l, 1.0 / 6.0);
}

struct LockUpdate {
    status: vec2<f32>,
    reactive: f32,
    contribution: f32,
    luminance_diff: f32,
}

// UpdateLockStatus.
fn update_lock_status(c: Common, reactive_in: f32, new_lock: bool, status_in: vec2<f32>) -> LockUpdate {
    var s = status_in;
    let scl = shading_change_luma(c.hr_uv);
    if s.y == 0.0 {
        s.y = scl;
    }
    let prev_scl = s.y;
    let diff = 1.0 - min_divided_by_max(prev_scl, scl);
    if new_lock {
        s.y = scl;
        s.x = select(1.0, 2.0, s.x != 0.0);
    } else if s.x <= 1.0 {
        s.y = mix(s.y, scl, 0.5);
    } else if diff > 0.1 {
        s.x = 0.0;
    }
    let r = max(reactive_in, saturate((diff - 0.1) * 10.0));
    s.x *= 1.0 - r;
    s.x *= saturate(1.0 - c.accumulation_mask);
    s.x *= f32(c.depth_clip < 0.1);
    let lifetime = saturate(s.x - 1.0);
    let shading = saturate(min_divided_by_max(s.y, scl));
    return LockUpdate(s, r, saturate(saturate(lifetime * 4.0) * shading), diff);
}

struct Box {
    centre: vec3<f32>,
    vec: vec3<f32>,
    lo: vec3<f32>,
    hi: vec3<f32>,
    weight: f32,
}

struct Upsample {
    color: vec4<f32>,
    b: Box,
}

struct UpsampleSetup {
    src_input: vec2<i32>,
    offset_tl: vec2<i32>,
    flip: vec2<bool>,
    base_offset: vec2<f32>,
    kernel_bias: f32,
    curve_bias: f32,
}

// ComputeMaxKernelWeight.
fn max_kernel_weight() -> f32 {
    let w = 1.0 + (1.0 / downscale_factor() - 1.0).x * 1.0;
    return min(1.99, w);
}

// One of the 3x3 taps of ComputeUpsampledColorAndWeight: the load, its Lanczos weight and the
// rectification box (RectificationBoxAddSample).
fn upsample_tap(u: Upsample, s: UpsampleSetup, row: i32, col: i32) -> Upsample {
    var o = u;
    let rs = vec2<i32>(params.size.xy);
    let col_row = vec2<i32>(select(col, 3 - col, s.flip.x), select(row, 3 - row, s.flip.y));
    let pos = s.src_input + s.offset_tl + col_row;
    // AMD loads the tap unclamped (ClampLoad with a zero offset clamps nothing): off the screen
    // it reads 0 (D3D12's out-of-bounds load, Vulkan's robust image access), which the
    // rectification box takes in though the Lanczos weight is 0.
    let on_screen_tap = is_on_screen(pos, rs);
    let sample = select(vec3<f32>(0.0), load_clamped(prepared, pos, rs).xyz, on_screen_tap);
    let off = s.base_offset + vec2<f32>(s.offset_tl + col_row);
    let on_screen = f32(on_screen_tap);
    let biased = off * s.kernel_bias;
    let w = on_screen * lanczos2_approx_sq(dot(biased, biased));
    o.color += vec4<f32>(sample * w, w);
    let box_w = exp(s.curve_bias * dot(off, off));
    if row == 0 && col == 0 {
        o.b = Box(sample * box_w, sample * sample * box_w, sample, sample, box_w);
    } else {
        o.b.lo = min(o.b.lo, sample);
        o.b.hi = max(o.b.hi, sample);
        o.b.centre += sample * box_w;
        o.b.vec += sample * sample * box_w;
        o.b.weight += box_w;
    }
    return o;
}

// ComputeUpsampledColorAndWeight.
fn upsampled_color_and_weight(c: Common, reactive_factor: f32) -> Upsample {
    var s: UpsampleSetup;
    let dst = vec2<f32>(c.hr) + 0.5;
    let src = dst * downscale_factor();
    s.src_input = vec2<i32>(floor(src));
    let unjittered = vec2<f32>(s.src_input) + 0.5 - jitter();
    s.flip = unjittered > src;
    s.offset_tl = select(vec2<i32>(-1), vec2<i32>(-2), s.flip);
    s.base_offset = unjittered - src;
    let kernel_reactive = max(reactive_factor, f32(c.new_sample));
    let bias_max = max_kernel_weight() * (1.0 - kernel_reactive);
    let bias_min = max(1.0, (1.0 + bias_max) * 0.3);
    let bias_factor = max(0.0, max(0.25 * c.depth_clip, kernel_reactive));
    s.kernel_bias = mix(bias_max, bias_min, bias_factor);
    s.curve_bias = mix(-2.0, -3.0, saturate(c.hr_velocity / 50.0));
    var u = Upsample(vec4<f32>(0.0), Box(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), 0.0));
    u = upsample_tap(u, s, 0, 0);
    u = upsample_tap(u, s, 0, 1);
    u = upsample_tap(u, s, 0, 2);
    u = upsample_tap(u, s, 1, 0);
    u = upsample_tap(u, s, 1, 1);
    u = upsample_tap(u, s, 1, 2);
    u = upsample_tap(u, s, 2, 0);
    u = upsample_tap(u, s, 2, 1);
    u = upsample_tap(u, s, 2, 2);
    // RectificationBoxComputeVarianceBoxData.
    let bw = select(1.0, u.b.weight, abs(u.b.weight) > FSR2_EPSILON);
    u.b.centre /= bw;
    u.b.vec = sqrt(abs(u.b.vec / bw - u.b.centre * u.b.centre));
    u.color.w *= f32(u.color.w > FSR2_EPSILON);
    if u.color.w > FSR2_EPSILON {
        u.color = vec4<f32>(clamp(u.color.xyz / u.color.w, u.b.lo, u.b.hi), u.color.w * UPSAMPLE_LANCZOS_WEIGHT_SCALE);
    }
    return u;
}

// ComputeLumaInstabilityFactor: also stores the shifted luma history.
fn luma_instability(c: Common, b: Box, this_reactive: f32, luminance_diff: f32) -> f32 {
    let threshold = 1.0 / 255.0;
    var cur = b.centre.x;
    cur = cur / (1.0 + max(0.0, cur));
    cur = round(cur * 255.0) / 255.0;
    let sample_history = max(max(c.depth_clip, c.accumulation_mask), luminance_diff) < 0.1 && !c.new_sample;
    var h = vec4<f32>(0.0);
    if sample_history {
        h = bilinear(luma_history_in, c.reprojected_uv, vec2<i32>(params.size.zw));
    }
    var instability = 0.0;
    let d0 = cur - h.x;
    var m = abs(d0);
    if m >= threshold {
        let d1 = cur - h.y;
        if sign(d0) == sign(d1) { m = min(m, abs(d1)); }
        let d2 = cur - h.z;
        if sign(d0) == sign(d2) { m = min(m, abs(d2)); }
        let d3 = cur - h.w;
        if sign(d0) == sign(d3) { m = min(m, abs(d3)); }
        let box_size_factor = pow(saturate(b.vec.x / 0.1), 6.0);
        instability = f32(m != abs(d0)) * box_size_factor;
        instability = f32(instability > threshold);
        instability *= 1.0 - max(c.accumulation_mask, pow(this_reactive, 1.0 / 6.0));
    }
    let shifted = vec4<f32>(cur, h.x, h.y, h.z);
    textureStore(luma_history_out, c.hr, shifted);
    return instability * f32(shifted.w != 0.0);
}

// ComputeBaseAccumulationWeight.
fn base_accumulation_weight(c: Common, this_reactive: f32, in_motion_last: bool, w_up: f32) -> f32 {
    var a = MAX_ACCUMULATION_LANCZOS_WEIGHT * f32(c.existing) * (1.0 - this_reactive) * (1.0 - c.depth_clip);
    a = min(a, mix(a, w_up * 10.0, max(f32(in_motion_last), saturate(c.hr_velocity * 10.0))));
    a = min(a, mix(a, w_up, saturate(c.hr_velocity / 20.0)));
    return a;
}

// ComputeTemporalReactiveFactor.
fn temporal_reactive_factor(c: Common, factor: f32) -> f32 {
    var f = min(0.99, factor);
    f = max(f, mix(f, 0.4, saturate(c.hr_velocity)));
    f = max(f * f, max(c.depth_clip * 0.1, c.dilated_reactive));
    if c.new_sample {
        f = 1.0;
    }
    if saturate(c.hr_velocity * 10.0) >= 1.0 {
        f = max(FSR2_EPSILON, f) * -1.0;
    }
    return f;
}

@compute @workgroup_size(8, 8)
fn accumulate(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= params.size.zw) {
        return;
    }
    let c = init_params(vec2<i32>(id.xy));
    let display = vec2<i32>(params.size.zw);
    let lock_index = id.y * params.size.z + id.x;

    var hist = vec3<f32>(0.0);
    var lock_status = vec2<f32>(0.0);
    var temporal_reactive = 0.0;
    var in_motion_last = false;
    var new_lock = false;
    if c.existing && !c.reset {
        // ReprojectHistoryColor.
        let h = history_sample(c.reprojected_uv);
        hist = rgb_to_ycocg(prepare_rgb(h.rgb, exposure()));
        temporal_reactive = saturate(abs(h.w));
        in_motion_last = h.w < 0.0;
        // ReprojectHistoryLockStatus.
        new_lock = new_locks[lock_index] > 127.0 / 255.0;
        lock_status = custom_bilinear(lock_status_in, c.reprojected_uv, display).xy;
    }
    let lock = update_lock_status(c, max(c.dilated_reactive, temporal_reactive), new_lock, lock_status);
    lock_status = lock.status;
    let this_reactive = lock.reactive;

    let up = upsampled_color_and_weight(c, this_reactive);
    let instability = luma_instability(c, up.b, this_reactive, lock.luminance_diff);
    var acc = vec3<f32>(base_accumulation_weight(c, this_reactive, in_motion_last, up.color.w));

    if c.new_sample {
        hist = ycocg_to_rgb(up.color.xyz);
    } else {
        // RectifyHistory.
        let df = downscale_factor();
        let influence = min(20.0, pow(1.0 / abs(df.x * df.y), 3.0));
        let velocity_factor = saturate(c.hr_velocity / 20.0);
        let t = max(c.depth_clip, max(c.accumulation_mask, velocity_factor));
        let box_scale = mix(influence, 1.0, t);
        let scaled = up.b.vec * box_scale;
        let lo = max(up.b.lo, up.b.centre - scaled);
        let hi = min(up.b.hi, up.b.centre + scaled);
        if any(lo > hist) || any(hist > hi) {
            let clamped = clamp(hist, lo, hi);
            var contribution = max(instability, lock.contribution);
            contribution *= 1.0 - pow(c.dilated_reactive, 1.0 / 2.0);
            hist = mix(clamped, hist, saturate(contribution));
            acc = mix(min(acc, vec3<f32>(0.1)), acc, saturate(contribution));
        }
        // Accumulate (HDR: the blend in tonemapped RGB).
        acc = max(vec3<f32>(FSR2_EPSILON), acc + up.color.w);
        let up_t = rgb_to_ycocg(tonemap(ycocg_to_rgb(up.color.xyz)));
        let hist_t = rgb_to_ycocg(tonemap(ycocg_to_rgb(hist)));
        let alpha = vec3<f32>(up.color.w) / acc;
        hist = inverse_tonemap(ycocg_to_rgb(mix(hist_t, up_t, alpha)));
    }
    // UnprepareRgb (pre-exposure 1).
    hist = hist / exposure();

    // FinalizeLockStatus.
    if !is_uv_inside(c.hr_uv - c.motion) {
        lock_status.x = 0.0;
    } else {
        let decrease_max = params.jitter.w * AVERAGE_LANCZOS_WEIGHT_PER_FRAME;
        lock_status.x = max(0.0, lock_status.x - up.color.w / decrease_max);
    }
    textureStore(lock_status_out, c.hr, vec4<f32>(lock_status, 0.0, 0.0));

    let factor = temporal_reactive_factor(c, this_reactive);
    textureStore(color_out, c.hr, vec4<f32>(hist, factor));
    new_locks[lock_index] = 0.0;
}
