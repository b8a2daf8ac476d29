// The first pass of a frame (metric.rs `predict_inner` + color.rs `transform`): each pixel of
// the test and reference frames to DKL (achromatic, red-green, yellow-violet) on the display,
// and for a video the temporal filters over the frame history: planes 0..5 are the sustained
// channels (test, reference per channel), 6 and 7 the achromatic transient ones. An image
// (`video == 0`) writes the six converted planes unfiltered.
// Prefixed by input_ldr.wgsl or input_hdr.wgsl (the decode), and common.wgsl.

struct Params {
    width: u32,
    height: u32,
    taps: u32,
    video: u32,
    // Rows of the linear RGB to DKL matrix (w unused).
    m0: vec4<f32>,
    m1: vec4<f32>,
    m2: vec4<f32>,
    // Linear input: exposure, lower clamp, peak, reflected ambient.
    linear: vec4<f32>,
    white: f32,
    _p0: f32,
    _p1: f32,
    _p2: f32,
}

// Tap j (oldest first): the array layer holding its frame, and each channel's weight
// (sustained achromatic, red-green, yellow-violet, transient): filters[channel][taps - 1 - j].
struct Taps {
    weights: array<vec4<f32>, 256>,
    layers: array<vec4<u32>, 64>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<uniform> taps: Taps;
@group(0) @binding(5) var<storage, read_write> p0: array<f32>;
@group(0) @binding(6) var<storage, read_write> p1: array<f32>;
@group(0) @binding(7) var<storage, read_write> p2: array<f32>;
@group(0) @binding(8) var<storage, read_write> p3: array<f32>;
@group(0) @binding(9) var<storage, read_write> p4: array<f32>;
@group(0) @binding(10) var<storage, read_write> p5: array<f32>;
@group(0) @binding(11) var<storage, read_write> p6: array<f32>;
@group(0) @binding(12) var<storage, read_write> p7: array<f32>;

fn dkl(l: vec3<f32>) -> vec3<f32> {
    let a = params.m0;
    let b = params.m1;
    let c = params.m2;
    return vec3<f32>(
        (l.x * a.x + l.y * a.y) + l.z * a.z,
        (l.x * b.x + l.y * b.y) + l.z * b.z,
        (l.x * c.x + l.y * c.y) + l.z * c.z,
    );
}

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= params.width || id.y >= params.height) {
        return;
    }
    let i = id.y * params.width + id.x;
    if (params.video == 0u) {
        let t = dkl(linear_test(id.x, id.y, 0u));
        let r = dkl(linear_reference(id.x, id.y, 0u));
        p0[i] = t.x;
        p1[i] = r.x;
        p2[i] = t.y;
        p3[i] = r.y;
        p4[i] = t.z;
        p5[i] = r.z;
        return;
    }
    var s0 = 0.0;
    var s1 = 0.0;
    var s2 = 0.0;
    var s3 = 0.0;
    var s4 = 0.0;
    var s5 = 0.0;
    var s6 = 0.0;
    var s7 = 0.0;
    for (var j = 0u; j < params.taps; j++) {
        let layer = taps.layers[j >> 2u][j & 3u];
        let w = taps.weights[j];
        let t = dkl(linear_test(id.x, id.y, layer));
        let r = dkl(linear_reference(id.x, id.y, layer));
        s0 += t.x * w.x;
        s1 += r.x * w.x;
        s2 += t.y * w.y;
        s3 += r.y * w.y;
        s4 += t.z * w.z;
        s5 += r.z * w.z;
        s6 += t.x * w.w;
        s7 += r.x * w.w;
    }
    p0[i] = s0;
    p1[i] = s1;
    p2[i] = s2;
    p3[i] = s3;
    p4[i] = s4;
    p5[i] = s5;
    p6[i] = s6;
    p7[i] = s7;
}
