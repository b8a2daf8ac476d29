// One channel of the baseband (metric.rs `process_frame`, no masking there): the difference of
// test and reference contrast over the mean background, weighted by the CSF at the reference's
// mean; written over the test plane and pooled per workgroup as diff.wgsl pools.
// Prefixed by common.wgsl and csf.wgsl.

struct Params {
    w: u32,
    h: u32,
    partial: u32,
    groups_x: u32,
    beta: f32,
    beta_eps: f32,
    _p0: f32,
    _p1: f32,
    csf: Csf,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> g_test: array<f32>;
@group(0) @binding(2) var<storage, read> g_reference: array<f32>;
@group(0) @binding(3) var<storage, read> mean: array<f32>;
@group(0) @binding(4) var<storage, read_write> partials: array<f32>;

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
        let bt = mean[0];
        let br = mean[1];
        let ct = min(g_test[i] / bt, 1000.0) * 1.0;
        let cr = min(g_reference[i] / br, 1000.0) * 1.0;
        let s = sensitivity(params.csf, log10_(br));
        let d = abs(ct - cr) * s;
        g_test[i] = d;
        v = spow(d, params.beta, params.beta_eps);
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
