//! The reference's own noise: the converged reference (`samples` jittered renders per pixel) on
//! its first compared frame against one of `reference.noise_samples` samples, on the scenario's
//! image metrics (PSNR, SSIM, FLIP, HDR-FLIP, ColorVideoVDP on that one frame). Two variants whose
//! values differ by less than it cannot be ranked against this reference (`tables.rs` prints them
//! as ties).
//!
//! Cheap by construction: the two renders are of the first compared frame only. The scenario is
//! copied with no warm-up frames and two measured frames, the second at the scene time of the
//! first compared frame (the warm-up's scene time as one time step), so neither reference renders
//! the warm-up; the comparison is on the CPU, whatever `metrics_device` says. Frame-to-frame
//! metrics (`flicker`, `tde`) and ColorVideoVDP's flicker measures have no meaning on one frame
//! and are left out; so is `motion_blur` (one frame has no motion to blur along).
//!
//! Not here: the reference render itself (`reference.rs`), the tie rule (`tessera_results::ReferenceNoise::tied`).

use std::collections::BTreeMap;

use tessera_results::ReferenceNoise;

use super::captured::{MetricInputs, ReferenceFrames};
use super::evaluate;
use super::plan::Plan;
use crate::gpu::Gpu;
use crate::metric::{MetricKind, Values};
use crate::render::scene::SceneGpu;
use crate::scenario::{Reference, Scenario};

/// The metrics that mean something on one frame: not those of consecutive frames.
fn one_frame_metric(m: MetricKind) -> bool {
    !matches!(m.def().values, Values::Consecutive | Values::Motion)
}

/// The scenario reduced to its first compared frame, rendered as the converged reference with
/// `samples` samples.
fn first_frame(scenario: &Scenario, samples: u32) -> Scenario {
    let mut s = scenario.clone();
    let warmup = scenario.warmup_frames;
    s.warmup_frames = 0;
    s.warmup_ms = Some(0.0);
    // Frame 1 at `warmup` time steps: the first compared frame's scene time.
    s.measured_frames = if warmup > 0 { 2 } else { 1 };
    if warmup > 0 {
        s.time_step = scenario.time_step * warmup as f64;
    }
    s.auto = None;
    s.save_frames = Vec::new();
    s.save_worst = false;
    s.motion_blur = false;
    s.gates = Vec::new();
    s.metrics.retain(|&m| one_frame_metric(m));
    s.reference = Reference::Converged { samples };
    s
}

/// Keeps only the last frame of a reduced render (the first compared frame).
fn last_only(r: &mut ReferenceFrames) {
    fn keep_last<T>(v: &mut Vec<T>) {
        let n = v.len();
        if n > 1 {
            v.drain(..n - 1);
        }
    }
    keep_last(&mut r.frames);
    keep_last(&mut r.hdr);
    keep_last(&mut r.exposures);
    keep_last(&mut r.masks);
    keep_last(&mut r.non_finite);
}

/// Measures the reference's noise, when the scenario asks for it (`reference_noise`). `None`
/// when it does not; an error (the renders failed) is recorded in the result, not raised.
pub fn measure(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    scenario: &Scenario,
    on_frame: &mut dyn FnMut(),
) -> Option<ReferenceNoise> {
    let dense = scenario.reference_noise?;
    let Reference::Converged { samples } = scenario.reference else {
        return None;
    };
    if !scenario.needs_reference() {
        return None;
    }
    let frame = 0;
    let mut noise = ReferenceNoise {
        reference_samples: samples,
        samples: dense,
        frame,
        metrics: BTreeMap::new(),
        error: None,
    };
    let base = first_frame(scenario, samples);
    let denser = first_frame(scenario, dense);
    // Read back to the CPU and evaluated there, whatever the scenario's metrics device.
    let plan = |s| Plan::new(gpu, s).on_cpu();
    let (base_plan, denser_plan) = (plan(&base), plan(&denser));
    let render = |p: &Plan<'_>, scene: &mut SceneGpu, on_frame: &mut dyn FnMut()| {
        super::reference::render(gpu, scene, p, on_frame).map(|mut r| {
            last_only(&mut r);
            r
        })
    };
    let (mut test, reference) = match (
        render(&base_plan, scene, on_frame),
        render(&denser_plan, scene, on_frame),
    ) {
        (Ok(t), Ok(r)) => (t, r),
        (Err(e), _) | (_, Err(e)) => {
            noise.error = Some(e);
            return Some(noise);
        }
    };
    let inputs = MetricInputs {
        reference: &reference,
        test: &std::mem::take(&mut test.frames),
        test_hdr: &test.hdr,
        test_gpu: &[],
        test_non_finite: &test.non_finite,
        motion: &Ok(Vec::new()),
    };
    let evaluation = evaluate::evaluate(gpu, &base_plan, &inputs);
    let names: Vec<&str> = base.metrics.iter().map(|m| m.name()).collect();
    for m in evaluation.metrics {
        if m.check.is_none() && names.contains(&m.name.as_str()) && m.value.is_finite() {
            noise.metrics.insert(m.name, m.value);
        }
    }
    noise.error = evaluation.error;
    Some(noise)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_frame_lands_on_the_first_compared_frame() {
        let mut s = crate::scenario::parse(
            std::path::Path::new("n.toml"),
            "resolution = [8, 8]\n[frames]\nwarmup = 5\nmeasured = 3\n\
             [reference]\nkind = \"ground-truth\"\n\
             [camera]\n[[camera.keyframes]]\ntime = 0.0\nposition = [0.0, 1.0, 4.0]\n\
             target = [0.0, 0.0, 0.0]\n[[techniques]]\ntechnique = \"native\"\n",
        )
        .unwrap();
        s.metrics = vec![MetricKind::Psnr, MetricKind::Flicker, MetricKind::Flip];
        let f = first_frame(&s, 128);
        assert_eq!((f.warmup_frames, f.measured_frames), (0, 2));
        // The last frame of the reduced render is the original's first compared frame.
        assert_eq!(f.frame_time(1), s.frame_time(s.warmup_frames));
        assert_eq!(f.metrics, vec![MetricKind::Psnr, MetricKind::Flip]);
        assert_eq!(f.reference, Reference::Converged { samples: 128 });
        assert_eq!(s.reference_noise, Some(128));
    }
}
