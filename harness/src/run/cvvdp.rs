//! The `cvvdp` metric of one variant: ColorVideoVDP of its measured frames against the
//! reference's, as a video at the scenario's frame rate (`1 / time_step`) on its `display`,
//! scored per shot across camera cuts, with the maps of saved frames.
//!
//! For: turning a scenario and two frame sequences into metric records, on the CPU
//! ([`records`]) or on the device that rendered them ([`records_on`]: `GpuMetrics::cvvdp`,
//! falling back to the CPU when the device cannot take the work); each record says which back end
//! computed it (`metrics_device`). Not for: the metric itself (`tessera_metrics::cvvdp`,
//! `tessera_metrics_gpu`) or saving images (the caller does, as for other extras). Called once
//! the variant's frames are all rendered, so it never overlaps timed GPU work.

use tessera_metrics::{
    CvvdpResult, CvvdpSettings, DistortionMap, Frames, HdrImage, MetricsError, Rgb8Image,
    DEFAULT_HDR_WHITE,
};
use tessera_metrics_gpu::{GpuMetrics, GpuMetricsError};
use tessera_results::measure::Measure;
use tessera_results::MetricRecord;

use super::plan::Plan;
use crate::metric::cvvdp::CVVDP_MEASURES;

/// Records `cvvdp` (JOD), `cvvdp-flicker` (the transient channel's JOD) and
/// `cvvdp-transient-share`, each with per-frame values, and the maps of the saved frames,
/// computed on the CPU.
pub fn records(
    plan: &Plan<'_>,
    reference: (&[Rgb8Image], &[HdrImage]),
    test: (&[Rgb8Image], &[HdrImage]),
) -> Result<(Vec<MetricRecord>, Vec<DistortionMap>), MetricsError> {
    records_on(plan, reference, test, None)
}

/// [`records`] on `gpu` when given. A device that cannot take the work (a plane beyond its
/// limits, a device error) leaves it to the CPU, with a note, and the records say `"cpu"`; input
/// the metric refuses is the same error on both.
pub fn records_on(
    plan: &Plan<'_>,
    reference: (&[Rgb8Image], &[HdrImage]),
    test: (&[Rgb8Image], &[HdrImage]),
    gpu: Option<&mut GpuMetrics>,
) -> Result<(Vec<MetricRecord>, Vec<DistortionMap>), MetricsError> {
    let scenario = plan.scenario;
    let n = reference.0.len().min(test.0.len());
    let settings = CvvdpSettings {
        display: scenario.display.clone(),
        fps: 1.0 / scenario.time_step,
        cuts: plan.cvvdp_cuts().into_iter().filter(|&c| c < n).collect(),
        map_frames: scenario
            .save_frames
            .iter()
            .map(|&f| f as usize)
            .filter(|&f| f < n)
            .collect(),
        ..CvvdpSettings::default()
    };
    let white = DEFAULT_HDR_WHITE;
    let linear = plan.display_linear && reference.1.len() >= n && test.1.len() >= n;
    let (rf, tf) = if linear {
        (
            Frames::Linear {
                frames: &reference.1[..n],
                white,
            },
            Frames::Linear {
                frames: &test.1[..n],
                white,
            },
        )
    } else {
        (Frames::Srgb(&reference.0[..n]), Frames::Srgb(&test.0[..n]))
    };
    let (r, device): (CvvdpResult, &str) = match gpu {
        Some(g) => match g.cvvdp(rf, tf, &settings) {
            Ok(r) => (r, "gpu"),
            Err(GpuMetricsError::Metrics(e)) => return Err(e),
            Err(e) => {
                eprintln!(
                    "note: ColorVideoVDP on the GPU unavailable ({e}); computing it on the CPU"
                );
                (tessera_metrics::cvvdp(rf, tf, &settings)?, "cpu")
            }
        },
        None => (tessera_metrics::cvvdp(rf, tf, &settings)?, "cpu"),
    };
    let frames: Vec<u32> = (0..n as u32).collect();
    let record = |m: Measure, per_frame: Vec<f64>, value: f64| MetricRecord {
        name: m.name().to_string(),
        frame_stats: super::summary::frame_stats(&per_frame),
        frames: frames[..per_frame.len()].to_vec(),
        per_frame,
        value,
        higher_is_better: m.direction().higher_is_better(),
        metrics_device: Some(device.into()),
        check: None,
    };
    let mut out = vec![record(Measure::Cvvdp, r.frame_jod.clone(), r.jod)];
    if let (Some(flicker), Some(share)) = (r.flicker_jod, r.transient_share) {
        out.push(record(
            CVVDP_MEASURES[0],
            r.frame_flicker_jod.clone(),
            flicker,
        ));
        out.push(record(
            CVVDP_MEASURES[1],
            r.frame_transient_share.clone(),
            share,
        ));
    }
    Ok((out, r.maps))
}
