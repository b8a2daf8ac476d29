//! `frames.save_worst`: by default each variant's run folder holds, beside the `frames.save`
//! frames, the worst measured frame of each of its metrics (its output, FLIP heat map and the
//! reference's frame), so the frames where a technique is worst can be looked at (issue 22, item
//! 6); `save_worst = false` saves the `save` frames only; a wrong type is a located error.

mod common;

use std::path::{Path, PathBuf};

use tessera_results::{ScenarioResult, VariantResult};

/// The tiny moving scene with 6 measured frames, frame 0 saved, and a few variants whose error
/// changes over the frames.
fn source(extra_frames: &str) -> String {
    common::TINY
        .replace(
            "measured = 2",
            &format!("measured = 6\nsave = [0]\n{extra_frames}"),
        )
        .replace(
            "resolution = [48, 32]\n",
            "resolution = [48, 32]\nmetrics = [\"psnr\", \"max-abs-error\", \"flip\"]\n",
        )
        .replace(
            "[[techniques]]\ntechnique = \"native\"\n",
            "[[techniques]]\ntechnique = \"native\"\n[[techniques]]\ntechnique = \"upscale\"\nscale = 0.5\n[[techniques]]\ntechnique = \"checkerboard\"\n",
        )
}

/// Runs `src` with `tessera run` into `out`: the run folder and the scenario's result.
fn run(src: &str, out: &Path) -> (PathBuf, ScenarioResult) {
    let f = out.join("worst.toml");
    std::fs::write(&f, src).unwrap();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_tessera"))
        .args(["run", f.to_str().unwrap(), "--quiet", "--out"])
        .arg(out.join("results"))
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{stdout}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let run_dir = std::fs::read_dir(out.join("results"))
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    let text = std::fs::read_to_string(run_dir.join("scenarios/worst.json")).unwrap();
    (run_dir, serde_json::from_str(&text).unwrap())
}

/// The worst frame of `metric` of `v`, found here from its per-frame values (first of equals).
fn worst(v: &VariantResult, metric: &str) -> u32 {
    let m = v.metrics.iter().find(|m| m.name == metric).unwrap();
    let mut best: Option<(u32, f64)> = None;
    for (&f, &x) in m.frames.iter().zip(&m.per_frame) {
        let worse = match best {
            None => x.is_finite(),
            Some((_, w)) => x.is_finite() && if m.higher_is_better { x < w } else { x > w },
        };
        if worse {
            best = Some((f, x));
        }
    }
    best.unwrap().0
}

fn frames_of(images: &[&tessera_results::ImageRecord], kind: &str) -> Vec<u32> {
    let mut f: Vec<u32> = images
        .iter()
        .filter(|i| i.kind == kind)
        .map(|i| i.frame)
        .collect();
    f.sort();
    f
}

#[test]
fn the_worst_frame_of_every_metric_is_among_the_saved_images() {
    let dir = tempfile::tempdir().unwrap();
    let (run_dir, result) = run(&source(""), dir.path());
    let all: Vec<&tessera_results::ImageRecord> =
        result.results.iter().flat_map(|v| &v.images).collect();
    let reference_frames = frames_of(&all, "reference");
    let mut added = 0;
    for v in result.results.iter().filter(|v| v.technique != "native") {
        let own: Vec<&tessera_results::ImageRecord> = v.images.iter().collect();
        let outputs = frames_of(&own, "output");
        let heatmaps = frames_of(&own, "heatmap");
        assert!(outputs.contains(&0), "{}: the save frame", v.variant);
        for metric in ["psnr", "max-abs-error", "flip"] {
            let f = worst(v, metric);
            // The worst frame itself, or a saved frame with the same (worst) value.
            let m = v.metrics.iter().find(|m| m.name == metric).unwrap();
            let value_at =
                |frame: u32| m.per_frame[m.frames.iter().position(|&x| x == frame).unwrap()];
            let shown = outputs.iter().find(|&&o| value_at(o) == value_at(f));
            let shown = *shown.unwrap_or_else(|| {
                panic!(
                    "{} {metric}: worst frame {f} not saved (saved {outputs:?})",
                    v.variant
                )
            });
            assert!(
                heatmaps.contains(&shown),
                "{} {metric}: heat map of frame {shown}",
                v.variant
            );
            assert!(
                reference_frames.contains(&shown),
                "{} {metric}: reference frame {shown} (saved {reference_frames:?})",
                v.variant
            );
        }
        added += outputs.len() - 1;
        for i in &v.images {
            assert!(run_dir.join(&i.path).is_file(), "{} missing", i.path);
        }
    }
    // The scene moves: some metric's worst frame is not frame 0, so frames were added.
    assert!(
        added > 0,
        "no worst frame beside frame 0: {:?}",
        result.results
    );
    // The native reference has no error of its own: its save frame only.
    let native = result
        .results
        .iter()
        .find(|v| v.technique == "native")
        .unwrap();
    let own: Vec<&tessera_results::ImageRecord> = native.images.iter().collect();
    assert_eq!(frames_of(&own, "output"), [0]);
}

#[test]
fn save_worst_false_saves_the_save_frames_only() {
    let dir = tempfile::tempdir().unwrap();
    let (_, result) = run(&source("save_worst = false"), dir.path());
    for v in &result.results {
        assert!(
            v.images.iter().all(|i| i.frame == 0),
            "{}: {:?}",
            v.variant,
            v.images
        );
    }
}

#[test]
fn save_worst_must_be_a_boolean() {
    let src = source("save_worst = \"yes\"");
    let err = tessera::scenario::parse(Path::new("s.toml"), &src)
        .expect_err("a string is refused")
        .0
        .iter()
        .map(|e| e.to_string())
        .collect::<Vec<_>>();
    assert_eq!(err.len(), 1, "{err:?}");
    assert!(
        err[0].starts_with("s.toml:8:14: `frames.save_worst`: ")
            && err[0].contains("expected true or false"),
        "{err:?}"
    );
}
