//! Status of one variant in two runs (`COMPARISON.md`, "Status"): a failure or a failed gate that
//! is new in B is worse, one that went away is better, and an ok variant that B skips is worse on
//! the same adapter (on another adapter a skip is what that adapter supports).
//!
//! Not for: time or metric verdicts.

use crate::{GateLevel, Status, VariantResult};

use super::findings::Verdict;

/// `ok`, `gate failed`, `skipped: reason`, `failed: error`.
pub fn label(r: &VariantResult) -> String {
    match &r.status {
        Status::Ok if failed_gate(r) => "gate failed".to_string(),
        Status::Ok => "ok".to_string(),
        Status::Skipped { reason } => format!("skipped: {reason}"),
        Status::Failed { error } => format!("failed: {error}"),
    }
}

fn failed_gate(r: &VariantResult) -> bool {
    r.gates.iter().any(|g| g.level == GateLevel::Fail)
}

fn is_failure(r: &VariantResult) -> bool {
    matches!(r.status, Status::Failed { .. }) || failed_gate(r)
}

pub(crate) fn verdict(a: Option<&VariantResult>, b: Option<&VariantResult>, same: bool) -> Verdict {
    match (a, b) {
        (_, Some(y)) if is_failure(y) && !a.is_some_and(is_failure) => Verdict::Worse,
        (Some(x), Some(y)) if is_failure(x) && !is_failure(y) => Verdict::Better,
        (Some(x), Some(y))
            if same && x.status == Status::Ok && matches!(y.status, Status::Skipped { .. }) =>
        {
            Verdict::Worse
        }
        _ => Verdict::Same,
    }
}
