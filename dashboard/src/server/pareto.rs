//! Error against run time (`/pareto?scenario=&adapter=&metric=&run=&base=`, `/api/pareto`): per
//! scenario and adapter, every variant as a point (median GPU time, metric), the Pareto front, and
//! how both moved since an older run (`base`, by default the run before).

use std::fmt::Write;

use axum::extract::{Query, State};
use axum::response::Html;
use axum::Json;
use serde::{Deserialize, Serialize};
use tessera_results::{ScenarioResult, Status};

use super::{AppError, AppState};
use crate::html::{enc, esc, num, page as layout};
use crate::store::read;
use crate::svg::{pareto_front, scatter, ScatterPoint};

#[derive(Debug, Deserialize, Default)]
pub struct ParetoQuery {
    pub scenario: Option<String>,
    pub adapter: Option<i64>,
    /// `flip` (default), `psnr` or any stored metric.
    pub metric: Option<String>,
    pub run: Option<String>,
    pub base: Option<String>,
}

#[derive(Debug, Serialize, Clone, PartialEq)]
pub struct ParetoPoint {
    pub variant: String,
    pub gpu_ms: f64,
    pub value: f64,
    pub on_front: bool,
}

#[derive(Debug, Serialize)]
pub struct ParetoView {
    pub scenarios: Vec<String>,
    pub adapters: Vec<read::AdapterRow>,
    pub scenario: Option<String>,
    pub adapter: Option<i64>,
    pub metric: String,
    pub higher_is_better: bool,
    pub run: Option<String>,
    pub base: Option<String>,
    pub points: Vec<ParetoPoint>,
    pub base_points: Vec<ParetoPoint>,
}

/// Points of one scenario record for `metric`, with the Pareto front marked. Variants without GPU
/// time or without a finite metric value are left out.
pub fn points(s: &ScenarioResult, metric: &str) -> (Vec<ParetoPoint>, bool) {
    // Until a record says (its `higher_is_better`): the measures known to grow with quality.
    let mut hib = metric.starts_with("psnr")
        || matches!(metric, "ssim" | "ssim-luma" | "cvvdp" | "cvvdp-flicker");
    let mut pts: Vec<ParetoPoint> = Vec::new();
    for v in s.results.iter().filter(|v| v.status == Status::Ok) {
        let Some(g) = v.gpu_frame_ms else { continue };
        let Some(m) = v.metrics.iter().find(|m| m.name == metric) else {
            continue;
        };
        hib = m.higher_is_better;
        if m.value.is_finite() {
            pts.push(ParetoPoint {
                variant: v.variant.clone(),
                gpu_ms: g.median,
                value: m.value,
                on_front: false,
            });
        }
    }
    let xy: Vec<(f64, f64)> = pts.iter().map(|p| (p.gpu_ms, p.value)).collect();
    for i in pareto_front(&xy, hib) {
        pts[i].on_front = true;
    }
    (pts, hib)
}

async fn load(state: &AppState, q: ParetoQuery) -> Result<ParetoView, AppError> {
    state
        .db(move |c| {
            let adapters = read::adapters(c)?;
            let adapter = q.adapter.or_else(|| adapters.first().map(|a| a.id));
            let scenarios = read::scenarios_on(c, adapter)?;
            let scenario = q
                .scenario
                .filter(|s| !s.is_empty())
                .or_else(|| scenarios.first().cloned());
            let metric = q
                .metric
                .filter(|m| !m.is_empty())
                .unwrap_or_else(|| "flip".into());
            let mut view = ParetoView {
                scenarios,
                adapters,
                scenario: scenario.clone(),
                adapter,
                higher_is_better: false,
                metric: metric.clone(),
                run: None,
                base: None,
                points: vec![],
                base_points: vec![],
            };
            let (Some(scenario), Some(adapter)) = (scenario, adapter) else {
                return Ok(view);
            };
            let recent = read::latest_runs_with(c, adapter, Some(&scenario), 2)?;
            let run = q.run.or_else(|| recent.first().cloned());
            let base = q
                .base
                .or_else(|| recent.iter().find(|r| Some(*r) != run.as_ref()).cloned());
            if let Some(run) = &run {
                let (p, hib) = points(&read::scenario_result(c, run, &scenario)?, &metric);
                view.points = p;
                view.higher_is_better = hib;
            }
            if let Some(base) = &base {
                view.base_points = points(&read::scenario_result(c, base, &scenario)?, &metric).0;
            }
            view.run = run;
            view.base = base;
            Ok(view)
        })
        .await
}

pub async fn api(
    State(state): State<AppState>,
    Query(q): Query<ParetoQuery>,
) -> Result<Json<ParetoView>, AppError> {
    Ok(Json(load(&state, q).await?))
}

pub fn render(v: &ParetoView) -> String {
    let mut b = String::from("<form>scenario <select name=scenario>");
    for s in &v.scenarios {
        let sel = if Some(s) == v.scenario.as_ref() {
            " selected"
        } else {
            ""
        };
        let _ = write!(b, "<option{sel}>{}</option>", esc(s));
    }
    b.push_str("</select> adapter <select name=adapter>");
    for a in &v.adapters {
        let sel = if Some(a.id) == v.adapter {
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
    let _ = write!(
        b,
        "</select> metric <input name=metric size=10 value=\"{}\"> <button>show</button></form>",
        esc(&v.metric)
    );
    let link = |r: &Option<String>| {
        r.as_ref().map_or("–".into(), |r| {
            format!("<a href=\"/runs/{}\">{}</a>", enc(r), esc(r))
        })
    };
    let _ = write!(
        b,
        "<p>filled: run {} · hollow: run {} · {} ({} is better) against median GPU ms; the line joins the Pareto front</p>",
        link(&v.run),
        link(&v.base),
        esc(&v.metric),
        if v.higher_is_better { "higher" } else { "lower" }
    );
    let pts: Vec<ScatterPoint> = v
        .points
        .iter()
        .map(|p| (p, 0))
        .chain(v.base_points.iter().map(|p| (p, 1)))
        .map(|(p, group)| ScatterPoint {
            label: p.variant.clone(),
            x: p.gpu_ms,
            y: p.value,
            group,
            on_front: p.on_front,
        })
        .collect();
    b.push_str(&scatter(&pts, "GPU ms", &v.metric));
    b.push_str("<table><tr><th>variant</th><th class=n>GPU ms</th><th class=n>value</th><th>front</th><th class=n>before: GPU ms</th><th class=n>value</th></tr>");
    for p in &v.points {
        let old = v.base_points.iter().find(|q| q.variant == p.variant);
        let _ = write!(
            b,
            "<tr><td>{}</td><td class=n>{}</td><td class=n>{}</td><td>{}</td><td class=n>{}</td><td class=n>{}</td></tr>",
            esc(&p.variant),
            num(p.gpu_ms),
            num(p.value),
            if p.on_front { "on front" } else { "dominated" },
            old.map_or("–".into(), |q| num(q.gpu_ms)),
            old.map_or("–".into(), |q| num(q.value))
        );
    }
    b.push_str("</table>");
    b
}

pub async fn page(
    State(state): State<AppState>,
    Query(q): Query<ParetoQuery>,
) -> Result<Html<String>, AppError> {
    let v = load(&state, q).await?;
    Ok(Html(layout(
        "Error against run time",
        "error vs time",
        &render(&v),
    )))
}
