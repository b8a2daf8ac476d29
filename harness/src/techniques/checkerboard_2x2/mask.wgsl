// `checkerboard-2x2`: the two pre-conditioned depth buffers, drawn once when the variant is built
// (seeds/depth-based-checkerboarding.txt 5.3.2 and 5.3.6: "depth creation is moved to application
// startup ... two persistent standby depth targets are maintained, used as a copy source").
//
// After a clear to the far value, depth compare Always writes, per 2x2 block (bx, by), the nearest
// depth where the block is masked; free blocks keep the clear value. Depth is reversed-Z here
// (near = 1, cleared to 0, compared with Greater), so the report's "depth output of zero" (nearest
// in standard depth) becomes 1.0: a scene fragment can never be Greater than 1.0 and is rejected by
// the early depth test in masked blocks. The scene shader itself writes no `frag_depth`, so early-Z
// stays on (../shared/notes/techniques.md 1c, "wgpu mapping").
//
// "White" (`free_parity = 0`) leaves the blocks with (bx + by) even free: the scene pass of even
// frames and the motion pass of odd frames start from it. "Black" (`free_parity = 1`) is the
// inverse.

// The mask as geometry (drawn once for `precondition = "copy"`'s standby buffers, each frame for
// `draw`): two triangles per masked 2x2 block at depth 1.0 (the nearest, from the vertex: no
// `frag_depth`, no fragment stage), free blocks degenerate. A full-screen `frag_depth` pass measured 0.302 ms at 1920x1080 on an H200
// against 0.154 ms for the copy (per-pixel depth output loses the depth buffer's compression);
// rasterised depth keeps it. The triangles' edges lie on even pixel coordinates, so each block
// covers exactly its four pixel centres.
override width: f32;
override height: f32;
override blocks_x: u32;
override free_parity: u32;

@vertex
fn vs_blocks(@builtin(vertex_index) v: u32) -> @builtin(position) vec4<f32> {
    let b = v / 6u;
    let bx = b % blocks_x;
    let by = b / blocks_x;
    if ((bx + by) & 1u) == free_parity {
        return vec4<f32>(0.0, 0.0, 0.0, 1.0);
    }
    // Corners of the two triangles: (0,0) (1,0) (0,1), (1,0) (1,1) (0,1).
    let c = v % 6u;
    let ox = select(0u, 1u, c == 1u || c == 3u || c == 4u);
    let oy = select(0u, 1u, c == 2u || c == 4u || c == 5u);
    let px = f32((bx + ox) * 2u);
    let py = f32((by + oy) * 2u);
    return vec4<f32>(px / width * 2.0 - 1.0, 1.0 - py / height * 2.0, 1.0, 1.0);
}
