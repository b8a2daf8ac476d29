// Adaptive shading's rate pass, entry point for any adapter (appended to `rate.wgsl`): lumas are
// exchanged through workgroup memory, the 32 partial sums reduced as a tree in the order the CPU
// model (model.rs) reduces them.

var<workgroup> lum: array<f32, 256>;
var<workgroup> sums: array<vec4<f32>, 32>;
var<workgroup> mins: array<vec2<f32>, 32>;

@compute @workgroup_size(16, 2)
fn main(
    @builtin(workgroup_id) tile: vec3<u32>,
    @builtin(local_invocation_id) lid: vec3<u32>,
    @builtin(local_invocation_index) i: u32,
) {
    let size = vec2<i32>(rp.size.xy);
    var s = vec4<f32>(0.0);
    var mn = vec2<f32>(1e30);
    var l: array<f32, 8>;
    for (var k = 0u; k < 8u; k = k + 1u) {
        let ly = lid.y * 8u + k;
        let px = read_pixel(vec2<i32>(tile.xy * 16u + vec2<u32>(lid.x, ly)));
        l[k] = px.l;
        mn = select(mn, min(mn, abs(px.m)), px.covered);
        s.w = s.w + px.disoccluded;
        lum[ly * 16u + lid.x] = l[k];
    }
    workgroupBarrier();
    for (var k = 0u; k < 8u; k = k + 1u) {
        let ly = lid.y * 8u + k;
        let p = vec2<i32>(tile.xy * 16u + vec2<u32>(lid.x, ly));
        if all(p < size) {
            let idx = ly * 16u + lid.x;
            if lid.x >= 1u {
                s.x = s.x + pair(l[k], lum[idx - 1u]);
            }
            if ly >= 1u {
                s.y = s.y + pair(l[k], lum[idx - 16u]);
            }
            s.z = s.z + l[k];
        }
    }
    sums[i] = s;
    mins[i] = mn;
    workgroupBarrier();
    for (var stride = 16u; stride > 0u; stride = stride / 2u) {
        if i < stride {
            sums[i] = sums[i] + sums[i + stride];
            mins[i] = min(mins[i], mins[i + stride]);
        }
        workgroupBarrier();
    }
    if i == 0u {
        decide(vec2<i32>(tile.xy), sums[0], mins[0]);
    }
}
