// Sample accessors of the checkerboard reconstruction for `sampling = "two-pass"`: each frame's
// two samples per quarter-resolution pixel are two single-sample textures (sample 0 at the
// (0.75, 0.75) position, sample 1 at (0.25, 0.25)), rendered with a jittered projection.
// Prepended to checkerboard_resolve.wgsl.

@group(0) @binding(1) var cur_color0: texture_2d<f32>;
@group(0) @binding(2) var cur_color1: texture_2d<f32>;
@group(0) @binding(3) var prev_color0: texture_2d<f32>;
@group(0) @binding(4) var prev_color1: texture_2d<f32>;
@group(0) @binding(5) var cur_depth0: texture_depth_2d;
@group(0) @binding(6) var cur_depth1: texture_depth_2d;
@group(0) @binding(7) var prev_depth0: texture_depth_2d;
@group(0) @binding(8) var prev_depth1: texture_depth_2d;

fn load_color(prev: bool, p: vec2<i32>, sample: u32) -> vec4<f32> {
    if prev {
        if sample == 0u {
            return textureLoad(prev_color0, p, 0);
        }
        return textureLoad(prev_color1, p, 0);
    }
    if sample == 0u {
        return textureLoad(cur_color0, p, 0);
    }
    return textureLoad(cur_color1, p, 0);
}

fn load_depth(prev: bool, p: vec2<i32>, sample: u32) -> f32 {
    if prev {
        if sample == 0u {
            return textureLoad(prev_depth0, p, 0);
        }
        return textureLoad(prev_depth1, p, 0);
    }
    if sample == 0u {
        return textureLoad(cur_depth0, p, 0);
    }
    return textureLoad(cur_depth1, p, 0);
}
