// A rendered frame (a float texture, linear RGB) into the two forms the metrics read: the 8-bit
// sRGB frame packed r | g << 8 | b << 16, encoded exactly as tessera-metrics' `encode_srgb8`
// (NaN to 0, clamp, IEC 61966-2-1, round) by counting the 255 thresholds from
// `port::srgb8_encode_thresholds` at or below each value, and the linear RGB as f32 (for
// HDR-FLIP, only when `with_hdr` is set). Alpha is dropped.

struct Params {
    width: u32,
    height: u32,
    with_hdr: u32,
    _p1: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var frame: texture_2d<f32>;
@group(0) @binding(2) var<storage, read> thresholds: array<f32, 256>;
@group(0) @binding(3) var<storage, read_write> ldr: array<u32>;
@group(0) @binding(4) var<storage, read_write> hdr: array<f32>;

fn encode(v: f32) -> u32 {
    // Binary search for the number of thresholds t[1..=255] with t <= v (NaN compares false).
    var lo = 0u;
    var hi = 255u;
    while (lo < hi) {
        let mid = (lo + hi + 1u) / 2u;
        if (thresholds[mid] <= v) {
            lo = mid;
        } else {
            hi = mid - 1u;
        }
    }
    return lo;
}

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= params.width || gid.y >= params.height) {
        return;
    }
    let c = textureLoad(frame, vec2<i32>(gid.xy), 0).rgb;
    let i = gid.y * params.width + gid.x;
    ldr[i] = encode(c.r) | (encode(c.g) << 8u) | (encode(c.b) << 16u);
    if (params.with_hdr == 0u) {
        return;
    }
    hdr[3u * i] = c.r;
    hdr[3u * i + 1u] = c.g;
    hdr[3u * i + 2u] = c.b;
}
