//! Runs one scenario on an open device: the reference first, then every variant, then metrics and
//! gates, into a [`ScenarioResult`]. Orchestration only: rendering is `frames.rs`, the reference
//! `reference.rs`, metrics `metrics.rs`, images `images.rs`, records `record.rs`.
//!
//! A variant that needs what the adapter lacks is `skipped` with the reason; a GPU error fails that
//! variant and the scenario goes on. Metrics are computed only after a variant's frames are all
//! rendered, never while timed GPU work is in flight.

use std::path::Path;
use std::time::Instant;

use tessera_metrics::Rgb8Image;
use tessera_results::{ScenarioResult, Status, VariantResult};

use super::evaluate::{CpuMetrics, Evaluator};
use super::frames::{self, Keep, Rendered};
use super::gpu_evaluate::GpuEvaluator;
use super::output::first_line;
use super::record::{empty_result, fill_conditions, fill_timings, finish, plan_record, PlanRecord};
use super::reference::{self, ReferenceFrames};
use super::{gates, images, metrics, motion, phases, stability};
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
    super::memory::reset_peak();
    let mut results: Vec<VariantResult> = Vec::new();
    let scene = phases::time("scene", || SceneGpu::new(&gpu.device, &gpu.queue, scenario));
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

    // On a GPU the PNGs are written beside the next variant's work (a CPU adapter renders on
    // the cores that would encode them).
    if gpu.info.device_type != "cpu" {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        images::defer_writes((cores / 4).clamp(1, 4));
    }
    let needs_reference = scenario.needs_reference();
    // Where the metrics run: `metrics_device` (the scenario's, `--metrics-device`), else by
    // adapter. With the GPU's, frames stay on the device when they fit its buffers.
    let backend = crate::metrics_device::chosen(scenario, gpu);
    let on_gpu = backend == Backend::Gpu
        && gpu
            .metrics()
            .frame_fits(
                scenario.width,
                scenario.height,
                reference::keep_hdr(scenario),
            )
            .is_ok();
    let native_is_reference =
        |v: &Variant| techniques::is_reference(v) && scenario.reference == Reference::Native;
    // The reference renders first; when it is the native variant itself, that render is reused.
    let mut reference: Option<Result<ReferenceFrames, String>> = None;
    if scenario.needs_separate_reference() {
        reference = Some(phases::time("reference", || {
            reference::render(gpu, &mut scene, scenario, on_gpu, on_frame)
        }));
    }
    // The reference's own noise on the first compared frame (the converged reference only).
    let reference_noise = phases::time("reference noise", || {
        super::reference_noise::measure(gpu, &mut scene, scenario, on_frame)
    });
    // The renderer's exact motion for `tde`, rendered once, outside any timed work.
    let motion: Result<Vec<Option<motion::MotionField>>, String> =
        if needs_reference && scenario.metrics.contains(&MetricKind::Tde) {
            phases::time("motion", || motion::capture(gpu, &mut scene, scenario))
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
    let gpu_evaluator = GpuEvaluator { gpu };
    let evaluator: &dyn Evaluator = match backend {
        Backend::Gpu => &gpu_evaluator,
        Backend::Cpu => &CpuMetrics,
    };
    // Frames beyond `frames.save` that some variant saved as its worst: the reference's too.
    let mut worst_frames: Vec<u32> = Vec::new();
    // The reference's worst frames read back from the device (GPU metrics).
    let mut worst_reference: Vec<(u32, Rgb8Image)> = Vec::new();
    for variant in order {
        let is_reference = needs_reference && native_is_reference(variant) && reference.is_none();
        let keep = reference::keep(scenario, on_gpu, is_reference);
        let mut result = empty_result(variant, Status::Ok);
        let outcome = render_variant(gpu, &mut scene, scenario, variant, keep, sensors, on_frame);
        let mut rendered = match outcome {
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
        result.frame_digests = std::mem::take(&mut rendered.digests);
        frames::append_hashes(&scenario.name, &variant.name, &rendered.hashes);
        phases::time("images", || {
            images::save_frames(&mut result, &rendered.saved, &image_dir, run_dir, "output")
        });
        // The native reference's frames become the reference (moved, not copied); its metrics are
        // then computed against itself, the sanity values every other variant is read against.
        let own: Option<ReferenceFrames> = if is_reference {
            reference = Some(Ok(ReferenceFrames::take(&mut rendered)));
            None
        } else {
            Some(ReferenceFrames::take(&mut rendered))
        };
        // Per measured frame, the MSE against the reference (the GPU's, when it computed them),
        // for the stability checks.
        let mut reference_mse: Option<Vec<f64>> = None;
        if needs_reference {
            match reference.as_ref() {
                Some(Ok(r)) => {
                    result.reference = Some(scenario.reference.name().to_string());
                    let test = own.as_ref().unwrap_or(r);
                    let inputs = metrics::MetricInputs {
                        reference: r,
                        test: &test.frames,
                        test_hdr: &test.hdr,
                        test_gpu: &test.gpu,
                        test_non_finite: &test.non_finite,
                        motion: &motion,
                    };
                    let evaluation =
                        phases::time("metrics", || evaluator.evaluate(scenario, &inputs));
                    let _span = phases::span("images");
                    images::save_cvvdp_maps(&mut result, &evaluation.maps, &image_dir, run_dir);
                    result.metrics = evaluation.metrics;
                    reference_mse = evaluation.mse_rgb;
                    if let Some(error) = evaluation.error {
                        result.status = Status::Failed { error };
                    }
                    // The reference against itself has no error to show.
                    if let (true, Some(maps)) = (own.is_some(), &evaluation.error_maps) {
                        images::save_heatmaps(&mut result, maps, &image_dir, run_dir);
                    } else if own.is_some() {
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
                    // With GPU metrics the frames stayed on the device: the worst are read back.
                    let own_frames = own.as_ref().map(|o| &o.frames).filter(|f| !f.is_empty());
                    let own_gpu = own.as_ref().map(|o| &o.gpu).filter(|f| !f.is_empty());
                    if let (true, None, Some(own_gpu)) = (scenario.save_worst, own_frames, own_gpu)
                    {
                        let worst = images::worst_frames(&result.metrics, &scenario.save_frames);
                        let mut backend = gpu.metrics();
                        let refs = phases::time("images", || {
                            images::save_worst_from_device(
                                &mut result,
                                &mut backend,
                                own_gpu,
                                &r.gpu,
                                &worst,
                                &image_dir,
                                run_dir,
                            )
                        });
                        for (f, img) in refs {
                            if !worst_reference.iter().any(|(g, _)| *g == f) {
                                worst_reference.push((f, img));
                            }
                        }
                    }
                    if let (true, Some(own_frames)) = (scenario.save_worst, own_frames) {
                        let worst = images::worst_frames(&result.metrics, &scenario.save_frames);
                        let images: Vec<(u32, Rgb8Image)> = worst
                            .iter()
                            .filter_map(|&f| own_frames.get(f as usize).map(|i| (f, i.clone())))
                            .collect();
                        images::save_frames(&mut result, &images, &image_dir, run_dir, "output");
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
        phases::time("images", || {
            images::save_extras(
                &mut result,
                &rendered.extras,
                &scenario.save_frames,
                &image_dir,
                run_dir,
            )
        });
        let _span = phases::span("stability");
        // The native reference's own frames and masks are the reference's.
        let reference_ok = match reference.as_ref() {
            Some(Ok(r)) if needs_reference => Some(r),
            _ => None,
        };
        let own_frames = own.as_ref().or(reference_ok);
        let own_view = stability::Frames {
            frames: own_frames.map_or(&[][..], |f| f.frames.as_slice()),
            masks: own_frames.map_or(&[][..], |f| f.masks.as_slice()),
        };
        let reference_view = reference_ok.map(|r| stability::Frames {
            frames: &r.frames,
            masks: &r.masks,
        });
        result.stability = Some(stability::check(
            scenario,
            own_view,
            rendered.deterministic,
            reference_view,
            reference_mse.as_deref(),
        ));
        results.push(result);
    }
    // Reference images once per scenario, next to the variants'.
    if let Some(Ok(r)) = &reference {
        if let Some(first) = results
            .iter_mut()
            .find(|r| r.status == Status::Ok && !techniques::is_reference_name(&r.technique))
        {
            // The frames `frames.save` names, then each worst frame some variant saved (read
            // back from the device with GPU metrics).
            worst_frames.sort_unstable();
            worst_frames.dedup();
            let mut worst: Vec<(u32, Rgb8Image)> = worst_frames
                .iter()
                .filter(|f| !r.saved.iter().any(|(i, _)| i == *f))
                .filter_map(|&f| r.frames.get(f as usize).map(|img| (f, img.clone())))
                .collect();
            for (f, img) in std::mem::take(&mut worst_reference) {
                let known = worst.iter().chain(&r.saved).any(|(g, _)| *g == f);
                if !known {
                    worst.push((f, img));
                }
            }
            worst.sort_by_key(|(f, _)| *f);
            phases::time("images", || {
                images::save_frames(first, &r.saved, &image_dir, run_dir, "reference");
                images::save_frames(first, &worst, &image_dir, run_dir, "reference");
            });
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
    let failed = phases::time("images", images::finish_writes);
    images::forget_failed(&mut results, &failed, run_dir);
    gates::apply(scenario, &mut results);
    let mut record = finish(scenario, run_id, results, start);
    // The separately rendered reference's digests (a native reference's are its variant's).
    if scenario.needs_separate_reference() {
        if let Some(Ok(r)) = &reference {
            record.reference_digests = r.digests.clone();
        }
    }
    record.reference_noise = reference_noise;
    record
}

type VariantOutcome = Result<Result<(Rendered, PlanRecord), Unsupported>, String>;

/// Builds and renders a variant inside a GPU error scope. Outer error: the GPU failed.
fn render_variant(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    scenario: &Scenario,
    variant: &Variant,
    keep: Keep,
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
    let built = phases::time("build", || {
        techniques::build(variant, &BuildContext::new(gpu, scene, target))
    });
    let result = match built {
        Err(u) => Ok(Err(u)),
        Ok(mut t) => {
            let plan = plan_record(t.as_ref());
            let sampler = sensors.sampler();
            match frames::render_sampled(gpu, scene, scenario, t.as_mut(), keep, sampler, on_frame)
            {
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
