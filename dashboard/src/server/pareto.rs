//! Error against run time (`/pareto?scenario=&adapter=&metric=&run=&base=`, `/api/pareto`): per
//! scenario and adapter, every variant as a point (median GPU time, metric), the Pareto front, and
//! how both moved since an older run (`base`, by default the run before). The metric is picked from
//! those the run's scenario has (by default `flip`, else `psnr`, else the first one); points are
//! numbered as the table's rows, so labels never collide, and the chart zooms.

use std::fmt::Write;

use axum::extract::{Query, State};
use axum::response::Html;
use axum::Json;
use serde::{Deserialize, Serialize};
use tessera_results::{ScenarioResult, Status};

use super::{AppError, AppState};
use crate::chart::{ScatterChart, ScatterPoint as ChartPoint};
use crate::html::{chart, enc, esc, num, page as layout, script_json};
use crate::store::read;
use crate::svg::{pareto_front, scatter, ScatterPoint};

#[derive(Debug, Deserialize, Default)]
pub struct ParetoQuery {
    pub scenario: Option<String>,
    pub adapter: Option<i64>,
    /// `flip` (default), `psnr` or any stored metric.
    pub metric: Option<String>,
    /// A second error measure shown beside the first (`none` for one chart); by default the
    /// first other error measure the scenario has: a front can change with the measure.
    pub metric2: Option<String>,
    pub run: Option<String>,
    pub base: Option<String>,
}

#[derive(Debug, Serialize, Clone, PartialEq)]
pub struct ParetoPoint {
    pub variant: String,
    /// The variant's technique: points are coloured by it.
    pub technique: String,
    pub gpu_ms: f64,
    pub value: f64,
    /// The baseline's median GPU time over this variant's (`None` for the baseline itself).
    pub speedup: Option<f64>,
    pub on_front: bool,
    /// The 95% interval of the median GPU time over the measured frames (6 or more).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gpu_ms_interval: Option<[f64; 2]>,
    /// The 95% interval of the measure from its per-frame values (2 or more, not all equal):
    /// `value ± 1.96 σ/√n`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub value_interval: Option<[f64; 2]>,
}

/// `value ± 1.96 σ/√n` of the finite per-frame values; `None` with fewer than 2 or no spread.
pub fn frames_interval(value: f64, per_frame: &[f64]) -> Option<[f64; 2]> {
    let xs: Vec<f64> = per_frame
        .iter()
        .copied()
        .filter(|x| x.is_finite())
        .collect();
    let n = xs.len() as f64;
    if xs.len() < 2 {
        return None;
    }
    let mean = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    let half = 1.96 * (var / n).sqrt();
    (half > 0.0 && half.is_finite()).then_some([value - half, value + half])
}

/// Whether `name` is an error measure: an image metric of the measure table (PSNR, SSIM, FLIP,
/// ColorVideoVDP, ...), not a technique's own check (`shading-rate`, `model-shades`) or a count.
pub fn is_error_measure(name: &str) -> bool {
    tessera_results::measure::Measure::from_name(name)
        .is_some_and(|m| m.info().source == tessera_results::measure::Source::Metric)
}

/// The colour of technique `t` among `all` (in first-seen order).
fn technique_colour(all: &[String], t: &str) -> &'static str {
    crate::svg::colour(all.iter().position(|x| x == t).unwrap_or(0))
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
    /// Metrics of the run's scenario with a finite value for some timed variant.
    pub metrics: Vec<String>,
    /// The second measure and its points (the newer run's), when shown.
    pub metric2: Option<String>,
    pub higher_is_better2: bool,
    pub points2: Vec<ParetoPoint>,
}

/// Error-measure names ([`is_error_measure`]) of ok, timed variants with a finite value, in
/// first-seen order.
pub fn metrics_present(s: &ScenarioResult) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for v in s
        .results
        .iter()
        .filter(|v| v.status == Status::Ok && v.gpu_frame_ms.is_some())
    {
        for m in v
            .metrics
            .iter()
            .filter(|m| m.value.is_finite() && is_error_measure(&m.name))
        {
            if !out.contains(&m.name) {
                out.push(m.name.clone());
            }
        }
    }
    out
}

/// Points of one scenario record for `metric`, with the Pareto front marked. Variants without GPU
/// time or without a finite metric value are left out.
pub fn points(s: &ScenarioResult, metric: &str) -> (Vec<ParetoPoint>, bool) {
    // The measure table's direction; a metric it does not know takes its record's.
    let known = tessera_results::measure::Measure::from_name(metric);
    let mut hib = known.is_some_and(|m| m.direction().higher_is_better());
    let mut pts: Vec<ParetoPoint> = Vec::new();
    for v in s.results.iter().filter(|v| v.status == Status::Ok) {
        let Some(g) = v.gpu_frame_ms else { continue };
        let Some(m) = v.metrics.iter().find(|m| m.name == metric) else {
            continue;
        };
        if known.is_none() {
            hib = m.higher_is_better;
        }
        if m.value.is_finite() {
            pts.push(ParetoPoint {
                variant: v.variant.clone(),
                technique: v.technique.clone(),
                speedup: tessera_results::measure::speedup(
                    &s.results,
                    v,
                    tessera_results::measure::DEFAULT_BASELINE,
                ),
                gpu_ms: g.median,
                value: m.value,
                on_front: false,
                gpu_ms_interval: g.median_ci95,
                value_interval: frames_interval(m.value, &m.per_frame),
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
            let asked = q.metric.filter(|m| !m.is_empty());
            let metric = asked.clone().unwrap_or_else(|| "flip".into());
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
                metrics: vec![],
                metric2: None,
                higher_is_better2: false,
                points2: vec![],
            };
            let (Some(scenario), Some(adapter)) = (scenario, adapter) else {
                return Ok(view);
            };
            let recent = read::latest_runs_with(c, adapter, Some(&scenario), 2)?;
            let run = q.run.or_else(|| recent.first().cloned());
            let base = q
                .base
                .or_else(|| recent.iter().find(|r| Some(*r) != run.as_ref()).cloned());
            let mut metric = metric;
            if let Some(run) = &run {
                let record = read::scenario_result(c, run, &scenario)?;
                view.metrics = metrics_present(&record);
                // Without an explicit choice, open on a metric the scenario has.
                if asked.is_none() && !view.metrics.contains(&metric) {
                    metric = ["psnr", "ssim"]
                        .iter()
                        .map(|m| m.to_string())
                        .find(|m| view.metrics.contains(m))
                        .or_else(|| view.metrics.first().cloned())
                        .unwrap_or(metric);
                }
                let (p, hib) = points(&record, &metric);
                view.points = p;
                view.higher_is_better = hib;
                let second = match q.metric2.as_deref().filter(|m| !m.is_empty()) {
                    Some("none") => None,
                    Some(m) => Some(m.to_string()),
                    // A perceptual or structural measure beside a per-pixel one, where present.
                    None => ["cvvdp", "psnr", "ssim", "flip"]
                        .iter()
                        .map(|m| m.to_string())
                        .find(|m| *m != metric && view.metrics.contains(m))
                        .or_else(|| view.metrics.iter().find(|m| **m != metric).cloned()),
                };
                if let Some(m2) = second.filter(|m| *m != metric) {
                    let (p2, hib2) = points(&record, &m2);
                    view.points2 = p2;
                    view.higher_is_better2 = hib2;
                    view.metric2 = Some(m2);
                }
            }
            if let Some(base) = &base {
                view.base_points = points(&read::scenario_result(c, base, &scenario)?, &metric).0;
            }
            view.metric = metric;
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
    b.push_str("</select> metric <select name=metric>");
    let mut names = v.metrics.clone();
    if !names.contains(&v.metric) {
        names.push(v.metric.clone());
    }
    for m in &names {
        let sel = if *m == v.metric { " selected" } else { "" };
        let _ = write!(b, "<option{sel}>{}</option>", esc(m));
    }
    b.push_str("</select> beside it <select name=metric2><option value=none>none</option>");
    for m in &v.metrics {
        let sel = if Some(m) == v.metric2.as_ref() {
            " selected"
        } else {
            ""
        };
        let _ = write!(b, "<option{sel}>{}</option>", esc(m));
    }
    b.push_str("</select> <button>show</button></form>");
    let link = |r: &Option<String>| {
        r.as_ref().map_or("–".into(), |r| {
            format!("<a href=\"/runs/{}\">{}</a>", enc(r), esc(r))
        })
    };
    // The hollow points only when a base run is shown.
    let hollow = v
        .base
        .as_ref()
        .map(|_| format!(" · hollow: run {}", link(&v.base)))
        .unwrap_or_default();
    let _ = write!(
        b,
        "<p>filled: run {}{hollow} · {} ({} is better) against median GPU ms; the line joins the Pareto front; bars: 95% intervals where the run has repeats (the median over the timed frames, the measure over the compared frames)</p>",
        link(&v.run),
        esc(&v.metric),
        if v.higher_is_better { "higher" } else { "lower" }
    );
    let mut techniques: Vec<String> = Vec::new();
    for p in v.points.iter().chain(&v.base_points) {
        if !techniques.contains(&p.technique) {
            techniques.push(p.technique.clone());
        }
    }
    // Row numbers: the table's rows (the newer run's points, in order). A point with no row (a
    // variant only the older run has, or only the second measure: the reference, whose error
    // against itself the first measure leaves out) is drawn without a number, since a number on
    // the chart names a row of the table.
    let num_of = |variant: &str| {
        v.points
            .iter()
            .position(|p| p.variant == variant)
            .map(|i| i + 1)
    };
    let tag_of = |variant: &str| num_of(variant).map_or(String::new(), |n| n.to_string());
    let label_of = |variant: &str| match num_of(variant) {
        Some(n) => format!("#{n} {variant}"),
        None => variant.to_string(),
    };
    let tagged = v
        .points
        .iter()
        .map(|p| (p, 0))
        .chain(v.base_points.iter().map(|p| (p, 1)));
    let pts: Vec<ScatterPoint> = tagged
        .clone()
        .map(|(p, group)| ScatterPoint {
            label: label_of(&p.variant),
            x: p.gpu_ms,
            y: p.value,
            group,
            on_front: p.on_front,
            tag: tag_of(&p.variant),
            colour: technique_colour(&techniques, &p.technique),
        })
        .collect();
    let spec = ScatterChart {
        kind: "scatter",
        x_label: "GPU time, median (ms)".into(),
        y_label: crate::html::axis_label(&v.metric),
        // The base run's group only when there is one (its legend entries read "run –" else).
        groups: std::iter::once(format!("run {}", v.run.as_deref().unwrap_or("–")))
            .chain(v.base.as_deref().map(|b| format!("run {b}")))
            .collect(),
        points: tagged
            .map(|(p, group)| ChartPoint {
                x: p.gpu_ms,
                y: p.value,
                group,
                num: num_of(&p.variant),
                label: p.variant.clone(),
                front: p.on_front,
                colour: technique_colour(&techniques, &p.technique).to_string(),
                x_interval: p.gpu_ms_interval.filter(|_| group == 0),
                y_interval: p.value_interval.filter(|_| group == 0),
            })
            .collect(),
    };
    let fallback = scatter(
        &pts,
        "GPU time, median (ms)",
        &crate::html::axis_label(&v.metric),
    );
    let first = if spec.points.is_empty() {
        fallback
    } else {
        chart("pareto-chart", &script_json(&spec), &fallback)
    };
    match &v.metric2 {
        Some(m2) => {
            // The second measure beside the first, its own front: a technique on one front may
            // be dominated on the other.
            let pts2: Vec<ScatterPoint> = v
                .points2
                .iter()
                .map(|p| ScatterPoint {
                    label: label_of(&p.variant),
                    x: p.gpu_ms,
                    y: p.value,
                    group: 0,
                    on_front: p.on_front,
                    tag: tag_of(&p.variant),
                    colour: technique_colour(&techniques, &p.technique),
                })
                .collect();
            let _ = write!(
                b,
                "<div class=pareto-pair style=\"display:flex;flex-wrap:wrap;gap:12px\"><div style=\"flex:1 1 480px;min-width:0\">{first}</div><div id=pareto-second style=\"flex:1 1 480px;min-width:0\"><p class=muted>{} ({} is better) against the same GPU time</p>{}</div></div>",
                esc(m2),
                if v.higher_is_better2 { "higher" } else { "lower" },
                scatter(
                    &pts2,
                    "GPU time, median (ms)",
                    &crate::html::axis_label(m2)
                )
            );
        }
        None => b.push_str(&first),
    }
    // The legend of the colours: one per technique.
    b.push_str("<ul class=\"legend techniques\">");
    for t in &techniques {
        let _ = write!(
            b,
            "<li style=\"display:inline-block;margin-right:12px\"><span class=swatch style=\"background:{}\"></span>{}</li>",
            technique_colour(&techniques, t),
            esc(t)
        );
    }
    b.push_str("</ul>");
    let unit = tessera_results::measure::Measure::from_name(&v.metric)
        .map(|m| m.unit())
        .filter(|u| !u.is_empty())
        .map_or(String::new(), |u| format!(" ({u})"));
    let _ = write!(
        b,
        "<div class=scroll><table id=pareto><tr><th class=n>#</th><th>variant</th><th class=n>GPU (ms)</th><th class=n>speed-up (×)</th><th class=n>{m}{unit}</th><th>front</th>{second}<th class=n>before: GPU (ms)</th><th class=n>before: {m}{unit}</th></tr>",
        m = esc(&v.metric),
        second = v.metric2.as_ref().map_or(String::new(), |m2| format!(
            "<th class=n>{}{}</th><th>front ({})</th>",
            esc(m2),
            tessera_results::measure::Measure::from_name(m2)
                .map(|m| m.unit())
                .filter(|u| !u.is_empty())
                .map_or(String::new(), |u| format!(" ({u})")),
            esc(m2)
        ))
    );
    for (row, p) in v.points.iter().enumerate() {
        let old = v.base_points.iter().find(|q| q.variant == p.variant);
        let _ = write!(
            b,
            "<tr><td class=n>{}</td><td><span class=swatch style=\"background:{}\" title=\"{}\"></span>{}</td><td class=n>{}</td><td class=n>{}</td><td class=n>{}</td><td>{}</td>{}<td class=n>{}</td><td class=n>{}</td></tr>",
            row + 1,
            technique_colour(&techniques, &p.technique),
            esc(&p.technique),
            crate::html::name(&p.variant),
            with_interval(p.gpu_ms, p.gpu_ms_interval),
            p.speedup.map_or("–".into(), |x| format!("{x:.2}")),
            with_interval(p.value, p.value_interval),
            if p.on_front { "on front" } else { "dominated" },
            match &v.metric2 {
                Some(_) => {
                    let q = v.points2.iter().find(|q| q.variant == p.variant);
                    format!(
                        "<td class=n>{}</td><td>{}</td>",
                        q.map_or("–".into(), |q| num(q.value)),
                        q.map_or("–", |q| if q.on_front { "on front" } else { "dominated" })
                    )
                }
                None => String::new(),
            },
            old.map_or("–".into(), |q| num(q.gpu_ms)),
            old.map_or("–".into(), |q| num(q.value))
        );
    }
    b.push_str("</table></div>");
    b
}

/// A value with its 95% interval under it, small: `1.234` / `1.20–1.25`.
fn with_interval(v: f64, interval: Option<[f64; 2]>) -> String {
    match interval {
        Some([lo, hi]) => format!(
            "{}<br><span class=muted title=\"95% interval\">{}–{}</span>",
            num(v),
            num(lo),
            num(hi)
        ),
        None => num(v),
    }
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

#[cfg(test)]
mod tests {
    #[test]
    fn the_interval_of_repeats_is_the_means_95_percent_interval_around_the_value() {
        // Mean 2, sample σ 1, n 3: ±1.96/√3.
        let [lo, hi] = super::frames_interval(2.5, &[1.0, 2.0, 3.0, f64::INFINITY]).unwrap();
        let half = 1.96 / 3f64.sqrt();
        assert!((lo - (2.5 - half)).abs() < 1e-12 && (hi - (2.5 + half)).abs() < 1e-12);
        // No repeats, or no spread: no bar.
        assert_eq!(super::frames_interval(1.0, &[1.0]), None);
        assert_eq!(super::frames_interval(1.0, &[1.0, 1.0, 1.0]), None);
    }
}
