// pyramid.rs `expand` (lpyr_dec.py gausspyr_expand with interleave_zeros_and_pad): a level
// brought up to the size above, vertical then horizontal, taps weighted 2 K. With
// `accumulate`, the result is added to what dst holds (the distortion map's reconstruction,
// metric.rs `process_frame`: `larger += band`).

struct Params {
    // Source (smaller) and output sizes.
    ws: u32,
    hs: u32,
    w: u32,
    h: u32,
    accumulate: u32,
    _p0: u32,
    _p1: u32,
    _p2: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> src: array<f32>;
@group(0) @binding(2) var<storage, read_write> dst: array<f32>;

// interleaved_index: the source sample that padded, zero-interleaved position `index` holds,
// or -1 for a zero.
fn interleaved(index: u32, expanded: u32, original: u32) -> i32 {
    if (index == 0u) {
        return 0;
    }
    if (index == expanded + 2u + expanded % 2u) {
        return i32(original) - 1;
    }
    if (index >= 2u && index < expanded + 2u && index % 2u == 0u) {
        return i32((index - 2u) / 2u);
    }
    return -1;
}

fn vert(x: u32, y: u32) -> f32 {
    var sum = 0.0;
    for (var k = 0; k < 5; k++) {
        let pos = interleaved(y + u32(k), params.h, params.hs);
        if (pos >= 0) {
            sum += src[u32(pos) * params.ws + x] * (2.0 * kernel(k));
        }
    }
    return sum;
}

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= params.w || id.y >= params.h) {
        return;
    }
    var sum = 0.0;
    for (var k = 0; k < 5; k++) {
        let pos = interleaved(id.x + u32(k), params.w, params.ws);
        if (pos >= 0) {
            sum += vert(u32(pos), id.y) * (2.0 * kernel(k));
        }
    }
    let i = id.y * params.w + id.x;
    if (params.accumulate != 0u) {
        sum += dst[i];
    }
    dst[i] = sum;
}
