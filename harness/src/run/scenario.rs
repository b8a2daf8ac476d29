//! Runs one scenario on an open device: its plan first, then the reference, then every variant
//! (render, evaluate, save), then gates, into a [`ScenarioResult`]. Orchestration only: what to
//! keep and where to compute is `plan.rs`, rendering `frames.rs`, the reference `reference.rs`,
//! metrics `evaluate.rs`, images `images.rs`, records `record.rs`.
//!
//! A variant that needs what the adapter lacks is `skipped` with the reason; a GPU error fails that
//! variant and the scenario goes on. Metrics are computed only after a variant's frames are all
//! rendered, never while timed GPU work is in flight.

use std::path::{Path, PathBuf};
use std::time::Instant;

use tessera_metrics::Rgb8Image;
use tessera_results::{ScenarioResult, Status, VariantResult};

use super::captured::MetricInputs;
use super::evaluate::{self, Evaluation};
use super::frames;
use super::motion::{self, MotionField};
use super::plan::Plan;
use super::record::{empty_result, fill_conditions, fill_timings, finish, plan_record, PlanRecord};
use super::reference::{self, ReferenceFrames};
use super::rendered::{self, Rendered};
use super::sequence::in_error_scope;
use super::{gates, images, phases, stability};
use crate::conditions::Sensors;
use crate::gpu::Gpu;
use crate::render::renderer::Unsupported;
use crate::render::scene::SceneGpu;
use crate::techniques::{self, BuildContext, Target, Variant};

/// Runs `scenario`. Images go under `run_dir/images/<scenario>/`. `on_frame` ticks progress.
pub fn run(
    gpu: &Gpu,
    scenario: &crate::scenario::Scenario,
    run_id: &str,
    run_dir: &Path,
    sensors: &Sensors,
    on_frame: &mut dyn FnMut(),
) -> ScenarioResult {
    let start = Instant::now();
    super::memory::reset_peak();
    let scene = phases::time("scene", || SceneGpu::new(&gpu.device, &gpu.queue, scenario));
    let mut scene = match scene {
        Ok(s) => s,
        Err(e) => {
            let error = e.to_string();
            let failed = |v| {
                let error = error.clone();
                empty_result(v, Status::Failed { error })
            };
            let results = scenario.variants.iter().map(failed).collect();
            return finish(scenario, run_id, results, start);
        }
    };
    // On a GPU the PNGs are written beside the next variant's work (a CPU adapter renders on
    // the cores that would encode them).
    if gpu.info.device_type != "cpu" {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        images::defer_writes((cores / 4).clamp(1, 4));
    }
    let plan = Plan::new(gpu, scenario);
    let mut run = ScenarioRun::new(gpu, &plan, run_dir, sensors);
    // The reference renders first; when it is the native variant itself, that render is reused.
    if plan.separate_reference {
        run.reference = Some(phases::time("reference", || {
            reference::render(gpu, &mut scene, &plan, on_frame)
        }));
    }
    // The reference's own noise on the first compared frame (the converged reference only).
    let reference_noise = phases::time("reference noise", || {
        super::reference_noise::measure(gpu, &mut scene, scenario, on_frame)
    });
    // The renderer's exact motion for `tde`, rendered once, outside any timed work.
    if plan.motion {
        run.motion = phases::time("motion", || motion::capture(gpu, &mut scene, scenario));
    }
    let mut results: Vec<VariantResult> = plan
        .order
        .iter()
        .map(|variant| run.variant(&mut scene, variant, on_frame))
        .collect();
    run.save_reference_images(&mut results);
    // Put results back in the scenario's declaration order.
    results.sort_by_key(|r| scenario.declared_position(&r.variant));
    let failed = phases::time("images", images::finish_writes);
    images::forget_failed(&mut results, &failed, run_dir);
    gates::apply(scenario, &mut results);
    let mut record = finish(scenario, run_id, results, start);
    // The separately rendered reference's digests (a native reference's are its variant's).
    if let (true, Some(Ok(r))) = (plan.separate_reference, &run.reference) {
        record.reference_digests = r.digests.clone();
    }
    record.reference_noise = reference_noise;
    record
}

/// A scenario's run in progress: the reference every variant is read against, the motion
/// `tde` reads, and the reference's frames some variant saved as its worst.
struct ScenarioRun<'a> {
    gpu: &'a Gpu,
    plan: &'a Plan<'a>,
    run_dir: &'a Path,
    image_dir: PathBuf,
    sensors: &'a Sensors,
    /// The separate reference, or the native variant's frames once it rendered.
    reference: Option<Result<ReferenceFrames, String>>,
    motion: Result<Vec<Option<MotionField>>, String>,
    worst: WorstFrames,
}

/// Frames beyond `frames.save` that some variant saved as its worst: the reference's frames of
/// them are saved once per scenario.
#[derive(Default)]
struct WorstFrames {
    frames: Vec<u32>,
    /// The reference's worst frames read back from the device (GPU metrics).
    reference: Vec<(u32, Rgb8Image)>,
}

impl<'a> ScenarioRun<'a> {
    fn new(gpu: &'a Gpu, plan: &'a Plan<'a>, run_dir: &'a Path, sensors: &'a Sensors) -> Self {
        ScenarioRun {
            gpu,
            plan,
            run_dir,
            image_dir: run_dir.join("images").join(&plan.scenario.name),
            sensors,
            reference: None,
            motion: Ok(Vec::new()),
            worst: WorstFrames::default(),
        }
    }

    /// Renders, evaluates and saves one variant.
    fn variant(
        &mut self,
        scene: &mut SceneGpu,
        variant: &Variant,
        on_frame: &mut dyn FnMut(),
    ) -> VariantResult {
        let plan = self.plan;
        let is_reference =
            plan.needs_reference && plan.is_native_reference(variant) && self.reference.is_none();
        let keep = plan.keep(is_reference);
        let mut result = empty_result(variant, Status::Ok);
        let outcome = render_variant(self.gpu, scene, plan, variant, keep, self.sensors, on_frame);
        let mut rendered = match outcome {
            Ok(Ok((r, plan_record))) => {
                fill_timings(&mut result, &r, plan_record);
                fill_conditions(&mut result, &r, plan.scenario, variant, self.sensors);
                r
            }
            Ok(Err(Unsupported(reason))) => {
                result.status = Status::Skipped { reason };
                return result;
            }
            Err(error) => {
                result.status = Status::Failed { error };
                if is_reference {
                    let error = format!("the native reference failed: {}", variant.name);
                    self.reference = Some(Err(error));
                }
                return result;
            }
        };
        result.non_finite_values = rendered.non_finite;
        result.frame_digests = std::mem::take(&mut rendered.digests);
        rendered::append_hashes(&plan.scenario.name, &variant.name, &rendered.hashes);
        phases::time("images", || {
            images::save_frames(
                &mut result,
                &rendered.saved,
                &self.image_dir,
                self.run_dir,
                "output",
            )
        });
        // The native reference's frames become the reference (moved, not copied); its metrics are
        // then computed against itself, the sanity values every other variant is read against.
        let own: Option<ReferenceFrames> = if is_reference {
            self.reference = Some(Ok(ReferenceFrames::take(&mut rendered)));
            None
        } else {
            Some(ReferenceFrames::take(&mut rendered))
        };
        let reference_mse = self.evaluate(&mut result, own.as_ref());
        result
            .metrics
            .extend(super::metrics::extra_values(&rendered.extras));
        phases::time("images", || {
            images::save_extras(
                &mut result,
                &rendered.extras,
                &plan.scenario.save_frames,
                &self.image_dir,
                self.run_dir,
            )
        });
        let _span = phases::span("stability");
        result.stability = Some(self.stability(own.as_ref(), &rendered, reference_mse));
        result
    }

    /// The variant's metrics against the reference (its own frames `own`, or the reference's
    /// when it is the native reference), with their images; per measured frame, the MSE against
    /// the reference when the GPU computed it (for the stability checks).
    fn evaluate(
        &mut self,
        result: &mut VariantResult,
        own: Option<&ReferenceFrames>,
    ) -> Option<Vec<f64>> {
        let plan = self.plan;
        if !plan.needs_reference {
            return None;
        }
        let r = match self.reference.as_ref()? {
            Ok(r) => r,
            Err(e) => {
                result.status = Status::Failed { error: e.clone() };
                return None;
            }
        };
        result.reference = Some(plan.scenario.reference.name().to_string());
        let test = own.unwrap_or(r);
        let inputs = MetricInputs {
            reference: r,
            test: &test.frames,
            test_hdr: &test.hdr,
            test_gpu: &test.gpu,
            test_non_finite: &test.non_finite,
            motion: &self.motion,
        };
        let evaluation: Evaluation =
            phases::time("metrics", || evaluate::evaluate(self.gpu, plan, &inputs));
        let _span = phases::span("images");
        let (dir, run_dir) = (&self.image_dir, self.run_dir);
        images::save_cvvdp_maps(result, &evaluation.maps, dir, run_dir);
        result.metrics = evaluation.metrics;
        if let Some(error) = evaluation.error {
            result.status = Status::Failed { error };
        }
        // The reference against itself has no error to show.
        if let (true, Some(maps)) = (own.is_some(), &evaluation.error_maps) {
            images::save_heatmaps(result, maps, dir, run_dir);
        } else if own.is_some() {
            let saved = &plan.scenario.save_frames;
            images::save_error_maps(result, &inputs, saved, plan.keep_hdr, dir, run_dir);
        }
        if plan.scenario.save_worst {
            let mut worst = std::mem::take(&mut self.worst);
            self.save_worst(&mut worst, result, own, &inputs);
            self.worst = worst;
        }
        evaluation.mse_rgb
    }

    /// Each metric's worst frame beside the saved ones (`frames.save_worst`): the output, its
    /// error maps (on the CPU: a back end maps only `frames.save`) and, once per scenario, the
    /// reference's frame. With GPU metrics the frames stayed on the device: the worst are read
    /// back.
    fn save_worst(
        &self,
        saved: &mut WorstFrames,
        result: &mut VariantResult,
        own: Option<&ReferenceFrames>,
        inputs: &MetricInputs<'_>,
    ) {
        let (dir, run_dir) = (&self.image_dir, self.run_dir);
        let worst = images::worst_frames(&result.metrics, &self.plan.scenario.save_frames);
        let own_frames = own.map(|o| &o.frames).filter(|f| !f.is_empty());
        let own_gpu = own.map(|o| &o.gpu).filter(|f| !f.is_empty());
        if let (None, Some(own_gpu)) = (own_frames, own_gpu) {
            let mut backend = self.gpu.metrics();
            let reference = &inputs.reference.gpu;
            let refs = phases::time("images: worst from device", || {
                images::save_worst_from_device(
                    result,
                    &mut backend,
                    own_gpu,
                    reference,
                    &worst,
                    dir,
                    run_dir,
                )
            });
            for (f, img) in refs {
                if !saved.reference.iter().any(|(g, _)| *g == f) {
                    saved.reference.push((f, img));
                }
            }
        }
        if let Some(own_frames) = own_frames {
            let images: Vec<(u32, Rgb8Image)> = worst
                .iter()
                .filter_map(|&f| own_frames.get(f as usize).map(|i| (f, i.clone())))
                .collect();
            images::save_frames(result, &images, dir, run_dir, "output");
            let hdr = self.plan.keep_hdr;
            images::save_error_maps(result, inputs, &worst, hdr, dir, run_dir);
            saved.frames.extend(worst);
        }
    }

    /// The stability checks of a rendered variant; the native reference's own frames and masks
    /// are the reference's.
    fn stability(
        &self,
        own: Option<&ReferenceFrames>,
        rendered: &Rendered,
        reference_mse: Option<Vec<f64>>,
    ) -> tessera_results::Stability {
        let reference_ok = match self.reference.as_ref() {
            Some(Ok(r)) if self.plan.needs_reference => Some(r),
            _ => None,
        };
        let own_frames = own.or(reference_ok);
        let own_view = stability::Frames {
            frames: own_frames.map_or(&[][..], |f| f.frames.as_slice()),
            masks: own_frames.map_or(&[][..], |f| f.masks.as_slice()),
        };
        let reference_view = reference_ok.map(|r| stability::Frames {
            frames: &r.frames,
            masks: &r.masks,
        });
        stability::check(
            self.plan,
            own_view,
            rendered.deterministic,
            reference_view,
            reference_mse.as_deref(),
        )
    }

    /// Reference images once per scenario, next to the first compared variant's: the frames
    /// `frames.save` names, then each worst frame some variant saved (read back from the device
    /// with GPU metrics).
    fn save_reference_images(&mut self, results: &mut [VariantResult]) {
        let Some(Ok(r)) = &self.reference else {
            return;
        };
        let Some(first) = results
            .iter_mut()
            .find(|r| r.status == Status::Ok && !techniques::is_reference_name(&r.technique))
        else {
            return;
        };
        let mut frames = std::mem::take(&mut self.worst.frames);
        frames.sort_unstable();
        frames.dedup();
        let mut worst: Vec<(u32, Rgb8Image)> = frames
            .iter()
            .filter(|f| !r.saved.iter().any(|(i, _)| i == *f))
            .filter_map(|&f| r.frames.get(f as usize).map(|img| (f, img.clone())))
            .collect();
        for (f, img) in std::mem::take(&mut self.worst.reference) {
            let known = worst.iter().chain(&r.saved).any(|(g, _)| *g == f);
            if !known {
                worst.push((f, img));
            }
        }
        worst.sort_by_key(|(f, _)| *f);
        let (dir, run_dir) = (&self.image_dir, self.run_dir);
        phases::time("images", || {
            images::save_frames(first, &r.saved, dir, run_dir, "reference");
            images::save_frames(first, &worst, dir, run_dir, "reference");
        });
    }
}

type VariantOutcome = Result<Result<(Rendered, PlanRecord), Unsupported>, String>;

/// Builds and renders a variant inside a GPU error scope. Outer error: the GPU failed.
fn render_variant(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    plan: &Plan<'_>,
    variant: &Variant,
    keep: rendered::Keep,
    sensors: &Sensors,
    on_frame: &mut dyn FnMut(),
) -> VariantOutcome {
    let scenario = plan.scenario;
    let outcome = in_error_scope(gpu, || {
        let target = Target::new(
            scenario.width,
            scenario.height,
            scenario.scene.has_dynamic_objects(),
        );
        let built = phases::time("build", || {
            techniques::build(variant, &BuildContext::new(gpu, scene, target))
        });
        let mut t = match built {
            Err(u) => return Ok(Err(u)),
            Ok(t) => t,
        };
        let record = plan_record(t.as_ref());
        let sampler = sensors.sampler();
        match frames::render_sampled(gpu, scene, scenario, t.as_mut(), keep, sampler, on_frame) {
            Ok(r) => Ok(Ok((r, record))),
            Err(e) => Err(e.to_string()),
        }
    });
    outcome.and_then(|r| r)
}
