//! Building a scenario's result records: a variant's empty result, its timings and memory from
//! the rendered frames and the plan, its sampling, pacing and conditions, the scenario record, and
//! a scenario whose variants all failed.

use std::time::Instant;

use tessera_results::conditions::Conditions;
use tessera_results::{PassRecord, ScenarioResult, Status, Summary, VariantResult};

use super::rendered::Rendered;
use crate::conditions::Sensors;
use crate::render::renderer::Renderer;
use crate::scenario::Scenario;
use crate::techniques::{FramePattern, Variant};
use crate::timing::{pacing, stop};

/// The scenario's record from its variants' results.
pub fn finish(
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
        peak_rss_bytes: super::memory::peak_bytes(),
        peak_heap_bytes: super::memory::peak_heap_bytes(),
        reference_digests: Vec::new(),
        reference_noise: None,
    }
}

/// A variant's result before anything is known but its status.
pub fn empty_result(v: &Variant, status: Status) -> VariantResult {
    VariantResult {
        variant: v.name.clone(),
        technique: v.technique.name().to_string(),
        baseline: v.technique.baseline(v).map(str::to_string),
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
            median_ci95: None,
        },
        resources: Vec::new(),
        allocated_bytes: 0,
        metrics: Vec::new(),
        non_finite_values: 0,
        stability: None,
        images: Vec::new(),
        gates: Vec::new(),
        conditions: None,
        sampling: None,
        pacing: None,
        convergence: None,
        frame_digests: Vec::new(),
        expectation: None,
    }
}

/// What the plan of a rendered variant looked like.
pub struct PlanRecord {
    passes: Vec<PassRecord>,
    culled: Vec<String>,
    resources: Vec<tessera_results::ResourceRecord>,
}

/// The plan of a built variant, its passes not yet timed.
pub fn plan_record(t: &dyn Renderer) -> PlanRecord {
    let plan = t.plan();
    PlanRecord {
        passes: plan
            .passes
            .iter()
            .map(|p| PassRecord {
                name: p.name.to_string(),
                kind: p.kind.name().to_string(),
                reads: p.reads.iter().map(|s| s.to_string()).collect(),
                writes: p.writes.iter().map(|s| s.to_string()).collect(),
                gpu_ms: None,
                samples_ms: Vec::new(),
                fragment_invocations: None,
            })
            .collect(),
        culled: plan.culled.iter().map(|s| s.to_string()).collect(),
        resources: plan.records(),
    }
}

/// A variant's timings, fragment counts and memory from its frames and plan.
pub fn fill_timings(result: &mut VariantResult, r: &Rendered, plan: PlanRecord) {
    for mut pass in plan.passes {
        let samples: Vec<f64> = if r.timestamps {
            r.measurements
                .iter()
                .filter_map(|m| m.gpu_ms.get(&pass.name).copied())
                .collect()
        } else {
            Vec::new()
        };
        let mut invocations: Vec<f64> = r
            .measurements
            .iter()
            .filter_map(|m| m.fragment_invocations.get(&pass.name).map(|c| *c as f64))
            .collect();
        invocations.sort_by(|a, b| a.total_cmp(b));
        pass.gpu_ms = Summary::of(&samples);
        pass.samples_ms = samples;
        pass.fragment_invocations =
            (!invocations.is_empty()).then(|| invocations[invocations.len() / 2] as u64);
        result.passes.push(pass);
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

/// Sampling, pacing and the sensors' record of a rendered variant.
pub fn fill_conditions(
    result: &mut VariantResult,
    r: &Rendered,
    scenario: &Scenario,
    variant: &Variant,
    sensors: &Sensors,
) {
    result.sampling = Some(match scenario.auto {
        Some(rule) => rule.record(&r.frame_ms, r.ended_by),
        None => stop::fixed_record(&r.frame_ms),
    });
    if r.timestamps {
        result.pacing = pacing::pacing(
            &r.frame_ms,
            scenario.warmup_frames,
            variant.technique.frames(variant) == FramePattern::Alternating,
        );
    }
    let mut conditions = sensors.result_record(
        r.conditions.as_deref(),
        r.energy_window.as_ref().map(|(s, n)| (s.as_slice(), *n)),
    );
    if let Conditions::Recorded(c) = &mut conditions {
        c.clock_warmup_ms = Some(r.clock_warmup_ms);
    }
    result.conditions = Some(conditions);
    result.convergence = Some(super::convergence::record(
        scenario,
        variant.technique.convergence(variant, scenario.width),
    ));
}
