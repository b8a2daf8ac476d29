//! Evaluation, the second stage of a variant's run (render, evaluate, save, report): captured
//! frames in ([`MetricInputs`]), metric records and metric images out. Every metric is computed
//! through its definition (`crate::metric`) on one of the two back ends of
//! `tessera_metrics_gpu::MetricsBackend`, as the plan's `backend` says: `tessera-metrics` on the
//! CPU, or the GPU passes on the device that rendered the frames (frames kept there are never
//! read back; frames read back instead are uploaded). Records say which back end computed them
//! (`metrics_device`). When the GPU cannot take a variant (a buffer beyond the device's limits, a
//! device error) the CPU evaluates it and its records say `"cpu"`.
//!
//! Not here: rendering (`frames.rs`, `reference.rs`), saving images (`images.rs`), records
//! (`record.rs`), ColorVideoVDP's records (`cvvdp.rs`).

use tessera_metrics::DistortionMap;
use tessera_metrics_gpu::{
    CpuMetrics, GpuMetrics, GpuMetricsError, MetricsBackend, PairRequest, PairValues, Sequence,
    SequenceValues,
};
use tessera_results::MetricRecord;

use super::captured::MetricInputs;
use super::metrics::record;
use super::plan::Plan;
use crate::gpu::Gpu;
use crate::metric::{flip, FrameAsk, MetricDef, MetricKind, Values};
use crate::metrics_device::Backend;

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

/// The scenario's metrics of the variant in `inputs` against its reference, on the plan's back
/// end (`gpu`'s metrics for the GPU).
pub fn evaluate(gpu: &Gpu, plan: &Plan<'_>, inputs: &MetricInputs<'_>) -> Evaluation {
    let on_gpu = plan.backend == Backend::Gpu;
    let pair = if on_gpu {
        let pair = pair_metrics(&mut Engine::Gpu(&mut gpu.metrics()), plan, inputs);
        match pair {
            Err(e) => {
                eprintln!("note: GPU metrics unavailable ({e}); computing them on the CPU");
                return evaluate(gpu, &plan.on_cpu(), inputs);
            }
            Ok(p) => p,
        }
    } else {
        pair_metrics(&mut Engine::Cpu(CpuMetrics), plan, inputs)
            .unwrap_or_else(|e| Err(format!("metrics: {e}")))
    };
    let mut out = match pair {
        Ok(p) => Evaluation {
            metrics: p.records,
            error_maps: on_gpu.then_some(p.error_maps),
            mse_rgb: p.mse,
            ..Evaluation::default()
        },
        // Bad input for the metric: the same error on both back ends.
        Err(error) => {
            return Evaluation {
                error: Some(error),
                ..Evaluation::default()
            }
        }
    };
    if plan.scenario.metrics.contains(&MetricKind::Cvvdp) {
        let _span = super::phases::span("metrics: cvvdp");
        let r = inputs.reference;
        let mut device = on_gpu.then(|| gpu.metrics());
        match super::cvvdp::records_on(
            plan,
            (&r.frames, &r.hdr),
            (inputs.test, inputs.test_hdr),
            device.as_deref_mut(),
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

/// The back end that computes the per-frame metrics.
enum Engine<'a> {
    Cpu(CpuMetrics),
    /// The GPU's, which also takes frames that stayed on the device.
    Gpu(&'a mut GpuMetrics),
}

impl Engine<'_> {
    fn backend(&mut self) -> &mut dyn MetricsBackend {
        match self {
            Engine::Cpu(c) => c,
            Engine::Gpu(g) => *g,
        }
    }

    fn name(&self) -> Backend {
        match self {
            Engine::Cpu(_) => Backend::Cpu,
            Engine::Gpu(_) => Backend::Gpu,
        }
    }
}

/// The per-frame metrics' records, the saved frames' heat maps (GPU only), and per-frame RGB MSE
/// (frames on the device only).
struct PairMetrics {
    records: Vec<MetricRecord>,
    error_maps: Vec<ErrorMap>,
    mse: Option<Vec<f64>>,
}

/// What the metrics read of frame pairs: the frames on the device when the capture kept them
/// there, else those on the CPU.
struct Frames<'a, 'b> {
    inputs: &'b MetricInputs<'a>,
    on_device: bool,
    /// Measured frames compared.
    n: usize,
}

/// Every metric of the scenario but `cvvdp`, on `engine`. `Err` when the GPU back end cannot
/// run (the caller falls back to the CPU); `Ok(Err)` for input the metrics refuse.
fn pair_metrics(
    engine: &mut Engine<'_>,
    plan: &Plan<'_>,
    inputs: &MetricInputs<'_>,
) -> Result<Result<PairMetrics, String>, GpuMetricsError> {
    let r = inputs.reference;
    let on_device = matches!(engine, Engine::Gpu(_))
        && !inputs.test_gpu.is_empty()
        && r.gpu.len() >= inputs.test_gpu.len();
    let n = if on_device {
        inputs.test_gpu.len()
    } else {
        inputs.test.len().min(r.frames.len())
    };
    let frames = Frames {
        inputs,
        on_device,
        n,
    };
    let request = requests(engine, plan, &frames);
    let values = match sequence_values(engine, plan, &frames, &request) {
        Ok(v) => v,
        Err(GpuMetricsError::Metrics(e)) => return Ok(Err(format!("metrics: {e}"))),
        Err(e) => return Err(e),
    };
    let values = match values {
        Ok(v) => v,
        Err(message) => return Ok(Err(message)),
    };
    let mut records = Vec::new();
    for &kind in &plan.scenario.metrics {
        let def = kind.def();
        match per_frame(engine, def, &frames, &values) {
            Ok(Some((indices, per_frame))) => {
                records.push(record(def, indices, per_frame, engine.name()))
            }
            Ok(None) => {}
            Err(Ok(message)) => return Ok(Err(message)),
            Err(Err(e)) => return Err(e),
        }
    }
    let mse = on_device.then(|| {
        values
            .frames
            .iter()
            .map(|v| v.mse_rgb.unwrap_or(f64::NAN))
            .collect()
    });
    Ok(Ok(PairMetrics {
        records,
        error_maps: heat_maps(values.frames),
        mse,
    }))
}

/// Frame `i`'s pair request: what each of the scenario's metrics asks, the MSE the stability
/// checks' cut recovery reads (frames on the device), and, on the GPU, the saved frames' heat
/// maps (the CPU makes them from its frames in `images::save_error_maps`).
fn requests<'p>(
    engine: &Engine<'_>,
    plan: &'p Plan<'_>,
    frames: &'p Frames<'_, '_>,
) -> impl Fn(usize) -> PairRequest + 'p {
    let r = frames.inputs.reference;
    let maps = matches!(engine, Engine::Gpu(_));
    let inputs = frames.inputs;
    let hdr_maps = plan.keep_hdr
        && r.exposures.len() >= frames.n
        && if frames.on_device {
            inputs.test_gpu.iter().all(|f| f.has_hdr()) && r.gpu.iter().all(|f| f.has_hdr())
        } else {
            r.hdr.len() >= frames.n && inputs.test_hdr.len() >= frames.n
        };
    let cut_mse = frames.on_device && !plan.cuts.is_empty();
    move |i| {
        let saved = maps && plan.scenario.save_frames.contains(&(i as u32));
        let ask = FrameAsk {
            exposure: r.exposures.get(i).copied(),
        };
        let mut request = PairRequest {
            mse_rgb: cut_mse,
            ..PairRequest::default()
        };
        if saved {
            flip::ask_ldr(&mut request, true);
        }
        if saved && hdr_maps {
            flip::ask_hdr(&mut request, &ask, true);
        }
        for kind in &plan.scenario.metrics {
            if let Values::Pair { ask: ask_for, .. } = kind.def().values {
                ask_for(&mut request, &ask);
            }
        }
        request
    }
}

/// Every frame's pair values (and flicker when asked), from the device's frames or the CPU's.
/// `Ok(Err)`: a frame the metrics refuse (HDR-FLIP of non-finite values, as the CPU checks).
fn sequence_values(
    engine: &mut Engine<'_>,
    plan: &Plan<'_>,
    frames: &Frames<'_, '_>,
    request: &dyn Fn(usize) -> PairRequest,
) -> Result<Result<SequenceValues, String>, GpuMetricsError> {
    let (inputs, n) = (frames.inputs, frames.n);
    let r = inputs.reference;
    let flicker =
        (plan.scenario.metrics.iter()).any(|m| matches!(m.def().values, Values::Consecutive));
    match engine {
        Engine::Gpu(g) if frames.on_device => {
            // What the CPU checks of the images: HDR-FLIP takes finite values only (the
            // capture counted them).
            if let Some(e) = (0..n).find_map(|i| hdr_non_finite(&request(i), inputs, i)) {
                return Ok(Err(format!("metrics: {e}")));
            }
            g.sequence_frames(&r.gpu[..n], inputs.test_gpu, request, flicker)
                .map(Ok)
        }
        _ => {
            let seq = Sequence {
                reference: &r.frames[..n],
                test: inputs.test,
                reference_hdr: &r.hdr,
                test_hdr: inputs.test_hdr,
            };
            engine.backend().sequence(seq, request, flicker).map(Ok)
        }
    }
}

/// A failure of one metric: `Ok` input the metric refuses (its message), `Err` a back end that
/// cannot run.
type MetricFailure = Result<String, GpuMetricsError>;

/// A metric's measured frames and their values.
type PerFrame = (Vec<u32>, Vec<f64>);

/// Metric `def`'s measured frames and per-frame values; `None` for `cvvdp` (its own records).
fn per_frame(
    engine: &mut Engine<'_>,
    def: &MetricDef,
    frames: &Frames<'_, '_>,
    values: &SequenceValues,
) -> Result<Option<PerFrame>, MetricFailure> {
    Ok(Some(match def.values {
        Values::Video => return Ok(None),
        Values::Pair { read, .. } => {
            let v = values
                .frames
                .iter()
                .map(|v: &PairValues| read(v).unwrap_or(f64::NAN))
                .collect();
            ((0..frames.n as u32).collect(), v)
        }
        Values::Consecutive => {
            let v = values.flicker.clone().unwrap_or_default();
            (
                (1..frames.inputs.test.len().max(frames.n) as u32).collect(),
                v,
            )
        }
        Values::Motion => tde(engine, frames)?,
    }))
}

/// TDE of every measured frame with motion from the previous one in the same shot.
fn tde(engine: &mut Engine<'_>, frames: &Frames<'_, '_>) -> Result<PerFrame, MetricFailure> {
    let inputs = frames.inputs;
    let r = inputs.reference;
    let motion = match inputs.motion {
        Ok(m) => m,
        Err(e) => return Err(Ok(format!("metrics: no motion for tde: {e}"))),
    };
    let (mut idx, mut v) = (Vec::new(), Vec::new());
    for t in 1..frames.n {
        let Some(Some(m)) = motion.get(t) else {
            continue;
        };
        let tde = match engine {
            Engine::Gpu(g) if frames.on_device => {
                let (tp, tt) = (&inputs.test_gpu[t - 1], &inputs.test_gpu[t]);
                let (rp, rt) = (&r.gpu[t - 1], &r.gpu[t]);
                g.tde_frames(tp, tt, rp, rt, &m.motion, &m.valid)
            }
            _ => {
                let (tp, tt) = (&inputs.test[t - 1], &inputs.test[t]);
                let (rp, rt) = (&r.frames[t - 1], &r.frames[t]);
                engine.backend().tde(tp, tt, rp, rt, &m.motion, &m.valid)
            }
        };
        match tde {
            Ok(Some(x)) => {
                idx.push(t as u32);
                v.push(x);
            }
            Ok(None) => {}
            Err(GpuMetricsError::Metrics(e)) => return Err(Ok(format!("metrics: {e}"))),
            Err(e) => return Err(Err(e)),
        }
    }
    Ok((idx, v))
}

/// The heat maps the back end made, per frame.
fn heat_maps(values: Vec<PairValues>) -> Vec<ErrorMap> {
    let mut maps = Vec::new();
    for (i, v) in values.into_iter().enumerate() {
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
    maps
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
