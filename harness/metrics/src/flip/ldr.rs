//! The LDR-FLIP error map from two linear-RGB images in [0,1].
//!
//! For: the per-pixel FLIP error, the part HDR-FLIP runs once per exposure. Not for: sRGB
//! decoding, tone mapping or pooling (see `mod.rs`, `hdr` and `pool`).
//!
//! Same arithmetic as `FLIP.h`'s `LDR_FLIP` (f32, kernels from `filters`, clamp-to-edge
//! borders), organised for a 2-core CPU: each output row is filtered vertically first (from the
//! precomputed YCxCz planes) and then horizontally, so intermediate rows stay in cache instead
//! of the four full-size intermediate images FLIP keeps. Separable filtering with clamped
//! borders gives the same result in either order up to f32 rounding.

use super::color::{
    clamped_rgb_to_hunt_lab, hyab, linear_rgb_to_xyz, max_distance, xyz_to_linear_rgb,
    xyz_to_ycxcz, ycxcz_to_xyz, PC, PT, QC,
};
use super::fastmath::pow;
use super::filters::{feature_filters, spatial_filters, FeatureFilters, SpatialFilters, QF};

const _: () = assert!(QF == 0.5, "the feature exponent is applied as sqrt");
use rayon::prelude::*;

/// One image in planes: Y, Cx, Cz, and the feature pipeline's normalised achromatic channel.
struct Planes {
    y: Vec<f32>,
    cx: Vec<f32>,
    cz: Vec<f32>,
    gray: Vec<f32>,
}

/// Planes of `n` pixels whose linear RGB (already in [0,1]) `pixel(i)` gives.
fn to_planes(n: usize, pixel: impl Fn(usize) -> [f32; 3] + Sync) -> Planes {
    let mut p = Planes {
        y: vec![0.0; n],
        cx: vec![0.0; n],
        cz: vec![0.0; n],
        gray: vec![0.0; n],
    };
    let one_over_116 = 1.0f32 / 116.0f32;
    let sixteen_over_116 = 16.0f32 / 116.0f32;
    const CHUNK: usize = 8192;
    p.y.par_chunks_mut(CHUNK)
        .zip(p.cx.par_chunks_mut(CHUNK))
        .zip(p.cz.par_chunks_mut(CHUNK))
        .zip(p.gray.par_chunks_mut(CHUNK))
        .enumerate()
        .for_each(|(chunk, (((y, cx), cz), gray))| {
            for i in 0..y.len() {
                let c = pixel(chunk * CHUNK + i);
                let v = xyz_to_ycxcz(linear_rgb_to_xyz(c[0], c[1], c[2]));
                y[i] = v[0];
                cx[i] = v[1];
                cz[i] = v[2];
                gray[i] = v[0] * one_over_116 + sixteen_over_116;
            }
        });
    p
}

/// Per-thread scratch rows, each padded by the kernel radius on both sides.
struct Scratch {
    /// Vertically filtered Y, Cx, Cz (two Gaussians) of reference and test.
    col: [[Vec<f32>; 4]; 2],
    /// Vertically filtered gray: Gaussian, first and second derivative, of reference and test.
    feat: [[Vec<f32>; 3]; 2],
    /// Horizontal results for one row.
    out_col: [[Vec<f32>; 4]; 2],
    out_feat: [[Vec<f32>; 4]; 2],
}

impl Scratch {
    fn new(w: usize, rs: usize, rf: usize) -> Self {
        let pc = || std::array::from_fn(|_| vec![0.0f32; w + 2 * rs]);
        let pf = || std::array::from_fn(|_| vec![0.0f32; w + 2 * rf]);
        let oc = || std::array::from_fn(|_| vec![0.0f32; w]);
        let of = || std::array::from_fn(|_| vec![0.0f32; w]);
        Scratch {
            col: [pc(), pc()],
            feat: [pf(), pf()],
            out_col: [oc(), oc()],
            out_feat: [of(), of()],
        }
    }
}

/// Where the linear RGB of each pixel comes from.
pub(crate) enum Source<'a> {
    /// 8-bit sRGB, decoded through a 256-entry table.
    Srgb8(&'a [u8], &'a [f32; 256]),
    /// Interleaved linear RGB; clamped to [0,1] as FLIP clamps LDR input.
    Linear(&'a [f32]),
}

impl Source<'_> {
    fn planes(&self, n: usize) -> Planes {
        match *self {
            Source::Srgb8(d, t) => to_planes(n, |i| {
                [
                    t[d[3 * i] as usize],
                    t[d[3 * i + 1] as usize],
                    t[d[3 * i + 2] as usize],
                ]
            }),
            Source::Linear(d) => to_planes(n, |i| {
                [
                    d[3 * i].clamp(0.0, 1.0),
                    d[3 * i + 1].clamp(0.0, 1.0),
                    d[3 * i + 2].clamp(0.0, 1.0),
                ]
            }),
        }
    }
}

/// LDR-FLIP of two images of `w * h` pixels at `ppd` pixels per degree.
pub(crate) fn ldr_flip_map(
    reference: Source,
    test: Source,
    w: usize,
    h: usize,
    ppd: f32,
) -> Vec<f32> {
    let n = w * h;
    let (pr, pt) = rayon::join(|| reference.planes(n), || test.planes(n));
    let planes = [pr, pt];
    let sf = spatial_filters(ppd);
    let ff = feature_filters(ppd);
    let rs = sf.y.len() / 2;
    let rf = ff.g.len() / 2;
    let cmax = max_distance();
    let pccmax = PC * cmax;

    let ctx = RowContext {
        planes: &planes,
        w,
        h,
        sf: &sf,
        ff: &ff,
        cmax,
        pccmax,
    };
    let mut error = vec![0.0f32; n];
    error.par_chunks_mut(w).enumerate().for_each_init(
        || Scratch::new(w, rs, rf),
        |s, (row, out)| process_row(&ctx, s, row, out),
    );
    error
}

/// What every row needs.
struct RowContext<'a> {
    planes: &'a [Planes; 2],
    w: usize,
    h: usize,
    sf: &'a SpatialFilters,
    ff: &'a FeatureFilters,
    cmax: f32,
    pccmax: f32,
}

/// One output row, with AVX2 when the CPU has it (the same arithmetic, wider vectors: no FMA,
/// so results do not depend on the CPU).
fn process_row(ctx: &RowContext, s: &mut Scratch, row: usize, out: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, checked just above.
        unsafe { process_row_avx2(ctx, s, row, out) };
        return;
    }
    process_row_generic(ctx, s, row, out);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn process_row_avx2(ctx: &RowContext, s: &mut Scratch, row: usize, out: &mut [f32]) {
    process_row_generic(ctx, s, row, out);
}

#[inline(always)]
fn process_row_generic(ctx: &RowContext, s: &mut Scratch, row: usize, out: &mut [f32]) {
    let (w, h) = (ctx.w, ctx.h);
    let rs = ctx.sf.y.len() / 2;
    let rf = ctx.ff.g.len() / 2;
    for (img, p) in ctx.planes.iter().enumerate() {
        vertical_color(&mut s.col[img], p, w, h, row, ctx.sf, rs);
        vertical_feature(&mut s.feat[img], p, w, h, row, ctx.ff, rf);
        horizontal_color(&mut s.out_col[img], &s.col[img], w, ctx.sf);
        horizontal_feature(&mut s.out_feat[img], &s.feat[img], w, ctx.ff);
    }
    combine(out, s, ctx.cmax, ctx.pccmax);
}

/// Vertical CSF pass for one output row into padded rows (edge values replicated).
#[inline(always)]
fn vertical_color(
    dst: &mut [Vec<f32>; 4],
    p: &Planes,
    w: usize,
    h: usize,
    row: usize,
    f: &SpatialFilters,
    r: usize,
) {
    let [dy, dcx, dcz1, dcz2] = dst;
    for d in [&mut *dy, &mut *dcx, &mut *dcz1, &mut *dcz2] {
        d[r..r + w].fill(0.0);
    }
    for k in 0..f.y.len() {
        let yy = (row as isize + k as isize - r as isize).clamp(0, h as isize - 1) as usize;
        let (wy, wcx, wcz1, wcz2) = (f.y[k], f.cx[k], f.cz1[k], f.cz2[k]);
        let sy = &p.y[yy * w..][..w];
        let scx = &p.cx[yy * w..][..w];
        let scz = &p.cz[yy * w..][..w];
        let oy = &mut dy[r..r + w];
        let ocx = &mut dcx[r..r + w];
        let ocz1 = &mut dcz1[r..r + w];
        let ocz2 = &mut dcz2[r..r + w];
        for x in 0..w {
            oy[x] += wy * sy[x];
            ocx[x] += wcx * scx[x];
            ocz1[x] += wcz1 * scz[x];
            ocz2[x] += wcz2 * scz[x];
        }
    }
    for d in [dy, dcx, dcz1, dcz2] {
        pad_edges(d, w, r);
    }
}

/// Vertical feature pass (Gaussian, first and second derivative) into padded rows.
#[inline(always)]
fn vertical_feature(
    dst: &mut [Vec<f32>; 3],
    p: &Planes,
    w: usize,
    h: usize,
    row: usize,
    f: &FeatureFilters,
    r: usize,
) {
    let [dg, ddg, dddg] = dst;
    for d in [&mut *dg, &mut *ddg, &mut *dddg] {
        d[r..r + w].fill(0.0);
    }
    for k in 0..f.g.len() {
        let yy = (row as isize + k as isize - r as isize).clamp(0, h as isize - 1) as usize;
        let (wg, wd, wdd) = (f.g[k], f.dg[k], f.ddg[k]);
        let src = &p.gray[yy * w..][..w];
        let og = &mut dg[r..r + w];
        let od = &mut ddg[r..r + w];
        let odd = &mut dddg[r..r + w];
        for x in 0..w {
            og[x] += wg * src[x];
            od[x] += wd * src[x];
            odd[x] += wdd * src[x];
        }
    }
    for d in [dg, ddg, dddg] {
        pad_edges(d, w, r);
    }
}

/// Replicates the first and last of the `w` values at `r..r + w` into the `r` slots each side.
#[inline(always)]
fn pad_edges(d: &mut [f32], w: usize, r: usize) {
    let (first, last) = (d[r], d[r + w - 1]);
    d[..r].fill(first);
    d[r + w..].fill(last);
}

#[inline(always)]
fn horizontal_color(dst: &mut [Vec<f32>; 4], src: &[Vec<f32>; 4], w: usize, f: &SpatialFilters) {
    for d in dst.iter_mut() {
        d.fill(0.0);
    }
    let [oy, ocx, ocz1, ocz2] = dst;
    for k in 0..f.y.len() {
        let (wy, wcx, wcz1, wcz2) = (f.y[k], f.cx[k], f.cz1[k], f.cz2[k]);
        let sy = &src[0][k..k + w];
        let scx = &src[1][k..k + w];
        let scz1 = &src[2][k..k + w];
        let scz2 = &src[3][k..k + w];
        for x in 0..w {
            oy[x] += wy * sy[x];
            ocx[x] += wcx * scx[x];
            ocz1[x] += wcz1 * scz1[x];
            ocz2[x] += wcz2 * scz2[x];
        }
    }
}

/// Horizontal feature pass: outputs dx, ddx (derivatives across the vertically smoothed row)
/// and dy, ddy (smoothing across the vertical derivatives).
#[inline(always)]
fn horizontal_feature(dst: &mut [Vec<f32>; 4], src: &[Vec<f32>; 3], w: usize, f: &FeatureFilters) {
    for d in dst.iter_mut() {
        d.fill(0.0);
    }
    let [dx, ddx, dy, ddy] = dst;
    for k in 0..f.g.len() {
        let (wg, wd, wdd) = (f.g[k], f.dg[k], f.ddg[k]);
        let sg = &src[0][k..k + w];
        let sd = &src[1][k..k + w];
        let sdd = &src[2][k..k + w];
        for x in 0..w {
            dx[x] += wd * sg[x];
            ddx[x] += wdd * sg[x];
            dy[x] += wg * sd[x];
            ddy[x] += wg * sdd[x];
        }
    }
}

/// Colour difference, feature difference and their combination for one row.
/// Hunt-adjusted CIELAB of the filtered YCxCz at column `x` (Cz is the sum of its two parts).
#[inline(always)]
fn hunt_lab(c: &[Vec<f32>; 4], x: usize) -> [f32; 3] {
    let xyz = ycxcz_to_xyz(c[0][x], c[1][x], c[2][x] + c[3][x]);
    clamped_rgb_to_hunt_lab(xyz_to_linear_rgb(xyz[0], xyz[1], xyz[2]))
}

#[inline(always)]
fn combine(out: &mut [f32], s: &Scratch, cmax: f32, pccmax: f32) {
    let normalization = 1.0f32 / 2.0f32.sqrt();
    let [rc, tc] = &s.out_col;
    let [rf, tf] = &s.out_feat;
    for (x, o) in out.iter_mut().enumerate() {
        let mut cd = pow(hyab(hunt_lab(rc, x), hunt_lab(tc, x)), QC);
        if cd < pccmax {
            cd *= PT / pccmax;
        } else {
            cd = PT + ((cd - pccmax) / (cmax - pccmax)) * (1.0 - PT);
        }

        let edge_r = (rf[0][x] * rf[0][x] + rf[2][x] * rf[2][x]).sqrt();
        let edge_t = (tf[0][x] * tf[0][x] + tf[2][x] * tf[2][x]).sqrt();
        let point_r = (rf[1][x] * rf[1][x] + rf[3][x] * rf[3][x]).sqrt();
        let point_t = (tf[1][x] * tf[1][x] + tf[3][x] * tf[3][x]).sqrt();
        let edge_diff = (edge_r - edge_t).abs();
        let point_diff = (point_r - point_t).abs();
        // powf(x, 0.5) as FLIP writes it; sqrt is the same function, and cheaper.
        let fd = (normalization * edge_diff.max(point_diff)).sqrt();
        *o = pow(cd, 1.0 - fd);
    }
}
