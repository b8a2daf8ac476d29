//! One run (`/runs/{run_id}`, `/api/runs/{run_id}`): per scenario, every variant with its status
//! or skip reason, per-pass GPU time (stacked), speedup against native on the same adapter,
//! metrics, memory, and links to its series and images.

use std::fmt::Write;

use axum::extract::{Path, State};
use axum::response::Html;
use axum::Json;
use tessera_results::{ScenarioResult, Status};

use super::{AppError, AppState};
use crate::html::{bytes, commit, enc, esc, ms, num, page as layout};
use crate::store::measures::{native_gpu_ms, speedup};
use crate::store::read::{self, RunDetail};
use crate::svg::{stacked_bars, Bar};

async fn load(state: &AppState, run_id: String) -> Result<RunDetail, AppError> {
    state.db(move |c| Ok(read::run(c, &run_id)?)).await
}

pub async fn api(
    State(state): State<AppState>,
    Path(run_id): Path<String>,
) -> Result<Json<RunDetail>, AppError> {
    Ok(Json(load(&state, run_id).await?))
}

fn scenario_section(d: &RunDetail, s: &ScenarioResult, out: &mut String) {
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
    let native = native_gpu_ms(s);
    let mut metric_names: Vec<&str> = Vec::new();
    for m in s.results.iter().flat_map(|v| &v.metrics) {
        if !metric_names.contains(&m.name.as_str()) {
            metric_names.push(&m.name);
        }
    }
    let _ = write!(out, "<table class=variants><tr><th>variant</th><th>status</th><th class=n>GPU ms</th><th class=n>CPU ms</th><th class=n>speedup</th>");
    for m in &metric_names {
        let _ = write!(out, "<th class=n>{}</th>", esc(m));
    }
    out.push_str("<th class=n>memory</th><th>passes</th><th>gates</th><th></th></tr>");
    for v in &s.results {
        let series_link = d
            .series
            .iter()
            .find(|l| {
                l.scenario == s.scenario && l.variant == v.variant && l.measure == "gpu_ms.median"
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
        let sp = speedup(v, native).map_or("–".into(), |x| format!("{x:.2}×"));
        let _ = write!(
            out,
            "<tr><td>{}</td><td>{status}</td><td class=n>{}</td><td class=n>{}</td><td class=n>{sp}</td>",
            esc(&v.variant),
            ms(v.gpu_frame_ms.map(|g| g.median)),
            ms(Some(v.cpu_frame_ms.median))
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
            "<td class=n>{}</td><td>{}</td><td>{}</td><td>{series_link}{images}</td></tr>",
            bytes(v.allocated_bytes),
            passes.join(", "),
            gates.join("; ")
        );
    }
    out.push_str("</table>");
    let _ = write!(
        out,
        "<p><a href=\"/pareto?scenario={}&adapter={}&run={}\">error against time</a></p>",
        enc(&s.scenario),
        d.run.adapter_id,
        enc(&d.run.run_id)
    );
}

/// The run page body.
pub fn render(d: &RunDetail) -> String {
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
    for s in &d.scenarios {
        scenario_section(d, s, &mut out);
    }
    out
}

pub async fn page(
    State(state): State<AppState>,
    Path(run_id): Path<String>,
) -> Result<Html<String>, AppError> {
    let d = load(&state, run_id).await?;
    Ok(Html(layout(
        &format!("Run {}", d.run.run_id),
        "runs",
        &render(&d),
    )))
}
