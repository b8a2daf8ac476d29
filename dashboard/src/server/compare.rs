//! Adapter comparison (`/compare?a=&b=&suite=`, `/api/compare`): for two adapters, the newest
//! pair of runs that share scenarios (A's newest run that has a partner on B: B's run of the same
//! commit, else B's newest run sharing scenarios; `store::adapter_pairs`), the page saying which
//! scenarios they share; per variant the speed-up against each run's baseline on each adapter
//! (raw milliseconds across vendors mix hardware with technique effects), the ratio B / A with
//! its 99% interval (the comparison engine's test of the cost relative to the baseline), a chart
//! of the ratios and their geometric mean, and the CPU-adapter warning. With no shared scenario
//! it lists what each adapter has.

use std::fmt::Write;

use axum::extract::{Query, State};
use axum::response::Html;
use axum::Json;
use serde::{Deserialize, Serialize};

use super::{AppError, AppState};
use crate::html::{enc, esc, ms, name as name_cell, page as layout};
use crate::interval_chart;
use crate::store::adapter_pairs::{self, Holdings};
use crate::store::read::{self, AdapterRow};
use tessera_results::compare::{self as engine, RunRef, Time};
use tessera_results::measure::{speedup, DEFAULT_BASELINE};

#[derive(Debug, Deserialize, Default)]
pub struct CompareQuery {
    pub a: Option<i64>,
    pub b: Option<i64>,
    pub suite: Option<String>,
}

#[derive(Debug, Serialize, Clone, PartialEq)]
pub struct CompareRow {
    pub scenario: String,
    pub variant: String,
    pub gpu_ms_a: Option<f64>,
    pub gpu_ms_b: Option<f64>,
    pub speedup_a: Option<f64>,
    pub speedup_b: Option<f64>,
    pub status_a: String,
    pub status_b: String,
    /// `speedup_b / speedup_a`: above 1 the technique saves more on B.
    pub ratio: Option<f64>,
    /// The ratio's 99% interval, from the test of each variant's per-frame cost relative to its
    /// baseline in its own run.
    pub interval: Option<[f64; 2]>,
}

#[derive(Debug, Serialize)]
pub struct Comparison {
    pub adapters: Vec<AdapterRow>,
    pub a: Option<i64>,
    pub b: Option<i64>,
    pub run_a: Option<String>,
    pub run_b: Option<String>,
    /// How run B was paired with run A: `same commit` or `newest run sharing scenarios`.
    pub matched_by: Option<String>,
    pub suite: Option<String>,
    /// The scenarios both runs hold.
    pub scenarios: Vec<String>,
    pub rows: Vec<CompareRow>,
    /// Geometric mean of the rows' ratios.
    pub geometric_mean: Option<f64>,
    /// The CPU adapter of the pair, when one is (its timings measure CPU work and load).
    pub cpu_adapter: Option<String>,
    /// What each adapter has, when no pair of runs shares a scenario.
    pub holdings: Option<Holdings>,
}

/// The ratio B / A of a variant's speed-up and its interval, from the engine's test of the
/// frame cost relative to the baseline (cost change `c` is a speed-up ratio of `1 / (1 + c)`).
fn ratio_of(t: &Time) -> (Option<f64>, Option<[f64; 2]>) {
    match t.tested() {
        Some(x) if x.change > -1.0 => (
            Some(1.0 / (1.0 + x.change)),
            x.interval
                .filter(|[lo, hi]| *lo > -1.0 && *hi > -1.0)
                .map(|[lo, hi]| [1.0 / (1.0 + hi), 1.0 / (1.0 + lo)]),
        ),
        _ => (None, None),
    }
}

async fn load(state: &AppState, q: CompareQuery) -> Result<Comparison, AppError> {
    state
        .db(move |c| {
            let adapters = read::adapters(c)?;
            let a = q.a.or_else(|| adapters.first().map(|x| x.id));
            let b =
                q.b.or_else(|| adapters.iter().map(|x| x.id).find(|&id| Some(id) != a));
            let suite = q.suite.filter(|s| !s.is_empty());
            let pair = match (a, b) {
                (Some(a), Some(b)) => {
                    adapter_pairs::newest_sharing_pair(c, a, b, suite.as_deref())?
                }
                _ => None,
            };
            let holdings = match (a, b, &pair) {
                (Some(a), Some(b), None) => Some(adapter_pairs::holdings(c, a, b)?),
                _ => None,
            };
            let mut rows = Vec::new();
            let mut cpu_adapter = None;
            if let Some(p) = &pair {
                let (ha, sa) = read::run_records(c, &p.run_a)?;
                let (hb, sb) = read::run_records(c, &p.run_b)?;
                for r in [&ha.info, &hb.info] {
                    if r.adapter.device_type == "cpu" && cpu_adapter.is_none() {
                        cpu_adapter = Some(r.adapter.name.clone());
                    }
                }
                let cmp = engine::compare(
                    RunRef {
                        info: &ha.info,
                        scenarios: &sa,
                    },
                    RunRef {
                        info: &hb.info,
                        scenarios: &sb,
                    },
                    &engine::Options::default(),
                );
                for s in &sa {
                    let Some(t) = sb.iter().find(|t| t.scenario == s.scenario) else {
                        continue;
                    };
                    for v in &s.results {
                        let Some(w) = t.results.iter().find(|w| w.variant == v.variant) else {
                            continue;
                        };
                        let speedup_a = speedup(&s.results, v, DEFAULT_BASELINE);
                        let speedup_b = speedup(&t.results, w, DEFAULT_BASELINE);
                        let time = cmp
                            .variants()
                            .find(|(x, y)| x.scenario == s.scenario && y.variant == v.variant)
                            .map(|(_, y)| &y.time);
                        let (ratio, interval) = match (time.map(ratio_of), speedup_a, speedup_b) {
                            // The baseline's own speed-up is 1 on both: not a ratio to count.
                            _ if matches!(time, Some(Time::Baseline)) => (None, None),
                            (Some((Some(r), i)), _, _) if !cmp.same_adapter => (Some(r), i),
                            (_, Some(x), Some(y)) if x > 0.0 => (Some(y / x), None),
                            _ => (None, None),
                        };
                        rows.push(CompareRow {
                            scenario: s.scenario.clone(),
                            variant: v.variant.clone(),
                            gpu_ms_a: v.gpu_frame_ms.map(|g| g.median),
                            gpu_ms_b: w.gpu_frame_ms.map(|g| g.median),
                            speedup_a,
                            speedup_b,
                            status_a: v.status.label().into(),
                            status_b: w.status.label().into(),
                            ratio,
                            interval,
                        });
                    }
                }
            }
            let logs: Vec<f64> = rows
                .iter()
                .filter_map(|r| r.ratio.filter(|x| *x > 0.0 && x.is_finite()))
                .map(f64::ln)
                .collect();
            let geometric_mean =
                (!logs.is_empty()).then(|| (logs.iter().sum::<f64>() / logs.len() as f64).exp());
            Ok(Comparison {
                adapters,
                a,
                b,
                run_a: pair.as_ref().map(|p| p.run_a.clone()),
                run_b: pair.as_ref().map(|p| p.run_b.clone()),
                matched_by: pair.as_ref().map(|p| p.how.clone()),
                scenarios: pair.map(|p| p.scenarios).unwrap_or_default(),
                suite,
                rows,
                geometric_mean,
                cpu_adapter,
                holdings,
            })
        })
        .await
}

pub async fn api(
    State(state): State<AppState>,
    Query(q): Query<CompareQuery>,
) -> Result<Json<Comparison>, AppError> {
    Ok(Json(load(&state, q).await?))
}

fn speed(v: Option<f64>) -> String {
    v.map_or("–".into(), |x| format!("{x:.2}×"))
}

fn list(names: &[String]) -> String {
    if names.is_empty() {
        "none".into()
    } else {
        names.iter().map(|n| esc(n)).collect::<Vec<_>>().join(", ")
    }
}

pub fn render(c: &Comparison) -> String {
    let name = |id: Option<i64>| {
        c.adapters
            .iter()
            .find(|a| Some(a.id) == id)
            .map_or("–".to_string(), |a| format!("{} ({})", a.name, a.backend))
    };
    let mut b = String::from("<form id=adapters-form>");
    for (field, sel) in [("a", c.a), ("b", c.b)] {
        let _ = write!(b, "<label>{field} <select name={field}>");
        for a in &c.adapters {
            let s = if Some(a.id) == sel { " selected" } else { "" };
            let _ = write!(
                b,
                "<option value={}{s}>{} ({}, {} runs)</option>",
                a.id,
                esc(&a.name),
                esc(&a.backend),
                a.runs
            );
        }
        b.push_str("</select></label> ");
    }
    let _ = write!(
        b,
        "<label>suite <input name=suite size=10 value=\"{}\" placeholder=\"any\"></label> <button>compare</button></form>",
        esc(c.suite.as_deref().unwrap_or(""))
    );
    if c.adapters.len() < 2 {
        b.push_str(
            "<p>Only one adapter is stored: import runs from a second adapter to compare.</p>",
        );
        return b;
    }
    let link = |r: &Option<String>| {
        r.as_ref().map_or("–".into(), |r| {
            format!("<a href=\"/runs/{}\">{}</a>", enc(r), esc(r))
        })
    };
    match (&c.run_a, &c.run_b) {
        (Some(ra), Some(rb)) => {
            let _ = write!(
                b,
                "<p id=pair>a: {} · {}<br>b: {} · {} ({})<br>{} shared: {} · <a href=\"/compare/runs?a={}&b={}\">compare these two runs in detail</a></p>",
                esc(&name(c.a)),
                link(&c.run_a),
                esc(&name(c.b)),
                link(&c.run_b),
                esc(c.matched_by.as_deref().unwrap_or("")),
                if c.scenarios.len() == 1 { "scenario" } else { "scenarios" },
                list(&c.scenarios),
                enc(ra),
                enc(rb)
            );
        }
        _ => {
            let _ = write!(
                b,
                "<p id=nothing-shared class=neutral>No run on {} shares a scenario with a run on {}{}.</p>",
                esc(&name(c.a)),
                esc(&name(c.b)),
                c.suite
                    .as_deref()
                    .map_or(String::new(), |s| format!(" in suite {}", esc(s)))
            );
            if let Some(h) = &c.holdings {
                let _ = write!(
                    b,
                    "<ul id=holdings><li>a has suites {} and scenarios {}</li><li>b has suites {} and scenarios {}</li><li>scenarios both have run: {}</li></ul>",
                    list(&h.suites_a),
                    list(&h.scenarios_a),
                    list(&h.suites_b),
                    list(&h.scenarios_b),
                    list(&h.shared_scenarios)
                );
            }
            return b;
        }
    }
    if let Some(cpu) = &c.cpu_adapter {
        let _ = write!(
            b,
            "<p id=cpu-warning class=worse>{} is a CPU adapter: its timings measure CPU work and the machine's load (lavapipe's repeat runs differ by tens of percent), so ratios involving it say little about a GPU.</p>",
            esc(cpu)
        );
    }
    let mut chart_rows: Vec<interval_chart::Row> = c
        .rows
        .iter()
        .filter_map(|r| {
            Some(interval_chart::Row {
                label: format!("{} / {}", r.scenario, r.variant),
                value: r.ratio?,
                interval: r.interval,
                summary: false,
            })
        })
        .collect();
    if let Some(g) = c.geometric_mean {
        let _ = write!(
            b,
            "<p id=summary><strong>Geometric mean of the speed-up ratios B / A: {g:.3}</strong> over {} variants ({}).</p>",
            chart_rows.len(),
            if g >= 1.0 {
                "the techniques save more, relative to their baseline, on b"
            } else {
                "the techniques save more, relative to their baseline, on a"
            }
        );
        chart_rows.push(interval_chart::Row {
            label: "geometric mean".into(),
            value: g,
            interval: None,
            summary: true,
        });
    }
    b.push_str("<div class=scroll>");
    b.push_str(&interval_chart::chart(
        &chart_rows,
        "speed-up ratio B / A (99% interval; 1 = the same saving on both)",
    ));
    b.push_str("</div>");
    b.push_str("<p class=muted>Speed-up: the baseline's median GPU time over the variant's, in its own run. Ratio B / A: the speed-up on b over that on a; above 1 the technique saves more on b. Its interval is the 99% interval of the change of each variant's per-frame cost relative to its baseline (the test of <code>tessera compare</code>).</p>");
    b.push_str("<div class=scroll><table id=compare><tr><th>scenario</th><th>variant</th><th class=n>speed-up a (×)</th><th class=n>speed-up b (×)</th><th class=n>ratio B / A</th><th class=n>99% interval</th><th class=\"n wide\">GPU a (ms)</th><th class=\"n wide\">GPU b (ms)</th></tr>");
    for r in &c.rows {
        let ratio = r.ratio.map_or("–".into(), |x| format!("{x:.3}"));
        let interval = r
            .interval
            .map_or("–".into(), |[lo, hi]| format!("{lo:.3}–{hi:.3}"));
        let _ = write!(
            b,
            "<tr><td>{}</td><td>{}</td><td class=n>{}</td><td class=n>{}</td><td class=n>{ratio}</td><td class=n>{interval}</td><td class=\"n wide\">{}</td><td class=\"n wide\">{}</td></tr>",
            name_cell(&r.scenario),
            name_cell(&r.variant),
            if r.status_a == "ok" { speed(r.speedup_a) } else { esc(&r.status_a) },
            if r.status_b == "ok" { speed(r.speedup_b) } else { esc(&r.status_b) },
            ms(r.gpu_ms_a),
            ms(r.gpu_ms_b)
        );
    }
    b.push_str("</table></div>");
    b
}

pub async fn page(
    State(state): State<AppState>,
    Query(q): Query<CompareQuery>,
) -> Result<Html<String>, AppError> {
    let c = load(&state, q).await?;
    Ok(Html(layout("Adapter comparison", "adapters", &render(&c))))
}
