//! FLIP's 1-D filter kernels, built in f32 exactly as `FLIP.h` builds them: the separated CSF
//! kernels of the colour pipeline and the Gaussian / first / second derivative kernels of the
//! feature pipeline.
//!
//! For: kernel weights. Not for: applying them (see `ldr`).
//!
//! The CSF of the Cz channel is a sum of two Gaussians, which is not separable as such; FLIP
//! (since v1.2, see its `separatedConvolutions.pdf`) filters Cz with two separable Gaussians
//! whose 1-D kernels are `sqrt(a sqrt(pi/b)) exp(-pi^2 x^2 / b)` and adds the results.

/// `FLIP::PI` as the header spells it (in f32).
#[allow(clippy::excessive_precision, clippy::approx_constant)]
const PI: f32 = 3.14159265358979;

/// CSF Gaussian parameters per opponent channel (Y, Cx, Cz).
const A1: [f32; 3] = [1.0, 1.0, 34.1];
const B1: [f32; 3] = [0.0047, 0.0053, 0.04];
const A2: [f32; 3] = [0.0, 0.0, 13.5];
const B2: [f32; 3] = [1.0e-5, 1.0e-5, 0.025];

/// Feature filter width parameter `w` (FLIP's `gw`) and feature exponent.
const GW: f32 = 0.082;
pub(crate) const QF: f32 = 0.5;

fn gaussian_ab(x2: f32, a: f32, b: f32) -> f32 {
    let pi_sq = PI * PI;
    a * (PI / b).sqrt() * (-pi_sq * x2 / b).exp()
}

fn gaussian_sqrt(x2: f32, a: f32, b: f32) -> f32 {
    let pi_sq = PI * PI;
    (a * (PI / b).sqrt()).sqrt() * (-pi_sq * x2 / b).exp()
}

/// Radius of the CSF kernels: `ceil(3 sqrt(max_b / (2 pi^2)) ppd)`.
pub(crate) fn spatial_radius(ppd: f32) -> usize {
    let pi_sq = PI * PI;
    let max_b = B1
        .iter()
        .chain(B2.iter())
        .fold(f32::NEG_INFINITY, |m, &b| m.max(b));
    (3.0f32 * (max_b / (2.0f32 * pi_sq)).sqrt() * ppd).ceil() as usize
}

/// The separated CSF kernels of the colour pipeline, all of width `2 * radius + 1`.
pub(crate) struct SpatialFilters {
    pub y: Vec<f32>,
    pub cx: Vec<f32>,
    pub cz1: Vec<f32>,
    pub cz2: Vec<f32>,
}

pub(crate) fn spatial_filters(ppd: f32) -> SpatialFilters {
    let radius = spatial_radius(ppd);
    let width = 2 * radius + 1;
    let delta_x = 1.0f32 / ppd;
    let mut f = SpatialFilters {
        y: Vec::with_capacity(width),
        cx: Vec::with_capacity(width),
        cz1: Vec::with_capacity(width),
        cz2: Vec::with_capacity(width),
    };
    let (mut sy, mut scx, mut scz1, mut scz2) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
    for x in 0..width {
        let ix = (x as i32 - radius as i32) as f32 * delta_x;
        let ix2 = ix * ix;
        let gy = gaussian_ab(ix2, A1[0], B1[0]);
        let gcx = gaussian_ab(ix2, A1[1], B1[1]);
        let gcz1 = gaussian_sqrt(ix2, A1[2], B1[2]);
        let gcz2 = gaussian_sqrt(ix2, A2[2], B2[2]);
        f.y.push(gy);
        f.cx.push(gcx);
        f.cz1.push(gcz1);
        f.cz2.push(gcz2);
        sy += gy;
        scx += gcx;
        scz1 += gcz1;
        scz2 += gcz2;
    }
    let ny = 1.0f32 / sy;
    let ncx = 1.0f32 / scx;
    let ncz = 1.0f32 / (scz1 * scz1 + scz2 * scz2).sqrt();
    f.y.iter_mut().for_each(|v| *v *= ny);
    f.cx.iter_mut().for_each(|v| *v *= ncx);
    f.cz1.iter_mut().for_each(|v| *v *= ncz);
    f.cz2.iter_mut().for_each(|v| *v *= ncz);
    f
}

/// Feature kernels: Gaussian (sums to 1), first derivative and second derivative (positive
/// and negative weights each sum to +1 and -1), sigma `0.5 * gw * ppd`, radius `ceil(3 sigma)`.
pub(crate) struct FeatureFilters {
    pub g: Vec<f32>,
    pub dg: Vec<f32>,
    pub ddg: Vec<f32>,
}

pub(crate) fn feature_filters(ppd: f32) -> FeatureFilters {
    let std_dev = 0.5f32 * GW * ppd;
    let radius = (3.0f32 * std_dev).ceil() as i32;
    let width = (2 * radius + 1) as usize;
    let mut g_v = Vec::with_capacity(width);
    let mut dg_v = Vec::with_capacity(width);
    let mut ddg_v = Vec::with_capacity(width);
    let (mut g_sum, mut dg_neg, mut dg_pos, mut ddg_neg, mut ddg_pos) =
        (0.0f32, 0.0f32, 0.0f32, 0.0f32, 0.0f32);
    for x in 0..width as i32 {
        let xx = (x - radius) as f32;
        let g = (-(xx * xx) / (2.0f32 * std_dev * std_dev)).exp();
        g_sum += g;
        let dg = -xx * g;
        if dg > 0.0 {
            dg_pos += dg;
        } else {
            dg_neg -= dg;
        }
        let ddg = (xx * xx / (std_dev * std_dev) - 1.0f32) * g;
        if ddg > 0.0 {
            ddg_pos += ddg;
        } else {
            ddg_neg -= ddg;
        }
        g_v.push(g);
        dg_v.push(dg);
        ddg_v.push(ddg);
    }
    let g = g_v.iter().map(|&v| v / g_sum).collect();
    let dg = dg_v
        .iter()
        .map(|&v| v / if v > 0.0 { dg_pos } else { dg_neg })
        .collect();
    let ddg = ddg_v
        .iter()
        .map(|&v| v / if v > 0.0 { ddg_pos } else { ddg_neg })
        .collect();
    FeatureFilters { g, dg, ddg }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radii_at_67_ppd() {
        assert_eq!(spatial_radius(67.0), 10);
        assert_eq!(feature_filters(67.0).g.len(), 19);
    }

    #[test]
    fn kernels_are_normalised() {
        let s = spatial_filters(67.0);
        assert!((s.y.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        assert!((s.cx.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        let (c1, c2): (f32, f32) = (s.cz1.iter().sum(), s.cz2.iter().sum());
        assert!((c1 * c1 + c2 * c2 - 1.0).abs() < 1e-6);
        let f = feature_filters(67.0);
        assert!((f.g.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        let pos: f32 = f.dg.iter().filter(|v| **v > 0.0).sum();
        let neg: f32 = f.dg.iter().filter(|v| **v < 0.0).sum();
        assert!((pos - 1.0).abs() < 1e-6 && (neg + 1.0).abs() < 1e-6);
    }
}
