// FLIP's vertical filter pass of one image (clamp-to-edge rows, taps in order, as
// tessera-metrics `flip/ldr.rs` `vertical_color` / `vertical_feature`): the CSF of Y, Cx and Cz
// (Cz with both of its Gaussians) and the Gaussian, first and second derivative of the feature
// channel.

struct Params {
    width: u32,
    height: u32,
    rs: u32,
    rf: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
// Kernels: y, cx, cz1, cz2 (2 rs + 1 taps each), then g, dg, ddg (2 rf + 1 taps each).
@group(0) @binding(1) var<storage, read> kernels: array<f32>;
@group(0) @binding(2) var<storage, read> planes: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> colour: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> feature: array<vec4<f32>>;

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = gid.x;
    let row = gid.y;
    if (x >= params.width || row >= params.height) {
        return;
    }
    let ns = 2u * params.rs + 1u;
    let nf = 2u * params.rf + 1u;
    let last = i32(params.height) - 1;
    var c = vec4<f32>(0.0);
    for (var k = 0u; k < ns; k++) {
        let yy = u32(clamp(i32(row) + i32(k) - i32(params.rs), 0, last));
        let p = planes[yy * params.width + x];
        c.x += kernels[k] * p.x;
        c.y += kernels[ns + k] * p.y;
        c.z += kernels[2u * ns + k] * p.z;
        c.w += kernels[3u * ns + k] * p.z;
    }
    var f = vec4<f32>(0.0);
    let fo = 4u * ns;
    for (var k = 0u; k < nf; k++) {
        let yy = u32(clamp(i32(row) + i32(k) - i32(params.rf), 0, last));
        let g = planes[yy * params.width + x].w;
        f.x += kernels[fo + k] * g;
        f.y += kernels[fo + nf + k] * g;
        f.z += kernels[fo + 2u * nf + k] * g;
    }
    let i = row * params.width + x;
    colour[i] = c;
    feature[i] = f;
}
