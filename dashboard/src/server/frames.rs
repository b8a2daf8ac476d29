//! Approved frames' pages and API (issue 35): the triage list of untriaged frames (`/frames`),
//! one frame beside its closest approved frame in the image viewer (flicker, wipe, the stored
//! FLIP map) with approve / mark-regression buttons
//! (`/frames/{run}/{scenario}/{variant}/{frame}`, a form with the write token), the JSON of
//! both, judging by API (`POST /api/frames/judge`, a write token), and the approved digests of
//! an adapter class (`GET /api/approved-frames?class=`), which `tessera run --expect URL` reads.
//!
//! Not for: SQL (see [`crate::store::frames`]).

use std::fmt::Write;

use axum::extract::{Path, Query, State};
use axum::response::{Html, Redirect};
use axum::{Form, Json};
use serde::Deserialize;

use super::auth::{self, Writer};
use super::images::{render as viewer, Viewer};
use super::{AppError, AppState};
use crate::html::{enc, esc, page as layout};
use crate::store::frames::{self, Approved, DigestFile, Judge, RunFrame};
use crate::store::read::{self, ImageRow};

/// How many untriaged frames the list shows.
const LIST_LIMIT: i64 = 500;

pub async fn list_api(State(state): State<AppState>) -> Result<Json<Vec<RunFrame>>, AppError> {
    Ok(Json(
        state.db(|c| Ok(frames::untriaged(c, LIST_LIMIT)?)).await?,
    ))
}

fn frame_url(f: &RunFrame) -> String {
    format!(
        "/frames/{}/{}/{}/{}",
        enc(&f.run_id),
        enc(&f.scenario),
        enc(&f.variant),
        f.frame
    )
}

fn short(d: &str) -> &str {
    &d[..d.len().min(12)]
}

/// `GET /frames`: untriaged frames by run, newest first.
pub async fn list_page(State(state): State<AppState>) -> Result<Html<String>, AppError> {
    let rows = state.db(|c| Ok(frames::untriaged(c, LIST_LIMIT)?)).await?;
    let mut body = String::from(
        "<p>Frames whose digest matches no approved frame of their scenario, variant, adapter class and frame index. A frame whose variant had an approved frame before is also an alert (<a href=\"/regressions\">regressions</a>); approve it if the change is intended, or mark it as a regression.</p>",
    );
    if rows.is_empty() {
        body.push_str("<p class=muted>No untriaged frames.</p>");
    } else {
        let _ = write!(body, "<p>{} untriaged frames.</p>", rows.len());
        // One table per run (rows come newest run first), so that narrow screens keep columns.
        let mut current: Option<&str> = None;
        for f in &rows {
            if current != Some(f.run_id.as_str()) {
                if current.is_some() {
                    body.push_str("</tbody></table>");
                }
                current = Some(f.run_id.as_str());
                let _ = write!(
                    body,
                    "<h2 style=\"font-size:1em;overflow-wrap:anywhere\">run <a href=\"/runs/{}\">{}</a> · commit <code>{}</code> · adapter class {}</h2><table><thead><tr><th>scenario</th><th>variant</th><th>frame</th><th>digest</th></tr></thead><tbody>",
                    enc(&f.run_id),
                    esc(&f.run_id),
                    esc(f.commit.as_deref().map_or("", |c| &c[..c.len().min(10)])),
                    esc(&f.adapter_class)
                );
            }
            let _ = write!(
                body,
                "<tr><td>{}</td><td><a href=\"{}\">{}</a></td><td>{}</td><td><code>{}</code></td></tr>",
                esc(&f.scenario),
                frame_url(f),
                esc(&f.variant),
                f.frame,
                esc(short(&f.digest))
            );
        }
        body.push_str("</tbody></table>");
    }
    Ok(Html(layout("untriaged frames", "frames", &body)))
}

/// One frame and what it is compared with.
#[derive(Debug, serde::Serialize)]
pub struct FrameDetail {
    pub frame: RunFrame,
    pub approved: Option<Approved>,
    /// The stored PNG of this frame and of the approved one, where saved (`frames.save`).
    pub image: Option<String>,
    pub approved_image: Option<String>,
}

fn image_of(images: &[ImageRow], variant: &str, frame: i64) -> Option<String> {
    let reference = variant == frames::REFERENCE_VARIANT;
    images
        .iter()
        .find(|i| {
            i.frame == frame
                && if reference {
                    i.kind == "reference"
                } else {
                    i.kind == "output" && i.variant == variant
                }
        })
        .map(|i| i.digest.clone())
}

fn detail(
    c: &mut dyn crate::db::Connection,
    run_id: &str,
    scenario: &str,
    variant: &str,
    frame: i64,
) -> Result<(FrameDetail, u32, u32), AppError> {
    let f = frames::of_run(c, run_id, Some(scenario))?
        .into_iter()
        .find(|f| f.variant == variant && f.frame == frame)
        .ok_or_else(|| {
            AppError::NotFound(format!(
                "no digest of frame {frame} of {scenario} / {variant} in run {run_id}"
            ))
        })?;
    let approved = frames::closest_approved(c, &f)?;
    let images = read::run_images(c, run_id, scenario)?;
    let image = image_of(&images, variant, frame);
    let approved_image = match approved.as_ref().and_then(|a| a.run_id.clone()) {
        Some(r) => image_of(&read::run_images(c, &r, scenario)?, variant, frame),
        None => None,
    };
    let dims = read::scenario_result(c, run_id, scenario)
        .map(|s| (s.width, s.height))
        .unwrap_or((0, 0));
    Ok((
        FrameDetail {
            frame: f,
            approved,
            image,
            approved_image,
        },
        dims.0,
        dims.1,
    ))
}

pub async fn detail_api(
    State(state): State<AppState>,
    Path((run_id, scenario, variant, frame)): Path<(String, String, String, i64)>,
) -> Result<Json<FrameDetail>, AppError> {
    let (d, _, _) = state
        .db(move |c| detail(c, &run_id, &scenario, &variant, frame))
        .await?;
    Ok(Json(d))
}

/// `GET /frames/{run}/{scenario}/{variant}/{frame}`.
pub async fn detail_page(
    State(state): State<AppState>,
    Path((run_id, scenario, variant, frame)): Path<(String, String, String, i64)>,
) -> Result<Html<String>, AppError> {
    let (r, s, v) = (run_id.clone(), scenario.clone(), variant.clone());
    let (d, w, h) = state.db(move |c| detail(c, &r, &s, &v, frame)).await?;
    let f = &d.frame;
    let mut body = String::new();
    let _ = write!(
        body,
        "<p style=\"overflow-wrap:anywhere\">Run <a href=\"/runs/{}\">{}</a>, adapter class <b>{}</b>, frame {} of <b>{}</b> / <b>{}</b>: triage <b class=\"triage-{}\">{}</b>, digest <code>{}</code>.</p>",
        enc(&f.run_id),
        esc(&f.run_id),
        esc(&f.adapter_class),
        f.frame,
        esc(&f.scenario),
        esc(&f.variant),
        esc(&f.triage),
        esc(&f.triage),
        esc(&f.digest)
    );
    match &d.approved {
        Some(a) => {
            let _ = write!(
                body,
                "<p style=\"overflow-wrap:anywhere\">Closest approved frame: digest <code>{}</code> from run {}, approved by {} at {}.</p>",
                esc(&a.digest),
                a.run_id.as_deref().map_or("?".to_string(), |r| format!(
                    "<a href=\"/runs/{}\">{}</a>",
                    enc(r),
                    esc(r)
                )),
                esc(&a.updated_by),
                esc(&a.updated_at)
            );
        }
        None => body.push_str(
            "<p>No approved frame yet for this scenario, variant, adapter class and frame: approving this one makes it the first.</p>",
        ),
    }
    // The viewer: A is the approved frame, B this run's.
    let mut images = Vec::new();
    if let Some(dg) = &d.approved_image {
        images.push(ImageRow {
            scenario: f.scenario.clone(),
            variant: f.variant.clone(),
            frame: f.frame,
            kind: "reference".into(),
            digest: dg.clone(),
        });
    }
    if let Some(dg) = &d.image {
        images.push(ImageRow {
            scenario: f.scenario.clone(),
            variant: f.variant.clone(),
            frame: f.frame,
            kind: "output".into(),
            digest: dg.clone(),
        });
    }
    if d.image.is_some() {
        body.push_str("<p class=muted>In the viewer, A (“reference”) is the approved frame and B (“variant”) this run's frame: flicker with F, wipe between them.</p>");
        body.push_str(&viewer(&Viewer {
            run_id: &f.run_id,
            scenario: &f.scenario,
            variant: &f.variant,
            images: &images,
            width: w,
            height: h,
            other: None,
            runs_with_images: &[],
            frame_charts: String::new(),
        })?);
    } else {
        let _ = write!(
            body,
            "<p class=muted>Frame {} was not saved as an image in this run (the scenario's <code>frames.save</code> and worst frames are): only its digest is known.</p>",
            f.frame
        );
    }
    let action = frame_url(f);
    let _ = write!(
        body,
        "<form method=post action=\"{action}\" class=judge><input name=token type=password size=18 placeholder=\"write token\" autocomplete=off required> <button name=state value=positive>approve</button> <button name=state value=negative>mark as regression</button></form><p><a href=\"/frames\">all untriaged frames</a></p>"
    );
    Ok(Html(layout(
        &format!("frame {} · {} · {}", f.frame, f.scenario, f.variant),
        "frames",
        &body,
    )))
}

#[derive(Debug, Deserialize)]
pub struct JudgeForm {
    pub state: String,
    #[serde(default)]
    pub token: String,
}

/// `POST /frames/{run}/{scenario}/{variant}/{frame}` (form with the token as a field).
pub async fn judge_form(
    State(state): State<AppState>,
    Path((run_id, scenario, variant, frame)): Path<(String, String, String, i64)>,
    Form(f): Form<JudgeForm>,
) -> Result<Redirect, AppError> {
    let by = auth::form_writer(&state, &f.token)?.name;
    let back = format!(
        "/frames/{}/{}/{}/{frame}",
        enc(&run_id),
        enc(&scenario),
        enc(&variant)
    );
    let j = Judge {
        run_id,
        scenario: Some(scenario),
        variant: Some(variant),
        frame: Some(frame),
        state: f.state,
        by,
    };
    state
        .db(move |c| Ok(crate::db::transaction(c, |c| frames::judge(c, &j))?))
        .await?;
    Ok(Redirect::to(&back))
}

#[derive(Debug, Deserialize)]
pub struct JudgeRequest {
    pub run_id: String,
    pub scenario: Option<String>,
    pub variant: Option<String>,
    pub frame: Option<i64>,
    /// `positive` (approve) or `negative` (a regression).
    pub state: String,
}

/// `POST /api/frames/judge` (write token): judges a run's frames, or a scenario's, variant's or
/// one frame; answers how many.
pub async fn judge_api(
    State(state): State<AppState>,
    Writer(p): Writer,
    Json(r): Json<JudgeRequest>,
) -> Result<Json<serde_json::Value>, AppError> {
    let j = Judge {
        run_id: r.run_id,
        scenario: r.scenario,
        variant: r.variant,
        frame: r.frame,
        state: r.state,
        by: p.name,
    };
    let n = state
        .db(move |c| Ok(crate::db::transaction(c, |c| frames::judge(c, &j))?))
        .await?;
    Ok(Json(serde_json::json!({ "judged": n })))
}

#[derive(Debug, Deserialize)]
pub struct ClassQuery {
    pub class: Option<String>,
}

/// `GET /api/approved-frames?class=CLASS`: the judged digests of an adapter class.
pub async fn approved_api(
    State(state): State<AppState>,
    Query(q): Query<ClassQuery>,
) -> Result<Json<DigestFile>, AppError> {
    let class = q.class.filter(|c| !c.is_empty()).ok_or_else(|| {
        AppError::BadRequest(
            "`class` is required: an adapter class such as llvmpipe, nvidia, amd, intel".into(),
        )
    })?;
    Ok(Json(
        state
            .db(move |c| Ok(frames::digest_file(c, &class)?))
            .await?,
    ))
}
