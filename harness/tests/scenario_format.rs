//! The scenario format's error messages, asserted whole: file, line:column, dotted key, and what
//! is allowed. These texts are part of the user interface.

use std::path::Path;

use tessera::metric::MetricKind;
use tessera::scenario::{self, Reference};

const VALID: &str = r#"
resolution = [64, 32]

[frames]
warmup = 1
measured = 3

[camera]
[[camera.keyframes]]
time = 0.0
position = [0, 1, 5]
target = [0, 0, 0]

[[techniques]]
technique = "native"
"#;

/// Every error of `source` (with `extra` appended to the valid base), one per line.
fn errors(extra: &str) -> Vec<String> {
    let src = format!("{VALID}{extra}");
    match scenario::parse(Path::new("s.toml"), &src) {
        Ok(_) => Vec::new(),
        Err(e) => e.0.iter().map(|e| e.to_string()).collect(),
    }
}

fn errors_of(source: &str) -> Vec<String> {
    match scenario::parse(Path::new("s.toml"), source) {
        Ok(_) => Vec::new(),
        Err(e) => e.0.iter().map(|e| e.to_string()).collect(),
    }
}

#[test]
fn a_minimal_scenario_gets_defaults() {
    let s = scenario::parse(Path::new("dir/minimal.toml"), VALID).unwrap();
    assert_eq!(s.name, "minimal");
    assert_eq!((s.width, s.height), (64, 32));
    assert_eq!(s.reference, Reference::Native);
    assert_eq!(s.metrics, MetricKind::DEFAULT.to_vec());
    assert_eq!(s.save_frames, vec![2]);
    assert_eq!(s.variants.len(), 1);
    assert_eq!(s.variants[0].name, "native");
    assert!((s.time_step - 1.0 / 60.0).abs() < 1e-12);
}

#[test]
fn unknown_keys_are_rejected_with_the_allowed_ones() {
    assert_eq!(
        errors("\n[scene]\nshading_costs = 3\n"),
        ["s.toml:18:1: `scene.shading_costs`: unknown key `shading_costs`, expected one of `background`, `ambient`, `shading_cost`, `ground`, `lights`, `objects`, `anisotropy`, `city`"]
    );
}

#[test]
fn syntax_errors_have_a_position() {
    assert_eq!(
        errors_of("resolution = [1, 2\n"),
        ["s.toml:1:19: unclosed array, expected `]`"]
    );
}

#[test]
fn wrong_types_say_what_was_expected() {
    assert_eq!(
        errors_of("resolution = \"big\"\n"),
        ["s.toml:1:14: `resolution`: wrong type: found string \"big\", expected an array"]
    );
}

#[test]
fn unknown_technique_lists_the_known_and_suggests_the_closest() {
    assert_eq!(
        errors("\n[[techniques]]\ntechnique = \"upscal\"\n"),
        ["s.toml:18:13: `techniques[1].technique`: unknown technique \"upscal\" (did you mean \"upscale\"?): known techniques are \"native\", \"upscale\", \"fsr1\", \"taau\", \"fsr2\", \"checkerboard\", \"checkerboard-2x2\", \"adaptive-shading\", \"native-deferred\", \"native-vrs\", \"interlace\""]
    );
    assert_eq!(
        errors("\n[[techniques]]\ntechnique = \"raytrace\"\n"),
        ["s.toml:18:13: `techniques[1].technique`: unknown technique \"raytrace\": known techniques are \"native\", \"upscale\", \"fsr1\", \"taau\", \"fsr2\", \"checkerboard\", \"checkerboard-2x2\", \"adaptive-shading\", \"native-deferred\", \"native-vrs\", \"interlace\""]
    );
}

#[test]
fn parameters_are_checked_against_each_other() {
    let e = errors(
        "\n[[techniques]]\ntechnique = \"checkerboard-2x2\"\nblend_min = 0.2\nblend_max = 0.1\n",
    );
    assert_eq!(e.len(), 1, "{e:?}");
    assert!(
        e[0].contains("`techniques[1]`")
            && e[0].contains("blend_min (0.2) must be less than blend_max (0.1)"),
        "{e:?}"
    );
}

#[test]
fn values_are_range_checked() {
    let src = VALID
        .replace("resolution = [64, 32]", "resolution = [0, 20000]")
        .replace("measured = 3", "measured = 0");
    assert_eq!(
        errors_of(&src),
        [
            "s.toml:2:15: `resolution[0]`: 0 is out of range: expected an integer from 1 to 16384",
            "s.toml:2:18: `resolution[1]`: 20000 is out of range: expected an integer from 1 to 16384",
            "s.toml:6:12: `frames.measured`: 0 is out of range: expected an integer from 1 to 100000",
        ]
    );
}

#[test]
fn the_energy_window_is_range_checked_and_zero_turns_it_off() {
    let src = VALID.replace("measured = 3", "measured = 3\nenergy_window_ms = -5");
    let e = errors_of(&src);
    assert_eq!(e.len(), 1, "{e:?}");
    assert!(
        e[0].contains("`frames.energy_window_ms`")
            && e[0].contains("-5 is out of range: expected 0 to 60000 milliseconds"),
        "{e:?}"
    );
    let src = VALID.replace("measured = 3", "measured = 3\nenergy_window_ms = 0");
    let s = scenario::parse(Path::new("s.toml"), &src).unwrap();
    assert_eq!(s.energy_window_ms, Some(0.0));
    // The steps that end it: 2 to 600, a located error otherwise.
    let src = VALID.replace("measured = 3", "measured = 3\nenergy_steps = 1");
    let e = errors_of(&src);
    assert_eq!(e.len(), 1, "{e:?}");
    assert!(e[0].contains("`frames.energy_steps`"), "{e:?}");
    let src = VALID.replace("measured = 3", "measured = 3\nenergy_steps = 6");
    let s = scenario::parse(Path::new("s.toml"), &src).unwrap();
    assert_eq!(s.energy_steps, Some(6));
}

#[test]
fn near_and_far_must_be_ordered() {
    let src = VALID.replace("[camera]\n", "[camera]\nnear = 10.0\nfar = 1.0\n");
    assert_eq!(
        errors_of(&src),
        ["s.toml:10:7: `camera.far`: 1 is not allowed: expected 0 < near < far (near = 10)"]
    );
    let src = VALID.replace("[camera]\n", "[camera]\nnear = 0.0\n");
    assert_eq!(
        errors_of(&src),
        ["s.toml:9:8: `camera.near`: 0 is not allowed: expected 0 < near < far"]
    );
}

#[test]
fn keyframe_times_must_increase() {
    let extra = "\n[[camera.keyframes]]\ntime = 0.0\nposition = [1, 1, 5]\ntarget = [0, 0, 0]\n";
    // Appended keyframes after [[techniques]] still belong to camera.keyframes.
    assert_eq!(
        errors(extra),
        ["s.toml:18:8: `camera.keyframes[1].time`: 0 is not after the previous keyframe's time 0: keyframe times must increase"]
    );
}

#[test]
fn non_finite_numbers_are_rejected() {
    assert_eq!(
        errors("\n[[scene.objects]]\nshape = \"sphere\"\nposition = [0, nan, 0]\n"),
        ["s.toml:19:16: `scene.objects[0].position[1]`: NaN is not a finite number"]
    );
}

#[test]
fn parameters_are_checked_per_technique_and_sweeps_expand() {
    assert_eq!(
        errors("\n[[techniques]]\ntechnique = \"upscale\"\nscale = [0.5, 1.5]\nfiltr = \"nearest\"\n"),
        [
            "s.toml:19:15: `techniques[1].scale[1]`: 1.5 is out of range: expected a number in (0, 1]",
            "s.toml:20:9: `techniques[1].filtr`: unknown parameter (did you mean \"filter\"?): technique \"upscale\" takes \"scale\", \"filter\"",
        ]
    );
    let s = scenario::parse(
        Path::new("s.toml"),
        &format!("{VALID}\n[[techniques]]\ntechnique = \"upscale\"\nscale = [0.5, 0.75]\nfilter = [\"bilinear\", \"nearest\"]\n"),
    )
    .unwrap();
    let names: Vec<&str> = s.variants.iter().map(|v| v.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "native",
            "upscale[filter=bilinear,scale=0.5]",
            "upscale[filter=bilinear,scale=0.75]",
            "upscale[filter=nearest,scale=0.5]",
            "upscale[filter=nearest,scale=0.75]",
        ]
    );
}

#[test]
fn shapes_accept_only_their_own_keys() {
    assert_eq!(
        errors("\n[[scene.objects]]\nshape = \"sphere\"\nsize = [1, 1, 1]\nradius = -1\n"),
        [
            "s.toml:19:8: `scene.objects[0].size`: `size` is not used by shape \"sphere\": allowed keys are \"radius\"",
            "s.toml:20:10: `scene.objects[0].radius`: -1 is not allowed: expected a finite number > 0",
        ]
    );
}

#[test]
fn ssim_needs_one_window_of_pixels() {
    let src = VALID.replace(
        "resolution = [64, 32]",
        "resolution = [64, 8]\nmetrics = [\"psnr\", \"ssim\"]",
    );
    assert_eq!(
        errors_of(&src),
        ["s.toml:3:20: `metrics[1]`: ssim needs at least 11x11 pixels (one Gaussian window); the resolution is 64x8"]
    );
}

#[test]
fn gates_need_a_computed_measure_and_ordered_levels() {
    assert_eq!(
        errors("\n[[gates]]\nmeasure = \"ssim\"\nwarn_below = 0.9\n"),
        ["s.toml:18:11: `gates[0].measure`: metric \"ssim\" is not computed by this scenario: add it to `metrics`"]
    );
    assert_eq!(
        errors("\n[[gates]]\nmeasure = \"psnr\"\nwarn_below = 30\nfail_below = 35\n"),
        ["s.toml:20:14: `gates[0].fail_below`: fail_below (35) is above warn_below (30): failing must be the stricter level"]
    );
}

#[test]
fn every_shipped_scenario_is_valid() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios");
    let mut count = 0;
    for dir in std::fs::read_dir(&root).unwrap() {
        let dir = dir.unwrap().path();
        if !dir.is_dir() {
            continue;
        }
        let Ok(files) = scenario::collect(&[dir]) else {
            continue;
        };
        for file in files {
            if let Err(e) = scenario::load(&file) {
                // glTF models come from ci/setup.sh; everything else must be valid as shipped.
                let only_missing_models = e.0.iter().all(|e| e.message.contains("run ci/setup.sh"));
                assert!(only_missing_models, "{e}");
            }
            count += 1;
        }
    }
    assert!(count >= 4, "found only {count} scenarios");
}

#[test]
fn measured_auto_defaults_and_errors() {
    let auto = |v: &str| VALID.replace("measured = 3", &format!("measured = {v}"));
    let s = scenario::parse(Path::new("s.toml"), &auto("\"auto\"")).unwrap();
    let rule = s.auto.unwrap();
    assert_eq!(
        (rule.min, rule.max, rule.precision, rule.timeout_s),
        (10, 2000, 0.005, 15.0)
    );
    assert_eq!(s.measured_frames, 10, "metrics use min frames");
    let s = scenario::parse(Path::new("s.toml"), &auto("{ min = 20, precision = 0.01 }")).unwrap();
    let rule = s.auto.unwrap();
    assert_eq!((rule.min, rule.max, rule.precision), (20, 2000, 0.01));
    assert!(scenario::parse(Path::new("s.toml"), VALID)
        .unwrap()
        .auto
        .is_none());

    assert_eq!(
        errors_of(&auto("\"often\"")),
        ["s.toml:6:12: `frames.measured`: \"often\" is not allowed: expected an integer from 1 to 100000, \"auto\" or a table { min, max, precision, timeout_s }"]
    );
    assert_eq!(
        errors_of(&auto("{ min = 50, max = 20, precision = 0 }")),
        [
            "s.toml:6:30: `frames.measured.max`: 20 is below min (50): expected min <= max",
            "s.toml:6:46: `frames.measured.precision`: 0 is out of range: expected a relative precision above 0 and below 1 (0.005 = 0.5%)",
        ]
    );
    assert_eq!(
        errors_of(&auto("{ mn = 5 }")),
        ["s.toml:6:14: `frames.measured.mn`: unknown key `mn`, expected one of `min`, `max`, `precision`, `timeout_s`"]
    );
    let wrong = errors_of(&auto("2.5"));
    assert!(
        wrong[0].contains(
            "expected an integer, \"auto\" or a table { min, max, precision, timeout_s }"
        ),
        "{wrong:?}"
    );
}

#[test]
fn city_and_material_keys_are_checked() {
    let e = errors("\n[scene.city]\ntexture_size = 100\ntexture_detail = 2.0\nblocks = 0\n");
    assert_eq!(e.len(), 3, "{e:?}");
    assert!(
        e.iter()
            .any(|m| m.contains("`scene.city.texture_size`: 100 is not a power of two")),
        "{e:?}"
    );
    assert!(
        e.iter()
            .any(|m| m.contains("`scene.city.texture_detail`: 2 is above 1")),
        "{e:?}"
    );
    assert!(e.iter().any(|m| m.contains("`scene.city.blocks`")), "{e:?}");
    let city = scenario::parse(
        Path::new("s.toml"),
        &format!("{VALID}\n[scene.city]\nmoving = 3\n"),
    )
    .unwrap();
    assert!(
        city.scene.has_dynamic_objects(),
        "moving vehicles are dynamic objects"
    );
    let e = errors("\n[[scene.objects]]\nshape = \"box\"\nmaterials = \"file\"\n");
    assert!(e[0].contains("`materials`"), "{e:?}");
    let e = errors("\n[scene]\nanisotropy = 32\n");
    assert!(
        e[0].contains("`scene.anisotropy`: 32 is out of range"),
        "{e:?}"
    );
}
