//! The GPU metrics back end of the evaluate stage: [`GpuEvaluator`] computes the scenario's
//! metrics with `tessera-metrics-gpu` on the device that rendered the frames (one
//! `GpuMetrics` per device, kept on [`Gpu`]), and the saved frames' FLIP heat maps with them.
//! Records are built as the CPU's (`metrics::record`) and say `metrics_device = "gpu"`.
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
            Ok(Ok((records, error_maps))) => {
                let mut out = Evaluation {
                    metrics: records,
                    error_maps: Some(error_maps),
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

type Records = (Vec<MetricRecord>, Vec<ErrorMap>);

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
        let n = inputs.test.len().min(r.frames.len());
        let want = |k: MetricKind| scenario.metrics.contains(&k);
        let hdr_maps =
            reference::keep_hdr(scenario) && r.hdr.len() >= n && inputs.test_hdr.len() >= n;
        let saved = |i: usize| scenario.save_frames.contains(&(i as u32));
        let request = |i: usize| PairRequest {
            mse_rgb: want(MetricKind::Psnr),
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
        let seq = Sequence {
            reference: &r.frames[..n],
            test: inputs.test,
            reference_hdr: &r.hdr,
            test_hdr: inputs.test_hdr,
        };
        let values = match backend.sequence(seq, &request, want(MetricKind::Flicker)) {
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
                    let indices = (1..inputs.test.len() as u32).collect();
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
                        let (tp, tt) = (&inputs.test[t - 1], &inputs.test[t]);
                        let (rp, rt) = (&r.frames[t - 1], &r.frames[t]);
                        match backend.tde(tp, tt, rp, rt, &m.motion, &m.valid) {
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
        Ok(Ok((records, maps)))
    }
}
