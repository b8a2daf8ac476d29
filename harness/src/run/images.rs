//! Saved images of a variant: its output frames, the reference's, and a technique's extra images
//! (e.g. adaptive shading's rate image), as PNG under the run folder, recorded in the result.

use std::path::Path;

use tessera_metrics::Rgb8Image;
use tessera_results::{ImageRecord, VariantResult};

use super::captured::MetricInputs;
use crate::render::renderer::FrameExtras;

/// Saves the frames chosen to be saved (`saved`: measured-frame index and image, as the capture
/// kept them) as `<variant>-fNNN.png` (or `reference-fNNN.png`) under `dir`, recorded in
/// `result` with `kind`.
pub fn save_frames(
    result: &mut VariantResult,
    saved: &[(u32, Rgb8Image)],
    dir: &Path,
    run_dir: &Path,
    kind: &str,
) {
    if saved.is_empty() {
        return;
    }
    let _ = std::fs::create_dir_all(dir);
    let stem = if kind == "reference" {
        "reference".to_string()
    } else {
        sanitize(&result.variant)
    };
    for (f, img) in saved {
        let path = dir.join(format!("{stem}-f{f:03}.png"));
        save_image(result, img, &path, run_dir, *f, kind);
    }
}

/// The per-pixel error maps of each saved frame against the reference, as images of the result:
/// the FLIP map in magma (kind `heatmap`, `<variant>-flip-fNNN.png`, as `tessera diff --heatmap`
/// writes it) always, and the HDR-FLIP map (kind `heatmap-hdr`, `<variant>-flip-hdr-fNNN.png`)
/// when the scenario measures `flip-hdr` (`hdr`). A map that cannot be computed (sizes differ) is
/// left out: the metrics report that.
pub fn save_error_maps(
    result: &mut VariantResult,
    inputs: &MetricInputs<'_>,
    save_frames: &[u32],
    hdr: bool,
    dir: &Path,
    run_dir: &Path,
) {
    let stem = sanitize(&result.variant);
    let ppd = tessera_metrics::DEFAULT_PIXELS_PER_DEGREE;
    for &f in save_frames {
        let i = f as usize;
        let (Some(r), Some(t)) = (inputs.reference.frames.get(i), inputs.test.get(i)) else {
            continue;
        };
        let _ = std::fs::create_dir_all(dir);
        if let Ok(map) = tessera_metrics::flip_ldr(r, t, ppd) {
            let path = dir.join(format!("{stem}-flip-f{f:03}.png"));
            let img = tessera_metrics::flip_heatmap(&map);
            save_image(result, &img, &path, run_dir, f, "heatmap");
        }
        let hdr_pair = (
            inputs.reference.hdr.get(i),
            inputs.test_hdr.get(i),
            inputs.reference.exposures.get(i),
        );
        if let (true, (Some(rh), Some(th), Some(range))) = (hdr, hdr_pair) {
            if let Ok(map) = tessera_metrics::flip_hdr(rh, th, range, ppd) {
                let path = dir.join(format!("{stem}-flip-hdr-f{f:03}.png"));
                let img = tessera_metrics::flip_heatmap(&map);
                save_image(result, &img, &path, run_dir, f, "heatmap-hdr");
            }
        }
    }
}

/// FLIP heat maps a metrics back end already made (the GPU's), named and recorded as
/// [`save_error_maps`] names and records its own.
pub fn save_heatmaps(
    result: &mut VariantResult,
    maps: &[super::evaluate::ErrorMap],
    dir: &Path,
    run_dir: &Path,
) {
    if maps.is_empty() {
        return;
    }
    let _ = std::fs::create_dir_all(dir);
    let stem = sanitize(&result.variant);
    for m in maps {
        let infix = if m.kind == "heatmap-hdr" {
            "flip-hdr"
        } else {
            "flip"
        };
        let path = dir.join(format!("{stem}-{infix}-f{:03}.png", m.frame));
        save_image(result, &m.image, &path, run_dir, m.frame, m.kind);
    }
}

/// The `cvvdp` distortion maps of saved frames, as `<variant>-cvvdp-fNNN.png` (kind `cvvdp`).
pub fn save_cvvdp_maps(
    result: &mut VariantResult,
    maps: &[tessera_metrics::DistortionMap],
    dir: &Path,
    run_dir: &Path,
) {
    if maps.is_empty() {
        return;
    }
    let _ = std::fs::create_dir_all(dir);
    let stem = sanitize(&result.variant);
    for m in maps {
        let path = dir.join(format!("{stem}-cvvdp-f{:03}.png", m.frame));
        let img = tessera_metrics::cvvdp_heatmap(m);
        save_image(result, &img, &path, run_dir, m.frame as u32, "cvvdp");
    }
}

/// Writes one PNG and records it (path relative to the run folder); a failed write is left out.
fn save_image(
    result: &mut VariantResult,
    img: &Rgb8Image,
    path: &Path,
    run_dir: &Path,
    frame: u32,
    kind: &str,
) {
    if tessera_metrics::save_png(path, img).is_ok() {
        let rel = path
            .strip_prefix(run_dir)
            .unwrap_or(path)
            .to_string_lossy()
            .replace('\\', "/");
        result.images.push(ImageRecord {
            frame,
            kind: kind.to_string(),
            path: rel,
        });
    }
}

/// A variant name as a file name: `upscale[scale=0.5]` → `upscale_scale=0.5_`.
pub fn sanitize(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "-_.=".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Saves the extra images of saved frames (e.g. `rate`) as `<variant>-<kind>-fNNN.png`.
pub fn save_extras(
    result: &mut VariantResult,
    extras: &[FrameExtras],
    save_frames: &[u32],
    dir: &Path,
    run_dir: &Path,
) {
    let stem = sanitize(&result.variant);
    for &f in save_frames {
        let Some(e) = extras.get(f as usize) else {
            continue;
        };
        for (kind, img) in &e.images {
            let _ = std::fs::create_dir_all(dir);
            let path = dir.join(format!("{stem}-{kind}-f{f:03}.png"));
            save_image(result, img, &path, run_dir, f, kind);
        }
    }
}
