// `fsr2` pass `motion`: the motion vectors an engine hands FSR 2 (not one of AMD's passes; its
// input): per render pixel, where its content was last frame, in uv (AMD's convention:
// previous uv minus current uv, unjittered). Dynamic objects from the shared motion provider
// (render/velocity.rs: the dynamic objects at the render size, in the scene pass's jittered
// view, motion in display pixels), trusted where its depth equals the scene's; everything else
// from the sample's depth through the cameras. A still camera on a static object gives exactly 0.

@group(0) @binding(1) var depth_low: texture_depth_2d;
@group(0) @binding(2) var velocity: texture_2d<f32>;
@group(0) @binding(3) var velocity_depth: texture_depth_2d;
@group(0) @binding(4) var motion_out: texture_storage_2d<rg32float, write>;

// As `render/velocity.rs` MOTION_DEPTH_EPSILON.
const MOTION_DEPTH_EPSILON: f32 = 1e-4;

@compute @workgroup_size(8, 8)
fn motion(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= params.size.xy) {
        return;
    }
    let q = vec2<i32>(id.xy);
    let depth = textureLoad(depth_low, q, 0);
    let display = display_size();
    var m = vec2<f32>(0.0);
    var dynamic_here = false;
    if params.mode.y != 0u {
        let v = textureLoad(velocity, q, 0);
        let vd = textureLoad(velocity_depth, q, 0);
        if v.z > 0.5 && !(depth - vd > MOTION_DEPTH_EPSILON * max(depth, vd)) {
            dynamic_here = true;
            m = -v.xy / display;
        }
    }
    if !dynamic_here && params.mode.z == 0u {
        // The unjittered position of this sample, in display pixels.
        let pos = (vec2<f32>(q) + 0.5 - jitter()) / render_size() * display;
        let ndc = vec4<f32>(pos.x / display.x * 2.0 - 1.0, 1.0 - pos.y / display.y * 2.0, depth, 1.0);
        let prev = params.prev_from_cur * ndc;
        let prev_uv = vec2<f32>(prev.x / prev.w * 0.5 + 0.5, 0.5 - prev.y / prev.w * 0.5);
        m = prev_uv - pos / display;
    }
    textureStore(motion_out, q, vec4<f32>(m, 0.0, 0.0));
}
