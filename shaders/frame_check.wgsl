// Checks of a rendered frame on the device (harness/src/render/frame_check.rs): its raw
// Rgba16Float bits, as copy_texture_to_buffer lays them out (rows padded to 256 bytes; per texel
// two u32 words, little-endian: R | G << 16, then B | A << 16).
//
// `non_finite`: counts the R, G and B values whose f16 exponent is all ones (NaN or +-Inf: what
// `f32::is_finite` says of the read-back values) and sets the pixel's bit in the mask. Bit tests,
// not float comparisons, so no compiler may assume the values finite.
// `compare`: counts the pixels whose R, G or B bits differ between two frames.
// Both add integers with atomics: the results do not depend on the order threads run in.

// One row band of the frame (a frame beyond the device's storage-binding limit is checked in
// bands): `frame` and `other` are bound from the band's first row.
struct Params {
    width: u32,
    // Rows of this band.
    height: u32,
    // u32 words per padded row.
    row_words: u32,
    // The band's first row in the frame (for the mask's pixel index).
    row0: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> frame: array<u32>;
// [0]: non-finite values, [1]: pixels that differ.
@group(0) @binding(2) var<storage, read_write> counters: array<atomic<u32>, 2>;
@group(0) @binding(3) var<storage, read_write> mask: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read> other: array<u32>;

fn bad(h: u32) -> u32 {
    return select(0u, 1u, (h & 0x7c00u) == 0x7c00u);
}

@compute @workgroup_size(16, 16)
fn non_finite(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= params.width || gid.y >= params.height) {
        return;
    }
    let base = gid.y * params.row_words + 2u * gid.x;
    let rg = frame[base];
    let ba = frame[base + 1u];
    let n = bad(rg & 0xffffu) + bad(rg >> 16u) + bad(ba & 0xffffu);
    if (n > 0u) {
        atomicAdd(&counters[0], n);
        let i = (params.row0 + gid.y) * params.width + gid.x;
        atomicOr(&mask[i / 32u], 1u << (i % 32u));
    }
}

@compute @workgroup_size(16, 16)
fn compare(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= params.width || gid.y >= params.height) {
        return;
    }
    let base = gid.y * params.row_words + 2u * gid.x;
    let same = frame[base] == other[base]
        && (frame[base + 1u] & 0xffffu) == (other[base + 1u] & 0xffffu);
    if (!same) {
        atomicAdd(&counters[1], 1u);
    }
}
