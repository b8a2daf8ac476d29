//! The command line's exit codes and outputs for good and bad input.
//! 0 ok, 1 a gate or variant failed, 2 bad input, 3 no usable adapter or device failure.

use std::path::Path;
use std::process::Command;

fn tessera(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_tessera"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

fn write(dir: &Path, name: &str, body: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, body).unwrap();
    p.to_string_lossy().into_owned()
}

const SCENE: &str = r#"
resolution = [32, 24]
[frames]
warmup = 1
measured = 2
[[scene.objects]]
shape = "sphere"
position = [0, 0.5, 0]
[[scene.lights]]
type = "directional"
[camera]
[[camera.keyframes]]
time = 0
position = [0, 1, 4]
target = [0, 0.5, 0]
[[techniques]]
technique = "native"
[[techniques]]
technique = "upscale"
scale = 0.5
"#;

#[test]
fn validate_good_and_bad() {
    let dir = tempfile::tempdir().unwrap();
    let good = write(dir.path(), "good.toml", SCENE);
    let (code, out, _) = tessera(&["validate", &good]);
    assert_eq!(code, 0);
    assert_eq!(out.trim(), "1 scenarios valid (2 variants)");
    let bad = write(dir.path(), "bad.toml", &SCENE.replace("native", "nativ"));
    let (code, _, err) = tessera(&["validate", &bad]);
    assert_eq!(code, 2);
    assert!(err.contains("bad.toml:17:13: `techniques[0].technique`: unknown technique \"nativ\" (did you mean \"native\"?)"), "{err}");
    let (code, _, err) = tessera(&["validate", "/no/such/file.toml"]);
    assert_eq!(code, 2);
    assert!(err.contains("/no/such/file.toml: cannot read"), "{err}");
}

#[test]
fn bad_arguments_are_exit_2() {
    assert_eq!(tessera(&["run"]).0, 2);
    assert_eq!(tessera(&["frobnicate"]).0, 2);
    assert_eq!(tessera(&["diff", "/no/a.png", "/no/b.png"]).0, 2);
}

#[test]
fn run_writes_results_and_gates_decide_the_exit_code() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let good = write(
        dir.path(),
        "good.toml",
        &SCENE.replace("measured = 2", "measured = 2\nsave = [1]"),
    );
    let junit = dir.path().join("junit.xml");
    let (code, stdout, stderr) = tessera(&[
        "run",
        &good,
        "--out",
        out.to_str().unwrap(),
        "--junit",
        junit.to_str().unwrap(),
        "--quiet",
        "--branch",
        "feature/x",
    ]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    assert!(
        stdout.contains("PASSED: 2 ok, 0 skipped, 0 failed"),
        "{stdout}"
    );
    let run_dir = std::fs::read_dir(&out)
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    for f in ["run.json", "results.csv", "scenarios/good.json"] {
        assert!(run_dir.join(f).is_file(), "missing {f}");
    }
    let run: tessera_results::RunInfo =
        serde_json::from_slice(&std::fs::read(run_dir.join("run.json")).unwrap()).unwrap();
    assert_eq!(run.status, tessera_results::RunStatus::Complete);
    // The suite is the folder the scenario file is in; `--branch` is recorded as given.
    let folder = dir.path().canonicalize().unwrap();
    assert_eq!(
        run.suite.as_deref(),
        folder.file_name().and_then(|n| n.to_str())
    );
    assert_eq!(run.branch.as_deref(), Some("feature/x"));
    let s: tessera_results::ScenarioResult =
        serde_json::from_slice(&std::fs::read(run_dir.join("scenarios/good.json")).unwrap())
            .unwrap();
    assert_eq!(s.results[1].variant, "upscale");
    assert_eq!(
        s.results[1]
            .passes
            .iter()
            .map(|p| p.name.as_str())
            .collect::<Vec<_>>(),
        ["scene", "upscale"]
    );
    // The saved frame of the variant comes with its FLIP heat map; the reference has none.
    let kinds = |i: usize| {
        let mut k: Vec<&str> = s.results[i]
            .images
            .iter()
            .map(|im| im.kind.as_str())
            .collect();
        k.sort();
        k
    };
    assert_eq!(kinds(0), ["output"]);
    assert_eq!(kinds(1), ["heatmap", "output", "reference"]);
    let heatmap = s.results[1]
        .images
        .iter()
        .find(|i| i.kind == "heatmap")
        .unwrap();
    assert_eq!(heatmap.path, "images/good/upscale-flip-f001.png");
    let Ok(tessera_metrics::LoadedImage::Ldr(png)) =
        tessera_metrics::load_image(&run_dir.join(&heatmap.path))
    else {
        panic!("{} is not an 8-bit PNG", heatmap.path);
    };
    assert_eq!((png.width, png.height), (32, 24));
    // 16x12 colour (8 B) and depth (4 B) at half scale, 32x24 output (8 B).
    assert_eq!(s.results[1].allocated_bytes, 16 * 12 * 12 + 32 * 24 * 8);
    assert!(std::fs::read_to_string(&junit)
        .unwrap()
        .contains("<testcase classname=\"good\" name=\"upscale\""));

    // An impossible gate fails the run with exit code 1.
    let gated = write(
        dir.path(),
        "gated.toml",
        &format!("{SCENE}\n[[gates]]\nmeasure = \"psnr\"\nfail_below = 200\n"),
    );
    let (code, stdout, _) = tessera(&["run", &gated, "--out", out.to_str().unwrap(), "--quiet"]);
    assert_eq!(code, 1, "{stdout}");
    assert!(stdout.contains("gate failed: psnr = "), "{stdout}");
    assert!(
        stdout
            .lines()
            .last()
            .unwrap()
            .starts_with("FAILED: 2 ok, 0 skipped, 0 failed; gates: 1 failed"),
        "{stdout}"
    );
}

#[test]
fn an_unknown_adapter_is_exit_3() {
    let dir = tempfile::tempdir().unwrap();
    let good = write(dir.path(), "good.toml", SCENE);
    let (code, _, err) = tessera(&[
        "run",
        &good,
        "--adapter",
        "no-such-gpu",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert_eq!(code, 3);
    assert!(
        err.contains("no adapter matches \"no-such-gpu\"; available: "),
        "{err}"
    );
}

#[test]
fn a_resolution_beyond_the_adapter_limit_is_skipped_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let big = write(
        dir.path(),
        "big.toml",
        &SCENE
            .replace("resolution = [32, 24]", "resolution = [16384, 1]")
            .replace("scale = 0.5", "scale = 1.0"),
    );
    // lavapipe's limit is 16384, so render a 1-pixel-high strip instead if the limit allows it;
    // ask for a ground-truth reference, whose 2x supersampling exceeds any limit at this width.
    let body = std::fs::read_to_string(&big).unwrap().replace(
        "[frames]",
        "[reference]\nkind = \"ground-truth\"\nsupersample = 2\n[frames]",
    );
    std::fs::write(&big, body).unwrap();
    let (code, stdout, stderr) = tessera(&[
        "run",
        &big,
        "--out",
        dir.path().to_str().unwrap(),
        "--quiet",
    ]);
    // Without a reference the variants cannot be compared: they fail, and say why.
    assert_eq!(code, 1, "{stdout}{stderr}");
    assert!(
        stdout.contains("exceeds the adapter's maximum texture size"),
        "{stdout}"
    );
}

/// The smoke suite, as the README's main command runs it, passes on the default adapter.
#[test]
fn smoke_suite_passes() {
    let dir = tempfile::tempdir().unwrap();
    let smoke = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/smoke");
    let (code, stdout, stderr) = tessera(&[
        "run",
        smoke.to_str().unwrap(),
        "--out",
        dir.path().to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    let verdict = stdout.lines().last().unwrap();
    assert!(verdict.starts_with("PASSED"), "{verdict}");
    assert!(!verdict.contains(" 0 ok"), "{verdict}");
}

/// `tessera validate` says, without opening a device, which variants need more than every
/// adapter has and what: hardware-only ones (VRS) as skipped without such a GPU.
#[test]
fn validate_prints_the_skip_reasons_of_hardware_only_variants() {
    let file = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenarios/adaptive/detailed.toml"
    );
    let (code, out, err) = tessera(&["validate", file]);
    assert_eq!(code, 0, "{err}");
    let needs = "needs VK_KHR_fragment_shading_rate with attachmentFragmentShadingRate (skipped without a GPU that offers it)";
    for variant in [
        "native-vrs[rate=1x1]",
        "adaptive-shading[threshold=0.15,vrs=hardware]",
    ] {
        assert!(
            out.lines()
                .any(|l| l.ends_with(&format!("detailed.toml: {variant}: {needs}"))),
            "no skip reason for {variant}:\n{out}"
        );
    }
    // A software variant needs nothing of the adapter: no line.
    assert!(
        !out.contains("adaptive-shading[coarse_sample=pixel"),
        "{out}"
    );
}

#[test]
fn a_sweep_runs_every_combination_and_regimes_tabulates_them() {
    let dir = tempfile::tempdir().unwrap();
    let body = SCENE.replace("scale = 0.5", "scale = 0.7071").replacen(
        "[frames]",
        "[reference]\nkind = \"none\"\n[sweep]\n\"scene.shading_cost\" = [0, 8]\nresolution = [[32, 24], [48, 32]]\n[frames]",
        1,
    );
    let file = write(dir.path(), "swept.toml", &body);
    let (code, out, err) = tessera(&["validate", &file]);
    assert_eq!(code, 0, "{out}{err}");
    assert_eq!(out.trim(), "4 scenarios valid (8 variants)");
    let out_dir = dir.path().join("out");
    let (code, out, err) = tessera(&["run", &file, "--out", out_dir.to_str().unwrap(), "--quiet"]);
    assert_eq!(code, 0, "{out}{err}");
    let run = std::fs::read_dir(&out_dir)
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    let (code, table, err) = tessera(&["regimes", run.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    for name in [
        "swept[shading_cost=0,resolution=32x24]",
        "swept[shading_cost=8,resolution=48x32]",
    ] {
        let row = table
            .lines()
            .find(|l| l.contains(name))
            .unwrap_or_else(|| panic!("{name}: {table}"));
        // A measured fraction (a percentage) and the speed-up of the half-pixel render.
        assert!(row.contains('%'), "{row}");
        assert!(row.trim_end().ends_with("x |"), "{row}");
    }
    // A bad swept value is reported at its key with the combination it came from.
    let bad = write(dir.path(), "bad.toml", &body.replace("[0, 8]", "[0, -3]"));
    let (code, _, err) = tessera(&["validate", &bad]);
    assert_eq!(code, 2);
    assert!(
        err.contains("`scene.shading_cost`")
            && err.contains("(with sweep scene.shading_cost = -3)"),
        "{err}"
    );
    // Not a run folder: a clear error, exit 2.
    let (code, _, err) = tessera(&["regimes", dir.path().to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
}
