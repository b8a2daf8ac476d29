//! `cvvdp` with `metrics_device = "gpu"`: on rendered frames (a pan, so the temporal channels
//! see motion; the paper's display `paper_27in_4k`) the GPU's ColorVideoVDP records agree with the
//! CPU's within issue 25's 0.001 JOD, say `"gpu"`, and the saved frame's distortion map image is
//! written by both back ends.

use std::path::Path;

use tessera_results::ScenarioResult;

const SCENARIO: &str = r#"
description = "cvvdp on the GPU against the CPU"
resolution = [64, 48]
metrics = ["ssim", "cvvdp"]
display = "paper_27in_4k"
time_step = 0.033333333
[frames]
warmup = 1
measured = 5
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
color = [0.6, 0.3, 0.35]
[[scene.objects]]
shape = "fence"
position = [-2.0, 0.0, -1.0]
end = [2.0, 0.0, -1.0]
height = 1.0
posts = 9
rails = 3
thickness = 0.03
[camera]
[[camera.keyframes]]
time = 0.0
position = [0.0, 1.6, 5.0]
target = [0.0, 0.4, 0.0]
[[camera.keyframes]]
time = 1.0
position = [0.8, 1.6, 5.0]
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

#[test]
fn gpu_cvvdp_records_agree_with_the_cpu_on_rendered_frames() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("cvvdp-gpu.toml");
    std::fs::write(&file, SCENARIO).unwrap();
    let (gpu, gpu_dir, _g) = run(&file, "gpu");
    let (cpu, cpu_dir, _c) = run(&file, "cpu");
    assert_eq!(gpu.results.len(), cpu.results.len());
    let mut worst = 0.0_f64;
    let mut visible = false;
    for (g, c) in gpu.results.iter().zip(&cpu.results) {
        assert_eq!(g.variant, c.variant);
        for name in ["cvvdp", "cvvdp-flicker", "cvvdp-transient-share"] {
            let find = |v: &tessera_results::VariantResult| {
                v.metrics
                    .iter()
                    .find(|m| m.name == name)
                    .cloned()
                    .unwrap_or_else(|| panic!("{} has no {name}", v.variant))
            };
            let (gm, cm) = (find(g), find(c));
            assert_eq!(gm.metrics_device.as_deref(), Some("gpu"), "{name}");
            assert_eq!(cm.metrics_device.as_deref(), Some("cpu"), "{name}");
            assert_eq!(gm.frames, cm.frames, "{} {name}", g.variant);
            let tolerance = if name == "cvvdp-transient-share" {
                1e-4
            } else {
                1e-3
            };
            for (a, b) in gm
                .per_frame
                .iter()
                .zip(&cm.per_frame)
                .chain([(&gm.value, &cm.value)])
            {
                let d = (a - b).abs();
                assert!(d <= tolerance, "{} {name}: gpu {a} cpu {b}", g.variant);
                if name != "cvvdp-transient-share" {
                    worst = worst.max(d);
                }
            }
            if name == "cvvdp" && cm.value < 9.9 {
                visible = true;
            }
        }
        let maps = |v: &tessera_results::VariantResult| -> Vec<String> {
            v.images
                .iter()
                .filter(|i| i.kind == "cvvdp")
                .map(|i| i.path.clone())
                .collect()
        };
        assert_eq!(maps(g), maps(c), "{}", g.variant);
        for path in maps(g) {
            assert!(gpu_dir.join(&path).is_file() && cpu_dir.join(&path).is_file());
        }
    }
    assert!(visible, "some variant must differ visibly from native");
    eprintln!("max |gpu - cpu| JOD on rendered frames: {worst:e}");
}
