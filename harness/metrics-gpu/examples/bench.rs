//! GPU metric timings, in a form that can be committed: per metric group the GPU time from
//! timestamp queries and the wall time of the whole request (record, submit, wait, read back),
//! median over `--iterations` after one warm-up, for generated pairs already on the device.
//!
//! ```text
//! cargo run --release -p tessera-metrics-gpu --example bench -- --adapter nvidia
//! cargo run --release -p tessera-metrics-gpu --example bench -- --size 256x144 --iterations 3
//! cargo run --release -p tessera-metrics-gpu --example bench -- --adapter nvidia --only cvvdp \
//!     --size 1920x1080 --size 3840x2160 --display paper_27in_4k
//! ```
//!
//! Options: `--adapter NAME` (substring of name, driver or backend; default: the first discrete
//! GPU, else any), `--size WxH` (repeatable; default 1920x1080 and 3840x2160), `--iterations N`
//! (default 10), `--cpu` (also time the CPU reference once per size, slow at 4K), `--only
//! cvvdp|pair` (one half of the table), and for ColorVideoVDP `--display NAME` (default
//! `standard_4k`), `--frames N` (default 8) and `--fps F` (default 60). ColorVideoVDP's rows are
//! per frame: the GPU ms of one frame's passes (timestamps, median over the frames of the
//! iterations) and the wall ms of the whole call divided by its frames (packing and uploading
//! the 8-bit frames, the passes, the readback of the partial sums, pooling).

use std::time::Instant;

use tessera_metrics::{
    hdr_exposure_range, CvvdpSettings, DisplaySpec, Frames, HdrImage, Rgb8Image,
    DEFAULT_PIXELS_PER_DEGREE,
};
use tessera_metrics_gpu::{
    CpuMetrics, FlipHdrRequest, FlipPooling, FlipRequest, GpuFrame, GpuMetrics, MetricsBackend,
    Pair, PairRequest,
};

struct Args {
    adapter: Option<String>,
    sizes: Vec<(u32, u32)>,
    iterations: usize,
    cpu: bool,
    only: Option<String>,
    display: String,
    frames: usize,
    fps: f64,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        adapter: None,
        sizes: Vec::new(),
        iterations: 10,
        cpu: false,
        only: None,
        display: tessera_metrics::DEFAULT_DISPLAY.into(),
        frames: 8,
        fps: 60.0,
    };
    let mut it = std::env::args().skip(1);
    while let Some(arg) = it.next() {
        let mut value = |name: &str| it.next().ok_or(format!("{name} needs a value"));
        match arg.as_str() {
            "--adapter" => a.adapter = Some(value("--adapter")?),
            "--size" => {
                let v = value("--size")?;
                let (w, h) = v
                    .split_once('x')
                    .and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?)))
                    .filter(|&(w, h): &(u32, u32)| w >= 11 && h >= 11)
                    .ok_or(format!(
                        "--size {v}: expected WxH, both at least 11, e.g. 1920x1080"
                    ))?;
                a.sizes.push((w, h));
            }
            "--iterations" => {
                let v = value("--iterations")?;
                a.iterations = v
                    .parse()
                    .ok()
                    .filter(|&n| n > 0)
                    .ok_or(format!("--iterations {v}: expected a positive integer"))?;
            }
            "--cpu" => a.cpu = true,
            "--only" => {
                let v = value("--only")?;
                if v != "cvvdp" && v != "pair" {
                    return Err(format!("--only {v}: expected cvvdp or pair"));
                }
                a.only = Some(v);
            }
            "--display" => {
                let v = value("--display")?;
                DisplaySpec::parse(&v).map_err(|e| format!("--display {v}: {e}"))?;
                a.display = v;
            }
            "--frames" => {
                let v = value("--frames")?;
                a.frames = v
                    .parse()
                    .ok()
                    .filter(|&n| n > 0)
                    .ok_or(format!("--frames {v}: expected a positive integer"))?;
            }
            "--fps" => {
                let v = value("--fps")?;
                a.fps = v
                    .parse()
                    .ok()
                    .filter(|&f: &f64| f > 0.0 && f <= 16384.0)
                    .ok_or(format!(
                        "--fps {v}: expected frames per second in (0, 16384]"
                    ))?;
            }
            "-h" | "--help" => {
                println!(
                    "usage: bench [--adapter NAME] [--size WxH]... [--iterations N] [--cpu] \
                     [--only cvvdp|pair] [--display NAME] [--frames N] [--fps F]"
                );
                std::process::exit(0);
            }
            other => return Err(format!("unknown argument {other}; see --help")),
        }
    }
    if a.sizes.is_empty() {
        a.sizes = vec![(1920, 1080), (3840, 2160)];
    }
    Ok(a)
}

/// A rendered-looking frame: gradients, edges and fine texture; the test adds noise and an offset.
fn frames(w: u32, h: u32) -> (Rgb8Image, Rgb8Image, HdrImage, HdrImage) {
    let mut s = 12345u32;
    let mut rnd = move || {
        s = s.wrapping_mul(1664525).wrapping_add(1013904223);
        (s >> 8) as f32 / (1u32 << 24) as f32
    };
    let n = (w * h) as usize;
    let mut r = Vec::with_capacity(3 * n);
    let mut t = Vec::with_capacity(3 * n);
    for y in 0..h {
        for x in 0..w {
            let (u, v) = (x as f32 / w as f32, y as f32 / h as f32);
            let check = if (x / 32 + y / 32) % 2 == 0 { 0.8 } else { 0.2 };
            let texture = 0.5 + 0.5 * ((x as f32 * 0.7).sin() * (y as f32 * 0.45).cos());
            let c = [u * check, v * texture, 0.3 * check + 0.2 * texture];
            for (i, c) in c.into_iter().enumerate() {
                let hdr = c * if i == 0 { 4.0 } else { 1.5 };
                r.push(hdr);
                t.push(hdr * (0.97 + 0.06 * rnd()));
            }
        }
    }
    let (rh, th) = (
        HdrImage {
            width: w,
            height: h,
            data: r,
        },
        HdrImage {
            width: w,
            height: h,
            data: t,
        },
    );
    (
        tessera_metrics::encode_srgb8(&rh),
        tessera_metrics::encode_srgb8(&th),
        rh,
        th,
    )
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn clocks() -> Option<String> {
    let out = std::process::Command::new("nvidia-smi")
        .args([
            "--query-gpu=name,driver_version,clocks.gr,clocks.mem,clocks.max.gr",
            "--format=csv,noheader",
        ])
        .output()
        .ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn main() {
    let args = match parse_args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let adapter = match tessera_metrics_gpu::select_adapter(args.adapter.as_deref()) {
        Ok(a) => a,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let info = adapter.get_info();
    let device = match tessera_metrics_gpu::open(adapter) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let mut gpu = GpuMetrics::new(&device.device, &device.queue, &info.name);
    println!("# tessera-metrics-gpu bench");
    println!(
        "adapter: {} ({}, {:?}); driver: {} {}",
        info.name,
        info.backend.to_str(),
        info.device_type,
        info.driver,
        info.driver_info
    );
    if let Some(c) = clocks() {
        println!("nvidia-smi (name, driver, clocks.gr, clocks.mem, clocks.max.gr): {c}");
    }
    let timestamps = device
        .device
        .features()
        .contains(wgpu::Features::TIMESTAMP_QUERY);
    println!(
        "timestamps: {}; iterations: {} (median, after 1 warm-up); frames already on the device",
        if timestamps {
            "yes"
        } else {
            "no (GPU ms not available)"
        },
        args.iterations
    );
    println!();
    println!("| size | request | GPU ms per group (median) | GPU ms total | wall ms |");
    println!("|---|---|---|---:|---:|");
    for &(w, h) in &args.sizes {
        if args.only.as_deref() != Some("pair") {
            cvvdp_rows(&mut gpu, &args, w, h);
        }
        if args.only.as_deref() == Some("cvvdp") {
            continue;
        }
        let (rl, tl, rh, th) = frames(w, h);
        let upload = |gpu: &GpuMetrics, l, h| gpu.upload(l, Some(h));
        let (r, t): (GpuFrame, GpuFrame) = match (upload(&gpu, &rl, &rh), upload(&gpu, &tl, &th)) {
            (Ok(r), Ok(t)) => (r, t),
            (Err(e), _) | (_, Err(e)) => {
                println!("| {w}x{h} | - | skipped: {e} | | |");
                continue;
            }
        };
        let range = hdr_exposure_range(&rh);
        let ppd = DEFAULT_PIXELS_PER_DEGREE;
        let flip = Some(FlipRequest {
            pixels_per_degree: ppd,
            heatmap: false,
            pooling: FlipPooling::Exact,
        });
        let requests: Vec<(&str, PairRequest)> = vec![
            (
                "psnr (rgb+luma) + max-abs",
                PairRequest {
                    mse_rgb: true,
                    mse_luma: true,
                    max_abs: true,
                    ..Default::default()
                },
            ),
            (
                "ssim (rgb+luma)",
                PairRequest {
                    ssim_rgb: true,
                    ssim_luma: true,
                    ..Default::default()
                },
            ),
            (
                "flip (ldr)",
                PairRequest {
                    flip: flip.clone(),
                    ..Default::default()
                },
            ),
            (
                "flip (ldr, flip-evaluator pooling: map read back)",
                PairRequest {
                    flip: Some(FlipRequest {
                        pooling: FlipPooling::FlipEvaluator,
                        ..flip.clone().unwrap()
                    }),
                    ..Default::default()
                },
            ),
            (
                "psnr + ssim + flip",
                PairRequest {
                    mse_rgb: true,
                    ssim_rgb: true,
                    flip: flip.clone(),
                    ..Default::default()
                },
            ),
            ("all ldr metrics", PairRequest::all_ldr(ppd)),
            (
                "flip-hdr",
                PairRequest {
                    flip_hdr: Some(FlipHdrRequest {
                        range,
                        pixels_per_degree: ppd,
                        heatmap: false,
                        pooling: FlipPooling::Exact,
                    }),
                    ..Default::default()
                },
            ),
        ];
        for (name, req) in &requests {
            let name = if name == &"flip-hdr" {
                format!("flip-hdr ({} exposures)", range.count)
            } else {
                name.to_string()
            };
            let mut wall = Vec::new();
            let mut groups: Vec<(&'static str, Vec<f64>)> = Vec::new();
            let mut failed = None;
            for i in 0..=args.iterations {
                let start = Instant::now();
                if let Err(e) = gpu.evaluate(&r, &t, req) {
                    failed = Some(e);
                    break;
                }
                let ms = start.elapsed().as_secs_f64() * 1e3;
                if i == 0 {
                    continue;
                }
                wall.push(ms);
                for &(g, v) in gpu.last_gpu_ms() {
                    match groups.iter_mut().find(|(n, _)| *n == g) {
                        Some((_, list)) => list.push(v),
                        None => groups.push((g, vec![v])),
                    }
                }
            }
            if let Some(e) = failed {
                println!("| {w}x{h} | {name} | failed: {e} | | |");
                continue;
            }
            let per: Vec<(&str, f64)> = groups.into_iter().map(|(g, v)| (g, median(v))).collect();
            let total: f64 = per.iter().map(|(_, v)| v).sum();
            let per_text = per
                .iter()
                .map(|(g, v)| format!("{g} {v:.3}"))
                .collect::<Vec<_>>()
                .join(", ");
            let total_text = if per.is_empty() {
                "-".into()
            } else {
                format!("{total:.3}")
            };
            println!(
                "| {w}x{h} | {name} | {} | {total_text} | {:.3} |",
                if per_text.is_empty() {
                    "-".into()
                } else {
                    per_text
                },
                median(wall)
            );
        }
        // Sequence metrics: flicker (frame vs previous) and TDE (with a motion field).
        let motion = vec![[0.5f32, 0.25]; (w * h) as usize];
        let valid = vec![true; (w * h) as usize];
        for which in ["flicker", "tde"] {
            let mut wall = Vec::new();
            let mut gpu_ms = Vec::new();
            for i in 0..=args.iterations {
                let start = Instant::now();
                let ok = if which == "flicker" {
                    gpu.flicker_frames(&r, &t).is_ok()
                } else {
                    gpu.tde_frames(&r, &t, &r, &t, &motion, &valid).is_ok()
                };
                let ms = start.elapsed().as_secs_f64() * 1e3;
                if ok && i > 0 {
                    wall.push(ms);
                    gpu_ms.extend(gpu.last_gpu_ms().iter().map(|(_, v)| *v));
                }
            }
            if wall.is_empty() {
                println!("| {w}x{h} | {which} | failed | | |");
                continue;
            }
            let g = if gpu_ms.is_empty() {
                "-".into()
            } else {
                format!("{:.3}", median(gpu_ms))
            };
            let note = if which == "tde" {
                " (includes motion upload)"
            } else {
                ""
            };
            println!(
                "| {w}x{h} | {which}{note} | {which} {g} | {g} | {:.3} |",
                median(wall)
            );
        }
        if args.cpu {
            let pair = Pair {
                reference: &rl,
                test: &tl,
                reference_hdr: Some(&rh),
                test_hdr: Some(&th),
            };
            for (name, req) in &requests[..6] {
                let start = Instant::now();
                let ok = CpuMetrics.pair(pair, req).is_ok();
                let ms = start.elapsed().as_secs_f64() * 1e3;
                println!(
                    "| {w}x{h} | cpu: {name} | - | - | {} |",
                    if ok {
                        format!("{ms:.1}")
                    } else {
                        "failed".into()
                    }
                );
            }
        }
    }
}

/// ColorVideoVDP rows: an image pair, and a video of `--frames` frames whose content moves and
/// whose test has visible noise (+-12 codes) on top of the pair's.
fn cvvdp_rows(gpu: &mut GpuMetrics, args: &Args, w: u32, h: u32) {
    let (rl, mut tl, _, _) = frames(w, h);
    let mut s = 777u32;
    for v in &mut tl.data {
        s = s.wrapping_mul(1664525).wrapping_add(1013904223);
        *v = (*v as i32 + (s >> 24) as i32 % 25 - 12).clamp(0, 255) as u8;
    }
    let shift = |img: &Rgb8Image, dx: u32| {
        let mut out = img.clone();
        for y in 0..h {
            for x in 0..w {
                let s = ((y * w + (x + dx) % w) * 3) as usize;
                let d = ((y * w + x) * 3) as usize;
                out.data[d..d + 3].copy_from_slice(&img.data[s..s + 3]);
            }
        }
        out
    };
    let reference: Vec<Rgb8Image> = (0..args.frames as u32).map(|f| shift(&rl, 2 * f)).collect();
    let test: Vec<Rgb8Image> = (0..args.frames as u32).map(|f| shift(&tl, 2 * f)).collect();
    let settings = CvvdpSettings {
        display: DisplaySpec::parse(&args.display).unwrap_or_default(),
        fps: args.fps,
        ..CvvdpSettings::default()
    };
    let cases = [
        ("image".to_string(), 1),
        (
            format!("video, {} frames at {} fps", args.frames, args.fps),
            args.frames,
        ),
    ];
    for (what, n) in cases {
        let name = format!("cvvdp {what} ({}), per frame", args.display);
        let (r, t) = (Frames::Srgb(&reference[..n]), Frames::Srgb(&test[..n]));
        let mut wall = Vec::new();
        let mut gpu_ms = Vec::new();
        let mut jod = 0.0;
        for i in 0..=args.iterations {
            let start = Instant::now();
            match gpu.cvvdp(r, t, &settings) {
                Ok(result) => jod = result.jod,
                Err(e) => {
                    println!("| {w}x{h} | {name} | failed: {e} | | |");
                    return;
                }
            }
            let ms = start.elapsed().as_secs_f64() * 1e3 / n as f64;
            if i > 0 {
                wall.push(ms);
                gpu_ms.extend_from_slice(gpu.last_cvvdp_frame_ms());
            }
        }
        let g = if gpu_ms.is_empty() {
            "-".into()
        } else {
            format!("{:.3}", median(gpu_ms))
        };
        println!(
            "| {w}x{h} | {name}: {jod:.4} JOD | cvvdp {g} | {g} | {:.3} |",
            median(wall)
        );
        if args.cpu {
            let start = Instant::now();
            let cpu = tessera_metrics::cvvdp(r, t, &settings);
            let ms = start.elapsed().as_secs_f64() * 1e3 / n as f64;
            match cpu {
                Ok(c) => println!(
                    "| {w}x{h} | cpu: {name}: {:.4} JOD | - | - | {ms:.1} |",
                    c.jod
                ),
                Err(e) => println!("| {w}x{h} | cpu: {name} | failed: {e} | | |"),
            }
        }
    }
}
