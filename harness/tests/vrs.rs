//! Hardware variable-rate shading without the hardware (lavapipe in CI): the variants are skipped
//! with the reason, the SPIR-V the raw pipelines are made of passes naga's validation (written
//! from validated WGSL, then read back and validated again), the raw material descriptor layout
//! is the shader's (reflected from the naga module), the plans need no GPU, and the raw Vulkan
//! passes without their rate attachment (`HardwareGpu::without_rates`) draw untextured and
//! textured scenes (the city, FlightHelmet when present) as `native` does. The mapping of rates
//! to attachment texels and the shade-count model are unit tests in
//! `techniques/adaptive_shading/attachment.rs`; GPU figures come from H200 runs
//! (`scenarios/adaptive/README.md`).

mod common;

use ash::vk;
use tessera::gpu::vrs::NEEDS;
use tessera::params::ParamValue;
use tessera::render::scene::SceneGpu;
use tessera::run::frames;
use tessera::techniques::adaptive_shading::hardware::{
    vrs_material_source, vrs_source, HardwareGpu, Rates, PREPASS, SCENE_PASS,
};
use tessera::techniques::adaptive_shading::raw_material;
use tessera::techniques::adaptive_shading::raw_pass::{self, spirv, MATERIAL_ENTRY_POINTS};
use tessera::techniques::{self, BuildContext, Target};
use tessera_metrics::HdrImage;

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
fn the_textured_vrs_pipelines_spirv_validates() {
    let source = vrs_material_source();
    for (stage, entry) in MATERIAL_ENTRY_POINTS {
        let words = spirv(&source, stage, entry).unwrap_or_else(|e| panic!("{entry}: {e}"));
        validate_spirv(&words, entry);
    }
}

/// What a raw descriptor type a naga global is bound as.
fn descriptor_type(module: &naga::Module, var: &naga::GlobalVariable) -> vk::DescriptorType {
    match (&var.space, &module.types[var.ty].inner) {
        (naga::AddressSpace::Uniform, _) => vk::DescriptorType::UNIFORM_BUFFER,
        (naga::AddressSpace::Storage { .. }, _) => vk::DescriptorType::STORAGE_BUFFER,
        (_, naga::TypeInner::Image { .. }) => vk::DescriptorType::SAMPLED_IMAGE,
        (_, naga::TypeInner::Sampler { comparison: false }) => vk::DescriptorType::SAMPLER,
        (space, ty) => panic!("unexpected binding {space:?} {ty:?}"),
    }
}

/// The raw descriptor set layouts of the textured draws (set 0: the scene's, set 1:
/// `raw_material.rs`'s) are the bindings the shader declares, each of the type it is used as;
/// every binding an entry point uses is in them (what Vulkan requires of a pipeline layout).
#[test]
fn the_raw_descriptor_layouts_are_the_shaders_bindings() {
    let source = vrs_material_source();
    let module = naga::front::wgsl::parse_str(&source).unwrap();
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .unwrap();
    let sets = [raw_pass::scene_bindings(), raw_material::bindings()];
    let mut declared: Vec<Vec<(u32, vk::DescriptorType)>> = vec![Vec::new(), Vec::new()];
    for (_, var) in module.global_variables.iter() {
        let Some(b) = &var.binding else { continue };
        assert!(b.group < 2, "{:?} is in group {}", var.name, b.group);
        declared[b.group as usize].push((b.binding, descriptor_type(&module, var)));
    }
    for (group, (mut d, mut raw)) in declared.into_iter().zip(sets.clone()).enumerate() {
        d.sort_by_key(|x| x.0);
        raw.sort_by_key(|x| x.0);
        assert_eq!(
            d, raw,
            "group {group}: the shader's bindings and the raw layout's"
        );
    }
    // Every global an entry point uses is in a layout.
    for (i, ep) in module.entry_points.iter().enumerate() {
        if !MATERIAL_ENTRY_POINTS.iter().any(|(_, e)| *e == ep.name) {
            continue;
        }
        let used = info.get_entry_point(i);
        for (handle, var) in module.global_variables.iter() {
            if used[handle].is_empty() {
                continue;
            }
            let Some(b) = &var.binding else { continue };
            // The material set is visible to fragment shaders only (as wgpu's layout).
            assert!(
                !(b.group == 1 && ep.stage == naga::ShaderStage::Vertex),
                "{} uses {:?} of the fragment-only material set",
                ep.name,
                var.name
            );
            let ty = descriptor_type(&module, var);
            assert!(
                sets[b.group as usize].contains(&(b.binding, ty)),
                "{}: uses {:?} (group {}, binding {}) the raw layout lacks",
                ep.name,
                var.name,
                b.group,
                b.binding
            );
        }
    }
    // The pool holds every binding of every set.
    let sizes = raw_material::pool_sizes(7);
    let total: u32 = sizes.iter().map(|p| p.descriptor_count).sum();
    assert_eq!(total as usize, 7 * raw_material::bindings().len());
}

/// A small city (alpha-tested foliage, moving vehicles, several materials) at `w` x `h`.
fn city(w: u32, h: u32) -> String {
    format!(
        r#"
resolution = [{w}, {h}]
[frames]
warmup = 1
measured = 2
[scene]
background = [0.55, 0.65, 0.8]
ambient = 0.12
anisotropy = 4
[scene.city]
seed = 1
blocks = 1
block_size = 30
buildings = 4
texture_size = 64
trees = 4
tree_cards = 4
poles = 2
parked = 2
moving = 4
speed = 10
[[scene.lights]]
type = "directional"
direction = [-0.5, -0.8, -0.3]
intensity = 3.0
[camera]
near = 0.1
far = 400.0
[[camera.keyframes]]
time = 0.0
position = [-30.0, 3.0, -1.0]
target = [0.0, 4.0, 0.0]
fov = 60
[[camera.keyframes]]
time = 1.0
position = [-26.0, 3.0, -1.0]
target = [4.0, 4.0, 0.0]
fov = 60
[[techniques]]
technique = "native"
"#
    )
}

/// Per pixel, the largest channel difference of two frames.
fn differences(a: &HdrImage, b: &HdrImage) -> Vec<f32> {
    assert_eq!((a.width, a.height), (b.width, b.height));
    let c = a.data.len() / (a.width * a.height) as usize;
    a.data
        .chunks(c)
        .zip(b.data.chunks(c))
        .map(|(x, y)| {
            x.iter()
                .zip(y)
                .take(3)
                .map(|(p, q)| (p - q).abs())
                .fold(0.0, f32::max)
        })
        .collect()
}

/// At most this many pixels in a thousand of a raw frame may differ from native's: the raw
/// passes' invariant positions against native's may move a silhouette on some drivers; on
/// lavapipe the frames are bitwise equal, and the bound there is 1 (drawing the city's
/// alpha-tested foliage in the pre-pass without its alpha test changes 55 of its 6,144 pixels,
/// leaving the textured draws out of the shading pass 5,069).
fn tolerance(gpu: &tessera::gpu::Gpu) -> usize {
    if gpu.info.name.contains("llvmpipe") {
        1
    } else {
        10
    }
}

fn assert_as_native(
    gpu: &tessera::gpu::Gpu,
    what: &str,
    r: &tessera::run::rendered::Rendered,
    native: &tessera::run::rendered::Rendered,
) {
    for (i, (a, b)) in r.hdr_frames.iter().zip(&native.hdr_frames).enumerate() {
        let pixels = (a.width * a.height) as usize;
        let d = differences(a, b);
        let off = d.iter().filter(|&&x| x > 1e-3).count();
        let max = d.iter().cloned().fold(0.0, f32::max);
        eprintln!("{what} frame {i}: {off} of {pixels} pixels differ, max {max}");
        assert!(
            off * 1000 <= pixels * tolerance(gpu),
            "{what} frame {i}: {off} of {pixels} pixels differ from native (max {max})"
        );
    }
}

/// Renders `s` with `native` and with both shapes of the raw passes without their rate
/// attachment (fixed 1x1: `native-vrs`'s single pass; adaptive: the motion pre-pass, the rate
/// passes, then the shading pass), and asserts that each raw frame is native's (within
/// [`tolerance`]). On an adapter with hardware VRS (the H200), also with the attachment:
/// `native-vrs` at 1x1 is native's frame, and at 2x2 covers exactly its pixels (the depth
/// pre-pass runs at 1x1) with fewer shading invocations.
fn raw_passes_draw_as_native(s: &tessera::scenario::Scenario, what: &str) {
    let gpu = common::gpu();
    let target = Target::new(s.width, s.height, s.scene.has_dynamic_objects());
    let mut scene = SceneGpu::new(&gpu.device, &gpu.queue, s).unwrap();
    let native = {
        let v = common::variant("native", &[]);
        let mut t = techniques::build(&v, &BuildContext::new(&gpu, &scene, target)).unwrap();
        frames::render(&gpu, &mut scene, s, t.as_mut(), true, true, &mut || {}).unwrap()
    };
    let background = native.hdr_frames[0]
        .data
        .chunks(4)
        .filter(|p| p[..3] == [0.55, 0.65, 0.8])
        .count();
    let pixels = (s.width * s.height) as usize;
    assert!(
        background < pixels / 2,
        "{what}: native shows mostly background"
    );
    for rates in [Rates::Fixed(1, 1), Rates::Adaptive(Default::default())] {
        let mut hw = HardwareGpu::without_rates(&gpu, rates, &scene, s.width, s.height)
            .unwrap_or_else(|e| panic!("{what} {rates:?}: {e}"));
        let r = frames::render(&gpu, &mut scene, s, &mut hw, true, true, &mut || {}).unwrap();
        assert_as_native(
            &gpu,
            &format!("{what} {rates:?} without rates"),
            &r,
            &native,
        );
        // The raw shading pass counted its own invocations: at least the covered pixels.
        if let Some(n) = hw.invocations() {
            let covered = hw.coverage(&gpu).iter().filter(|&&c| c).count() as u64;
            assert!(
                n >= covered,
                "{what}: {n} invocations for {covered} covered pixels"
            );
        }
    }
    let Ok(caps) = &gpu.vrs else { return };
    let mut full = HardwareGpu::new(&gpu, caps, Rates::Fixed(1, 1), &scene, s.width, s.height)
        .unwrap_or_else(|e| panic!("{what} native-vrs 1x1: {e}"));
    let r = frames::render(&gpu, &mut scene, s, &mut full, true, true, &mut || {}).unwrap();
    assert_as_native(&gpu, &format!("{what} native-vrs 1x1"), &r, &native);
    let covered = full.coverage(&gpu);
    let full_shades = full.invocations();
    let mut coarse = HardwareGpu::new(&gpu, caps, Rates::Fixed(2, 2), &scene, s.width, s.height)
        .unwrap_or_else(|e| panic!("{what} native-vrs 2x2: {e}"));
    frames::render(&gpu, &mut scene, s, &mut coarse, true, true, &mut || {}).unwrap();
    assert!(
        coarse.coverage(&gpu) == covered,
        "{what}: 2x2 covers other pixels than 1x1"
    );
    if let (Some(a), Some(b)) = (coarse.invocations(), full_shades) {
        eprintln!("{what}: fragment invocations 2x2 {a}, 1x1 {b}");
        assert!(a < b, "{what}: 2x2 shaded {a} times, 1x1 {b}");
    }
    let mut adaptive = HardwareGpu::new(
        &gpu,
        caps,
        Rates::Adaptive(Default::default()),
        &scene,
        s.width,
        s.height,
    )
    .unwrap_or_else(|e| panic!("{what} adaptive: {e}"));
    let r = frames::render(&gpu, &mut scene, s, &mut adaptive, true, true, &mut || {}).unwrap();
    assert_eq!(
        r.non_finite, 0,
        "{what}: adaptive shading wrote non-finite pixels"
    );
}

#[test]
fn the_raw_passes_draw_the_untextured_scene_as_native() {
    let s = common::scenario(common::TINY);
    raw_passes_draw_as_native(&s, "tiny");
}

#[test]
fn the_raw_passes_draw_the_textured_city_as_native() {
    let dir = tempfile::tempdir().unwrap();
    let s = tessera::scenario::parse(&dir.path().join("city.toml"), &city(96, 64))
        .unwrap_or_else(|e| panic!("{e}"));
    raw_passes_draw_as_native(&s, "city");
}

/// FlightHelmet: six meshes, normal maps, one BLEND material (drawn last, sorted, blended).
#[test]
fn the_raw_passes_draw_flight_helmet_as_native() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let path = root.join("../../shared/assets/FlightHelmet/FlightHelmet.gltf");
    if !path.exists() {
        eprintln!("skipped: {} is not there", path.display());
        return;
    }
    let src = format!(
        r#"
resolution = [64, 64]
[frames]
warmup = 0
measured = 2
[scene]
background = [0.0, 1.0, 0.0]
ambient = 0.3
[[scene.lights]]
type = "directional"
direction = [-0.4, -0.6, -0.7]
intensity = 2.0
[[scene.objects]]
shape = "mesh"
path = "{}"
materials = "file"
[camera]
[[camera.keyframes]]
time = 0
position = [0, 0.35, 0.9]
target = [0, 0.3, 0]
fov = 50
[[camera.keyframes]]
time = 1
position = [0.2, 0.35, 0.85]
target = [0, 0.3, 0]
fov = 50
[[techniques]]
technique = "native"
"#,
        path.display()
    );
    let dir = tempfile::tempdir().unwrap();
    let s = tessera::scenario::parse(&dir.path().join("helmet.toml"), &src)
        .unwrap_or_else(|e| panic!("{e}"));
    raw_passes_draw_as_native(&s, "FlightHelmet");
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
    assert_eq!(names, [PREPASS, "rates", "rate_attachment", SCENE_PASS]);
    // The paper's order of work (section 5): this frame's motion first, then the rates, then the
    // frame shaded at them; no pass only clears (the raw passes clear in their load ops).
    let pass = |name: &str| plan.passes.iter().find(|p| p.name == name).unwrap();
    assert!(pass(PREPASS).writes.contains(&"motion") && pass(PREPASS).self_counted);
    assert!(pass("rates").reads.contains(&"motion"));
    // Section 5.4's filter is applied by the attachment pass, which stores the filtered codes.
    assert!(pass("rate_attachment").reads.contains(&"rates_raw"));
    assert!(pass("rate_attachment").writes.contains(&"rates"));
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

/// `tessera validate` on the city: the hardware variants are skipped only where the extension is
/// missing, the software path on every adapter for the textures; the curve's scenario validates.
#[test]
fn validate_skips_only_the_deferred_path_for_textures() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_tessera"))
        .arg("validate")
        .arg(root.join("scenarios/content/city-1080p.toml"))
        .arg(root.join("scenarios/content/regimes-vrs.toml"))
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.starts_with("5 scenarios valid"), "{stdout}");
    for line in stdout.lines().skip(1) {
        if line.contains("vrs=hardware") || line.contains(": native-vrs") {
            assert!(line.contains(NEEDS) && !line.contains("textured"), "{line}");
        }
    }
    let software: Vec<&str> = stdout
        .lines()
        .filter(|l| l.contains("vrs=software"))
        .collect();
    assert_eq!(software.len(), 1, "{stdout}");
    assert!(
        software[0].contains("cannot draw textured materials")
            && software[0].ends_with("(skipped on every adapter)"),
        "{stdout}"
    );
    // Four sweep points, each with native-vrs and hardware adaptive shading: both named.
    let hardware = stdout
        .lines()
        .filter(|l| l.contains("regimes-vrs.toml"))
        .count();
    assert_eq!(hardware, 8, "{stdout}");
}
