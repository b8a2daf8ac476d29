// Fills the fragment-shading-rate attachment of adaptive shading's hardware path from the rate
// pass's per-tile codes, applying section 5.4's neighbour filter on the way where it is on
// (`filtered_code`, `rate_filter.wgsl`, appended to this module) and storing the codes it used
// (`rates`, for the readback): one pass instead of a filter pass and this one. CPU model, and the
// mapping in words: `harness/src/techniques/adaptive_shading/attachment.rs`.
//
// One thread per four attachment texels, packed little-endian into one u32 of a buffer that the
// raw Vulkan pass copies into the R8_UINT attachment image (wgpu has no such image usage); thread
// i also stores tile i's code.

struct Params {
    // x, y: tiles; z, w: attachment texels.
    size: vec4<u32>,
    // x, y: attachment texel size in pixels; z: 1 where the codes are filtered here.
    texel: vec4<u32>,
    // Attachment texel per rate code (log2(rx) | log2(ry) << 2), four per vector.
    table: array<vec4<u32>, 4>,
}

@group(0) @binding(0) var<uniform> p: Params;
// The rate pass's codes (before the filter where z says so).
@group(0) @binding(1) var rates_in: texture_2d<u32>;
@group(0) @binding(2) var<storage, read_write> texels: array<u32>;
// The codes the attachment is made of (filtered where z says so).
@group(0) @binding(3) var rates_out: texture_storage_2d<r32uint, write>;

const TILE: u32 = 16u;

// Tile t's code as the shading pass uses it.
fn code_at(t: vec2<i32>) -> u32 {
    if p.texel.z != 0u {
        return filtered_code(t, vec2<i32>(p.size.xy));
    }
    return textureLoad(rates_in, t, 0).r;
}

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
                c = code_at(vec2<i32>(vec2<u32>(tx, ty)));
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
    let tiles = p.size.x * p.size.y;
    if id.x < tiles {
        let t = vec2<i32>(vec2<u32>(id.x % p.size.x, id.x / p.size.x));
        textureStore(rates_out, t, vec4<u32>(code_at(t), 0u, 0u, 0u));
    }
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
