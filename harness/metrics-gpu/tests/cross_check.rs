//! Both back ends on generated pairs and sequences (noise, edges, gradients, HDR values, odd and
//! tiny sizes): the GPU's values must equal the CPU reference within the tolerances of issue
//! 25's Acceptance, on whatever adapter is first (lavapipe in CI; `TESSERA_METRICS_ADAPTER`
//! picks another). Each test prints the largest deviation it saw (`--nocapture`).

use std::sync::{Mutex, MutexGuard, OnceLock};

use tessera_metrics::{hdr_exposure_range, HdrImage, Rgb8Image, DEFAULT_PIXELS_PER_DEGREE};
use tessera_metrics_gpu::{
    Backend, CpuMetrics, FlipHdrRequest, FlipPooling, FlipRequest, GpuMetrics, GpuMetricsError,
    MetricsBackend, Pair, PairRequest, Sequence,
};

/// Acceptance tolerances (issue 25).
const PSNR_REL: f64 = 1e-6;
const SSIM_ABS: f64 = 1e-6;
const FLIP_MEAN_ABS: f64 = 1e-5;
const TEMPORAL_ABS: f64 = 1e-5;

/// One GPU back end for every test of this binary (pipelines compile once).
fn gpu() -> MutexGuard<'static, GpuMetrics> {
    static GPU: OnceLock<Mutex<GpuMetrics>> = OnceLock::new();
    GPU.get_or_init(|| {
        let wanted = std::env::var("TESSERA_METRICS_ADAPTER").ok();
        let adapter = tessera_metrics_gpu::select_adapter(wanted.as_deref())
            .expect("no GPU adapter: run ci/setup.sh to install lavapipe");
        let name = adapter.get_info().name;
        eprintln!("adapter: {name}");
        let d = tessera_metrics_gpu::open(adapter).expect("open device");
        Mutex::new(GpuMetrics::new(&d.device, &d.queue, &name))
    })
    .lock()
    .unwrap_or_else(|e| e.into_inner())
}

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 33) as u32
    }
    fn unit(&mut self) -> f32 {
        (self.next() >> 8) as f32 / (1u32 << 24) as f32
    }
}

fn image(w: u32, h: u32, mut f: impl FnMut(u32, u32) -> [u8; 3]) -> Rgb8Image {
    let mut data = Vec::with_capacity((w * h * 3) as usize);
    for y in 0..h {
        for x in 0..w {
            data.extend(f(x, y));
        }
    }
    Rgb8Image {
        width: w,
        height: h,
        data,
    }
}

fn perturb(img: &Rgb8Image, amplitude: i32, seed: u64) -> Rgb8Image {
    let mut rng = Rng(seed);
    let mut out = img.clone();
    for v in &mut out.data {
        let d = (rng.next() % (2 * amplitude as u32 + 1)) as i32 - amplitude;
        *v = (*v as i32 + d).clamp(0, 255) as u8;
    }
    out
}

/// Named generated pairs.
fn pairs() -> Vec<(String, Rgb8Image, Rgb8Image)> {
    let mut out = Vec::new();
    for (w, h) in [(37, 23), (8, 8), (64, 48), (11, 11), (160, 90)] {
        let mut rng = Rng(w as u64 * 31 + h as u64);
        let noise = image(w, h, |_, _| {
            [rng.next() as u8, rng.next() as u8, rng.next() as u8]
        });
        out.push((
            format!("noise {w}x{h} +-3"),
            noise.clone(),
            perturb(&noise, 3, 1),
        ));
        out.push((
            format!("noise {w}x{h} vs noise"),
            noise.clone(),
            perturb(&noise, 120, 2),
        ));
        let edges = image(w, h, |x, y| {
            let v = if (x / 4 + y / 3) % 2 == 0 { 230 } else { 20 };
            [v, 255 - v, if x > w / 2 { 128 } else { 0 }]
        });
        let shifted = image(w, h, |x, y| {
            let x = x.saturating_sub(1);
            let v = if (x / 4 + y / 3) % 2 == 0 { 230 } else { 20 };
            [v, 255 - v, if x > w / 2 { 128 } else { 0 }]
        });
        out.push((format!("edges {w}x{h} shifted"), edges, shifted));
        let grad = image(w, h, |x, y| {
            [
                (x * 255 / w.max(2)) as u8,
                (y * 255 / h.max(2)) as u8,
                ((x + y) * 127 / (w + h)) as u8,
            ]
        });
        out.push((
            format!("gradient {w}x{h} +-1"),
            grad.clone(),
            perturb(&grad, 1, 3),
        ));
        out.push((
            format!("gradient {w}x{h} identical"),
            grad.clone(),
            grad.clone(),
        ));
        let flat = Rgb8Image::filled(w, h, [250, 250, 250]);
        out.push((
            format!("flat {w}x{h} bright"),
            flat.clone(),
            perturb(&flat, 2, 4),
        ));
    }
    out.push((
        "black vs white 16x16".into(),
        Rgb8Image::filled(16, 16, [0, 0, 0]),
        Rgb8Image::filled(16, 16, [255, 255, 255]),
    ));
    out
}

fn rel(a: f64, b: f64) -> f64 {
    if a == b {
        0.0
    } else {
        (a - b).abs() / b.abs().max(1e-300)
    }
}

fn psnr(mse: f64) -> f64 {
    tessera_metrics::psnr_from_mse(mse, 255.0)
}

#[test]
fn pixel_metrics_and_ssim_agree() {
    let mut gpu = gpu();
    let mut cpu = CpuMetrics;
    let (mut psnr_dev, mut psnr_luma_dev, mut ssim_dev, mut ssim_luma_dev) =
        (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (name, r, t) in pairs() {
        let ssim = r.width >= 11 && r.height >= 11;
        let req = PairRequest {
            mse_rgb: true,
            mse_luma: true,
            max_abs: true,
            ssim_rgb: ssim,
            ssim_luma: ssim,
            flip: None,
            flip_hdr: None,
        };
        let pair = Pair {
            reference: &r,
            test: &t,
            reference_hdr: None,
            test_hdr: None,
        };
        let c = cpu.pair(pair, &req).unwrap();
        let g = gpu.pair(pair, &req).unwrap();
        assert_eq!((c.backend, g.backend), (Backend::Cpu, Backend::Gpu));
        // Integer sums: bit-exact.
        assert_eq!(g.mse_rgb, c.mse_rgb, "{name}: mse_rgb");
        assert_eq!(g.max_abs, c.max_abs, "{name}: max_abs");
        let (pc, pg) = (psnr(c.mse_rgb.unwrap()), psnr(g.mse_rgb.unwrap()));
        psnr_dev = psnr_dev.max(rel(pg, pc));
        let (lc, lg) = (psnr(c.mse_luma.unwrap()), psnr(g.mse_luma.unwrap()));
        assert_eq!(
            lc.is_infinite(),
            lg.is_infinite(),
            "{name}: luma PSNR {lc} vs {lg}"
        );
        if lc.is_finite() {
            let d = rel(lg, lc);
            assert!(d <= PSNR_REL, "{name}: PSNR luma {lg} vs {lc} (rel {d:e})");
            psnr_luma_dev = psnr_luma_dev.max(d);
        }
        if ssim {
            let d = (g.ssim_rgb.unwrap() - c.ssim_rgb.unwrap()).abs();
            assert!(
                d <= SSIM_ABS,
                "{name}: SSIM {:?} vs {:?} ({d:e})",
                g.ssim_rgb,
                c.ssim_rgb
            );
            ssim_dev = ssim_dev.max(d);
            let d = (g.ssim_luma.unwrap() - c.ssim_luma.unwrap()).abs();
            assert!(
                d <= SSIM_ABS,
                "{name}: SSIM luma {:?} vs {:?} ({d:e})",
                g.ssim_luma,
                c.ssim_luma
            );
            ssim_luma_dev = ssim_luma_dev.max(d);
        }
    }
    eprintln!(
        "max deviation: psnr rel {psnr_dev:e} (mse_rgb, max_abs exact), psnr_luma rel \
         {psnr_luma_dev:e}, ssim {ssim_dev:e}, ssim_luma {ssim_luma_dev:e}"
    );
}

/// The magma index of each heat-map colour.
fn magma_index(heat: &Rgb8Image) -> Vec<i32> {
    let lut = tessera_metrics::port::MAGMA;
    heat.data
        .chunks_exact(3)
        .map(|c| lut.iter().position(|m| m == c).expect("a magma colour") as i32)
        .collect()
}

#[test]
fn ldr_flip_and_heatmap_agree() {
    let mut gpu = gpu();
    let (mut mean_dev, mut exact_dev, mut max_dev, mut heat_dev) = (0.0f64, 0.0f64, 0.0f64, 0);
    for ppd in [DEFAULT_PIXELS_PER_DEGREE, 30.0] {
        for (name, r, t) in pairs() {
            let req = PairRequest {
                flip: Some(FlipRequest {
                    pixels_per_degree: ppd,
                    heatmap: true,
                    pooling: FlipPooling::FlipEvaluator,
                }),
                ..Default::default()
            };
            let pair = Pair {
                reference: &r,
                test: &t,
                reference_hdr: None,
                test_hdr: None,
            };
            let g = gpu.pair(pair, &req).unwrap().flip.unwrap();
            let c = tessera_metrics::flip_ldr(&r, &t, ppd).unwrap();
            // Pooled as flip-evaluator (the error map read back) vs the CPU's `mean`, and the
            // exact means of both.
            let d = (g.mean - c.mean).abs();
            assert!(
                d <= FLIP_MEAN_ABS,
                "{name} @ {ppd}: FLIP mean {} vs {} ({d:e})",
                g.mean,
                c.mean
            );
            mean_dev = mean_dev.max(d);
            let d = (g.exact_mean - c.exact_mean).abs();
            assert!(
                d <= FLIP_MEAN_ABS,
                "{name} @ {ppd}: exact mean {} vs {} ({d:e})",
                g.exact_mean,
                c.exact_mean
            );
            exact_dev = exact_dev.max(d);
            // The exact pooling gives the same exact mean without the map.
            let exact = PairRequest {
                flip: Some(FlipRequest {
                    pixels_per_degree: ppd,
                    heatmap: false,
                    pooling: FlipPooling::Exact,
                }),
                ..Default::default()
            };
            let e = gpu.pair(pair, &exact).unwrap().flip.unwrap();
            assert_eq!(
                (e.mean, e.exact_mean, e.pooling),
                (g.exact_mean, g.exact_mean, FlipPooling::Exact)
            );
            max_dev = max_dev.max((g.max - c.max).abs());
            let gi = magma_index(g.heatmap.as_ref().unwrap());
            let ci = magma_index(&tessera_metrics::flip_heatmap(&c));
            let worst = gi
                .iter()
                .zip(&ci)
                .map(|(a, b)| (a - b).abs())
                .max()
                .unwrap();
            assert!(
                worst <= 1,
                "{name} @ {ppd}: heat map index differs by {worst}"
            );
            heat_dev = heat_dev.max(worst);
        }
    }
    eprintln!(
        "max deviation: flip mean (flip-evaluator pooling) {mean_dev:e}, exact mean \
         {exact_dev:e}, flip max {max_dev:e}, heat map {heat_dev} step(s) of 255"
    );
}

fn hdr_image(w: u32, h: u32, seed: u64, f: impl Fn(u32, u32, &mut Rng) -> [f32; 3]) -> HdrImage {
    let mut rng = Rng(seed);
    let mut data = Vec::new();
    for y in 0..h {
        for x in 0..w {
            data.extend(f(x, y, &mut rng));
        }
    }
    HdrImage {
        width: w,
        height: h,
        data,
    }
}

#[test]
fn hdr_flip_agrees() {
    let mut gpu = gpu();
    let mut cpu = CpuMetrics;
    let (mut mean_dev, mut exact_dev, mut heat_dev) = (0.0f64, 0.0f64, 0);
    let cases = [
        (
            "hdr noise 37x23",
            hdr_image(37, 23, 5, |_, _, r| {
                let s = (r.unit() * 8.0 - 3.0).exp2();
                [s * r.unit(), s * r.unit(), s * r.unit()]
            }),
        ),
        (
            "hdr gradient with highlight 64x40",
            hdr_image(64, 40, 6, |x, y, _| {
                let v = x as f32 / 8.0 + if (x / 8 + y / 8) % 5 == 0 { 40.0 } else { 0.0 };
                [v, v * 0.5, y as f32 / 40.0]
            }),
        ),
        (
            "hdr tiny 8x8",
            hdr_image(8, 8, 7, |x, y, _| [x as f32, y as f32, 0.25]),
        ),
    ];
    for (name, r) in cases {
        let mut rng = Rng(9);
        let t = HdrImage {
            data: r
                .data
                .iter()
                .map(|v| v * (0.9 + 0.2 * rng.unit()))
                .collect(),
            ..r.clone()
        };
        let range = hdr_exposure_range(&r);
        let (rl, tl) = (
            tessera_metrics::encode_srgb8(&r),
            tessera_metrics::encode_srgb8(&t),
        );
        let req = PairRequest {
            flip_hdr: Some(FlipHdrRequest {
                range,
                pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
                heatmap: true,
                pooling: FlipPooling::FlipEvaluator,
            }),
            ..Default::default()
        };
        let pair = Pair {
            reference: &rl,
            test: &tl,
            reference_hdr: Some(&r),
            test_hdr: Some(&t),
        };
        let c = cpu.pair(pair, &req).unwrap().flip_hdr.unwrap();
        let g = gpu.pair(pair, &req).unwrap().flip_hdr.unwrap();
        let d = (g.mean - c.mean).abs();
        assert!(
            d <= FLIP_MEAN_ABS,
            "{name}: HDR-FLIP mean {} vs {} ({d:e}), {} exposures",
            g.mean,
            c.mean,
            range.count
        );
        mean_dev = mean_dev.max(d);
        let d = (g.exact_mean - c.exact_mean).abs();
        assert!(d <= FLIP_MEAN_ABS, "{name}: HDR-FLIP exact mean ({d:e})");
        exact_dev = exact_dev.max(d);
        let gi = magma_index(g.heatmap.as_ref().unwrap());
        let ci = magma_index(c.heatmap.as_ref().unwrap());
        let worst = gi
            .iter()
            .zip(&ci)
            .map(|(a, b)| (a - b).abs())
            .max()
            .unwrap();
        assert!(worst <= 1, "{name}: heat map index differs by {worst}");
        heat_dev = heat_dev.max(worst);
    }
    eprintln!(
        "max deviation: flip_hdr mean {mean_dev:e}, exact mean {exact_dev:e}, heat map \
         {heat_dev} step(s) of 255"
    );
}

/// A moving sequence: content slides by a sub-pixel amount per frame; the test adds noise that
/// changes from frame to frame (flicker the reference does not have).
fn sequence(w: u32, h: u32, frames: usize) -> (Vec<Rgb8Image>, Vec<Rgb8Image>, Vec<[f32; 2]>) {
    let motion = [0.6f32, -0.35];
    let at = |f: usize| {
        let (ox, oy) = (motion[0] * f as f32, motion[1] * f as f32);
        image(w, h, move |x, y| {
            let (u, v) = (x as f32 - ox, y as f32 - oy);
            [
                (128.0 + 100.0 * (u * 0.3).sin()) as u8,
                (128.0 + 90.0 * (v * 0.21 + u * 0.05).cos()) as u8,
                ((u + v).abs() as u32 % 256) as u8,
            ]
        })
    };
    let reference: Vec<Rgb8Image> = (0..frames).map(at).collect();
    let test = reference
        .iter()
        .enumerate()
        .map(|(i, r)| perturb(r, 4, 100 + i as u64))
        .collect();
    (reference, test, vec![motion; (w * h) as usize])
}

#[test]
fn flicker_and_tde_agree() {
    let mut gpu = gpu();
    let mut cpu = CpuMetrics;
    let (mut flicker_dev, mut tde_dev) = (0.0f64, 0.0f64);
    for (w, h) in [(37, 23), (8, 8), (96, 64)] {
        let (reference, test, motion) = sequence(w, h, 4);
        let seq = Sequence {
            reference: &reference,
            test: &test,
            reference_hdr: &[],
            test_hdr: &[],
        };
        let req = |_| PairRequest {
            mse_rgb: true,
            ..Default::default()
        };
        let c = cpu.sequence(seq, &req, true).unwrap();
        let g = gpu.sequence(seq, &req, true).unwrap();
        // Flicker is an integer sum over a count: exact.
        assert_eq!(g.flicker, c.flicker, "{w}x{h}: flicker");
        assert_eq!(g.frames.len(), 4);
        for (a, b) in g.frames.iter().zip(&c.frames) {
            assert_eq!(a.mse_rgb, b.mse_rgb);
        }
        for fl in c.flicker.as_ref().unwrap() {
            assert!(*fl > 0.0);
        }
        flicker_dev = flicker_dev.max(0.0);
        // The mask leaves out a border column and every seventh pixel.
        let valid: Vec<bool> = (0..(w * h) as usize)
            .map(|i| i % w as usize != 0 && i % 7 != 3)
            .collect();
        for f in 1..4 {
            let args = (&test[f - 1], &test[f], &reference[f - 1], &reference[f]);
            let c = cpu
                .tde(args.0, args.1, args.2, args.3, &motion, &valid)
                .unwrap();
            let g = gpu
                .tde(args.0, args.1, args.2, args.3, &motion, &valid)
                .unwrap();
            let d = (g.unwrap() - c.unwrap()).abs();
            assert!(
                d <= TEMPORAL_ABS,
                "{w}x{h} frame {f}: tde {g:?} vs {c:?} ({d:e})"
            );
            tde_dev = tde_dev.max(d);
            // A test that changes exactly as the reference gives exactly zero on both.
            let same = (
                &reference[f - 1],
                &reference[f],
                &reference[f - 1],
                &reference[f],
            );
            assert_eq!(
                gpu.tde(same.0, same.1, same.2, same.3, &motion, &valid)
                    .unwrap(),
                Some(0.0)
            );
            let none = vec![false; valid.len()];
            assert_eq!(
                gpu.tde(args.0, args.1, args.2, args.3, &motion, &none)
                    .unwrap(),
                None
            );
        }
    }
    eprintln!("max deviation: flicker {flicker_dev:e} (exact), tde {tde_dev:e}");
}

#[test]
fn results_are_bitwise_repeatable() {
    let mut gpu = gpu();
    let (_, r, t) = pairs().swap_remove(1);
    let pair = Pair {
        reference: &r,
        test: &t,
        reference_hdr: None,
        test_hdr: None,
    };
    let req = PairRequest::all_ldr(DEFAULT_PIXELS_PER_DEGREE);
    let a = gpu.pair(pair, &req).unwrap();
    let b = gpu.pair(pair, &req).unwrap();
    assert_eq!(a, b);
    assert_eq!(a.ssim_rgb.unwrap().to_bits(), b.ssim_rgb.unwrap().to_bits());
    assert_eq!(
        a.flip.unwrap().mean.to_bits(),
        b.flip.unwrap().mean.to_bits()
    );
}

#[test]
fn bad_input_gives_the_cpu_errors() {
    let mut gpu = gpu();
    let a = Rgb8Image::filled(8, 8, [1, 2, 3]);
    let b = Rgb8Image::filled(8, 9, [1, 2, 3]);
    let pair = |r, t| Pair {
        reference: r,
        test: t,
        reference_hdr: None,
        test_hdr: None,
    };
    let all = PairRequest::all_ldr(DEFAULT_PIXELS_PER_DEGREE);
    let e = gpu.pair(pair(&a, &b), &all).unwrap_err();
    assert!(
        matches!(
            e,
            GpuMetricsError::Metrics(tessera_metrics::MetricsError::SizeMismatch { .. })
        ),
        "{e}"
    );
    // SSIM on 8x8: too small on both back ends, with the same message.
    let e = gpu.pair(pair(&a, &a), &all).unwrap_err();
    let c = CpuMetrics.pair(pair(&a, &a), &all).unwrap_err();
    assert_eq!(e.to_string(), c.to_string());
    assert!(e.to_string().contains("at least 11x11"), "{e}");
    // Without SSIM the tiny pair works.
    let req = PairRequest {
        ssim_rgb: false,
        ssim_luma: false,
        ..all.clone()
    };
    let v = gpu.pair(pair(&a, &a), &req).unwrap();
    assert_eq!(v.mse_rgb, Some(0.0));
    // Identical images: 0 exactly on lavapipe; the H200 gives 2.8e-9 (fused arithmetic), inside
    // issue 25's FLIP tolerance of 1e-5.
    assert!(v.flip.unwrap().mean.abs() < 1e-5);
    // Invalid viewing condition.
    let bad = PairRequest {
        flip: Some(FlipRequest {
            pixels_per_degree: -1.0,
            heatmap: false,
            pooling: FlipPooling::Exact,
        }),
        ..Default::default()
    };
    assert!(gpu
        .pair(pair(&a, &a), &bad)
        .unwrap_err()
        .to_string()
        .contains("pixels_per_degree"));
    // HDR-FLIP without floats, or with NaN.
    let hdr = HdrImage {
        width: 8,
        height: 8,
        data: vec![0.5; 192],
    };
    let req = PairRequest {
        flip_hdr: Some(FlipHdrRequest {
            range: hdr_exposure_range(&hdr),
            pixels_per_degree: 67.0,
            heatmap: false,
            pooling: FlipPooling::Exact,
        }),
        ..Default::default()
    };
    assert!(gpu.pair(pair(&a, &a), &req).is_err());
    let mut nan = hdr.clone();
    nan.data[4] = f32::NAN;
    let p = Pair {
        reference: &a,
        test: &a,
        reference_hdr: Some(&hdr),
        test_hdr: Some(&nan),
    };
    let e = gpu.pair(p, &req).unwrap_err();
    assert!(e.to_string().contains("non-finite"), "{e}");
}

#[test]
fn diff_reports_agree() {
    use tessera_metrics::LoadedImage;
    let mut gpu = gpu();
    let mut worst_percentile = 0.0f64;
    for (name, r, t) in pairs()
        .into_iter()
        .filter(|(n, _, _)| n.contains("37x23") || n.contains("8x8"))
    {
        let (r, t) = (LoadedImage::Ldr(r), LoadedImage::Ldr(t));
        let c = tessera_metrics::diff_images(&r, &t).unwrap();
        let g = tessera_metrics_gpu::diff_images(&mut gpu, &r, &t).unwrap();
        assert_eq!(
            (g.mse_rgb, g.max_abs_error, g.bit_depth),
            (c.mse_rgb, c.max_abs_error, 8),
            "{name}"
        );
        assert_eq!(g.ssim_rgb.is_some(), c.ssim_rgb.is_some(), "{name}");
        if let (Some(a), Some(b)) = (g.ssim_rgb, c.ssim_rgb) {
            assert!((a - b).abs() <= SSIM_ABS, "{name}");
        }
        assert!((g.flip.mean - c.flip.mean).abs() <= FLIP_MEAN_ABS, "{name}");
        for (a, b) in [
            (g.flip.p50, c.flip.p50),
            (g.flip.p95, c.flip.p95),
            (g.flip.p99, c.flip.p99),
        ] {
            worst_percentile = worst_percentile.max((a - b).abs());
        }
    }
    // HDR files: HDR-FLIP with the reference's exposure range, as the CPU report.
    let r = hdr_image(24, 16, 3, |x, y, _| [x as f32 * 0.3, y as f32 * 0.2, 2.0]);
    let t = HdrImage {
        data: r.data.iter().map(|v| v * 1.1).collect(),
        ..r.clone()
    };
    let (r, t) = (LoadedImage::Hdr(r), LoadedImage::Hdr(t));
    let c = tessera_metrics::diff_images(&r, &t).unwrap();
    let g = tessera_metrics_gpu::diff_images(&mut gpu, &r, &t).unwrap();
    assert_eq!(g.exposure_range, c.exposure_range);
    let (gh, ch) = (g.flip_hdr.unwrap(), c.flip_hdr.unwrap());
    assert!(
        (gh.mean - ch.mean).abs() <= FLIP_MEAN_ABS,
        "{} vs {}",
        gh.mean,
        ch.mean
    );
    eprintln!("max deviation: diff report flip percentiles {worst_percentile:e}");
}
