//! Computes every metric for the image pairs listed in a manifest and prints them as JSON, for
//! `tools/crosscheck.py` to compare with scikit-image and flip-evaluator.
//!
//! For: the optional cross-check only (not part of `cargo test`). Not for: production use; the
//! harness calls the library directly.
//!
//! Usage: `cargo run --release -p tessera-metrics --example crosscheck -- MANIFEST.json`, where
//! the manifest is a list of `{"name", "kind": "ldr" | "hdr", "reference", "test", "width",
//! "height"}`; LDR files are PNGs, HDR files raw little-endian f32 RGB.

use std::path::{Path, PathBuf};
use tessera_metrics::*;

fn read_raw(path: &Path, width: u32, height: u32) -> HdrImage {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let data = bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    HdrImage {
        width,
        height,
        data,
    }
}

fn read_png(path: &Path) -> Rgb8Image {
    match load_image(path).unwrap_or_else(|e| panic!("{e}")) {
        LoadedImage::Ldr(i) => i,
        LoadedImage::Ldr16(i) => i.to_rgb8(),
        LoadedImage::Hdr(_) => panic!("{} is not LDR", path.display()),
    }
}

/// Writes the FLIP error map as raw little-endian f32 to `DIR/NAME.flipmap.f32`.
fn write_map(dir: &Path, name: &str, f: &FlipResult) {
    let bytes: Vec<u8> = f.error_map.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(dir.join(format!("{name}.flipmap.f32")), bytes).unwrap();
}

fn flip_json(f: &FlipResult) -> serde_json::Value {
    serde_json::json!({"mean": f.mean, "exact_mean": f.exact_mean, "p50": f.p50, "p95": f.p95, "p99": f.p99, "max": f.max})
}

fn main() {
    let manifest = PathBuf::from(std::env::args().nth(1).expect("usage: crosscheck MANIFEST"));
    let dir = manifest.parent().unwrap().to_owned();
    let text = std::fs::read_to_string(&manifest).unwrap();
    let entries: Vec<serde_json::Value> = serde_json::from_str(&text).unwrap();
    let mut out = Vec::new();
    for e in entries {
        let name = e["name"].as_str().unwrap();
        let r = dir.join(e["reference"].as_str().unwrap());
        let t = dir.join(e["test"].as_str().unwrap());
        let result = if e["kind"] == "hdr" {
            let (w, h) = (
                e["width"].as_u64().unwrap() as u32,
                e["height"].as_u64().unwrap() as u32,
            );
            let (a, b) = (read_raw(&r, w, h), read_raw(&t, w, h));
            let range = hdr_exposure_range(&a);
            let f = flip_hdr(&a, &b, &range, DEFAULT_PIXELS_PER_DEGREE).unwrap();
            write_map(&dir, name, &f);
            serde_json::json!({"name": name, "range": range, "flip": flip_json(&f)})
        } else {
            let (a, b) = (read_png(&r), read_png(&t));
            let start = std::time::Instant::now();
            let report = diff(&a, &b).unwrap();
            let secs = start.elapsed().as_secs_f64();
            write_map(&dir, name, &report.flip);
            serde_json::json!({
                "name": name,
                "seconds": secs,
                "psnr_rgb": report.psnr_rgb,
                "psnr_luma": report.psnr_luma,
                "ssim_rgb": report.ssim_rgb,
                "ssim_luma": report.ssim_luma,
                "max_abs_error": report.max_abs_error,
                "flip": flip_json(&report.flip),
            })
        };
        out.push(result);
    }
    println!("{}", serde_json::to_string_pretty(&out).unwrap());
}
