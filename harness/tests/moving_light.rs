//! A world that changes without moving (issue 33, item 5): `scenarios/quality/moving-light.toml`,
//! a still camera under an oscillating point light, run with `tessera run`. `taau` at scale 1
//! with its defaults (a shipped TAA: it clips every frame and always blends in new samples)
//! stays within 0.5 dB of `native`'s PSNR against the converged reference or above it; the
//! still-scene accumulator's options lose clearly there. Lights' `animation` is validated like
//! objects'.

use std::path::Path;

use tessera_results::ScenarioResult;

fn psnr(s: &ScenarioResult, variant: &str) -> f64 {
    let r = s
        .results
        .iter()
        .find(|r| r.variant == variant)
        .unwrap_or_else(|| panic!("no variant {variant}"));
    r.metrics.iter().find(|m| m.name == "psnr").unwrap().value
}

#[test]
fn a_shipped_taa_follows_a_moving_light_and_the_accumulator_options_do_not() {
    let dir = tempfile::tempdir().unwrap();
    let scenario =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/quality/moving-light.toml");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_tessera"))
        .args(["run", scenario.to_str().unwrap(), "--quiet", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    let run = std::fs::read_dir(dir.path())
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    let text = std::fs::read_to_string(run.join("scenarios/moving-light.json")).unwrap();
    let s: ScenarioResult = serde_json::from_str(&text).unwrap();
    let native = psnr(&s, "native");
    let taau = psnr(&s, "taau");
    assert!(taau >= native - 0.5, "taau {taau} dB, native {native} dB");
    for held in [
        "taau[scale=1,freeze_converged]",
        "taau[scale=1,clip_moving_only]",
    ] {
        let p = psnr(&s, held);
        assert!(p < taau - 3.0, "{held}: {p} dB against taau's {taau} dB");
    }
    // Its warm-up is taau's declared convergence at scale 1 (8 phases), and the result says so.
    let c = s
        .results
        .iter()
        .find(|r| r.variant == "taau")
        .unwrap()
        .convergence
        .unwrap();
    assert_eq!((c.frames, c.warmup_frames, c.converged), (8, 8, true));
}

fn errors(light: &str) -> Vec<String> {
    let src = format!(
        "resolution = [8, 8]\n[camera]\n[[camera.keyframes]]\ntime = 0\nposition = [0, 1, 4]\ntarget = [0, 0, 0]\n[[techniques]]\ntechnique = \"native\"\n[[scene.lights]]\n{light}\n"
    );
    match tessera::scenario::parse(Path::new("s.toml"), &src) {
        Ok(_) => Vec::new(),
        Err(e) => e.0.iter().map(|e| e.to_string()).collect(),
    }
}

#[test]
fn lights_take_the_animation_table_and_a_wrong_kind_is_a_located_error() {
    assert!(errors("type = \"point\"\nposition = [0, 1, 0]\nanimation = { kind = \"oscillate\", amplitude = [1, 0, 0], period = 1 }").is_empty());
    assert!(errors("type = \"directional\"\nanimation = { kind = \"rotate\", axis = [0, 1, 0], degrees_per_second = 30 }").is_empty());
    let e = errors("type = \"point\"\nposition = [0, 1, 0]\nanimation = { kind = \"rotate\" }");
    assert_eq!(e.len(), 1, "{e:?}");
    assert!(
        e[0].starts_with("s.toml:")
            && e[0].contains("`scene.lights[0].animation.kind`")
            && e[0].contains("a point light's animation is `translate` or `oscillate`"),
        "{e:?}"
    );
    let e = errors(
        "type = \"directional\"\nanimation = { kind = \"translate\", velocity = [1, 0, 0] }",
    );
    assert!(
        e.len() == 1 && e[0].contains("a directional light's animation is `rotate`"),
        "{e:?}"
    );
}

#[test]
fn an_animated_light_moves_and_turns_with_time() {
    use glam::Vec3;
    use tessera::world::scene::{Animation, Light};
    let p = Light::Point {
        position: Vec3::new(0.0, 1.0, 0.0),
        color: Vec3::ONE,
        intensity: 1.0,
        animation: Some(Animation::Translate {
            velocity: Vec3::new(2.0, 0.0, 0.0),
        }),
    };
    match p.at(0.5) {
        Light::Point { position, .. } => assert_eq!(position, Vec3::new(1.0, 1.0, 0.0)),
        _ => unreachable!(),
    }
    let d = Light::Directional {
        direction: Vec3::X,
        color: Vec3::ONE,
        intensity: 1.0,
        animation: Some(Animation::Rotate {
            axis: Vec3::Y,
            degrees_per_second: 90.0,
        }),
    };
    match d.at(1.0) {
        Light::Directional { direction, .. } => {
            assert!((direction - Vec3::NEG_Z).length() < 1e-6, "{direction}")
        }
        _ => unreachable!(),
    }
}
