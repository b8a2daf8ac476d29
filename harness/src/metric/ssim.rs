//! SSIM (RGB and luma) with its Gaussian window (`ssim.wgsl`, `tessera_metrics::ssim`):
//! frames must be at least a window wide and tall.

use tessera_results::measure::Measure;

use super::{Aggregate, MetricDef, MetricKind, Needs, Values};

/// The side of SSIM's window, the smallest frame it measures.
const WINDOW: u32 = tessera_metrics::SSIM_MIN_SIZE;

pub const SSIM: MetricDef = MetricDef {
    kind: MetricKind::Ssim,
    measure: Measure::Ssim,
    needs: Needs {
        min_size: WINDOW,
        ..Needs::NONE
    },
    values: Values::Pair {
        ask: |r, _| r.ssim_rgb = true,
        read: |v| v.ssim_rgb,
        aggregate: Aggregate::Mean,
    },
};

pub const SSIM_LUMA: MetricDef = MetricDef {
    kind: MetricKind::SsimLuma,
    measure: Measure::SsimLuma,
    needs: Needs {
        min_size: WINDOW,
        ..Needs::NONE
    },
    values: Values::Pair {
        ask: |r, _| r.ssim_luma = true,
        read: |v| v.ssim_luma,
        aggregate: Aggregate::Mean,
    },
};
