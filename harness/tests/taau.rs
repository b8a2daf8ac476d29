//! TAAU on the default adapter: the jitter puts each render pixel's sample where the sequence
//! says (against a 4x supersampled render); a still camera's accumulated output is exactly the
//! mean of the renders at the claimed sample positions; the GPU resolve (and its RCAS) equals
//! the CPU model on real frames with a moving camera, an animated object and a cut, where the
//! history resets.

mod common;

use common::check::{close, f16x4, vec4s, Rig};
use glam::{Vec2, Vec4};
use tessera::params::ParamValue;
use tessera::render::kit::record_scene_pass;
use tessera::render::readback::{read_texture, read_texture_raw};
use tessera::render::scene::{SceneGpu, ScenePipeline, View, COLOR_FORMAT, DEPTH_FORMAT};
use tessera::render::timers::Timers;
use tessera::scenario::Scenario;
use tessera::techniques::shared::jitter::{jitter, ndc_offset};
use tessera::techniques::shared::rcas_model as fsr1_model;
use tessera::techniques::taau::model::{self, Inputs, Source};
use tessera::techniques::taau::{Options, TaauGpu};
use tessera::techniques::Variant;

const SCENE: &str = r#"
resolution = [40, 30]
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
[[scene.objects]]
shape = "pole"
position = [-1.0, 0, 0.5]
radius = 0.02
[[scene.objects]]
shape = "fence"
position = [-2, 0, -1]
end = [2, 0, -1]
[[scene.objects]]
shape = "sphere"
position = [1.2, 0.5, -0.5]
radius = 0.5
"#;

const MOVING: &str = r#"
[scene.objects.animation]
kind = "translate"
velocity = [-3, 0, 0]
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
"#;

const STILL: &str = r#"
[camera]
[[camera.keyframes]]
time = 0
position = [0, 1.5, 4]
target = [0, 0.4, 0]
"#;

fn scenario(parts: &[&str]) -> Scenario {
    common::scenario(&format!(
        "{}\n[[techniques]]\ntechnique = \"native\"\n",
        parts.concat()
    ))
}

/// One render of the scene at `width` x `height` with `view`, read back.
fn render_view(
    gpu: &tessera::gpu::Gpu,
    scene: &mut SceneGpu,
    (width, height): (u32, u32),
    view: View,
) -> Vec<Vec4> {
    let tex = |format, usage| {
        gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("test"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | usage,
            view_formats: &[],
        })
    };
    let color = tex(COLOR_FORMAT, wgpu::TextureUsages::COPY_SRC);
    let depth = tex(DEPTH_FORMAT, wgpu::TextureUsages::empty());
    let timers = Timers::new(&gpu.device, &[]).unwrap();
    scene.write_objects(&gpu.queue, view.time, view.prev_time);
    scene.write_view(&gpu.queue, 0, &view);
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    record_scene_pass(
        gpu,
        scene,
        &timers,
        &mut encoder,
        "scene",
        &color.create_view(&Default::default()),
        &depth.create_view(&Default::default()),
        0,
        ScenePipeline::Forward { samples: 1 },
    );
    gpu.queue.submit([encoder.finish()]);
    vec4s(read_texture(&gpu.device, &gpu.queue, &color))
}

#[test]
fn render_pixels_sample_at_the_claimed_jitter_positions() {
    // Point-sampled ground: a sample's colour depends on its position only.
    let s = scenario(&[
        &SCENE.replace(
            "checker_size = 0.25",
            "checker_size = 0.25\nfilter = \"none\"",
        ),
        STILL,
    ]);
    let gpu = common::gpu();
    let mut scene = SceneGpu::new(&gpu.device, &gpu.queue, &s).unwrap();
    let (w, h) = (s.width, s.height);
    // 4x per axis, unjittered: hi-res pixel k's centre is at (k + 0.5) / 4 render pixels.
    let hi = render_view(&gpu, &mut scene, (4 * w, 4 * h), View::whole(0.0, 0.0));
    // (0.375, 0.125): render pixel q samples at q + (0.875, 0.625) = ((4q + 3) + 0.5, (4q + 2)
    // + 0.5) / 4, the centre of hi-res pixel (4q + 3, 4q + 2).
    let mut matches = |j: Vec2| {
        let lo = render_view(
            &gpu,
            &mut scene,
            (w, h),
            View {
                ndc_offset: ndc_offset(j, w, h),
                ..View::whole(0.0, 0.0)
            },
        );
        let mut same = 0;
        for y in 0..h {
            for x in 0..w {
                let a = lo[(y * w + x) as usize];
                let b = hi[((4 * y + 2) * 4 * w + 4 * x + 3) as usize];
                if close(b, a, 2e-3) {
                    same += 1;
                }
            }
        }
        same as f64 / (w * h) as f64
    };
    let claimed = matches(Vec2::new(0.375, 0.125));
    // Rasterisers snap vertices to a sub-pixel grid per resolution: a sample within about
    // 1/256 px of an edge may fall on the other side.
    assert!(claimed >= 0.98, "{claimed}");
    // The mirrored jitter does not sample there.
    let mirrored = matches(Vec2::new(-0.375, -0.125));
    assert!(mirrored < claimed - 0.05, "{mirrored} vs {claimed}");
}

#[test]
fn a_still_camera_accumulates_the_mean_of_the_claimed_samples() {
    let s = scenario(&[SCENE, STILL]);
    // The still-scene accumulator's options, 32 phases and a history weight that reaches 32:
    // the mean of one whole jitter cycle.
    let v = common::variant(
        "taau",
        &[
            ("phases", ParamValue::Float(32.0)),
            ("max_weight", ParamValue::Float(32.0)),
            ("clip_moving_only", ParamValue::Bool(true)),
            ("freeze_converged", ParamValue::Bool(true)),
        ],
    );
    let options = Options::from_variant(&v);
    assert_eq!(options.phases(s.width), 32);
    let mut rig = Rig::new(
        &s,
        |gpu| TaauGpu::new(gpu, options, s.width, s.height, false),
        TaauGpu::texture,
    );
    for index in 0..32 {
        rig.frame(&s, index);
    }
    let out = rig.output();
    // The same 32 renders, one per claimed sample position, averaged on the CPU.
    let n = (s.width * s.height) as usize;
    let mut mean = vec![Vec4::ZERO; n];
    let mut max = vec![0.0f32; n];
    for index in 0..32 {
        let frame = render_view(
            &rig.gpu,
            &mut rig.scene,
            (s.width, s.height),
            View {
                ndc_offset: ndc_offset(jitter(index, 32), s.width, s.height),
                gradient_scale: options.gradient_scale(),
                ..View::whole(0.0, 0.0)
            },
        );
        for ((m, x), f) in mean.iter_mut().zip(&mut max).zip(&frame) {
            *m += *f / 32.0;
            *x = x.max(f.truncate().max_element());
        }
    }
    for (i, (o, m)) in out.iter().zip(&mean).enumerate() {
        // Every pixel kept its history through all 32 phases (no disocclusion reset at
        // silhouettes, where the samples alternate between surfaces).
        assert_eq!(o.w, 32.0, "pixel {i}: weight {}", o.w);
        // The running mean is stored in f16 after every frame: each conversion (at most one ulp
        // of the running value, which never exceeds the pixel's largest sample: stores may
        // round towards zero, as lavapipe's do, every error then of one sign) persists with
        // weight k/32 after frame k, at most 16.5 ulps in all.
        let ulp = (2.0f32).powi(max[i].max(2.0f32.powi(-14)).log2().floor() as i32 - 10);
        let bound = 16.5 * ulp + 1e-4;
        let d = (o.truncate() - m.truncate()).abs().max_element();
        assert!(d <= bound, "pixel {i}: taau {o} mean {m} (bound {bound})");
    }
    // Converged and still: held, frame after frame (`freeze_converged`), as still as native.
    for index in 32..36 {
        rig.frame(&s, index);
    }
    assert_eq!(rig.output(), out);
}

/// Renders `frames` frames of `v`, comparing every resolve (and RCAS) with the model; returns
/// each frame's sources.
fn compare_with_model(s: &Scenario, v: &Variant, frames: u32) -> Vec<Vec<Source>> {
    let options = Options::from_variant(v);
    let dynamic = s.scene.has_dynamic_objects();
    let mut rig = Rig::new(
        s,
        |gpu| TaauGpu::new(gpu, options, s.width, s.height, dynamic),
        TaauGpu::texture,
    );
    let read_r32 = |rig: &Rig<TaauGpu>, name: &str| {
        bytemuck::pod_collect_to_vec::<u8, f32>(&read_texture_raw(&rig.gpu, rig.texture(name)))
    };
    let mut all = Vec::new();
    for index in 0..frames {
        rig.frame(s, index);
        let last = rig.renderer.last_frame().unwrap();
        let color_low = rig.read4("color_low");
        let depth_low = rig.read("depth_low");
        let history = rig.read4("history");
        let depth_history = read_r32(&rig, "depth_history");
        let velocity = last.velocity.then(|| rig.read4("velocity"));
        let velocity_depth = last.velocity.then(|| rig.read("velocity_depth"));
        let inputs = Inputs {
            low: rig.renderer.render_size(),
            out: (s.width, s.height),
            jitter: last.jitter,
            color_low: &color_low,
            depth_low: &depth_low,
            history: &history,
            depth_history: &depth_history,
            velocity: velocity.as_deref(),
            velocity_depth: velocity_depth.as_deref(),
            prev_from_cur: last.prev_from_cur,
            history_valid: last.history_valid,
            camera_still: last.camera_still,
            clip_still: !options.clip_moving_only,
            clip_gamma: options.clip_gamma,
            depth_tolerance: options.depth_tolerance,
            max_weight: options.max_weight,
            moving_weight: options.moving_weight,
            fill_weight: tessera::techniques::taau::gpu::FILL_WEIGHT,
            freeze_converged: options.freeze_converged,
        };
        let model = model::resolve_all(&inputs);
        let resolved = rig.read4("resolved");
        let depth = read_r32(&rig, "depth");
        let mut bad = Vec::new();
        for (i, (m, g)) in model.iter().zip(&resolved).enumerate() {
            let want = f16x4(m.color);
            if !close(want, *g, 3e-3) {
                bad.push(format!(
                    "pixel ({}, {}): model {want} ({:?}, lands {}, history at {} depth {}) gpu {g}",
                    i as u32 % s.width,
                    i as u32 / s.width,
                    m.source,
                    m.lands,
                    m.prev_pos,
                    m.prev_depth
                ));
            }
            assert_eq!(m.depth, depth[i], "frame {index} pixel {i}");
        }
        assert!(
            bad.is_empty(),
            "{options:?} frame {index}: {} pixels differ: {}",
            bad.len(),
            bad[..bad.len().min(6)].join("; ")
        );
        if let Some(stops) = options.rcas_sharpness() {
            let img = fsr1_model::Image {
                width: s.width,
                height: s.height,
                texels: &resolved,
            };
            let out = rig.output();
            for y in 0..s.height {
                for x in 0..s.width {
                    let (_, c) = fsr1_model::rcas(&img, (-stops).exp2(), true, x, y);
                    let want = f16x4(c.extend(0.0));
                    let got = out[(y * s.width + x) as usize].truncate().extend(0.0);
                    assert!(
                        close(want, got, 3e-3),
                        "frame {index} rcas ({x}, {y}): model {want} gpu {got}"
                    );
                }
            }
        }
        all.push(model.iter().map(|r| r.source).collect());
    }
    all
}

#[test]
fn moving_camera_animated_object_and_cut_match_the_model() {
    let s = scenario(&[SCENE, MOVING]);
    assert!(s.scene.has_dynamic_objects());
    for params in [
        vec![],
        vec![("scale", ParamValue::Float(0.5))],
        vec![("scale", ParamValue::Float(std::f64::consts::FRAC_1_SQRT_2))],
        vec![
            ("scale", ParamValue::Float(std::f64::consts::FRAC_1_SQRT_2)),
            ("rcas", ParamValue::Bool(true)),
        ],
        vec![("clip_moving_only", ParamValue::Bool(true))],
        vec![("freeze_converged", ParamValue::Bool(true))],
    ] {
        let v = common::variant("taau", &params);
        let frames = compare_with_model(&s, &v, 6);
        // Frame 0 has no history.
        assert!(frames[0].iter().all(|s| *s == Source::Reset), "{}", v.name);
        // Moving content is clipped; something keeps history.
        assert!(frames[2].contains(&Source::Clipped), "{}", v.name);
        // The cut (0.06 s: frame 4 at 60 Hz) drops every pixel's history.
        assert!(frames[4].iter().all(|s| *s == Source::Reset), "{}", v.name);
        assert!(frames[5].contains(&Source::Clipped), "{}", v.name);
    }
}

#[test]
fn a_still_scene_keeps_history_unclipped_with_clip_moving_only() {
    let s = scenario(&[SCENE, STILL]);
    let v = common::variant(
        "taau",
        &[
            ("scale", ParamValue::Float(0.5)),
            ("clip_moving_only", ParamValue::Bool(true)),
        ],
    );
    let frames = compare_with_model(&s, &v, 4);
    assert!(frames[0].iter().all(|s| *s == Source::Reset));
    // Nothing moves: no clipping, and from frame 1 on every pixel has history (upsampled pixels
    // whose first sample has not landed carry the fill).
    for f in &frames[1..] {
        assert!(f.iter().all(|s| *s == Source::History), "{f:?}");
    }
}

#[test]
fn the_defaults_clip_every_frame_and_never_stop_accumulating() {
    // A shipped TAA's defaults (Bevy's taa.wgsl, FSR 2): a still scene's history is clipped every
    // frame, and a converged still pixel still takes in its new sample.
    let s = scenario(&[SCENE, STILL]);
    let v = common::variant("taau", &[]);
    let options = Options::from_variant(&v);
    assert!(!options.clip_moving_only && !options.freeze_converged);
    assert_eq!(options.phases(s.width), 8);
    let frames = compare_with_model(&s, &v, 4);
    assert!(frames[0].iter().all(|s| *s == Source::Reset));
    for f in &frames[1..] {
        assert!(f.iter().all(|s| *s == Source::Clipped), "{f:?}");
    }
    // Past `max_weight` frames the output still changes with each jitter phase.
    let mut rig = Rig::new(
        &s,
        |gpu| TaauGpu::new(gpu, options, s.width, s.height, false),
        TaauGpu::texture,
    );
    let mut last = Vec::new();
    let mut changed = 0;
    for index in 0..40 {
        rig.frame(&s, index);
        let out = rig.output();
        if index >= 34 && out != last {
            changed += 1;
        }
        last = out;
    }
    assert!(
        changed > 0,
        "a converged still image stopped taking samples"
    );
}
