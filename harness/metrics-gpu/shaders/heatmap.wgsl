// A FLIP error map through the magma colour map, packed r | g << 8 | b << 16 (tessera-metrics
// `flip_heatmap`: index `int(e * 255 + 0.5) % 256`, NaN as 0).

struct Params {
    count: u32,
    groups_x: u32,
    _p0: u32,
    _p1: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> error: array<f32>;
@group(0) @binding(2) var<storage, read> magma: array<u32, 256>;
@group(0) @binding(3) var<storage, read_write> image: array<u32>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.groups_x * 256u;
    if (i >= params.count) {
        return;
    }
    let e = error[i];
    var k = 0;
    // Finite values only (the CPU's `as i32` saturates; FLIP errors are in [0, 1]).
    if (e == e && abs(e) < 1.0e6) {
        k = i32(e * 255.0 + 0.5);
    }
    image[i] = magma[u32(((k % 256) + 256) % 256)];
}
