//! One run (`/runs/{run_id}`, `/api/runs/{run_id}?format=json|csv`): per scenario, every variant
//! with its status or skip reason, per-pass GPU time (stacked), speedup against native on the same
//! adapter, the change of GPU time against the previous run of the same suite on the same adapter
//! (the significance test of `tessera compare`), metrics, allocated bytes, links to its series and
//! images, and per-frame charts of each measure (`run_frame_charts.rs`). The CSV export has the
//! columns of the harness's `results.csv`.

use std::fmt::Write;

use axum::extract::{Path, Query, State};
use axum::response::{Html, IntoResponse, Response};
use axum::Json;
use tessera_results::measure::{self, points, Key, Measure, DEFAULT_BASELINE};
use tessera_results::stats::{compare_times, frame_samples, TimeVerdict, DEFAULT_THRESHOLD_PCT};
use tessera_results::{ScenarioResult, Status};

use super::export::{csv, csv_response, no_markdown, Format, FormatQuery};
use super::{AppError, AppState};
use crate::html::{bytes, commit, enc, esc, ms, name, num, page as layout, pct};
use crate::store::browse;
use crate::store::read::{self, RunDetail};
use crate::svg::{stacked_bars, Bar};

async fn load(state: &AppState, run_id: String) -> Result<RunDetail, AppError> {
    state.db(move |c| Ok(read::run(c, &run_id)?)).await
}

/// `format=json` (default): the run with its records; `format=csv`: one row per (scenario,
/// variant, measure), the columns of `results.csv`.
pub async fn api(
    State(state): State<AppState>,
    Path(run_id): Path<String>,
    Query(f): Query<FormatQuery>,
) -> Result<Response, AppError> {
    let d = load(&state, run_id).await?;
    match f.format {
        Format::Json => Ok(Json(d).into_response()),
        Format::Csv => {
            let mut rows = Vec::new();
            for s in &d.scenarios {
                for v in &s.results {
                    let base = [
                        d.run.run_id.clone(),
                        s.scenario.clone(),
                        v.variant.clone(),
                        v.technique.clone(),
                        d.run.adapter.clone(),
                        d.run.backend.clone(),
                        v.status.label().to_string(),
                    ];
                    let ms = points(&s.results, v);
                    if ms.is_empty() {
                        let mut r = base.to_vec();
                        r.extend(["status".into(), String::new(), String::new()]);
                        rows.push(r);
                    }
                    for m in ms {
                        // The unit of `results.csv`, from the measure table.
                        let unit = Key::parse(&m.key).map_or("", |k| k.measure.unit());
                        let mut r = base.to_vec();
                        r.extend([m.key, m.value.to_string(), unit.to_string()]);
                        rows.push(r);
                    }
                }
            }
            let body = csv(&tessera_results::CSV_COLUMNS, &rows);
            Ok(csv_response(body, &format!("{}.csv", d.run.run_id)))
        }
        Format::Md => Err(no_markdown()),
    }
}

/// The previous run of the same suite on the same adapter, with its scenario records.
pub struct Previous {
    pub run_id: String,
    pub scenarios: Vec<ScenarioResult>,
    /// The fixed threshold and each frame-time series' own noise ([`crate::store::noise`]).
    pub options: tessera_results::compare::Options,
}

/// GPU time of `variant` against the previous run: change and verdict, as a table cell.
fn change_cell(
    prev: Option<&Previous>,
    scenario: &str,
    v: &tessera_results::VariantResult,
) -> String {
    let Some(prev) = prev else {
        return "<td class=n></td>".into();
    };
    let before = prev
        .scenarios
        .iter()
        .find(|s| s.scenario == scenario)
        .and_then(|s| s.results.iter().find(|w| w.variant == v.variant))
        .filter(|w| w.status == Status::Ok);
    let (Some(a), Some(b)) = (before.and_then(frame_samples), frame_samples(v)) else {
        return "<td class=n>–</td>".into();
    };
    let (threshold, noise) = prev.options.threshold_for(scenario, &v.variant);
    match compare_times(&a, &b, threshold) {
        Some(c) => {
            let (class, word) = match c.verdict {
                TimeVerdict::Slower => ("worse", "slower"),
                TimeVerdict::Faster => ("better", "faster"),
                // The engine's other words: within noise, below threshold, too few frames.
                v => ("muted", v.words()),
            };
            let noise = noise.map_or(String::new(), |s| {
                format!(", nightly noise {:.2}%", s * 100.0)
            });
            // Said, not only coloured: grey cannot tell "too few frames" from "within noise".
            let shown = match c.verdict {
                TimeVerdict::TooFewFrames => {
                    format!("{} <span class=muted>?</span>", pct(c.change))
                }
                _ => pct(c.change),
            };
            format!(
                "<td class=\"n {class}\" title=\"{word}, Mann-Whitney U p={:.4}, threshold {threshold:.1}%{noise}\">{shown}</td>",
                c.p,
            )
        }
        None => "<td class=n>–</td>".into(),
    }
}

fn scenario_section(d: &RunDetail, prev: Option<&Previous>, s: &ScenarioResult, out: &mut String) {
    let _ = write!(
        out,
        "<h2 id=\"s-{}\">{}</h2><p class=muted>{}×{}, {} measured frames after {} warm-up, reference: {}, wall {:.0} ms</p>",
        esc(&s.scenario),
        esc(&s.scenario),
        s.width,
        s.height,
        s.measured_frames,
        s.warmup_frames,
        esc(&s.reference),
        s.wall_ms
    );
    let bars: Vec<Bar> = s
        .results
        .iter()
        .filter(|v| v.status == Status::Ok)
        .map(|v| Bar {
            label: v.variant.clone(),
            parts: v
                .passes
                .iter()
                .filter_map(|p| p.gpu_ms.map(|g| (p.name.clone(), g.median)))
                .collect(),
        })
        .collect();
    if bars.iter().any(|b| !b.parts.is_empty()) {
        out.push_str(&stacked_bars(&bars, "GPU ms (median per pass)"));
    }
    let mut metric_names: Vec<&str> = Vec::new();
    for m in s.results.iter().flat_map(|v| &v.metrics) {
        if !metric_names.contains(&m.name.as_str()) {
            metric_names.push(&m.name);
        }
    }
    // Column heads are the measures' names; the title says the unit and which way is better.
    let head = |m: Measure| {
        let i = m.info();
        let unit = if i.unit.is_empty() {
            String::new()
        } else {
            format!(" ({})", i.unit)
        };
        // The unit in the header itself: a column of numbers says what they count.
        format!(
            "<th class=n title=\"{}{unit}, {}\">{}{}</th>",
            esc(i.label),
            i.direction.phrase(),
            esc(i.name),
            esc(&unit)
        )
    };
    let _ = write!(
        out,
        "<div class=scroll><table class=variants><tr><th>variant</th><th>status</th>{}<th class=n title=\"GPU time against the previous run of the suite\">vs prev</th>{}{}",
        head(Measure::GpuMs),
        head(Measure::CpuMs),
        head(Measure::Speedup)
    );
    for m in &metric_names {
        match Measure::from_name(m) {
            Some(known) => out.push_str(&head(known)),
            None => {
                let _ = write!(out, "<th class=n>{}</th>", esc(m));
            }
        }
    }
    let _ = write!(
        out,
        "{}<th>passes</th><th>gates</th><th></th></tr>",
        head(Measure::AllocatedBytes)
    );
    for v in &s.results {
        let series_link = d
            .series
            .iter()
            .find(|l| {
                l.scenario == s.scenario
                    && l.variant == v.variant
                    && l.measure == Measure::GpuMs.store_key()
            })
            .map(|l| format!("<a href=\"/series/{}\">history</a>", l.series_id))
            .unwrap_or_default();
        let status = match &v.status {
            Status::Ok => "<span class=ok>ok</span>".to_string(),
            Status::Skipped { reason } => {
                format!("<span class=skipped>skipped</span>: {}", esc(reason))
            }
            Status::Failed { error } => format!("<span class=failed>failed</span>: {}", esc(error)),
        };
        let sp = measure::speedup(&s.results, v, DEFAULT_BASELINE)
            .map_or("–".into(), |x| format!("{x:.2}×"));
        let ok = v.status == Status::Ok;
        // Skipped and failed variants measured nothing: no times, no memory.
        let _ = write!(
            out,
            "<tr><td>{}</td><td>{status}</td><td class=n>{}</td>{}<td class=n>{}</td><td class=n>{sp}</td>",
            name(&v.variant),
            if ok { ms(v.gpu_frame_ms.map(|g| g.median)) } else { "–".into() },
            if ok { change_cell(prev, &s.scenario, v) } else { "<td class=n>–</td>".into() },
            if ok { ms(Some(v.cpu_frame_ms.median)) } else { "–".into() }
        );
        for name in &metric_names {
            let val = v
                .metrics
                .iter()
                .find(|m| m.name == *name)
                .map_or("–".into(), |m| num(m.value));
            let _ = write!(out, "<td class=n>{val}</td>");
        }
        let passes: Vec<String> = v
            .passes
            .iter()
            .map(|p| format!("{} {}", esc(&p.name), ms(p.gpu_ms.map(|g| g.median))))
            .chain(v.culled_passes.iter().map(|c| format!("<s>{}</s>", esc(c))))
            .collect();
        let gates: Vec<String> = v
            .gates
            .iter()
            .map(|g| format!("{:?} {}", g.level, esc(&g.message)).to_lowercase())
            .collect();
        let images = if d
            .images
            .iter()
            .any(|i| i.scenario == s.scenario && i.variant == v.variant)
        {
            format!(
                " <a href=\"/runs/{}/images/{}/{}\">images</a>",
                enc(&d.run.run_id),
                enc(&s.scenario),
                enc(&v.variant)
            )
        } else {
            String::new()
        };
        let _ = write!(
            out,
            "<td class=n>{}</td><td class=wrap>{}</td><td class=wrap>{}</td><td class=links>{series_link}{images}</td></tr>",
            if ok { bytes(v.allocated_bytes) } else { "–".into() },
            passes.join(", "),
            gates.join("; ")
        );
    }
    out.push_str("</table></div>");
    out.push_str(&super::conditions_view::table(s));
    // Per-frame charts of every measure with per-frame values, a line per variant; the worst
    // frame links to the viewer when its image was saved.
    let outputs: std::collections::HashSet<(&str, i64)> = d
        .images
        .iter()
        .filter(|i| i.scenario == s.scenario && i.kind == "output")
        .map(|i| (i.variant.as_str(), i.frame))
        .collect();
    let saved = |variant: &str, frame: u32| outputs.contains(&(variant, i64::from(frame)));
    out.push_str(&super::run_frame_charts::render(&d.run.run_id, s, &saved));
    let _ = write!(
        out,
        "<p><a href=\"/pareto?scenario={}&adapter={}&run={}\">error against time</a></p>",
        enc(&s.scenario),
        d.run.adapter_id,
        enc(&d.run.run_id)
    );
}

/// The run page body.
pub fn render(d: &RunDetail, prev: Option<&Previous>) -> String {
    let r = &d.run;
    let mut out = format!(
        "<p>commit <code>{}</code>{} · started {} · finished {} · {} · harness {}</p><p>adapter <a href=\"/?adapter={}\">{}</a> ({}, {}) · driver {} {} · host {}</p><p><span class=ok>{} ok</span> · <span class=skipped>{} skipped</span> · <span class=failed>{} failed</span></p>",
        esc(&commit(r.commit.as_deref())),
        if r.dirty { " (dirty)" } else { "" },
        esc(&r.started_at),
        esc(d.info.finished_at.as_deref().unwrap_or("–")),
        esc(&r.status),
        esc(&r.harness_version),
        r.adapter_id,
        esc(&r.adapter),
        esc(&d.info.adapter.device_type),
        esc(&r.backend),
        esc(&r.driver),
        esc(&r.driver_info),
        esc(&d.info.host.hostname),
        r.ok,
        r.skipped,
        r.failed
    );
    let _ = write!(
        out,
        "<p>suite {} · branch {} · export <a href=\"/api/runs/{}?format=csv\">CSV</a> <a href=\"/api/runs/{}\">JSON</a></p>",
        esc(r.suite.as_deref().unwrap_or("–")),
        esc(r.branch.as_deref().unwrap_or("–")),
        enc(&r.run_id),
        enc(&r.run_id)
    );
    match prev {
        Some(p) => {
            let _ = write!(
                out,
                "<p>Previous run of this suite on this adapter: <a href=\"/runs/{}\">{}</a> · <a id=compare-prev href=\"/compare/runs?a={}&b={}\">compare with it</a>. The <em>vs prev</em> column is the change of median GPU time (red: slower, green: faster beyond noise by the test of <code>tessera compare</code>; grey: within noise).</p>",
                enc(&p.run_id),
                esc(&p.run_id),
                enc(&p.run_id),
                enc(&r.run_id)
            );
        }
        None => out.push_str("<p class=muted>No earlier run of this suite on this adapter.</p>"),
    }
    for s in &d.scenarios {
        scenario_section(d, prev, s, &mut out);
    }
    out
}

pub async fn page(
    State(state): State<AppState>,
    Path(run_id): Path<String>,
) -> Result<Html<String>, AppError> {
    let (d, prev) = state
        .db(move |c| {
            let d = read::run(c, &run_id)?;
            let prev = match browse::previous_in_suite(c, &run_id)? {
                Some(p) => Some(Previous {
                    scenarios: read::run_scenarios(c, &p)?,
                    run_id: p,
                    options: tessera_results::compare::Options {
                        threshold_pct: DEFAULT_THRESHOLD_PCT,
                        noise: crate::store::noise::frame_time_noise(c, &run_id)?,
                    },
                }),
                None => None,
            };
            Ok((d, prev))
        })
        .await?;
    Ok(Html(layout(
        &format!("Run {}", d.run.run_id),
        "runs",
        &render(&d, prev.as_ref()),
    )))
}
