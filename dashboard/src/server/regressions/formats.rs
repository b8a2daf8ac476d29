//! Regressions as text: a group's Markdown (`/regressions/groups/{id}.md`, for a bot to paste
//! into a pull request) and the one-line summary of an alert.
//! Not for: the Markdown itself (see [`crate::notify::markdown`]) or HTML (see [`super::pages`]).

use axum::http::{header, HeaderMap};
use axum::response::{IntoResponse, Response};

use super::{base_url, load_group};
use crate::html::{num, pct};
use crate::notify;
use crate::server::{AppError, AppState};
use crate::store::read::RegressionRow;

/// A one-line summary of a change: its size with its interval and where it lies, e.g.
/// `tiny · upscale[scale=0.5] · llvmpipe · gpu_ms.median: 3.476 → 3.824 (+10.0%, 95% interval
/// +8.1% to +11.9%, worse); at run b with 62% probability, runs a2 to b`.
pub fn summary(r: &RegressionRow) -> String {
    let interval = interval(r).map_or(String::new(), |i| format!(", 95% interval {i}"));
    let location = match r.location_probability {
        Some(p) => {
            let range = match (&r.first_candidate, &r.last_candidate) {
                (Some(f), Some(l)) if f != l => format!(", runs {f} to {l}"),
                _ => String::new(),
            };
            format!(
                "; at run {} with {:.0}% probability{range}",
                r.run_after,
                p * 100.0
            )
        }
        None => format!("; at run {}", r.run_after),
    };
    format!(
        "{} · {} · {} · {}: {} → {} ({}{interval}, {}){location}",
        r.series.scenario,
        r.series.variant,
        r.series.adapter,
        r.series.measure,
        num(r.value_before),
        num(r.value_after),
        pct(r.relative_change),
        if r.is_regression { "worse" } else { "better" },
    )
}

/// The change's 95% interval, `+8.1% to +11.9%`, where detection stored one.
pub fn interval(r: &RegressionRow) -> Option<String> {
    match (r.change_low, r.change_high) {
        (Some(lo), Some(hi)) => Some(format!("{} to {}", pct(lo), pct(hi))),
        _ => None,
    }
}

/// Where the change lies, as an HTML cell's content: the location probability at its run and,
/// when more than one run is a candidate, the candidate range; "–" where detection stored none.
/// (How sure detection is that *a* change happened is the `title`, not the cell: it reads near
/// 100% for every alert and says nothing about where.)
pub fn located_cell(r: &RegressionRow) -> String {
    let Some(p) = r.location_probability else {
        return "–".to_string();
    };
    let range = match (&r.first_candidate, &r.last_candidate) {
        (Some(f), Some(l)) if f != l => format!(
            "<br><small class=muted>runs {} to {}</small>",
            crate::html::esc(f),
            crate::html::esc(l)
        ),
        _ => "<br><small class=muted>this run only</small>".to_string(),
    };
    format!("{:.0}% at this run{range}", p * 100.0)
}

/// The change cell's second line: its 95% interval, where stored.
pub fn interval_line(r: &RegressionRow) -> String {
    interval(r).map_or(String::new(), |i| {
        format!(
            "<br><small class=muted>95%: {}</small>",
            crate::html::esc(&i)
        )
    })
}

/// The Markdown of group `id`.
pub(super) async fn markdown(
    state: &AppState,
    headers: &HeaderMap,
    id: i64,
) -> Result<Response, AppError> {
    let g = load_group(state, id).await?;
    let md = notify::markdown::render(&g, &base_url(state, headers));
    Ok(([(header::CONTENT_TYPE, "text/markdown; charset=utf-8")], md).into_response())
}
