//! Times each metric on a generated 1920x1080 pair (CPU time per call, for quick comparisons on
//! a loaded machine; criterion's `benches/metrics.rs` gives the reported figures).
//!
//! Usage: `RAYON_NUM_THREADS=1 cargo run --release -p tessera-metrics --example timing`.

use std::time::Instant;
use tessera_metrics::*;

fn cpu_seconds() -> f64 {
    // /proc/self/stat fields 14 and 15: user and system time in clock ticks (100 Hz).
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let fields: Vec<&str> = stat
        .rsplit(')')
        .next()
        .unwrap_or("")
        .split_whitespace()
        .collect();
    let ticks = |i: usize| {
        fields
            .get(i)
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (ticks(11) + ticks(12)) / 100.0
}

fn frame(width: u32, height: u32, seed: u32) -> Rgb8Image {
    let mut s = seed;
    let mut data = Vec::with_capacity((width * height * 3) as usize);
    for y in 0..height {
        for x in 0..width {
            s = s.wrapping_mul(1664525).wrapping_add(1013904223);
            let noise = (s >> 29) as i32 - 4;
            let v = ((x / 64 + y / 64) % 2) as i32 * 60 + (x * 100 / width) as i32;
            for c in [v, 255 - v, (y % 256) as i32] {
                data.push((c + noise).clamp(0, 255) as u8);
            }
        }
    }
    Rgb8Image {
        width,
        height,
        data,
    }
}

fn time<T>(name: &str, n: u32, f: impl Fn() -> T) {
    f();
    let (c0, w0) = (cpu_seconds(), Instant::now());
    for _ in 0..n {
        std::hint::black_box(f());
    }
    let (cpu, wall) = (
        (cpu_seconds() - c0) / n as f64,
        w0.elapsed().as_secs_f64() / n as f64,
    );
    println!(
        "{name:<12} cpu {:7.1} ms  wall {:7.1} ms",
        cpu * 1e3,
        wall * 1e3
    );
}

fn main() {
    let (a, b) = (frame(1920, 1080, 1), frame(1920, 1080, 2));
    time("flip_ldr", 5, || {
        flip_ldr(&a, &b, DEFAULT_PIXELS_PER_DEGREE).unwrap()
    });
    time("ssim_rgb", 5, || ssim_rgb(&a, &b).unwrap());
    time("ssim_luma", 5, || ssim_luma(&a, &b).unwrap());
    time("psnr+max", 5, || {
        (
            psnr_rgb(&a, &b).unwrap(),
            psnr_luma(&a, &b).unwrap(),
            max_abs_error(&a, &b).unwrap(),
        )
    });
    time("diff", 5, || diff(&a, &b).unwrap());
}
