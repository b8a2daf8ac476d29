// Adaptive shading's hardware path for textured materials, appended to scene.wgsl and
// shaders/material/material.wgsl (its material bindings, group 1, and `shade_material`): the
// entry points of the raw Vulkan pipelines that draw the scene's textured draws (`raw_pass.rs`,
// `raw_material.rs`) in the same passes as vrs.wgsl's untextured ones.
//
// Per pass, by alpha mode (glTF OPAQUE, MASK, BLEND):
//   - the motion pre-pass (`adaptive-shading`): `fs_vrs_material_motion` for opaque draws,
//     `fs_vrs_material_motion_mask` for alpha-tested ones (the alpha test at full rate, so the
//     depth the shading pass tests EQUAL against has the cut-outs); blended draws write no depth;
//   - the depth pre-pass of `native-vrs`: opaque draws with the vertex shader alone, alpha-tested
//     ones with `fs_vrs_material_depth_mask` (the alpha test, no colour);
//   - the shading pass, at the attachment's rates: `fs_vrs_material` for every class. Opaque and
//     alpha-tested draws test EQUAL against the pre-pass without depth writes; an alpha-tested draw
//     is not tested again there: the pre-pass did it per pixel, and a coarse fragment that
//     discarded would leave its pixels at the clear colour where the pre-pass kept the card.
//     Blended draws come last, back to front, depth test GREATER without writes, blended.
// At 1x1 everywhere the colour is native's: `fs_material` / `fs_material_alpha`'s shading (a
// MASK material's output alpha is 1 either way, a BLEND material's its base alpha).

// As vrs.wgsl's `VrsVs`, with the material's texture coordinates and tangent: the position is
// invariant, since the pre-pass and the shading draw run this vertex shader in different
// pipelines and must agree on every depth bit.
struct VrsMaterialVs {
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) rel_pos: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) local: vec3<f32>,
    @location(3) @interpolate(flat) object: u32,
    @location(4) uv: vec2<f32>,
    @location(5) tangent: vec4<f32>,
    @location(6) current: vec4<f32>,
    @location(7) previous: vec4<f32>,
}

@vertex
fn vs_vrs_material(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) tangent: vec4<f32>,
    @builtin(instance_index) object: u32,
) -> VrsMaterialVs {
    let v = material_transform(position, normal, uv, tangent, object);
    let previous = previous_clip(position, object, v.clip, is_still(object));
    return VrsMaterialVs(
        v.clip,
        v.rel_pos,
        v.normal,
        v.local,
        v.object,
        v.uv,
        v.tangent,
        v.clip,
        previous,
    );
}

@fragment
fn fs_vrs_material(in: VrsMaterialVs) -> @location(0) vec4<f32> {
    let g = uv_gradients(in.uv);
    let base = base_color(g);
    return shade_material(in.rel_pos, in.normal, in.local, in.object, in.tangent, g, base);
}

// The pre-pass's motion, as vrs.wgsl's `fs_vrs_motion` writes it.
fn vrs_material_motion(in: VrsMaterialVs) -> vec4<f32> {
    let motion = screen_motion(in.current, in.previous, is_still(in.object));
    return vec4<f32>(motion, in.previous.z / in.previous.w, 1.0);
}

@fragment
fn fs_vrs_material_motion(in: VrsMaterialVs) -> @location(0) vec4<f32> {
    return vrs_material_motion(in);
}

@fragment
fn fs_vrs_material_motion_mask(in: VrsMaterialVs) -> @location(0) vec4<f32> {
    let g = uv_gradients(in.uv);
    if alpha_discarded(base_color(g)) {
        discard;
    }
    return vrs_material_motion(in);
}

// `native-vrs`'s depth pre-pass of an alpha-tested draw: the alpha test, no colour (the pipeline
// writes none).
@fragment
fn fs_vrs_material_depth_mask(in: VrsMaterialVs) {
    let g = uv_gradients(in.uv);
    if alpha_discarded(base_color(g)) {
        discard;
    }
}
