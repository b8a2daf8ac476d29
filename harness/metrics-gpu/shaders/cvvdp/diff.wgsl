// One channel's visible difference in one band above the baseband (metric.rs `mask`): the
// masked, soft-clamped difference of normalised test and reference contrast, written over the
// test plane; and its pooling, safe_pow(d, beta) summed per 16x16 workgroup (fixed tree order;
// the partials are summed on the CPU in f64, in workgroup order).
// Prefixed by common.wgsl.

struct Params {
    w: u32,
    h: u32,
    channels: u32,
    // First partial of this (band, channel) and workgroups per row.
    partial: u32,
    groups_x: u32,
    _p0: u32,
    _p1: u32,
    _p2: u32,
    // xcm[source * 4 + channel] for source 0..3.
    xcm: vec4<f32>,
    mask_p: f32,
    mask_p_eps: f32,
    max_d: f32,
    beta: f32,
    beta_eps: f32,
    _q0: f32,
    _q1: f32,
    _q2: f32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> n_test: array<f32>;
@group(0) @binding(2) var<storage, read> n_reference: array<f32>;
@group(0) @binding(3) var<storage, read> mask0: array<f32>;
@group(0) @binding(4) var<storage, read> mask1: array<f32>;
@group(0) @binding(5) var<storage, read> mask2: array<f32>;
@group(0) @binding(6) var<storage, read> mask3: array<f32>;
@group(0) @binding(7) var<storage, read_write> partials: array<f32>;

var<workgroup> s_sum: array<f32, 256>;

@compute @workgroup_size(16, 16)
fn main(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
) {
    var v = 0.0;
    if (id.x < params.w && id.y < params.h) {
        let i = id.y * params.w + id.x;
        var m = 0.0;
        m += mask0[i] * params.xcm.x;
        m += mask1[i] * params.xcm.y;
        m += mask2[i] * params.xcm.z;
        if (params.channels > 3u) {
            m += mask3[i] * params.xcm.w;
        }
        let diff = abs(n_test[i] - n_reference[i]);
        let d = spow(diff, params.mask_p, params.mask_p_eps) / (1.0 + m);
        let clamped = params.max_d * d / (params.max_d + d);
        n_test[i] = clamped;
        v = spow(clamped, params.beta, params.beta_eps);
    }
    s_sum[li] = v;
    workgroupBarrier();
    for (var stride = 128u; stride > 0u; stride = stride >> 1u) {
        if (li < stride) {
            s_sum[li] += s_sum[li + stride];
        }
        workgroupBarrier();
    }
    if (li == 0u) {
        partials[params.partial + wg.y * params.groups_x + wg.x] = s_sum[0];
    }
}
