// The converged ground-truth reference (`[reference] kind = "ground-truth"`, `samples = N`): the
// scene is rendered N times at the output resolution, each time with the projection offset by
// one point of a low-discrepancy sequence inside the pixel (harness/src/techniques/native/
// converged.rs); entry `accumulate` adds each render into a per-pixel f32 sum (a storage buffer:
// read-write storage textures of rgba32float are not portable), `resolve` writes the mean.

struct Params {
    // x, y: size; z: 1 on the first sample of the frame (the sum starts from it); w: samples.
    size: vec4<u32>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> sum: array<vec4<f32>>;
@group(0) @binding(2) var src: texture_2d<f32>;
@group(0) @binding(3) var dst: texture_storage_2d<rgba16float, write>;

@compute @workgroup_size(8, 8)
fn accumulate(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.size.x || id.y >= params.size.y {
        return;
    }
    let i = id.y * params.size.x + id.x;
    let c = textureLoad(src, vec2<i32>(id.xy), 0);
    if params.size.z == 1u {
        sum[i] = c;
    } else {
        sum[i] = sum[i] + c;
    }
}

@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.size.x || id.y >= params.size.y {
        return;
    }
    let i = id.y * params.size.x + id.x;
    textureStore(dst, id.xy, sum[i] / f32(params.size.w));
}
