//! Series: the finder (`/series`, `/api/series?scenario=&variant=&measure=&adapter=&offset=&limit=`,
//! substring filters, paged, the total in `X-Total-Count`) and one series over runs
//! (`/series/{id}?with=ID,ID`, `/api/series/{id}?format=json|csv`): an interactive chart with the
//! p5-p95 band, other series overlaid, detected change points and driver/harness segments, over a
//! server-drawn SVG and a table that work without JavaScript.

use std::fmt::Write;

use axum::extract::{Path, Query, State};
use axum::http::HeaderValue;
use axum::response::{Html, IntoResponse, Response};
use axum::Json;
use serde::{Deserialize, Serialize};

use super::export::{cell, csv, csv_response, no_markdown, Format, FormatQuery};
use super::{AppError, AppState};
use crate::chart::{time_chart, Mark};
use crate::html::{chart, commit, enc, esc, num, page as layout, pager, pct, script_json};
use crate::store::browse::{self, BandPoint, SeriesFilter, SeriesList};
use crate::store::read::{self, RegressionRow, SeriesKey};
use crate::svg::{colour, series_chart, SeriesMark};

#[derive(Debug, Deserialize, Default)]
pub struct Filter {
    pub scenario: Option<String>,
    pub variant: Option<String>,
    pub adapter: Option<String>,
    pub measure: Option<String>,
    pub offset: Option<i64>,
    pub limit: Option<i64>,
}

impl Filter {
    fn adapter_id(&self) -> Result<Option<i64>, AppError> {
        match self.adapter.as_deref().filter(|a| !a.is_empty()) {
            None => Ok(None),
            Some(a) => a
                .parse()
                .map(Some)
                .map_err(|_| AppError::BadRequest(format!("adapter must be an id, not {a:?}"))),
        }
    }
}

async fn find(state: &AppState, f: &Filter) -> Result<SeriesList, AppError> {
    let filter = SeriesFilter {
        scenario: f.scenario.clone(),
        variant: f.variant.clone(),
        measure: f.measure.clone(),
        adapter: f.adapter_id()?,
    };
    let limit = f.limit.unwrap_or(100).clamp(1, 1000);
    let offset = f.offset.unwrap_or(0).max(0);
    state
        .db(move |c| Ok(browse::series_list(c, &filter, offset, limit)?))
        .await
}

/// The matching series as an array; the number over all pages is in `X-Total-Count`.
pub async fn list_api(
    State(state): State<AppState>,
    Query(f): Query<Filter>,
) -> Result<Response, AppError> {
    let list = find(&state, &f).await?;
    let mut res = Json(list.series).into_response();
    res.headers_mut()
        .insert("x-total-count", HeaderValue::from(list.total));
    Ok(res)
}

pub async fn list_page(
    State(state): State<AppState>,
    Query(f): Query<Filter>,
) -> Result<Html<String>, AppError> {
    let list = find(&state, &f).await?;
    let text = |s: &Option<String>| esc(s.as_deref().unwrap_or(""));
    let mut b = format!(
        "<form id=find>scenario <input name=scenario value=\"{}\" placeholder=\"any part\"> variant <input name=variant value=\"{}\" placeholder=\"any part\"> measure <input name=measure value=\"{}\" placeholder=\"e.g. gpu_ms\"> adapter <select name=adapter><option value=\"\">any</option>",
        text(&f.scenario),
        text(&f.variant),
        text(&f.measure)
    );
    let chosen = f.adapter_id()?;
    for a in &list.adapters {
        let sel = if Some(a.id) == chosen {
            " selected"
        } else {
            ""
        };
        let _ = write!(
            b,
            "<option value={}{sel}>{} ({})</option>",
            a.id,
            esc(&a.name),
            esc(&a.backend)
        );
    }
    b.push_str("</select> <button>find</button> <span class=muted>filters match any part of the name, ignoring case</span></form>");
    let base = format!(
        "/series?scenario={}&variant={}&measure={}&adapter={}&",
        enc(f.scenario.as_deref().unwrap_or("")),
        enc(f.variant.as_deref().unwrap_or("")),
        enc(f.measure.as_deref().unwrap_or("")),
        chosen.map_or(String::new(), |a| a.to_string())
    );
    let pages = pager(
        &base,
        list.offset,
        list.limit,
        list.total,
        list.series.len(),
    );
    b.push_str(&pages);
    b.push_str("<table id=series><tr><th>scenario</th><th>variant</th><th>adapter</th><th>measure</th></tr>");
    for s in &list.series {
        let _ = write!(
            b,
            "<tr><td>{}</td><td><a href=\"/series/{}\">{}</a></td><td>{}</td><td><a href=\"/series/{}\">{}</a></td></tr>",
            esc(&s.scenario),
            s.id,
            esc(&s.variant),
            esc(&s.adapter),
            s.id,
            esc(&s.measure)
        );
    }
    b.push_str("</table>");
    if list.total == 0 {
        b.push_str("<p>No series match.</p>");
    }
    b.push_str(&pages);
    Ok(Html(layout("Series", "series", &b)))
}

#[derive(Debug, Deserialize, Default)]
pub struct View {
    /// Series to overlay, as comma-separated ids.
    pub with: Option<String>,
}

/// One series with its points (and bands), overlays, stored changes and what can be overlaid.
#[derive(Debug, Serialize)]
pub struct SeriesView {
    pub series: SeriesKey,
    pub points: Vec<BandPoint>,
    /// Indices into `points` where the environment (driver, harness version) changes.
    pub segment_starts: Vec<usize>,
    pub regressions: Vec<RegressionRow>,
    pub overlays: Vec<(SeriesKey, Vec<BandPoint>)>,
    pub related: Vec<SeriesKey>,
}

fn parse_ids(with: Option<&str>) -> Result<Vec<i64>, AppError> {
    let mut ids = Vec::new();
    for part in with
        .unwrap_or("")
        .split(',')
        .filter(|p| !p.trim().is_empty())
    {
        ids.push(part.trim().parse::<i64>().map_err(|_| {
            AppError::BadRequest(format!(
                "with= takes series ids separated by commas, not {part:?}"
            ))
        })?);
    }
    ids.truncate(8);
    Ok(ids)
}

async fn load(state: &AppState, id: i64, overlay: Vec<i64>) -> Result<SeriesView, AppError> {
    state
        .db(move |c| {
            // The key and changes only: the points are read once, with their bands.
            let key = browse::series_keys(c, &[id])?
                .pop()
                .ok_or_else(|| AppError::NotFound(format!("series {id} not found")))?;
            let regressions = read::regressions(c, None, Some(id), 1000)?;
            let points = browse::band_points(c, id)?;
            let mut segment_starts = Vec::new();
            for i in 0..points.len() {
                if i == 0 || points[i].environment != points[i - 1].environment {
                    segment_starts.push(i);
                }
            }
            let mut overlays = Vec::new();
            for key in browse::series_keys(c, &overlay)? {
                if key.id != id {
                    let pts = browse::band_points(c, key.id)?;
                    overlays.push((key, pts));
                }
            }
            let related = browse::related_series(c, &key)?;
            Ok(SeriesView {
                series: key,
                points,
                segment_starts,
                regressions,
                overlays,
                related,
            })
        })
        .await
}

/// `format=json` (default): the series with its points and bands; `format=csv`: one row per point.
pub async fn api(
    State(state): State<AppState>,
    Path(id): Path<i64>,
    Query(f): Query<FormatQuery>,
) -> Result<Response, AppError> {
    let v = load(&state, id, Vec::new()).await?;
    match f.format {
        Format::Json => Ok(Json(v).into_response()),
        Format::Csv => {
            let rows: Vec<Vec<String>> = v
                .points
                .iter()
                .map(|p| {
                    vec![
                        p.run_id.clone(),
                        p.commit.clone().unwrap_or_default(),
                        p.started_at.clone(),
                        p.environment.clone(),
                        p.value.to_string(),
                        cell(p.p5),
                        cell(p.p95),
                    ]
                })
                .collect();
            let body = csv(
                &[
                    "run_id",
                    "commit",
                    "started_at",
                    "environment",
                    "value",
                    "p5",
                    "p95",
                ],
                &rows,
            );
            Ok(csv_response(body, &format!("series-{id}.csv")))
        }
        Format::Md => Err(no_markdown()),
    }
}

/// What a series is called in a legend, given the series it is shown with.
fn legend(k: &SeriesKey, main: &SeriesKey) -> String {
    let mut parts = Vec::new();
    if k.variant != main.variant || k.id == main.id {
        parts.push(k.variant.clone());
    }
    if k.adapter_id != main.adapter_id {
        parts.push(k.adapter.clone());
    }
    if k.measure != main.measure {
        parts.push(k.measure.clone());
    }
    if parts.is_empty() {
        parts.push(k.variant.clone());
    }
    parts.join(" · ")
}

pub fn render(v: &SeriesView) -> String {
    let s = &v.series;
    let mut lines: Vec<(String, String, &[BandPoint])> =
        vec![(legend(s, s), colour(0).to_string(), &v.points[..])];
    for (i, (k, pts)) in v.overlays.iter().enumerate() {
        lines.push((legend(k, s), colour(i + 1).to_string(), &pts[..]));
    }
    let (mut spec, rows) = time_chart(&crate::html::axis_label(&s.measure), &lines);
    let row_of = |i: usize| rows[0][i];
    for &i in &v.segment_starts {
        if i > 0 {
            spec.marks.push(Mark {
                at: row_of(i),
                kind: "segment",
                label: v.points[i].environment.clone(),
                short: v.points[i].environment.clone(),
            });
        }
    }
    let index_of = |run: &str| v.points.iter().position(|p| p.run_id == run);
    for r in &v.regressions {
        if let Some(i) = index_of(&r.run_after) {
            spec.marks.push(Mark {
                at: row_of(i),
                kind: "change",
                label: format!(
                    "{} ({:.1}% confidence)",
                    pct(r.relative_change),
                    r.confidence * 100.0
                ),
                short: pct(r.relative_change),
            });
        }
    }
    // The server-drawn fallback: the main series only.
    let marks: Vec<SeriesMark> = v
        .points
        .iter()
        .map(|p| SeriesMark {
            value: p.value,
            tick: commit(p.commit.as_deref()),
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
    let cps: Vec<(usize, String, String)> = v
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
    let segs: Vec<(usize, String)> = v
        .segment_starts
        .iter()
        .map(|&i| (i, v.points[i].environment.clone()))
        .collect();
    let fallback = series_chart(&marks, &cps, &segs, &crate::html::axis_label(&s.measure));
    let banded = spec.series[0].p5.is_some();
    let mut b = format!(
        "<p>{} · {} · <a href=\"/?adapter={}\">{}</a> · {} ({} is better) · {} points{} · export <a href=\"/api/series/{}?format=csv\">CSV</a> <a href=\"/api/series/{}\">JSON</a></p>",
        esc(&s.scenario),
        esc(&s.variant),
        s.adapter_id,
        esc(&s.adapter),
        esc(&s.measure),
        if s.higher_is_better { "higher" } else { "lower" },
        v.points.len(),
        if banded { " · band: p5–p95 of each run's frames" } else { "" },
        s.id,
        s.id
    );
    b.push_str(&chart("series-chart", &script_json(&spec), &fallback));
    // Overlays: links that add or remove a series.
    let current: Vec<i64> = v.overlays.iter().map(|(k, _)| k.id).collect();
    let href = |ids: &[i64]| {
        if ids.is_empty() {
            format!("/series/{}", s.id)
        } else {
            let list: Vec<String> = ids.iter().map(i64::to_string).collect();
            format!("/series/{}?with={}", s.id, list.join("%2C"))
        }
    };
    if !v.related.is_empty() {
        b.push_str(
            "<details id=overlays><summary>overlay other variants, adapters or passes</summary><p>",
        );
        for k in &v.related {
            let on = current.contains(&k.id);
            let ids: Vec<i64> = if on {
                current.iter().copied().filter(|&i| i != k.id).collect()
            } else {
                current.iter().copied().chain([k.id]).collect()
            };
            let _ = write!(
                b,
                "<a href=\"{}\">{}{}</a> · ",
                href(&ids),
                if on { "✓ " } else { "+ " },
                esc(&legend(k, s))
            );
        }
        b.push_str("</p></details>");
    }
    b.push_str("<h2>Detected changes</h2><table id=changes><tr><th>after run</th><th>commit</th><th class=n>before</th><th class=n>after</th><th class=n>change (95% interval)</th><th class=n>located</th><th>state</th></tr>");
    for r in &v.regressions {
        let _ = write!(
            b,
            "<tr><td><a href=\"/runs/{}\">{}</a></td><td><code>{}</code></td><td class=n>{}</td><td class=n>{}</td><td class=\"n {}\" title=\"significance of a change: {:.2}%\">{}{}</td><td class=n>{}</td><td>{}</td></tr>",
            enc(&r.run_after),
            esc(&r.run_after),
            esc(&commit(r.commit_after.as_deref())),
            num(r.value_before),
            num(r.value_after),
            if r.is_regression { "worse" } else { "better" },
            r.confidence * 100.0,
            pct(r.relative_change),
            super::regressions::formats::interval_line(r),
            super::regressions::formats::located_cell(r),
            esc(r.state.as_str())
        );
    }
    b.push_str("</table>");
    // Every point as a table (newest first), the numbers without JavaScript.
    b.push_str("<details id=points-table><summary>points</summary><table id=points><tr><th>run</th><th>commit</th><th>started</th><th class=n>value</th><th class=n>p5</th><th class=n>p95</th><th>environment</th></tr>");
    for p in v.points.iter().rev() {
        let _ = write!(
            b,
            "<tr><td><a href=\"/runs/{}\">{}</a></td><td><code>{}</code></td><td>{}</td><td class=n>{}</td><td class=n>{}</td><td class=n>{}</td><td>{}</td></tr>",
            enc(&p.run_id),
            esc(&p.run_id),
            esc(&commit(p.commit.as_deref())),
            esc(&p.started_at),
            num(p.value),
            p.p5.map_or("–".into(), num),
            p.p95.map_or("–".into(), num),
            esc(&p.environment)
        );
    }
    b.push_str("</table></details>");
    b
}

pub async fn page(
    State(state): State<AppState>,
    Path(id): Path<i64>,
    Query(view): Query<View>,
) -> Result<Html<String>, AppError> {
    let overlay = parse_ids(view.with.as_deref())?;
    let v = load(&state, id, overlay).await?;
    let title = format!(
        "{} · {} · {}",
        v.series.scenario, v.series.variant, v.series.measure
    );
    Ok(Html(layout(&title, "series", &render(&v))))
}
