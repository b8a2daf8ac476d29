// Ground-truth reference, pass `downsample`: box filter of an NxN supersampled render, one
// invocation per output pixel (N = the scenario's `reference.supersample`).

struct Params {
    factor: u32,
}

@group(0) @binding(0) var src: texture_2d<f32>;
@group(0) @binding(1) var dst: texture_storage_2d<rgba16float, write>;
@group(0) @binding(2) var<uniform> params: Params;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(dst);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let n = params.factor;
    var sum = vec4<f32>(0.0);
    for (var y = 0u; y < n; y = y + 1u) {
        for (var x = 0u; x < n; x = x + 1u) {
            sum = sum + textureLoad(src, id.xy * n + vec2<u32>(x, y), 0);
        }
    }
    textureStore(dst, id.xy, sum / f32(n * n));
}
