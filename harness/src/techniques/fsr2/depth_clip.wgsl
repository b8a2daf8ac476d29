// `fsr2` pass `depth_clip`: AMD's depth clip pass (ffx_fsr2_depth_clip.h, DepthClip; entry
// ffx_fsr2_depth_clip_pass.glsl), one invocation per render pixel: the disocclusion factor
// from the reconstructed previous depth (ComputeDepthClip, EvaluateSurface), the prepared input
// colour (exposed, YCoCg; ComputePreparedInputColor) with that factor in alpha, and the
// dilated reactive masks (PreProcessReactiveMasks): no reactive or transparency-and-composition
// mask is given, so AMD's 3x3 mask loop leaves x = 0 and y = the motion divergence
// (ComputeMotionDivergence, ComputeTemporalMotionDivergence, ComputeDepthDivergence); its 9
// colour loads, which only matter under a mask, are left out. Masks are kept in f32 (AMD: R8G8
// unorm). Loops over fixed taps are unrolled by hand.

@group(0) @binding(1) var dilated_depth: texture_2d<f32>;
@group(0) @binding(2) var dilated_motion: texture_2d<f32>;
@group(0) @binding(3) var previous_dilated_motion: texture_2d<f32>;
@group(0) @binding(4) var motion_in: texture_2d<f32>;
@group(0) @binding(5) var color_low: texture_2d<f32>;
@group(0) @binding(6) var<storage, read> exposure_buf: vec2<f32>;
@group(0) @binding(7) var<storage, read> reconstructed_depth: array<u32>;
@group(0) @binding(8) var prepared_out: texture_storage_2d<rgba16float, write>;
@group(0) @binding(9) var reactive_out: texture_storage_2d<rg32float, write>;

fn exposure() -> f32 {
    return select(1.0, exposure_buf.x, params.mode.w != 0u);
}

fn rsize() -> vec2<i32> {
    return vec2<i32>(params.size.xy);
}

fn load_reconstructed_prev_depth(p: vec2<i32>) -> f32 {
    let c = clamp(p, vec2<i32>(0), rsize() - 1);
    return bitcast<f32>(reconstructed_depth[u32(c.y) * params.size.x + u32(c.x)]);
}

fn load_dilated_depth(p: vec2<i32>) -> f32 {
    return textureLoad(dilated_depth, clamp(p, vec2<i32>(0), rsize() - 1), 0).r;
}

fn load_input_motion(p: vec2<i32>) -> vec2<f32> {
    return textureLoad(motion_in, clamp(p, vec2<i32>(0), rsize() - 1), 0).xy;
}

// A linear sampler's read of the previous dilated motion (clamp to edge).
fn sample_previous_dilated_motion(uv: vec2<f32>) -> vec2<f32> {
    let b = bilinear_data(uv, render_size());
    var sum = vec2<f32>(0.0);
    for (var i = 0; i < 4; i++) {
        let c = clamp(b.base + bilinear_offset(i), vec2<i32>(0), rsize() - 1);
        sum += textureLoad(previous_dilated_motion, c, 0).xy * b.weights[i];
    }
    return sum;
}

// One tap of ComputeDepthClip; returns (weighted clip, weight).
fn depth_clip_tap(pos: vec2<i32>, weight: f32, current_depth: f32, current_view: f32) -> vec2<f32> {
    if !is_on_screen(pos, rsize()) || !(weight > RECONSTRUCTED_DEPTH_WEIGHT_THRESHOLD) {
        return vec2<f32>(0.0);
    }
    let prev_depth = load_reconstructed_prev_depth(pos);
    let prev_view = view_space_depth(prev_depth);
    let diff = current_view - prev_view;
    if !(diff > 0.0) {
        return vec2<f32>(0.0);
    }
    let plane_depth = min(prev_depth, current_depth);
    let centre = view_space_position(vec2<i32>(render_size() * 0.5), rsize(), plane_depth);
    let corner = view_space_position(vec2<i32>(0), rsize(), plane_depth);
    let half_viewport_width = length(render_size());
    let threshold = max(current_view, prev_view);
    let ksep = 1.37e-05;
    let kfov = length(corner) / length(centre);
    let required = ksep * kfov * half_viewport_width * threshold;
    let resolution_factor = saturate(length(render_size()) / length(vec2<f32>(1920.0, 1080.0)));
    let power = mix(1.0, 3.0, resolution_factor);
    return vec2<f32>(pow(saturate(required / diff), power) * weight, weight);
}

// ComputeDepthClip.
fn compute_depth_clip(uv: vec2<f32>, current_depth: f32) -> f32 {
    let current_view = view_space_depth(current_depth);
    let b = bilinear_data(uv, render_size());
    var acc = depth_clip_tap(b.base, b.weights.x, current_depth, current_view);
    acc += depth_clip_tap(b.base + vec2<i32>(1, 0), b.weights.y, current_depth, current_view);
    acc += depth_clip_tap(b.base + vec2<i32>(0, 1), b.weights.z, current_depth, current_view);
    acc += depth_clip_tap(b.base + vec2<i32>(1, 1), b.weights.w, current_depth, current_view);
    if acc.y > 0.0 {
        return saturate(1.0 - acc.x / acc.y);
    }
    return 0.0;
}

// EvaluateSurface: 0 on a steep slope of the reconstructed previous depth, else 1.
fn evaluate_surface(p: vec2<i32>) -> f32 {
    let d0 = view_space_depth(load_reconstructed_prev_depth(p + vec2<i32>(0, -1)));
    let d1 = view_space_depth(load_reconstructed_prev_depth(p));
    let d2 = view_space_depth(load_reconstructed_prev_depth(p + vec2<i32>(0, 1)));
    return 1.0 - f32(((d0 - d1) > (d1 * 0.01)) && ((d1 - d2) > (d2 * 0.01)));
}

// One neighbour of ComputeMotionDivergence: (max velocity so far, min convergence so far).
fn divergence_tap(acc: vec2<f32>, p: vec2<i32>, off: vec2<i32>, nucleus: vec2<f32>) -> vec2<f32> {
    let mv = load_input_motion(clamp_load(p, off, rsize()));
    var v = length(mv);
    let max_v = max(v, acc.x);
    v = max(v, max_v);
    return vec2<f32>(max_v, min(acc.y, dot(mv / v, nucleus / v)));
}

// ComputeMotionDivergence (3x3, unrolled).
fn motion_divergence(p: vec2<i32>) -> f32 {
    let nucleus = load_input_motion(p);
    var acc = vec2<f32>(length(nucleus), 1.0);
    if length(nucleus * render_size()) > 1e-2 {
        acc = divergence_tap(acc, p, vec2<i32>(-1, -1), nucleus);
        acc = divergence_tap(acc, p, vec2<i32>(0, -1), nucleus);
        acc = divergence_tap(acc, p, vec2<i32>(1, -1), nucleus);
        acc = divergence_tap(acc, p, vec2<i32>(-1, 0), nucleus);
        acc = divergence_tap(acc, p, vec2<i32>(0, 0), nucleus);
        acc = divergence_tap(acc, p, vec2<i32>(1, 0), nucleus);
        acc = divergence_tap(acc, p, vec2<i32>(-1, 1), nucleus);
        acc = divergence_tap(acc, p, vec2<i32>(0, 1), nucleus);
        acc = divergence_tap(acc, p, vec2<i32>(1, 1), nucleus);
    }
    return saturate(1.0 - acc.y) * saturate(acc.x / 0.01);
}

// ComputeDepthDivergence (view-space to meters factor 1).
fn depth_divergence(p: vec2<i32>) -> f32 {
    let max_dist = view_space_depth(0.0);
    var dmax = 0.0;
    var dmin = max_dist;
    var max_found = false;
    for (var y = -1; y < 2; y++) {
        for (var x = -1; x < 2; x++) {
            let s = p + vec2<i32>(x, y);
            let on = select(0.0, 1.0, is_on_screen(s, rsize()));
            let d = view_space_depth(load_dilated_depth(s)) * on;
            max_found = max_found || (max_dist == d);
            dmin = min(dmin, d);
            dmax = max(dmax, d);
        }
    }
    return (1.0 - dmin / dmax) * select(1.0, 0.0, max_found);
}

// ComputeTemporalMotionDivergence.
fn temporal_motion_divergence(p: vec2<i32>) -> f32 {
    let uv = (vec2<f32>(p) + 0.5) / render_size();
    let mv = textureLoad(dilated_motion, p, 0).xy;
    let reprojected = clamp_uv(uv + mv, render_size(), render_size());
    let prev_mv = sample_previous_dilated_motion(reprojected);
    let px = length(mv * display_size());
    if px > 1.0 {
        return mix(0.0, 1.0 - saturate(length(prev_mv) / length(mv)), saturate(pow(px / 20.0, 3.0)));
    }
    return 0.0;
}

@compute @workgroup_size(8, 8)
fn depth_clip(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= params.size.xy) {
        return;
    }
    let p = vec2<i32>(id.xy);
    let depth_uv = (vec2<f32>(p) + 0.5) / render_size();
    var mv = textureLoad(dilated_motion, p, 0).xy;
    // Discard tiny motion vectors.
    mv *= f32(length(mv * display_size()) > 0.01);
    let dilated_uv = depth_uv + mv;
    let clip = compute_depth_clip(dilated_uv, load_dilated_depth(p)) * evaluate_surface(p);
    let rgb = prepare_rgb(max(vec3<f32>(0.0), textureLoad(color_low, p, 0).rgb), exposure());
    textureStore(prepared_out, p, vec4<f32>(rgb_to_ycocg(rgb), clip));
    let divergence = motion_divergence(p);
    var temporal = 0.0;
    if params.mode.x == 0u {
        temporal = temporal_motion_divergence(p);
    }
    let difference = saturate(temporal - depth_divergence(p));
    textureStore(reactive_out, p, vec4<f32>(0.0, max(difference, divergence), 0.0, 0.0));
}
