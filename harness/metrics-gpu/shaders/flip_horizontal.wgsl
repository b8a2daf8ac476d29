// FLIP's horizontal filter pass of both images and the per-pixel combination (tessera-metrics
// `flip/ldr.rs` `horizontal_color`, `horizontal_feature`, `combine`): Hunt-adjusted HyAB^qc
// remapped, the edge and point feature difference, `colour^(1 - feature)`. `mode` 0 writes the
// error map, 1 keeps the per-pixel maximum (HDR-FLIP over exposures).

struct Params {
    width: u32,
    height: u32,
    rs: u32,
    rf: u32,
    mode: u32,
    cmax: f32,
    pccmax: f32,
    pt_over_pccmax: f32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> kernels: array<f32>;
@group(0) @binding(2) var<storage, read> colour_r: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> feature_r: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> colour_t: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> feature_t: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> error: array<f32>;

struct Filtered {
    lab: vec3<f32>,
    // dx, ddx, dy, ddy
    feat: vec4<f32>,
}

fn filtered(is_test: bool, x: u32, row: u32) -> Filtered {
    let ns = 2u * params.rs + 1u;
    let nf = 2u * params.rf + 1u;
    let last = i32(params.width) - 1;
    let base = row * params.width;
    var c = vec4<f32>(0.0);
    for (var k = 0u; k < ns; k++) {
        let xx = u32(clamp(i32(x) + i32(k) - i32(params.rs), 0, last));
        var v: vec4<f32>;
        if (is_test) {
            v = colour_t[base + xx];
        } else {
            v = colour_r[base + xx];
        }
        c.x += kernels[k] * v.x;
        c.y += kernels[ns + k] * v.y;
        c.z += kernels[2u * ns + k] * v.z;
        c.w += kernels[3u * ns + k] * v.w;
    }
    var f = vec4<f32>(0.0);
    let fo = 4u * ns;
    for (var k = 0u; k < nf; k++) {
        let xx = u32(clamp(i32(x) + i32(k) - i32(params.rf), 0, last));
        var v: vec4<f32>;
        if (is_test) {
            v = feature_t[base + xx];
        } else {
            v = feature_r[base + xx];
        }
        let wg = kernels[fo + k];
        let wd = kernels[fo + nf + k];
        let wdd = kernels[fo + 2u * nf + k];
        f.x += wd * v.x;
        f.y += wdd * v.x;
        f.z += wg * v.y;
        f.w += wg * v.z;
    }
    let xyz = ycxcz_to_xyz(c.x, c.y, c.z + c.w);
    return Filtered(clamped_rgb_to_hunt_lab(xyz_to_linear_rgb(xyz)), f);
}

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = gid.x;
    let row = gid.y;
    if (x >= params.width || row >= params.height) {
        return;
    }
    let r = filtered(false, x, row);
    let t = filtered(true, x, row);
    var cd = pow0(hyab(r.lab, t.lab), C_QC);
    if (cd < params.pccmax) {
        cd *= params.pt_over_pccmax;
    } else {
        cd = C_PT + ((cd - params.pccmax) / (params.cmax - params.pccmax)) * (1.0 - C_PT);
    }
    let edge_r = sqrt(r.feat.x * r.feat.x + r.feat.z * r.feat.z);
    let edge_t = sqrt(t.feat.x * t.feat.x + t.feat.z * t.feat.z);
    let point_r = sqrt(r.feat.y * r.feat.y + r.feat.w * r.feat.w);
    let point_t = sqrt(t.feat.y * t.feat.y + t.feat.w * t.feat.w);
    let fd = sqrt(C_NORMALIZATION * max(abs(edge_r - edge_t), abs(point_r - point_t)));
    let e = pow0(cd, 1.0 - fd);
    let i = row * params.width + x;
    if (params.mode == 0u) {
        error[i] = e;
    } else if (e > error[i]) {
        error[i] = e;
    }
}
