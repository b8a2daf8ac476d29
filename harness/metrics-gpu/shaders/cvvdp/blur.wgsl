// pyramid.rs `blur` (the phase uncertainty, torchvision's GaussianBlur with reflection): one
// direction of the separable Gaussian. The vertical pass also applies the masker's power,
// safe_pow(|v * 10^mask_c|, mask_q[c]) (metric.rs `mask`). A level too small to blur gets a
// one-tap kernel [1] (an exact copy).

struct Params {
    w: u32,
    h: u32,
    radius: u32,
    // 0: horizontal; 1: vertical and the masker's power.
    vertical: u32,
    kernel: array<vec4<f32>, 4>,
    mask_scale: f32,
    q: f32,
    q_eps: f32,
    _p0: f32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> src: array<f32>;
@group(0) @binding(2) var<storage, read_write> dst: array<f32>;

fn reflect_(index: i32, size: u32) -> u32 {
    if (index < 0) {
        return u32(-index);
    }
    if (index >= i32(size)) {
        return u32(2 * i32(size) - index - 2);
    }
    return u32(index);
}

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = params.w;
    if (id.x >= w || id.y >= params.h) {
        return;
    }
    let r = i32(params.radius);
    var sum = 0.0;
    for (var k = 0; k <= 2 * r; k++) {
        let weight = params.kernel[k >> 2u][k & 3];
        if (params.vertical == 0u) {
            sum += src[id.y * w + reflect_(i32(id.x) + k - r, w)] * weight;
        } else {
            sum += src[reflect_(i32(id.y) + k - r, params.h) * w + id.x] * weight;
        }
    }
    if (params.vertical != 0u) {
        sum = spow(abs(sum * params.mask_scale), params.q, params.q_eps);
    }
    dst[id.y * w + id.x] = sum;
}
