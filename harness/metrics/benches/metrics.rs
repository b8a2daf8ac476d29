//! Criterion benchmark: every metric on one 1920x1080 pair (the harness's common frame size),
//! plus each metric alone to show where the time goes.
//!
//! Run: `cargo bench -p tessera-metrics --bench metrics`. The README records the figure for the
//! project's 2-core machine; the target is `diff` (all metrics) in at most 250 ms.

use criterion::{criterion_group, criterion_main, Criterion};
use tessera_metrics::*;

/// A rendered-like frame: gradients, hard-edged shapes and a little noise, deterministic.
fn frame(width: u32, height: u32, seed: u32) -> Rgb8Image {
    let mut s = seed;
    let mut data = Vec::with_capacity((width * height * 3) as usize);
    for y in 0..height {
        for x in 0..width {
            s = s.wrapping_mul(1664525).wrapping_add(1013904223);
            let noise = (s >> 29) as i32 - 4;
            let (u, v) = (x as f32 / width as f32, y as f32 / height as f32);
            let inside = ((u - 0.5) * (u - 0.5) * 3.0 + (v - 0.5) * (v - 0.5)) < 0.06;
            let checker = ((x / 64 + y / 64) % 2) as f32;
            let base = if inside {
                [220.0 * v, 90.0, 40.0 + 100.0 * u]
            } else {
                [60.0 + 120.0 * u, 80.0 + 100.0 * v, 90.0 + 60.0 * checker]
            };
            for c in base {
                data.push((c as i32 + noise).clamp(0, 255) as u8);
            }
        }
    }
    Rgb8Image {
        width,
        height,
        data,
    }
}

fn bench(c: &mut Criterion) {
    let reference = frame(1920, 1080, 1);
    let test = frame(1920, 1080, 2);
    let mut g = c.benchmark_group("1920x1080");
    g.sample_size(20);
    g.bench_function("diff (all metrics)", |b| {
        b.iter(|| diff(&reference, &test).unwrap())
    });
    g.bench_function("flip_ldr", |b| {
        b.iter(|| flip_ldr(&reference, &test, DEFAULT_PIXELS_PER_DEGREE).unwrap())
    });
    g.bench_function("ssim_rgb", |b| {
        b.iter(|| ssim_rgb(&reference, &test).unwrap())
    });
    g.bench_function("ssim_luma", |b| {
        b.iter(|| ssim_luma(&reference, &test).unwrap())
    });
    g.bench_function("psnr_rgb + psnr_luma + max_abs_error", |b| {
        b.iter(|| {
            (
                psnr_rgb(&reference, &test).unwrap(),
                psnr_luma(&reference, &test).unwrap(),
                max_abs_error(&reference, &test).unwrap(),
            )
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
