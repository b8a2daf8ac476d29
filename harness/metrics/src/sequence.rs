//! Image sequences for `tessera diff`: finding numbered frames on disk, and every metric of a
//! reference/test sequence pair (the per-frame metrics averaged, plus ColorVideoVDP of the whole).
//!
//! For: comparing two folders of numbered PNG/EXR/HDR frames, or two variants of a run folder.
//! Not for: decoding one image (see `io`) or computing a metric (each has its module).

use crate::{
    cvvdp, diff_images, load_image, psnr_from_mse, CvvdpResult, CvvdpSettings, DiffReport, Frames,
    HdrImage, LoadedImage, MetricsError, Rgb8Image, DATA_RANGE_8BIT, DEFAULT_HDR_WHITE,
};
use serde::Serialize;
use std::fmt::Write;
use std::path::{Path, PathBuf};

const EXTENSIONS: [&str; 3] = ["png", "exr", "hdr"];

/// The frame files of a sequence, in frame order.
///
/// `path` is either a folder (every PNG/EXR/HDR file in it whose name holds a number; the last
/// number in the name is the frame number), or a run folder's variant stem `DIR/<variant>` that
/// names no file itself: then the files `DIR/<variant>-fNNN.png` that `tessera run` saves.
pub fn load_sequence(path: &Path) -> Result<Vec<(u64, PathBuf)>, MetricsError> {
    let (dir, prefix) = if path.is_dir() {
        (path.to_path_buf(), None)
    } else {
        let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
        let stem = path
            .file_name()
            .map(|s| format!("{}-f", s.to_string_lossy()));
        (dir, stem)
    };
    let entries = std::fs::read_dir(&dir).map_err(|source| MetricsError::Io {
        action: "read folder",
        path: dir.clone(),
        source,
    })?;
    let mut frames = Vec::new();
    for entry in entries.flatten() {
        let p = entry.path();
        let ext = p
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        if !p.is_file() || !ext.is_some_and(|e| EXTENSIONS.contains(&e.as_str())) {
            continue;
        }
        let stem = p
            .file_stem()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned();
        let number = match &prefix {
            Some(prefix) => stem
                .strip_prefix(prefix.as_str())
                .filter(|rest| !rest.is_empty() && rest.bytes().all(|b| b.is_ascii_digit()))
                .and_then(|rest| rest.parse().ok()),
            None => last_number(&stem),
        };
        if let Some(n) = number {
            frames.push((n, p));
        }
    }
    if frames.is_empty() {
        return Err(MetricsError::NoFrames {
            path: path.to_path_buf(),
        });
    }
    frames.sort();
    if let Some(w) = frames.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(MetricsError::DuplicateFrame {
            number: w[0].0,
            first: w[0].1.clone(),
            second: w[1].1.clone(),
        });
    }
    Ok(frames)
}

/// The frames of [`load_sequence`], decoded, in frame order.
pub fn load_sequence_images(path: &Path) -> Result<Vec<LoadedImage>, MetricsError> {
    load_sequence(path)?
        .iter()
        .map(|(_, p)| load_image(p))
        .collect()
}

/// [`diff_sequences`] of two sequences on disk (see [`load_sequence`] for what a path may be).
pub fn diff_sequence_paths(
    reference: &Path,
    test: &Path,
    settings: &CvvdpSettings,
) -> Result<SequenceReport, MetricsError> {
    let (r, t) = (
        load_sequence_images(reference)?,
        load_sequence_images(test)?,
    );
    diff_sequences(&r, &t, settings)
}

fn last_number(stem: &str) -> Option<u64> {
    let end = stem.rfind(|c: char| c.is_ascii_digit())? + 1;
    let start = stem[..end]
        .rfind(|c: char| !c.is_ascii_digit())
        .map_or(0, |i| i + 1);
    stem[start..end].parse().ok()
}

/// Every metric of a reference/test sequence pair.
#[derive(Debug, Clone, Serialize)]
pub struct SequenceReport {
    pub frames: usize,
    pub width: u32,
    pub height: u32,
    /// PSNR of the MSE averaged over frames, dB (`null` when every frame is identical).
    pub psnr_rgb: Option<f64>,
    /// Mean over frames of SSIM (RGB); `None` below 11x11 pixels.
    pub ssim_rgb: Option<f64>,
    /// Mean over frames of the mean LDR-FLIP.
    pub flip_mean: f64,
    /// Mean over frames of the mean HDR-FLIP (linear inputs only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub flip_hdr_mean: Option<f64>,
    pub cvvdp: CvvdpResult,
}

/// Every metric of two decoded sequences of one kind (8/16-bit PNG, or linear HDR). 16-bit PNGs
/// reach ColorVideoVDP rounded to 8 bits; linear frames are shown at [`DEFAULT_HDR_WHITE`]
/// cd/m² per unit.
pub fn diff_sequences(
    reference: &[LoadedImage],
    test: &[LoadedImage],
    settings: &CvvdpSettings,
) -> Result<SequenceReport, MetricsError> {
    diff_sequences_with(reference, test, settings, diff_images)
}

/// [`diff_sequences`] with the per-frame report computed by `pair` (another back end's
/// `diff_images`, e.g. the GPU's); ColorVideoVDP and the averaging stay here.
pub fn diff_sequences_with<E: From<MetricsError>>(
    reference: &[LoadedImage],
    test: &[LoadedImage],
    settings: &CvvdpSettings,
    mut pair: impl FnMut(&LoadedImage, &LoadedImage) -> Result<DiffReport, E>,
) -> Result<SequenceReport, E> {
    if reference.is_empty() || reference.len() != test.len() {
        return Err(MetricsError::SequenceLength {
            reference: reference.len(),
            test: test.len(),
        }
        .into());
    }
    let reports = reference
        .iter()
        .zip(test)
        .map(|(r, t)| pair(r, t))
        .collect::<Result<Vec<_>, _>>()?;
    let n = reports.len() as f64;
    let hdr = |s: &[LoadedImage]| -> Option<Vec<HdrImage>> {
        s.iter()
            .map(|i| match i {
                LoadedImage::Hdr(h) => Some(h.clone()),
                _ => None,
            })
            .collect()
    };
    let ldr = |s: &[LoadedImage]| -> Vec<Rgb8Image> {
        s.iter()
            .map(|i| match i {
                LoadedImage::Ldr(i) => i.clone(),
                LoadedImage::Ldr16(i) => i.to_rgb8(),
                LoadedImage::Hdr(h) => crate::encode_srgb8(h),
            })
            .collect()
    };
    // diff_images refused mixed kinds above, so both are HDR or neither is.
    let cvvdp = match (hdr(reference), hdr(test)) {
        (Some(r), Some(t)) => {
            let white = DEFAULT_HDR_WHITE;
            cvvdp(
                Frames::Linear { frames: &r, white },
                Frames::Linear { frames: &t, white },
                settings,
            )?
        }
        _ => {
            let (r, t) = (ldr(reference), ldr(test));
            cvvdp(Frames::Srgb(&r), Frames::Srgb(&t), settings)?
        }
    };
    let mse = reports.iter().map(|r| r.mse_rgb).sum::<f64>() / n;
    let range = if reports[0].bit_depth == 16 {
        crate::DATA_RANGE_16BIT
    } else {
        DATA_RANGE_8BIT
    };
    let ssim: Option<Vec<f64>> = reports.iter().map(|r| r.ssim_rgb).collect();
    let flip_hdr: Option<Vec<f64>> = reports
        .iter()
        .map(|r| r.flip_hdr.as_ref().map(|f| f.mean))
        .collect();
    Ok(SequenceReport {
        frames: reports.len(),
        width: reports[0].width,
        height: reports[0].height,
        psnr_rgb: Some(psnr_from_mse(mse, range)).filter(|v| v.is_finite()),
        ssim_rgb: ssim.map(|s| s.iter().sum::<f64>() / n),
        flip_mean: reports.iter().map(|r| r.flip.mean).sum::<f64>() / n,
        flip_hdr_mean: flip_hdr.map(|s| s.iter().sum::<f64>() / n),
        cvvdp,
    })
}

impl SequenceReport {
    /// Aligned, human-readable lines.
    pub fn to_text(&self) -> String {
        let c = &self.cvvdp;
        let mut rows = vec![
            (
                "frames".to_owned(),
                format!("{} of {}x{}", self.frames, self.width, self.height),
            ),
            (
                "PSNR (RGB)".to_owned(),
                self.psnr_rgb.map_or("inf (identical)".to_owned(), |v| {
                    format!("{v:.3} dB (MSE averaged over frames)")
                }),
            ),
            (
                "SSIM (RGB)".to_owned(),
                self.ssim_rgb
                    .map_or("n/a (needs 11x11 pixels)".to_owned(), |v| {
                        format!("{v:.6} (mean over frames)")
                    }),
            ),
            (
                "FLIP mean".to_owned(),
                format!("{:.6} (mean over frames)", self.flip_mean),
            ),
        ];
        if let Some(v) = self.flip_hdr_mean {
            rows.push(("HDR-FLIP mean".into(), format!("{v:.6} (mean over frames)")));
        }
        rows.push((
            "JOD".to_owned(),
            format!(
                "{:.4} (ColorVideoVDP 0.5.7; 10 = no visible difference, higher is better)",
                c.jod
            ),
        ));
        rows.push((
            "display".to_owned(),
            format!(
                "{}: {:.1} ppd, {} cd/m² peak, {} fps",
                c.display, c.pixels_per_degree, c.peak_luminance, c.fps
            ),
        ));
        if let (Some(f), Some(s)) = (c.flicker_jod, c.transient_share) {
            rows.push((
                "flicker".to_owned(),
                format!(
                    "{f:.4} JOD (transient channel alone), {:.1}% of the visible difference",
                    s * 100.0
                ),
            ));
        }
        if c.shots.len() > 1 {
            let shots: Vec<String> = c
                .shots
                .iter()
                .map(|s| format!("{}+{}: {:.4}", s.first_frame, s.frames, s.jod))
                .collect();
            rows.push(("shots".to_owned(), shots.join("  ")));
        }
        if c.frame_jod.len() > 1 {
            let (i, worst) =
                c.frame_jod
                    .iter()
                    .enumerate()
                    .fold(
                        (0, f64::INFINITY),
                        |a, (i, &v)| if v < a.1 { (i, v) } else { a },
                    );
            rows.push((
                "worst frame".to_owned(),
                format!("{i} at {worst:.4} JOD (per-frame JOD)"),
            ));
        }
        let mut s = String::new();
        for (label, value) in rows {
            let _ = writeln!(s, "{label:<14} {value}");
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_numbers_come_from_the_last_digits() {
        assert_eq!(last_number("frame_0012"), Some(12));
        assert_eq!(last_number("v2-f007"), Some(7));
        assert_eq!(last_number("12"), Some(12));
        assert_eq!(last_number("reference"), None);
    }

    #[test]
    fn folders_and_run_variant_stems_list_their_frames() {
        let dir = tempfile::tempdir().unwrap();
        let img = Rgb8Image::filled(8, 8, [10, 20, 30]);
        for name in [
            "cb-f002.png",
            "cb-f010.png",
            "cb-f001.png",
            "cb-motion-f001.png",
            "reference-f001.png",
        ] {
            crate::save_png(&dir.path().join(name), &img).unwrap();
        }
        std::fs::write(dir.path().join("notes.txt"), "x").unwrap();
        let cb = load_sequence(&dir.path().join("cb")).unwrap();
        let numbers: Vec<u64> = cb.iter().map(|f| f.0).collect();
        assert_eq!(numbers, [1, 2, 10]);
        assert_eq!(
            load_sequence(&dir.path().join("reference")).unwrap().len(),
            1
        );
        let e = load_sequence(dir.path()).unwrap_err();
        assert!(e.to_string().contains("both hold frame 1"), "{e}");
        let e = load_sequence(&dir.path().join("nothing")).unwrap_err();
        assert!(e.to_string().contains("no numbered"), "{e}");
    }
}
