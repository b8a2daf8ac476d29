//! Adapter comparison (`/compare?a=&b=&suite=`, `/api/compare`): the newest run on adapter A (of
//! `suite` when given) and the run on adapter B of the same suite at the same commit, or else the
//! nearest in time (the page says which), side by side per scenario and variant, by speedup
//! against native on each adapter (raw milliseconds across vendors mix hardware with technique
//! effects).

use std::fmt::Write;

use axum::extract::{Query, State};
use axum::response::Html;
use axum::Json;
use serde::{Deserialize, Serialize};

use super::{AppError, AppState};
use crate::html::{enc, esc, ms, page as layout};
use crate::store::read::{self, AdapterRow};
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
}

#[derive(Debug, Serialize)]
pub struct Comparison {
    pub adapters: Vec<AdapterRow>,
    pub a: Option<i64>,
    pub b: Option<i64>,
    pub run_a: Option<String>,
    pub run_b: Option<String>,
    /// How run B was matched to run A: `same commit` or `nearest in time`.
    pub matched_by: Option<String>,
    pub suite: Option<String>,
    pub rows: Vec<CompareRow>,
}

async fn load(state: &AppState, q: CompareQuery) -> Result<Comparison, AppError> {
    state
        .db(move |c| {
            let adapters = read::adapters(c)?;
            let a = q.a.or_else(|| adapters.first().map(|x| x.id));
            let b =
                q.b.or_else(|| adapters.iter().map(|x| x.id).find(|&id| Some(id) != a));
            let suite = q.suite.filter(|s| !s.is_empty());
            let run_a = match (a, b) {
                // Without a suite: the newest run on A of a suite B has runs of too.
                (Some(a), Some(b)) if suite.is_none() => {
                    crate::store::browse::newest_with_shared_suite(c, a, b)?
                }
                (Some(a), _) => crate::store::browse::run_list(
                    c,
                    &crate::store::browse::RunFilter {
                        adapter: Some(a),
                        suite: suite.clone(),
                        ..Default::default()
                    },
                    0,
                    1,
                )?
                .runs
                .into_iter()
                .next()
                .map(|r| r.run.run_id),
                (None, _) => None,
            };
            let (run_b, matched_by) = match (&run_a, b) {
                (Some(ra), Some(b)) => match crate::store::browse::counterpart(c, ra, b)? {
                    Some(m) => (Some(m.run_id), Some(m.how)),
                    None => (None, None),
                },
                _ => (None, None),
            };
            let mut rows = Vec::new();
            if let (Some(ra), Some(rb)) = (&run_a, &run_b) {
                let sa = read::run_scenarios(c, ra)?;
                let sb = read::run_scenarios(c, rb)?;
                for s in &sa {
                    let Some(t) = sb.iter().find(|t| t.scenario == s.scenario) else {
                        continue;
                    };
                    for v in &s.results {
                        let Some(w) = t.results.iter().find(|w| w.variant == v.variant) else {
                            continue;
                        };
                        rows.push(CompareRow {
                            scenario: s.scenario.clone(),
                            variant: v.variant.clone(),
                            gpu_ms_a: v.gpu_frame_ms.map(|g| g.median),
                            gpu_ms_b: w.gpu_frame_ms.map(|g| g.median),
                            speedup_a: speedup(&s.results, v, DEFAULT_BASELINE),
                            speedup_b: speedup(&t.results, w, DEFAULT_BASELINE),
                            status_a: v.status.label().into(),
                            status_b: w.status.label().into(),
                        });
                    }
                }
            }
            Ok(Comparison {
                adapters,
                a,
                b,
                run_a,
                run_b,
                matched_by,
                suite,
                rows,
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

pub fn render(c: &Comparison) -> String {
    let name = |id: Option<i64>| {
        c.adapters
            .iter()
            .find(|a| Some(a.id) == id)
            .map_or("–".to_string(), |a| format!("{} ({})", a.name, a.backend))
    };
    let mut b = String::from("<form>");
    for (field, sel) in [("a", c.a), ("b", c.b)] {
        let _ = write!(b, "{field} <select name={field}>");
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
        b.push_str("</select> ");
    }
    let _ = write!(
        b,
        "suite <input name=suite size=10 value=\"{}\" placeholder=\"any\"> <button>compare</button></form>",
        esc(c.suite.as_deref().unwrap_or(""))
    );
    let link = |r: &Option<String>| {
        r.as_ref().map_or("–".into(), |r| {
            format!("<a href=\"/runs/{}\">{}</a>", enc(r), esc(r))
        })
    };
    let _ = write!(
        b,
        "<p>a: {} · newest run{} with runs on b too: {}<br>b: {} · {} {}</p>",
        esc(&name(c.a)),
        c.suite
            .as_deref()
            .map_or(String::new(), |s| format!(" of suite {}", esc(s))),
        link(&c.run_a),
        esc(&name(c.b)),
        match c.matched_by.as_deref() {
            Some("same commit") => "the run of the same suite at the same commit:".to_string(),
            Some(how) => format!(
                "no run of that commit; the run of the same suite {}:",
                esc(how)
            ),
            None => "no run of the same suite".to_string(),
        },
        link(&c.run_b)
    );
    if let (Some(ra), Some(rb)) = (&c.run_a, &c.run_b) {
        let _ = write!(
            b,
            "<p><a href=\"/compare/runs?a={}&b={}\">compare these two runs in detail</a></p>",
            enc(ra),
            enc(rb)
        );
    }
    b.push_str("<table id=compare><tr><th>scenario</th><th>variant</th><th class=n>speedup a</th><th class=n>speedup b</th><th class=n>b / a</th><th class=n>GPU ms a</th><th class=n>GPU ms b</th></tr>");
    for r in &c.rows {
        let ratio = match (r.speedup_a, r.speedup_b) {
            (Some(x), Some(y)) => format!("{:.2}", y / x),
            _ => "–".into(),
        };
        let _ = write!(
            b,
            "<tr><td>{}</td><td>{}</td><td class=n>{}</td><td class=n>{}</td><td class=n>{ratio}</td><td class=n>{}</td><td class=n>{}</td></tr>",
            esc(&r.scenario),
            esc(&r.variant),
            if r.status_a == "ok" { speed(r.speedup_a) } else { esc(&r.status_a) },
            if r.status_b == "ok" { speed(r.speedup_b) } else { esc(&r.status_b) },
            ms(r.gpu_ms_a),
            ms(r.gpu_ms_b)
        );
    }
    b.push_str("</table>");
    if c.adapters.len() < 2 {
        b.push_str(
            "<p>Only one adapter is stored: import runs from a second adapter to compare.</p>",
        );
    }
    b
}

pub async fn page(
    State(state): State<AppState>,
    Query(q): Query<CompareQuery>,
) -> Result<Html<String>, AppError> {
    let c = load(&state, q).await?;
    Ok(Html(layout("Adapter comparison", "adapters", &render(&c))))
}
