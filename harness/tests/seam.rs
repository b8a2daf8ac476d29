//! The technique seam without a GPU (issue 21): every technique's options, requirements, plan,
//! baseline and frame pattern are read from a variant alone, and the per-variant answers are the
//! ones the issue asks for.

mod common;

use tessera::params::ParamValue;
use tessera::run::record::empty_result;
use tessera::techniques::{self, FramePattern, Target, ALL};
use tessera_results::Status;

use common::variant;

fn hardware() -> ParamValue {
    ParamValue::Str("hardware".into())
}

#[test]
fn each_adaptive_path_is_read_against_its_own_pipeline() {
    let software = variant("adaptive-shading", &[]);
    let hw = variant("adaptive-shading", &[("vrs", hardware())]);
    assert_eq!(
        software.technique.baseline(&software),
        Some("native-deferred")
    );
    assert_eq!(hw.technique.baseline(&hw), Some("native-vrs"));
    // The result records it, so `speedup.native-vrs` is written for the hardware path.
    assert_eq!(
        empty_result(&hw, Status::Ok).baseline.as_deref(),
        Some("native-vrs")
    );
    assert_eq!(
        empty_result(&variant("native", &[]), Status::Ok).baseline,
        None
    );
}

#[test]
fn alternating_techniques_say_so() {
    for (name, pattern) in [
        ("native", FramePattern::Same),
        ("upscale", FramePattern::Same),
        ("checkerboard", FramePattern::Alternating),
        ("checkerboard-2x2", FramePattern::Alternating),
        ("interlace", FramePattern::Alternating),
        ("adaptive-shading", FramePattern::Same),
        ("fsr2", FramePattern::Same),
    ] {
        let v = variant(name, &[]);
        assert_eq!(v.technique.frames(&v), pattern, "{name}");
    }
}

#[test]
fn requirements_are_known_without_a_gpu() {
    let hw = variant("adaptive-shading", &[("vrs", hardware())]);
    let fixed = variant("native-vrs", &[]);
    for v in [&hw, &fixed] {
        let r = techniques::requirements(v);
        assert!(r.hardware_only(), "{}", v.name);
        assert_eq!(
            techniques::skip_reasons(v),
            ["needs VK_KHR_fragment_shading_rate with attachmentFragmentShadingRate (skipped without a GPU that offers it)"]
        );
    }
    let msaa = variant(
        "checkerboard",
        &[("sampling", ParamValue::Str("msaa2x".into()))],
    );
    let reasons = techniques::skip_reasons(&msaa);
    assert_eq!(reasons.len(), 2, "{reasons:?}");
    assert!(
        reasons[0].starts_with("needs MULTISAMPLE_X2 for rgba16float"),
        "{reasons:?}"
    );
    // fsr1's anti-aliased input (issue 33) is a 4x MSAA render: 4x is what WebGPU guarantees
    // for these formats (lavapipe has it), and the reason says so where it is missing.
    let fsr1 = variant("fsr1", &[]);
    let reasons = techniques::skip_reasons(&fsr1);
    assert!(
        !reasons.is_empty()
            && reasons
                .iter()
                .all(|r| r.starts_with("needs MULTISAMPLE_X4")),
        "{reasons:?}"
    );
    // Every other default variant runs on every adapter.
    for t in ALL {
        let v = variant(t.name(), &[]);
        if t.name() != "native-vrs" && t.name() != "fsr1" {
            assert!(techniques::requirements(&v).is_empty(), "{}", t.name());
        }
        // And plans without a GPU.
        assert!(!techniques::plan(&v, Target::new(64, 48, true))
            .passes
            .is_empty());
    }
}

/// `fsr2` plans AMD's passes in AMD's dispatch order, after the engine's inputs (scene, motion
/// provider, motion vectors), and declares one cycle of AMD's jitter as its convergence
/// (`ffxFsr2GetJitterPhaseCount` at the mode's render width); a mode with a `scale` is refused.
#[test]
fn fsr2_plans_amds_passes_and_declares_amds_phase_count() {
    let v = variant("fsr2", &[]);
    let names = |v: &tessera::techniques::Variant, dynamic: bool| -> Vec<&'static str> {
        techniques::plan(v, Target::new(1920, 1080, dynamic))
            .passes
            .iter()
            .map(|p| p.name)
            .collect()
    };
    let amd = [
        "luminance_pyramid",
        "auto_exposure",
        "reconstruct",
        "depth_clip",
        "lock",
        "accumulate",
    ];
    let with = |head: &[&'static str], tail: &[&'static str]| -> Vec<&'static str> {
        head.iter().chain(&amd).chain(tail).copied().collect()
    };
    assert_eq!(names(&v, false), with(&["scene", "motion"], &["rcas"]));
    assert_eq!(
        names(&v, true),
        with(&["scene", "velocity", "motion"], &["rcas"])
    );
    let plain = variant("fsr2", &[("sharpening", ParamValue::Bool(false))]);
    assert_eq!(names(&plain, false), with(&["scene", "motion"], &[]));
    for (mode, phases) in [
        ("quality", 18),
        ("balanced", 23),
        ("performance", 32),
        ("ultra-performance", 72),
    ] {
        let v = variant("fsr2", &[("mode", ParamValue::Str(mode.into()))]);
        assert_eq!(v.technique.convergence(&v, 1920), phases, "{mode}");
    }
    let both = techniques::by_name("fsr2")
        .unwrap()
        .check(&variant("fsr2", &[("scale", ParamValue::Float(0.4))]));
    assert!(both.unwrap_err().contains("sets the render scale"));
}
