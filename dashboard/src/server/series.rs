//! Series: the finder (`/series`, `/api/series?scenario=&variant=&adapter=&measure=`) and one
//! series over commits (`/series/{id}`, `/api/series/{id}`) with detected change points, driver
//! and harness segments, links to each run, and zoom by `?last=N`.

use std::fmt::Write;

use axum::extract::{Path, Query, State};
use axum::response::Html;
use axum::Json;
use serde::Deserialize;

use super::{AppError, AppState};
use crate::html::{commit, enc, esc, num, page as layout, pct};
use crate::store::read::{self, SeriesDetail, SeriesKey};
use crate::svg::{series_chart, SeriesMark};

#[derive(Debug, Deserialize, Default)]
pub struct Filter {
    pub scenario: Option<String>,
    pub variant: Option<String>,
    pub adapter: Option<i64>,
    pub measure: Option<String>,
    pub limit: Option<i64>,
}

fn non_empty(s: &Option<String>) -> Option<String> {
    s.as_ref().filter(|s| !s.is_empty()).cloned()
}

async fn find(state: &AppState, f: Filter) -> Result<Vec<SeriesKey>, AppError> {
    let limit = f.limit.unwrap_or(200).clamp(1, 2000);
    let (s, v, m) = (
        non_empty(&f.scenario),
        non_empty(&f.variant),
        non_empty(&f.measure),
    );
    state
        .db(move |c| {
            Ok(read::find_series(
                c,
                s.as_deref(),
                v.as_deref(),
                f.adapter,
                m.as_deref(),
                limit,
            )?)
        })
        .await
}

pub async fn list_api(
    State(state): State<AppState>,
    Query(f): Query<Filter>,
) -> Result<Json<Vec<SeriesKey>>, AppError> {
    Ok(Json(find(&state, f).await?))
}

pub async fn list_page(
    State(state): State<AppState>,
    Query(f): Query<Filter>,
) -> Result<Html<String>, AppError> {
    let mut f = f;
    if f.measure.is_none() {
        f.measure = Some("gpu_ms.median".into());
    }
    let form = format!(
        "<form>scenario <input name=scenario value=\"{}\"> variant <input name=variant value=\"{}\"> measure <input name=measure value=\"{}\"> <button>find</button></form>",
        esc(f.scenario.as_deref().unwrap_or("")),
        esc(f.variant.as_deref().unwrap_or("")),
        esc(f.measure.as_deref().unwrap_or(""))
    );
    let list = find(&state, f).await?;
    let mut b = form;
    b.push_str("<table><tr><th>scenario</th><th>variant</th><th>adapter</th><th>measure</th></tr>");
    for s in &list {
        let _ = write!(
            b,
            "<tr><td>{}</td><td><a href=\"/series/{}\">{}</a></td><td>{}</td><td>{}</td></tr>",
            esc(&s.scenario),
            s.id,
            esc(&s.variant),
            esc(&s.adapter),
            esc(&s.measure)
        );
    }
    b.push_str("</table>");
    Ok(Html(layout("Series", "series", &b)))
}

#[derive(Debug, Deserialize, Default)]
pub struct Zoom {
    /// Show only the last N points.
    pub last: Option<usize>,
}

async fn load(state: &AppState, id: i64) -> Result<SeriesDetail, AppError> {
    state.db(move |c| Ok(read::series(c, id)?)).await
}

pub async fn api(
    State(state): State<AppState>,
    Path(id): Path<i64>,
) -> Result<Json<SeriesDetail>, AppError> {
    Ok(Json(load(&state, id).await?))
}

pub fn render(d: &SeriesDetail, zoom: &Zoom) -> String {
    let s = &d.series;
    let from = zoom.last.map_or(0, |n| d.points.len().saturating_sub(n));
    let pts = &d.points[from..];
    let marks: Vec<SeriesMark> = pts
        .iter()
        .map(|p| SeriesMark {
            value: p.value,
            label: format!(
                "{} {} {}: {}",
                commit(p.commit.as_deref()),
                p.run_id,
                p.started_at,
                num(p.value)
            ),
            href: format!("/runs/{}", enc(&p.run_id)),
        })
        .collect();
    let index_of = |run: &str| pts.iter().position(|p| p.run_id == run);
    let cps: Vec<(usize, String, String)> = d
        .regressions
        .iter()
        .filter_map(|r| {
            index_of(&r.run_after).map(|i| {
                (
                    i,
                    format!(
                        "{} ({:.1}% confidence) · {}",
                        pct(r.relative_change),
                        r.confidence * 100.0,
                        r.state
                    ),
                    format!("/regressions#r{}", r.id),
                )
            })
        })
        .collect();
    let segs: Vec<(usize, String)> = d
        .segment_starts
        .iter()
        .filter(|&&i| i >= from)
        .map(|&i| (i - from, d.points[i].environment.clone()))
        .collect();
    let mut b = format!(
        "<p>{} · {} · <a href=\"/?adapter={}\">{}</a> · {} ({} is better) · {} points</p><p>zoom: <a href=\"?\">all</a> <a href=\"?last=100\">last 100</a> <a href=\"?last=30\">last 30</a></p>",
        esc(&s.scenario),
        esc(&s.variant),
        s.adapter_id,
        esc(&s.adapter),
        esc(&s.measure),
        if s.higher_is_better { "higher" } else { "lower" },
        d.points.len()
    );
    b.push_str(&series_chart(&marks, &cps, &segs, &s.measure));
    b.push_str("<h2>Detected changes</h2><table><tr><th>after run</th><th>commit</th><th class=n>before</th><th class=n>after</th><th class=n>change</th><th class=n>confidence</th><th>state</th></tr>");
    for r in &d.regressions {
        let _ = write!(
            b,
            "<tr><td><a href=\"/runs/{}\">{}</a></td><td><code>{}</code></td><td class=n>{}</td><td class=n>{}</td><td class=\"n {}\">{}</td><td class=n>{:.2}%</td><td>{}</td></tr>",
            enc(&r.run_after),
            esc(&r.run_after),
            esc(&commit(r.commit_after.as_deref())),
            num(r.value_before),
            num(r.value_after),
            if r.is_regression { "worse" } else { "better" },
            pct(r.relative_change),
            r.confidence * 100.0,
            esc(&r.state)
        );
    }
    b.push_str("</table>");
    b
}

pub async fn page(
    State(state): State<AppState>,
    Path(id): Path<i64>,
    Query(zoom): Query<Zoom>,
) -> Result<Html<String>, AppError> {
    let d = load(&state, id).await?;
    let title = format!(
        "{} · {} · {}",
        d.series.scenario, d.series.variant, d.series.measure
    );
    Ok(Html(layout(&title, "series", &render(&d, &zoom))))
}
