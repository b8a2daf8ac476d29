//! Temporal difference error (notes/metrics.md 3.3, item 1): per measured frame that has the
//! renderer's exact motion from a previous measured frame in the same shot, the error of the
//! variant's frame-to-frame change against the reference's; the value is the mean over those
//! frames. Either back end's `tde`.

use tessera_results::measure::Measure;

use super::{MetricDef, MetricKind, Needs, Values};

pub const TDE: MetricDef = MetricDef {
    kind: MetricKind::Tde,
    measure: Measure::Tde,
    needs: Needs {
        motion: true,
        ..Needs::NONE
    },
    values: Values::Motion,
};
