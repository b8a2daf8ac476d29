// pyramid.rs `reduce` (lpyr_dec.py gausspyr_reduce): the next Gaussian level, vertical then
// horizontal 5-tap filtering with the reference's end corrections, including the horizontal
// one that follows the *height*'s parity. The vertical value a horizontal tap needs is computed
// where it is needed, in the CPU's order.

struct Params {
    // Source size; the output is (ceil(w / 2), ceil(h / 2)).
    w: u32,
    h: u32,
    _p0: u32,
    _p1: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> src: array<f32>;
@group(0) @binding(2) var<storage, read_write> dst: array<f32>;

fn at(x: u32, y: u32) -> f32 {
    return src[y * params.w + x];
}

// The vertical pass's value at source column x, output row y.
fn vert(x: u32, y: u32) -> f32 {
    let h = params.h;
    let hv = (h + 1u) / 2u;
    let center = i32(2u * y);
    var sum = 0.0;
    for (var k = 0; k < 5; k++) {
        let pos = center + k - 2;
        if (pos >= 0 && pos < i32(h)) {
            sum += at(x, u32(pos)) * kernel(k);
        }
    }
    if (y == 0u) {
        sum += at(x, 0u) * K1 + at(x, 1u) * K0;
    }
    if (y == hv - 1u) {
        if (h % 2u == 1u) {
            sum += at(x, h - 1u) * K3 + at(x, h - 2u) * K4;
        } else {
            sum += at(x, h - 1u) * K4;
        }
    }
    return sum;
}

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = params.w;
    let wo = (w + 1u) / 2u;
    let ho = (params.h + 1u) / 2u;
    if (id.x >= wo || id.y >= ho) {
        return;
    }
    let y = id.y;
    let center = i32(2u * id.x);
    var sum = 0.0;
    for (var k = 0; k < 5; k++) {
        let pos = center + k - 2;
        if (pos >= 0 && pos < i32(w)) {
            sum += vert(u32(pos), y) * kernel(k);
        }
    }
    if (id.x == 0u) {
        sum += vert(0u, y) * K1 + vert(1u, y) * K0;
    }
    if (id.x == wo - 1u) {
        if (params.h % 2u == 1u) {
            sum += vert(w - 1u, y) * K3 + vert(w - 2u, y) * K4;
        } else {
            sum += vert(w - 1u, y) * K4;
        }
    }
    dst[id.y * wo + id.x] = sum;
}
