// `fsr1` technique: AMD FidelityFX Super Resolution 1 as two compute passes, `easu` (edge-adaptive
// spatial upsampling, this file) then `rcas` (robust contrast-adaptive sharpening,
// `shared/rcas.wgsl`, which precedes this file in the module and declares the bindings, `encode`
// and `decode` used here), written from AMD's MIT reference `ffx_fsr1.h` as released in
// FidelityFX FSR v1.0.2 (GPUOpen-Effects/FidelityFX-FSR commit a21ffb8; sections "[EASU] EDGE
// ADAPTIVE SPATIAL UPSAMPLING", "NON-PACKED 32-BIT VERSION" of EASU, "[SRTM] SIMPLE REVERSIBLE
// TONE-MAPPER").
//
// Input contract (ffx_fsr1.h, EASU "Input image requirements"): 3 channels in [0, 1], encoded "as
// if presenting to sRGB display or similar (e.g. Gamma 2.0)", no noise below input pixel
// granularity; RCAS is undefined for negative input. The scene pass renders linear HDR radiance,
// so every tap EASU loads is first made finite and non-negative (NaN and negatives to 0, +Inf to
// the f16 maximum), tonemapped reversibly (SRTM: c / (max3(c) + 1), in [0, 1)), then gamma 2.0
// encoded (sqrt). RCAS works in that space and its output is decoded back to linear (square,
// SRTM inverse: c / (1 - max3(c))): the harness's output is linear. Without RCAS, EASU decodes.
//
// Differences from the reference, all deliberate (the CPU model in
// harness/src/techniques/fsr1/model.rs does the same):
// - taps are `textureLoad`s clamped to the edge instead of gather4 with a clamping sampler (the
//   same texels; gather is an optimisation);
// - AMD's approximate reciprocals (APrxLoRcpF1, APrxLoRsqF1, APrxMedRcpF1) are exact divisions
//   and `inverseSqrt`, with the zero cases the bit tricks leave finite made explicit: a zero
//   gradient gives a zero edge length, RCAS's limiters are 0 where their denominator is 0.
// - no FP16 path, no 8x8 remapping of invocations (one invocation per output pixel);
// - RCAS's filtered value is clamped to [0, 1] before the decode: v1.0.2's limiter keeps it there
//   in exact arithmetic, the clamp absorbs f32 rounding so `1 - max3` never reaches its floor.

fn load_src(p: vec2<i32>) -> vec3<f32> {
    let size = vec2<i32>(params.size.xy);
    return encode(textureLoad(src, clamp(p, vec2<i32>(0), size - 1), 0).rgb);
}

// "Luma times 2" of EASU and RCAS: b/2 + r/2 + g.
fn luma2(c: vec3<f32>) -> f32 {
    return c.b * 0.5 + (c.r * 0.5 + c.g);
}

// Edge length of one axis (FsrEasuSetF): the '+' differences around `c`; gradient reversal gives
// 0, a monotonic gradient 1, squared.
fn axis_length(a: f32, c: f32, e: f32) -> f32 {
    let m = max(abs(e - c), abs(c - a));
    let d = abs(e - a);
    var l = 0.0;
    if m > 0.0 {
        l = clamp(d / m, 0.0, 1.0);
    }
    return l * l;
}

// FsrEasuSetF: one of the four bilinear corners' direction and length, weighted by `w`.
//    a
//  b c d
//    e
struct DirLen {
    dir: vec2<f32>,
    len: f32,
}

fn easu_set(acc: DirLen, w: f32, a: f32, b: f32, c: f32, d: f32, e: f32) -> DirLen {
    return DirLen(
        acc.dir + vec2<f32>(d - b, e - a) * w,
        acc.len + (axis_length(b, c, d) + axis_length(a, c, e)) * w,
    );
}

// The kernel's shape at this position (FsrEasuF after the four FsrEasuSetF): normalised
// direction, anisotropic length (x along the edge, y across), negative lobe and clip point.
struct Kernel {
    dir: vec2<f32>,
    len2: vec2<f32>,
    lob: f32,
    clp: f32,
}

fn easu_kernel(acc: DirLen) -> Kernel {
    var dir = acc.dir;
    let dir_r2 = dot(dir, dir);
    // "Normalize with approximation, and cleanup close to zero."
    if dir_r2 < 1.0 / 32768.0 {
        dir = vec2<f32>(1.0, dir.y);
    } else {
        dir = dir * inverseSqrt(dir_r2);
    }
    // {0 to 2} to {0 to 1}, shaped with a square.
    var len = acc.len * 0.5;
    len = len * len;
    // 1 on horizontal or vertical edges, sqrt(2) on diagonals.
    let stretch = dot(dir, dir) / max(abs(dir.x), abs(dir.y));
    let len2 = vec2<f32>(1.0 + (stretch - 1.0) * len, 1.0 - 0.5 * len);
    let lob = 0.5 + ((1.0 / 4.0 - 0.04) - 0.5) * len;
    return Kernel(dir, len2, lob, 1.0 / lob);
}

// FsrEasuTapF: the weight of a tap at offset `off` from the resolve position: a windowed
// approximation of lanczos 2 on the rotated, anisotropically scaled distance.
fn easu_weight(off: vec2<f32>, k: Kernel) -> f32 {
    var v = vec2<f32>(off.x * k.dir.x + off.y * k.dir.y, off.x * -k.dir.y + off.y * k.dir.x);
    v = v * k.len2;
    let d2 = min(dot(v, v), k.clp);
    var wb = 2.0 / 5.0 * d2 - 1.0;
    var wa = k.lob * d2 - 1.0;
    wb = wb * wb;
    wa = wa * wa;
    wb = 25.0 / 16.0 * wb - (25.0 / 16.0 - 1.0);
    return wb * wa;
}

@compute @workgroup_size(8, 8)
fn easu(@builtin(global_invocation_id) id: vec3<u32>) {
    let out_size = params.size.zw;
    if id.x >= out_size.x || id.y >= out_size.y {
        return;
    }
    let in_size = vec2<f32>(params.size.xy);
    // Output pixel centre in input pixel coordinates (texel centres at integers): FsrEasuCon's
    // con0, "output integer position to a pixel position in viewport".
    let scale = in_size / vec2<f32>(out_size);
    var pp = vec2<f32>(id.xy) * scale + (0.5 * scale - 0.5);
    let fp = floor(pp);
    pp = pp - fp;
    let f0 = vec2<i32>(fp);
    // The 12-tap kernel around the 2x2 quad f g / j k:
    //    b c
    //  e f g h
    //  i j k l
    //    n o
    let b = load_src(f0 + vec2<i32>(0, -1));
    let c = load_src(f0 + vec2<i32>(1, -1));
    let e = load_src(f0 + vec2<i32>(-1, 0));
    let f = load_src(f0);
    let g = load_src(f0 + vec2<i32>(1, 0));
    let h = load_src(f0 + vec2<i32>(2, 0));
    let i = load_src(f0 + vec2<i32>(-1, 1));
    let j = load_src(f0 + vec2<i32>(0, 1));
    let k = load_src(f0 + vec2<i32>(1, 1));
    let l = load_src(f0 + vec2<i32>(2, 1));
    let n = load_src(f0 + vec2<i32>(0, 2));
    let o = load_src(f0 + vec2<i32>(1, 2));
    let bL = luma2(b);
    let cL = luma2(c);
    let eL = luma2(e);
    let fL = luma2(f);
    let gL = luma2(g);
    let hL = luma2(h);
    let iL = luma2(i);
    let jL = luma2(j);
    let kL = luma2(k);
    let lL = luma2(l);
    let nL = luma2(n);
    let oL = luma2(o);
    // Direction and length at the four corners f, g, j, k, bilinearly weighted (s t / u v).
    var acc = DirLen(vec2<f32>(0.0), 0.0);
    acc = easu_set(acc, (1.0 - pp.x) * (1.0 - pp.y), bL, eL, fL, gL, jL);
    acc = easu_set(acc, pp.x * (1.0 - pp.y), cL, fL, gL, hL, kL);
    acc = easu_set(acc, (1.0 - pp.x) * pp.y, fL, iL, jL, kL, nL);
    acc = easu_set(acc, pp.x * pp.y, gL, jL, kL, lL, oL);
    let kern = easu_kernel(acc);
    // Weighted sum of the 12 taps, offsets from the resolve position.
    var sum = vec3<f32>(0.0);
    var wsum = 0.0;
    var w: f32;
    w = easu_weight(vec2<f32>(0.0, -1.0) - pp, kern); sum += b * w; wsum += w;
    w = easu_weight(vec2<f32>(1.0, -1.0) - pp, kern); sum += c * w; wsum += w;
    w = easu_weight(vec2<f32>(-1.0, 1.0) - pp, kern); sum += i * w; wsum += w;
    w = easu_weight(vec2<f32>(0.0, 1.0) - pp, kern); sum += j * w; wsum += w;
    w = easu_weight(vec2<f32>(0.0, 0.0) - pp, kern); sum += f * w; wsum += w;
    w = easu_weight(vec2<f32>(-1.0, 0.0) - pp, kern); sum += e * w; wsum += w;
    w = easu_weight(vec2<f32>(1.0, 1.0) - pp, kern); sum += k * w; wsum += w;
    w = easu_weight(vec2<f32>(2.0, 1.0) - pp, kern); sum += l * w; wsum += w;
    w = easu_weight(vec2<f32>(2.0, 0.0) - pp, kern); sum += h * w; wsum += w;
    w = easu_weight(vec2<f32>(1.0, 0.0) - pp, kern); sum += g * w; wsum += w;
    w = easu_weight(vec2<f32>(1.0, 2.0) - pp, kern); sum += o * w; wsum += w;
    w = easu_weight(vec2<f32>(0.0, 2.0) - pp, kern); sum += n * w; wsum += w;
    // "Normalize and dering": limited to the min/max of the nearest 2x2 (f g j k).
    let lo = min(min(f, g), min(j, k));
    let hi = max(max(f, g), max(j, k));
    let pix = min(hi, max(lo, sum / wsum));
    if params.rcas.y > 0.5 {
        textureStore(dst, id.xy, vec4<f32>(pix, 1.0));
    } else {
        textureStore(dst, id.xy, vec4<f32>(decode(pix), 1.0));
    }
}

