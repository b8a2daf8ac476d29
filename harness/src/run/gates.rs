//! Gates: thresholds a scenario declares on metrics and timings, evaluated per variant at two
//! levels (warn, fail). Pure functions over finished results; the exit code is decided in `main`.

use tessera_results::{GateLevel, GateOutcome, Status, VariantResult};

use crate::scenario::{Gate, Reference, Scenario};

/// Median GPU frame time; `None` on adapters without timestamps.
pub fn frame_ms(r: &VariantResult) -> Option<f64> {
    r.gpu_frame_ms.map(|s| s.median)
}

/// Speed-up of `r` against the `native` variant of the same scenario on the same adapter.
pub fn speedup(results: &[VariantResult], r: &VariantResult) -> Option<f64> {
    speedup_over(results, r, crate::techniques::native::NAME)
}

/// Speed-up of `r` against the first ok variant of technique `baseline` (e.g. `native-deferred`,
/// the baseline of `adaptive-shading`) of the same scenario on the same adapter: found by
/// technique, as the dashboard finds it, so a `label` on the baseline changes nothing.
pub fn speedup_over(results: &[VariantResult], r: &VariantResult, baseline: &str) -> Option<f64> {
    let native = results
        .iter()
        .find(|v| v.technique == baseline && v.status == Status::Ok)?;
    if r.status != Status::Ok {
        return None;
    }
    let (n, v) = (frame_ms(native)?, frame_ms(r)?);
    (v > 0.0).then(|| n / v)
}

/// `*` matches any run of characters; everything else literally.
pub fn matches(pattern: &str, name: &str) -> bool {
    let parts: Vec<&str> = pattern.split('*').collect();
    if parts.len() == 1 {
        return pattern == name;
    }
    let mut rest = name;
    for (i, part) in parts.iter().enumerate() {
        if i == 0 {
            let Some(r) = rest.strip_prefix(part) else {
                return false;
            };
            rest = r;
        } else if i == parts.len() - 1 {
            return rest.ends_with(part);
        } else {
            let Some(pos) = rest.find(part) else {
                return false;
            };
            rest = &rest[pos + part.len()..];
        }
    }
    true
}

fn applies(gate: &Gate, scenario: &Scenario, r: &VariantResult) -> bool {
    match &gate.variants {
        Some(p) => matches(p, &r.variant),
        None => !(scenario.reference == Reference::Native && r.variant == "native"),
    }
}

fn measure(results: &[VariantResult], r: &VariantResult, name: &str) -> Option<f64> {
    match name {
        "gpu_ms" => frame_ms(r),
        "cpu_ms" => (r.cpu_frame_ms.count > 0).then_some(r.cpu_frame_ms.median),
        "speedup" => speedup(results, r),
        "non-finite" => Some(r.non_finite_values as f64),
        "spread-non-finite" => r.stability.as_ref()?.spread_pixels.map(|v| v as f64),
        "nondeterministic" => r
            .stability
            .as_ref()?
            .deterministic
            .map(|d| if d { 0.0 } else { 1.0 }),
        "unrecovered-cuts" => r
            .stability
            .as_ref()
            .map(|s| super::stability::unrecovered_cuts(s) as f64),
        metric => r.metrics.iter().find(|m| m.name == metric).map(|m| m.value),
    }
}

/// Evaluates one gate on one value.
pub fn evaluate(gate: &Gate, value: f64) -> (GateLevel, String) {
    let checks = [
        (gate.fail_below, GateLevel::Fail, true),
        (gate.fail_above, GateLevel::Fail, false),
        (gate.warn_below, GateLevel::Warn, true),
        (gate.warn_above, GateLevel::Warn, false),
    ];
    for (bound, level, below) in checks {
        if let Some(b) = bound {
            let crossed = if below { value < b } else { value > b };
            if crossed {
                let rel = if below { "below" } else { "above" };
                let verb = if level == GateLevel::Fail {
                    "fails"
                } else {
                    "warns"
                };
                return (
                    level,
                    format!(
                        "{} = {} is {rel} {b}: {verb}",
                        gate.measure,
                        fmt_value(value)
                    ),
                );
            }
        }
    }
    (
        GateLevel::Pass,
        format!("{} = {} passes", gate.measure, fmt_value(value)),
    )
}

fn fmt_value(v: f64) -> String {
    if v.is_infinite() {
        "inf".to_string()
    } else {
        format!("{v:.4}")
    }
}

/// Evaluates every gate of the scenario on every variant it applies to. A gate whose measure is
/// missing (skipped variant, no timestamps) warns instead of passing silently; failed variants fail.
pub fn apply(scenario: &Scenario, results: &mut [VariantResult]) {
    let snapshot = results.to_vec();
    for r in results.iter_mut() {
        let gates: Vec<&Gate> = scenario
            .gates
            .iter()
            .filter(|g| applies(g, scenario, r))
            .collect();
        for gate in gates {
            let outcome = match (&r.status, measure(&snapshot, r, &gate.measure)) {
                (Status::Skipped { .. }, _) => continue,
                (Status::Failed { .. }, _) => GateOutcome {
                    measure: gate.measure.clone(),
                    value: f64::NAN,
                    level: GateLevel::Fail,
                    message: format!("{}: the variant failed", gate.measure),
                },
                (_, Some(v)) => {
                    let (level, message) = evaluate(gate, v);
                    GateOutcome {
                        measure: gate.measure.clone(),
                        value: v,
                        level,
                        message,
                    }
                }
                (_, None) => GateOutcome {
                    measure: gate.measure.clone(),
                    value: f64::NAN,
                    level: GateLevel::Warn,
                    message: format!("{}: not measured on this adapter", gate.measure),
                },
            };
            r.gates.push(outcome);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gate() -> Gate {
        Gate {
            measure: "psnr".into(),
            variants: None,
            warn_below: Some(35.0),
            fail_below: Some(30.0),
            warn_above: None,
            fail_above: None,
        }
    }

    #[test]
    fn two_levels() {
        assert_eq!(evaluate(&gate(), 40.0).0, GateLevel::Pass);
        assert_eq!(evaluate(&gate(), 33.0).0, GateLevel::Warn);
        let (level, msg) = evaluate(&gate(), 29.0);
        assert_eq!(level, GateLevel::Fail);
        assert_eq!(msg, "psnr = 29.0000 is below 30: fails");
        assert_eq!(evaluate(&gate(), f64::INFINITY).0, GateLevel::Pass);
    }

    #[test]
    fn patterns() {
        assert!(matches("upscale*", "upscale[scale=0.5]"));
        assert!(matches("*0.5]", "upscale[scale=0.5]"));
        assert!(matches("up*=*]", "upscale[scale=0.5]"));
        assert!(!matches("native", "native-deferred"));
        assert!(matches("native", "native"));
    }
}
