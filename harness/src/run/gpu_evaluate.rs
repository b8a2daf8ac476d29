//! The GPU metrics back end of the evaluate stage: [`GpuEvaluator`] computes the scenario's
//! metrics with `tessera-metrics-gpu` on the device that rendered the frames (one
//! `GpuMetrics` per device, kept on [`Gpu`]), and the saved frames' FLIP heat maps with them.
//! Records are built as the CPU's (`metrics::record`) and say `metrics_device = "gpu"`.
//!
//! The frames are those the capture kept on the device (`MetricInputs::test_gpu`, the
//! reference's `gpu`): nothing but values and the saved frames' heat maps comes back. Frames
//! read back instead (they did not fit the device's buffers) are uploaded.
//!
//! ColorVideoVDP runs on the same device (`cvvdp::records_on`). Not here: choosing the back
//! end (`metrics_device.rs`), saving images (`images.rs`). When the GPU cannot take a variant (a
//! buffer beyond the device's limits, a device error) the CPU evaluates it and its records say
//! `"cpu"`.

use tessera_metrics::DEFAULT_PIXELS_PER_DEGREE;
use tessera_metrics_gpu::{
    FlipHdrRequest, FlipPooling, FlipRequest, GpuMetricsError, MetricsBackend, PairRequest,
    Sequence,
};
use tessera_results::MetricRecord;

use super::captured::MetricInputs;
use super::evaluate::{CpuMetrics, ErrorMap, Evaluation, Evaluator};
use super::{cvvdp, metrics, reference};
use crate::gpu::Gpu;
use crate::metrics_device::Backend;
use crate::scenario::{MetricKind, Scenario};

/// The scenario's metrics on the GPU.
pub struct GpuEvaluator<'a> {
    pub gpu: &'a Gpu,
}

impl Evaluator for GpuEvaluator<'_> {
    fn evaluate(&self, scenario: &Scenario, inputs: &MetricInputs<'_>) -> Evaluation {
        match self.metrics(scenario, inputs) {
            Ok(Ok((records, error_maps, mse))) => {
                let mut out = Evaluation {
                    metrics: records,
                    error_maps: Some(error_maps),
                    mse_rgb: mse,
                    ..Evaluation::default()
                };
                if scenario.metrics.contains(&MetricKind::Cvvdp) {
                    let r = inputs.reference;
                    match cvvdp::records_on(
                        scenario,
                        (&r.frames, &r.hdr),
                        (inputs.test, inputs.test_hdr),
                        Some(&mut self.gpu.metrics()),
                    ) {
                        Ok((records, maps)) => {
                            out.metrics.extend(records);
                            out.maps = maps;
                        }
                        Err(e) => out.error = Some(format!("metrics: {e}")),
                    }
                }
                out
            }
            // Bad input for the metric: the same error the CPU would report.
            Ok(Err(message)) => Evaluation {
                error: Some(message),
                ..Evaluation::default()
            },
            Err(e) => {
                eprintln!("note: GPU metrics unavailable ({e}); computing them on the CPU");
                CpuMetrics.evaluate(scenario, inputs)
            }
        }
    }
}

/// Records, the saved frames' heat maps, and per-frame RGB MSE (frames on the device only).
type Records = (Vec<MetricRecord>, Vec<ErrorMap>, Option<Vec<f64>>);

impl GpuEvaluator<'_> {
    /// `Err` when the GPU back end cannot run (fall back to the CPU); `Ok(Err)` for input the
    /// metrics refuse.
    fn metrics(
        &self,
        scenario: &Scenario,
        inputs: &MetricInputs<'_>,
    ) -> Result<Result<Records, String>, GpuMetricsError> {
        let mut backend = self.gpu.metrics();
        let r = inputs.reference;
        // The frames on the device, when the capture kept them there.
        let on_device = !inputs.test_gpu.is_empty() && r.gpu.len() >= inputs.test_gpu.len();
        let (n, test_count) = if on_device {
            (inputs.test_gpu.len(), inputs.test_gpu.len())
        } else {
            (inputs.test.len().min(r.frames.len()), inputs.test.len())
        };
        let want = |k: MetricKind| scenario.metrics.contains(&k);
        let hdr_maps = reference::keep_hdr(scenario)
            && r.exposures.len() >= n
            && if on_device {
                inputs.test_gpu.iter().all(|f| f.has_hdr()) && r.gpu.iter().all(|f| f.has_hdr())
            } else {
                r.hdr.len() >= n && inputs.test_hdr.len() >= n
            };
        let saved = |i: usize| scenario.save_frames.contains(&(i as u32));
        // The stability checks' cut recovery reads the MSE of every frame.
        let cut_mse = on_device && !super::stability::cut_frames(scenario).is_empty();
        let request = |i: usize| PairRequest {
            mse_rgb: want(MetricKind::Psnr) || cut_mse,
            mse_luma: want(MetricKind::PsnrLuma),
            max_abs: want(MetricKind::MaxAbsError),
            ssim_rgb: want(MetricKind::Ssim),
            ssim_luma: want(MetricKind::SsimLuma),
            // Pooled as flip-evaluator (and the CPU back end): the values continue CPU history.
            flip: (want(MetricKind::Flip) || saved(i)).then(|| FlipRequest {
                pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
                heatmap: saved(i),
                pooling: FlipPooling::FlipEvaluator,
            }),
            flip_hdr: ((want(MetricKind::FlipHdr) || (hdr_maps && saved(i)))
                && i < r.exposures.len())
            .then(|| FlipHdrRequest {
                range: r.exposures[i],
                pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
                heatmap: hdr_maps && saved(i),
                pooling: FlipPooling::FlipEvaluator,
            }),
        };
        let flicker = want(MetricKind::Flicker);
        let values = if on_device {
            // What the CPU checks of the images: HDR-FLIP takes finite values only (the
            // capture counted them).
            if let Some(e) = (0..n).find_map(|i| hdr_non_finite(&request(i), inputs, i)) {
                return Ok(Err(format!("metrics: {e}")));
            }
            backend.sequence_frames(&r.gpu[..n], inputs.test_gpu, &request, flicker)
        } else {
            let seq = Sequence {
                reference: &r.frames[..n],
                test: inputs.test,
                reference_hdr: &r.hdr,
                test_hdr: inputs.test_hdr,
            };
            backend.sequence(seq, &request, flicker)
        };
        let values = match values {
            Ok(v) => v,
            Err(GpuMetricsError::Metrics(e)) => return Ok(Err(format!("metrics: {e}"))),
            Err(e) => return Err(e),
        };
        let frames: Vec<u32> = (0..n as u32).collect();
        let mut records = Vec::new();
        for &kind in &scenario.metrics {
            let per_frame = |f: &dyn Fn(&tessera_metrics_gpu::PairValues) -> Option<f64>| {
                values
                    .frames
                    .iter()
                    .map(|v| f(v).unwrap_or(f64::NAN))
                    .collect()
            };
            let per_frame: Vec<f64> = match kind {
                MetricKind::Cvvdp => continue,
                MetricKind::Flicker => {
                    let v = values.flicker.clone().unwrap_or_default();
                    let indices = (1..test_count as u32).collect();
                    records.push(metrics::record(kind, indices, v, Backend::Gpu));
                    continue;
                }
                MetricKind::Tde => {
                    let motion = match inputs.motion {
                        Ok(m) => m,
                        Err(e) => return Ok(Err(format!("metrics: no motion for tde: {e}"))),
                    };
                    let (mut idx, mut v) = (Vec::new(), Vec::new());
                    for t in 1..n {
                        let Some(Some(m)) = motion.get(t) else {
                            continue;
                        };
                        let tde = if on_device {
                            let (tp, tt) = (&inputs.test_gpu[t - 1], &inputs.test_gpu[t]);
                            let (rp, rt) = (&r.gpu[t - 1], &r.gpu[t]);
                            backend.tde_frames(tp, tt, rp, rt, &m.motion, &m.valid)
                        } else {
                            let (tp, tt) = (&inputs.test[t - 1], &inputs.test[t]);
                            let (rp, rt) = (&r.frames[t - 1], &r.frames[t]);
                            backend.tde(tp, tt, rp, rt, &m.motion, &m.valid)
                        };
                        match tde {
                            Ok(Some(x)) => {
                                idx.push(t as u32);
                                v.push(x);
                            }
                            Ok(None) => {}
                            Err(GpuMetricsError::Metrics(e)) => {
                                return Ok(Err(format!("metrics: {e}")))
                            }
                            Err(e) => return Err(e),
                        }
                    }
                    records.push(metrics::record(kind, idx, v, Backend::Gpu));
                    continue;
                }
                MetricKind::Psnr => per_frame(&|v| v.mse_rgb),
                MetricKind::PsnrLuma => per_frame(&|v| v.mse_luma),
                MetricKind::MaxAbsError => per_frame(&|v| v.max_abs.map(f64::from)),
                MetricKind::Ssim => per_frame(&|v| v.ssim_rgb),
                MetricKind::SsimLuma => per_frame(&|v| v.ssim_luma),
                MetricKind::Flip => per_frame(&|v| v.flip.as_ref().map(|f| f.mean)),
                MetricKind::FlipHdr => per_frame(&|v| v.flip_hdr.as_ref().map(|f| f.mean)),
            };
            records.push(metrics::record(
                kind,
                frames.clone(),
                per_frame,
                Backend::Gpu,
            ));
        }
        let mse = on_device.then(|| {
            values
                .frames
                .iter()
                .map(|v| v.mse_rgb.unwrap_or(f64::NAN))
                .collect()
        });
        let mut maps = Vec::new();
        for (i, v) in values.frames.into_iter().enumerate() {
            for (kind, f) in [("heatmap", v.flip), ("heatmap-hdr", v.flip_hdr)] {
                if let Some(image) = f.and_then(|f| f.heatmap) {
                    maps.push(ErrorMap {
                        frame: i as u32,
                        kind,
                        image,
                    });
                }
            }
        }
        Ok(Ok((records, maps, mse)))
    }
}

/// The error HDR-FLIP gives on the CPU for frame `i` with non-finite values (the reference's
/// first), when `request` asks for HDR-FLIP.
fn hdr_non_finite(
    request: &PairRequest,
    inputs: &MetricInputs<'_>,
    i: usize,
) -> Option<tessera_metrics::MetricsError> {
    request.flip_hdr.as_ref()?;
    let counts = [
        ("reference", inputs.reference.non_finite.get(i)),
        ("test", inputs.test_non_finite.get(i)),
    ];
    counts.into_iter().find_map(|(image, count)| {
        let count = *count? as usize;
        (count > 0).then_some(tessera_metrics::MetricsError::NonFinite { image, count })
    })
}
