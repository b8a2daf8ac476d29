// The distortion map's last step (metric.rs `process_frame`): 1 - met2jod(q) / 10 per pixel
// (parameters.rs `jod`, with its linear segment below q = 0.1).

struct Params {
    count: u32,
    groups_x: u32,
    _p0: u32,
    _p1: u32,
    // jod_a * 0.1^(jod_exp - 1), jod_a, jod_exp.
    linear: f32,
    jod_a: f32,
    jod_exp: f32,
    _q0: f32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> map: array<f32>;

@compute @workgroup_size(256)
fn main(@builtin(local_invocation_index) li: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    let i = (wg.x + wg.y * params.groups_x) * 256u + li;
    if (i >= params.count) {
        return;
    }
    let q = map[i];
    var jod: f32;
    if (q <= 0.1) {
        jod = 10.0 - params.linear * q;
    } else {
        jod = 10.0 - params.jod_a * pow(q, params.jod_exp);
    }
    map[i] = 1.0 - jod / 10.0;
}
