//! Compare two runs (`/compare/runs?a=&b=`, `/api/compare/runs?a=&b=&format=json|csv|md`): per
//! scenario and variant, B's GPU time against A's with the significance test of `tessera compare`
//! (`tessera_results::stats`: Mann-Whitney U on per-frame times, p < 0.01 and a median change of at
//! least `threshold` percent, 5 by default), per-pass changes under the same test, metric changes,
//! status, and links to both runs' images. `a` and `b` are run ids, or commits (a prefix of at
//! least 4 hex digits) resolved to the newest run of that commit, on `adapter` and in `suite` when
//! given. On different adapters or drivers times are compared relative to each run's `native`
//! variant, as `tessera compare` does.
//!
//! Not for: runs of one adapter over time (see [`super::series`]).

use std::fmt::Write;

use axum::extract::{RawQuery, State};
use axum::response::{Html, IntoResponse, Response};
use axum::Json;
use serde::Serialize;
use tessera_results::measure::{Key, Measure};
use tessera_results::stats::{
    compare_times, frame_samples, TimeVerdict, ALPHA, DEFAULT_THRESHOLD_PCT,
};
use tessera_results::{RunInfo, ScenarioResult, Status, VariantResult};

use super::export::{cell, csv, csv_response, md_response, Format};
use super::{AppError, AppState};
use crate::html::{commit, enc, esc, num, page as layout, pct};
use crate::store::browse;
use crate::store::read::{self, RunRow};

/// The request, parsed from the query string (`pick` may repeat: the runs list's tick boxes).
#[derive(Debug, Default, Clone)]
pub struct CompareRunsQuery {
    pub a: Option<String>,
    pub b: Option<String>,
    pub adapter: Option<i64>,
    pub suite: Option<String>,
    pub threshold: f64,
    pub format: Format,
    pub picks: Vec<String>,
}

fn parse_query(raw: Option<&str>) -> Result<CompareRunsQuery, AppError> {
    let pairs: Vec<(String, String)> = serde_urlencoded::from_str(raw.unwrap_or(""))
        .map_err(|e| AppError::BadRequest(format!("bad query: {e}")))?;
    let mut q = CompareRunsQuery {
        threshold: DEFAULT_THRESHOLD_PCT,
        ..Default::default()
    };
    for (k, v) in pairs {
        let v = v.trim().to_string();
        if v.is_empty() {
            continue;
        }
        match k.as_str() {
            "a" => q.a = Some(v),
            "b" => q.b = Some(v),
            "pick" => q.picks.push(v),
            "suite" => q.suite = Some(v),
            "adapter" => {
                q.adapter = Some(v.parse().map_err(|_| {
                    AppError::BadRequest(format!("adapter must be an id, not {v:?}"))
                })?)
            }
            "threshold" => {
                q.threshold = v
                    .parse()
                    .ok()
                    .filter(|t: &f64| t.is_finite() && *t >= 0.0)
                    .ok_or_else(|| {
                        AppError::BadRequest(format!("threshold must be a percentage, not {v:?}"))
                    })?
            }
            "format" => {
                q.format = match v.as_str() {
                    "json" => Format::Json,
                    "csv" => Format::Csv,
                    "md" => Format::Md,
                    _ => {
                        return Err(AppError::BadRequest(format!(
                            "format must be json, csv or md, not {v:?}"
                        )))
                    }
                }
            }
            _ => {}
        }
    }
    Ok(q)
}

/// A change of one timed thing (the frame, or one pass) from A to B.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct TimeDelta {
    pub name: String,
    /// Medians, in milliseconds (or relative to native when compared by speedup).
    pub a: Option<f64>,
    pub b: Option<f64>,
    pub change: Option<f64>,
    pub p: Option<f64>,
    /// `slower`, `faster`, `same` (within noise), or why it was not compared.
    pub verdict: String,
}

#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct MetricDelta {
    pub name: String,
    pub a: Option<f64>,
    pub b: Option<f64>,
    pub higher_is_better: bool,
    /// `better`, `worse` or `same`.
    pub verdict: String,
}

#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct VariantDelta {
    pub variant: String,
    pub status_a: String,
    pub status_b: String,
    pub time: TimeDelta,
    pub passes: Vec<TimeDelta>,
    pub metrics: Vec<MetricDelta>,
    pub images_a: bool,
    pub images_b: bool,
}

#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ScenarioDelta {
    pub scenario: String,
    pub variants: Vec<VariantDelta>,
    /// Variants in one run only.
    pub only_a: Vec<String>,
    pub only_b: Vec<String>,
}

#[derive(Clone, Debug, Serialize)]
pub struct RunComparison {
    pub a: RunRow,
    pub b: RunRow,
    /// Times relative to each run's `native` (the adapters or drivers differ).
    pub by_speedup: bool,
    pub threshold_pct: f64,
    pub alpha: f64,
    pub scenarios: Vec<ScenarioDelta>,
    pub only_a: Vec<String>,
    pub only_b: Vec<String>,
}

fn same_adapter(a: &RunInfo, b: &RunInfo) -> bool {
    let (x, y) = (&a.adapter, &b.adapter);
    x.name == y.name
        && x.backend == y.backend
        && x.driver == y.driver
        && x.driver_info == y.driver_info
}

fn median(s: &[f64]) -> Option<f64> {
    tessera_results::Summary::of(s).map(|s| s.median)
}

fn verdict_word(v: TimeVerdict) -> &'static str {
    match v {
        TimeVerdict::Same => "same",
        TimeVerdict::Slower => "slower",
        TimeVerdict::Faster => "faster",
    }
}

fn delta(name: &str, a: Option<Vec<f64>>, b: Option<Vec<f64>>, threshold: f64) -> TimeDelta {
    let (ma, mb) = (a.as_deref().and_then(median), b.as_deref().and_then(median));
    let (change, p, verdict) = match (a.as_deref(), b.as_deref()) {
        (Some(a), Some(b)) => match compare_times(a, b, threshold) {
            Some(c) => (
                Some(c.change),
                Some(c.p),
                verdict_word(c.verdict).to_string(),
            ),
            None => (None, None, "not timed".into()),
        },
        _ => (None, None, "not timed in both".into()),
    };
    TimeDelta {
        name: name.to_string(),
        a: ma,
        b: mb,
        change,
        p,
        verdict,
    }
}

fn native_median(s: &ScenarioResult) -> Option<f64> {
    s.results
        .iter()
        .find(|r| r.technique == "native" && r.status == Status::Ok)
        .and_then(frame_samples)
        .and_then(|v| median(&v))
}

fn compare_variant(
    sa: &ScenarioResult,
    va: &VariantResult,
    sb: &ScenarioResult,
    vb: &VariantResult,
    by_speedup: bool,
    threshold: f64,
) -> VariantDelta {
    let ok = va.status == Status::Ok && vb.status == Status::Ok;
    let scale = |s: &ScenarioResult, v: Vec<f64>| -> Option<Vec<f64>> {
        if !by_speedup {
            return Some(v);
        }
        let n = native_median(s)?;
        Some(v.into_iter().map(|x| x / n).collect())
    };
    let time = if !ok {
        TimeDelta {
            name: "frame".into(),
            a: None,
            b: None,
            change: None,
            p: None,
            verdict: "not ok in both".into(),
        }
    } else if by_speedup && va.technique == "native" {
        TimeDelta {
            name: "frame".into(),
            a: None,
            b: None,
            change: None,
            p: None,
            verdict: "baseline".into(),
        }
    } else {
        delta(
            "frame",
            frame_samples(va).and_then(|v| scale(sa, v)),
            frame_samples(vb).and_then(|v| scale(sb, v)),
            threshold,
        )
    };
    let mut passes = Vec::new();
    if ok && !by_speedup {
        for pa in &va.passes {
            let pb = vb.passes.iter().find(|p| p.name == pa.name);
            let samples = |p: &tessera_results::PassRecord| {
                (p.gpu_ms.is_some() && !p.samples_ms.is_empty()).then(|| p.samples_ms.clone())
            };
            passes.push(delta(
                &pa.name,
                samples(pa),
                pb.and_then(samples),
                threshold,
            ));
        }
    }
    let mut metrics = Vec::new();
    for ma in &va.metrics {
        let mb = vb.metrics.iter().find(|m| m.name == ma.name);
        let b = mb.map(|m| m.value);
        // The measure table's direction; a metric it does not know takes its record's.
        let higher_is_better = tessera_results::measure::Measure::from_name(&ma.name)
            .map_or(ma.higher_is_better, |m| m.direction().higher_is_better());
        let verdict = match b {
            Some(b) if b == ma.value => "same",
            Some(b) if (b > ma.value) == higher_is_better => "better",
            Some(_) => "worse",
            None => "only in A",
        };
        metrics.push(MetricDelta {
            name: ma.name.clone(),
            a: Some(ma.value),
            b,
            higher_is_better,
            verdict: verdict.into(),
        });
    }
    VariantDelta {
        variant: va.variant.clone(),
        status_a: va.status.label().into(),
        status_b: vb.status.label().into(),
        time,
        passes,
        metrics,
        images_a: !va.images.is_empty(),
        images_b: !vb.images.is_empty(),
    }
}

/// The comparison of two runs' records.
pub fn compare(
    a: RunRow,
    info_a: &RunInfo,
    sa: &[ScenarioResult],
    b: RunRow,
    info_b: &RunInfo,
    sb: &[ScenarioResult],
    threshold: f64,
) -> RunComparison {
    let by_speedup = !same_adapter(info_a, info_b);
    let mut scenarios = Vec::new();
    for x in sa {
        let Some(y) = sb.iter().find(|y| y.scenario == x.scenario) else {
            continue;
        };
        let mut variants = Vec::new();
        for va in &x.results {
            if let Some(vb) = y.results.iter().find(|v| v.variant == va.variant) {
                variants.push(compare_variant(x, va, y, vb, by_speedup, threshold));
            }
        }
        let names = |s: &ScenarioResult, other: &ScenarioResult| -> Vec<String> {
            s.results
                .iter()
                .filter(|v| !other.results.iter().any(|w| w.variant == v.variant))
                .map(|v| v.variant.clone())
                .collect()
        };
        scenarios.push(ScenarioDelta {
            scenario: x.scenario.clone(),
            variants,
            only_a: names(x, y),
            only_b: names(y, x),
        });
    }
    let only = |s: &[ScenarioResult], other: &[ScenarioResult]| -> Vec<String> {
        s.iter()
            .filter(|x| !other.iter().any(|y| y.scenario == x.scenario))
            .map(|x| x.scenario.clone())
            .collect()
    };
    RunComparison {
        only_a: only(sa, sb),
        only_b: only(sb, sa),
        a,
        b,
        by_speedup,
        threshold_pct: threshold,
        alpha: ALPHA,
        scenarios,
    }
}

fn resolve(
    c: &mut dyn crate::db::Connection,
    what: &str,
    q: &CompareRunsQuery,
) -> Result<String, AppError> {
    if c.query_opt("SELECT 1 FROM runs WHERE run_id = $1", &[what.into()])?
        .is_some()
    {
        return Ok(what.to_string());
    }
    browse::run_of_commit(c, what, q.adapter, q.suite.as_deref())?.ok_or_else(|| {
        AppError::NotFound(format!(
            "no run {what:?} and no run of a commit starting with it{}",
            if q.adapter.is_some() || q.suite.is_some() {
                " on that adapter and suite"
            } else {
                ""
            }
        ))
    })
}

async fn load(state: &AppState, q: CompareRunsQuery) -> Result<Option<RunComparison>, AppError> {
    state
        .db(move |c| {
            let (a, b) = match (&q.a, &q.b, q.picks.as_slice()) {
                (Some(a), Some(b), _) => (resolve(c, a, &q)?, resolve(c, b, &q)?),
                (_, _, [x, y]) => {
                    // Ticked in the runs list: the older is A.
                    let (x, y) = (resolve(c, x, &q)?, resolve(c, y, &q)?);
                    let rx = read::run(c, &x)?.run.started_at;
                    let ry = read::run(c, &y)?.run.started_at;
                    if rx <= ry {
                        (x, y)
                    } else {
                        (y, x)
                    }
                }
                (None, None, []) => return Ok(None),
                (_, _, picks) if !picks.is_empty() => {
                    return Err(AppError::BadRequest(format!(
                        "tick exactly two runs to compare ({} ticked)",
                        picks.len()
                    )))
                }
                _ => return Err(AppError::BadRequest("give both a= and b=".into())),
            };
            let da = read::run(c, &a)?;
            let db = read::run(c, &b)?;
            Ok(Some(compare(
                da.run,
                &da.info,
                &da.scenarios,
                db.run,
                &db.info,
                &db.scenarios,
                q.threshold,
            )))
        })
        .await
}

fn opt(v: Option<f64>) -> String {
    v.map_or("–".into(), num)
}

fn change(v: Option<f64>) -> String {
    v.map_or("–".into(), pct)
}

fn p_value(p: Option<f64>) -> String {
    match p {
        Some(p) if p < 0.001 => "p<0.001".into(),
        Some(p) => format!("p={p:.3}"),
        None => String::new(),
    }
}

/// The comparison as Markdown (what a pull request comment would show).
pub fn markdown(c: &RunComparison) -> String {
    let mut out = format!(
        "## Tessera: run `{}` against `{}`\n\nA: `{}` (commit `{}`, {}, {} {})\nB: `{}` (commit `{}`, {}, {} {})\n\nTime: Mann-Whitney U on per-frame GPU times, p < {} and a median change of at least {}%{}.\n",
        c.b.run_id,
        c.a.run_id,
        c.a.run_id,
        commit(c.a.commit.as_deref()),
        c.a.adapter,
        c.a.driver,
        c.a.driver_info,
        c.b.run_id,
        commit(c.b.commit.as_deref()),
        c.b.adapter,
        c.b.driver,
        c.b.driver_info,
        c.alpha,
        c.threshold_pct,
        if c.by_speedup { "; different adapters or drivers: times relative to each run's native" } else { "" }
    );
    for s in &c.scenarios {
        let _ = write!(
            out,
            "\n### {}\n\n| variant | status A → B | GPU ms A | GPU ms B | change | verdict | metrics |\n|---|---|---:|---:|---:|---|---|\n",
            s.scenario
        );
        for v in &s.variants {
            let metrics: Vec<String> = v
                .metrics
                .iter()
                .filter(|m| m.verdict != "same")
                .map(|m| format!("{} {} → {} ({})", m.name, opt(m.a), opt(m.b), m.verdict))
                .collect();
            let _ = writeln!(
                out,
                "| {} | {} → {} | {} | {} | {} | {} {} | {} |",
                v.variant,
                v.status_a,
                v.status_b,
                opt(v.time.a),
                opt(v.time.b),
                change(v.time.change),
                v.time.verdict,
                p_value(v.time.p),
                metrics.join("; ")
            );
        }
    }
    out
}

/// One CSV row per (scenario, variant, measure).
pub fn csv_rows(c: &RunComparison) -> Vec<Vec<String>> {
    let mut rows = Vec::new();
    for s in &c.scenarios {
        for v in &s.variants {
            let mut time = |measure: String, t: &TimeDelta| {
                rows.push(vec![
                    s.scenario.clone(),
                    v.variant.clone(),
                    measure,
                    cell(t.a),
                    cell(t.b),
                    cell(t.change),
                    cell(t.p),
                    t.verdict.clone(),
                ]);
            };
            let gpu_ms = Key::of(Measure::GpuMs).statistic("median");
            time(
                if c.by_speedup {
                    // Not a measure of a result: the medians over each run's native median.
                    "gpu_ms.relative_to_native".into()
                } else {
                    gpu_ms.render()
                },
                &v.time,
            );
            for p in &v.passes {
                time(gpu_ms.clone().pass(&p.name).render(), p);
            }
            for m in &v.metrics {
                rows.push(vec![
                    s.scenario.clone(),
                    v.variant.clone(),
                    m.name.clone(),
                    cell(m.a.filter(|x| x.is_finite())),
                    cell(m.b.filter(|x| x.is_finite())),
                    String::new(),
                    String::new(),
                    m.verdict.clone(),
                ]);
            }
        }
    }
    rows
}

const CSV_HEADER: [&str; 8] = [
    "scenario", "variant", "measure", "a", "b", "change", "p", "verdict",
];

pub async fn api(
    State(state): State<AppState>,
    RawQuery(raw): RawQuery,
) -> Result<Response, AppError> {
    let q = parse_query(raw.as_deref())?;
    let format = q.format;
    let Some(c) = load(&state, q).await? else {
        return Err(AppError::BadRequest(
            "give a= and b= (run ids or commits)".into(),
        ));
    };
    let name = format!("compare-{}-{}", c.a.run_id, c.b.run_id);
    Ok(match format {
        Format::Json => Json(c).into_response(),
        Format::Csv => csv_response(csv(&CSV_HEADER, &csv_rows(&c)), &format!("{name}.csv")),
        Format::Md => md_response(markdown(&c), &format!("{name}.md")),
    })
}

/// A verdict as the page words it.
fn shown(v: &str) -> &str {
    if v == "same" {
        "within noise"
    } else {
        v
    }
}

fn verdict_class(v: &str) -> &'static str {
    match v {
        "slower" | "worse" => "worse",
        "faster" | "better" => "better",
        _ => "muted",
    }
}

fn run_line(label: &str, r: &RunRow) -> String {
    format!(
        "<p>{label}: <a href=\"/runs/{}\">{}</a> · commit <code>{}</code> · {} · {} · {} {} · suite {}</p>",
        enc(&r.run_id),
        esc(&r.run_id),
        esc(&commit(r.commit.as_deref())),
        esc(&r.started_at),
        esc(&r.adapter),
        esc(&r.driver),
        esc(&r.driver_info),
        esc(r.suite.as_deref().unwrap_or("–"))
    )
}

pub fn render(c: &RunComparison) -> String {
    let q = format!("a={}&b={}", enc(&c.a.run_id), enc(&c.b.run_id));
    let thr = if c.threshold_pct == DEFAULT_THRESHOLD_PCT {
        String::new()
    } else {
        format!("&threshold={}", c.threshold_pct)
    };
    let mut b = run_line("A (base)", &c.a);
    b.push_str(&run_line("B (new)", &c.b));
    let _ = write!(
        b,
        "<p><a id=permalink href=\"/compare/runs?{q}{thr}\">permalink</a> · export <a href=\"/api/compare/runs?{q}{thr}&format=md\">Markdown</a> <a href=\"/api/compare/runs?{q}{thr}&format=csv\">CSV</a> <a href=\"/api/compare/runs?{q}{thr}\">JSON</a> · <a href=\"/compare/runs?a={}&b={}{thr}\">swap A and B</a></p><p class=muted>Time: Mann-Whitney U test on per-frame GPU times (the test of <code>tessera compare</code>); slower or faster when p &lt; {} and the median moved by at least {}%, otherwise within noise.{}</p>",
        enc(&c.b.run_id),
        enc(&c.a.run_id),
        c.alpha,
        c.threshold_pct,
        if c.by_speedup {
            " The adapters or drivers differ: times are relative to each run's <code>native</code> variant (a change means the speedup against native changed)."
        } else {
            ""
        }
    );
    let tally = |word: &str| -> usize {
        c.scenarios
            .iter()
            .flat_map(|s| &s.variants)
            .filter(|v| v.time.verdict == word)
            .count()
    };
    let _ = write!(
        b,
        "<p><span class=worse>{} slower</span> · <span class=better>{} faster</span> · {} within noise</p>",
        tally("slower"),
        tally("faster"),
        tally("same")
    );
    for s in &c.scenarios {
        let _ = write!(
            b,
            "<h2 id=\"s-{}\">{}</h2><div class=scroll><table class=compare><tr><th>variant</th><th>status A → B</th><th class=n>GPU ms A</th><th class=n>GPU ms B</th><th class=n>change</th><th>verdict</th><th>passes (change, verdict)</th><th>metrics A → B</th><th>images</th></tr>",
            esc(&s.scenario),
            esc(&s.scenario)
        );
        for v in &s.variants {
            let passes: Vec<String> = v
                .passes
                .iter()
                .map(|p| {
                    format!(
                        "{} <span class={}>{} {}</span>",
                        esc(&p.name),
                        verdict_class(&p.verdict),
                        change(p.change),
                        esc(shown(&p.verdict))
                    )
                })
                .collect();
            let metrics: Vec<String> = v
                .metrics
                .iter()
                .map(|m| {
                    format!(
                        "{} {} → <span class={}>{}</span>",
                        esc(&m.name),
                        opt(m.a),
                        verdict_class(&m.verdict),
                        opt(m.b)
                    )
                })
                .collect();
            let img = |run: &str, has: bool, label: &str| {
                if has {
                    format!(
                        "<a href=\"/runs/{}/images/{}/{}\">{label}</a>",
                        enc(run),
                        enc(&s.scenario),
                        enc(&v.variant)
                    )
                } else {
                    String::new()
                }
            };
            let both = if v.images_a && v.images_b {
                format!(
                    " <a href=\"/runs/{}/images/{}/{}?other={}\">A beside B</a>",
                    enc(&c.b.run_id),
                    enc(&s.scenario),
                    enc(&v.variant),
                    enc(&c.a.run_id)
                )
            } else {
                String::new()
            };
            let status = if v.status_a == v.status_b {
                esc(&v.status_a)
            } else {
                format!(
                    "<span class=worse>{} → {}</span>",
                    esc(&v.status_a),
                    esc(&v.status_b)
                )
            };
            let _ = write!(
                b,
                "<tr><td>{}</td><td>{status}</td><td class=n>{}</td><td class=n>{}</td><td class=\"n {}\">{}</td><td class={}>{} <span class=muted>{}</span></td><td class=wrap>{}</td><td class=wrap>{}</td><td>{} {}{both}</td></tr>",
                esc(&v.variant),
                opt(v.time.a),
                opt(v.time.b),
                verdict_class(&v.time.verdict),
                change(v.time.change),
                verdict_class(&v.time.verdict),
                esc(shown(&v.time.verdict)),
                p_value(v.time.p),
                passes.join(", "),
                metrics.join(", "),
                img(&c.a.run_id, v.images_a, "A"),
                img(&c.b.run_id, v.images_b, "B"),
            );
        }
        b.push_str("</table></div>");
        if !s.only_a.is_empty() || !s.only_b.is_empty() {
            let _ = write!(
                b,
                "<p class=muted>only in A: {} · only in B: {}</p>",
                esc(&s.only_a.join(", ")),
                esc(&s.only_b.join(", "))
            );
        }
    }
    if !c.only_a.is_empty() || !c.only_b.is_empty() {
        let _ = write!(
            b,
            "<p class=muted>scenarios only in A: {} · only in B: {}</p>",
            esc(&c.only_a.join(", ")),
            esc(&c.only_b.join(", "))
        );
    }
    b
}

fn form(q: &CompareRunsQuery) -> String {
    format!(
        "<form id=pick>A <input name=a size=28 value=\"{}\" placeholder=\"run id or commit\"> B <input name=b size=28 value=\"{}\" placeholder=\"run id or commit\"> suite <input name=suite size=10 value=\"{}\"> adapter id <input name=adapter size=4 value=\"{}\"> threshold % <input name=threshold size=4 value=\"{}\"> <button>compare</button></form>",
        esc(q.a.as_deref().unwrap_or("")),
        esc(q.b.as_deref().unwrap_or("")),
        esc(q.suite.as_deref().unwrap_or("")),
        q.adapter.map_or(String::new(), |a| a.to_string()),
        q.threshold
    )
}

pub async fn page(
    State(state): State<AppState>,
    RawQuery(raw): RawQuery,
) -> Result<Html<String>, AppError> {
    let q = parse_query(raw.as_deref())?;
    let mut body = form(&q);
    match load(&state, q).await? {
        Some(c) => {
            body.push_str(&render(&c));
            Ok(Html(layout(
                &format!("Compare {} with {}", c.b.run_id, c.a.run_id),
                "compare",
                &body,
            )))
        }
        None => {
            body.push_str("<p>Give two run ids (or two commits, with a suite and an adapter) above, or tick two runs in the <a href=\"/\">runs list</a>.</p>");
            Ok(Html(layout("Compare two runs", "compare", &body)))
        }
    }
}
