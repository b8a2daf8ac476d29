//! Static-scene flicker (notes/metrics.md section 3.3, SSF): per measured frame after the first,
//! the mean absolute difference from the previous frame over pixels and RGB channels, in 8-bit
//! units; the value is the mean over frames. Zero for a converged deterministic technique on a
//! static scene; on moving scenes it measures change, not error. Either back end's `flicker`.

use tessera_results::measure::Measure;

use super::{MetricDef, MetricKind, Needs, Values};

pub const FLICKER: MetricDef = MetricDef {
    kind: MetricKind::Flicker,
    measure: Measure::Flicker,
    needs: Needs::NONE,
    values: Values::Consecutive,
};
