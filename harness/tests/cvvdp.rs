//! `cvvdp` in a scenario: ColorVideoVDP records on every variant, maps of saved frames, and the
//! flicker finding of the quality suite (checkerboard's min-max history clamp flickers on the
//! static scene, `clamp = none` does not) ranked the same way by JOD. Also the `display` key's
//! validation.

mod common;

use tessera_results::{ScenarioResult, VariantResult};

/// `scenarios/quality/static.toml` with its checkerboard variants cut to the two clamps.
fn static_scene(metrics: &str) -> String {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenarios/quality/static.toml"
    );
    let src = std::fs::read_to_string(path).unwrap();
    let scene = &src[..src.find("[[techniques]]").unwrap()];
    let line = scene
        .lines()
        .find(|l| l.starts_with("metrics = "))
        .unwrap()
        .to_string();
    let scene = scene.replace(&line, &format!("metrics = {metrics}"));
    format!(
        "{scene}[[techniques]]\ntechnique = \"native\"\n\n[[techniques]]\ntechnique = \
         \"checkerboard\"\nclamp = [\"none\", \"min-max\"]\n"
    )
}

fn run(src: &str) -> ScenarioResult {
    common::run_ok(src, "static.toml")
}

fn metric(v: &VariantResult, name: &str) -> f64 {
    v.metrics
        .iter()
        .find(|m| m.name == name)
        .unwrap_or_else(|| panic!("{} has no {name}", v.variant))
        .value
}

#[test]
fn jod_ranks_the_flickering_min_max_clamp_below_no_clamp_on_the_static_scene() {
    let result = run(&static_scene("[\"flicker\", \"cvvdp\"]"));
    let variant = |needle: &str| {
        result
            .results
            .iter()
            .find(|v| v.variant.contains(needle))
            .unwrap_or_else(|| panic!("no variant {needle}"))
    };
    let (none, min_max, native) = (
        variant("clamp=none"),
        variant("clamp=min-max"),
        variant("native"),
    );
    let jod = |v| metric(v, "cvvdp");
    eprintln!(
        "static scene JOD: native {}, clamp=none {}, clamp=min-max {}; flicker JOD {} / {}; \
         transient share {} / {}",
        jod(native),
        jod(none),
        jod(min_max),
        metric(none, "cvvdp-flicker"),
        metric(min_max, "cvvdp-flicker"),
        metric(none, "cvvdp-transient-share"),
        metric(min_max, "cvvdp-transient-share"),
    );
    // The flicker finding the quality suite records in 8-bit units, seen by a viewer.
    assert_eq!(metric(none, "flicker"), 0.0);
    assert!(metric(min_max, "flicker") > 0.0);
    assert!(
        jod(min_max) < jod(none),
        "{} vs {}",
        jod(min_max),
        jod(none)
    );
    assert!(metric(min_max, "cvvdp-flicker") < metric(none, "cvvdp-flicker"));
    assert_eq!(jod(native), 10.0, "the reference against itself");
    // Per-frame JOD, higher is better, and the map of the saved (last) frame.
    let rec = none.metrics.iter().find(|m| m.name == "cvvdp").unwrap();
    assert!(rec.higher_is_better);
    assert_eq!(rec.per_frame.len(), 8);
    let maps: Vec<_> = min_max
        .images
        .iter()
        .filter(|i| i.kind == "cvvdp")
        .collect();
    assert_eq!(maps.len(), 1, "{:?}", min_max.images);
    assert_eq!(maps[0].frame, 7);
}

#[test]
fn display_is_checked_with_what_is_allowed() {
    let bad = |extra: &str, metrics: &str| {
        let src = format!("display = {extra}\n{}", static_scene(metrics));
        tessera::scenario::parse(std::path::Path::new("s.toml"), &src)
            .unwrap_err()
            .to_string()
    };
    let e = bad("\"standard_5k\"", "[\"cvvdp\"]");
    assert!(
        e.contains("unknown display") && e.contains("paper_27in_4k"),
        "{e}"
    );
    let e = bad("{ peak = 400 }", "[\"cvvdp\"]");
    assert!(e.contains("unknown field `peak`"), "{e}");
    let e = bad("\"standard_fhd\"", "[\"psnr\"]");
    assert!(e.contains("add \"cvvdp\" to metrics"), "{e}");
    let ok = format!(
        "display = {{ base = \"paper_27in_4k\", peak_luminance = 400 }}\n{}",
        static_scene("[\"cvvdp\"]")
    );
    let s = common::scenario(&ok);
    assert!(matches!(s.display, tessera_metrics::DisplaySpec::Custom(_)));
}

/// `tessera diff` on two folders of numbered frames prints JOD beside PSNR, SSIM and FLIP.
#[test]
fn diff_of_two_frame_folders_prints_jod() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("ref"), dir.path().join("test"));
    std::fs::create_dir_all(&a).unwrap();
    std::fs::create_dir_all(&b).unwrap();
    for f in 0..6u8 {
        let frame = |level: u8| {
            let mut img = tessera_metrics::Rgb8Image::filled(32, 24, [90, 120, 150]);
            for (i, px) in img.data.chunks_mut(3).enumerate() {
                if (i % 32 / 4 + i / 32 / 4) % 2 == 0 {
                    px.copy_from_slice(&[level, level, level]);
                }
            }
            img
        };
        let name = format!("frame_{f:04}.png");
        tessera_metrics::save_png(&a.join(&name), &frame(200)).unwrap();
        // The test flickers: alternate frames darker.
        let level = if f % 2 == 0 { 200 } else { 180 };
        tessera_metrics::save_png(&b.join(&name), &frame(level)).unwrap();
    }
    let run = |extra: &[&str]| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_tessera"))
            .arg("diff")
            .args([&a, &b])
            .args(extra)
            .output()
            .unwrap();
        (
            o.status.code().unwrap_or(-1),
            String::from_utf8_lossy(&o.stdout).into_owned(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let (code, out, err) = run(&["--fps", "30"]);
    assert_eq!(code, 0, "{out}{err}");
    for label in [
        "frames",
        "PSNR (RGB)",
        "SSIM (RGB)",
        "FLIP mean",
        "JOD",
        "flicker",
    ] {
        assert!(out.contains(label), "{label} missing:\n{out}");
    }
    assert!(
        out.contains("6 of 32x24") && out.contains("30 fps"),
        "{out}"
    );
    let (code, _, err) = run(&["--display", "standard_5k"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("unknown display"), "{err}");
}
