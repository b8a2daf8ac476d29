// `checkerboard-2x2`: the two pre-conditioned depth buffers, drawn once when the variant is built
// (seeds/depth-based-checkerboarding.txt 5.3.2 and 5.3.6: "depth creation is moved to application
// startup ... two persistent standby depth targets are maintained, used as a copy source").
//
// A full-screen triangle with depth compare Always writes, per 2x2 block (bx, by), the nearest
// depth where the block is masked and the clear value where it is free. Depth is reversed-Z here
// (near = 1, cleared to 0, compared with Greater), so the report's "depth output of zero" (nearest
// in standard depth) becomes 1.0: a scene fragment can never be Greater than 1.0 and is rejected by
// the early depth test in masked blocks. The scene shader itself writes no `frag_depth`, so early-Z
// stays on (../shared/notes/techniques.md 1c, "wgpu mapping").
//
// Each frame with `precondition = "draw"`; once at start-up for `copy`'s standby buffers (the
// default: on an H200 at 1920x1080 this pass takes 0.302 ms, the copy 0.154 ms; the same mask as
// two triangles per block at the nearest vertex depth took 2.17 ms, tiny triangles being slow).
//
// "White" (`fs_white`) leaves the blocks with (bx + by) even free: the scene pass of even frames
// and the motion pass of odd frames start from it. "Black" (`fs_black`) is the inverse.

@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

// Nearest depth (1.0) on blocks whose parity is not `free_parity`, the clear value (0.0) elsewhere.
fn mask_depth(pixel: vec2<f32>, free_parity: u32) -> f32 {
    let b = vec2<u32>(pixel) >> vec2<u32>(1u);
    return select(0.0, 1.0, ((b.x + b.y) & 1u) != free_parity);
}

@fragment
fn fs_white(@builtin(position) p: vec4<f32>) -> @builtin(frag_depth) f32 {
    return mask_depth(p.xy, 0u);
}

@fragment
fn fs_black(@builtin(position) p: vec4<f32>) -> @builtin(frag_depth) f32 {
    return mask_depth(p.xy, 1u);
}
