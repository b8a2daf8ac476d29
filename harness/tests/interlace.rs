//! Interlace on the default adapter: the GPU reconstruction equals the CPU model on the same
//! half-width frame, history and velocity, every frame, on a moving camera with an animated
//! object and a cut; and a static point-sampled scene rebuilds native within one level.

mod common;

use glam::Vec4;
use tessera::params::ParamValue;
use tessera::render::readback::read_texture;
use tessera::render::renderer::Renderer;
use tessera::render::scene::SceneGpu;
use tessera::render::timers::Timers;
use tessera::scenario::Scenario;
use tessera::techniques::interlace::model::{self, half_width, Inputs, Source};
use tessera::techniques::interlace::{InterlaceGpu, Options};
use tessera::techniques::Variant;
use tessera::techniques::{self, BuildContext, Target};

fn variant(params: &[(&str, ParamValue)]) -> Variant {
    common::variant("interlace", params)
}

fn vec4s(v: Vec<f32>) -> Vec<Vec4> {
    v.chunks_exact(4).map(Vec4::from_slice).collect()
}

/// Renders `frames` frames, comparing the GPU output of each with the model's; returns every
/// frame's sources.
fn compare_with_model(s: &Scenario, v: &Variant, frames: u32) -> Vec<Vec<Source>> {
    let gpu = common::gpu();
    let mut scene = SceneGpu::new(&gpu.device, s).unwrap();
    let mut t = InterlaceGpu::new(
        &gpu,
        Options::from_variant(v),
        s.width,
        s.height,
        s.scene.has_dynamic_objects(),
    );
    let mut timers = Timers::new(&gpu.device, &[]).unwrap();
    let mut all = Vec::new();
    let read = |t: &InterlaceGpu, name: &str| {
        read_texture(&gpu.device, &gpu.queue, t.texture(name).unwrap())
    };
    for index in 0..frames {
        tessera::run::frames::submit_frame(&gpu, &mut scene, s, &mut t, &mut timers, index);
        let _ = gpu.device.poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: None,
        });
        let _ = timers.try_collect(&gpu.queue);
        let last = t.last_frame().unwrap();
        let half_color = vec4s(read(&t, "half_color"));
        let half_depth = read(&t, "half_depth");
        let history = vec4s(read(&t, "history"));
        let velocity = last.velocity.then(|| vec4s(read(&t, "velocity")));
        let inputs = Inputs {
            width: s.width,
            height: s.height,
            parity: last.parity,
            half_width: half_width(s.width),
            half_color: &half_color,
            half_depth: &half_depth,
            history: &history,
            velocity: velocity.as_deref(),
            prev_from_cur: last.prev_from_cur,
            history_valid: last.history_valid,
            clamp: last.clamp,
        };
        let model = model::reconstruct_all(&inputs);
        let gpu_out = vec4s(read_texture(&gpu.device, &gpu.queue, t.output()));
        for (i, ((m, src), g)) in model.iter().zip(&gpu_out).enumerate() {
            // The output is Rgba16Float: quantise the model the same way; the bilinear history
            // fetch may round differently in the last f16 bit.
            let m16 = Vec4::from_array(m.to_array().map(|x| half::f16::from_f32(x).to_f32()));
            let d = (m16 - *g).abs().max_element();
            assert!(
                d <= 2e-3 * m16.abs().max_element().max(1.0),
                "frame {index} pixel {i}: model {m16} ({src:?}) gpu {g}"
            );
        }
        all.push(model.iter().map(|(_, s)| *s).collect());
    }
    all
}

const SCENE: &str = r#"
resolution = [41, 30]
[frames]
warmup = 0
measured = 1
[scene]
shading_cost = 2
[scene.ground]
checker_size = 0.5
[[scene.lights]]
type = "directional"
intensity = 2.0
[[scene.objects]]
shape = "box"
position = [0, 0.5, 0]
color = [0.8, 0.3, 0.2]
[[scene.objects]]
shape = "pole"
position = [-1.0, 0, 0.5]
radius = 0.03
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

#[test]
fn moving_camera_animated_object_and_cut_match_the_model() {
    let s = common::scenario(&format!(
        "{SCENE}{MOVING}\n[[techniques]]\ntechnique = \"native\"\n"
    ));
    assert!(s.scene.has_dynamic_objects());
    for clamp in [true, false] {
        let frames = compare_with_model(&s, &variant(&[("clamp", ParamValue::Bool(clamp))]), 6);
        // Frame 0 has no history: fills only; later frames reproject, some from off screen.
        assert!(frames[0].contains(&Source::Fill));
        assert!(!frames[0].contains(&Source::History));
        assert!(frames[2].contains(&Source::History));
        // The cut (at 0.06 s: frame 4 at 60 Hz) drops the history again.
        assert!(!frames[4].contains(&Source::History), "clamp {clamp}");
        // Every frame shades half the columns.
        let shaded = frames[3].iter().filter(|s| **s == Source::Shaded).count();
        assert_eq!(shaded, (s.width / 2 * s.height) as usize);
    }
}

#[test]
fn static_point_sampled_scene_rebuilds_native_within_one_level() {
    // Point-sampled ground: the half-width render's derivatives do not change its look.
    let s = common::scenario(&format!(
        "{}{STILL}\n[[techniques]]\ntechnique = \"native\"\n",
        SCENE.replace(
            "checker_size = 0.5",
            "checker_size = 0.5\nfilter = \"none\""
        )
    ));
    let gpu = common::gpu();
    let render = |v: &Variant| {
        let mut scene = SceneGpu::new(&gpu.device, &s).unwrap();
        let mut t = techniques::build(
            v,
            &BuildContext::new(&gpu, &scene, Target::new(s.width, s.height, false)),
        )
        .unwrap();
        let mut s2 = s.clone();
        s2.warmup_frames = 3;
        s2.measured_frames = 2;
        tessera::run::frames::render(&gpu, &mut scene, &s2, t.as_mut(), true, false, &mut || {})
            .unwrap()
    };
    let native = render(&common::variant("native", &[]));
    // Unclamped: the pole is thinner than a column, and a clamp to its neighbours would erase it.
    let interlace = render(&variant(&[("clamp", ParamValue::Bool(false))]));
    for (f, (n, c)) in native.frames.iter().zip(&interlace.frames).enumerate() {
        let max = n
            .data
            .iter()
            .zip(&c.data)
            .map(|(a, b)| a.abs_diff(*b))
            .max()
            .unwrap();
        assert!(max <= 1, "frame {f}: max error {max}/255");
    }
}
