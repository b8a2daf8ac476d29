//! Evaluation, the second stage of a variant's run (render, evaluate, save, report): captured
//! frames in ([`MetricInputs`]), metric records and metric images out. [`Evaluator`] is the seam
//! a metrics back end plugs into: [`CpuMetrics`] (`tessera-metrics` on the CPU: `metrics.rs`,
//! `cvvdp.rs`) or the GPU's (`gpu_evaluate.rs`), as `metrics_device` picks
//! (`crate::metrics_device::evaluator_for`).
//!
//! Not here: rendering (`frames.rs`, `reference.rs`), saving images (`images.rs`), records
//! (`record.rs`).

use tessera_metrics::DistortionMap;
use tessera_results::MetricRecord;

use super::captured::MetricInputs;
use super::{cvvdp, metrics};
use crate::scenario::{MetricKind, Scenario};

/// What evaluating one variant gives.
#[derive(Default)]
pub struct Evaluation {
    /// The scenario's metrics of the variant against its reference, in the scenario's order
    /// (`cvvdp`'s records last).
    pub metrics: Vec<MetricRecord>,
    /// ColorVideoVDP distortion maps per measured frame, when the scenario measures `cvvdp`.
    pub maps: Vec<DistortionMap>,
    /// The saved frames' FLIP heat maps when the back end made them (the GPU's); `None` lets
    /// `images::save_error_maps` compute them on the CPU.
    pub error_maps: Option<Vec<ErrorMap>>,
    /// Per measured frame, the RGB MSE against the reference, when the back end computed it
    /// with the frames on the device (the stability checks' cut recovery reads it); `None`
    /// lets `stability` compute it from the frames on the CPU.
    pub mse_rgb: Option<Vec<f64>>,
    /// Why evaluation failed (the result is then `failed`); the metrics that were computed are
    /// kept.
    pub error: Option<String>,
}

/// A FLIP heat map of one measured frame: `kind` `heatmap` (LDR-FLIP) or `heatmap-hdr`.
pub struct ErrorMap {
    pub frame: u32,
    pub kind: &'static str,
    pub image: tessera_metrics::Rgb8Image,
}

/// A metrics back end: the scenario's metrics of captured frames against the reference's.
pub trait Evaluator {
    fn evaluate(&self, scenario: &Scenario, inputs: &MetricInputs<'_>) -> Evaluation;
}

/// The metrics of `tessera-metrics`, computed on the CPU.
pub struct CpuMetrics;

impl Evaluator for CpuMetrics {
    fn evaluate(&self, scenario: &Scenario, inputs: &MetricInputs<'_>) -> Evaluation {
        let r = inputs.reference;
        let video = scenario.metrics.contains(&MetricKind::Cvvdp).then(|| {
            cvvdp::records(
                scenario,
                (&r.frames, &r.hdr),
                (inputs.test, inputs.test_hdr),
            )
        });
        match metrics::compute(&scenario.metrics, inputs) {
            Ok(mut m) => {
                let mut out = Evaluation::default();
                match video {
                    Some(Ok((records, maps))) => {
                        m.extend(records);
                        out.maps = maps;
                    }
                    Some(Err(e)) => out.error = Some(format!("metrics: {e}")),
                    None => {}
                }
                out.metrics = m;
                out
            }
            Err(e) => Evaluation {
                error: Some(format!("metrics: {e}")),
                ..Evaluation::default()
            },
        }
    }
}
