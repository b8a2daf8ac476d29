// The baseband's background (metric.rs `process_frame`): the mean of max(level, 0.01) over the
// whole achromatic sustained level, test and reference. One workgroup: each thread sums a
// strided share in order, then a fixed tree.

struct Params {
    count: u32,
    _p0: u32,
    _p1: u32,
    _p2: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> g_test: array<f32>;
@group(0) @binding(2) var<storage, read> g_reference: array<f32>;
@group(0) @binding(3) var<storage, read_write> mean: array<f32>;

var<workgroup> s_t: array<f32, 256>;
var<workgroup> s_r: array<f32, 256>;

@compute @workgroup_size(256)
fn main(@builtin(local_invocation_index) li: u32) {
    var t = 0.0;
    var r = 0.0;
    for (var i = li; i < params.count; i += 256u) {
        t += max(g_test[i], 0.01);
        r += max(g_reference[i], 0.01);
    }
    s_t[li] = t;
    s_r[li] = r;
    workgroupBarrier();
    for (var stride = 128u; stride > 0u; stride = stride >> 1u) {
        if (li < stride) {
            s_t[li] += s_t[li + stride];
            s_r[li] += s_r[li + stride];
        }
        workgroupBarrier();
    }
    if (li == 0u) {
        mean[0] = s_t[0] / f32(params.count);
        mean[1] = s_r[0] / f32(params.count);
    }
}
