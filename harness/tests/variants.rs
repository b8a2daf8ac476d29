//! `tessera run --variants`: only the named variants run, with `native` and their baselines; a
//! scenario without a match is left out; a pattern that matches nothing is exit code 2.

use std::process::Command;

const SCENARIO: &str = r#"
resolution = [32, 18]
metrics = ["psnr"]
[frames]
warmup = 1
measured = 2
[[scene.objects]]
shape = "box"
position = [0, 0.5, 0]
[camera]
[[camera.keyframes]]
time = 0
position = [0, 1.5, 4]
target = [0, 0.4, 0]
[[techniques]]
technique = "native"
[[techniques]]
technique = "upscale"
scale = [0.5, 0.75]
[[techniques]]
technique = "taau"
"#;

#[test]
fn only_the_named_variants_run() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("a.toml"), SCENARIO).unwrap();
    let only_native = SCENARIO
        .split("[[techniques]]\ntechnique = \"upscale\"")
        .next()
        .unwrap();
    std::fs::write(dir.path().join("b.toml"), only_native).unwrap();
    let out = dir.path().join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_tessera"))
        .arg("run")
        .arg(dir.path())
        .args(["--quiet", "--variants", "upscale[scale=0.5]", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(
        err.contains("left out 1 scenario(s) without a match: b"),
        "{err}"
    );
    let run = std::fs::read_dir(&out)
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    let files = tessera_results::layout::scenario_files(&run).unwrap();
    assert_eq!(files.len(), 1);
    let s: tessera_results::ScenarioResult =
        serde_json::from_str(&std::fs::read_to_string(&files[0]).unwrap()).unwrap();
    let names: Vec<&str> = s.results.iter().map(|r| r.variant.as_str()).collect();
    assert_eq!(names, ["native", "upscale[scale=0.5]"]);

    let o = Command::new(env!("CARGO_BIN_EXE_tessera"))
        .arg("run")
        .arg(dir.path())
        .args(["--quiet", "--variants", "fsr9*", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("matches no variant") && err.contains("taau"),
        "{err}"
    );
}
