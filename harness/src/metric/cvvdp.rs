//! ColorVideoVDP: the sequence as a video at the scenario's frame rate on its display model,
//! scored per shot across camera cuts, in JOD, with its transient channel's own JOD and share
//! (`run/cvvdp.rs` makes the records; `tessera_metrics::cvvdp` and `GpuMetrics::cvvdp` compute).

use tessera_results::measure::Measure;

use super::{MetricDef, MetricKind, Needs, Values};

/// The measures `cvvdp` records besides `cvvdp` (JOD): the transient channel's own JOD (higher
/// is better) and its share of the visible difference (lower is better).
pub const CVVDP_MEASURES: [Measure; 2] = [Measure::CvvdpFlicker, Measure::CvvdpTransientShare];

/// Whether `display` takes linear frames (an HDR display: its colour space is not sRGB, e.g.
/// `standard_hdr_linear`); SDR displays take the 8-bit sRGB output.
pub fn uses_linear(display: &tessera_metrics::DisplaySpec) -> bool {
    display.model().is_ok_and(|m| m.color_space != "sRGB")
}

pub const CVVDP: MetricDef = MetricDef {
    kind: MetricKind::Cvvdp,
    measure: Measure::Cvvdp,
    needs: Needs {
        display: true,
        ..Needs::NONE
    },
    values: Values::Video,
};
