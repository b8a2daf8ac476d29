//! Result files: `run.json`, `scenarios/<scenario>.json`, `results.csv` and JUnit XML.
//!
//! Exporters are pure (records in, bytes out); [`write_atomic`] (`crate::files`) puts bytes on
//! disk through a temporary file and a rename, so an interrupted run keeps every scenario it
//! completed and never leaves a half-written file. The format is documented in `results/README.md`.

use std::fmt::Write as _;

use tessera_results::csv_file::{self, Formulas};
use tessera_results::expectation::Outcome;
use tessera_results::measure::{self, Key, Measure, DEFAULT_BASELINE};
use tessera_results::{GateLevel, RunInfo, ScenarioResult, Status, VariantResult, CSV_COLUMNS};

use Measure::*;

pub use crate::files::{write_atomic, WriteError};

pub fn run_json(run: &RunInfo) -> Vec<u8> {
    serde_json::to_vec_pretty(run).expect("run records serialise")
}

pub fn scenario_json(s: &ScenarioResult) -> Vec<u8> {
    serde_json::to_vec_pretty(s).expect("scenario records serialise")
}

fn num(v: f64) -> String {
    if v.is_infinite() && v > 0.0 {
        "inf".to_string()
    } else if v.is_finite() {
        format!("{v}")
    } else {
        String::new()
    }
}

/// `results.csv`: one row per (scenario, variant, measure); columns in [`CSV_COLUMNS`].
pub fn results_csv(run: &RunInfo, scenarios: &[ScenarioResult]) -> Vec<u8> {
    let mut lines: Vec<[String; 10]> = Vec::new();
    for s in scenarios {
        for r in &s.results {
            let mut rows: Vec<(String, String, &str)> = Vec::new();
            csv_rows(&s.results, r, &mut rows);
            for (measure, value, unit) in rows {
                lines.push([
                    run.run_id.clone(),
                    s.scenario.clone(),
                    r.variant.clone(),
                    r.technique.clone(),
                    run.adapter.name.clone(),
                    run.adapter.backend.clone(),
                    r.status.label().to_string(),
                    measure,
                    value,
                    unit.to_string(),
                ]);
            }
        }
    }
    csv_file::write(&CSV_COLUMNS, &lines, Formulas::Keep)
}

/// The (measure, value, unit) rows of one result, in `results.csv` order: names and units from
/// the measure table (`tessera_results::measure`), a technique's own checks' units from their
/// records.
fn csv_rows<'r>(
    results: &[VariantResult],
    r: &'r VariantResult,
    rows: &mut Vec<(String, String, &'r str)>,
) {
    let row = |key: Key, value: String| (key.render(), value, key.measure.unit());
    if r.status != Status::Ok {
        // The only row of a skipped or failed variant.
        rows.push(("status".to_string(), String::new(), ""));
        return;
    }
    let stat = |m: Measure, st: &'static str| Key::of(m).statistic(st);
    if let Some(t) = r.gpu_frame_ms {
        rows.push(row(stat(GpuMs, "median"), num(t.median)));
        rows.push(row(stat(GpuMs, "p5"), num(t.p5)));
        rows.push(row(stat(GpuMs, "p95"), num(t.p95)));
        rows.push(row(stat(GpuMs, "min"), num(t.min)));
    }
    rows.push(row(stat(CpuMs, "median"), num(r.cpu_frame_ms.median)));
    if let Some(sp) = measure::speedup(results, r, DEFAULT_BASELINE) {
        rows.push(row(Key::of(Speedup), num(sp)));
    }
    // The variant's own baseline (its technique's, per variant), beside native; a file written
    // before results recorded it gets its technique's default variant's (what was read then).
    let recorded = r.baseline.as_deref();
    let fallback = || {
        let t = crate::techniques::by_name(&r.technique)?;
        t.baseline(&crate::techniques::Variant::with_defaults(t))
    };
    if let Some(b) = recorded.or_else(fallback) {
        if let Some(sp) = measure::speedup(results, r, b) {
            rows.push(row(Key::speedup_over(b), num(sp)));
        }
    }
    if let Some([lo, hi]) = r.gpu_frame_ms.and_then(|t| t.median_ci95) {
        rows.push(row(stat(GpuMs, "median_ci95.low"), num(lo)));
        rows.push(row(stat(GpuMs, "median_ci95.high"), num(hi)));
    }
    if let Some(sm) = &r.sampling {
        rows.push(row(Key::of(MeasuredFrames), sm.frames.to_string()));
        if let Some(p) = sm.precision {
            rows.push(row(Key::of(GpuMsPrecision), num(p)));
        }
    }
    if let Some(p) = &r.pacing {
        rows.push(row(Key::of(PacingP95OverP50), num(p.p95_over_p50)));
        rows.push(row(Key::of(PacingMeanAbsDeltaMs), num(p.mean_abs_delta_ms)));
        if let Some(par) = &p.parity {
            rows.push(row(stat(PacingEvenMs, "median"), num(par.even_median_ms)));
            rows.push(row(stat(PacingOddMs, "median"), num(par.odd_median_ms)));
            rows.push(row(Key::of(PacingEvenOverOdd), num(par.even_over_odd)));
        }
    }
    if let Some(c) = r.conditions.as_ref().and_then(|c| c.recorded()) {
        let spreads = [
            (GraphicsClockMhz, c.graphics_clock_mhz),
            (MemoryClockMhz, c.memory_clock_mhz),
            (TemperatureC, c.temperature_c),
            (PowerW, c.power_w),
        ];
        for (m, spread) in spreads {
            if let Some(v) = spread {
                rows.push(row(stat(m, "min"), num(v.min)));
                rows.push(row(stat(m, "median"), num(v.median)));
                rows.push(row(stat(m, "max"), num(v.max)));
            }
        }
        if let Some(e) = measure::energy_mj(r) {
            rows.push(row(Key::of(EnergyMj), num(e)));
        }
        if let Some(x) = measure::energy_saving(results, r, DEFAULT_BASELINE) {
            rows.push(row(Key::of(EnergySaving), num(x)));
        }
        rows.push(row(Key::of(Throttled), u8::from(c.throttled).to_string()));
    }
    for p in &r.passes {
        if let Some(t) = p.gpu_ms {
            rows.push(row(stat(GpuMs, "median").pass(&p.name), num(t.median)));
        }
        if let Some(f) = p.fragment_invocations {
            rows.push(row(
                Key::of(FragmentInvocations).pass(&p.name),
                f.to_string(),
            ));
        }
    }
    rows.push(row(Key::of(AllocatedBytes), r.allocated_bytes.to_string()));
    rows.push(row(
        Key::of(NonFiniteValues),
        r.non_finite_values.to_string(),
    ));
    for m in &r.metrics {
        match Measure::from_name(&m.name) {
            Some(known) => rows.push(row(Key::of(known), num(m.value))),
            // A metric the table does not know (a technique's own check): its own name, and the
            // unit its record carries.
            None => rows.push((m.name.clone(), num(m.value), measure::metric_unit(m))),
        }
    }
}

fn xml(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// JUnit XML: one test suite per scenario, one test case per variant. Failed variants and failed
/// gates are failures; skipped variants are skipped; warnings go to system-out.
pub fn junit(run: &RunInfo, scenarios: &[ScenarioResult]) -> Vec<u8> {
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let tests: usize = scenarios.iter().map(|s| s.results.len()).sum();
    let _ = writeln!(
        out,
        "<testsuites name=\"tessera {}\" tests=\"{tests}\">",
        xml(&run.run_id)
    );
    for s in scenarios {
        let failures = s.results.iter().filter(|r| failed(r)).count();
        let skipped = s
            .results
            .iter()
            .filter(|r| {
                matches!(r.status, Status::Skipped { .. })
                    || crate::expect::apply::expected_failure(r)
            })
            .count();
        let _ = writeln!(
            out,
            "  <testsuite name=\"{}\" tests=\"{}\" failures=\"{failures}\" skipped=\"{skipped}\" time=\"{:.3}\">",
            xml(&s.scenario),
            s.results.len(),
            s.wall_ms / 1000.0
        );
        for r in &s.results {
            testcase(&mut out, &s.scenario, r);
        }
        out.push_str("  </testsuite>\n");
    }
    out.push_str("</testsuites>\n");
    out.into_bytes()
}

/// One variant's `<testcase>`: its metrics and expectation as properties, its outcome, and its
/// warnings as system-out.
fn testcase(out: &mut String, scenario: &str, r: &tessera_results::VariantResult) {
    let time = r.cpu_frame_ms.mean * r.cpu_frame_ms.count as f64 / 1000.0;
    let _ = write!(
        out,
        "    <testcase classname=\"{}\" name=\"{}\" time=\"{time:.3}\"",
        xml(scenario),
        xml(&r.variant)
    );
    let mut body = properties(r);
    outcome(&mut body, r);
    system_out(&mut body, r);
    if body.is_empty() {
        out.push_str("/>\n");
    } else {
        out.push_str(">\n");
        out.push_str(&body);
        out.push_str("    </testcase>\n");
    }
}

/// Every metric as a property, its direction in the name: `cvvdp (higher is better)`; the
/// expectation that applied, as `expectation`.
fn properties(r: &tessera_results::VariantResult) -> String {
    let mut body = String::new();
    if !r.metrics.is_empty() || r.expectation.is_some() {
        body.push_str("      <properties>\n");
        if let Some(e) = &r.expectation {
            let _ = writeln!(
                body,
                "        <property name=\"expectation\" value=\"{}\"/>",
                xml(&format!(
                    "{} ({}): {}: {}",
                    e.label.as_str(),
                    e.source,
                    e.outcome.as_str(),
                    e.reason
                ))
            );
        }
        for m in &r.metrics {
            let dir = if m.higher_is_better {
                "higher"
            } else {
                "lower"
            };
            let _ = writeln!(
                body,
                "        <property name=\"{} ({dir} is better)\" value=\"{}\"/>",
                xml(&m.name),
                num(m.value)
            );
        }
        body.push_str("      </properties>\n");
    }
    body
}

/// A failure, a skip, or nothing, as the status, the gates and the expectation say.
fn outcome(body: &mut String, r: &tessera_results::VariantResult) {
    let outcome = r.expectation.as_ref().map(|e| (e, e.outcome));
    match &r.status {
        // A failure an expectation said would happen is reported as pytest reports an
        // expected failure: skipped, with why.
        _ if matches!(outcome, Some((_, Outcome::ExpectedFailure))) => {
            let e = outcome.expect("matched").0;
            let _ = writeln!(
                body,
                "      <skipped message=\"{}\"/>",
                xml(&format!(
                    "expected failure ({}: {}, {}): {}",
                    e.label.as_str(),
                    e.reason,
                    e.source,
                    e.error.as_deref().unwrap_or("")
                ))
            );
        }
        _ if matches!(outcome, Some((_, Outcome::UnexpectedPass))) => {
            let e = outcome.expect("matched").0;
            let _ = writeln!(
                body,
                "      <failure message=\"{}\"/>",
                xml(&format!(
                    "unexpected pass: remove the entry at {} ({}: {})",
                    e.source,
                    e.label.as_str(),
                    e.reason
                ))
            );
        }
        Status::Skipped { reason } => {
            let _ = writeln!(body, "      <skipped message=\"{}\"/>", xml(reason));
        }
        Status::Failed { error } => {
            let _ = writeln!(body, "      <failure message=\"{}\"/>", xml(error));
        }
        Status::Ok => {
            for g in r.gates.iter().filter(|g| g.level == GateLevel::Fail) {
                let _ = writeln!(body, "      <failure message=\"{}\"/>", xml(&g.message));
            }
        }
    }
}

/// Warning gates and throttling, as system-out.
fn system_out(body: &mut String, r: &tessera_results::VariantResult) {
    let throttled = r
        .conditions
        .as_ref()
        .and_then(|c| c.recorded())
        .filter(|c| c.throttled)
        .map(|c| format!("throttled: {}", c.throttle_causes.join("; ")));
    let warnings: Vec<&str> = r
        .gates
        .iter()
        .filter(|g| g.level == GateLevel::Warn)
        .map(|g| g.message.as_str())
        .chain(throttled.as_deref())
        .collect();
    if !warnings.is_empty() {
        let _ = writeln!(
            body,
            "      <system-out>{}</system-out>",
            xml(&warnings.join("\n"))
        );
    }
}

/// Whether JUnit counts a result as a failure: it failed and no expectation said it would, or it
/// passed where one said it would not.
fn failed(r: &tessera_results::VariantResult) -> bool {
    use crate::expect::apply;
    (apply::failed(r) && !apply::expected_failure(r)) || apply::unexpected_pass(r)
}

/// The first lines of a GPU error, joined: enough to tell what failed.
pub fn first_line(s: &str) -> String {
    s.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .take(3)
        .collect::<Vec<_>>()
        .join(" ")
}
