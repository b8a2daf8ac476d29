// 8-bit sRGB frames: one u32 per pixel (r | g << 8 | b << 16) in an R32Uint array layer; each
// code value's absolute luminance comes from the display's table (src/cvvdp/model.rs `Decode`),
// a 256-texel texture (texture reads take per-pixel indices without serialising, as uniform
// arrays would).

@group(0) @binding(2) var lut: texture_1d<f32>;
@group(0) @binding(3) var test_frames: texture_2d_array<u32>;
@group(0) @binding(4) var reference_frames: texture_2d_array<u32>;

fn code(c: u32) -> f32 {
    return textureLoad(lut, c, 0).x;
}

fn decode(t: texture_2d_array<u32>, x: u32, y: u32, layer: u32) -> vec3<f32> {
    let p = textureLoad(t, vec2<u32>(x, y), layer, 0).x;
    return vec3<f32>(code(p & 255u), code((p >> 8u) & 255u), code((p >> 16u) & 255u));
}

fn linear_test(x: u32, y: u32, layer: u32) -> vec3<f32> {
    return decode(test_frames, x, y, layer);
}

fn linear_reference(x: u32, y: u32, layer: u32) -> vec3<f32> {
    return decode(reference_frames, x, y, layer);
}
