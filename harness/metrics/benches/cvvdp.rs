//! Criterion benchmark: ColorVideoVDP of a test sequence against its reference, at the two sizes
//! the issue names: 8 frames of 1920x1080 and 60 frames of 960x540, both at 60 fps on
//! `standard_4k`, without distortion maps (the harness asks for maps of saved frames only).
//!
//! Run: `cargo bench -p tessera-metrics --bench cvvdp`. One iteration takes seconds, so every
//! sample is one iteration (flat sampling) and there are 10 of them (criterion's minimum); the
//! README records the figures. CI compiles this benchmark (clippy `--all-targets`) but never
//! runs it.

use criterion::{criterion_group, criterion_main, Criterion, SamplingMode};
use std::time::Duration;
use tessera_metrics::*;

/// A rendered-like frame whose bright box moves 4 pixels a frame; `seed` changes the noise.
fn frame(width: u32, height: u32, t: u32, seed: u32) -> Rgb8Image {
    let mut s = seed.wrapping_mul(2654435761).wrapping_add(t);
    let mut data = Vec::with_capacity((width * height * 3) as usize);
    for y in 0..height {
        for x in 0..width {
            s = s.wrapping_mul(1664525).wrapping_add(1013904223);
            let noise = (s >> 29) as i32 - 4;
            let (u, v) = (x as f32 / width as f32, y as f32 / height as f32);
            let bx = (x + 4 * t) % width;
            let inside = bx > width / 3 && bx < width / 2 && y > height / 3 && y < height / 2;
            let checker = ((x / 32 + y / 32) % 2) as f32;
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
    let settings = CvvdpSettings {
        fps: 60.0,
        ..CvvdpSettings::default()
    };
    let mut g = c.benchmark_group("cvvdp");
    g.sampling_mode(SamplingMode::Flat)
        .sample_size(10)
        .warm_up_time(Duration::from_millis(1))
        .measurement_time(Duration::from_secs(1));
    for (name, w, h, n) in [
        ("8 frames 1920x1080", 1920, 1080, 8),
        ("60 frames 960x540", 960, 540, 60),
    ] {
        let reference: Vec<Rgb8Image> = (0..n).map(|t| frame(w, h, t, 1)).collect();
        let test: Vec<Rgb8Image> = (0..n).map(|t| frame(w, h, t, 2 + t % 2)).collect();
        g.bench_function(name, |b| {
            b.iter(|| cvvdp(Frames::Srgb(&reference), Frames::Srgb(&test), &settings).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
