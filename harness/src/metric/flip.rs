//! NVIDIA's FLIP: LDR-FLIP of the 8-bit frames and HDR-FLIP of the linear ones (exposures from
//! the reference frame), at the default pixels per degree, pooled as flip-evaluator pools its
//! mean (so GPU values continue CPU history). The saved frames' heat maps come from the same
//! request (`run/evaluate.rs`).

use tessera_metrics::DEFAULT_PIXELS_PER_DEGREE;
use tessera_metrics_gpu::{FlipHdrRequest, FlipPooling, FlipRequest, PairRequest};
use tessera_results::measure::Measure;

use super::{Aggregate, FrameAsk, MetricDef, MetricKind, Needs, Values};

pub const FLIP: MetricDef = MetricDef {
    kind: MetricKind::Flip,
    measure: Measure::Flip,
    needs: Needs::NONE,
    values: Values::Pair {
        ask: |r, _| ask_ldr(r, false),
        read: |v| v.flip.as_ref().map(|f| f.mean),
        aggregate: Aggregate::Mean,
    },
};

pub const FLIP_HDR: MetricDef = MetricDef {
    kind: MetricKind::FlipHdr,
    measure: Measure::FlipHdr,
    needs: Needs {
        linear: true,
        ..Needs::NONE
    },
    values: Values::Pair {
        ask: |r, frame| ask_hdr(r, frame, false),
        read: |v| v.flip_hdr.as_ref().map(|f| f.mean),
        aggregate: Aggregate::Mean,
    },
};

/// The worst pixel: the largest per-pixel LDR-FLIP error of any measured frame (a firefly, a
/// sparkle or a NaN fill that a mean over millions of pixels hides).
pub const FLIP_MAX: MetricDef = MetricDef {
    kind: MetricKind::FlipMax,
    measure: Measure::FlipMax,
    needs: Needs::NONE,
    values: Values::Pair {
        ask: |r, _| ask_ldr(r, false),
        read: |v| v.flip.as_ref().map(|f| f.max),
        aggregate: Aggregate::Max,
    },
};

/// Asks for LDR-FLIP (and its heat map when `heatmap`), keeping a heat map already asked for.
pub fn ask_ldr(request: &mut PairRequest, heatmap: bool) {
    let f = request.flip.get_or_insert(FlipRequest {
        pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
        heatmap: false,
        pooling: FlipPooling::FlipEvaluator,
    });
    f.heatmap |= heatmap;
}

/// Asks for HDR-FLIP at the frame's exposure range (and its heat map when `heatmap`); nothing
/// without a range.
pub fn ask_hdr(request: &mut PairRequest, frame: &FrameAsk, heatmap: bool) {
    let Some(range) = frame.exposure else {
        return;
    };
    let f = request.flip_hdr.get_or_insert(FlipHdrRequest {
        range,
        pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
        heatmap: false,
        pooling: FlipPooling::FlipEvaluator,
    });
    f.heatmap |= heatmap;
}
