//! FLIP's colour spaces in f32, operation for operation as `FLIP.h` (flip-evaluator 1.7) writes
//! them: linear RGB <-> XYZ (D65), XYZ <-> YCxCz (FLIP's linearised CIELAB), XYZ -> CIELAB, the
//! Hunt adjustment and the HyAB distance.
//!
//! For: the per-pixel arithmetic of the colour pipeline. Not for: filtering (see `filters`),
//! or the sRGB curve (see the crate's `srgb` module).
//!
//! Literals are written exactly as `FLIP.h` writes them (some carry more digits than f32 holds;
//! they round to the same f32 values).
#![allow(clippy::excessive_precision)]

/// D65 reference white, Y = 1.
const ILLUMINANT: [f32; 3] = [0.950428545, 1.000000000, 1.088900371];
/// Its reciprocal as FLIP tabulates it.
const INV_ILLUMINANT: [f32; 3] = [1.052156925, 1.000000000, 0.918357670];

/// FLIP's colour-difference exponent, and the remap constants.
pub(crate) const QC: f32 = 0.7;
pub(crate) const PC: f32 = 0.4;
pub(crate) const PT: f32 = 0.95;

#[inline(always)]
pub(crate) fn linear_rgb_to_xyz(r: f32, g: f32, b: f32) -> [f32; 3] {
    let a11 = 10135552.0f32 / 24577794.0f32;
    let a12 = 8788810.0f32 / 24577794.0f32;
    let a13 = 4435075.0f32 / 24577794.0f32;
    let a21 = 2613072.0f32 / 12288897.0f32;
    let a22 = 8788810.0f32 / 12288897.0f32;
    let a23 = 887015.0f32 / 12288897.0f32;
    let a31 = 1425312.0f32 / 73733382.0f32;
    let a32 = 8788810.0f32 / 73733382.0f32;
    let a33 = 70074185.0f32 / 73733382.0f32;
    [
        a11 * r + a12 * g + a13 * b,
        a21 * r + a22 * g + a23 * b,
        a31 * r + a32 * g + a33 * b,
    ]
}

#[inline(always)]
pub(crate) fn xyz_to_linear_rgb(x: f32, y: f32, z: f32) -> [f32; 3] {
    let a11 = 3.241003275f32;
    let a12 = -1.537398934f32;
    let a13 = -0.498615861f32;
    let a21 = -0.969224334f32;
    let a22 = 1.875930071f32;
    let a23 = 0.041554224f32;
    let a31 = 0.055639423f32;
    let a32 = -0.204011202f32;
    let a33 = 1.057148933f32;
    [
        a11 * x + a12 * y + a13 * z,
        a21 * x + a22 * y + a23 * z,
        a31 * x + a32 * y + a33 * z,
    ]
}

/// XYZ to YCxCz, FLIP's opponent space.
#[inline(always)]
pub(crate) fn xyz_to_ycxcz(xyz: [f32; 3]) -> [f32; 3] {
    let x = xyz[0] * INV_ILLUMINANT[0];
    let y = xyz[1] * INV_ILLUMINANT[1];
    let z = xyz[2] * INV_ILLUMINANT[2];
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

#[inline(always)]
pub(crate) fn ycxcz_to_xyz(yy: f32, cx: f32, cz: f32) -> [f32; 3] {
    let y = (yy + 16.0) / 116.0;
    let cx = cx / 500.0;
    let cz = cz / 200.0;
    let x = y + cx;
    let z = y - cz;
    [x * ILLUMINANT[0], y * ILLUMINANT[1], z * ILLUMINANT[2]]
}

/// CIELAB's companding of one normalised XYZ component.
#[inline(always)]
fn lab_f(v: f32) -> f32 {
    let delta = 6.0f32 / 29.0f32;
    let delta_square = delta * delta;
    let delta_cube = delta * delta_square;
    let factor = 1.0f32 / (3.0f32 * delta_square);
    let term = 4.0f32 / 29.0f32;
    if v > delta_cube {
        super::fastmath::pow(v, 1.0f32 / 3.0f32)
    } else {
        factor * v + term
    }
}

#[inline(always)]
pub(crate) fn xyz_to_cielab(xyz: [f32; 3]) -> [f32; 3] {
    let x = lab_f(xyz[0] * INV_ILLUMINANT[0]);
    let y = lab_f(xyz[1] * INV_ILLUMINANT[1]);
    let z = lab_f(xyz[2] * INV_ILLUMINANT[2]);
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

/// Hunt adjustment of one chrominance component.
#[inline(always)]
pub(crate) fn hunt(luminance: f32, chrominance: f32) -> f32 {
    0.01 * luminance * chrominance
}

/// HyAB distance: city-block on L, Euclidean on (a, b).
#[inline(always)]
pub(crate) fn hyab(a: [f32; 3], b: [f32; 3]) -> f32 {
    let dl = (a[0] - b[0]).abs();
    let dab = ((a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2])).sqrt();
    dl + dab
}

/// Linear RGB in [0,1] (clamped here) to Hunt-adjusted CIELAB.
#[inline(always)]
pub(crate) fn clamped_rgb_to_hunt_lab(rgb: [f32; 3]) -> [f32; 3] {
    let r = rgb[0].clamp(0.0, 1.0);
    let g = rgb[1].clamp(0.0, 1.0);
    let b = rgb[2].clamp(0.0, 1.0);
    let lab = xyz_to_cielab(linear_rgb_to_xyz(r, g, b));
    [lab[0], hunt(lab[0], lab[1]), hunt(lab[0], lab[2])]
}

/// `cmax`: the HyAB^qc distance between Hunt-adjusted pure green and pure blue.
pub(crate) fn max_distance() -> f32 {
    let green = clamped_rgb_to_hunt_lab([0.0, 1.0, 0.0]);
    let blue = clamped_rgb_to_hunt_lab([0.0, 0.0, 1.0]);
    hyab(green, blue).powf(QC)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_is_l100_and_neutral() {
        let lab = xyz_to_cielab(linear_rgb_to_xyz(1.0, 1.0, 1.0));
        assert!((lab[0] - 100.0).abs() < 1e-3, "{lab:?}");
        assert!(lab[1].abs() < 1e-2 && lab[2].abs() < 1e-2, "{lab:?}");
    }

    #[test]
    fn ycxcz_roundtrip() {
        let xyz = linear_rgb_to_xyz(0.2, 0.5, 0.9);
        let y = xyz_to_ycxcz(xyz);
        let back = ycxcz_to_xyz(y[0], y[1], y[2]);
        let rgb = xyz_to_linear_rgb(back[0], back[1], back[2]);
        for (a, b) in rgb.iter().zip([0.2, 0.5, 0.9]) {
            assert!((a - b).abs() < 1e-5, "{rgb:?}");
        }
    }

    #[test]
    fn cmax_is_about_the_published_value() {
        // Green vs blue after Hunt: roughly 203^0.7 ~ 41.
        let c = max_distance();
        assert!((40.0..42.0).contains(&c), "{c}");
    }
}
