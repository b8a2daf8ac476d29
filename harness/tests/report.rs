//! `tessera report`: its table read back against the run's own `results.csv` on lavapipe (every
//! GPU ms, speed-up and metric of every variant, to the printed precision), the Pareto front
//! against a hand check of the same numbers, and bad input refused with exit code 2.

use std::collections::BTreeMap;
use std::process::Command;

fn tessera() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tessera"))
}

/// (variant, measure) -> value, from `results.csv`.
fn csv_values(text: &str) -> BTreeMap<(String, String), f64> {
    let mut out = BTreeMap::new();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| head.iter().position(|h| *h == n).unwrap();
    let (variant, measure, value) = (col("variant"), col("measure"), col("value"));
    for line in lines {
        // Variant names hold commas inside quotes (`upscale[scale=0.5]` has none, but be safe).
        let fields = split_csv(line);
        if let Ok(v) = fields[value].parse::<f64>() {
            out.insert((fields[variant].clone(), fields[measure].clone()), v);
        }
    }
    out
}

fn split_csv(line: &str) -> Vec<String> {
    let mut out = vec![String::new()];
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' if quoted && chars.peek() == Some(&'"') => {
                chars.next();
                out.last_mut().unwrap().push('"');
            }
            '"' => quoted = !quoted,
            ',' if !quoted => out.push(String::new()),
            c => out.last_mut().unwrap().push(c),
        }
    }
    out
}

const SCENARIO: &str = r#"
resolution = [64, 36]
metrics = ["psnr", "flip"]
[frames]
warmup = 1
measured = 3
[scene]
shading_cost = 2
[[scene.lights]]
type = "directional"
direction = [-0.4, -1.0, -0.3]
intensity = 2.0
[[scene.objects]]
shape = "box"
position = [0, 0.5, 0]
color = [0.8, 0.3, 0.2]
[[scene.objects]]
shape = "sphere"
position = [1.2, 0.5, 0]
radius = 0.5
[camera]
[[camera.keyframes]]
time = 0
position = [0, 1.5, 4]
target = [0, 0.4, 0]
[[camera.keyframes]]
time = 1
position = [0.3, 1.5, 4]
target = [0, 0.4, 0]
[[techniques]]
technique = "native"
[[techniques]]
technique = "upscale"
scale = [0.5, 0.75]
"#;

#[test]
fn report_equals_the_runs_results_csv() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("report-check.toml");
    std::fs::write(&file, SCENARIO).unwrap();
    let out = dir.path().join("runs");
    let run = tessera()
        .args(["run", file.to_str().unwrap(), "--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(
        run.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&run.stdout)
    );
    let run_dir = std::fs::read_dir(&out)
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    let run_id = run_dir.file_name().unwrap().to_str().unwrap().to_string();
    let csv = csv_values(&std::fs::read_to_string(run_dir.join("results.csv")).unwrap());

    // The folder of runs is descended into.
    let rep = tessera()
        .args(["report", "--format", "md"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(rep.status.code(), Some(0));
    let md = String::from_utf8(rep.stdout).unwrap();
    assert!(md.contains("report-check on "), "{md}");
    assert!(md.contains(&format!("runs: {run_id}")), "{md}");

    let rows: Vec<Vec<String>> = md
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| variant"))
        .map(|l| {
            l.trim_matches('|')
                .split(" | ")
                .map(|c| c.trim().to_string())
                .collect()
        })
        .collect();
    let head: Vec<String> = md
        .lines()
        .find(|l| l.starts_with("| variant"))
        .unwrap()
        .trim_matches('|')
        .split(" | ")
        .map(|c| c.trim().to_string())
        .collect();
    assert_eq!(
        head,
        [
            "variant",
            "GPU ms",
            "speed-up",
            "psnr (dB)",
            "flip",
            "front",
            "runs"
        ]
    );
    assert_eq!(rows.len(), 3, "{md}");
    let get = |v: &str, m: &str| {
        *csv.get(&(v.to_string(), m.to_string()))
            .unwrap_or_else(|| panic!("no {m} for {v} in results.csv"))
    };
    for r in &rows {
        let v = r[0].as_str();
        assert_eq!(r[1], format!("{:.3}", get(v, "gpu_ms.median")), "{v}");
        assert_eq!(r[2], format!("{:.2}x", get(v, "speedup")), "{v}");
        if v == "native" {
            assert_eq!(r[3], "inf");
        } else {
            assert_eq!(r[3], format!("{:.2}", get(v, "psnr")), "{v}");
        }
        let flip = get(v, "flip");
        let printed: f64 = r[4].parse().unwrap();
        assert!(
            (printed - flip).abs() <= 0.5e-5 * flip.abs().max(1.0),
            "{v}: {printed} against {flip}"
        );
        assert_eq!(r[6], run_id);
    }
    // The front, checked by hand on the same numbers: on the FLIP front exactly the rows no other
    // row beats in both GPU ms and FLIP.
    for r in &rows {
        let (t, f) = (get(&r[0], "gpu_ms.median"), get(&r[0], "flip"));
        let dominated = rows.iter().any(|o| {
            let (to, fo) = (get(&o[0], "gpu_ms.median"), get(&o[0], "flip"));
            o[0] != r[0] && to <= t && fo <= f && (to < t || fo < f)
        });
        assert_eq!(r[5].split(", ").any(|x| x == "flip"), !dominated, "{r:?}");
    }
    // native is the reference (FLIP 0, infinite PSNR): on both fronts unless a faster row ties it.
    let native = rows.iter().find(|r| r[0] == "native").unwrap();
    assert!(native[5].contains("psnr") && native[5].contains("flip"));

    // The text format carries the same numbers.
    let text = tessera().arg("report").arg(&run_dir).output().unwrap();
    let text = String::from_utf8(text.stdout).unwrap();
    for r in &rows {
        assert!(text.contains(&r[1]), "{text}");
    }
}

#[test]
fn report_refuses_what_is_not_a_run() {
    let dir = tempfile::tempdir().unwrap();
    let o = tessera().arg("report").arg(dir.path()).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("run.json"), "{err}");
    let o = tessera()
        .args(["report", "no/such/folder"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
}
