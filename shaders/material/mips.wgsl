// One mip level from the level above it: a box filter over the source texels the destination
// texel covers (2x2 for even sizes, up to 3x3 where a size is odd, so no texel is dropped).
//
// Run as a render pass into the destination level: for an sRGB texture `textureLoad` decodes to
// linear and the attachment encodes on write, so the average is taken in linear space (a gamma-
// space average darkens high-contrast detail at a distance). wgpu generates no mip levels.

@group(0) @binding(0) var src: texture_2d<f32>;

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs_main(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let dst = vec2<u32>(p.xy);
    let ss = textureDimensions(src);
    let ds = max(ss / 2u, vec2<u32>(1u));
    let lo = dst * ss / ds;
    let hi = min(((dst + 1u) * ss + ds - 1u) / ds, ss);
    var sum = vec4<f32>(0.0);
    for (var y = lo.y; y < hi.y; y = y + 1u) {
        for (var x = lo.x; x < hi.x; x = x + 1u) {
            sum = sum + textureLoad(src, vec2<u32>(x, y), 0);
        }
    }
    let n = f32((hi.x - lo.x) * (hi.y - lo.y));
    return sum / n;
}
