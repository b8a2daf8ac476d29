// Adaptive shading's rate pass, entry point where one subgroup holds a whole tile (subgroups of
// at least 32 invocations: NVIDIA, AMD; appended to `rate.wgsl`; wgpu's WGSL front end takes
// subgroup builtins without an `enable subgroups;` directive, which it does not parse yet). Lumas
// move between threads by shuffles and the partial sums are reduced by subgroup operations: no
// workgroup memory, no barrier. Thread (x, h) is subgroup invocation 16h + x, so the pixel to the
// left is one invocation down and the one above the column sixteen. The sums are added in the
// subgroup's order, not the model's tree: they may differ from it by rounding (tests/adaptive.rs
// counts decisions that close as a tie).

@compute @workgroup_size(32)
fn main(
    @builtin(workgroup_id) tile: vec3<u32>,
    @builtin(subgroup_invocation_id) sid: u32,
) {
    let size = vec2<i32>(rp.size.xy);
    let x = sid % 16u;
    let h = sid / 16u;
    var s = vec4<f32>(0.0);
    var mn = vec2<f32>(1e30);
    var first = 0.0;
    var last = 0.0;
    for (var k = 0u; k < 8u; k = k + 1u) {
        let ly = h * 8u + k;
        let p = vec2<i32>(tile.xy * 16u + vec2<u32>(x, ly));
        let px = read_pixel(p);
        let left = subgroupShuffleUp(px.l, 1u);
        if all(p < size) {
            if x >= 1u {
                s.x = s.x + pair(px.l, left);
            }
            if k >= 1u {
                s.y = s.y + pair(px.l, last);
            }
            s.z = s.z + px.l;
        }
        if k == 0u {
            first = px.l;
        }
        last = px.l;
        mn = select(mn, min(mn, abs(px.m)), px.covered);
        s.w = s.w + px.disoccluded;
    }
    // The column's first pixel against the last of the column above (thread x, h - 1).
    let above = subgroupShuffleUp(last, 16u);
    if h >= 1u && all(vec2<i32>(tile.xy * 16u + vec2<u32>(x, h * 8u)) < size) {
        s.y = s.y + pair(first, above);
    }
    let total = subgroupAdd(s);
    let vmin = subgroupMin(mn);
    if sid == 0u {
        decide(vec2<i32>(tile.xy), total, vmin);
    }
}
