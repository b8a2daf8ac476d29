// Pixel-wise sums of one 8-bit pair, one set of partials per workgroup of 256 pixels, every sum
// exact in u32 (summed on the CPU in u64): squared RGB differences (MSE, PSNR), the squared
// BT.601 luma difference in thousandths split so it stays exact (|D| = 512 h + l, D^2 = 2^18 h^2
// + 2^10 h l + l^2), the largest channel difference and the sum of absolute differences
// (flicker). Pixels are packed r | g << 8 | b << 16.

struct Params {
    count: u32,
    groups_x: u32,
    _p0: u32,
    _p1: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> a: array<u32>;
@group(0) @binding(2) var<storage, read> b: array<u32>;
// Six u32 per workgroup: sq_rgb, hh, hl, ll, max_abs, sum_abs.
@group(0) @binding(3) var<storage, read_write> partials: array<u32>;

var<workgroup> s_sq: array<u32, 256>;
var<workgroup> s_hh: array<u32, 256>;
var<workgroup> s_hl: array<u32, 256>;
var<workgroup> s_ll: array<u32, 256>;
var<workgroup> s_max: array<u32, 256>;
var<workgroup> s_abs: array<u32, 256>;

fn channel(p: u32, c: u32) -> i32 {
    return i32((p >> (8u * c)) & 0xffu);
}

@compute @workgroup_size(256)
fn main(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
) {
    let group = wg.x + wg.y * params.groups_x;
    let i = group * 256u + li;
    var sq = 0u;
    var hh = 0u;
    var hl = 0u;
    var ll = 0u;
    var mx = 0u;
    var ab = 0u;
    if (i < params.count) {
        let pa = a[i];
        let pb = b[i];
        let dr = channel(pa, 0u) - channel(pb, 0u);
        let dg = channel(pa, 1u) - channel(pb, 1u);
        let db = channel(pa, 2u) - channel(pb, 2u);
        sq = u32(dr * dr + dg * dg + db * db);
        let d = u32(abs(299 * dr + 587 * dg + 114 * db));
        let h = d >> 9u;
        let l = d & 511u;
        hh = h * h;
        hl = h * l;
        ll = l * l;
        mx = u32(max(abs(dr), max(abs(dg), abs(db))));
        ab = u32(abs(dr) + abs(dg) + abs(db));
    }
    s_sq[li] = sq;
    s_hh[li] = hh;
    s_hl[li] = hl;
    s_ll[li] = ll;
    s_max[li] = mx;
    s_abs[li] = ab;
    workgroupBarrier();
    for (var stride = 128u; stride > 0u; stride = stride >> 1u) {
        if (li < stride) {
            s_sq[li] += s_sq[li + stride];
            s_hh[li] += s_hh[li + stride];
            s_hl[li] += s_hl[li + stride];
            s_ll[li] += s_ll[li + stride];
            s_max[li] = max(s_max[li], s_max[li + stride]);
            s_abs[li] += s_abs[li + stride];
        }
        workgroupBarrier();
    }
    if (li == 0u) {
        let o = group * 6u;
        partials[o] = s_sq[0];
        partials[o + 1u] = s_hh[0];
        partials[o + 2u] = s_hl[0];
        partials[o + 3u] = s_ll[0];
        partials[o + 4u] = s_max[0];
        partials[o + 5u] = s_abs[0];
    }
}
