// `fsr2` pass `rcas`: AMD's FSR 2 RCAS pass over the accumulated colour, written from
// `ffx_fsr2_rcas_pass.glsl` and `ffx_fsr2_rcas.h` (`RCAS`, `CurrFilter`, `FsrRcasLoadF`) and the
// copy of FSR 1's `FsrRcasF` that FSR 2.2.1 ships (its own `ffx_fsr1.h`, section "NON-PACKED
// 32-BIT VERSION"). What makes it FSR 2's and not `techniques/shared/rcas.wgsl` (FSR 1's RCAS
// in a perceptual encoding, used by `fsr1` and `taau`):
// - it runs on the exposed linear colour (`PrepareRgb` per tap, pre-exposure 1, undone by
//   `UnprepareRgb` after), values above 1 included, with no encoding;
// - noise removal on (`FSR_RCAS_DENOISE 1` in ffx_fsr2_rcas.h);
// - the limiters bounded by the ring alone (FSR 1 v1.0's, as FSR 2.2.1's copy has them, not
//   v1.0.2's centre-bounded ones);
// - AMD's reciprocals: `ffxApproximateReciprocalMedium` where AMD uses it (so a flat region
//   comes out times 0.99685, as AMD's does), exact divisions where AMD calls `rcp`.
// Taps outside the image read 0, as D3D12 defines a load outside a resource (and Vulkan with
// robust image access): AMD's pass reads them at the image's edges. Differences from AMD's
// code: 8x8 invocations per workgroup with a bounds check, where AMD runs 64 per 16x16 tile
// (`ffxRemapForQuad`) and stores outside the image at sizes that are not whole tiles.

@group(0) @binding(1) var color: texture_2d<f32>;
// x: the exposure (AMD's `Exposure()`), y: the average log luma (not read here).
@group(0) @binding(2) var<storage, read> exposure_buf: vec2<f32>;
@group(0) @binding(3) var color_out: texture_storage_2d<rgba16float, write>;
// AMD's `cbRCAS.rcasConfig` as `FsrRcasCon` fills it: x the linear sharpness's f32 bits.
@group(0) @binding(4) var<uniform> rcas_config: vec4<u32>;

// FSR_RCAS_LIMIT: "the limit of providing unnatural results for sharpening".
const FSR_RCAS_LIMIT: f32 = 0.25 - 1.0 / 16.0;

fn exposure() -> f32 {
    return select(1.0, exposure_buf.x, params.mode.w != 0u);
}

// ffxApproximateReciprocalMedium: a bit-trick estimate refined by one Newton step.
fn approximate_reciprocal_medium(v: f32) -> f32 {
    let b = bitcast<f32>(0x7ef19fffu - bitcast<u32>(v));
    return b * (-b * v + 2.0);
}

// FsrRcasLoadF: the tap (0 outside the image), exposed.
fn rcas_load(p: vec2<i32>) -> vec3<f32> {
    var c = vec3<f32>(0.0);
    if is_on_screen(p, vec2<i32>(params.size.zw)) {
        c = textureLoad(color, p, 0).rgb;
    }
    return prepare_rgb(c, exposure());
}

fn max3(a: f32, b: f32, c: f32) -> f32 {
    return max(a, max(b, c));
}

fn min3(a: f32, b: f32, c: f32) -> f32 {
    return min(a, min(b, c));
}

// Luma times 2 (FsrRcasF).
fn luma2(c: vec3<f32>) -> f32 {
    return c.b * 0.5 + (c.r * 0.5 + c.g);
}

// CurrFilter: FsrRcasF on the 5-tap cross
//    b
//  d e f
//    h
// then UnprepareRgb.
@compute @workgroup_size(8, 8)
fn rcas(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= params.size.zw) {
        return;
    }
    let p = vec2<i32>(id.xy);
    let b = rcas_load(p + vec2<i32>(0, -1));
    let d = rcas_load(p + vec2<i32>(-1, 0));
    let e = rcas_load(p);
    let f = rcas_load(p + vec2<i32>(1, 0));
    let h = rcas_load(p + vec2<i32>(0, 1));
    let bl = luma2(b);
    let dl = luma2(d);
    let el = luma2(e);
    let fl = luma2(f);
    let hl = luma2(h);
    // Noise detection.
    var nz = 0.25 * bl + 0.25 * dl + 0.25 * fl + 0.25 * hl - el;
    let range = max3(max3(bl, dl, el), fl, hl) - min3(min3(bl, dl, el), fl, hl);
    nz = saturate(abs(nz) * approximate_reciprocal_medium(range));
    nz = -0.5 * nz + 1.0;
    // Min and max of the ring, per channel.
    let mn4 = min(min(b, min(d, f)), h);
    let mx4 = max(max(b, max(d, f)), h);
    // Limiters, with exact reciprocals (AMD: "these need to be high precision RCPs").
    let hit_min = mn4 * (1.0 / (4.0 * mx4));
    let hit_max = (1.0 - mx4) * (1.0 / (4.0 * mn4 - 4.0));
    let lobe_rgb = max(-hit_min, hit_max);
    var lobe = max(-FSR_RCAS_LIMIT, min(max3(lobe_rgb.r, lobe_rgb.g, lobe_rgb.b), 0.0))
        * bitcast<f32>(rcas_config.x);
    // Noise removal (FSR_RCAS_DENOISE).
    lobe *= nz;
    let rcp_l = approximate_reciprocal_medium(4.0 * lobe + 1.0);
    let pix = (lobe * b + lobe * d + lobe * h + lobe * f + e) * rcp_l;
    // UnprepareRgb (pre-exposure 1).
    textureStore(color_out, id.xy, vec4<f32>(pix / exposure(), 1.0));
}
