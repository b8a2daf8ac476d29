// `fsr2` pass `lock`: AMD's lock pass (ffx_fsr2_lock.h, ComputeLock; entry
// ffx_fsr2_lock_pass.glsl), one invocation per render pixel: a thin feature (a luma ridge whose
// similar neighbours cover no 2x2 corner of the 3x3; ComputeThinFeatureConfidence) sets a new
// lock at the display pixel its sample fell in; and the reconstructed previous depth of this
// pixel is cleared for the next frame (ClearResourcesForNextFrame: inverted depth, far = 0).
// The 8 neighbours and the 4 rejection masks are unrolled by hand.

@group(0) @binding(1) var lock_luma: texture_2d<f32>;
@group(0) @binding(2) var<storage, read_write> new_locks: array<f32>;
@group(0) @binding(3) var<storage, read_write> reconstructed_depth: array<u32>;

const SIMILAR_THRESHOLD: f32 = 1.05;

struct Ridge {
    mask: u32,
    lo: f32,
    hi: f32,
}

// One neighbour (bit `idx` of the 3x3, row-major) of ComputeThinFeatureConfidence.
fn ridge_tap(r: Ridge, p: vec2<i32>, off: vec2<i32>, idx: u32, nucleus: f32) -> Ridge {
    let s = clamp_load(p, off, vec2<i32>(params.size.xy));
    let l = textureLoad(lock_luma, s, 0).r;
    let difference = max(l, nucleus) / min(l, nucleus);
    if difference > 0.0 && difference < SIMILAR_THRESHOLD {
        return Ridge(r.mask | (1u << idx), r.lo, r.hi);
    }
    return Ridge(r.mask, min(r.lo, l), max(r.hi, l));
}

fn thin_feature(p: vec2<i32>) -> bool {
    let nucleus = textureLoad(lock_luma, p, 0).r;
    var r = Ridge(1u << 4u, FSR2_FLT_MAX, 0.0);
    r = ridge_tap(r, p, vec2<i32>(-1, -1), 0u, nucleus);
    r = ridge_tap(r, p, vec2<i32>(0, -1), 1u, nucleus);
    r = ridge_tap(r, p, vec2<i32>(1, -1), 2u, nucleus);
    r = ridge_tap(r, p, vec2<i32>(-1, 0), 3u, nucleus);
    r = ridge_tap(r, p, vec2<i32>(1, 0), 5u, nucleus);
    r = ridge_tap(r, p, vec2<i32>(-1, 1), 6u, nucleus);
    r = ridge_tap(r, p, vec2<i32>(0, 1), 7u, nucleus);
    r = ridge_tap(r, p, vec2<i32>(1, 1), 8u, nucleus);
    let is_ridge = nucleus > r.hi || nucleus < r.lo;
    if !is_ridge {
        return false;
    }
    // Upper left, upper right, lower left, lower right 2x2 corners.
    let m0 = (1u << 0u) | (1u << 1u) | (1u << 3u) | (1u << 4u);
    let m1 = (1u << 1u) | (1u << 2u) | (1u << 4u) | (1u << 5u);
    let m2 = (1u << 3u) | (1u << 4u) | (1u << 6u) | (1u << 7u);
    let m3 = (1u << 4u) | (1u << 5u) | (1u << 7u) | (1u << 8u);
    let any_corner = (r.mask & m0) == m0 || (r.mask & m1) == m1 || (r.mask & m2) == m2 || (r.mask & m3) == m3;
    return !any_corner;
}

@compute @workgroup_size(8, 8)
fn lock(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= params.size.xy) {
        return;
    }
    let p = vec2<i32>(id.xy);
    if thin_feature(p) {
        let hr = hr_pos_from_lr_pos(p);
        if is_on_screen(hr, vec2<i32>(params.size.zw)) {
            new_locks[u32(hr.y) * params.size.z + u32(hr.x)] = 1.0;
        }
    }
    reconstructed_depth[id.y * params.size.x + id.x] = 0u;
}
