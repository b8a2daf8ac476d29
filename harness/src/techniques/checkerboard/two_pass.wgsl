// Sample accessors of the checkerboard reconstruction for `sampling = "two-pass"`: every sample
// of both frames lives in one 4-layer array per kind, layer `parity * 2 + sample` (sample 0 at
// the standard (0.75, 0.75) position, sample 1 at (0.25, 0.25)), rendered with a jittered
// projection. One fetch per load, no branch. Prepended to checkerboard_resolve.wgsl.

@group(0) @binding(1) var colors: texture_2d_array<f32>;
@group(0) @binding(5) var depths: texture_depth_2d_array;

fn layer(prev: bool, sample: u32) -> i32 {
    let parity = select(params.mode.x, 1u - params.mode.x, prev);
    return i32(parity * 2u + sample);
}

fn load_color(prev: bool, p: vec2<i32>, sample: u32) -> vec4<f32> {
    return textureLoad(colors, p, layer(prev, sample), 0);
}

fn load_depth(prev: bool, p: vec2<i32>, sample: u32) -> f32 {
    return textureLoad(depths, p, layer(prev, sample), 0);
}
