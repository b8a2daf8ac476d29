//! Per-frame values of one measure summarised for a result (mean, p95, max, standard deviation):
//! what metrics and ColorVideoVDP record beside their aggregate. Pure.

/// The summary of `per_frame`, `None` when it is empty.
pub fn frame_stats(per_frame: &[f64]) -> Option<tessera_results::FrameStats> {
    tessera_metrics::series_stats(per_frame).map(|s| tessera_results::FrameStats {
        mean: s.mean,
        p95: s.p95,
        max: s.max,
        std_dev: s.std_dev,
    })
}
