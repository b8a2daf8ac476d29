// Sample accessors of the checkerboard reconstruction for `sampling = "msaa2x"`: each frame's
// samples are the two samples of a 2x multisampled quarter-resolution target at the standard
// positions (sample 0 at (0.75, 0.75), sample 1 at (0.25, 0.25); checked per adapter).
// Prepended to checkerboard_resolve.wgsl.

@group(0) @binding(1) var cur_color: texture_multisampled_2d<f32>;
@group(0) @binding(3) var prev_color: texture_multisampled_2d<f32>;
@group(0) @binding(5) var cur_depth: texture_depth_multisampled_2d;
@group(0) @binding(7) var prev_depth: texture_depth_multisampled_2d;

fn load_color(prev: bool, p: vec2<i32>, sample: u32) -> vec4<f32> {
    if prev {
        return textureLoad(prev_color, p, i32(sample));
    }
    return textureLoad(cur_color, p, i32(sample));
}

fn load_depth(prev: bool, p: vec2<i32>, sample: u32) -> f32 {
    if prev {
        return textureLoad(prev_depth, p, i32(sample));
    }
    return textureLoad(cur_depth, p, i32(sample));
}
