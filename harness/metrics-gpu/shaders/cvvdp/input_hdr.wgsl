// Linear BT.709 frames (RGBA f32 array layers): value * white cd/m², then color.rs's linear
// display model: (v * exposure) clamped to [max(black, 0.005), peak], plus the reflected ambient.

@group(0) @binding(3) var test_frames: texture_2d_array<f32>;
@group(0) @binding(4) var reference_frames: texture_2d_array<f32>;

fn decode(t: texture_2d_array<f32>, x: u32, y: u32, layer: u32) -> vec3<f32> {
    let v = textureLoad(t, vec2<u32>(x, y), layer, 0).xyz * params.white;
    let e = params.linear;
    return clamp(v * e.x, vec3<f32>(e.y), vec3<f32>(e.z)) + e.w;
}

fn linear_test(x: u32, y: u32, layer: u32) -> vec3<f32> {
    return decode(test_frames, x, y, layer);
}

fn linear_reference(x: u32, y: u32, layer: u32) -> vec3<f32> {
    return decode(reference_frames, x, y, layer);
}
