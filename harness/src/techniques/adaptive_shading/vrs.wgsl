// Adaptive shading's hardware path, appended to scene.wgsl: the forward pass drawn with a
// fragment-shading-rate attachment (VK_KHR_fragment_shading_rate). Compiled to SPIR-V by naga and
// run by a raw Vulkan pipeline (`harness/src/gpu/vrs.rs`), since wgpu has no VRS.
//
// Drawn twice in one render pass: a depth pre-pass (this vertex shader alone), then the shading
// draw with depth test EQUAL, so every covered pixel is shaded by its visible primitive only.
//
// The colour is `fs_main`'s: the same `shade`, so at 1x1 everywhere the image is native's. The
// hardware runs this fragment shader once per coarse pixel and primitive, and derivatives (the
// ground filter's footprint) span the coarse pixel, as the software path's `centre` sampling does.
//
// The second target is what the next frame's rate pass needs (section 5: the rates of frame N + 1
// come from frame N's output and motion): xy the screen motion in pixels from the previous frame
// to this one; z this fragment's own reversed-Z depth, so that the rate pass, reprojecting with
// this motion as the estimate of the next frame's (constant velocity), rejects tiles where the
// depth along the motion is not continuous; w = 1 where something is drawn.

// The position is invariant: the depth pre-pass and the shading draw (depth test EQUAL) run this
// vertex shader in two pipelines and must agree on every depth bit.
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

struct VrsTargets {
    @location(0) color: vec4<f32>,
    @location(1) motion: vec4<f32>,
}

@fragment
fn fs_vrs(in: VrsVs) -> VrsTargets {
    let color = shade(VsOut(in.clip, in.rel_pos, in.normal, in.local, in.object));
    let motion = screen_motion(in.current, in.previous, is_still(in.object));
    return VrsTargets(color, vec4<f32>(motion, in.clip.z, 1.0));
}
