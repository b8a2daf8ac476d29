//! Tessera's image metrics, each defined once, as techniques are: its name, unit, direction and
//! tolerance (its [`Measure`] row in `tessera-results`), what it needs of the frames, how its
//! per-frame values are asked of and read from either metrics back end (the CPU reference
//! implementations of `tessera-metrics` and the GPU passes of `tessera-metrics-gpu`, both behind
//! `tessera_metrics_gpu::MetricsBackend`), and how they aggregate. [`METRICS`] is the one list.
//!
//! For: the scenario's `metrics = [...]` names, what a run keeps for them, and the evaluate
//! stage (`run/evaluate.rs`), which computes every metric through these definitions. Not for:
//! the metrics' mathematics (`tessera-metrics`, `tessera-metrics-gpu`) or records and images
//! (`run/`). See "Adding a metric" in `harness/README.md`.

pub mod cvvdp;
pub mod flicker;
pub mod flip;
pub mod pixel;
pub mod ssim;
pub mod tde;

use tessera_metrics::ExposureRange;
use tessera_metrics_gpu::{PairRequest, PairValues};
use tessera_results::measure::Measure;

/// Image metrics a scenario can ask for, by the names of `metrics = [...]`; each has one
/// definition in [`METRICS`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MetricKind {
    Psnr,
    PsnrLuma,
    MaxAbsError,
    Ssim,
    SsimLuma,
    Flip,
    /// Static-scene flicker: mean absolute change between consecutive output frames.
    Flicker,
    /// HDR-FLIP on the linear output, exposures from the reference frame.
    FlipHdr,
    /// The largest per-pixel LDR-FLIP error of the sequence.
    FlipMax,
    /// Temporal difference error with the renderer's exact motion (notes/metrics.md 3.3).
    Tde,
    /// ColorVideoVDP in JOD on the scenario's `display`, plus its perceptual-flicker measures.
    Cvvdp,
}

/// Every metric, in the order `tessera` lists them.
pub const METRICS: [&MetricDef; 11] = [
    &pixel::PSNR,
    &pixel::PSNR_LUMA,
    &pixel::MAX_ABS_ERROR,
    &ssim::SSIM,
    &ssim::SSIM_LUMA,
    &flip::FLIP,
    &flicker::FLICKER,
    &flip::FLIP_HDR,
    &flip::FLIP_MAX,
    &tde::TDE,
    &cvvdp::CVVDP,
];

/// One metric's definition.
pub struct MetricDef {
    pub kind: MetricKind,
    /// Its row in the measure table: name, unit, direction, label, tolerance.
    pub measure: Measure,
    pub needs: Needs,
    pub values: Values,
}

/// What a metric needs beyond the 8-bit frames of the variant and its reference.
#[derive(Clone, Copy, Debug)]
pub struct Needs {
    /// Linear (HDR) frames of both, and the reference's exposure range per frame.
    pub linear: bool,
    /// The renderer's exact motion between consecutive frames.
    pub motion: bool,
    /// The frames as the scenario's display model takes them (linear on an HDR display).
    pub display: bool,
    /// Frames at least this many pixels wide and tall.
    pub min_size: u32,
}

impl Needs {
    /// Nothing beyond the 8-bit frames.
    pub const NONE: Needs = Needs {
        linear: false,
        motion: false,
        display: false,
        min_size: 0,
    };
}

/// How a metric's values come.
pub enum Values {
    /// One value per measured frame of the (reference, variant) pair from either back end's pair
    /// pass: `ask` adds what it needs to frame `i`'s request, `read` takes its value back.
    Pair {
        ask: fn(&mut PairRequest, &FrameAsk),
        read: fn(&PairValues) -> Option<f64>,
        aggregate: Aggregate,
    },
    /// One value per consecutive pair of the variant's own frames (flicker).
    Consecutive,
    /// One value per measured frame with motion from the previous one in the same shot (TDE).
    Motion,
    /// A video metric over the whole sequence on the display model, with records of its own
    /// (`run/cvvdp.rs`).
    Video,
}

/// What a metric's `ask` knows of frame `i`.
pub struct FrameAsk {
    /// The reference frame's HDR-FLIP exposure range, when linear frames are kept.
    pub exposure: Option<ExposureRange>,
}

/// How per-frame values become the metric's value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Aggregate {
    /// The per-frame values are MSEs: the value is the PSNR of their mean (the PSNR of the
    /// sequence), each frame's its own PSNR.
    PsnrOfMeanMse,
    /// The largest.
    Max,
    /// The mean.
    Mean,
}

impl MetricKind {
    /// Every metric, in [`METRICS`]' order.
    pub const ALL: [MetricKind; METRICS.len()] = {
        let mut all = [MetricKind::Psnr; METRICS.len()];
        let mut i = 0;
        while i < METRICS.len() {
            all[i] = METRICS[i].kind;
            i += 1;
        }
        all
    };
    /// What a scenario measures when it names nothing.
    pub const DEFAULT: [MetricKind; 3] = [
        MetricKind::Psnr,
        MetricKind::PsnrLuma,
        MetricKind::MaxAbsError,
    ];

    /// Its definition.
    pub fn def(self) -> &'static MetricDef {
        METRICS
            .iter()
            .find(|d| d.kind == self)
            .expect("every metric kind is in METRICS (the `every_kind_has_one_definition` test)")
    }

    /// The measure this metric records (its name, unit, direction and tolerance are defined
    /// there).
    pub fn measure(self) -> Measure {
        self.def().measure
    }

    /// The name in `metrics = [...]`, gates, the CSV and the store: the measure's.
    pub fn name(self) -> &'static str {
        self.measure().name()
    }

    pub fn higher_is_better(self) -> bool {
        self.measure().direction().higher_is_better()
    }

    /// The metric called `name`.
    pub fn from_name(name: &str) -> Option<MetricKind> {
        MetricKind::ALL.into_iter().find(|m| m.name() == name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kind_has_one_definition() {
        for kind in MetricKind::ALL {
            assert_eq!(METRICS.iter().filter(|d| d.kind == kind).count(), 1);
            assert!(
                kind.measure().is_metric(),
                "{} is a metric measure",
                kind.name()
            );
        }
        let mut names: Vec<&str> = MetricKind::ALL.iter().map(|m| m.name()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), METRICS.len(), "names are unique");
    }
}
