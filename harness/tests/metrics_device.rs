//! `metrics_device`: the same scenario with its metrics on the GPU and on the CPU (on lavapipe in
//! CI) gives the same records within issue 25's tolerances, each saying where it was computed,
//! and the same heat-map images; a bad `metrics_device` is a located error.

use std::path::Path;

use tessera_results::ScenarioResult;

/// Every metric the GPU computes, on real rendered frames: HDR highlights, motion, a cut-free pan.
const SCENARIO: &str = r#"
description = "metrics_device cross-check"
resolution = [64, 48]
metrics = ["psnr", "psnr-luma", "max-abs-error", "ssim", "ssim-luma", "flip", "flip-max", "flip-hdr", "flicker", "tde"]
[frames]
warmup = 1
measured = 4
save = [-1]
[scene]
shading_cost = 2
[scene.ground]
checker_size = 0.5
[[scene.lights]]
type = "directional"
direction = [-0.4, -1.0, -0.3]
intensity = 1.5
[[scene.objects]]
shape = "box"
position = [0.0, 0.5, 0.0]
color = [0.3, 0.3, 0.35]
[[scene.objects]]
shape = "sphere"
position = [1.2, 0.4, 0.6]
radius = 0.08
emissive = [50.0, 42.0, 30.0]
[camera]
[[camera.keyframes]]
time = 0.0
position = [0.0, 1.6, 5.0]
target = [0.0, 0.4, 0.0]
[[camera.keyframes]]
time = 1.0
position = [0.6, 1.6, 5.0]
target = [0.4, 0.4, 0.0]
[[techniques]]
technique = "native"
[[techniques]]
technique = "upscale"
scale = 0.5
[[techniques]]
technique = "checkerboard"
"#;

fn run(file: &Path, device: &str) -> (ScenarioResult, std::path::PathBuf, tempfile::TempDir) {
    let out = tempfile::tempdir().unwrap();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_tessera"))
        .args([
            "run",
            file.to_str().unwrap(),
            "--quiet",
            "--metrics-device",
            device,
            "--out",
        ])
        .arg(out.path())
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    let run_dir = std::fs::read_dir(out.path())
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    let files = tessera_results::layout::scenario_files(&run_dir).unwrap();
    let text = std::fs::read_to_string(&files[0]).unwrap();
    (serde_json::from_str(&text).unwrap(), run_dir, out)
}

/// Tolerance of one metric's values (issue 25's Acceptance).
fn close(name: &str, gpu: f64, cpu: f64) -> bool {
    if gpu == cpu || (gpu.is_nan() && cpu.is_nan()) {
        return true;
    }
    match name {
        "psnr" | "psnr-luma" => (gpu - cpu).abs() <= 1e-6 * cpu.abs(),
        "ssim" | "ssim-luma" => (gpu - cpu).abs() <= 1e-6,
        "flip" | "flip-hdr" | "tde" | "flicker" => (gpu - cpu).abs() <= 1e-5,
        // One pixel's error: the device's per-pixel FLIP is within a few ulp of the CPU's.
        "flip-max" => (gpu - cpu).abs() <= 1e-5,
        // Integer-valued: exact.
        _ => false,
    }
}

#[test]
fn gpu_and_cpu_records_agree_on_rendered_frames() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("metrics-device.toml");
    std::fs::write(&file, SCENARIO).unwrap();
    let (gpu, gpu_dir, _g) = run(&file, "gpu");
    let (cpu, cpu_dir, _c) = run(&file, "cpu");
    let mut worst: Vec<(String, f64)> = Vec::new();
    assert_eq!(gpu.results.len(), cpu.results.len());
    for (g, c) in gpu.results.iter().zip(&cpu.results) {
        assert_eq!(g.variant, c.variant);
        let quality: Vec<_> = c
            .metrics
            .iter()
            .filter(|m| m.metrics_device.is_some())
            .collect();
        assert_eq!(quality.len(), 10, "{}: {:?}", c.variant, c.metrics);
        for cm in quality {
            let gm = g.metrics.iter().find(|m| m.name == cm.name).unwrap();
            assert_eq!(cm.metrics_device.as_deref(), Some("cpu"));
            assert_eq!(gm.metrics_device.as_deref(), Some("gpu"), "{}", gm.name);
            assert_eq!(gm.frames, cm.frames, "{} {}", g.variant, gm.name);
            for (a, b) in gm
                .per_frame
                .iter()
                .zip(&cm.per_frame)
                .chain([(&gm.value, &cm.value)])
            {
                assert!(
                    close(&gm.name, *a, *b),
                    "{} {}: gpu {a} cpu {b}",
                    g.variant,
                    gm.name
                );
                let d = if a == b { 0.0 } else { (a - b).abs() };
                match worst.iter_mut().find(|(n, _)| *n == gm.name) {
                    Some((_, w)) => *w = w.max(d),
                    None => worst.push((gm.name.clone(), d)),
                }
            }
        }
        // The same images are saved (names and kinds), for every variant but the reference: the
        // worst frame of each metric too (read back from the device with GPU metrics), whose
        // HDR map only the CPU path makes (its linear frames were read back).
        let kinds = |v: &tessera_results::VariantResult| {
            let mut k: Vec<(String, String)> = v
                .images
                .iter()
                .filter(|i| i.kind != "heatmap-hdr" || i.frame == 3)
                .map(|i| (i.kind.clone(), i.path.clone()))
                .collect();
            k.sort();
            k
        };
        if g.variant != "native" {
            assert!(
                g.images.iter().any(|i| i.kind == "output" && i.frame != 3),
                "{}: a worst frame beside the saved one: {:?}",
                g.variant,
                g.images
            );
        }
        assert_eq!(kinds(g), kinds(c), "{}", g.variant);
        for (_, path) in kinds(g) {
            assert!(
                gpu_dir.join(&path).is_file() && cpu_dir.join(&path).is_file(),
                "{path}"
            );
        }
    }
    eprintln!("max |gpu - cpu| per metric on rendered frames: {worst:?}");
}

#[test]
fn a_bad_metrics_device_is_a_located_error() {
    let src = SCENARIO.replace("description = ", "metrics_device = \"tpu\"\ndescription = ");
    let e = tessera::scenario::parse(Path::new("bad.toml"), &src).unwrap_err();
    let text = e.to_string();
    assert!(text.contains("bad.toml:2"), "{text}");
    assert!(text.contains("metrics_device"), "{text}");
    assert!(text.contains("allowed: \"gpu\", \"cpu\""), "{text}");
}

/// Injected NaN and +Inf, a moving camera with a cut, a saved frame: with the GPU metrics the
/// frames stay on the device (non-finite values counted there, the determinism check compared
/// there, cut recovery from the GPU's MSE), and every stability record and count must be the
/// CPU run's.
const STABILITY: &str = r#"
description = "stability with frames on the device"
resolution = [48, 32]
metrics = ["psnr", "flip"]
[frames]
warmup = 1
measured = 6
save = [2]
[scene]
shading_cost = 2
[scene.ground]
checker_size = 0.5
[[scene.lights]]
type = "directional"
intensity = 2.0
[[scene.objects]]
shape = "sphere"
position = [-0.7, 0.5, 0.0]
radius = 0.45
inject = "nan"
[[scene.objects]]
shape = "box"
position = [0.8, 0.4, 0.0]
size = [0.6, 0.8, 0.6]
inject = "inf"
[camera]
[[camera.keyframes]]
time = 0.0
position = [0.0, 1.5, 4.0]
target = [0.0, 0.4, 0.0]
[[camera.keyframes]]
time = 0.04
position = [0.5, 1.5, 4.0]
target = [0.0, 0.4, 0.0]
[[camera.keyframes]]
time = 0.05
position = [-2.0, 1.5, 4.0]
target = [0.0, 0.4, 0.0]
cut = true
[[camera.keyframes]]
time = 0.2
position = [-1.5, 1.5, 4.0]
target = [0.0, 0.4, 0.0]
[[techniques]]
technique = "native"
[[techniques]]
technique = "checkerboard"
[[techniques]]
technique = "taau"
scale = 0.5
"#;

#[test]
fn stability_records_agree_with_frames_on_the_device() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("stability.toml");
    std::fs::write(&file, STABILITY).unwrap();
    let (gpu, gpu_dir, _g) = run(&file, "gpu");
    let (cpu, _, _c) = run(&file, "cpu");
    assert_eq!(gpu.results.len(), 3);
    let mut cuts = 0;
    for (g, c) in gpu.results.iter().zip(&cpu.results) {
        assert_eq!(g.status, c.status, "{}", g.variant);
        assert_eq!(g.non_finite_values, c.non_finite_values, "{}", g.variant);
        if g.variant.starts_with("taau") {
            // taau's resolve makes its input samples finite before they enter the history
            // (taau/resolve.wgsl): the injected NaN and +Inf never reach its output.
            assert_eq!(g.non_finite_values, 0, "{}: sanitises its input", g.variant);
        } else {
            assert!(
                g.non_finite_values > 0,
                "{}: the scene injects NaN",
                g.variant
            );
        }
        let (gs, cs) = (g.stability.as_ref().unwrap(), c.stability.as_ref().unwrap());
        assert_eq!(gs.non_finite_pixels, cs.non_finite_pixels, "{}", g.variant);
        assert_eq!(gs.spread_pixels, cs.spread_pixels, "{}", g.variant);
        assert_eq!(gs.deterministic, Some(true), "{}", g.variant);
        assert_eq!(gs.deterministic, cs.deterministic, "{}", g.variant);
        // The MSEs are integer sums on both: exactly equal.
        assert_eq!(
            serde_json::to_value(&gs.cuts).unwrap(),
            serde_json::to_value(&cs.cuts).unwrap(),
            "{}",
            g.variant
        );
        cuts += gs.cuts.len();
        // The saved frame came back for its image.
        let output = g.images.iter().find(|i| i.kind == "output").unwrap();
        assert!(gpu_dir.join(&output.path).is_file());
    }
    assert!(cuts > 0, "the scenario has a cut");
}
