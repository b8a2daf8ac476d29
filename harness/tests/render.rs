//! Rendering on the default adapter (lavapipe in CI): frames are not blank, repeated renders are
//! bitwise identical, and techniques produce what their definition says.

mod common;

use tessera::params::ParamValue;
use tessera::render::scene::SceneGpu;
use tessera::run::frames;
use tessera::techniques::Variant;
use tessera::techniques::{self, BuildContext, Target};

use common::variant;

fn render(
    gpu: &tessera::gpu::Gpu,
    s: &tessera::scenario::Scenario,
    v: &Variant,
) -> tessera::run::rendered::Rendered {
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
fn tiny_scenario_is_not_blank_and_renders_bitwise_identically_twice() {
    let gpu = common::gpu();
    let s = common::scenario(common::TINY);
    let v = variant("native", &[]);
    let a = render(&gpu, &s, &v);
    let b = render(&gpu, &s, &v);
    assert_eq!(a.hdr_frames.len(), 2);
    for (fa, fb) in a.hdr_frames.iter().zip(&b.hdr_frames) {
        let bits = |d: &[f32]| d.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert!(
            bits(&fa.data) == bits(&fb.data),
            "two renders of the same frame differ"
        );
    }
    // Not blank: many distinct colours, and not only the background.
    let frame = &a.frames[1];
    let mut colours: Vec<&[u8]> = frame.data.chunks_exact(3).collect();
    colours.sort();
    colours.dedup();
    assert!(
        colours.len() > 50,
        "only {} distinct colours",
        colours.len()
    );
    // The rotating box moves between measured frames.
    assert_ne!(a.frames[0].data, a.frames[1].data);
    assert_eq!(a.non_finite, 0);
}

#[test]
fn upscale_at_scale_one_equals_native() {
    let gpu = common::gpu();
    let s = common::scenario(common::TINY);
    let native = render(&gpu, &s, &variant("native", &[]));
    for filter in ["bilinear", "nearest"] {
        let v = variant(
            "upscale",
            &[
                ("scale", ParamValue::Float(1.0)),
                ("filter", ParamValue::Str(filter.into())),
            ],
        );
        let up = render(&gpu, &s, &v);
        assert_eq!(up.frames[1].data, native.frames[1].data, "filter {filter}");
    }
}

#[test]
fn timings_and_fragment_counts_are_recorded_per_pass() {
    let gpu = common::gpu();
    let s = common::scenario(common::TINY);
    let v = variant("upscale", &[("scale", ParamValue::Float(0.5))]);
    let r = render(&gpu, &s, &v);
    assert_eq!(r.measurements.len(), 2);
    if gpu.info.features.timestamps {
        for m in &r.measurements {
            assert!(
                m.gpu_ms.contains_key("scene") && m.gpu_ms.contains_key("upscale"),
                "{:?}",
                m.gpu_ms
            );
            assert!(m.gpu_ms.values().all(|t| *t > 0.0));
        }
    }
    if gpu.info.features.pipeline_statistics {
        // The scene pass at 24x16 shades at most every pixel a few times over (overdraw, quads).
        let f = r.measurements[0].fragment_invocations["scene"];
        assert!(
            f > 24 * 16 / 2 && f < 24 * 16 * 8,
            "{f} fragment invocations"
        );
    }
}
