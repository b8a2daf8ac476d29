// Adaptive shading's hardware path, appended to scene.wgsl: the forward pass drawn with a
// fragment-shading-rate attachment (VK_KHR_fragment_shading_rate). Compiled to SPIR-V by naga and
// run by raw Vulkan pipelines (`raw_pass.rs`), since wgpu has no VRS.
//
// The order of work is the paper's (seeds/nvidia-adaptive-shading.txt, section 5: the rate pass
// runs "right after a depth pre-pass", and section 5.2 binds the motion vectors that pass writes):
//   1. `fs_vrs_motion`: the depth pre-pass of `adaptive-shading`, writing this frame's depth and
//      motion (the G-buffer's motion of the software path: xy the screen motion in pixels from the
//      previous frame, z the surface's reversed-Z depth in the previous frame, w = 1);
//   2. the rate pass (rate.wgsl) reprojects the previous output with that motion;
//   3. `fs_vrs`: the shading draw at those rates, depth test EQUAL against the pre-pass, no depth
//      writes, so every covered pixel is shaded by its visible primitive only.
// `native-vrs` has no rate pass and needs no motion: its pre-pass is this vertex shader alone.
//
// The colour is `fs_main`'s: the same `shade`, so at 1x1 everywhere the image is native's. The
// hardware runs `fs_vrs` once per coarse pixel and primitive, and derivatives (the ground
// filter's footprint) span the coarse pixel, as the software path's `centre` sampling does.

// The position is invariant: the pre-pass and the shading draw (depth test EQUAL) run this vertex
// shader in different pipelines and must agree on every depth bit.
struct VrsVs {
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) rel_pos: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) local: vec3<f32>,
    @location(3) @interpolate(flat) object: u32,
    @location(4) current: vec4<f32>,
    @location(5) previous: vec4<f32>,
}

@vertex
fn vs_vrs(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @builtin(instance_index) object: u32,
) -> VrsVs {
    let v = transform(position, normal, object);
    let previous = previous_clip(position, object, v.clip, is_still(object));
    return VrsVs(v.clip, v.rel_pos, v.normal, v.local, v.object, v.clip, previous);
}

@fragment
fn fs_vrs(in: VrsVs) -> @location(0) vec4<f32> {
    return shade(VsOut(in.clip, in.rel_pos, in.normal, in.local, in.object));
}

// The pre-pass's motion, as the software path's G-buffer writes it (shade.wgsl, `GBufferMotion`).
// The target is not cleared: the rate pass reads it only where this frame's depth is not the
// clear value.
@fragment
fn fs_vrs_motion(in: VrsVs) -> @location(0) vec4<f32> {
    let motion = screen_motion(in.current, in.previous, is_still(in.object));
    return vec4<f32>(motion, in.previous.z / in.previous.w, 1.0);
}
