//! Hardware variable-rate shading without the hardware (lavapipe in CI): the variants are skipped
//! with the reason, the SPIR-V the raw pipeline is made of passes naga's validation (written from
//! validated WGSL, then read back and validated again), and the plans need no GPU. The mapping of
//! rates to attachment texels and the shade-count model are unit tests in
//! `techniques/adaptive_shading/attachment.rs`; GPU figures come from H200 runs
//! (`scenarios/adaptive/README.md`).

mod common;

use tessera::gpu::vrs::NEEDS;
use tessera::params::ParamValue;
use tessera::render::scene::SceneGpu;
use tessera::techniques::adaptive_shading::hardware::{vrs_source, PREPASS, SCENE_PASS};
use tessera::techniques::adaptive_shading::raw_pass::spirv;
use tessera::techniques::{self, BuildContext, Target};

fn validate_spirv(words: &[u32], what: &str) {
    assert_eq!(words[0], 0x0723_0203, "{what}: not SPIR-V");
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    let module = naga::front::spv::parse_u8_slice(&bytes, &Default::default())
        .unwrap_or_else(|e| panic!("{what}: naga cannot read the SPIR-V back: {e}"));
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{what}: the SPIR-V does not validate: {e:?}"));
}

#[test]
fn the_vrs_pipelines_spirv_validates() {
    let source = vrs_source();
    let vs = spirv(&source, naga::ShaderStage::Vertex, "vs_vrs").unwrap();
    let fs = spirv(&source, naga::ShaderStage::Fragment, "fs_vrs").unwrap();
    let motion = spirv(&source, naga::ShaderStage::Fragment, "fs_vrs_motion").unwrap();
    validate_spirv(&vs, "vs_vrs");
    validate_spirv(&fs, "fs_vrs");
    validate_spirv(&motion, "fs_vrs_motion");
    // A missing entry point is an error, not a panic.
    assert!(spirv(&source, naga::ShaderStage::Fragment, "no_such_entry").is_err());
}

#[test]
fn hardware_plans_need_no_gpu() {
    let target = Target::new(100, 60, true);
    let hw = common::variant(
        "adaptive-shading",
        &[("vrs", ParamValue::Str("hardware".into()))],
    );
    let plan = techniques::plan(&hw, target);
    let names: Vec<&str> = plan.passes.iter().map(|p| p.name).collect();
    assert_eq!(
        names,
        [
            PREPASS,
            "rates",
            "rate_filter",
            "rate_attachment",
            SCENE_PASS
        ]
    );
    // The paper's order of work (section 5): this frame's motion first, then the rates, then the
    // frame shaded at them; no pass only clears (the raw passes clear in their load ops).
    let pass = |name: &str| plan.passes.iter().find(|p| p.name == name).unwrap();
    assert!(pass(PREPASS).writes.contains(&"motion") && pass(PREPASS).self_counted);
    assert!(pass("rates").reads.contains(&"motion"));
    assert!(pass(SCENE_PASS).self_counted && !pass(SCENE_PASS).writes.contains(&"motion"));
    // 100x60 at 16x16 texels: a 7x4 attachment.
    let a = plan
        .resources
        .iter()
        .find(|r| r.name == "attachment")
        .unwrap();
    assert_eq!((a.desc.width, a.desc.height), (7, 4));
    let fixed = common::variant("native-vrs", &[("rate", ParamValue::Str("2x2".into()))]);
    let names: Vec<&str> = techniques::plan(&fixed, target)
        .passes
        .iter()
        .map(|p| p.name)
        .collect();
    assert_eq!(names, [SCENE_PASS]);
    // Fixed rates need no motion (`native` has none).
    let fixed_plan = techniques::plan(&fixed, target);
    assert!(fixed_plan.resources.iter().all(|r| r.name != "motion"));
}

#[test]
fn pixel_sampling_needs_the_software_path() {
    let v = common::variant(
        "adaptive-shading",
        &[
            ("vrs", ParamValue::Str("hardware".into())),
            ("coarse_sample", ParamValue::Str("pixel".into())),
        ],
    );
    let err = v.technique.check(&v).unwrap_err();
    assert!(err.contains("needs `vrs = \"software\"`"), "{err}");
}

/// On an adapter without the extension (lavapipe), building a hardware variant is unsupported with
/// the reason, and a run reports those variants as skipped beside the software path, which runs.
#[test]
fn without_the_extension_hardware_variants_are_skipped() {
    let gpu = common::gpu();
    let target = Target::new(48, 32, false);
    let scene = SceneGpu::new(&gpu.device, &gpu.queue, &common::scenario(common::TINY)).unwrap();
    for v in [
        common::variant(
            "adaptive-shading",
            &[("vrs", ParamValue::Str("hardware".into()))],
        ),
        common::variant("native-vrs", &[]),
    ] {
        match (
            &gpu.vrs,
            techniques::build(&v, &BuildContext::new(&gpu, &scene, target)),
        ) {
            (Ok(caps), Ok(_)) => eprintln!("{} offers VRS: {caps:?}", gpu.info.name),
            (Err(reason), Err(u)) => {
                assert!(u.0.starts_with(NEEDS), "{}", u.0);
                assert_eq!(&u.0, reason);
            }
            (Ok(_), Err(u)) => panic!("VRS offered but the variant failed: {}", u.0),
            (Err(r), Ok(_)) => panic!("built without VRS ({r})"),
        }
    }
    if gpu.vrs.is_ok() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("vrs.toml");
    let scenario = common::TINY.to_string()
        + r#"
[[techniques]]
technique = "native-vrs"
rate = ["1x1", "2x2"]

[[techniques]]
technique = "adaptive-shading"
vrs = ["software", "hardware"]
"#;
    std::fs::write(&path, scenario).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_tessera"))
        .args(["run", path.to_str().unwrap(), "--quiet", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let skipped: Vec<&str> = stdout.lines().filter(|l| l.contains("skipped: ")).collect();
    assert_eq!(skipped.len(), 3, "{stdout}");
    assert!(skipped.iter().all(|l| l.contains(NEEDS)), "{stdout}");
    let verdict = stdout.lines().last().unwrap();
    assert!(
        verdict.starts_with("PASSED: ") && verdict.contains(" ok, 3 skipped, 0 failed"),
        "{stdout}"
    );
}
