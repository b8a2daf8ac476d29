//! FSR 1 on the default adapter: EASU and RCAS on the GPU equal their CPU models on real frames
//! (a moving camera, an animated object, a cut) at the four quality modes and a custom scale,
//! with and without RCAS; and a flat image stays flat through both.

mod common;

use common::check::{self, close, f16x4, vec4s, Rig};
use glam::{Vec3, Vec4};
use tessera::params::ParamValue;
use tessera::render::readback::read_texture;
use tessera::render::timers::Timers;
use tessera::scenario::Scenario;
use tessera::techniques::fsr1::model::{self, Image};
use tessera::techniques::fsr1::{Fsr1Gpu, Options};
use tessera::techniques::shared::rcas_model;
use tessera::techniques::Variant;

/// `v` as the `Rgba16Float` targets store it.
fn f16(v: Vec3) -> Vec3 {
    v.map(check::f16)
}

const SCENE: &str = r#"
resolution = [41, 30]
[frames]
warmup = 0
measured = 1
[scene]
shading_cost = 2
[scene.ground]
checker_size = 0.25
[[scene.lights]]
type = "directional"
intensity = 3.0
[[scene.objects]]
shape = "box"
position = [0, 0.5, 0]
color = [0.8, 0.3, 0.2]
animation = { kind = "rotate", degrees_per_second = 90 }
[[scene.objects]]
shape = "pole"
position = [-1.0, 0, 0.5]
radius = 0.03
[[scene.objects]]
shape = "fence"
position = [-2, 0, -1]
end = [2, 0, -1]
[[scene.objects]]
shape = "sphere"
position = [1.2, 0.5, -0.5]
radius = 0.5
emissive = [6.0, 5.0, 2.0]
[camera]
[[camera.keyframes]]
time = 0
position = [0, 1.5, 4]
target = [0, 0.4, 0]
[[camera.keyframes]]
time = 0.05
position = [0.4, 1.5, 4]
target = [0, 0.4, 0]
[[camera.keyframes]]
time = 0.06
position = [-1, 2, 3]
target = [0, 0.4, 0]
cut = true
[[techniques]]
technique = "native"
"#;

/// Renders `frames` frames of `v`, comparing EASU and RCAS with the model every frame.
fn compare_with_model(s: &Scenario, v: &Variant, frames: u32) {
    let options = Options::from_variant(v);
    let mut rig = Rig::new(
        s,
        |gpu| Fsr1Gpu::new(gpu, options, s.width, s.height),
        Fsr1Gpu::texture,
    );
    let (lw, lh) = options.render_size(s.width, s.height);
    let (mut edges, mut sharpened) = (0, 0);
    for index in 0..frames {
        rig.frame(s, index);
        let low = rig.read4("color_low");
        let src = Image {
            width: lw,
            height: lh,
            texels: &low,
        };
        let out = rig.read4("color");
        let easu_gpu = options.rcas_sharpness().map(|_| rig.read4("easu"));
        for y in 0..s.height {
            for x in 0..s.width {
                let i = (y * s.width + x) as usize;
                let e = model::easu(&src, (s.width, s.height), x, y);
                if e.len > 1.0 {
                    edges += 1;
                }
                // EASU's perceptual output (with RCAS) or its decoded output (without), both
                // stored as f16.
                let (want, got) = match &easu_gpu {
                    Some(g) => (f16(e.color), g[i].truncate()),
                    None => (f16(model::decode(e.color)), out[i].truncate()),
                };
                assert!(
                    close(want.extend(0.0), got.extend(0.0), 2e-3),
                    "{} frame {index} easu ({x}, {y}): model {want} gpu {got} ({e:?})",
                    v.name
                );
            }
        }
        if let (Some(g), Some(stops)) = (&easu_gpu, options.rcas_sharpness()) {
            let img = Image {
                width: s.width,
                height: s.height,
                texels: g,
            };
            for y in 0..s.height {
                for x in 0..s.width {
                    let i = (y * s.width + x) as usize;
                    let (lobe, c) = rcas_model::rcas(&img, (-stops).exp2(), false, x, y);
                    if lobe < -1e-3 {
                        sharpened += 1;
                    }
                    let want = f16(c);
                    let got = out[i].truncate();
                    assert!(
                        close(want.extend(0.0), got.extend(0.0), 2e-3),
                        "{} frame {index} rcas ({x}, {y}): model {want} gpu {got} (lobe {lobe})",
                        v.name
                    );
                }
            }
        }
    }
    // The frames exercised the decisions: edges found, pixels sharpened.
    assert!(edges > 0, "{}: no edges", v.name);
    if options.rcas {
        assert!(sharpened > 0, "{}: nothing sharpened", v.name);
    }
}

#[test]
fn easu_and_rcas_match_the_model_on_real_frames() {
    let s = common::scenario(SCENE);
    let mode = |m: &str| ("mode", ParamValue::Str(m.to_string()));
    for params in [
        vec![mode("ultra-quality")],
        vec![mode("quality")],
        vec![mode("balanced")],
        vec![mode("performance")],
        vec![("scale", ParamValue::Float(std::f64::consts::FRAC_1_SQRT_2))],
        vec![
            ("rcas", ParamValue::Bool(false)),
            ("scale", ParamValue::Float(0.6)),
        ],
        vec![("sharpness", ParamValue::Float(0.0))],
        vec![("input", ParamValue::Str("aliased".into()))],
    ] {
        let v = common::variant("fsr1", &params);
        compare_with_model(&s, &v, 5);
    }
}

#[test]
fn a_mode_and_a_scale_together_are_refused() {
    let v = common::variant(
        "fsr1",
        &[
            ("mode", ParamValue::Str("quality".into())),
            ("scale", ParamValue::Float(0.6)),
        ],
    );
    let err = v.technique.check(&v).unwrap_err();
    assert!(err.contains("mode = \"quality\""), "{err}");
    let ok = common::variant("fsr1", &[("mode", ParamValue::Str("quality".into()))]);
    assert!(ok.technique.check(&ok).is_ok());
    let o = Options::from_variant(&ok);
    assert!((o.render_scale() - 1.0 / 1.5).abs() < 1e-12);
    // AMD's -0.58 mip bias on the ground's filter width.
    assert!((o.gradient_scale() - (-0.58f32).exp2()).abs() < 1e-6);
}

#[test]
fn rcas_on_the_gpu_keeps_an_isolated_peak_within_one_and_equals_the_model() {
    // FSR 1.0.2's case on the GPU: 0.8 encoded at isolated pixels over a ring of 0.5 (and the
    // mirror case, 0.05), sharpness 0.2 stops. v1.0's limiter decoded the peak to about 61,000.
    use wgpu::util::DeviceExt;
    let gpu = common::gpu();
    let (w, h) = (6u32, 5u32);
    let mut texels = vec![Vec4::new(0.5, 0.5, 0.5, 1.0); (w * h) as usize];
    texels[(2 * w + 2) as usize] = Vec4::new(0.8, 0.8, 0.8, 1.0);
    texels[(2 * w + 4) as usize] = Vec4::new(0.8, 0.5, 0.05, 1.0);
    texels[(4 * w) as usize] = Vec4::new(0.05, 0.05, 0.05, 1.0);
    let halves: Vec<half::f16> = texels
        .iter()
        .flat_map(|t| t.to_array().map(half::f16::from_f32))
        .collect();
    let size = wgpu::Extent3d {
        width: w,
        height: h,
        depth_or_array_layers: 1,
    };
    let desc = |label, usage| wgpu::TextureDescriptor {
        label: Some(label),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: tessera::render::scene::COLOR_FORMAT,
        usage,
        view_formats: &[],
    };
    let src = gpu.device.create_texture_with_data(
        &gpu.queue,
        &desc("peaks", wgpu::TextureUsages::TEXTURE_BINDING),
        wgpu::util::TextureDataOrder::LayerMajor,
        bytemuck::cast_slice(&halves),
    );
    let dst = gpu.device.create_texture(&desc(
        "rcas out",
        wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC,
    ));
    let stops = 0.2f32;
    let pass = tessera::techniques::shared::rcas::rcas_pass(
        &gpu,
        (
            &src.create_view(&Default::default()),
            &dst.create_view(&Default::default()),
        ),
        (w, h),
        stops,
        false,
    );
    let timers = Timers::new(&gpu.device, &[]).unwrap();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    pass.record(&timers, &mut encoder);
    gpu.queue.submit([encoder.finish()]);
    let out = vec4s(read_texture(&gpu.device, &gpu.queue, &dst));
    let stored: Vec<Vec4> = texels.iter().map(|t| f16x4(*t)).collect();
    let img = Image {
        width: w,
        height: h,
        texels: &stored,
    };
    for y in 0..h {
        for x in 0..w {
            let raw = rcas_model::rcas_unclamped(&img, (-stops).exp2(), x, y);
            assert!(
                raw.min_element() >= 0.0 && raw.max_element() <= 1.0,
                "({x}, {y}): the limiter let {raw} out of [0, 1]"
            );
            let (_, c) = rcas_model::rcas(&img, (-stops).exp2(), false, x, y);
            let (want, got) = (f16(c), out[(y * w + x) as usize].truncate());
            assert!(
                got.is_finite() && got.max_element() < 30.0,
                "({x}, {y}): {got}"
            );
            let d = (want - got).abs().max_element();
            assert!(
                d <= 2e-3 * want.abs().max_element().max(1.0),
                "({x}, {y}): model {want} gpu {got}"
            );
        }
    }
    // The peak was sharpened (above its own decoded value), not flattened.
    let peak = out[(2 * w + 2) as usize].x;
    assert!(
        peak > model::decode(Vec3::splat(stored[(2 * w + 2) as usize].x)).x,
        "{peak}"
    );
}
