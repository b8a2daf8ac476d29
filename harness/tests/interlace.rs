//! Interlace on the default adapter: the GPU reconstruction equals the CPU model on the same
//! reduced renders, history and velocity, every frame, on a moving camera with an animated object
//! and a cut; a still scene rebuilds native (exactly without derivative shading, at 35 dB and more
//! with it).

mod common;

use common::check::{close, f16x4, Rig};
use tessera::params::ParamValue;
use tessera::render::scene::SceneGpu;
use tessera::scenario::Scenario;
use tessera::techniques::interlace::model::{self, quarter_size, Inputs, Source};
use tessera::techniques::interlace::{InterlaceGpu, Options};
use tessera::techniques::Variant;
use tessera::techniques::{self, BuildContext, Target};

fn variant(params: &[(&str, ParamValue)]) -> Variant {
    common::variant("interlace", params)
}

/// Renders `frames` frames of the default pattern, comparing the GPU output (colour and depth)
/// of each with the model's; returns every frame's sources.
fn compare_with_model(s: &Scenario, v: &Variant, frames: u32) -> Vec<Vec<Source>> {
    let options = Options::from_variant(v);
    let dynamic = s.scene.has_dynamic_objects();
    let mut rig = Rig::new(
        s,
        |gpu| InterlaceGpu::new(gpu, options, s.width, s.height, dynamic),
        InterlaceGpu::texture,
    );
    let mut all = Vec::new();
    for index in 0..frames {
        rig.frame(s, index);
        let last = rig.renderer.last_frame().unwrap();
        // Every array layer (the quarter-resolution renders are two), layer 0 first.
        let rows_color = rig.read4("rows_color");
        let rows_depth = rig.read("rows_depth");
        let history = rig.read4("history");
        let history_depth = rig.read("history_depth");
        let velocity = last.velocity.then(|| rig.read4("velocity"));
        let velocity_depth = last.velocity.then(|| rig.read("velocity_depth"));
        let inputs = Inputs {
            width: s.width,
            height: s.height,
            parity: last.parity,
            quarter: quarter_size(s.width, s.height),
            rows_color: &rows_color,
            rows_depth: &rows_depth,
            history: &history,
            history_depth: &history_depth,
            velocity: velocity.as_deref(),
            velocity_depth: velocity_depth.as_deref(),
            prev_from_cur: last.prev_from_cur,
            history_valid: last.history_valid,
            still: last.still,
            clamp: options.clamp,
            near: last.near,
            far: last.far,
            depth_tolerance: options.depth_tolerance,
            coherency_scale: options.coherency,
            velocity_scale: options.velocity_scale,
        };
        let model = model::reconstruct_all(&inputs);
        let gpu_out = rig.output();
        let gpu_depth = rig.read("depth_out");
        for (i, ((m, md, src), g)) in model.iter().zip(&gpu_out).enumerate() {
            // The output is Rgba16Float: quantise the model the same way; the bilinear history
            // fetch and the weights may round differently in the last f16 bits.
            let m16 = f16x4(*m);
            assert!(
                close(m16, *g, 2e-3),
                "frame {index} pixel {i}: model {m16} ({src:?}) gpu {g}"
            );
            assert_eq!(*md, gpu_depth[i], "frame {index} pixel {i}: depth");
        }
        all.push(model.iter().map(|(_, _, s)| *s).collect());
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

// Slightly off the mirror plane: centred on x = 0, the box's silhouette vertices project exactly
// onto the centre column's pixel centres (41 px wide), where coverage is a tie that the last bit
// of the quarter-resolution projection remap decides either way (one pixel of 1230 then costs
// 14 dB: 36.3 dB). Off it, every pixel centre is clear of the edges by more than rounding.
const STILL_OFF_AXIS: &str = r#"
[camera]
[[camera.keyframes]]
time = 0
position = [0.0137, 1.5, 4]
target = [0.0137, 0.4, 0]
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
        // Every frame shades half the pixels (41 x 30: 615), a checkerboard.
        for f in &frames {
            let shaded = f.iter().filter(|s| **s == Source::Shaded).count();
            assert_eq!(shaded, (s.width * s.height / 2) as usize);
        }
        assert!(frames[3]
            .iter()
            .enumerate()
            .all(|(i, src)| (*src == Source::Shaded)
                == model::shaded(1, i as u32 % s.width, i as u32 / s.width)));
    }
}

/// Renders the still scene (point-sampled ground or not) with `v` and with native, 3 warm-up and
/// 2 compared frames; returns each frame's PSNR (dB, RGBA8) and largest error (levels).
fn still_against_native(v: &Variant, point_sampled: bool, camera: &str) -> Vec<(f64, u8)> {
    let ground = if point_sampled {
        "checker_size = 0.5\nfilter = \"none\""
    } else {
        "checker_size = 0.5"
    };
    let s = common::scenario(&format!(
        "{}{camera}\n[[techniques]]\ntechnique = \"native\"\n",
        SCENE.replace("checker_size = 0.5", ground)
    ));
    let gpu = common::gpu();
    let render = |v: &Variant| {
        let mut scene = SceneGpu::new(&gpu.device, &gpu.queue, &s).unwrap();
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
    let other = render(v);
    native
        .frames
        .iter()
        .zip(&other.frames)
        .map(|(n, c)| {
            let sq: f64 = n
                .data
                .iter()
                .zip(&c.data)
                .map(|(a, b)| (f64::from(*a) - f64::from(*b)).powi(2))
                .sum();
            let mse = sq / n.data.len() as f64;
            let psnr = if mse == 0.0 {
                f64::INFINITY
            } else {
                10.0 * (255.0f64 * 255.0 / mse).log10()
            };
            let max = n
                .data
                .iter()
                .zip(&c.data)
                .map(|(a, b)| a.abs_diff(*b))
                .max();
            (psnr, max.unwrap())
        })
        .collect()
}

#[test]
fn still_scene_reproduces_native() {
    // Issue 26's acceptance: at least 50 dB without derivative shading. Nothing moves, so the
    // history at each missing pixel is its own shade of the last frame, taken with confidence 1:
    // the output is native's exactly (inf dB on lavapipe).
    for (f, (psnr, max)) in still_against_native(&variant(&[]), true, STILL_OFF_AXIS)
        .into_iter()
        .enumerate()
    {
        assert!(psnr >= 50.0, "frame {f}: {psnr:.2} dB, max {max}/255");
    }
    // With the filtered ground the shaded pixels themselves differ: the quarter-resolution
    // derivatives (differences over 2 pixels, scaled by `gradient_scale = 0.5`, constant over 4x4
    // pixel quads) are not native's (over 1 pixel, 2x2 quads) where the perspective is strong, and
    // the box filter near the pattern's Nyquist limit turns that into up to 29 levels on the far
    // ground: 36.0 dB on lavapipe, as the checkerboards' quarter-resolution renders do.
    for (f, (psnr, max)) in still_against_native(&variant(&[]), false, STILL_OFF_AXIS)
        .into_iter()
        .enumerate()
    {
        assert!(
            psnr >= 35.0,
            "filtered, frame {f}: {psnr:.2} dB, max {max}/255"
        );
    }
}
