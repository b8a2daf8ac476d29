// `upscale` technique, pass `upscale`: one invocation per output pixel samples the reduced-resolution
// colour with the pass's sampler (bilinear or nearest) at the output pixel centre.

@group(0) @binding(0) var src: texture_2d<f32>;
@group(0) @binding(1) var src_sampler: sampler;
@group(0) @binding(2) var dst: texture_storage_2d<rgba16float, write>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(dst);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let uv = (vec2<f32>(id.xy) + 0.5) / vec2<f32>(size);
    textureStore(dst, id.xy, textureSampleLevel(src, src_sampler, uv, 0.0));
}
