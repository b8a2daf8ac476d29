//! Which numbers of a result become series, and under which measure names. The names are those of
//! `results.csv` (`gpu_ms.median`, `pass.<pass>.gpu_ms.median`, metric names, `speedup`, ...).
//!
//! Pure functions; not for: storing them (see [`super::ingest`]).

use tessera_results::{ScenarioResult, Status, VariantResult};

#[derive(Clone, Debug, PartialEq)]
pub struct Measure {
    pub name: String,
    pub value: f64,
    pub higher_is_better: bool,
}

/// The native variant's median GPU time in a scenario: what `speedup` divides.
pub fn native_gpu_ms(s: &ScenarioResult) -> Option<f64> {
    s.results
        .iter()
        .find(|v| v.technique == "native" && v.status == Status::Ok)
        .and_then(|v| v.gpu_frame_ms.map(|g| g.median))
}

/// `native / variant` median GPU time; `None` without timings or without a native variant.
pub fn speedup(v: &VariantResult, native_gpu_ms: Option<f64>) -> Option<f64> {
    let own = v.gpu_frame_ms?.median;
    let native = native_gpu_ms?;
    (own > 0.0 && native > 0.0).then(|| native / own)
}

/// The series values of one result. Skipped and failed results have none; non-finite values
/// (infinite PSNR of identical frames) are left out.
pub fn measures(v: &VariantResult, native_gpu_ms: Option<f64>) -> Vec<Measure> {
    if v.status != Status::Ok {
        return Vec::new();
    }
    let mut out = Vec::new();
    let mut push = |name: String, value: f64, higher_is_better: bool| {
        if value.is_finite() {
            out.push(Measure {
                name,
                value,
                higher_is_better,
            });
        }
    };
    if let Some(g) = v.gpu_frame_ms {
        push("gpu_ms.median".into(), g.median, false);
    }
    push("cpu_ms.median".into(), v.cpu_frame_ms.median, false);
    for p in &v.passes {
        if let Some(g) = p.gpu_ms {
            push(format!("pass.{}.gpu_ms.median", p.name), g.median, false);
        }
    }
    push("allocated_bytes".into(), v.allocated_bytes as f64, false);
    if v.technique != "native" {
        if let Some(s) = speedup(v, native_gpu_ms) {
            push("speedup".into(), s, true);
        }
    }
    for m in &v.metrics {
        push(m.name.clone(), m.value, m.higher_is_better);
    }
    // Energy per frame where the adapter's sensors recorded it (`results/README.md`, Conditions).
    if let Some(e) = v
        .conditions
        .as_ref()
        .and_then(|c| c.recorded())
        .and_then(|c| c.energy)
    {
        push("energy_mj".into(), e.mj_per_frame, false);
    }
    out
}
