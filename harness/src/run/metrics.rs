//! A variant's metric records: one metric's per-frame values aggregated as its definition says
//! ([`record`]; the values come from `evaluate.rs`), and the technique's own per-frame values
//! ([`extra_values`]).
//!
//! Pure: values in, records out.

use tessera_results::{Check, MetricRecord};

use super::summary::frame_stats;
use crate::metric::{Aggregate, MetricDef, Values};
use crate::metrics_device::Backend;
use crate::render::renderer::{FrameExtras, FrameValue};

/// The record of metric `def` from its per-frame values (for PSNR: the MSEs), aggregated over
/// frames as its definition says: PSNR from the mean MSE (the PSNR of the sequence; per frame
/// from each MSE), max-abs-error as the maximum, the others as the mean. `device` is the back
/// end that computed the values.
pub(super) fn record(
    def: &MetricDef,
    frames: Vec<u32>,
    per_frame: Vec<f64>,
    device: Backend,
) -> MetricRecord {
    let aggregate = match def.values {
        Values::Pair { aggregate, .. } => aggregate,
        _ => Aggregate::Mean,
    };
    let (per_frame, value) = match aggregate {
        Aggregate::PsnrOfMeanMse => {
            let mean_mse = per_frame.iter().sum::<f64>() / per_frame.len().max(1) as f64;
            let psnr: Vec<f64> = per_frame
                .iter()
                .map(|m| tessera_metrics::psnr_from_mse(*m, 255.0))
                .collect();
            (psnr, tessera_metrics::psnr_from_mse(mean_mse, 255.0))
        }
        Aggregate::Max => {
            let max = per_frame.iter().copied().fold(0.0, f64::max);
            (per_frame, max)
        }
        Aggregate::Mean => {
            let mean = per_frame.iter().sum::<f64>() / per_frame.len().max(1) as f64;
            (per_frame, mean)
        }
    };
    MetricRecord {
        name: def.measure.name().to_string(),
        frame_stats: frame_stats(&per_frame),
        metrics_device: Some(device.name().to_string()),
        check: None,
        per_frame,
        frames,
        value,
        higher_is_better: def.measure.direction().higher_is_better(),
    }
}

/// A technique's per-frame extra values (e.g. `shading-rate`) as metrics of the variant's own
/// frames, the value their mean.
pub fn extra_values(extras: &[FrameExtras]) -> Vec<MetricRecord> {
    let mut out = Vec::new();
    let mut first: Vec<FrameValue> = Vec::new();
    for e in extras {
        for v in &e.values {
            if !first.iter().any(|f| f.name == v.name) {
                first.push(*v);
            }
        }
    }
    for kind in first {
        let name = kind.name;
        let (frames, per_frame): (Vec<u32>, Vec<f64>) = extras
            .iter()
            .enumerate()
            .filter_map(|(f, e)| {
                let v = e.values.iter().find(|v| v.name == name)?.value;
                Some((f as u32, v))
            })
            .unzip();
        let value = per_frame.iter().sum::<f64>() / per_frame.len().max(1) as f64;
        out.push(MetricRecord {
            name: name.to_string(),
            frame_stats: frame_stats(&per_frame),
            metrics_device: None,
            // A technique's own values carry their unit and direction themselves: no shared
            // table knows them.
            check: Some(Check {
                unit: kind.unit.to_string(),
                direction: kind.direction,
            }),
            per_frame,
            frames,
            value,
            higher_is_better: kind.direction.higher_is_better(),
        });
    }
    out
}
