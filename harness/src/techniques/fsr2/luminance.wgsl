// `fsr2` passes `luminance_pyramid` and `auto_exposure`: AMD's compute luminance pyramid pass
// (ffx_fsr2_compute_luminance_pyramid.h, ComputeAutoExposure with ffx_spd.h's SpdDownsample)
// as a plain two-step reduction instead of SPD's single pass (SPD's last-workgroup atomic
// counter and its 12 mip stores are an optimisation; FSR 2 reads only two of its outputs):
// `luminance_pyramid` writes the shading-change mip (LumaMipLevelToUse 4: the render's log luma,
// log(max(1e-3, luma)), averaged over 32 x 32 render pixels; SpdLoadSourceImage), one 8x8
// workgroup per texel of it, each invocation summing 4x4 render pixels; `auto_exposure`
// averages that mip in one workgroup (SPD's 1x1 level) and stores the exposure (SpdStore at
// MipCount() - 1: temporal smoothing with rate 1 / s, ComputeAutoExposureFromLavg).
// Deviations (measured against AMD's compiled pass in tests/fsr2_amd.rs): SPD reads the colour
// at (p + 0.5 + Jitter()) / RenderSize() bilinearly, here each texel's own value (SPD then
// averages a 2x2 box of those, so both average the same region up to the sub-pixel shift; a
// mip texel moves by up to 0.17 in log luma at an edge or a one-pixel feature). The mip itself
// is AMD's otherwise: floor(size / 32) texels, each a whole 32 x 32 block, the last
// size % 32 columns and rows left out by both. The 1x1 level is not: AMD's is the mean over the
// 2^mips square from the origin (mips = floor(log2(max(w, h)))) with zero for every pixel off
// the image or, from 7 mips, outside level 5's floor(size / 64) texels (what its last workgroup
// reads beyond them), so a non-square or non-power-of-two image has part of it left out and
// part padded with zeros (log luma 0, luma 1); here it is the mean of the mip's whole blocks.
// At 426 x 240 AMD's average log luma is 0.37 above this one (its exposure 31% lower).

@group(0) @binding(1) var color_low: texture_2d<f32>;
@group(0) @binding(2) var luma_mip_out: texture_storage_2d<r32float, write>;
@group(0) @binding(3) var luma_mip_in: texture_2d<f32>;
// x: exposure, y: the smoothed average log luma (SPD_SetExposureBuffer).
@group(0) @binding(4) var<storage, read_write> exposure_buf: vec2<f32>;

const BLOCK: i32 = 32;

var<workgroup> block_sum: array<vec2<f32>, 64>;

// One workgroup per texel of the mip: each of its 64 invocations sums a 4x4 part of the 32x32
// block (log luma and count), then the workgroup adds the 64 parts.
@compute @workgroup_size(8, 8)
fn luminance_pyramid(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(local_invocation_id) local: vec3<u32>,
    @builtin(local_invocation_index) i: u32,
) {
    let size = vec2<i32>(params.size.xy);
    let base = vec2<i32>(group.xy) * BLOCK + vec2<i32>(local.xy) * 4;
    var part = vec2<f32>(0.0);
    for (var y = 0; y < 4; y++) {
        for (var x = 0; x < 4; x++) {
            let p = base + vec2<i32>(x, y);
            if all(p < size) {
                let rgb = textureLoad(color_low, p, 0).rgb;
                part += vec2<f32>(log(max(FSR2_EPSILON, rgb_to_luma(rgb))), 1.0);
            }
        }
    }
    block_sum[i] = part;
    workgroupBarrier();
    for (var stride = 32u; stride > 0u; stride >>= 1u) {
        if i < stride {
            block_sum[i] += block_sum[i + stride];
        }
        workgroupBarrier();
    }
    if i == 0u && all(group.xy < params.luma.xy) {
        let s = block_sum[0];
        textureStore(luma_mip_out, group.xy, vec4<f32>(s.x / max(s.y, 1.0), 0.0, 0.0, 0.0));
    }
}

var<workgroup> partial: array<f32, 64>;

// ComputeAutoExposureFromLavg.
fn auto_exposure_from_lavg(lavg_log: f32) -> f32 {
    let lavg = exp(lavg_log);
    let s = 100.0;
    let k = 12.5;
    let exposure_iso100 = log2((lavg * s) / k);
    let q = 0.65;
    let lmax = (78.0 / (q * s)) * pow(2.0, exposure_iso100);
    return 1.0 / lmax;
}

@compute @workgroup_size(64)
fn auto_exposure(@builtin(local_invocation_index) i: u32) {
    let dims = params.luma.xy;
    let count = dims.x * dims.y;
    var sum = 0.0;
    for (var t = i; t < count; t += 64u) {
        sum += textureLoad(luma_mip_in, vec2<u32>(t % dims.x, t / dims.x), 0).r;
    }
    partial[i] = sum;
    workgroupBarrier();
    for (var stride = 32u; stride > 0u; stride >>= 1u) {
        if i < stride {
            partial[i] += partial[i + stride];
        }
        workgroupBarrier();
    }
    if i == 0u {
        var result = partial[0] / f32(count);
        let prev = exposure_buf.y;
        if params.mode.x == 0u && prev < RESET_AUTO_EXPOSURE_AVERAGE_SMOOTHING {
            let rate = 1.0;
            result = prev + (result - prev) * (1.0 - exp(-params.jitter.z * rate));
        }
        exposure_buf = vec2<f32>(auto_exposure_from_lavg(result), result);
    }
}
