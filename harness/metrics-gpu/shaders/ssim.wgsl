// SSIM (Wang et al. 2004 settings, as tessera-metrics' `ssim`): one 16x16 tile of valid output
// pixels per workgroup, the 11x11 Gaussian window applied directly to a 26x26 tile in workgroup
// memory, and the tile's SSIM sum written as the workgroup's partial (summed on the CPU in f64,
// in workgroup order).
//
// Precision in f32: the moments are taken of values shifted by the window's centre sample
// (mu = c + E[x - c], var = E[(x - c)^2] - E[x - c]^2), and both SSIM factors are written as
// one minus a small term, `1 - (mu_x - mu_y)^2 / (mu_x^2 + mu_y^2 + C1)` and
// `1 - var(x - y) / (var_x + var_y + C2)` (the same functions, rearranged), so nothing large
// cancels. Channel 0..2 is R, G, B; channel 3 is BT.601 luma in thousandths (integers, exact in
// f32), with C1 and C2 scaled to match.

struct Params {
    width: u32,
    height: u32,
    channel: u32,
    groups_x: u32,
    c1: f32,
    c2: f32,
    _p0: u32,
    _p1: u32,
    // The 11 window weights.
    w: array<vec4<f32>, 3>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> a: array<u32>;
@group(0) @binding(2) var<storage, read> b: array<u32>;
@group(0) @binding(3) var<storage, read_write> partials: array<f32>;

const TILE: u32 = 26u;
var<workgroup> ta: array<f32, 676>;
var<workgroup> tb: array<f32, 676>;
var<workgroup> red: array<f32, 256>;

fn value(p: u32) -> f32 {
    let r = f32(p & 0xffu);
    let g = f32((p >> 8u) & 0xffu);
    let bl = f32((p >> 16u) & 0xffu);
    switch params.channel {
        case 0u: { return r; }
        case 1u: { return g; }
        case 2u: { return bl; }
        default: { return 299.0 * r + 587.0 * g + 114.0 * bl; }
    }
}

fn weight(i: u32) -> f32 {
    return params.w[i / 4u][i % 4u];
}

@compute @workgroup_size(16, 16)
fn main(
    @builtin(local_invocation_id) lid: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
) {
    let out_w = params.width - 10u;
    let out_h = params.height - 10u;
    let base = wg.xy * 16u;
    for (var k = li; k < TILE * TILE; k += 256u) {
        let x = min(base.x + k % TILE, params.width - 1u);
        let y = min(base.y + k / TILE, params.height - 1u);
        let idx = y * params.width + x;
        ta[k] = value(a[idx]);
        tb[k] = value(b[idx]);
    }
    workgroupBarrier();
    var s = 0.0;
    let o = base + lid.xy;
    if (o.x < out_w && o.y < out_h) {
        let centre = (lid.y + 5u) * TILE + lid.x + 5u;
        let ca = ta[centre];
        let cb = tb[centre];
        var ma = 0.0;
        var mb = 0.0;
        var maa = 0.0;
        var mbb = 0.0;
        var mdd = 0.0;
        for (var i = 0u; i < 11u; i++) {
            // Vertical sums of column i, then weighted across (as the CPU: rows, then columns).
            var ra = 0.0;
            var rb = 0.0;
            var raa = 0.0;
            var rbb = 0.0;
            var rdd = 0.0;
            for (var j = 0u; j < 11u; j++) {
                let t = (lid.y + j) * TILE + lid.x + i;
                let wj = weight(j);
                let da = ta[t] - ca;
                let db = tb[t] - cb;
                let dd = da - db;
                ra += wj * da;
                rb += wj * db;
                raa += wj * (da * da);
                rbb += wj * (db * db);
                rdd += wj * (dd * dd);
            }
            let wi = weight(i);
            ma += wi * ra;
            mb += wi * rb;
            maa += wi * raa;
            mbb += wi * rbb;
            mdd += wi * rdd;
        }
        let ux = ca + ma;
        let uy = cb + mb;
        let du = (ca - cb) + (ma - mb);
        let vx = maa - ma * ma;
        let vy = mbb - mb * mb;
        let dm = ma - mb;
        let vd = mdd - dm * dm;
        let lum = 1.0 - (du * du) / (ux * ux + uy * uy + params.c1);
        let cs = 1.0 - vd / (vx + vy + params.c2);
        s = lum * cs;
    }
    red[li] = s;
    workgroupBarrier();
    for (var stride = 128u; stride > 0u; stride = stride >> 1u) {
        if (li < stride) {
            red[li] += red[li + stride];
        }
        workgroupBarrier();
    }
    if (li == 0u) {
        partials[wg.x + wg.y * params.groups_x] = red[0];
    }
}
