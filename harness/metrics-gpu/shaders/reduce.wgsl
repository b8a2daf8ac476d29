// Sum and maximum of an f32 map, one pair per workgroup of 256 values (fixed tree order; the
// partials are summed on the CPU in f64, in workgroup order). NaN and negative values count as 0,
// as tessera-metrics' FLIP pooling counts them.

struct Params {
    count: u32,
    groups_x: u32,
    _p0: u32,
    _p1: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> values: array<f32>;
@group(0) @binding(2) var<storage, read_write> partials: array<f32>;

var<workgroup> s_sum: array<f32, 256>;
var<workgroup> s_max: array<f32, 256>;

@compute @workgroup_size(256)
fn main(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
) {
    let group = wg.x + wg.y * params.groups_x;
    let i = group * 256u + li;
    var v = 0.0;
    if (i < params.count) {
        let x = values[i];
        v = select(0.0, x, x > 0.0);
    }
    s_sum[li] = v;
    s_max[li] = v;
    workgroupBarrier();
    for (var stride = 128u; stride > 0u; stride = stride >> 1u) {
        if (li < stride) {
            s_sum[li] += s_sum[li + stride];
            s_max[li] = max(s_max[li], s_max[li + stride]);
        }
        workgroupBarrier();
    }
    if (li == 0u) {
        partials[2u * group] = s_sum[0];
        partials[2u * group + 1u] = s_max[0];
    }
}
