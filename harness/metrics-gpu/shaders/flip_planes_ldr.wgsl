// FLIP planes of an 8-bit sRGB frame: decode through FLIP's 256-entry table, then YCxCz and the
// feature channel (tessera-metrics `flip/ldr.rs` `to_planes`).

struct Params {
    count: u32,
    groups_x: u32,
    _p0: u32,
    _p1: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> src: array<u32>;
@group(0) @binding(2) var<storage, read> table: array<f32, 256>;
@group(0) @binding(3) var<storage, read_write> planes: array<vec4<f32>>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.groups_x * 256u;
    if (i >= params.count) {
        return;
    }
    let p = src[i];
    let c = vec3<f32>(table[p & 0xffu], table[(p >> 8u) & 0xffu], table[(p >> 16u) & 0xffu]);
    planes[i] = planes_of(c);
}
