//! How numbers of a comparison are written, the same on the compare page, in the API's CSV and in
//! the Markdown: `+18.3%`, `[+16.0%, +20.6%]`, `p<0.001`, `4 vs 4 frames`.
//!
//! Not for: escaping (each format escapes its own way).

use crate::stats::TimeChange;

/// A relative change as a signed percentage with one decimal: `+18.3%`; what rounds to zero is
/// `+0.0%`, never `-0.0%`.
pub fn pct(change: f64) -> String {
    let p = change * 100.0;
    format!("{:+.1}%", if p.abs() < 0.05 { 0.0 } else { p })
}

/// `p<0.001` or `p=0.042`.
pub fn p_value(p: f64) -> String {
    if p < 0.001 {
        "p<0.001".to_string()
    } else {
        format!("p={p:.3}")
    }
}

/// The change with its interval: `+18.3% [+16.0%, +20.6%]`, or the change alone without one.
pub fn change_with_interval(t: &TimeChange) -> String {
    match t.interval {
        Some([lo, hi]) => format!("{} [{}, {}]", pct(t.change), pct(lo), pct(hi)),
        None => pct(t.change),
    }
}

/// The verdict with its evidence: `slower (p<0.001)`, `within noise (p=0.481)`, or for too few
/// frames `too few frames (4 vs 4; 5 per side needed)`.
pub fn verdict_with_evidence(t: &TimeChange, frames_needed: usize) -> String {
    match t.verdict {
        crate::stats::TimeVerdict::TooFewFrames => format!(
            "too few frames ({} vs {}; {frames_needed} per side needed)",
            t.frames[0], t.frames[1]
        ),
        v => format!("{} ({})", v.words(), p_value(t.p)),
    }
}
