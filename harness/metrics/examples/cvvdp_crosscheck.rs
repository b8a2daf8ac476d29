//! The Rust side of `tools/crosscheck_cvvdp.py`: reads the cases the script generated (raw 8-bit
//! sRGB or f32 cd/m² frames and `manifest.json`), computes ColorVideoVDP with `cvvdp()` and writes
//! `rust.json` beside them.
//!
//! Usage: `cargo run --release -p tessera-metrics --example cvvdp_crosscheck -- DIR`

use serde_json::{json, Value};
use std::path::Path;
use std::time::Instant;
use tessera_metrics::*;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::args()
        .nth(1)
        .ok_or("usage: cvvdp_crosscheck DIR")?;
    let dir = Path::new(&dir);
    let manifest: Vec<Value> =
        serde_json::from_str(&std::fs::read_to_string(dir.join("manifest.json"))?)?;
    let mut cases = serde_json::Map::new();
    for case in &manifest {
        let name = case["name"].as_str().ok_or("case without name")?;
        let (w, h, n) = (
            case["width"].as_u64().ok_or("width")? as u32,
            case["height"].as_u64().ok_or("height")? as u32,
            case["frames"].as_u64().ok_or("frames")? as usize,
        );
        let fps = case["fps"].as_f64().unwrap_or(0.0);
        let settings = CvvdpSettings {
            display: DisplaySpec::parse(case["display_spec"].as_str().ok_or("display_spec")?)?,
            fps: if fps > 0.0 { fps } else { 60.0 },
            ..CvvdpSettings::default()
        };
        let px = (w * h * 3) as usize;
        let read = |which: &str| std::fs::read(dir.join(format!("{name}.{which}")));
        let (r, t) = (read("ref")?, read("test")?);
        let start = Instant::now();
        let result = if case["kind"] == "srgb" {
            let frames = |b: &[u8]| -> Vec<Rgb8Image> {
                b.chunks(px)
                    .map(|c| Rgb8Image {
                        width: w,
                        height: h,
                        data: c.to_vec(),
                    })
                    .collect()
            };
            let (r, t) = (frames(&r), frames(&t));
            assert_eq!(r.len(), n);
            cvvdp(Frames::Srgb(&r), Frames::Srgb(&t), &settings)?
        } else {
            // Already absolute cd/m²: shown at 1 cd/m² per unit.
            let frames = |b: &[u8]| -> Vec<HdrImage> {
                b.chunks(px * 4)
                    .map(|c| HdrImage {
                        width: w,
                        height: h,
                        data: c
                            .chunks(4)
                            .map(|v| f32::from_le_bytes([v[0], v[1], v[2], v[3]]))
                            .collect(),
                    })
                    .collect()
            };
            let (r, t) = (frames(&r), frames(&t));
            assert_eq!(r.len(), n);
            let white = 1.0;
            cvvdp(
                Frames::Linear { frames: &r, white },
                Frames::Linear { frames: &t, white },
                &settings,
            )?
        };
        let seconds = start.elapsed().as_secs_f64();
        println!("{name:<26} {:.6} JOD  {seconds:.3} s", result.jod);
        cases.insert(
            name.to_owned(),
            json!({
                "jod": result.jod,
                "frame_jod": result.frame_jod,
                "flicker_jod": result.flicker_jod,
                "transient_share": result.transient_share,
                "ppd": result.pixels_per_degree,
                "seconds": seconds,
            }),
        );
    }
    let out = json!({ "threads": rayon_threads(), "cases": cases });
    std::fs::write(dir.join("rust.json"), serde_json::to_string_pretty(&out)?)?;
    Ok(())
}

fn rayon_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}
