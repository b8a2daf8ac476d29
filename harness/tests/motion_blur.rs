//! `reference.motion_blur`: the blur pass equals its CPU model, a still camera is not blurred (the
//! metrics equal the unblurred run's), and under a pan the compared frames are blurred (upscale's
//! error against native falls, as the paper says motion blur hides reduced shading) while the
//! frame checks still read the unblurred output.

mod common;

use tessera::render::motion_blur::{model, MotionBlur};
use tessera_results::ScenarioResult;

fn texture(gpu: &tessera::gpu::Gpu, w: u32, h: u32, data: &[[f32; 4]]) -> wgpu::Texture {
    let t = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("test"),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba16Float,
        usage: wgpu::TextureUsages::COPY_DST
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    });
    let halves: Vec<half::f16> = data
        .iter()
        .flatten()
        .map(|&v| half::f16::from_f32(v))
        .collect();
    gpu.queue.write_texture(
        t.as_image_copy(),
        bytemuck::cast_slice(&halves),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(w * 8),
            rows_per_image: Some(h),
        },
        t.size(),
    );
    t
}

#[test]
fn the_blur_pass_equals_its_model() {
    let gpu = common::gpu();
    let (w, h) = (37u32, 23u32);
    // A pattern with edges everywhere, values exact in f16 (multiples of 1/64).
    let frame: Vec<[f32; 4]> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let v = ((x * 7 + y * 13) % 64) as f32 / 64.0;
            [v, 1.0 - v, ((x ^ y) & 1) as f32, 1.0]
        })
        .collect();
    // Motion varying per pixel: still, sub-pixel, long and diagonal, past the border, NaN.
    let motion: Vec<[f32; 2]> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            match (x + y) % 5 {
                0 => [0.0, 0.0],
                1 => [0.25, -0.125],
                2 => [6.0, 0.0],
                3 => [-3.5, 2.25],
                _ if x == 3 => [f32::NAN, 0.0],
                _ => [20.0, -11.0],
            }
        })
        .collect();
    let motion4: Vec<[f32; 4]> = motion.iter().map(|m| [m[0], m[1], 0.0, 0.0]).collect();
    // The model reads what the GPU reads: the f16 values.
    let f16 = |v: f32| half::f16::from_f32(v).to_f32();
    let frame_q: Vec<[f32; 4]> = frame.iter().map(|p| p.map(f16)).collect();
    let motion_q: Vec<[f32; 2]> = motion.iter().map(|m| m.map(f16)).collect();
    let src = texture(&gpu, w, h, &frame);
    let mv = texture(&gpu, w, h, &motion4);
    let blur = MotionBlur::new(&gpu, w, h);
    let view = mv.create_view(&Default::default());
    let out = blur.blur(&gpu, &src, &view, true).unwrap();
    let got = tessera::render::readback::read_texture(&gpu.device, &gpu.queue, out);
    let want = model(&frame_q, &motion_q, w, h);
    let mut worst = 0.0f32;
    let mut blurred = 0;
    for (i, px) in want.iter().enumerate() {
        for c in 0..4 {
            // The output is f16: half a unit in the last place of values up to 1.
            worst = worst.max((got[i * 4 + c] - px[c]).abs());
        }
        if px[..3] != frame_q[i][..3] {
            blurred += 1;
        }
    }
    assert!(worst <= 1.0 / 1024.0, "largest difference {worst}");
    assert!(blurred > (w * h) as usize / 3, "{blurred} pixels blurred");
    // Not enabled (a frame that starts a shot): a copy.
    let out = blur.blur(&gpu, &src, &view, false).unwrap();
    let got = tessera::render::readback::read_texture(&gpu.device, &gpu.queue, out);
    for (i, px) in frame_q.iter().enumerate() {
        assert_eq!(&got[i * 4..i * 4 + 4], px, "pixel {i}");
    }
    // A wrong size is an error, not a panic.
    let small = texture(&gpu, 4, 4, &[[0.0; 4]; 16]);
    assert!(blur.blur(&gpu, &small, &view, true).is_err());
}

const SCENE: &str = r#"
resolution = [64, 40]
metrics = ["psnr", "flip"]
[frames]
warmup = 1
measured = 4
save = [3]
[scene]
shading_cost = 1
[scene.ground]
checker_size = 0.25
[[scene.lights]]
type = "directional"
[[scene.objects]]
shape = "box"
position = [0, 0.5, 0]
[camera]
[[camera.keyframes]]
time = 0
position = [0, 1.5, 4]
target = [0, 0.4, 0]
[[camera.keyframes]]
time = 1
position = [MOVE, 1.5, 4]
target = [MOVE, 0.4, 0]
[[techniques]]
technique = "native"
[[techniques]]
technique = "upscale"
scale = 0.5
"#;

fn run(src: &str) -> ScenarioResult {
    common::run_ok(src, "s.toml")
}

fn values(s: &ScenarioResult, variant: &str, metric: &str) -> Vec<f64> {
    let r = s
        .results
        .iter()
        .find(|r| r.technique == variant)
        .unwrap_or_else(|| {
            panic!(
                "no {variant} in {:?}",
                s.results.iter().map(|r| &r.variant).collect::<Vec<_>>()
            )
        });
    r.metrics
        .iter()
        .find(|m| m.name == metric)
        .unwrap_or_else(|| panic!("{metric} of {variant}: {:?}", r.status))
        .per_frame
        .clone()
}

fn with_blur(src: &str) -> String {
    src.replace("[frames]", "[reference]\nmotion_blur = true\n[frames]")
}

#[test]
fn a_still_camera_is_not_blurred_and_a_pan_is() {
    let still = SCENE.replace("MOVE", "0");
    let plain = run(&still);
    let blurred = run(&with_blur(&still));
    for m in ["psnr", "flip"] {
        assert_eq!(
            values(&plain, "upscale", m),
            values(&blurred, "upscale", m),
            "{m} on a still camera"
        );
    }
    // A fast pan (about 8 px per frame at this size): both frames blurred alike hide most of
    // upscale's loss; the checks still pass (deterministic, no non-finite values).
    let pan = SCENE.replace("MOVE", "2.0");
    let plain = run(&pan);
    let blurred = run(&with_blur(&pan));
    let (a, b) = (
        values(&plain, "upscale", "psnr"),
        values(&blurred, "upscale", "psnr"),
    );
    // Frame 0 follows the warm-up frame in the same shot, so every measured frame is blurred.
    for (i, (a, b)) in a.iter().zip(&b).enumerate() {
        assert!(b > a, "frame {i}: {b} dB blurred against {a} sharp");
    }
    for r in &blurred.results {
        assert_eq!(r.non_finite_values, 0, "{}", r.variant);
        let st = r.stability.as_ref().unwrap();
        assert_eq!(st.deterministic, Some(true), "{}", r.variant);
    }
}

#[test]
fn motion_blur_needs_a_reference() {
    let src = with_blur(&SCENE.replace("MOVE", "1")).replace(
        "[reference]\nmotion_blur = true",
        "[reference]\nkind = \"none\"\nmotion_blur = true",
    );
    let src = src.replace("metrics = [\"psnr\", \"flip\"]\n", "");
    let e = tessera::scenario::parse(std::path::Path::new("s.toml"), &src)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        e.contains("reference.motion_blur") && e.contains("needs a reference"),
        "{e}"
    );
}
