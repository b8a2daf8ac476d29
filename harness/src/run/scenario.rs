//! Runs one scenario on an open device: the reference first, then every variant, then metrics and
//! gates, into a [`ScenarioResult`]. Orchestration only: rendering is `frames.rs`, the reference
//! `reference.rs`, metrics `metrics.rs`, images `images.rs`, records `record.rs`.
//!
//! A variant that needs what the adapter lacks is `skipped` with the reason; a GPU error fails that
//! variant and the scenario goes on. Metrics are computed only after a variant's frames are all
//! rendered, never while timed GPU work is in flight.

use std::path::Path;
use std::time::Instant;

use tessera_results::{ScenarioResult, Status, VariantResult};

use super::evaluate::{CpuMetrics, Evaluator};
use super::frames::{self, Rendered};
use super::gpu_evaluate::GpuEvaluator;
use super::output::first_line;
use super::record::{empty_result, fill_conditions, fill_timings, finish, plan_record, PlanRecord};
use super::reference::{self, ReferenceFrames};
use super::{gates, images, metrics, motion, stability};
use crate::conditions::Sensors;
use crate::gpu::Gpu;
use crate::metrics_device::Backend;
use crate::render::renderer::Unsupported;
use crate::render::scene::SceneGpu;
use crate::scenario::{MetricKind, Reference, Scenario};
use crate::techniques::Variant;
use crate::techniques::{self, BuildContext, Target};

/// Runs `scenario`. Images go under `run_dir/images/<scenario>/`. `on_frame` ticks progress.
pub fn run(
    gpu: &Gpu,
    scenario: &Scenario,
    run_id: &str,
    run_dir: &Path,
    sensors: &Sensors,
    on_frame: &mut dyn FnMut(),
) -> ScenarioResult {
    let start = Instant::now();
    let mut results: Vec<VariantResult> = Vec::new();
    let scene = SceneGpu::new(&gpu.device, &gpu.queue, scenario);
    let mut scene = match scene {
        Ok(s) => s,
        Err(e) => {
            for v in &scenario.variants {
                results.push(empty_result(
                    v,
                    Status::Failed {
                        error: e.to_string(),
                    },
                ));
            }
            return finish(scenario, run_id, results, start);
        }
    };

    let needs_reference = scenario.needs_reference();
    let native_is_reference =
        |v: &Variant| techniques::is_reference(v) && scenario.reference == Reference::Native;
    // The reference renders first; when it is the native variant itself, that render is reused.
    let mut reference: Option<Result<ReferenceFrames, String>> = None;
    if scenario.needs_separate_reference() {
        reference = Some(reference::render(gpu, &mut scene, scenario, on_frame));
    }
    // The renderer's exact motion for `tde`, rendered once, outside any timed work.
    let motion: Result<Vec<Option<motion::MotionField>>, String> =
        if needs_reference && scenario.metrics.contains(&MetricKind::Tde) {
            motion::capture(gpu, &mut scene, scenario)
        } else {
            Ok(Vec::new())
        };
    let mut order: Vec<&Variant> = scenario
        .variants
        .iter()
        .filter(|v| native_is_reference(v))
        .collect();
    order.extend(scenario.variants.iter().filter(|v| !native_is_reference(v)));

    let image_dir = run_dir.join("images").join(&scenario.name);
    // Where the metrics run: `metrics_device` (the scenario's, `--metrics-device`), else by adapter.
    let gpu_evaluator = GpuEvaluator { gpu };
    let evaluator: &dyn Evaluator = match crate::metrics_device::chosen(scenario, gpu) {
        Backend::Gpu => &gpu_evaluator,
        Backend::Cpu => &CpuMetrics,
    };
    // Frames beyond `frames.save` that some variant saved as its worst: the reference's too.
    let mut worst_frames: Vec<u32> = Vec::new();
    for variant in order {
        let is_reference = needs_reference && native_is_reference(variant) && reference.is_none();
        let keep = needs_reference || !scenario.save_frames.is_empty();
        let mut result = empty_result(variant, Status::Ok);
        let outcome = render_variant(gpu, &mut scene, scenario, variant, keep, sensors, on_frame);
        let rendered = match outcome {
            Ok(Ok((r, plan_record))) => {
                fill_timings(&mut result, &r, plan_record);
                fill_conditions(&mut result, &r, scenario, variant, sensors);
                r
            }
            Ok(Err(Unsupported(reason))) => {
                result.status = Status::Skipped { reason };
                results.push(result);
                continue;
            }
            Err(error) => {
                result.status = Status::Failed { error };
                if is_reference {
                    reference = Some(Err(format!(
                        "the native reference failed: {}",
                        variant.name
                    )));
                }
                results.push(result);
                continue;
            }
        };
        result.non_finite_values = rendered.non_finite;
        frames::append_hashes(&scenario.name, &variant.name, &rendered.hashes);
        images::save_frames(
            &mut result,
            &rendered.frames,
            &scenario.save_frames,
            &image_dir,
            run_dir,
            "output",
        );
        // The native reference's frames become the reference (moved, not copied); its metrics are
        // then computed against itself, the sanity values every other variant is read against.
        let (frames, hdr, masks) = if is_reference {
            reference = Some(Ok(ReferenceFrames::new(
                rendered.frames,
                rendered.hdr_frames,
                rendered.non_finite_masks,
            )));
            (None, None, None)
        } else {
            (
                Some(rendered.frames),
                Some(rendered.hdr_frames),
                Some(rendered.non_finite_masks),
            )
        };
        if needs_reference {
            match reference.as_ref() {
                Some(Ok(r)) => {
                    result.reference = Some(scenario.reference.name().to_string());
                    let inputs = metrics::MetricInputs {
                        reference: r,
                        test: frames.as_deref().unwrap_or(&r.frames),
                        test_hdr: hdr.as_deref().unwrap_or(&r.hdr),
                        motion: &motion,
                    };
                    let evaluation = evaluator.evaluate(scenario, &inputs);
                    images::save_cvvdp_maps(&mut result, &evaluation.maps, &image_dir, run_dir);
                    result.metrics = evaluation.metrics;
                    if let Some(error) = evaluation.error {
                        result.status = Status::Failed { error };
                    }
                    // The reference against itself has no error to show.
                    if let (true, Some(maps)) = (frames.is_some(), &evaluation.error_maps) {
                        images::save_heatmaps(&mut result, maps, &image_dir, run_dir);
                    } else if frames.is_some() {
                        images::save_error_maps(
                            &mut result,
                            &inputs,
                            &scenario.save_frames,
                            reference::keep_hdr(scenario),
                            &image_dir,
                            run_dir,
                        );
                    }
                    // Each metric's worst frame beside the saved ones (`frames.save_worst`): the
                    // output, its error maps (on the CPU: a back end maps only `frames.save`) and,
                    // once per scenario below, the reference's frame.
                    if let (true, Some(own)) = (scenario.save_worst, frames.as_deref()) {
                        let worst = images::worst_frames(&result.metrics, &scenario.save_frames);
                        images::save_frames(
                            &mut result,
                            own,
                            &worst,
                            &image_dir,
                            run_dir,
                            "output",
                        );
                        images::save_error_maps(
                            &mut result,
                            &inputs,
                            &worst,
                            reference::keep_hdr(scenario),
                            &image_dir,
                            run_dir,
                        );
                        worst_frames.extend(worst);
                    }
                }
                Some(Err(e)) => result.status = Status::Failed { error: e.clone() },
                None => {}
            }
        }
        result
            .metrics
            .extend(metrics::extra_values(&rendered.extras));
        images::save_extras(
            &mut result,
            &rendered.extras,
            &scenario.save_frames,
            &image_dir,
            run_dir,
        );
        // The native reference's own frames and masks are the reference's.
        let reference_ok = match reference.as_ref() {
            Some(Ok(r)) if needs_reference => Some(r),
            _ => None,
        };
        let own = stability::Frames {
            frames: frames
                .as_deref()
                .or(reference_ok.map(|r| r.frames.as_slice()))
                .unwrap_or(&[]),
            masks: masks
                .as_deref()
                .or(reference_ok.map(|r| r.masks.as_slice()))
                .unwrap_or(&[]),
        };
        let reference_view = reference_ok.map(|r| stability::Frames {
            frames: &r.frames,
            masks: &r.masks,
        });
        result.stability = Some(stability::check(
            scenario,
            own,
            rendered.deterministic,
            reference_view,
        ));
        results.push(result);
    }
    // Reference images once per scenario, next to the variants'.
    if let Some(Ok(r)) = &reference {
        if let Some(first) = results
            .iter_mut()
            .find(|r| r.status == Status::Ok && r.technique != "native")
        {
            let mut saved = scenario.save_frames.clone();
            saved.extend(
                worst_frames
                    .iter()
                    .filter(|f| !scenario.save_frames.contains(f)),
            );
            saved.sort();
            saved.dedup();
            images::save_frames(first, &r.frames, &saved, &image_dir, run_dir, "reference");
        }
    }
    // Put results back in the scenario's declaration order.
    results.sort_by_key(|r| {
        scenario
            .variants
            .iter()
            .position(|v| v.name == r.variant)
            .unwrap_or(usize::MAX)
    });
    gates::apply(scenario, &mut results);
    finish(scenario, run_id, results, start)
}

type VariantOutcome = Result<Result<(Rendered, PlanRecord), Unsupported>, String>;

/// Builds and renders a variant inside a GPU error scope. Outer error: the GPU failed.
fn render_variant(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    scenario: &Scenario,
    variant: &Variant,
    keep: bool,
    sensors: &Sensors,
    on_frame: &mut dyn FnMut(),
) -> VariantOutcome {
    let validation = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let oom = gpu.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let target = Target::new(
        scenario.width,
        scenario.height,
        scenario.scene.has_dynamic_objects(),
    );
    let built = techniques::build(variant, &BuildContext::new(gpu, scene, target));
    let result = match built {
        Err(u) => Ok(Err(u)),
        Ok(mut t) => {
            let plan = plan_record(t.as_ref());
            let hdr = keep && reference::keep_hdr(scenario);
            let sampler = sensors.sampler();
            match frames::render_sampled(
                gpu,
                scene,
                scenario,
                t.as_mut(),
                keep,
                hdr,
                sampler,
                on_frame,
            ) {
                Ok(r) => Ok(Ok((r, plan))),
                Err(e) => Err(e.to_string()),
            }
        }
    };
    let oom = pollster::block_on(oom.pop());
    let validation = pollster::block_on(validation.pop());
    if let Some(e) = oom.or(validation) {
        return Err(format!("GPU error: {}", first_line(&e.to_string())));
    }
    result
}
