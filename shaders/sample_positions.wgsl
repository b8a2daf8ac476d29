// Probe of an adapter's 2x MSAA sample positions (checkerboard `msaa2x` relies on the standard
// ones, (0.75, 0.75) and (0.25, 0.25), origin top-left): a full-target triangle on a 1x1 2x
// target writes each sample's position within the pixel, interpolated per sample from a
// screen-space varying (../shared/notes/techniques.md section 3); a compute pass copies the two
// samples to a buffer.

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(linear, sample) pixel: vec2<f32>,
}

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> VsOut {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    let ndc = uv * 2.0 - 1.0;
    // Pixel coordinates of a 1x1 target, y down.
    return VsOut(vec4<f32>(ndc, 0.0, 1.0), vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5));
}

@fragment
fn fs_main(in: VsOut, @builtin(sample_index) s: u32) -> @location(0) vec4<f32> {
    return vec4<f32>(in.pixel, f32(s), 1.0);
}

@group(0) @binding(0) var samples: texture_multisampled_2d<f32>;
@group(0) @binding(1) var<storage, read_write> positions: array<vec4<f32>, 2>;

@compute @workgroup_size(1)
fn copy_samples() {
    positions[0] = textureLoad(samples, vec2<i32>(0, 0), 0);
    positions[1] = textureLoad(samples, vec2<i32>(0, 0), 1);
}
