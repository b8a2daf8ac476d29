//! Adaptive shading: the paper's numbers on the CPU model (motion factors, section 4.2's worked
//! example), and on the default adapter: `native-deferred` renders what `native` renders, the GPU
//! rates equal the CPU model's on the inputs the rate pass was given (static, moving and cut
//! cameras, a dynamic object), the shading pass shades once per coarse pixel and object and
//! writes that shade to all its pixels, and the reported shading rate counts exactly those shades.

mod common;

use common::check::{vec4s, Rig};
use glam::Vec4;
use tessera::params::ParamValue;
use tessera::render::readback::read_texture_raw;
use tessera::render::scene::SceneGpu;
use tessera::run::frames;
use tessera::scenario::Scenario;
use tessera::techniques::adaptive_shading::model::{
    self, b_half, b_quarter, decode, Inputs, Mode, RateParams, TileStats,
};
use tessera::techniques::adaptive_shading::{rates_of, AdaptiveGpu as Adaptive};
use tessera::techniques::Variant;
use tessera::techniques::{self, BuildContext, Target};

/// Eq. 20 and 21 against the values in notes/techniques.md section 2 (evaluated from the fits).
#[test]
fn motion_factors_match_the_published_fits() {
    let v = [0.0, 0.5, 1.0, 2.0, 3.0, 4.0, 8.0];
    let bh = [1.0000, 0.9564, 0.7633, 0.4324, 0.2851, 0.2099, 0.0993];
    let bq = [2.1300, 2.0850, 1.9194, 1.4290, 1.0372, 0.7841, 0.3653];
    for i in 0..v.len() {
        assert!((b_half(v[i]) - bh[i]).abs() < 1e-4, "b_H({})", v[i]);
        assert!(
            (b_quarter(v[i], 2.13) - bq[i]).abs() < 1e-4,
            "b_Q({})",
            v[i]
        );
    }
}

fn standalone(v: f32) -> (u32, u32) {
    // Section 4.2: t = 0.03, e = 0.1, motion along x only, no hysteresis.
    let p = RateParams {
        threshold: 0.03,
        mode: Mode::Motion,
        max_error: 0.1,
        hysteresis: 0.0,
        allow_4x4: true,
        ..RateParams::default()
    };
    let stats = TileStats {
        error: [0.0; 2],
        avg_luma: 0.5,
        min_motion: [v, 0.0],
        disoccluded: 0,
    };
    decode(model::select(&stats, [-1.0; 2], true, &p).code)
}

/// Section 4.2: with t = 0.03 and e = 0.1, half rate is allowed from 2.8586 px/frame ("2.8") and
/// quarter rate from 9.4877 px/frame (notes/techniques.md section 2); at rest, full rate.
#[test]
fn worked_example_of_section_4_2() {
    assert_eq!(standalone(0.0), (1, 1));
    assert_eq!(standalone(2.85), (1, 1));
    assert_eq!(standalone(2.87), (2, 1));
    assert_eq!(standalone(9.48), (2, 1));
    // 4x1 is no region: quarter on x alone is shaded 2x1 ...
    assert_eq!(standalone(9.50), (2, 1));
    // ... and with motion on both axes it is 4x4 when allowed.
    let p = RateParams {
        threshold: 0.03,
        mode: Mode::Motion,
        hysteresis: 0.0,
        allow_4x4: true,
        ..RateParams::default()
    };
    let stats = TileStats {
        error: [0.0; 2],
        avg_luma: 0.5,
        min_motion: [9.5, 9.5],
        disoccluded: 0,
    };
    assert_eq!(
        decode(model::select(&stats, [-1.0; 2], true, &p).code),
        (4, 4)
    );
    let no44 = RateParams {
        allow_4x4: false,
        ..p
    };
    let (rx, ry) = decode(model::select(&stats, [-1.0; 2], true, &no44).code);
    assert_eq!(rx * ry, 8, "4x4 off: one axis back to half ({rx}x{ry})");
}

/// Eq. 15 and 16 at rest: full rate when E >= t(I_avg + l), quarter when kE < t(I_avg + l);
/// hysteresis (section 5.4) moves each threshold by t * epsilon towards keeping the previous rate.
#[test]
fn content_thresholds_and_hysteresis() {
    let p = RateParams {
        hysteresis: 0.0,
        allow_4x4: true,
        ..RateParams::default()
    };
    let tau = 0.15 * (0.5 + 0.05);
    let at = |e: f32, prev: f32, p: &RateParams| {
        let stats = TileStats {
            error: [e, e],
            avg_luma: 0.5,
            min_motion: [0.0, 0.0],
            disoccluded: 0,
        };
        decode(model::select(&stats, [prev; 2], true, p).code).0
    };
    assert_eq!(at(tau * 1.01, -1.0, &p), 1);
    assert_eq!(at(tau * 0.99, -1.0, &p), 2);
    assert_eq!(at(tau / 2.13 * 1.01, -1.0, &p), 2);
    assert_eq!(at(tau / 2.13 * 0.99, -1.0, &p), 4);
    let h = RateParams {
        hysteresis: 0.1,
        ..p
    };
    // The previous rate (log2) is sticky: just above tau, a half-rate tile stays half
    // (t(1 + eps)); just below, a full-rate tile stays full (t(1 - eps)); likewise at the
    // half/quarter boundary.
    assert_eq!(at(tau * 1.05, 1.0, &h), 2);
    assert_eq!(at(tau * 1.15, 1.0, &h), 1);
    assert_eq!(at(tau * 0.95, 0.0, &h), 1);
    assert_eq!(at(tau * 0.85, 0.0, &h), 2);
    assert_eq!(at(tau / 2.13 * 1.05, 2.0, &h), 4);
    assert_eq!(at(tau / 2.13 * 0.95, 1.0, &h), 2);
    assert_eq!(at(tau / 2.13 * 0.85, 1.0, &h), 4);
    // Disoccluded tiles are shaded at full rate whatever their error.
    let stats = TileStats {
        error: [0.0, 0.0],
        avg_luma: 0.5,
        min_motion: [0.0, 0.0],
        disoccluded: 1,
    };
    assert_eq!(model::select(&stats, [-1.0; 2], true, &p).code, 0);
}

/// A small scene with a ground, objects, a dynamic box and a panning camera; `shading_cost` low.
const SCENE: &str = r#"
resolution = [72, 40]
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
animation = { kind = "translate", velocity = [2, 0, 0] }
[[scene.objects]]
shape = "sphere"
position = [1.4, 0.5, 0.3]
radius = 0.5
[[scene.objects]]
shape = "box"
position = [-1.5, 0.3, -0.5]
size = [0.6, 0.6, 0.6]
color = [0.6, 0.6, 0.6]
[camera]
[[camera.keyframes]]
time = 0
position = [0, 1.5, 4]
target = [0, 0.4, 0]
[[camera.keyframes]]
time = 0.1
position = [0.6, 1.5, 4]
target = [0.2, 0.4, 0]
[[camera.keyframes]]
time = 0.11
position = [3, 2, 3]
target = [0, 0.4, 0]
cut = true
[[techniques]]
technique = "native"
"#;

fn adaptive(params: &[(&str, ParamValue)]) -> Variant {
    common::variant("adaptive-shading", params)
}

fn render(gpu: &tessera::gpu::Gpu, s: &Scenario, v: &Variant) -> tessera::run::rendered::Rendered {
    let mut scene = SceneGpu::new(&gpu.device, &gpu.queue, s).unwrap();
    let mut t = techniques::build(
        v,
        &BuildContext::new(
            gpu,
            &scene,
            Target::new(s.width, s.height, s.scene.has_dynamic_objects()),
        ),
    )
    .unwrap();
    frames::render(gpu, &mut scene, s, t.as_mut(), true, true, &mut || {}).unwrap()
}

#[test]
fn native_deferred_renders_what_native_renders() {
    let gpu = common::gpu();
    let s = common::scenario(common::TINY);
    let native = render(&gpu, &s, &common::variant("native", &[]));
    let deferred = render(&gpu, &s, &common::variant("native-deferred", &[]));
    // The same shading function on the same interpolated inputs: bitwise identical (lavapipe).
    for (a, b) in native.hdr_frames.iter().zip(&deferred.hdr_frames) {
        let bits = |d: &[f32]| d.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert!(
            bits(&a.data) == bits(&b.data),
            "native-deferred differs from native"
        );
    }
    for e in &deferred.extras {
        let values: Vec<(&str, f64)> = e.values.iter().map(|v| (v.name, v.value)).collect();
        assert_eq!(values, vec![("shading-rate", 1.0)]);
    }
    assert_eq!(deferred.non_finite, 0);
}

fn f32s(bytes: Vec<u8>) -> Vec<f32> {
    bytemuck::cast_slice(&bytes).to_vec()
}

/// Renders `frames` frames; after each compares the GPU's rates with the CPU model's on the same
/// inputs. Returns the number of tiles at each region size over all frames with history.
fn compare_with_model(s: &Scenario, v: &Variant, frames: u32) -> [usize; 5] {
    let mut rig = Rig::new(
        s,
        |gpu| Adaptive::new(gpu, rates_of(v), s.width, s.height),
        Adaptive::texture,
    );
    let mut histogram = [0usize; 5];
    let mut close_calls = 0;
    let (tw, th) = model::tiles(s.width, s.height);
    let rgba = |v: Vec<f32>| -> Vec<[f32; 4]> { vec4s(v).iter().map(Vec4::to_array).collect() };
    for index in 0..frames {
        rig.frame(s, index);
        let last = rig.renderer.last_frame().unwrap();
        let (cur, prev) = (last.parity, 1 - last.parity);
        let raw_of = |name: String| read_texture_raw(&rig.gpu, rig.texture(&name));
        let prev_color = rgba(rig.read(&format!("color{prev}")));
        let motion = rgba(rig.read("motion"));
        let prev_depth = rig.read(&format!("depth{prev}"));
        let depth = rig.read(&format!("depth{cur}"));
        let prev_state: Vec<[f32; 2]> = f32s(raw_of(format!("rate_state{prev}")))
            .chunks_exact(2)
            .map(|c| [c[0], c[1]])
            .collect();
        let state: Vec<[f32; 2]> = f32s(raw_of(format!("rate_state{cur}")))
            .chunks_exact(2)
            .map(|c| [c[0], c[1]])
            .collect();
        let raw_name = if last.params.neighbour_filter {
            "rates_raw"
        } else {
            "rates"
        };
        let raw: Vec<u32> = bytemuck::cast_slice(&raw_of(raw_name.into())).to_vec();
        let rates = rig.renderer.rates(&rig.gpu).unwrap();
        let inputs = Inputs {
            width: s.width,
            height: s.height,
            prev_color: &prev_color,
            motion: &motion,
            depth: &depth,
            prev_depth: &prev_depth,
            prev_state: &prev_state,
            near: last.near,
            far: last.far,
            history: last.history,
            params: last.params,
        };
        let (decisions, model_rates) = model::rates_all(&inputs);
        for (i, d) in decisions.iter().enumerate() {
            if d.margin < 1e-4 {
                // f32 rounding (fused multiply-adds) may decide the other way this close.
                close_calls += 1;
                continue;
            }
            assert_eq!(
                raw[i],
                d.code,
                "frame {index} tile {i}: gpu {:?} model {:?} ({d:?})",
                decode(raw[i]),
                decode(d.code)
            );
            if last.history {
                for (g, m) in state[i].into_iter().zip(d.state) {
                    assert!(
                        (g - m).abs() <= 1e-4 * m.abs().max(1e-3),
                        "frame {index} tile {i} state {g} vs {m}"
                    );
                }
            }
        }
        if close_calls == 0 {
            assert_eq!(rates, model_rates, "frame {index}: filtered rates");
        }
        assert_eq!(rates.len(), (tw * th) as usize);
        if !last.history {
            assert!(rates.iter().all(|c| *c == 0), "no history: full rate");
        } else {
            for c in &rates {
                let (rx, ry) = decode(*c);
                histogram[(rx * ry).trailing_zeros() as usize] += 1;
            }
        }
    }
    assert!(close_calls <= 2, "{close_calls} tiles at a threshold");
    histogram
}

#[test]
fn gpu_rates_equal_the_model_on_a_moving_scene_with_a_cut() {
    let s = common::scenario(SCENE);
    // Frames 0-6 pan (the box moves too), frame 7 is after the cut (no history), 8 after it.
    let h = compare_with_model(&s, &adaptive(&[]), 9);
    let reduced: usize = h[1..].iter().sum();
    assert!(reduced > 0, "some tiles shade at a reduced rate: {h:?}");
    assert!(h[0] > 0, "some tiles stay at full rate: {h:?}");
}

#[test]
fn gpu_rates_equal_the_model_in_every_mode() {
    let s = common::scenario(SCENE);
    for (mode, filter, allow, sample) in [
        ("content", false, true, "centre"),
        ("motion", true, false, "centre"),
        ("content-motion", false, false, "pixel"),
    ] {
        compare_with_model(
            &s,
            &adaptive(&[
                ("mode", ParamValue::Str(mode.into())),
                ("neighbour_filter", ParamValue::Bool(filter)),
                ("allow_4x4", ParamValue::Bool(allow)),
                ("coarse_sample", ParamValue::Str(sample.into())),
                ("threshold", ParamValue::Float(0.3)),
            ]),
            4,
        );
    }
}

/// After each frame: every coarse pixel (a tile's rate) shows one colour per object in it, and the
/// shades counted on the GPU are exactly one per coarse pixel and object; the covered pixels are
/// those with an object. Both ways of placing the shade.
#[test]
fn one_shade_per_coarse_pixel_and_object() {
    let s = common::scenario(SCENE);
    for sample in ["centre", "pixel"] {
        let v = adaptive(&[
            ("threshold", ParamValue::Float(0.4)),
            ("allow_4x4", ParamValue::Bool(true)),
            ("coarse_sample", ParamValue::Str(sample.into())),
        ]);
        let mut rig = Rig::new(
            &s,
            |gpu| Adaptive::new(gpu, rates_of(&v), s.width, s.height),
            Adaptive::texture,
        );
        let (w, h) = (s.width as usize, s.height as usize);
        let (tw, _) = model::tiles(s.width, s.height);
        let mut coarse_blocks = 0;
        for index in 0..6 {
            rig.frame(&s, index);
            let objects: Vec<u32> = f32s(read_texture_raw(&rig.gpu, rig.texture("gbuf_position")))
                .chunks_exact(4)
                .map(|c| c[3] as u32)
                .collect();
            let color: Vec<f32> = rig.output().iter().flat_map(|c| c.to_array()).collect();
            let rates = rig.renderer.rates(&rig.gpu).unwrap();
            let mut shades = 0u32;
            for by in 0..h {
                for bx in 0..w {
                    let (rx, ry) = decode(rates[(by / 16) * tw as usize + bx / 16]);
                    let (rx, ry) = (rx as usize, ry as usize);
                    // Visit each coarse pixel once, at its top-left pixel.
                    if bx % rx != 0 || by % ry != 0 {
                        continue;
                    }
                    if rx * ry > 1 {
                        coarse_blocks += 1;
                    }
                    let mut seen: Vec<(u32, &[f32])> = Vec::new();
                    for y in by..(by + ry).min(h) {
                        for x in bx..(bx + rx).min(w) {
                            let o = objects[y * w + x];
                            if o == 0 {
                                continue;
                            }
                            let c = &color[(y * w + x) * 4..(y * w + x) * 4 + 4];
                            match seen.iter().find(|(so, _)| *so == o) {
                                Some((_, sc)) => assert_eq!(
                                    *sc, c,
                                    "{sample} frame {index}: pixel ({x}, {y}) of object {o}"
                                ),
                                None => seen.push((o, c)),
                            }
                        }
                    }
                    shades += seen.len() as u32;
                }
            }
            let covered = objects.iter().filter(|o| **o != 0).count() as u32;
            assert_eq!(
                rig.renderer.counters(&rig.gpu),
                [shades, covered],
                "{sample} frame {index}"
            );
        }
        assert!(coarse_blocks > 0, "{sample}: no coarse pixel was tested");
    }
}

/// The shading rate reported per frame is what the rates imply on a frame without object edges
/// inside coarse pixels: here, checked as bounds (every shade covers 1 to 8 pixels).
#[test]
fn reported_shading_rate_is_within_the_rates_bounds() {
    let gpu = common::gpu();
    let mut s = common::scenario(SCENE);
    s.warmup_frames = 3;
    let r = render(
        &gpu,
        &s,
        &adaptive(&[("threshold", ParamValue::Float(1.0))]),
    );
    let v = r.extras[0].values[0];
    let rate = (v.name, v.value);
    assert_eq!(rate.0, "shading-rate");
    assert!(
        rate.1 > 1.0 / 8.0 && rate.1 < 1.0,
        "shading rate {}",
        rate.1
    );
    assert_eq!(r.non_finite, 0);
}

/// The pass graphs, without a GPU: native-deferred has no rate pass, motion or history; the
/// neighbour filter adds one pass and one tile-resolution texture; bytes per pixel as declared.
#[test]
fn pass_graphs_run_and_allocate_only_what_each_variant_needs() {
    use tessera::techniques::adaptive_shading::graph;
    let names = |p: &tessera::render::graph::Plan| -> Vec<&str> {
        p.passes.iter().map(|x| x.name).collect()
    };
    let (w, h) = (64u32, 48u32);
    let px = (w * h) as u64;
    let deferred = graph(None, w, h);
    assert_eq!(names(&deferred), ["gbuffer", "shade"]);
    // Three Rgba32Float G-buffer targets, one Rgba16Float output, one Depth32Float.
    let total = |p: &tessera::render::graph::Plan| p.records().iter().map(|r| r.bytes).sum::<u64>();
    assert_eq!(total(&deferred), px * (3 * 16 + 8 + 4));

    let adaptive_default = graph(rates_of(&adaptive(&[])).as_ref(), w, h);
    assert_eq!(
        names(&adaptive_default),
        ["gbuffer", "rates", "rate_filter", "shade"]
    );
    let no_filter = graph(
        rates_of(&adaptive(&[("neighbour_filter", ParamValue::Bool(false))])).as_ref(),
        w,
        h,
    );
    assert_eq!(names(&no_filter), ["gbuffer", "rates", "shade"]);
    let tiles = (w.div_ceil(16) * h.div_ceil(16)) as u64;
    // The filter's input: one R32Uint per tile.
    assert_eq!(total(&adaptive_default) - total(&no_filter), tiles * 4);
    // History (a second output and depth), motion (Rgba16Float), rates (R32Uint) and two
    // Rg32Float rate states on top of the baseline.
    assert_eq!(
        total(&no_filter) - total(&deferred),
        px * (8 + 4 + 8) + tiles * (4 + 2 * 8)
    );
}
