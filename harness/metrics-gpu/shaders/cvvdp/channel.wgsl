// One channel of one band above the baseband (metric.rs `process_frame` and `mask`): the
// Laplacian layers of test and reference as contrast over the expanded (local) background,
// weighted by the CSF at the reference's background and the channel's gain; their mutual
// masker min(|test|, |reference|). The normalised contrasts replace the Gaussian levels.
// Prefixed by common.wgsl and csf.wgsl.

struct Params {
    w: u32,
    h: u32,
    // 1 for the first band, 2 for the others.
    gain: f32,
    // The channel's masking gain (1.45 for red-green).
    channel_gain: f32,
    csf: Csf,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> g_test: array<f32>;
@group(0) @binding(2) var<storage, read_write> g_reference: array<f32>;
@group(0) @binding(3) var<storage, read> e_test: array<f32>;
@group(0) @binding(4) var<storage, read> e_reference: array<f32>;
// The expanded achromatic sustained levels: the backgrounds of test and reference.
@group(0) @binding(5) var<storage, read> bg_test: array<f32>;
@group(0) @binding(6) var<storage, read> bg_reference: array<f32>;
@group(0) @binding(7) var<storage, read_write> mutual: array<f32>;

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= params.w || id.y >= params.h) {
        return;
    }
    let i = id.y * params.w + id.x;
    let bt = max(bg_test[i], 0.01);
    let br = max(bg_reference[i], 0.01);
    let ct = min((g_test[i] - e_test[i]) / bt, 1000.0) * params.gain;
    let cr = min((g_reference[i] - e_reference[i]) / br, 1000.0) * params.gain;
    let s = sensitivity(params.csf, log10_(br));
    let nt = ct * s * params.channel_gain;
    let nr = cr * s * params.channel_gain;
    g_test[i] = nt;
    g_reference[i] = nr;
    mutual[i] = min(abs(nt), abs(nr));
}
