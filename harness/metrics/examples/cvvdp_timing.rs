//! CPU and wall time of one `cvvdp()` call on each workload of `benches/cvvdp.rs` (8 frames of
//! 1920x1080, 60 frames of 960x540, 60 fps, `standard_4k`), for a loaded machine where criterion's
//! wall-clock samples would mostly measure other people's builds.
//!
//! Usage: `RAYON_NUM_THREADS=1 cargo run --release -p tessera-metrics --example cvvdp_timing`.

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

/// The benchmark's frame: a box moving 4 pixels a frame over gradients; `seed` changes the noise.
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

fn main() {
    let settings = CvvdpSettings {
        fps: 60.0,
        ..CvvdpSettings::default()
    };
    for (name, w, h, n) in [
        ("8 frames 1920x1080", 1920, 1080, 8),
        ("60 frames 960x540", 960, 540, 60),
    ] {
        let reference: Vec<Rgb8Image> = (0..n).map(|t| frame(w, h, t, 1)).collect();
        let test: Vec<Rgb8Image> = (0..n).map(|t| frame(w, h, t, 2 + t % 2)).collect();
        let (cpu, wall) = (cpu_seconds(), Instant::now());
        let r = cvvdp(Frames::Srgb(&reference), Frames::Srgb(&test), &settings).unwrap();
        println!(
            "{name}: {:.2} s CPU, {:.2} s wall, {:.4} JOD",
            cpu_seconds() - cpu,
            wall.elapsed().as_secs_f64(),
            r.jod
        );
    }
}
