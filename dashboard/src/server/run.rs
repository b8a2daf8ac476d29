//! One run (`/runs/{run_id}`, `/api/runs/{run_id}?format=json|csv`): per scenario, every variant
//! with its status or skip reason, per-pass GPU time (stacked), speedup against native on the same
//! adapter, the change of GPU time against the previous run of the same suite on the same adapter
//! (the significance test of `tessera compare`), metrics, allocated bytes, links to its series and
//! images, and per-frame charts of each measure (`run_frame_charts.rs`). The CSV export has the
//! columns of the harness's `results.csv`.
//!
//! A run of more than one scenario opens on a summary per scenario (ok / skipped / failed, what
//! changed against the previous run beyond noise); a run wider than [`INLINE_RESULTS`] shows only
//! the summary, each scenario's detail on its own page (`/runs/{run_id}/scenarios/{scenario}`).

use std::collections::HashMap;
use std::fmt::Write;

use axum::extract::{Path, Query, State};
use axum::response::{Html, IntoResponse, Response};
use axum::Json;
use tessera_results::measure::{self, points, Key, Measure, DEFAULT_BASELINE};
use tessera_results::stats::{compare_times, frame_samples, TimeVerdict, DEFAULT_THRESHOLD_PCT};
use tessera_results::{RunInfo, ScenarioResult, Status};

use super::export::{csv, csv_response, no_markdown, Format, FormatQuery};
use super::{AppError, AppState};
use crate::html::{bytes, commit, enc, esc, ms, name, num, page as layout, pct};
use crate::store::browse;
use crate::store::read::{self, RunDetail, RunHead, RunRow, ScenarioLines};
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

/// The previous run of the same suite on the same adapter: the per-frame GPU times of its
/// variants that ran, by scenario and variant.
pub struct Previous {
    pub run_id: String,
    pub frames: HashMap<(String, String), Vec<f64>>,
    /// The fixed threshold and each frame-time series' own noise ([`crate::store::noise`]).
    pub options: tessera_results::compare::Options,
}

impl Previous {
    fn frames_of(&self, scenario: &str, variant: &str) -> Option<&[f64]> {
        self.frames
            .get(&(scenario.to_string(), variant.to_string()))
            .map(Vec::as_slice)
    }
}

/// GPU time of `variant` (its per-frame times `frames`) against the previous run: the engine's
/// comparison, the threshold it was judged with and the series' own noise; `None` without a
/// previous run or frames on both sides.
fn change_of(
    prev: &Previous,
    scenario: &str,
    variant: &str,
    frames: Option<&[f64]>,
) -> Option<(tessera_results::stats::TimeChange, f64, Option<f64>)> {
    let (a, b) = (prev.frames_of(scenario, variant)?, frames?);
    let (threshold, noise) = prev.options.threshold_for(scenario, variant);
    compare_times(a, b, threshold).map(|c| (c, threshold, noise))
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
    match change_of(prev, scenario, &v.variant, frame_samples(v).as_deref()) {
        Some((c, threshold, noise)) => {
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

/// A run with more results than this opens on its per-scenario summary alone; each scenario's
/// detail (tables, per-pass bars, per-frame charts, conditions) is its own page
/// (`/runs/{run_id}/scenarios/{scenario}`). A nightly run of 1,700 results would otherwise be
/// 7.6 MB of HTML that takes a browser seconds to lay out.
pub const INLINE_RESULTS: usize = 150;

/// Most changed or failed variants named in one summary cell; the rest are counted.
const SUMMARY_NAMES: usize = 3;

/// Where a scenario's detail is: its section on this page, or its own page.
fn scenario_href(run_id: &str, scenario: &str, inline: bool) -> String {
    if inline {
        format!("#s-{}", enc(scenario))
    } else {
        format!("/runs/{}/scenarios/{}", enc(run_id), enc(scenario))
    }
}

/// Names with a rest count: `a +6.1%, b +5.2%, c +5.0% and 4 more`.
fn named_list(items: &[String]) -> String {
    let mut out = items
        .iter()
        .take(SUMMARY_NAMES)
        .cloned()
        .collect::<Vec<_>>()
        .join(", ");
    if items.len() > SUMMARY_NAMES {
        let _ = write!(out, " and {} more", items.len() - SUMMARY_NAMES);
    }
    out
}

/// The per-scenario summary: variants, ok / skipped / failed, and what changed against the
/// previous run beyond noise (slower, faster; the largest first), what could not be decided.
pub fn summary(
    run_id: &str,
    scenarios: &[ScenarioLines],
    prev: Option<&Previous>,
    inline: bool,
) -> String {
    struct Row<'a> {
        s: &'a ScenarioLines,
        ok: usize,
        skipped: usize,
        failed: Vec<String>,
        changed: Vec<(f64, bool, String)>,
        undecided: usize,
    }
    let rows: Vec<Row> = scenarios
        .iter()
        .map(|s| {
            let mut r = Row {
                s,
                ok: 0,
                skipped: 0,
                failed: Vec::new(),
                changed: Vec::new(),
                undecided: 0,
            };
            for v in &s.variants {
                match &v.status {
                    Status::Ok => r.ok += 1,
                    Status::Skipped { .. } => r.skipped += 1,
                    Status::Failed { error } => r.failed.push(format!(
                        "<span title=\"{}\">{}</span>",
                        esc(error),
                        name(&v.variant)
                    )),
                }
                if v.status != Status::Ok {
                    continue;
                }
                match prev.and_then(|p| change_of(p, &s.scenario, &v.variant, v.frames.as_deref()))
                {
                    Some((c, ..))
                        if matches!(c.verdict, TimeVerdict::Slower | TimeVerdict::Faster) =>
                    {
                        r.changed.push((
                            c.change,
                            c.verdict == TimeVerdict::Slower,
                            v.variant.clone(),
                        ))
                    }
                    Some((c, ..)) if c.verdict == TimeVerdict::TooFewFrames => r.undecided += 1,
                    _ => {}
                }
            }
            r.changed.sort_by(|a, b| b.0.abs().total_cmp(&a.0.abs()));
            r
        })
        .collect();
    let count = |f: &dyn Fn(&Row) -> bool| rows.iter().filter(|r| f(r)).count();
    let results: usize = scenarios.iter().map(|s| s.variants.len()).sum();
    let mut out = format!(
        "<h2 id=summary>Scenarios</h2><p id=summary-counts>{results} results in {} scenarios · <span class=worse>{} with a slower variant</span> · <span class=better>{} with a faster one</span> · <span class=failed>{} with a failure</span>{}</p>",
        scenarios.len(),
        count(&|r| r.changed.iter().any(|c| c.1)),
        count(&|r| r.changed.iter().any(|c| !c.1)),
        count(&|r| !r.failed.is_empty()),
        if inline {
            String::new()
        } else {
            " · each scenario's tables and charts open on its own page".into()
        }
    );
    let _ = write!(
        out,
        "<div class=scroll><table id=run-summary><tr><th>scenario</th><th class=n>variants</th><th class=n>ok</th><th class=n>skipped</th><th class=n>failed</th><th title=\"median GPU time against the previous run, beyond its noise by the test of tessera compare\">changed vs prev (GPU ms)</th><th class=n title=\"too few frames to tell a change\">undecided</th><th>failures</th></tr>"
    );
    for r in &rows {
        let changed: Vec<String> = r
            .changed
            .iter()
            .map(|(c, slower, v)| {
                format!(
                    "<span class=nw>{} <span class={}>{}</span></span>",
                    name(v),
                    if *slower { "worse" } else { "better" },
                    pct(*c)
                )
            })
            .collect();
        let _ = write!(
            out,
            "<tr><td><a href=\"{}\">{}</a></td><td class=n>{}</td><td class=n>{}</td><td class=n>{}</td><td class=\"n{}\">{}</td><td>{}</td><td class=n>{}</td><td>{}</td></tr>",
            scenario_href(run_id, &r.s.scenario, inline),
            name(&r.s.scenario),
            r.s.variants.len(),
            r.ok,
            r.skipped,
            if r.failed.is_empty() { "" } else { " failed" },
            r.failed.len(),
            if prev.is_none() { "<span class=muted>no previous run</span>".into() } else { named_list(&changed) },
            r.undecided,
            named_list(&r.failed)
        );
    }
    out.push_str("</table></div>");
    out
}

/// The lines above the detail: commit, times, adapter, counts, exports, and the previous run.
fn header(r: &RunRow, info: &RunInfo, prev: Option<&Previous>) -> String {
    let mut out = format!(
        "<p>commit <code>{}</code>{} · started {} · finished {} · {} · harness {}</p><p>adapter <a href=\"/?adapter={}\">{}</a> ({}, {}) · driver {} {} · host {}</p><p><span class=ok>{} ok</span> · <span class=skipped>{} skipped</span> · <span class=failed>{} failed</span></p>",
        esc(&commit(r.commit.as_deref())),
        if r.dirty { " (dirty)" } else { "" },
        esc(&r.started_at),
        esc(info.finished_at.as_deref().unwrap_or("–")),
        esc(&r.status),
        esc(&r.harness_version),
        r.adapter_id,
        esc(&r.adapter),
        esc(&info.adapter.device_type),
        esc(&r.backend),
        esc(&r.driver),
        esc(&r.driver_info),
        esc(&info.host.hostname),
        r.ok,
        r.skipped,
        r.failed
    );
    let _ = write!(
        out,
        "<p>suite {} · branch {} · export <a href=\"/api/runs/{}?format=csv\">CSV</a> <a href=\"/api/runs/{}\">JSON</a> · {}</p>",
        esc(r.suite.as_deref().unwrap_or("–")),
        esc(r.branch.as_deref().unwrap_or("–")),
        enc(&r.run_id),
        enc(&r.run_id),
        // Against the previous run's commit, else this commit against itself.
        super::ab_form::link(prev.map_or(&r.run_id, |p| &p.run_id), &r.run_id, None)
    );
    if r.commit.is_none() {
        out.push_str("<p id=no-commit class=neutral>This run was recorded without a git commit (tessera ran outside a checkout): it is kept, but never used as the previous run of its suite.</p>");
    }
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
    out
}

/// The run page body: the header, the per-scenario summary (for more than one scenario), and
/// every scenario's detail when the run has at most [`INLINE_RESULTS`] results.
pub fn render(d: &RunDetail, prev: Option<&Previous>) -> String {
    let lines: Vec<ScenarioLines> = d.scenarios.iter().map(ScenarioLines::of).collect();
    let mut out = header(&d.run, &d.info, prev);
    let inline = is_inline(&d.run);
    if d.scenarios.len() > 1 || !inline {
        out.push_str(&summary(&d.run.run_id, &lines, prev, inline));
    }
    if inline {
        for s in &d.scenarios {
            scenario_section(d, prev, s, &mut out);
        }
    }
    out
}

/// The body of a run wider than [`INLINE_RESULTS`]: the header and the per-scenario summary,
/// from the results' rows alone.
pub fn render_wide(head: &RunHead, lines: &[ScenarioLines], prev: Option<&Previous>) -> String {
    let mut out = header(&head.run, &head.info, prev);
    out.push_str(&summary(&head.run.run_id, lines, prev, false));
    out
}

/// Whether the run's detail is on its page (at most [`INLINE_RESULTS`] results).
fn is_inline(r: &RunRow) -> bool {
    (r.ok + r.skipped + r.failed) as usize <= INLINE_RESULTS
}

/// One scenario of a large run on its own page: a link back to the summary, the previous and
/// next scenarios, and the scenario's detail as the run page shows it for a small run.
pub fn render_scenario(
    d: &RunDetail,
    names: &[String],
    prev: Option<&Previous>,
    scenario: &str,
) -> String {
    let r = &d.run;
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    let at = names.iter().position(|n| *n == scenario);
    let link = |n: &str, word: &str| {
        format!(
            " · {word} <a href=\"/runs/{}/scenarios/{}\">{}</a>",
            enc(&r.run_id),
            enc(n),
            name(n)
        )
    };
    let mut out = format!(
        "<p id=crumbs><a href=\"/runs/{}#summary\">run {}</a> (all {} scenarios){}{}</p><p>commit <code>{}</code> · adapter {} · driver {} {} · started {} · {}</p>",
        enc(&r.run_id),
        esc(&r.run_id),
        names.len(),
        at.and_then(|i| i.checked_sub(1))
            .map_or(String::new(), |i| link(names[i], "previous")),
        at.and_then(|i| names.get(i + 1))
            .map_or(String::new(), |n| link(n, "next")),
        esc(&commit(r.commit.as_deref())),
        esc(&r.adapter),
        esc(&r.driver),
        esc(&r.driver_info),
        esc(&r.started_at),
        super::ab_form::link(
            prev.map_or(&r.run_id, |p| &p.run_id),
            &r.run_id,
            Some(scenario)
        ),
    );
    if let Some(p) = prev {
        let _ = write!(
            out,
            "<p>The <em>vs prev</em> column is against <a href=\"/runs/{}/scenarios/{}\">{}</a>, the previous run of this suite on this adapter.</p>",
            enc(&p.run_id),
            enc(scenario),
            esc(&p.run_id)
        );
    }
    if let Some(s) = d.scenarios.iter().find(|s| s.scenario == scenario) {
        scenario_section(d, prev, s, &mut out);
    }
    out
}

/// The previous run of `run_id`'s suite with its per-frame GPU times (its results' rows), compared
/// at the default threshold and `run_id`'s frame-time noise. The noise of a series costs two
/// queries, so it is read only for the variants `needs_noise` accepts, given their frame times
/// against the previous run's: where it can change a verdict or where the page shows it.
fn previous(
    c: &mut dyn crate::db::Connection,
    run_id: &str,
    needs_noise: &dyn Fn(&str, &str, &Previous) -> bool,
) -> Result<Option<Previous>, crate::store::StoreError> {
    let Some(p) = browse::previous_in_suite(c, run_id)? else {
        return Ok(None);
    };
    let pk = read::run_pk(c, &p)?;
    let mut frames = HashMap::new();
    for s in read::lines(c, pk)? {
        for v in s.variants {
            if let (Status::Ok, Some(f)) = (v.status, v.frames) {
                frames.insert((s.scenario.clone(), v.variant), f);
            }
        }
    }
    let mut prev = Previous {
        run_id: p,
        frames,
        options: tessera_results::compare::Options {
            threshold_pct: DEFAULT_THRESHOLD_PCT,
            noise: Default::default(),
        },
    };
    prev.options.noise =
        crate::store::noise::frame_time_noise_where(c, run_id, &|s, v| needs_noise(s, v, &prev))?;
    Ok(Some(prev))
}

/// Whether a series' noise can change the verdict on `frames` against the previous run: only
/// where the change is significant but below the fixed threshold (the noise only lowers it).
fn noise_can_decide(
    prev: &Previous,
    scenario: &str,
    variant: &str,
    frames: Option<&[f64]>,
) -> bool {
    let (Some(a), Some(b)) = (prev.frames_of(scenario, variant), frames) else {
        return false;
    };
    compare_times(a, b, prev.options.threshold_pct)
        .is_some_and(|c| c.verdict == TimeVerdict::BelowThreshold)
}

enum RunPage {
    Inline(RunDetail),
    Wide(RunHead, Vec<ScenarioLines>),
}

pub async fn page(
    State(state): State<AppState>,
    Path(run_id): Path<String>,
) -> Result<Html<String>, AppError> {
    let (body, prev) = state
        .db(move |c| {
            let head = read::run_head(c, &run_id)?;
            if is_inline(&head.run) {
                // The detail shows every variant's noise in its vs-prev cell.
                let prev = previous(c, &run_id, &|_, _, _| true)?;
                return Ok((RunPage::Inline(read::run(c, &run_id)?), prev));
            }
            let lines = read::lines(c, head.pk)?;
            let by_key: HashMap<(&str, &str), Option<&[f64]>> = lines
                .iter()
                .flat_map(|s| {
                    s.variants.iter().map(move |v| {
                        (
                            (s.scenario.as_str(), v.variant.as_str()),
                            v.frames.as_deref(),
                        )
                    })
                })
                .collect();
            let prev = previous(c, &run_id, &|s, v, p| {
                by_key
                    .get(&(s, v))
                    .is_some_and(|f| noise_can_decide(p, s, v, *f))
            })?;
            drop(by_key);
            Ok((RunPage::Wide(head, lines), prev))
        })
        .await?;
    let (title, html) = match &body {
        RunPage::Inline(d) => (&d.run.run_id, render(d, prev.as_ref())),
        RunPage::Wide(head, lines) => (&head.run.run_id, render_wide(head, lines, prev.as_ref())),
    };
    Ok(Html(layout(&format!("Run {title}"), "runs", &html)))
}

/// `GET /runs/{run_id}/scenarios/{scenario}`: one scenario's detail, against the same
/// scenario of the previous run of the suite.
pub async fn scenario_page(
    State(state): State<AppState>,
    Path((run_id, scenario)): Path<(String, String)>,
) -> Result<Html<String>, AppError> {
    let wanted = scenario.clone();
    let (d, names, prev) = state
        .db(move |c| {
            let Some((d, names)) = read::run_scenario(c, &run_id, &scenario)? else {
                return Err(AppError::NotFound(format!(
                    "run {run_id} has no scenario {scenario:?}"
                )));
            };
            // The detail shows this scenario's noise in its vs-prev cells.
            let prev = previous(c, &run_id, &|s, _, _| s == scenario)?;
            Ok((d, names, prev))
        })
        .await?;
    Ok(Html(layout(
        &format!("Run {} · {}", d.run.run_id, wanted),
        "runs",
        &render_scenario(&d, &names, prev.as_ref(), &wanted),
    )))
}
