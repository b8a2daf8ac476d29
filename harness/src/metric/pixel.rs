//! The per-pixel error metrics: PSNR (RGB and luma, from the mean squared error) and the largest
//! absolute channel difference. One pass on the GPU (`pixel.wgsl`), `tessera_metrics::pixel` on
//! the CPU.

use tessera_results::measure::Measure;

use super::{Aggregate, MetricDef, MetricKind, Needs, Values};

pub const PSNR: MetricDef = MetricDef {
    kind: MetricKind::Psnr,
    measure: Measure::Psnr,
    needs: Needs::NONE,
    values: Values::Pair {
        ask: |r, _| r.mse_rgb = true,
        read: |v| v.mse_rgb,
        aggregate: Aggregate::PsnrOfMeanMse,
    },
};

pub const PSNR_LUMA: MetricDef = MetricDef {
    kind: MetricKind::PsnrLuma,
    measure: Measure::PsnrLuma,
    needs: Needs::NONE,
    values: Values::Pair {
        ask: |r, _| r.mse_luma = true,
        read: |v| v.mse_luma,
        aggregate: Aggregate::PsnrOfMeanMse,
    },
};

pub const MAX_ABS_ERROR: MetricDef = MetricDef {
    kind: MetricKind::MaxAbsError,
    measure: Measure::MaxAbsError,
    needs: Needs::NONE,
    values: Values::Pair {
        ask: |r, _| r.max_abs = true,
        read: |v| v.max_abs.map(f64::from),
        aggregate: Aggregate::Max,
    },
};
