//! Saved images of a variant: its output frames, the reference's, and a technique's extra images
//! (e.g. adaptive shading's rate image), as PNG under the run folder, recorded in the result; and
//! which frames those are beyond `frames.save`: each metric's worst frame ([`worst_frames`]).

use std::path::Path;

use tessera_metrics::Rgb8Image;
use tessera_results::{ImageRecord, MetricRecord, VariantResult};

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
    let images: Vec<Pending<'_>> = saved
        .iter()
        .map(|(f, img)| Pending {
            path: dir.join(format!("{stem}-f{f:03}.png")),
            image: std::borrow::Cow::Borrowed(img),
            frame: *f,
            kind: kind.to_string(),
        })
        .collect();
    write_all(result, images, run_dir);
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
    let maps = par_map(save_frames, |&f| {
        let i = f as usize;
        let mut out = Vec::new();
        let (Some(r), Some(t)) = (inputs.reference.frames.get(i), inputs.test.get(i)) else {
            return out;
        };
        if let Ok(map) = tessera_metrics::flip_ldr(r, t, ppd) {
            out.push(Pending::owned(
                dir.join(format!("{stem}-flip-f{f:03}.png")),
                tessera_metrics::flip_heatmap(&map),
                f,
                "heatmap",
            ));
        }
        let hdr_pair = (
            inputs.reference.hdr.get(i),
            inputs.test_hdr.get(i),
            inputs.reference.exposures.get(i),
        );
        if let (true, (Some(rh), Some(th), Some(range))) = (hdr, hdr_pair) {
            if let Ok(map) = tessera_metrics::flip_hdr(rh, th, range, ppd) {
                out.push(Pending::owned(
                    dir.join(format!("{stem}-flip-hdr-f{f:03}.png")),
                    tessera_metrics::flip_heatmap(&map),
                    f,
                    "heatmap-hdr",
                ));
            }
        }
        out
    });
    let _ = std::fs::create_dir_all(dir);
    write_all(result, maps.into_iter().flatten().collect(), run_dir);
}

/// Each metric's worst frame when the frames stayed on the device (GPU metrics): the output and
/// the reference frame are read back, saved as [`save_frames`] saves them, with the FLIP map of
/// the pair made by the device that holds them (the GPU back end's heat map, within 1 in 8 bits
/// of the CPU's: its cross-check; on a 4K frame the CPU map took about a second per frame).
/// Returns the reference frames read back, for the reference's images once per scenario.
pub fn save_worst_from_device(
    result: &mut VariantResult,
    backend: &mut tessera_metrics_gpu::GpuMetrics,
    test: &[tessera_metrics_gpu::GpuFrame],
    reference: &[tessera_metrics_gpu::GpuFrame],
    worst: &[u32],
    dir: &Path,
    run_dir: &Path,
) -> Vec<(u32, Rgb8Image)> {
    let stem = sanitize(&result.variant);
    let heatmap_only = tessera_metrics_gpu::PairRequest {
        flip: Some(tessera_metrics_gpu::FlipRequest {
            pixels_per_degree: tessera_metrics::DEFAULT_PIXELS_PER_DEGREE,
            heatmap: true,
            pooling: tessera_metrics_gpu::FlipPooling::Exact,
        }),
        ..Default::default()
    };
    let mut pairs: Vec<(u32, Rgb8Image, Rgb8Image)> = Vec::new();
    let mut maps: Vec<Pending<'_>> = Vec::new();
    for &f in worst {
        let i = f as usize;
        let (Some(t), Some(r)) = (test.get(i), reference.get(i)) else {
            continue;
        };
        if let (Ok(t_img), Ok(r_img)) = (backend.read_ldr(t), backend.read_ldr(r)) {
            let map = backend
                .evaluate(r, t, &heatmap_only)
                .ok()
                .and_then(|v| v.flip)
                .and_then(|flip| flip.heatmap);
            if let Some(map) = map {
                maps.push(Pending::owned(
                    dir.join(format!("{stem}-flip-f{f:03}.png")),
                    map,
                    f,
                    "heatmap",
                ));
            }
            pairs.push((f, t_img, r_img));
        }
    }
    let _ = std::fs::create_dir_all(dir);
    let mut images: Vec<Pending<'_>> = pairs
        .iter()
        .map(|(f, t, _)| Pending {
            path: dir.join(format!("{stem}-f{f:03}.png")),
            image: std::borrow::Cow::Borrowed(t),
            frame: *f,
            kind: "output".into(),
        })
        .collect();
    images.extend(maps);
    write_all(result, images, run_dir);
    pairs.into_iter().map(|(f, _, r)| (f, r)).collect()
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
    let _span = super::phases::span("images: cvvdp maps");
    let stem = sanitize(&result.variant);
    for m in maps {
        let path = dir.join(format!("{stem}-cvvdp-f{:03}.png", m.frame));
        let img = tessera_metrics::cvvdp_heatmap(m);
        save_image(result, &img, &path, run_dir, m.frame as u32, "cvvdp");
    }
}

/// The worst measured frame of each metric in `metrics` (the largest error; the lowest PSNR, SSIM
/// or JOD, by the record's `higher_is_better`), without repeats, sorted, leaving out the frames in
/// `saved` and every frame a saved frame ties with: when a metric's worst value is reached on a
/// frame already saved (a still scene, where every frame is the same), no frame is added for it.
/// Non-finite values (the infinite PSNR of identical frames) are never worst. `frames.save_worst`
/// (on by default) saves these beside `frames.save`, so "the frames where this technique is worst"
/// can be looked at (issue 22, item 6).
pub fn worst_frames(metrics: &[MetricRecord], saved: &[u32]) -> Vec<u32> {
    let mut out: Vec<u32> = Vec::new();
    for m in metrics {
        if m.per_frame.len() != m.frames.len() {
            continue;
        }
        let worse = |a: f64, b: f64| {
            if m.higher_is_better {
                a < b
            } else {
                a > b
            }
        };
        let mut worst: Option<f64> = None;
        for &v in m.per_frame.iter().filter(|v| v.is_finite()) {
            if worst.is_none_or(|w| worse(v, w)) {
                worst = Some(v);
            }
        }
        let Some(w) = worst else {
            continue;
        };
        let at: Vec<u32> = m
            .frames
            .iter()
            .zip(&m.per_frame)
            .filter(|(_, &v)| v == w)
            .map(|(&f, _)| f)
            .collect();
        if at.iter().any(|f| saved.contains(f)) {
            continue;
        }
        if let Some(&f) = at.first() {
            if !out.contains(&f) {
                out.push(f);
            }
        }
    }
    out.sort();
    out
}

/// Writes one PNG and records it (path relative to the run folder); a failed write is left out.
/// A PNG to write and record: [`write_all`] writes a list of them on all cores.
struct Pending<'a> {
    path: std::path::PathBuf,
    image: std::borrow::Cow<'a, Rgb8Image>,
    frame: u32,
    kind: String,
}

impl Pending<'static> {
    fn owned(path: std::path::PathBuf, image: Rgb8Image, frame: u32, kind: &str) -> Self {
        Pending {
            path,
            image: std::borrow::Cow::Owned(image),
            frame,
            kind: kind.to_string(),
        }
    }
}

/// `f` of every item, on up to the machine's cores (scoped threads, items in contiguous chunks),
/// results in the items' order. PNG encoding and the CPU FLIP maps of saved frames are
/// independent per image: a 4K run saved 60 images one after the other in 9.7 s (H200 host).
fn par_map<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    if items.len() < 2 || threads < 2 {
        return items.iter().map(&f).collect();
    }
    let chunk = items.len().div_ceil(threads);
    std::thread::scope(|scope| {
        let handles: Vec<_> = items
            .chunks(chunk)
            .map(|c| scope.spawn(|| c.iter().map(&f).collect::<Vec<R>>()))
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
            .collect()
    })
}

/// A scenario's PNG writes handed to background threads ([`defer_writes`]): the images are
/// recorded at once and encoded while the GPU goes on with the next variant; [`finish_writes`]
/// waits for them and names the ones that failed, whose records the caller removes.
struct Deferred {
    jobs: std::sync::mpsc::SyncSender<(std::path::PathBuf, Rgb8Image)>,
    writers: Vec<std::thread::JoinHandle<Vec<std::path::PathBuf>>>,
}

thread_local! {
    /// The running scenario's deferred writes, on the thread that runs it (tests run scenarios
    /// side by side).
    static DEFERRED: std::cell::RefCell<Option<Deferred>> = const { std::cell::RefCell::new(None) };
}

/// Images queued at most before a write waits (each up to a 4K frame's 25 MB).
const DEFERRED_QUEUE: usize = 8;

/// From now until [`finish_writes`], PNGs are encoded and written by `threads` background threads
/// instead of in place. For a real GPU only: on a CPU adapter (lavapipe) the encoding would take
/// the cores that render and time the frames. A 4K run spent 2.4 of its 16.5 s writing PNGs
/// between variants (H200 host).
pub fn defer_writes(threads: usize) {
    let (jobs, rx) =
        std::sync::mpsc::sync_channel::<(std::path::PathBuf, Rgb8Image)>(DEFERRED_QUEUE);
    let rx = std::sync::Arc::new(std::sync::Mutex::new(rx));
    let writers = (0..threads.max(1))
        .map(|_| {
            let rx = std::sync::Arc::clone(&rx);
            std::thread::spawn(move || {
                let mut failed = Vec::new();
                loop {
                    let job = rx.lock().unwrap_or_else(|e| e.into_inner()).recv();
                    let Ok((path, image)) = job else {
                        return failed;
                    };
                    if tessera_metrics::save_png(&path, &image).is_err() {
                        failed.push(path);
                    }
                }
            })
        })
        .collect();
    let old = DEFERRED.with(|d| d.replace(Some(Deferred { jobs, writers })));
    // A scenario that ended without finishing its writes (a device loss): let them finish.
    drop(old);
}

/// Waits for the deferred writes and returns the paths that could not be written (nothing
/// when writes were not deferred).
pub fn finish_writes() -> Vec<std::path::PathBuf> {
    let Some(d) = DEFERRED.with(|d| d.borrow_mut().take()) else {
        return Vec::new();
    };
    drop(d.jobs);
    d.writers
        .into_iter()
        .flat_map(|w| w.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
        .collect()
}

/// Removes the records of images [`finish_writes`] could not write.
pub fn forget_failed(results: &mut [VariantResult], failed: &[std::path::PathBuf], run_dir: &Path) {
    if failed.is_empty() {
        return;
    }
    let rel: Vec<String> = failed.iter().map(|p| relative(p, run_dir)).collect();
    for r in results {
        r.images.retain(|i| !rel.contains(&i.path));
    }
}

/// Writes `images` (in parallel, or queued for the background writers) and records each one
/// written in `result`, in their order.
fn write_all(result: &mut VariantResult, images: Vec<Pending<'_>>, run_dir: &Path) {
    let jobs = DEFERRED.with(|d| d.borrow().as_ref().map(|d| d.jobs.clone()));
    if let Some(jobs) = jobs {
        for p in images {
            let image = p.image.into_owned();
            let _span = super::phases::span("images: queue wait");
            let queued = jobs.send((p.path.clone(), image)).is_ok();
            if queued {
                record(result, &p.path, run_dir, p.frame, &p.kind);
            }
        }
        return;
    }
    let written = par_map(&images, |p| {
        tessera_metrics::save_png(&p.path, &p.image).is_ok()
    });
    for (p, ok) in images.iter().zip(written) {
        if ok {
            record(result, &p.path, run_dir, p.frame, &p.kind);
        }
    }
}

fn relative(path: &Path, run_dir: &Path) -> String {
    path.strip_prefix(run_dir)
        .unwrap_or(path)
        .to_string_lossy()
        .replace('\\', "/")
}

fn record(result: &mut VariantResult, path: &Path, run_dir: &Path, frame: u32, kind: &str) {
    result.images.push(ImageRecord {
        frame,
        kind: kind.to_string(),
        path: relative(path, run_dir),
    });
}

fn save_image(
    result: &mut VariantResult,
    img: &Rgb8Image,
    path: &Path,
    run_dir: &Path,
    frame: u32,
    kind: &str,
) {
    let image = Pending {
        path: path.to_path_buf(),
        image: std::borrow::Cow::Borrowed(img),
        frame,
        kind: kind.to_string(),
    };
    write_all(result, vec![image], run_dir);
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deferred_writes_are_recorded_written_and_failures_forgotten() {
        let dir = tempfile::tempdir().unwrap();
        let img = Rgb8Image {
            width: 4,
            height: 2,
            data: (0..24).map(|i| i as u8 * 10).collect(),
        };
        let native = crate::techniques::by_name("native").unwrap();
        let mut result = super::super::record::empty_result(
            &crate::techniques::Variant::with_defaults(native),
            tessera_results::Status::Ok,
        );
        defer_writes(2);
        let good = dir.path().join("native-f000.png");
        let bad = dir.path().join("missing-folder").join("native-f001.png");
        save_image(&mut result, &img, &good, dir.path(), 0, "output");
        save_image(&mut result, &img, &bad, dir.path(), 1, "output");
        // Recorded at once, written in the background.
        assert_eq!(result.images.len(), 2);
        let failed = finish_writes();
        assert_eq!(failed, vec![bad.clone()]);
        let mut results = vec![result];
        forget_failed(&mut results, &failed, dir.path());
        assert_eq!(results[0].images.len(), 1);
        assert_eq!(results[0].images[0].path, "native-f000.png");
        match tessera_metrics::load_image(&good) {
            Ok(tessera_metrics::LoadedImage::Ldr(back)) => assert_eq!(back.data, img.data),
            _ => panic!("native-f000.png was not written as an 8-bit PNG"),
        }
        // Not deferred any more: a write happens in place, and a failed one is not recorded.
        save_image(&mut results[0], &img, &bad, dir.path(), 1, "output");
        assert_eq!(results[0].images.len(), 1);
        assert!(finish_writes().is_empty());
    }

    fn metric(name: &str, higher_is_better: bool, per_frame: &[f64]) -> MetricRecord {
        MetricRecord {
            name: name.into(),
            per_frame: per_frame.to_vec(),
            frames: (0..per_frame.len() as u32).collect(),
            value: 0.0,
            higher_is_better,
            frame_stats: None,
            metrics_device: None,
            check: None,
        }
    }

    #[test]
    fn the_worst_frame_of_each_metric_by_its_direction() {
        let m = [
            metric("flip", false, &[0.1, 0.3, 0.2, 0.1]),
            metric("psnr", true, &[f64::INFINITY, 30.0, 25.0, 40.0]),
            metric("ssim", true, &[0.99, 0.98, 0.97, 0.99]),
        ];
        assert_eq!(worst_frames(&m, &[3]), [1, 2]);
        // A saved frame already shows flip's worst: only psnr's and ssim's frame is added.
        assert_eq!(worst_frames(&m, &[1]), [2]);
        // A tie with a saved frame adds nothing; all non-finite adds nothing.
        let still = [
            metric("flip", false, &[0.2, 0.2, 0.2]),
            metric("psnr", true, &[f64::INFINITY; 3]),
        ];
        assert_eq!(worst_frames(&still, &[2]), Vec::<u32>::new());
        assert_eq!(worst_frames(&still, &[]), [0]);
    }
}
