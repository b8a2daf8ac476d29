//! Runs one scenario on an open device: the reference first, then every variant, then metrics and
//! gates, into a [`ScenarioResult`].
//!
//! A variant that needs what the adapter lacks is `skipped` with the reason; a GPU error fails that
//! variant and the scenario goes on. Metrics are computed only after a variant's frames are all
//! rendered, never while timed GPU work is in flight.

use std::path::Path;
use std::time::Instant;

use tessera_metrics::{DistortionMap, ExposureRange, HdrImage, Rgb8Image};
use tessera_results::{
    ImageRecord, MetricRecord, PassRecord, ScenarioResult, Status, Summary, VariantResult,
};

use super::frames::{self, Rendered};
use super::gates;
use super::motion;
use super::stability;
use crate::gpu::Gpu;
use crate::params::Variant;
use crate::render::renderer::{Renderer, Unsupported};
use crate::render::scene::SceneGpu;
use crate::scenario::{MetricKind, Reference, Scenario};
use crate::techniques::{self, native, Target};

/// Frames a reference render produced, in measured-frame order.
struct ReferenceFrames {
    frames: Vec<Rgb8Image>,
    /// Linear frames and their HDR-FLIP exposure ranges, when `flip-hdr` is asked for: the range
    /// of each reference frame is held fixed for every variant diffed against it.
    hdr: Vec<HdrImage>,
    exposures: Vec<ExposureRange>,
    /// Non-finite pixels per frame (what the scene injected, as the reference renders it).
    masks: Vec<Option<Vec<u64>>>,
}

/// Runs `scenario`. Images go under `run_dir/images/<scenario>/`. `on_frame` ticks progress.
pub fn run(
    gpu: &Gpu,
    scenario: &Scenario,
    run_id: &str,
    run_dir: &Path,
    on_frame: &mut dyn FnMut(),
) -> ScenarioResult {
    let start = Instant::now();
    let mut results: Vec<VariantResult> = Vec::new();
    let scene = SceneGpu::new(&gpu.device, scenario);
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
        |v: &Variant| v.technique.name() == native::NAME && scenario.reference == Reference::Native;
    // The reference renders first; when it is the native variant itself, that render is reused.
    let mut reference: Option<Result<ReferenceFrames, String>> = None;
    if scenario.needs_separate_reference() {
        reference = Some(render_reference(gpu, &mut scene, scenario, on_frame));
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
    for variant in order {
        let is_reference = needs_reference && native_is_reference(variant) && reference.is_none();
        let keep = needs_reference || !scenario.save_frames.is_empty();
        let mut result = empty_result(variant, Status::Ok);
        let outcome = render_variant(gpu, &mut scene, scenario, variant, keep, on_frame);
        let rendered = match outcome {
            Ok(Ok((r, plan_record))) => {
                fill_timings(&mut result, &r, plan_record);
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
        append_hashes(&scenario.name, &variant.name, &rendered.hashes);
        save_images(
            &mut result,
            &rendered.frames,
            scenario,
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
                    let inputs = MetricInputs {
                        reference: r,
                        test: frames.as_deref().unwrap_or(&r.frames),
                        test_hdr: hdr.as_deref().unwrap_or(&r.hdr),
                        motion: &motion,
                    };
                    match compute_metrics(scenario, &inputs) {
                        Ok((m, maps)) => {
                            result.metrics = m;
                            save_cvvdp_maps(&mut result, &maps, &image_dir, run_dir);
                        }
                        Err(e) => {
                            result.status = Status::Failed {
                                error: format!("metrics: {e}"),
                            }
                        }
                    }
                    // The reference against itself has no error to show.
                    if frames.is_some() {
                        save_error_maps(&mut result, &inputs, scenario, &image_dir, run_dir);
                    }
                }
                Some(Err(e)) => result.status = Status::Failed { error: e.clone() },
                None => {}
            }
        }
        add_extras(&mut result, &rendered.extras, scenario, &image_dir, run_dir);
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
            save_images(first, &r.frames, scenario, &image_dir, run_dir, "reference");
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

fn finish(
    scenario: &Scenario,
    run_id: &str,
    results: Vec<VariantResult>,
    start: Instant,
) -> ScenarioResult {
    ScenarioResult {
        schema_version: tessera_results::SCHEMA_VERSION,
        run_id: run_id.to_string(),
        scenario: scenario.name.clone(),
        file: scenario.file.display().to_string(),
        width: scenario.width,
        height: scenario.height,
        warmup_frames: scenario.warmup_frames,
        measured_frames: scenario.measured_frames,
        time_step: scenario.time_step,
        reference: scenario.reference.name().to_string(),
        results,
        wall_ms: start.elapsed().as_secs_f64() * 1000.0,
    }
}

fn empty_result(v: &Variant, status: Status) -> VariantResult {
    VariantResult {
        variant: v.name.clone(),
        technique: v.technique.name().to_string(),
        params: v
            .params
            .iter()
            .map(|(k, p)| (k.clone(), p.to_json()))
            .collect(),
        status,
        reference: None,
        passes: Vec::new(),
        culled_passes: Vec::new(),
        gpu_frame_ms: None,
        cpu_frame_ms: Summary {
            count: 0,
            median: 0.0,
            p5: 0.0,
            p95: 0.0,
            min: 0.0,
            max: 0.0,
            mean: 0.0,
        },
        resources: Vec::new(),
        allocated_bytes: 0,
        metrics: Vec::new(),
        non_finite_values: 0,
        stability: None,
        images: Vec::new(),
        gates: Vec::new(),
    }
}

/// What the plan of a rendered variant looked like.
struct PlanRecord {
    passes: Vec<(String, String, Vec<String>, Vec<String>)>,
    culled: Vec<String>,
    resources: Vec<tessera_results::ResourceRecord>,
}

type VariantOutcome = Result<Result<(Rendered, PlanRecord), Unsupported>, String>;

/// Builds and renders a variant inside a GPU error scope. Outer error: the GPU failed.
fn render_variant(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    scenario: &Scenario,
    variant: &Variant,
    keep: bool,
    on_frame: &mut dyn FnMut(),
) -> VariantOutcome {
    let validation = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let oom = gpu.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let built = techniques::build(
        gpu,
        variant,
        Target {
            width: scenario.width,
            height: scenario.height,
            dynamic_scene: scenario.scene.has_dynamic_objects(),
        },
    );
    let result = match built {
        Err(u) => Ok(Err(u)),
        Ok(mut t) => {
            let plan = plan_record(t.as_ref());
            let hdr = keep && keep_hdr(scenario);
            match frames::render(gpu, scene, scenario, t.as_mut(), keep, hdr, on_frame) {
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

fn first_line(s: &str) -> String {
    s.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .take(3)
        .collect::<Vec<_>>()
        .join(" ")
}

fn plan_record(t: &dyn Renderer) -> PlanRecord {
    let plan = t.plan();
    PlanRecord {
        passes: plan
            .passes
            .iter()
            .map(|p| {
                (
                    p.name.to_string(),
                    p.kind.name().to_string(),
                    p.reads.iter().map(|s| s.to_string()).collect(),
                    p.writes.iter().map(|s| s.to_string()).collect(),
                )
            })
            .collect(),
        culled: plan.culled.iter().map(|s| s.to_string()).collect(),
        resources: plan.records(),
    }
}

fn render_reference(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    scenario: &Scenario,
    on_frame: &mut dyn FnMut(),
) -> Result<ReferenceFrames, String> {
    let validation = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let built: Result<Box<dyn Renderer>, Unsupported> = match scenario.reference {
        Reference::GroundTruth { supersample } => {
            native::ground_truth(gpu, scenario.width, scenario.height, supersample)
        }
        _ => techniques::build(
            gpu,
            &Variant::with_defaults(&native::Native),
            Target {
                width: scenario.width,
                height: scenario.height,
                dynamic_scene: false,
            },
        ),
    };
    let result = match built {
        Err(Unsupported(reason)) => Err(format!("no reference: {reason}")),
        Ok(mut t) => frames::render(
            gpu,
            scene,
            scenario,
            t.as_mut(),
            true,
            keep_hdr(scenario),
            on_frame,
        )
        .map(|r| {
            append_hashes(&scenario.name, "(reference)", &r.hashes);
            ReferenceFrames::new(r.frames, r.hdr_frames, r.non_finite_masks)
        })
        .map_err(|e| format!("reference render failed: {e}")),
    };
    if let Some(e) = pollster::block_on(validation.pop()) {
        return Err(format!(
            "reference render failed: GPU error: {}",
            first_line(&e.to_string())
        ));
    }
    result
}

fn fill_timings(result: &mut VariantResult, r: &Rendered, plan: PlanRecord) {
    for (name, kind, reads, writes) in plan.passes {
        let samples: Vec<f64> = if r.timestamps {
            r.measurements
                .iter()
                .filter_map(|m| m.gpu_ms.get(&name).copied())
                .collect()
        } else {
            Vec::new()
        };
        let mut invocations: Vec<f64> = r
            .measurements
            .iter()
            .filter_map(|m| m.fragment_invocations.get(&name).map(|c| *c as f64))
            .collect();
        invocations.sort_by(|a, b| a.total_cmp(b));
        result.passes.push(PassRecord {
            name,
            kind,
            reads,
            writes,
            gpu_ms: Summary::of(&samples),
            samples_ms: samples,
            fragment_invocations: (!invocations.is_empty())
                .then(|| invocations[invocations.len() / 2] as u64),
        });
    }
    if r.timestamps {
        let per_frame: Vec<f64> = r
            .measurements
            .iter()
            .map(|m| m.gpu_ms.values().sum())
            .collect();
        result.gpu_frame_ms = Summary::of(&per_frame);
    }
    if let Some(s) = Summary::of(&r.cpu_ms) {
        result.cpu_frame_ms = s;
    }
    result.culled_passes = plan.culled;
    result.allocated_bytes = plan.resources.iter().map(|r| r.bytes).sum();
    result.resources = plan.resources;
}

impl ReferenceFrames {
    fn new(frames: Vec<Rgb8Image>, hdr: Vec<HdrImage>, masks: Vec<Option<Vec<u64>>>) -> Self {
        let exposures = hdr
            .iter()
            .map(tessera_metrics::hdr_exposure_range)
            .collect();
        ReferenceFrames {
            frames,
            hdr,
            exposures,
            masks,
        }
    }
}

/// Linear frames are kept only for HDR-FLIP, and for `cvvdp` on an HDR display.
fn keep_hdr(scenario: &Scenario) -> bool {
    scenario.metrics.contains(&MetricKind::FlipHdr)
        || (scenario.metrics.contains(&MetricKind::Cvvdp) && super::cvvdp::uses_linear(scenario))
}

/// What a variant's metrics are computed from.
struct MetricInputs<'a> {
    reference: &'a ReferenceFrames,
    test: &'a [Rgb8Image],
    test_hdr: &'a [HdrImage],
    motion: &'a Result<Vec<Option<motion::MotionField>>, String>,
}

#[derive(Debug, thiserror::Error)]
enum MetricError {
    #[error("{0}")]
    Metric(#[from] tessera_metrics::MetricsError),
    #[error("no motion for tde: {0}")]
    Motion(String),
}

/// Metrics of every measured frame against the reference's frame of the same index, and the
/// `cvvdp` maps of saved frames.
fn compute_metrics(
    scenario: &Scenario,
    inputs: &MetricInputs<'_>,
) -> Result<(Vec<MetricRecord>, Vec<DistortionMap>), MetricError> {
    let (reference, test) = (&inputs.reference.frames[..], inputs.test);
    let frames: Vec<u32> = (0..test.len().min(reference.len()) as u32).collect();
    let mut out = Vec::new();
    let mut maps = Vec::new();
    for &kind in &scenario.metrics {
        if kind == MetricKind::Cvvdp {
            let (records, m) = super::cvvdp::records(
                scenario,
                (reference, &inputs.reference.hdr),
                (test, inputs.test_hdr),
            )?;
            out.extend(records);
            maps = m;
            continue;
        }
        if kind == MetricKind::Flicker {
            out.push(flicker(test));
            continue;
        }
        if kind == MetricKind::Tde {
            let motion = inputs
                .motion
                .as_ref()
                .map_err(|e| MetricError::Motion(e.clone()))?;
            out.push(tde(reference, test, motion)?);
            continue;
        }
        let mut per_frame = Vec::new();
        for &f in &frames {
            let (r, t) = (&reference[f as usize], &test[f as usize]);
            let v = match kind {
                MetricKind::Psnr => tessera_metrics::mse_rgb(r, t)?,
                MetricKind::PsnrLuma => tessera_metrics::mse_luma(r, t)?,
                MetricKind::MaxAbsError => tessera_metrics::max_abs_error(r, t)? as f64,
                MetricKind::Ssim => tessera_metrics::ssim_rgb(r, t)?,
                MetricKind::SsimLuma => tessera_metrics::ssim_luma(r, t)?,
                MetricKind::Flip => {
                    tessera_metrics::flip_ldr(r, t, tessera_metrics::DEFAULT_PIXELS_PER_DEGREE)?
                        .mean
                }
                MetricKind::FlipHdr => {
                    let i = f as usize;
                    let rh = &inputs.reference.hdr[i];
                    tessera_metrics::flip_hdr(
                        rh,
                        &inputs.test_hdr[i],
                        &inputs.reference.exposures[i],
                        tessera_metrics::DEFAULT_PIXELS_PER_DEGREE,
                    )?
                    .mean
                }
                MetricKind::Flicker | MetricKind::Tde | MetricKind::Cvvdp => {
                    unreachable!("computed above")
                }
            };
            per_frame.push(v);
        }
        // PSNR is aggregated from the mean MSE (the PSNR of the sequence), per frame from each MSE.
        let (per_frame, value) = match kind {
            MetricKind::Psnr | MetricKind::PsnrLuma => {
                let mean_mse = per_frame.iter().sum::<f64>() / per_frame.len().max(1) as f64;
                let psnr: Vec<f64> = per_frame
                    .iter()
                    .map(|m| tessera_metrics::psnr_from_mse(*m, 255.0))
                    .collect();
                (psnr, tessera_metrics::psnr_from_mse(mean_mse, 255.0))
            }
            MetricKind::MaxAbsError => {
                let max = per_frame.iter().copied().fold(0.0, f64::max);
                (per_frame, max)
            }
            _ => {
                let mean = per_frame.iter().sum::<f64>() / per_frame.len().max(1) as f64;
                (per_frame, mean)
            }
        };
        out.push(MetricRecord {
            name: kind.name().to_string(),
            series: series(&per_frame),
            per_frame,
            frames: frames.clone(),
            value,
            higher_is_better: kind.higher_is_better(),
        });
    }
    Ok((out, maps))
}

pub(super) fn series(per_frame: &[f64]) -> Option<tessera_results::SeriesSummary> {
    tessera_metrics::series_stats(per_frame).map(|s| tessera_results::SeriesSummary {
        mean: s.mean,
        p95: s.p95,
        max: s.max,
        std_dev: s.std_dev,
    })
}

/// Temporal difference error (notes/metrics.md 3.3, item 1) per measured frame that has motion
/// from a previous measured frame in the same shot; the value is the mean over those frames.
fn tde(
    reference: &[Rgb8Image],
    test: &[Rgb8Image],
    motion: &[Option<motion::MotionField>],
) -> Result<MetricRecord, MetricError> {
    let (mut frames, mut per_frame) = (Vec::new(), Vec::new());
    for t in 1..test.len().min(reference.len()) {
        let Some(Some(m)) = motion.get(t) else {
            continue;
        };
        let v = tessera_metrics::temporal_difference_error(
            &test[t - 1],
            &test[t],
            &reference[t - 1],
            &reference[t],
            &m.motion,
            &m.valid,
        )?;
        if let Some(v) = v {
            frames.push(t as u32);
            per_frame.push(v);
        }
    }
    let value = per_frame.iter().sum::<f64>() / per_frame.len().max(1) as f64;
    Ok(MetricRecord {
        name: MetricKind::Tde.name().to_string(),
        series: series(&per_frame),
        frames,
        per_frame,
        value,
        higher_is_better: false,
    })
}

/// Static-scene flicker (notes/metrics.md section 3.3, SSF): per measured frame after the first,
/// the mean absolute difference from the previous frame over pixels and RGB channels, in 8-bit
/// units; the value is the mean over frames. Zero for a converged deterministic technique on a
/// static scene; on moving scenes it measures change, not error.
fn flicker(frames: &[Rgb8Image]) -> MetricRecord {
    let per_frame: Vec<f64> = frames
        .windows(2)
        .map(|w| {
            let sum: u64 = w[0]
                .data
                .iter()
                .zip(&w[1].data)
                .map(|(a, b)| a.abs_diff(*b) as u64)
                .sum();
            sum as f64 / w[1].data.len().max(1) as f64
        })
        .collect();
    let value = per_frame.iter().sum::<f64>() / per_frame.len().max(1) as f64;
    MetricRecord {
        name: MetricKind::Flicker.name().to_string(),
        series: series(&per_frame),
        frames: (1..frames.len() as u32).collect(),
        per_frame,
        value,
        higher_is_better: false,
    }
}

/// A technique's per-frame extras: values become metrics of the variant's own frames (value: the
/// mean), images of saved frames are saved as `<variant>-<kind>-fNNN.png`.
fn add_extras(
    result: &mut VariantResult,
    extras: &[crate::render::renderer::FrameExtras],
    scenario: &Scenario,
    dir: &Path,
    run_dir: &Path,
) {
    let mut names: Vec<&'static str> = Vec::new();
    for e in extras {
        for (name, _) in &e.values {
            if !names.contains(name) {
                names.push(name);
            }
        }
    }
    for name in names {
        let (frames, per_frame): (Vec<u32>, Vec<f64>) = extras
            .iter()
            .enumerate()
            .filter_map(|(f, e)| {
                let v = e.values.iter().find(|(n, _)| *n == name)?.1;
                Some((f as u32, v))
            })
            .unzip();
        let value = per_frame.iter().sum::<f64>() / per_frame.len().max(1) as f64;
        result.metrics.push(MetricRecord {
            name: name.to_string(),
            series: series(&per_frame),
            per_frame,
            frames,
            value,
            higher_is_better: false,
        });
    }
    let stem = sanitize(&result.variant);
    for &f in &scenario.save_frames {
        let Some(e) = extras.get(f as usize) else {
            continue;
        };
        for (kind, img) in &e.images {
            let _ = std::fs::create_dir_all(dir);
            let path = dir.join(format!("{stem}-{kind}-f{f:03}.png"));
            save_image(result, img, &path, run_dir, f, kind);
        }
    }
}

/// The `cvvdp` distortion maps of saved frames, as `<variant>-cvvdp-fNNN.png` (kind `cvvdp`).
fn save_cvvdp_maps(result: &mut VariantResult, maps: &[DistortionMap], dir: &Path, run_dir: &Path) {
    if maps.is_empty() {
        return;
    }
    let _ = std::fs::create_dir_all(dir);
    let stem = sanitize(&result.variant);
    for m in maps {
        let path = dir.join(format!("{stem}-cvvdp-f{:03}.png", m.frame));
        let img = tessera_metrics::cvvdp_heatmap(m);
        save_image(result, &img, &path, run_dir, m.frame as u32, "cvvdp");
    }
}

fn save_images(
    result: &mut VariantResult,
    frames: &[Rgb8Image],
    scenario: &Scenario,
    dir: &Path,
    run_dir: &Path,
    kind: &str,
) {
    if frames.is_empty() {
        return;
    }
    let _ = std::fs::create_dir_all(dir);
    let stem = if kind == "reference" {
        "reference".to_string()
    } else {
        sanitize(&result.variant)
    };
    for &f in &scenario.save_frames {
        let Some(img) = frames.get(f as usize) else {
            continue;
        };
        let path = dir.join(format!("{stem}-f{f:03}.png"));
        save_image(result, img, &path, run_dir, f, kind);
    }
}

/// The per-pixel error maps of each saved frame against the reference, as images of the result:
/// the FLIP map in magma (kind `heatmap`, `<variant>-flip-fNNN.png`, as `tessera diff --heatmap`
/// writes it) always, and the HDR-FLIP map (kind `heatmap-hdr`, `<variant>-flip-hdr-fNNN.png`)
/// when the scenario measures `flip-hdr`. A map that cannot be computed (sizes differ) is left out: the metrics report that.
fn save_error_maps(
    result: &mut VariantResult,
    inputs: &MetricInputs<'_>,
    scenario: &Scenario,
    dir: &Path,
    run_dir: &Path,
) {
    let stem = sanitize(&result.variant);
    let ppd = tessera_metrics::DEFAULT_PIXELS_PER_DEGREE;
    let hdr = keep_hdr(scenario);
    for &f in &scenario.save_frames {
        let i = f as usize;
        let (Some(r), Some(t)) = (inputs.reference.frames.get(i), inputs.test.get(i)) else {
            continue;
        };
        let _ = std::fs::create_dir_all(dir);
        if let Ok(map) = tessera_metrics::flip_ldr(r, t, ppd) {
            let path = dir.join(format!("{stem}-flip-f{f:03}.png"));
            let img = tessera_metrics::flip_heatmap(&map);
            save_image(result, &img, &path, run_dir, f, "heatmap");
        }
        let hdr_pair = (
            inputs.reference.hdr.get(i),
            inputs.test_hdr.get(i),
            inputs.reference.exposures.get(i),
        );
        if let (true, (Some(rh), Some(th), Some(range))) = (hdr, hdr_pair) {
            if let Ok(map) = tessera_metrics::flip_hdr(rh, th, range, ppd) {
                let path = dir.join(format!("{stem}-flip-hdr-f{f:03}.png"));
                let img = tessera_metrics::flip_heatmap(&map);
                save_image(result, &img, &path, run_dir, f, "heatmap-hdr");
            }
        }
    }
}

/// Writes one PNG and records it (path relative to the run folder); a failed write is left out.
fn save_image(
    result: &mut VariantResult,
    img: &Rgb8Image,
    path: &Path,
    run_dir: &Path,
    frame: u32,
    kind: &str,
) {
    if tessera_metrics::save_png(path, img).is_ok() {
        let rel = path
            .strip_prefix(run_dir)
            .unwrap_or(path)
            .to_string_lossy()
            .replace('\\', "/");
        result.images.push(ImageRecord {
            frame,
            kind: kind.to_string(),
            path: rel,
        });
    }
}

/// A variant name as a file name: `upscale[scale=0.5]` → `upscale_scale=0.5_`.
pub fn sanitize(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "-_.=".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// A scenario result whose every variant failed with `error` (e.g. after a lost device).
pub fn run_failed(scenario: &Scenario, run_id: &str, error: &str) -> ScenarioResult {
    let results = scenario
        .variants
        .iter()
        .map(|v| {
            empty_result(
                v,
                Status::Failed {
                    error: error.to_string(),
                },
            )
        })
        .collect();
    finish(scenario, run_id, results, Instant::now())
}

/// Appends a variant's frame hashes to the `TESSERA_FRAME_HASHES` file, when set.
fn append_hashes(scenario: &str, variant: &str, hashes: &[u64]) {
    use std::io::Write;
    let Some(path) = frames::frame_hash_file() else {
        return;
    };
    let lines: String = hashes
        .iter()
        .enumerate()
        .map(|(i, h)| format!("{scenario} {variant} {i} {h:016x}\n"))
        .collect();
    let written = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&path)
        .and_then(|mut f| f.write_all(lines.as_bytes()));
    if let Err(e) = written {
        eprintln!(
            "warning: cannot append frame hashes to {}: {e}",
            path.display()
        );
    }
}
