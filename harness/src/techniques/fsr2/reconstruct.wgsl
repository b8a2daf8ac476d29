// `fsr2` pass `reconstruct`: AMD's reconstruct and dilate pass
// (ffx_fsr2_reconstruct_dilated_velocity_and_previous_depth.h, ReconstructAndDilate; entry
// ffx_fsr2_reconstruct_previous_depth_pass.glsl), one invocation per render pixel: the nearest
// depth of the 3x3 neighbourhood and its motion (FindNearestDepth; motion at render resolution,
// FFX_FSR2_OPTION_LOW_RESOLUTION_MOTION_VECTORS 1), the current depth pushed to the previous
// frame's positions it reprojects to (ReconstructPrevDepth: an atomic max, reversed depth, into
// every bilinear tap of weight above 0.01), and the lock luma (ComputeLockInputLuma). The 9 loads
// are unrolled by hand (the spilling hazard of fixed-size private arrays).

@group(0) @binding(1) var depth_low: texture_depth_2d;
@group(0) @binding(2) var motion_in: texture_2d<f32>;
@group(0) @binding(3) var color_low: texture_2d<f32>;
@group(0) @binding(4) var<storage, read> exposure_buf: vec2<f32>;
@group(0) @binding(5) var dilated_depth_out: texture_storage_2d<r32float, write>;
@group(0) @binding(6) var dilated_motion_out: texture_storage_2d<rg32float, write>;
@group(0) @binding(7) var lock_luma_out: texture_storage_2d<r32float, write>;
@group(0) @binding(8) var<storage, read_write> reconstructed_depth: array<atomic<u32>>;

fn exposure() -> f32 {
    return select(1.0, exposure_buf.x, params.mode.w != 0u);
}

fn load_depth(p: vec2<i32>) -> f32 {
    // LoadInputDepth reads out of bounds as 0 (a null texel); off-screen taps are not chosen.
    let c = clamp(p, vec2<i32>(0), vec2<i32>(params.size.xy) - 1);
    return textureLoad(depth_low, c, 0);
}

struct Nearest {
    depth: f32,
    coord: vec2<i32>,
}

// One tap of FindNearestDepth (inverted depth: the largest is nearest).
fn nearer(n: Nearest, p: vec2<i32>, size: vec2<i32>) -> Nearest {
    if is_on_screen(p, size) {
        let d = load_depth(p);
        if d > n.depth {
            return Nearest(d, p);
        }
    }
    return n;
}

fn find_nearest_depth(p: vec2<i32>, size: vec2<i32>) -> Nearest {
    var n = Nearest(load_depth(p), p);
    // AMD's order: (+1, 0), (0, +1), (0, -1), (-1, 0), (-1, +1), (+1, +1), (-1, -1), (+1, -1).
    n = nearer(n, p + vec2<i32>(1, 0), size);
    n = nearer(n, p + vec2<i32>(0, 1), size);
    n = nearer(n, p + vec2<i32>(0, -1), size);
    n = nearer(n, p + vec2<i32>(-1, 0), size);
    n = nearer(n, p + vec2<i32>(-1, 1), size);
    n = nearer(n, p + vec2<i32>(1, 1), size);
    n = nearer(n, p + vec2<i32>(-1, -1), size);
    n = nearer(n, p + vec2<i32>(1, -1), size);
    return n;
}

fn store_reconstructed_depth(p: vec2<i32>, depth: f32) {
    let i = u32(p.y) * params.size.x + u32(p.x);
    atomicMax(&reconstructed_depth[i], bitcast<u32>(depth));
}

// ReconstructPrevDepth.
fn reconstruct_prev_depth(p: vec2<i32>, depth: f32, motion_in_uv: vec2<f32>, size: vec2<i32>) {
    let motion = motion_in_uv * f32(length(motion_in_uv * display_size()) > 0.1);
    let uv = (vec2<f32>(p) + 0.5) / vec2<f32>(size);
    let b = bilinear_data(uv + motion, render_size());
    for (var i = 0; i < 4; i++) {
        if b.weights[i] > RECONSTRUCTED_DEPTH_WEIGHT_THRESHOLD {
            let s = b.base + bilinear_offset(i);
            if is_on_screen(s, size) {
                store_reconstructed_depth(s, depth);
            }
        }
    }
}

// ComputeLockInputLuma (HDR input: tonemapped).
fn lock_input_luma(p: vec2<i32>) -> f32 {
    var rgb = max(vec3<f32>(0.0), textureLoad(color_low, p, 0).rgb);
    rgb = rgb * exposure();
    rgb = tonemap(rgb);
    return pow(rgb_to_perceived_luma(rgb), 1.0 / 6.0);
}

@compute @workgroup_size(8, 8)
fn reconstruct(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= params.size.xy) {
        return;
    }
    let p = vec2<i32>(id.xy);
    let size = vec2<i32>(params.size.xy);
    let n = find_nearest_depth(p, size);
    let motion = textureLoad(motion_in, n.coord, 0).xy;
    textureStore(dilated_depth_out, p, vec4<f32>(n.depth, 0.0, 0.0, 0.0));
    textureStore(dilated_motion_out, p, vec4<f32>(motion, 0.0, 0.0));
    reconstruct_prev_depth(p, n.depth, motion, size);
    textureStore(lock_luma_out, p, vec4<f32>(lock_input_luma(p), 0.0, 0.0, 0.0));
}
