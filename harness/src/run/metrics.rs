//! A variant's metrics: each of the scenario's metrics per measured frame against the reference's
//! frame of the same index, aggregated over frames (PSNR from the mean MSE, max-abs-error as the
//! maximum, the others as the mean); `tde` and `flicker`; and the technique's own per-frame values.
//!
//! Pure: frames in, records out. Rendering is `frames.rs`, the reference `reference.rs`; what they capture for this module,
//! `captured.rs`.

use tessera_metrics::Rgb8Image;
use tessera_results::{Check, MetricRecord};

pub use super::captured::MetricInputs;
use super::motion;
use super::summary::frame_stats;
use crate::metrics_device::Backend;
use crate::render::renderer::{FrameExtras, FrameValue};
use crate::scenario::MetricKind;

#[derive(Debug, thiserror::Error)]
pub enum MetricError {
    #[error("{0}")]
    Metric(#[from] tessera_metrics::MetricsError),
    #[error("no motion for tde: {0}")]
    Motion(String),
}

/// Metrics of every measured frame against the reference's frame of the same index.
pub fn compute(
    metrics: &[MetricKind],
    inputs: &MetricInputs<'_>,
) -> Result<Vec<MetricRecord>, MetricError> {
    let (reference, test) = (&inputs.reference.frames[..], inputs.test);
    let frames: Vec<u32> = (0..test.len().min(reference.len()) as u32).collect();
    let mut out = Vec::new();
    for &kind in metrics {
        // A video metric over the whole sequence, with a display model: `run::cvvdp`.
        if kind == MetricKind::Cvvdp {
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
        out.push(record(kind, frames.clone(), per_frame, Backend::Cpu));
    }
    Ok(out)
}

/// The record of metric `kind` from its per-frame values (for PSNR: the MSEs), aggregated over
/// frames: PSNR from the mean MSE (the PSNR of the sequence; per frame from each MSE),
/// max-abs-error as the maximum, the others as the mean. `device` is the back end that computed
/// the values.
pub(super) fn record(
    kind: MetricKind,
    frames: Vec<u32>,
    per_frame: Vec<f64>,
    device: Backend,
) -> MetricRecord {
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
    MetricRecord {
        name: kind.name().to_string(),
        frame_stats: frame_stats(&per_frame),
        metrics_device: Some(device.name().to_string()),
        check: None,
        per_frame,
        frames,
        value,
        higher_is_better: kind.higher_is_better(),
    }
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
    Ok(record(MetricKind::Tde, frames, per_frame, Backend::Cpu))
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
    let indices = (1..frames.len() as u32).collect();
    record(MetricKind::Flicker, indices, per_frame, Backend::Cpu)
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
