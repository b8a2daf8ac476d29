//! `fsr2` inside `tessera run` on the default adapter, at a tiny resolution: it runs (finite
//! output, every pass timed), its history accumulates on a still scene (the converged frames beat
//! the first frame and bilinear `upscale` at the same render scale, and stop changing), and on a
//! moving camera with an animated object its error stays below bilinear `upscale`'s at the same
//! render scale.

mod common;

use tessera_results::ScenarioResult;

const SCENE: &str = r#"
resolution = [64, 48]
metrics = ["psnr", "flip"]
[scene]
shading_cost = 1
[scene.ground]
checker_size = 0.25
[[scene.lights]]
type = "directional"
intensity = 3.0
[[scene.objects]]
shape = "box"
position = [0, 0.5, 0]
color = [0.8, 0.3, 0.2]
[[scene.objects]]
shape = "sphere"
position = [1.2, 0.5, -0.5]
radius = 0.5
[[scene.objects]]
shape = "fence"
position = [-2, 0, -1]
end = [2, 0, -1]
[[techniques]]
technique = "native"
[[techniques]]
technique = "upscale"
scale = 0.5
[[techniques]]
technique = "fsr2"
mode = "performance"
"#;

const STILL: &str = r#"
[camera]
[[camera.keyframes]]
time = 0
position = [0, 1.5, 4]
target = [0, 0.4, 0]
"#;

const MOVING: &str = r#"
[[scene.objects]]
shape = "box"
position = [0.5, 0.3, 1]
color = [0.2, 0.6, 0.9]
animation = { kind = "rotate", axis = [0, 1, 0], degrees_per_second = 60 }
[camera]
[[camera.keyframes]]
time = 0
position = [0, 1.5, 4]
target = [0, 0.4, 0]
[[camera.keyframes]]
time = 4
position = [1.0, 1.6, 3.6]
target = [0.3, 0.4, 0]
"#;

fn metric<'a>(
    s: &'a ScenarioResult,
    variant: &str,
    name: &str,
) -> &'a tessera_results::MetricRecord {
    let r = s
        .results
        .iter()
        .find(|r| r.variant.starts_with(variant))
        .unwrap_or_else(|| panic!("no {variant}"));
    r.metrics.iter().find(|m| m.name == name).unwrap()
}

fn run(parts: &[&str], frames: &str) -> ScenarioResult {
    // Top-level keys and [frames] go before the first table.
    let src = SCENE.replacen("\n[scene]\n", &format!("\n{frames}\n[scene]\n"), 1);
    common::run_ok(&format!("{src}\n{}", parts.concat()), "fsr2.toml")
}

#[test]
fn fsr2_converges_on_a_still_scene() {
    // The first frame alone (no history): one jittered sample per render pixel.
    let first = run(&[STILL], "[frames]\nwarmup = 0\nmeasured = 1");
    // After its declared convergence (32 phases at Performance): 32 warm-up frames.
    let late = run(&[STILL], "[frames]\nwarmup = 32\nmeasured = 4");
    let f0 = metric(&first, "fsr2", "psnr").value;
    let conv = metric(&late, "fsr2", "psnr");
    let up = metric(&late, "upscale", "psnr").value;
    assert!(conv.per_frame.iter().all(|v| v.is_finite()), "{conv:?}");
    assert!(conv.value > f0 + 1.0, "converged {} first {f0}", conv.value);
    assert!(
        conv.value > up + 1.0,
        "converged {} bilinear {up}",
        conv.value
    );
    // Steady: the measured frames agree within 0.5 dB.
    let (lo, hi) = conv
        .per_frame
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(*v), b.max(*v)));
    assert!(hi - lo < 0.5, "{:?}", conv.per_frame);
    // Every one of AMD's passes ran and was timed.
    let r = late
        .results
        .iter()
        .find(|r| r.variant.starts_with("fsr2"))
        .unwrap();
    for pass in ["reconstruct", "depth_clip", "lock", "accumulate", "rcas"] {
        assert!(
            r.passes.iter().any(|p| p.name == pass),
            "{pass} missing: {:?}",
            r.passes.iter().map(|p| &p.name).collect::<Vec<_>>()
        );
    }
}

#[test]
fn fsr2_beats_bilinear_on_a_moving_scene() {
    let s = run(
        &[MOVING],
        "time_step = 0.0333\n[frames]\nwarmup = 32\nmeasured = 6",
    );
    let fsr2 = metric(&s, "fsr2", "flip");
    let up = metric(&s, "upscale", "flip");
    assert!(fsr2.per_frame.iter().all(|v| v.is_finite()), "{fsr2:?}");
    assert!(
        fsr2.value < up.value,
        "fsr2 FLIP {} not below bilinear {}",
        fsr2.value,
        up.value
    );
    let p = metric(&s, "fsr2", "psnr").value;
    let pu = metric(&s, "upscale", "psnr").value;
    assert!(p > pu, "fsr2 PSNR {p} not above bilinear {pu}");
}
