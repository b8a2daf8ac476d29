// One band of the distortion map (metric.rs `process_frame`): the channels' weighted
// differences pooled with beta_tch, over the band's gain.
// Prefixed by common.wgsl.

struct Params {
    w: u32,
    h: u32,
    channels: u32,
    _p0: u32,
    // Per channel: channel weight * integration (* baseband weight on the baseband).
    weights: vec4<f32>,
    beta_tch: f32,
    beta_tch_eps: f32,
    inv_beta_tch: f32,
    inv_beta_tch_eps: f32,
    gain: f32,
    _q0: f32,
    _q1: f32,
    _q2: f32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> d0: array<f32>;
@group(0) @binding(2) var<storage, read> d1: array<f32>;
@group(0) @binding(3) var<storage, read> d2: array<f32>;
@group(0) @binding(4) var<storage, read> d3: array<f32>;
@group(0) @binding(5) var<storage, read_write> band: array<f32>;

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= params.w || id.y >= params.h) {
        return;
    }
    let i = id.y * params.w + id.x;
    let b = params.beta_tch;
    let e = params.beta_tch_eps;
    var sum = 0.0;
    sum += spow(d0[i] * params.weights.x, b, e);
    sum += spow(d1[i] * params.weights.y, b, e);
    sum += spow(d2[i] * params.weights.z, b, e);
    if (params.channels > 3u) {
        sum += spow(d3[i] * params.weights.w, b, e);
    }
    band[i] = spow(sum, params.inv_beta_tch, params.inv_beta_tch_eps) / params.gain;
}
