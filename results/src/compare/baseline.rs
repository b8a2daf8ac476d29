//! Which adapters count as the same, and each variant's baseline (`COMPARISON.md`,
//! "Baselines"). The one `same_adapter` of the house: `tessera compare`, the dashboard's compare
//! page and its API read it from here.
//!
//! Not for: computing speedups of one run for the CSV or the store (`crate::measure`, which this
//! module's lookup falls back to).

use crate::measure::{baseline_of, DEFAULT_BASELINE};
use crate::{RunInfo, Status, VariantResult};

use super::InRun;

/// Same adapter name, backend, driver and driver info: milliseconds of the two runs can be
/// compared. PCI ids and features are not compared (a driver update changes the driver info).
pub fn same_adapter(a: &RunInfo, b: &RunInfo) -> bool {
    let (x, y) = (&a.adapter, &b.adapter);
    x.name == y.name
        && x.backend == y.backend
        && x.driver == y.driver
        && x.driver_info == y.driver_info
}

/// The baseline a result declares: its record's `baseline` (the technique's per-variant
/// same-pipeline baseline, written by the harness). Results written before the record had the
/// field declare none and fall back to `native`, as the CSV's `speedup` does.
fn declared(r: &VariantResult) -> Option<&str> {
    r.baseline.as_deref()
}

/// Whether `x` is measured against nothing: a variant of the technique it would be measured
/// against (`native` itself), or the variant its record names.
pub(crate) fn is_root(x: InRun) -> bool {
    let wanted = declared(x.r).unwrap_or(DEFAULT_BASELINE);
    x.r.technique == wanted || x.r.variant == wanted
}

/// The variant `x` is measured against in its scenario: the one its record declares (a variant
/// of that name, else the first ok variant of that technique), else the first ok variant of
/// technique `native` ([`baseline_of`]). Found by technique, never by a variant's name or label
/// unless the record names it. `None` for the baseline itself, and when the scenario has no ok
/// baseline.
pub(crate) fn of<'a>(x: InRun<'a>) -> Option<&'a VariantResult> {
    if is_root(x) {
        return None;
    }
    let wanted = declared(x.r).unwrap_or(DEFAULT_BASELINE);
    x.results
        .iter()
        .find(|v| v.variant == wanted && v.status == Status::Ok)
        .or_else(|| baseline_of(x.results, wanted))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compare::time::tests::result;

    #[test]
    fn native_is_found_by_technique_and_has_no_baseline_itself() {
        let mut native = result("native", &[1.0]);
        native.variant = "native[label=full]".into();
        let upscale = result("upscale", &[0.5]);
        let results = vec![upscale.clone(), native.clone()];
        let of_upscale = of(InRun {
            results: &results,
            r: &results[0],
        });
        assert_eq!(
            of_upscale.map(|r| r.variant.as_str()),
            Some("native[label=full]")
        );
        assert!(of(InRun {
            results: &results,
            r: &results[1],
        })
        .is_none());
    }

    #[test]
    fn a_declared_baseline_is_found_by_technique_then_native_for_the_rest() {
        let mut hardware = result("adaptive-shading[vrs=hardware]", &[0.5]);
        hardware.baseline = Some("native-vrs".into());
        let mut software = result("adaptive-shading[vrs=software]", &[0.5]);
        software.baseline = Some("native-deferred".into());
        let results = vec![
            result("native", &[1.0]),
            result("native-deferred", &[1.1]),
            result("native-vrs[rate=1x1]", &[1.2]),
            hardware,
            software,
        ];
        let base = |i: usize| {
            of(InRun {
                results: &results,
                r: &results[i],
            })
            .map(|r| r.variant.as_str())
        };
        assert_eq!(base(3), Some("native-vrs[rate=1x1]"));
        assert_eq!(base(4), Some("native-deferred"));
        // The baselines themselves fall back to native.
        assert_eq!(base(1), Some("native"));
        assert_eq!(base(2), Some("native"));
        assert_eq!(base(0), None);
    }

    #[test]
    fn a_skipped_baseline_is_no_baseline() {
        let mut native = result("native", &[1.0]);
        native.status = Status::Skipped { reason: "x".into() };
        let results = vec![native, result("upscale", &[0.5])];
        assert!(of(InRun {
            results: &results,
            r: &results[1],
        })
        .is_none());
    }
}
