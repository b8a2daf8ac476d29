//! `tde` and `flip-hdr` inside `tessera run`, on the default adapter: the temporal difference
//! error with the renderer's exact motion is zero for the reference itself and not for a
//! technique that changes differently; HDR-FLIP uses one exposure range per reference frame.

mod common;

use tessera_results::ScenarioResult;

const PAN: &str = r#"
resolution = [48, 32]
metrics = ["psnr", "flip-hdr", "tde"]
[frames]
warmup = 1
measured = 5
[scene]
shading_cost = 1
[scene.ground]
checker_size = 0.5
[[scene.lights]]
type = "directional"
[[scene.objects]]
shape = "box"
position = [0, 0.5, 0]
emissive = [20.0, 8.0, 2.0]
animation = { kind = "rotate", axis = [0, 1, 0], degrees_per_second = 90 }
[camera]
[[camera.keyframes]]
time = 0
position = [0, 1.5, 4]
target = [0, 0.4, 0]
[[camera.keyframes]]
time = 1
position = [1.5, 1.5, 4]
target = [1.5, 0.4, 0]
[[camera.keyframes]]
time = 1.06
position = [-1, 1.2, 3]
target = [0, 0.4, 0]
cut = true
[[techniques]]
technique = "native"
[[techniques]]
technique = "upscale"
scale = 0.5
[[techniques]]
technique = "checkerboard"
"#;

fn run(src: &str) -> ScenarioResult {
    common::run_ok(src, "pan.toml")
}

fn metric<'a>(
    s: &'a ScenarioResult,
    variant: &str,
    name: &str,
) -> &'a tessera_results::MetricRecord {
    s.results
        .iter()
        .find(|r| r.variant == variant)
        .unwrap()
        .metrics
        .iter()
        .find(|m| m.name == name)
        .unwrap()
}

#[test]
fn tde_is_zero_for_the_reference_and_skips_frames_without_motion() {
    // 0.25 s per frame: frame 0 is warm-up, measured frames 0..4 are frames 1..5 (0.25 s to
    // 1.25 s), and the cut at 1.06 s starts a new shot at measured frame 4.
    let s = run(&PAN.replace(
        "resolution = [48, 32]",
        "resolution = [48, 32]\ntime_step = 0.25",
    ));
    let native = metric(&s, "native", "tde");
    assert_eq!(native.value, 0.0);
    // Frame 0 has no previous measured frame; frame 4 starts a new shot (cut at 1.06 s).
    assert_eq!(native.frames, [1, 2, 3]);
    let up = metric(&s, "upscale", "tde");
    assert!(up.value > 0.0, "{up:?}");
    assert_eq!(up.frames, native.frames);
    assert!(up.per_frame.iter().all(|v| v.is_finite() && *v >= 0.0));
    // HDR-FLIP: zero against itself, positive for upscale, one value per measured frame.
    assert_eq!(metric(&s, "native", "flip-hdr").value, 0.0);
    let fh = metric(&s, "upscale", "flip-hdr");
    assert_eq!(fh.per_frame.len(), 5);
    assert!(fh.value > 0.0 && fh.value < 1.0, "{fh:?}");
}
