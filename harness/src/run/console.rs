//! Console report: per scenario an aligned table of variants on stdout, then one verdict line.
//!
//! Formatting only; numbers come from the finished records.

use std::fmt::Write as _;

use tessera_results::conditions::{SamplingMode, StopReason};
use tessera_results::expectation::Outcome;
use tessera_results::measure::Measure;
use tessera_results::{GateLevel, ScenarioResult, Status, VariantResult};

use super::gates;
use crate::techniques;

fn ms(v: Option<f64>) -> String {
    v.map(|v| format!("{v:.3}"))
        .unwrap_or_else(|| "-".to_string())
}

fn psnr(r: &VariantResult) -> String {
    match r.metrics.iter().find(|m| m.name == Measure::Psnr.name()) {
        Some(m) if m.value.is_infinite() => "inf".to_string(),
        Some(m) => format!("{:.2}", m.value),
        None => "-".to_string(),
    }
}

fn status(r: &VariantResult) -> String {
    if let Some(e) = &r.expectation {
        let entry = format!("{}: {}", e.label.as_str(), e.reason);
        match e.outcome {
            Outcome::ExpectedFailure => {
                return format!(
                    "expected failure ({entry}): {}",
                    e.error.as_deref().unwrap_or("")
                )
            }
            Outcome::UnexpectedPass => {
                return format!(
                    "UNEXPECTED PASS: remove the entry at {} ({entry})",
                    e.source
                )
            }
            Outcome::PassedOnRetry => {
                return format!(
                    "ok on retry (flaky: {}; first attempt: {})",
                    e.reason,
                    e.error.as_deref().unwrap_or("")
                )
            }
            Outcome::NotRun => return format!("not run ({entry})"),
            Outcome::FailedOnRetry | Outcome::Ran => {
                return format!("{} [{entry}]", plain_status(r))
            }
        }
    }
    plain_status(r)
}

fn plain_status(r: &VariantResult) -> String {
    let gate = r
        .gates
        .iter()
        .map(|g| g.level)
        .max()
        .unwrap_or(GateLevel::Pass);
    match &r.status {
        Status::Ok => match gate {
            GateLevel::Pass => "ok".to_string(),
            GateLevel::Warn => format!("ok, gate warns: {}", gate_messages(r, GateLevel::Warn)),
            GateLevel::Fail => format!("gate failed: {}", gate_messages(r, GateLevel::Fail)),
        },
        Status::Skipped { reason } => format!("skipped: {reason}"),
        Status::Failed { error } => format!("failed: {error}"),
    }
}

fn gate_messages(r: &VariantResult, level: GateLevel) -> String {
    r.gates
        .iter()
        .filter(|g| g.level == level)
        .map(|g| g.message.as_str())
        .collect::<Vec<_>>()
        .join("; ")
}

/// The table of one scenario.
pub fn scenario_table(s: &ScenarioResult) -> String {
    // The measures' labels (`tessera_results::measure`), as the dashboard shows them.
    let header = [
        "variant",
        Measure::GpuMs.label(),
        Measure::CpuMs.label(),
        Measure::Speedup.label(),
        Measure::Psnr.label(),
        "status",
    ];
    let rows: Vec<[String; 6]> = s
        .results
        .iter()
        .map(|r| {
            let ok = r.status == Status::Ok;
            [
                r.variant.clone(),
                if ok {
                    ms(gates::frame_ms(r))
                } else {
                    "-".into()
                },
                if ok {
                    ms(Some(r.cpu_frame_ms.median))
                } else {
                    "-".into()
                },
                gates::speedup(&s.results, r)
                    .map(|v| format!("{v:.2}x"))
                    .unwrap_or_else(|| "-".into()),
                psnr(r),
                status(r),
            ]
        })
        .collect();
    let mut widths = header.map(str::len);
    for row in &rows {
        for (i, c) in row.iter().enumerate().take(5) {
            widths[i] = widths[i].max(c.chars().count());
        }
    }
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{} ({}x{}, {} measured frames, reference: {})",
        s.scenario, s.width, s.height, s.measured_frames, s.reference
    );
    let line = |cells: &[String]| {
        let mut l = format!("  {:<w0$}", cells[0], w0 = widths[0]);
        for i in 1..5 {
            let _ = write!(l, "  {:>w$}", cells[i], w = widths[i]);
        }
        let _ = write!(l, "  {}", cells[5]);
        l.trim_end().to_string()
    };
    let _ = writeln!(out, "{}", line(&header.map(String::from)));
    for row in &rows {
        let _ = writeln!(out, "{}", line(row));
    }
    if let Some(n) = &s.reference_noise {
        let _ = writeln!(out, "  {}", crate::tables::noise_line(n));
    }
    for r in &s.results {
        for f in stability_findings(r) {
            let _ = writeln!(out, "  stability: {}: {f}", r.variant);
        }
    }
    for r in &s.results {
        if let Some(e) = &r.expectation {
            let _ = writeln!(
                out,
                "  expectation: {}: {} ({}): {}: {}",
                r.variant,
                e.label.as_str(),
                e.source,
                e.outcome.as_str(),
                e.reason
            );
        }
    }
    for r in &s.results {
        if let Some(line) = conditions_line(&s.results, r) {
            let _ = writeln!(out, "  conditions: {}: {line}", r.variant);
        }
    }
    if let Some(b) = s.peak_rss_bytes {
        let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
        let heap = s.peak_heap_bytes.map_or(String::new(), |h| {
            format!(", {:.0} MiB peak heap (the harness's own)", mib(h))
        });
        let _ = writeln!(
            out,
            "  memory: {:.0} MiB peak resident (the process on the host, driver included){heap}; {:.1} s wall",
            mib(b),
            s.wall_ms / 1000.0
        );
    }
    out
}

/// One result's conditions in a line: graphics clock, temperature, power, energy per frame (and
/// the energy saved against native), throttling, and the frames `measured = "auto"` took; `None`
/// when there is none of these.
pub fn conditions_line(results: &[VariantResult], r: &VariantResult) -> Option<String> {
    let mut parts = Vec::new();
    if let Some(c) = r.conditions.as_ref().and_then(|c| c.recorded()) {
        if let Some(g) = c.graphics_clock_mhz {
            parts.push(format!("clock {:.0} MHz (min {:.0})", g.median, g.min));
        }
        if let Some(t) = c.temperature_c {
            parts.push(format!("{:.0}-{:.0} C", t.min, t.max));
        }
        if let Some(p) = c.power_w {
            parts.push(format!("{:.0} W median", p.median));
        }
        if let Some(e) = c.energy {
            let saving = gates::energy_saving(results, r)
                .filter(|_| !techniques::is_reference_name(&r.variant))
                .map(|x| format!(" (saving {x:.2}x against native)"))
                .unwrap_or_default();
            parts.push(format!("{:.3} mJ/frame{saving}", e.mj_per_frame));
        }
        if let Some(ms) = c.clock_warmup_ms {
            parts.push(format!("warm-up {ms:.0} ms"));
        }
        if c.throttled {
            parts.push("THROTTLED".into());
        }
    }
    if let Some(sm) = r.sampling.filter(|s| s.mode == SamplingMode::Auto) {
        let precision = sm
            .precision
            .map(|p| format!("±{:.2}%", p * 100.0))
            .unwrap_or_else(|| "no interval".into());
        let ended = match sm.ended_by {
            StopReason::Cap => "frame cap",
            StopReason::Timeout => "timeout",
            _ => "target met",
        };
        parts.push(format!(
            "{} frames, median {precision} ({ended})",
            sm.frames
        ));
    }
    (!parts.is_empty()).then(|| parts.join(", "))
}

/// The stderr hints of one scenario: each throttled result, why, and what to do about it.
pub fn throttle_hints(s: &ScenarioResult) -> Vec<String> {
    s.results
        .iter()
        .filter_map(|r| {
            let c = r.conditions.as_ref()?.recorded()?;
            c.throttled.then(|| {
                format!(
                    "hint: {} / {} was throttled during its measured frames ({}): its timings read low clocks. Lengthen `frames.warmup_ms`, let the GPU cool between runs, or lock its clocks on a machine you control (scenarios/perf/README.md); tessera never changes GPU settings",
                    s.scenario,
                    r.variant,
                    c.throttle_causes.join("; ")
                )
            })
        })
        .collect()
}

/// What the stability checks found wrong with one result, one line each (nothing when clean).
pub fn stability_findings(r: &VariantResult) -> Vec<String> {
    let Some(s) = &r.stability else {
        return Vec::new();
    };
    let mut out = Vec::new();
    match s.spread_pixels {
        Some(n) if n > 0 => out.push(format!(
            "{n} non-finite pixels where the reference is finite ({} non-finite in all)",
            s.non_finite_pixels
        )),
        None if s.non_finite_pixels > 0 => {
            out.push(format!("{} non-finite pixels", s.non_finite_pixels))
        }
        _ => {}
    }
    if s.deterministic == Some(false) {
        out.push("not deterministic: the second render of the sequence ended on other bits".into());
    }
    for c in s.cuts.iter().filter(|c| c.recovered == Some(false)) {
        let db = |mse: f64| tessera_metrics::psnr_from_mse(mse, 255.0);
        let after = c.mse.get(2).copied().unwrap_or(f64::NAN);
        out.push(format!(
            "error not back to steady 2 frames after the cut at frame {}: PSNR {:.2} dB against a steady {:.2} dB",
            c.frame,
            db(after),
            c.steady_mse.map(db).unwrap_or(f64::NAN)
        ));
    }
    out
}

/// One line over a whole run: how many results the stability checks looked at, and findings.
pub fn stability_summary(scenarios: &[ScenarioResult]) -> String {
    let checked: Vec<&VariantResult> = scenarios
        .iter()
        .flat_map(|s| &s.results)
        .filter(|r| r.stability.is_some())
        .collect();
    let findings = checked
        .iter()
        .filter(|r| !stability_findings(r).is_empty())
        .count();
    let cuts: usize = checked
        .iter()
        .filter_map(|r| r.stability.as_ref())
        .map(|s| s.cuts.iter().filter(|c| c.recovered.is_some()).count())
        .sum();
    let deterministic = checked
        .iter()
        .filter(|r| r.stability.as_ref().and_then(|s| s.deterministic) == Some(true))
        .count();
    format!(
        "stability: {} results checked, {findings} with findings; {deterministic} rendered the same twice; {cuts} camera cuts judged",
        checked.len()
    )
}

/// Counts over a whole run.
#[derive(Debug, Default, PartialEq, Eq)]
pub struct Tally {
    pub ok: usize,
    pub skipped: usize,
    pub failed: usize,
    pub gate_warnings: usize,
    pub gate_failures: usize,
    /// Failures an expectation (`broken`) said would happen: counted here, not as failures.
    pub expected_failures: usize,
    /// Passes of results labelled `broken`: they fail the run until the entry is removed.
    pub unexpected_passes: usize,
    /// `flaky` results that failed once and passed when run again.
    pub passed_on_retry: usize,
}

pub fn tally(scenarios: &[ScenarioResult]) -> Tally {
    let mut t = Tally::default();
    for r in scenarios.iter().flat_map(|s| &s.results) {
        if let Some(e) = &r.expectation {
            match e.outcome {
                Outcome::ExpectedFailure => {
                    t.expected_failures += 1;
                    continue;
                }
                Outcome::UnexpectedPass => t.unexpected_passes += 1,
                Outcome::PassedOnRetry => t.passed_on_retry += 1,
                _ => {}
            }
        }
        match r.status {
            Status::Ok => t.ok += 1,
            Status::Skipped { .. } => t.skipped += 1,
            Status::Failed { .. } => t.failed += 1,
        }
        t.gate_warnings += r
            .gates
            .iter()
            .filter(|g| g.level == GateLevel::Warn)
            .count();
        t.gate_failures += r
            .gates
            .iter()
            .filter(|g| g.level == GateLevel::Fail)
            .count();
    }
    t
}

/// The one verdict line.
pub fn verdict(t: &Tally) -> String {
    let mut counts = format!(
        "{} ok, {} skipped, {} failed; gates: {} failed, {} warned",
        t.ok, t.skipped, t.failed, t.gate_failures, t.gate_warnings
    );
    if t.expected_failures + t.unexpected_passes + t.passed_on_retry > 0 {
        let _ = write!(
            counts,
            "; expectations: {} expected failures, {} unexpected passes, {} passed on retry",
            t.expected_failures, t.unexpected_passes, t.passed_on_retry
        );
    }
    if t.failed > 0 || t.gate_failures > 0 || t.unexpected_passes > 0 {
        format!("FAILED: {counts}")
    } else if t.gate_warnings > 0 {
        format!("PASSED with warnings: {counts}")
    } else {
        format!("PASSED: {counts}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn verdict_lines() {
        assert_eq!(
            verdict(&Tally {
                ok: 3,
                skipped: 1,
                ..Default::default()
            }),
            "PASSED: 3 ok, 1 skipped, 0 failed; gates: 0 failed, 0 warned"
        );
        assert!(verdict(&Tally {
            ok: 3,
            gate_warnings: 1,
            ..Default::default()
        })
        .starts_with("PASSED with warnings"));
        assert!(verdict(&Tally {
            ok: 3,
            gate_failures: 1,
            ..Default::default()
        })
        .starts_with("FAILED"));
        assert!(verdict(&Tally {
            failed: 1,
            ..Default::default()
        })
        .starts_with("FAILED"));
    }
}
