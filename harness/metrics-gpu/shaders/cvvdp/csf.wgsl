// csf.rs `sensitivity`: castleCSF at one band and channel (the table the CPU interpolated at
// the band's frequency), linear in log luminance on the table's uniform axis, clamped.

struct Csf {
    table: array<vec4<f32>, 8>,
    // log10 of the first luminance, log10(last) - log10(first), the last index, correction
    // (10^(sensitivity_correction / 20)).
    axis: vec4<f32>,
}

fn csf_at(csf: Csf, i: u32) -> f32 {
    return csf.table[i >> 2u][i & 3u];
}

fn sensitivity(csf: Csf, log_l: f32) -> f32 {
    let last = csf.axis.z;
    let index = clamp((log_l - csf.axis.x) / csf.axis.y * last, 0.0, last);
    let lo = u32(index);
    let hi = min(lo + 1u, u32(last));
    let f = fract(index);
    return pow10(csf_at(csf, lo) * (1.0 - f) + csf_at(csf, hi) * f) * csf.axis.w;
}
