// Temporal difference error of one frame (tessera-metrics `temporal.rs`): over valid pixels and
// RGB, |(T - W(T_prev)) - (R - W(R_prev))| in 8-bit units, written as |(T - R) - W(T_prev -
// R_prev)| (the same in exact arithmetic; the warp is linear), so that a test that changes
// exactly as the reference gives exactly 0 in f32 too. W samples bilinearly at p - motion(p),
// pixel centres at i + 0.5, clamped to the edge. Per workgroup: the f32 sum and the u32 count.

struct Params {
    width: u32,
    height: u32,
    count: u32,
    groups_x: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> test_prev: array<u32>;
@group(0) @binding(2) var<storage, read> test: array<u32>;
@group(0) @binding(3) var<storage, read> ref_prev: array<u32>;
@group(0) @binding(4) var<storage, read> reference: array<u32>;
@group(0) @binding(5) var<storage, read> motion: array<vec2<f32>>;
@group(0) @binding(6) var<storage, read> valid: array<u32>;
@group(0) @binding(7) var<storage, read_write> partials: array<u32>;

var<workgroup> s_sum: array<f32, 256>;
var<workgroup> s_count: array<u32, 256>;

fn diff(i: u32) -> vec3<f32> {
    let t = test_prev[i];
    let r = ref_prev[i];
    return vec3<f32>(
        f32(i32(t & 0xffu) - i32(r & 0xffu)),
        f32(i32((t >> 8u) & 0xffu) - i32((r >> 8u) & 0xffu)),
        f32(i32((t >> 16u) & 0xffu) - i32((r >> 16u) & 0xffu)),
    );
}

@compute @workgroup_size(256)
fn main(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
) {
    let group = wg.x + wg.y * params.groups_x;
    let i = group * 256u + li;
    var sum = 0.0;
    var count = 0u;
    if (i < params.count && valid[i] != 0u) {
        let w = params.width;
        let m = motion[i];
        let x = f32(i % w) + 0.5 - m.x;
        let y = f32(i / w) + 0.5 - m.y;
        let fx = clamp(x - 0.5, 0.0, f32(w - 1u));
        let fy = clamp(y - 0.5, 0.0, f32(params.height - 1u));
        let x0 = u32(floor(fx));
        let y0 = u32(floor(fy));
        let x1 = min(x0 + 1u, w - 1u);
        let y1 = min(y0 + 1u, params.height - 1u);
        let ax = fx - f32(x0);
        let ay = fy - f32(y0);
        let top = diff(y0 * w + x0) * (1.0 - ax) + diff(y0 * w + x1) * ax;
        let bottom = diff(y1 * w + x0) * (1.0 - ax) + diff(y1 * w + x1) * ax;
        let warped = top * (1.0 - ay) + bottom * ay;
        let t = test[i];
        let r = reference[i];
        let now = vec3<f32>(
            f32(i32(t & 0xffu) - i32(r & 0xffu)),
            f32(i32((t >> 8u) & 0xffu) - i32((r >> 8u) & 0xffu)),
            f32(i32((t >> 16u) & 0xffu) - i32((r >> 16u) & 0xffu)),
        );
        let d = abs(now - warped);
        sum = d.x + d.y + d.z;
        count = 3u;
    }
    s_sum[li] = sum;
    s_count[li] = count;
    workgroupBarrier();
    for (var stride = 128u; stride > 0u; stride = stride >> 1u) {
        if (li < stride) {
            s_sum[li] += s_sum[li + stride];
            s_count[li] += s_count[li + stride];
        }
        workgroupBarrier();
    }
    if (li == 0u) {
        partials[2u * group] = bitcast<u32>(s_sum[0]);
        partials[2u * group + 1u] = s_count[0];
    }
}
