//! Gates: thresholds a scenario declares on metrics and timings, evaluated per variant at two
//! levels (warn, fail). Pure functions over finished results; the exit code is decided in `main`.

use tessera_results::measure::{self, Measure, DEFAULT_BASELINE};
use tessera_results::{GateLevel, GateOutcome, Status, VariantResult};

use crate::scenario::{Gate, Reference, Scenario};
use crate::techniques;

/// Median GPU frame time; `None` on adapters without timestamps.
pub fn frame_ms(r: &VariantResult) -> Option<f64> {
    measure::gpu_ms(r)
}

/// Speed-up of `r` against the `native` variant of the same scenario on the same adapter.
pub fn speedup(results: &[VariantResult], r: &VariantResult) -> Option<f64> {
    measure::speedup(results, r, DEFAULT_BASELINE)
}

/// Speed-up of `r` against the first ok variant of technique `baseline` (e.g. `native-deferred`,
/// the baseline of `adaptive-shading`) of the same scenario on the same adapter: found by
/// technique ([`measure::baseline_of`]), as the dashboard finds it, so a `label` on the baseline
/// changes nothing.
pub fn speedup_over(results: &[VariantResult], r: &VariantResult, baseline: &str) -> Option<f64> {
    measure::speedup(results, r, baseline)
}

/// Energy per measured frame in millijoules; `None` where the adapter's sensors are not available.
pub fn energy_mj(r: &VariantResult) -> Option<f64> {
    measure::energy_mj(r)
}

/// Energy saved against the `native` variant of the same scenario: native's energy per frame over
/// this variant's (2 = half the energy per frame), the energy counterpart of [`speedup`].
pub fn energy_saving(results: &[VariantResult], r: &VariantResult) -> Option<f64> {
    measure::energy_saving(results, r, DEFAULT_BASELINE)
}

/// Whether the result was throttled during its measured frames; `None` without sensors.
pub fn throttled(r: &VariantResult) -> Option<bool> {
    Some(r.conditions.as_ref()?.recorded()?.throttled)
}

pub use crate::scenario::pattern::matches;

fn applies(gate: &Gate, scenario: &Scenario, r: &VariantResult) -> bool {
    match &gate.variants {
        Some(p) => matches(p, &r.variant),
        None => {
            !(scenario.reference == Reference::Native && techniques::is_reference_name(&r.variant))
        }
    }
}

/// The gated value: the measure's (its median where summarised, [`measure::value`]); a gate on
/// `<name>.median` reads the same. Validation allows only measures of the table.
fn measure(results: &[VariantResult], r: &VariantResult, name: &str) -> Option<f64> {
    let key = measure::Key::parse(name)?;
    if key.pass.is_some()
        || key.baseline.is_some()
        || !matches!(key.statistic, None | Some("median"))
    {
        return None;
    }
    measure::value(results, r, key.measure)
}

/// The measure name a gate outcome is written with: the canonical one (`non-finite` is written
/// `non_finite_values`).
fn canonical(name: &str) -> String {
    Measure::from_name(name).map_or_else(|| name.to_string(), |m| m.name().to_string())
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
                        canonical(&gate.measure),
                        fmt_value(value)
                    ),
                );
            }
        }
    }
    (
        GateLevel::Pass,
        format!("{} = {} passes", canonical(&gate.measure), fmt_value(value)),
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
            let name = canonical(&gate.measure);
            let outcome = match (&r.status, measure(&snapshot, r, &gate.measure)) {
                (Status::Skipped { .. }, _) => continue,
                (Status::Failed { .. }, _) => GateOutcome {
                    measure: name.clone(),
                    value: f64::NAN,
                    level: GateLevel::Fail,
                    message: format!("{name}: the variant failed"),
                },
                (_, Some(v)) => {
                    let (level, message) = evaluate(gate, v);
                    GateOutcome {
                        measure: name.clone(),
                        value: v,
                        level,
                        message,
                    }
                }
                (_, None) => GateOutcome {
                    measure: name.clone(),
                    value: f64::NAN,
                    level: GateLevel::Warn,
                    message: format!("{name}: not measured on this adapter"),
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
