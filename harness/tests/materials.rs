//! Textured materials on the default adapter (lavapipe in CI), at small sizes: textures are
//! sampled, mip chains average in linear space, alpha test cuts out, normal maps shade; glTF
//! files that are broken give errors naming the file and what is wrong; the assimp test models
//! and FlightHelmet (when present) load and render. Each rendering test compares against a
//! control that differs only in the feature, so it fails when the feature is off.

mod common;

use std::path::{Path, PathBuf};

use tessera::render::scene::SceneGpu;
use tessera::run::frames;
use tessera::techniques::{self, BuildContext, Target};
use tessera::world::gltf_model;
use tessera_metrics::HdrImage;

const ASSIMP: &str = "/usr/share/assimp/models/glTF2";
const FLIGHT_HELMET: &str = "../../shared/assets/FlightHelmet/FlightHelmet.gltf";

/// A square of side `size` in the xy plane facing +z, uv (0, 0) at the top left, written as
/// `name.gltf` (+ `.bin` and the PNGs) into `dir` with one material of `material_json`, whose
/// textures refer to images 0.. (`images`, RGBA8 `w x h`).
fn write_quad(
    dir: &Path,
    name: &str,
    size: f32,
    images: &[(u32, u32, Vec<u8>)],
    material_json: &str,
    sampler_json: &str,
) -> PathBuf {
    let h = size * 0.5;
    let positions: [[f32; 3]; 4] = [[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]];
    let normals = [[0.0f32, 0.0, 1.0]; 4];
    let uvs: [[f32; 2]; 4] = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
    let indices: [u16; 6] = [0, 1, 2, 0, 2, 3];
    let mut bin: Vec<u8> = Vec::new();
    bin.extend(bytemuck::cast_slice(&positions));
    bin.extend(bytemuck::cast_slice(&normals));
    bin.extend(bytemuck::cast_slice(&uvs));
    bin.extend(bytemuck::cast_slice(&indices));
    std::fs::write(dir.join(format!("{name}.bin")), &bin).unwrap();
    let mut image_json = Vec::new();
    let mut texture_json = Vec::new();
    for (i, (w, hgt, data)) in images.iter().enumerate() {
        let file = format!("{name}-{i}.png");
        image::RgbaImage::from_raw(*w, *hgt, data.clone())
            .unwrap()
            .save(dir.join(&file))
            .unwrap();
        image_json.push(format!(r#"{{ "uri": "{file}" }}"#));
        texture_json.push(format!(r#"{{ "source": {i}, "sampler": 0 }}"#));
    }
    let json = format!(
        r#"{{
  "asset": {{ "version": "2.0" }},
  "scene": 0,
  "scenes": [{{ "nodes": [0] }}],
  "nodes": [{{ "mesh": 0 }}],
  "meshes": [{{ "primitives": [{{
    "attributes": {{ "POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2 }},
    "indices": 3, "material": 0 }}] }}],
  "materials": [{material_json}],
  "textures": [{textures}],
  "images": [{images}],
  "samplers": [{sampler_json}],
  "buffers": [{{ "uri": "{name}.bin", "byteLength": {len} }}],
  "bufferViews": [
    {{ "buffer": 0, "byteOffset": 0, "byteLength": 48 }},
    {{ "buffer": 0, "byteOffset": 48, "byteLength": 48 }},
    {{ "buffer": 0, "byteOffset": 96, "byteLength": 32 }},
    {{ "buffer": 0, "byteOffset": 128, "byteLength": 12 }}
  ],
  "accessors": [
    {{ "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
       "min": [{mh}, {mh}, 0], "max": [{h}, {h}, 0] }},
    {{ "bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3" }},
    {{ "bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2" }},
    {{ "bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR" }}
  ]
}}"#,
        textures = texture_json.join(", "),
        images = image_json.join(", "),
        len = bin.len(),
        mh = -h,
        h = h,
    );
    let path = dir.join(format!("{name}.gltf"));
    std::fs::write(&path, json).unwrap();
    path
}

const TRILINEAR: &str = r#"{ "magFilter": 9729, "minFilter": 9987 }"#;

/// A scenario looking straight at the quad at `path` from `distance`, lit by `lights` (TOML).
fn quad_scenario(
    dir: &Path,
    path: &Path,
    size: u32,
    distance: f32,
    ambient: f32,
    lights: &str,
) -> tessera::scenario::Scenario {
    let src = format!(
        r#"
resolution = [{size}, {size}]
[frames]
warmup = 0
measured = 1
[scene]
background = [0.0, 1.0, 0.0]
ambient = {ambient}
{lights}
[[scene.objects]]
shape = "mesh"
path = "{path}"
materials = "file"
[camera]
[[camera.keyframes]]
time = 0
position = [0, 0, {distance}]
target = [0, 0, 0]
fov = 60
[[techniques]]
technique = "native"
"#,
        path = path.display(),
    );
    tessera::scenario::parse(&dir.join("quad.toml"), &src).unwrap_or_else(|e| panic!("{e}"))
}

fn render(s: &tessera::scenario::Scenario, technique: &str) -> HdrImage {
    let gpu = common::gpu();
    let mut scene = SceneGpu::new(&gpu.device, &gpu.queue, s).unwrap();
    let v = common::variant(technique, &[]);
    let target = Target::new(s.width, s.height, s.scene.has_dynamic_objects());
    let mut t = techniques::build(&v, &BuildContext::new(&gpu, &scene, target)).unwrap();
    let r = frames::render(&gpu, &mut scene, s, t.as_mut(), true, true, &mut || {}).unwrap();
    r.hdr_frames.into_iter().last().unwrap()
}

/// The last frame of the scenario's converged ground-truth reference with `samples` samples.
fn render_converged(s: &tessera::scenario::Scenario, samples: u32) -> HdrImage {
    let gpu = common::gpu();
    let mut scene = SceneGpu::new(&gpu.device, &gpu.queue, s).unwrap();
    let target = Target::new(s.width, s.height, false);
    let cx = BuildContext::new(&gpu, &scene, target);
    let mut t = techniques::converged_reference(samples, &cx).unwrap();
    let r = frames::render(&gpu, &mut scene, s, t.as_mut(), true, true, &mut || {}).unwrap();
    r.hdr_frames.into_iter().last().unwrap()
}

/// Linear RGB of pixel (x, y), y down.
fn pixel(img: &HdrImage, x: u32, y: u32) -> [f32; 3] {
    let d = &img.data;
    let c = d.len() / (img.width * img.height) as usize;
    let i = (y * img.width + x) as usize * c;
    [d[i], d[i + 1], d[i + 2]]
}

fn solid(w: u32, h: u32, rgba: [u8; 4]) -> (u32, u32, Vec<u8>) {
    (w, h, rgba.repeat((w * h) as usize))
}

fn image_of(w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 4]) -> (u32, u32, Vec<u8>) {
    let mut d = Vec::new();
    for y in 0..h {
        for x in 0..w {
            d.extend(f(x, y));
        }
    }
    (w, h, d)
}

const MATTE: &str = r#""metallicFactor": 0.0, "roughnessFactor": 1.0"#;

#[test]
fn base_colour_textures_are_sampled_not_a_constant() {
    let dir = tempfile::tempdir().unwrap();
    // Left half red, right half blue (sRGB 255 = linear 1).
    let img = image_of(16, 16, |x, _| {
        if x < 8 {
            [255, 0, 0, 255]
        } else {
            [0, 0, 255, 255]
        }
    });
    let material = format!(
        r#"{{ "pbrMetallicRoughness": {{ "baseColorTexture": {{ "index": 0 }}, {MATTE} }} }}"#
    );
    let path = write_quad(dir.path(), "halves", 4.0, &[img], &material, TRILINEAR);
    let s = quad_scenario(dir.path(), &path, 32, 2.0, 1.0, "");
    let out = render(&s, "native");
    let (l, r) = (pixel(&out, 6, 16), pixel(&out, 26, 16));
    assert!(l[0] > 0.9 && l[2] < 0.05, "left {l:?}");
    assert!(r[2] > 0.9 && r[0] < 0.05, "right {r:?}");
}

#[test]
fn the_converged_reference_draws_the_textured_models() {
    // The reference every content scenario is judged against: without the textured models it
    // shows only the background, and every variant (native too) scores 6 dB on the city.
    let dir = tempfile::tempdir().unwrap();
    let img = image_of(16, 16, |x, _| {
        if x < 8 {
            [255, 0, 0, 255]
        } else {
            [0, 0, 255, 255]
        }
    });
    let material = format!(
        r#"{{ "pbrMetallicRoughness": {{ "baseColorTexture": {{ "index": 0 }}, {MATTE} }} }}"#
    );
    let path = write_quad(dir.path(), "halves", 4.0, &[img], &material, TRILINEAR);
    let s = quad_scenario(dir.path(), &path, 32, 2.0, 1.0, "");
    let reference = render_converged(&s, 8);
    let native = render(&s, "native");
    let (l, r) = (pixel(&reference, 6, 16), pixel(&reference, 26, 16));
    assert!(l[0] > 0.9 && l[2] < 0.05, "left {l:?}");
    assert!(r[2] > 0.9 && r[0] < 0.05, "right {r:?}");
    // Away from the texture's one edge and the quad's border, the average of 8 jittered
    // renders equals native's single sample.
    for (x, y) in [(4, 10), (28, 22)] {
        let (a, b) = (pixel(&reference, x, y), pixel(&native, x, y));
        for c in 0..3 {
            assert!(
                (a[c] - b[c]).abs() < 0.02,
                "({x}, {y}): {a:?} vs native {b:?}"
            );
        }
    }
}

#[test]
fn a_minified_high_frequency_texture_matches_a_flat_texture_of_its_linear_mean() {
    let dir = tempfile::tempdir().unwrap();
    // A one-texel checker of sRGB 0 and 255: linear 0 and 1, mean 0.5 (sRGB 188). Averaged in
    // gamma space instead, the mean would be sRGB 128 (linear 0.22); without mips, point or
    // bilinear samples alias between 0 and 1.
    let checker = image_of(256, 256, |x, y| {
        if (x + y) % 2 == 0 {
            [255, 255, 255, 255]
        } else {
            [0, 0, 0, 255]
        }
    });
    let flat = solid(256, 256, [188, 188, 188, 255]);
    let material = format!(
        r#"{{ "pbrMetallicRoughness": {{ "baseColorTexture": {{ "index": 0 }}, {MATTE} }} }}"#
    );
    // The quad (side 4) fills the 32-pixel view from distance 1.73 with 4 texels a pixel: level 2.
    let a = write_quad(dir.path(), "checker", 4.0, &[checker], &material, TRILINEAR);
    let b = write_quad(dir.path(), "flat", 4.0, &[flat], &material, TRILINEAR);
    let render_of = |p: &Path| render(&quad_scenario(dir.path(), p, 32, 1.73, 1.0, ""), "native");
    let (ca, cb) = (render_of(&a), render_of(&b));
    let mut worst: f32 = 0.0;
    for y in 4..28 {
        for x in 4..28 {
            let (p, q) = (pixel(&ca, x, y), pixel(&cb, x, y));
            worst = worst.max((p[0] - q[0]).abs());
        }
    }
    // sRGB 188 is linear 0.5029; the mip chain's own rounding to 8 bits adds < 0.01.
    assert!(
        worst < 0.02,
        "minified checker differs from its mean by {worst}"
    );
    let centre = pixel(&cb, 16, 16)[0];
    assert!(
        (centre - 0.503).abs() < 0.01,
        "flat texture rendered {centre}"
    );
}

#[test]
fn an_alpha_tested_card_shows_the_background_through_its_cut_out() {
    let dir = tempfile::tempdir().unwrap();
    // Left half transparent (alpha 0), right half opaque white.
    let img = image_of(16, 16, |x, _| {
        if x < 8 {
            [255, 255, 255, 0]
        } else {
            [255, 255, 255, 255]
        }
    });
    let mat = |mode: &str| {
        format!(
            r#"{{ "alphaMode": "{mode}", "alphaCutoff": 0.5, "doubleSided": true,
                "pbrMetallicRoughness": {{ "baseColorTexture": {{ "index": 0 }}, {MATTE} }} }}"#
        )
    };
    let masked = write_quad(
        dir.path(),
        "mask",
        4.0,
        std::slice::from_ref(&img),
        &mat("MASK"),
        TRILINEAR,
    );
    let opaque = write_quad(dir.path(), "opaque", 4.0, &[img], &mat("OPAQUE"), TRILINEAR);
    let m = render(
        &quad_scenario(dir.path(), &masked, 32, 2.0, 1.0, ""),
        "native",
    );
    let o = render(
        &quad_scenario(dir.path(), &opaque, 32, 2.0, 1.0, ""),
        "native",
    );
    // The background is pure green.
    assert_eq!(
        pixel(&m, 6, 16),
        [0.0, 1.0, 0.0],
        "cut-out must show the background"
    );
    assert!(pixel(&m, 26, 16)[0] > 0.9, "opaque half drawn");
    // The same card drawn OPAQUE covers the background (the control).
    assert!(pixel(&o, 6, 16)[0] > 0.9, "{:?}", pixel(&o, 6, 16));
    // Checkerboard's quarter-resolution scene passes cut it out too.
    let c = render(
        &quad_scenario(dir.path(), &masked, 32, 2.0, 1.0, ""),
        "checkerboard",
    );
    assert_eq!(pixel(&c, 6, 16), [0.0, 1.0, 0.0]);
}

#[test]
fn a_normal_map_tilts_the_shading_normal_along_the_tangent() {
    let dir = tempfile::tempdir().unwrap();
    // Tangent-space normals tilted 30 degrees towards +u (left half) and -u (right half).
    let (s30, c30) = (0.5f32, 0.866f32);
    let enc = |v: f32| ((v * 0.5 + 0.5) * 255.0).round() as u8;
    let normals = image_of(16, 16, |x, _| {
        let nx = if x < 8 { s30 } else { -s30 };
        [enc(nx), 128, enc(c30), 255]
    });
    let flat = solid(16, 16, [128, 128, 255, 255]);
    let white = solid(4, 4, [255, 255, 255, 255]);
    let material = format!(
        r#"{{ "normalTexture": {{ "index": 1 }},
            "pbrMetallicRoughness": {{ "baseColorTexture": {{ "index": 0 }}, {MATTE} }} }}"#
    );
    // Light from the +x side at 45 degrees: towards the light is (1, 0, 1) / sqrt 2.
    let light = r#"[[scene.lights]]
type = "directional"
direction = [-1.0, 0.0, -1.0]
intensity = 1.0"#;
    let tilted = write_quad(
        dir.path(),
        "tilted",
        4.0,
        &[white.clone(), normals],
        &material,
        TRILINEAR,
    );
    let plain = write_quad(
        dir.path(),
        "plain",
        4.0,
        &[white, flat],
        &material,
        TRILINEAR,
    );
    let t = render(
        &quad_scenario(dir.path(), &tilted, 32, 2.0, 0.0, light),
        "native",
    );
    let p = render(
        &quad_scenario(dir.path(), &plain, 32, 2.0, 0.0, light),
        "native",
    );
    let lum = |img: &HdrImage, x| pixel(img, x, 16)[1];
    // Lambert: n.l = cos(45 - 30) = 0.966 (towards), cos(75) = 0.259 (away), flat 0.707; the
    // GGX lobe at roughness 1 adds about 1 %.
    let (towards, away, flat_l, flat_r) = (lum(&t, 6), lum(&t, 26), lum(&p, 6), lum(&p, 26));
    assert!(
        (flat_l - flat_r).abs() < 1e-3,
        "flat map: {flat_l} vs {flat_r}"
    );
    assert!(
        (towards / flat_l - 0.966 / 0.707).abs() < 0.08,
        "towards {towards} flat {flat_l}"
    );
    assert!(
        (away / flat_l - 0.259 / 0.707).abs() < 0.08,
        "away {away} flat {flat_l}"
    );
}

#[test]
fn broken_gltf_files_are_errors_naming_the_file_and_the_fault() {
    let cases = [
        ("IndexOutOfRange/IndexOutOfRange.gltf", "out of range"),
        (
            "MissingBin/BoxTextured.gltf",
            "BoxTextured0.bin, which does not exist",
        ),
    ];
    for (file, expected) in cases {
        let path = Path::new(ASSIMP).join(file);
        if !path.exists() {
            eprintln!("skipped: {} absent (run ci/setup.sh)", path.display());
            continue;
        }
        let e = gltf_model::load(&path, 1.0).expect_err(file).to_string();
        assert!(e.contains(&path.display().to_string()), "{e}");
        assert!(e.contains(expected), "{file}: {e}");
    }
    // A required extension Tessera does not implement.
    let dir = tempfile::tempdir().unwrap();
    let p = write_quad(
        dir.path(),
        "draco",
        1.0,
        &[solid(1, 1, [255; 4])],
        "{}",
        TRILINEAR,
    );
    let text = std::fs::read_to_string(&p).unwrap().replacen(
        r#""asset""#,
        r#""extensionsUsed": ["KHR_draco_mesh_compression"], "extensionsRequired": ["KHR_draco_mesh_compression"], "asset""#,
        1,
    );
    std::fs::write(&p, text).unwrap();
    let e = gltf_model::load(&p, 1.0).unwrap_err().to_string();
    // The gltf crate's validation or Tessera's own check, whichever sees it first.
    assert!(
        e.contains(&p.display().to_string())
            && e.contains("KHR_draco_mesh_compression")
            && e.to_lowercase().contains("extension"),
        "{e}"
    );
}

#[test]
fn the_assimp_textured_models_load_with_their_materials() {
    let cases = [
        ("BoxTextured-glTF/BoxTextured.gltf", 12),
        ("ClearCoat-glTF/ClearCoatTest.gltf", 0),
        ("textureTransform/TextureTransformTest.gltf", 0),
    ];
    for (file, triangles) in cases {
        let path = Path::new(ASSIMP).join(file);
        if !path.exists() {
            eprintln!("skipped: {} absent (run ci/setup.sh)", path.display());
            continue;
        }
        let m = gltf_model::load(&path, 1.0).unwrap_or_else(|e| panic!("{e}"));
        if triangles > 0 {
            assert_eq!(m.triangles(), triangles, "{file}");
        }
        assert!(!m.images.is_empty(), "{file}: no textures");
        assert!(
            m.materials.iter().any(|x| x.textures[0].is_some()),
            "{file}: no base colour texture"
        );
    }
    // textureTransform: some materials carry a non-identity transform.
    let path = Path::new(ASSIMP).join("textureTransform/TextureTransformTest.gltf");
    if path.exists() {
        let m = gltf_model::load(&path, 1.0).unwrap();
        let transformed = m
            .materials
            .iter()
            .filter_map(|x| x.textures[0])
            .filter(|t| t.transform != tessera::world::material::UvTransform::IDENTITY)
            .count();
        assert!(transformed > 0, "no KHR_texture_transform read");
    }
}

fn flight_helmet() -> Option<PathBuf> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join(FLIGHT_HELMET);
    if p.exists() {
        Some(p)
    } else {
        eprintln!("skipped: {} absent (the shared CC0 assets)", p.display());
        None
    }
}

#[test]
fn flight_helmet_loads_with_its_six_meshes_and_renders() {
    let Some(path) = flight_helmet() else {
        return;
    };
    let m = gltf_model::load(&path, 1.0).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(m.triangles(), 94_722);
    assert_eq!(m.materials.len(), 6);
    let blend = m
        .materials
        .iter()
        .filter(|x| x.alpha == tessera::world::material::AlphaMode::Blend)
        .count();
    assert_eq!(blend, 1);
    assert_eq!(m.images.len(), 15);
    let dir = tempfile::tempdir().unwrap();
    let light = r#"[[scene.lights]]
type = "directional"
direction = [-0.3, -0.6, -1.0]
intensity = 2.0"#;
    let src_dir = dir.path();
    let mut s = quad_scenario(src_dir, &path, 24, 1.2, 0.2, light);
    s.camera.keyframes[0].target = glam::DVec3::new(0.0, 0.3, 0.0);
    s.camera.keyframes[0].position = glam::DVec3::new(0.0, 0.35, 1.0);
    let out = render(&s, "native");
    let covered = (0..24)
        .flat_map(|y| (0..24).map(move |x| (x, y)))
        .filter(|&(x, y)| pixel(&out, x, y) != [0.0, 1.0, 0.0])
        .count();
    assert!(covered > 50, "only {covered} of 576 pixels show the helmet");
}

#[test]
fn techniques_without_the_forward_pipelines_skip_textured_scenes_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let material = format!(r#"{{ "pbrMetallicRoughness": {{ {MATTE} }} }}"#);
    let path = write_quad(
        dir.path(),
        "plain",
        1.0,
        &[solid(1, 1, [255; 4])],
        &material,
        TRILINEAR,
    );
    let s = quad_scenario(dir.path(), &path, 16, 2.0, 1.0, "");
    let gpu = common::gpu();
    let scene = SceneGpu::new(&gpu.device, &gpu.queue, &s).unwrap();
    assert!(scene.has_materials());
    let target = Target::new(s.width, s.height, false);
    for name in ["adaptive-shading", "native-deferred"] {
        let v = common::variant(name, &[]);
        match techniques::build(&v, &BuildContext::new(&gpu, &scene, target)) {
            Err(u) => assert!(
                u.0.contains("cannot draw textured materials"),
                "{name}: {}",
                u.0
            ),
            Ok(_) => panic!("{name} built on a textured scene"),
        }
    }
    // The hardware path draws them: on an adapter without VRS (lavapipe) it is skipped for the
    // extension alone, never for the textures.
    for v in [
        common::variant(
            "adaptive-shading",
            &[("vrs", tessera::params::ParamValue::Str("hardware".into()))],
        ),
        common::variant("native-vrs", &[]),
    ] {
        match techniques::build(&v, &BuildContext::new(&gpu, &scene, target)) {
            Ok(_) => assert!(gpu.vrs.is_ok(), "{} built without VRS", v.name),
            Err(u) => {
                assert!(!u.0.contains("textured"), "{}: {}", v.name, u.0);
                assert!(
                    u.0.starts_with(tessera::gpu::vrs::NEEDS),
                    "{}: {}",
                    v.name,
                    u.0
                );
            }
        }
        assert_eq!(
            techniques::scene_skip_reason(&v, &s.scene),
            None,
            "{}",
            v.name
        );
    }
    let software = common::variant("native-deferred", &[]);
    let reason = techniques::scene_skip_reason(&software, &s.scene).unwrap();
    assert!(
        reason.contains("cannot draw textured materials"),
        "{reason}"
    );
    for name in [
        "native",
        "checkerboard",
        "checkerboard-2x2",
        "interlace",
        "upscale",
    ] {
        let v = common::variant(name, &[]);
        assert!(
            techniques::build(&v, &BuildContext::new(&gpu, &scene, target)).is_ok(),
            "{name} draws textured materials"
        );
    }
}

/// A glTF file with materials is drawn with them unless the scenario asks for `"color"`
/// (issue 33): a textured model loaded as a new user would is not drawn flat grey.
#[test]
fn a_mesh_with_materials_is_drawn_with_them_by_default() {
    let src = |materials: &str| {
        format!(
            "resolution = [8, 8]\n[camera]\n[[camera.keyframes]]\ntime = 0\nposition = [0, 1, 4]\ntarget = [0, 0, 0]\n[[techniques]]\ntechnique = \"native\"\n[[scene.objects]]\nshape = \"mesh\"\npath = \"{FLIGHT_HELMET}\"\n{materials}\n"
        )
    };
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("s.toml");
    let textured = |m: &str| {
        tessera::scenario::parse(&file, &src(m))
            .unwrap_or_else(|e| panic!("{e:?}"))
            .scene
            .has_textured_models()
    };
    assert!(textured(""));
    assert!(textured("materials = \"file\""));
    assert!(!textured("materials = \"color\""));
}
