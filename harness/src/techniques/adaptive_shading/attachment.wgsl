// Fills the fragment-shading-rate attachment of adaptive shading's hardware path from the rate
// pass's per-tile codes (after the neighbour filter). CPU model, and the mapping in words:
// `harness/src/techniques/adaptive_shading/attachment.rs`.
//
// One thread per four attachment texels, packed little-endian into one u32 of a buffer that the
// raw Vulkan pass copies into the R8_UINT attachment image (wgpu has no such image usage).

struct Params {
    // x, y: tiles; z, w: attachment texels.
    size: vec4<u32>,
    // x, y: attachment texel size in pixels.
    texel: vec4<u32>,
    // Attachment texel per rate code (log2(rx) | log2(ry) << 2), four per vector.
    table: array<vec4<u32>, 4>,
}

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var rates: texture_2d<u32>;
@group(0) @binding(2) var<storage, read_write> texels: array<u32>;

const TILE: u32 = 16u;

// The finest rate per axis of the tiles texel (ax, ay) overlaps (one tile when texel <= 16).
fn texel_at(ax: u32, ay: u32) -> u32 {
    let t0 = vec2<u32>(ax * p.texel.x / TILE, ay * p.texel.y / TILE);
    let t1 = max(
        min(
            vec2<u32>(((ax + 1u) * p.texel.x + TILE - 1u) / TILE, ((ay + 1u) * p.texel.y + TILE - 1u) / TILE),
            p.size.xy,
        ),
        t0 + vec2<u32>(1u),
    );
    var lx = 3u;
    var ly = 3u;
    for (var ty = t0.y; ty < t1.y; ty++) {
        for (var tx = t0.x; tx < t1.x; tx++) {
            var c = 0u;
            if tx < p.size.x && ty < p.size.y {
                c = textureLoad(rates, vec2<u32>(tx, ty), 0).r;
            }
            lx = min(lx, c & 3u);
            ly = min(ly, (c >> 2u) & 3u);
        }
    }
    let code = lx | (ly << 2u);
    return p.table[code / 4u][code % 4u];
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = p.size.z * p.size.w;
    let first = id.x * 4u;
    if first >= n {
        return;
    }
    var packed = 0u;
    for (var b = 0u; b < 4u; b++) {
        let i = first + b;
        if i < n {
            packed |= (texel_at(i % p.size.z, i / p.size.z) & 0xffu) << (8u * b);
        }
    }
    texels[id.x] = packed;
}
