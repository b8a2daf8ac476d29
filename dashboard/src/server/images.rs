//! Images: the viewer (`/runs/{run}/images/{scenario}/{variant}?other=RUN`), the list API, and
//! `/images/{digest}`, which serves stored PNG bytes by SHA-256. Images live in the store, never on
//! disk, so no route can reach a file: a digest is 64 hex digits or a 404.
//!
//! The viewer shows one saved frame at a time: A/B flicker between reference and variant (button
//! or the F key), a wipe between them, reference, variant, the FLIP heat map and the shading-rate
//! image (alone and over the variant) where stored, and the same variant's frame in another run.
//! A frame wider than its pane opens fitted to it (the whole frame in view; `fit` returns there),
//! smaller ones at natural size or enlarged; zoom up to 32x with nearest-neighbour pixels; all
//! panes pan together. A frame slider and playback step through the saved frames. Without
//! JavaScript every image is still shown at natural size.

use std::fmt::Write;

use axum::extract::{Path, Query, State};
use axum::http::header;
use axum::response::{Html, IntoResponse, Response};
use axum::Json;
use serde::{Deserialize, Serialize};

use super::{AppError, AppState};
use crate::html::{enc, esc, page as layout, script_json};
use crate::store::browse;
use crate::store::read::{self, ImageRow};

pub async fn api(
    State(state): State<AppState>,
    Path((run_id, scenario)): Path<(String, String)>,
) -> Result<Json<Vec<ImageRow>>, AppError> {
    Ok(Json(
        state
            .db(move |c| Ok(read::run_images(c, &run_id, &scenario)?))
            .await?,
    ))
}

pub fn valid_digest(d: &str) -> bool {
    d.len() == 64
        && d.bytes()
            .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b))
}

pub async fn blob(
    State(state): State<AppState>,
    Path(digest): Path<String>,
) -> Result<Response, AppError> {
    if !valid_digest(&digest) {
        return Err(AppError::NotFound(
            "images are named by their SHA-256 in hex".into(),
        ));
    }
    let bytes = state.db(move |c| Ok(read::blob(c, &digest)?)).await?;
    Ok((
        [
            (header::CONTENT_TYPE, "image/png"),
            (header::CACHE_CONTROL, "public, max-age=31536000, immutable"),
        ],
        bytes,
    )
        .into_response())
}

/// Image kinds of the viewer, in order: (kind, heading). The reference may be stored under any
/// variant of the scenario; `other` is the variant's output in the other run.
const KINDS: [(&str, &str); 7] = [
    ("reference", "reference (A)"),
    ("output", "variant (B)"),
    ("heatmap", "FLIP error (magma)"),
    ("heatmap-hdr", "HDR-FLIP error (magma)"),
    ("cvvdp", "ColorVideoVDP map (blue: invisible, red: 1 JOD)"),
    ("rate", "shading rate"),
    ("other", "variant in the other run"),
];

/// The colour scale of a FLIP map: the magma colour map the harness writes, from 0 (no
/// perceived difference, black) to 1 (largest, pale yellow).
const FLIP_SCALE: &str = "<div class=flip-scale><span>0</span><span class=bar style=\"background:linear-gradient(90deg,#000004,#3b0f70 20%,#8c2981 40%,#de4968 60%,#fe9f6d 80%,#fcfdbf)\"></span><span>1</span> <span class=muted>FLIP error (magma): black none, yellow largest</span></div>";

#[derive(Debug, Deserialize, Default)]
pub struct ViewerQuery {
    /// Another run whose frames of the same variant are shown beside.
    pub other: Option<String>,
}

/// What the viewer's script reads: per frame, the URL of each kind (empty when absent).
#[derive(Debug, Serialize)]
struct ViewerSpec {
    frames: Vec<i64>,
    kinds: Vec<&'static str>,
    urls: Vec<Vec<String>>,
    width: u32,
    height: u32,
}

pub struct Viewer<'a> {
    pub run_id: &'a str,
    pub scenario: &'a str,
    pub variant: &'a str,
    pub images: &'a [ImageRow],
    pub width: u32,
    pub height: u32,
    /// The other run and its images of this scenario.
    pub other: Option<(&'a str, &'a [ImageRow])>,
    /// Runs that stored images of this variant, for the picker.
    pub runs_with_images: &'a [String],
    /// Per-frame charts of the variant (metrics, GPU time), synced with the frame slider.
    pub frame_charts: String,
}

fn pick(images: &[ImageRow], variant: &str, frame: i64, kind: &str) -> Option<String> {
    images
        .iter()
        .find(|i| i.frame == frame && i.kind == kind && i.variant == variant)
        .or_else(|| {
            (kind == "reference")
                .then(|| images.iter().find(|i| i.frame == frame && i.kind == kind))
                .flatten()
        })
        .map(|i| format!("/images/{}", i.digest))
}

pub fn render(v: &Viewer<'_>) -> Result<String, AppError> {
    let mut frames: Vec<i64> = v
        .images
        .iter()
        .filter(|i| i.variant == v.variant)
        .map(|i| i.frame)
        .collect();
    frames.sort();
    frames.dedup();
    if frames.is_empty() {
        return Err(AppError::NotFound(format!(
            "no images of {} in {} of run {}",
            v.variant, v.scenario, v.run_id
        )));
    }
    let urls: Vec<Vec<String>> = frames
        .iter()
        .map(|&f| {
            KINDS
                .iter()
                .map(|(k, _)| match (*k, v.other) {
                    ("other", Some((_, imgs))) => pick(imgs, v.variant, f, "output"),
                    ("other", None) => None,
                    _ => pick(v.images, v.variant, f, k),
                })
                .map(Option::unwrap_or_default)
                .collect()
        })
        .collect();
    let present: Vec<bool> = (0..KINDS.len())
        .map(|j| urls.iter().any(|f| !f[j].is_empty()))
        .collect();
    let first = |kind: &str| -> String {
        let j = KINDS.iter().position(|k| k.0 == kind).expect("known kind");
        urls.iter()
            .map(|f| f[j].clone())
            .find(|u| !u.is_empty())
            .unwrap_or_default()
    };
    let mut out = format!(
        "<p><a href=\"/runs/{}#s-{}\">back to the run</a> · {}×{} px · {} saved frame(s)</p>",
        enc(v.run_id),
        esc(v.scenario),
        v.width,
        v.height,
        frames.len()
    );
    // Another run's frames of this variant.
    let _ = write!(
        out,
        "<form id=other-run>same variant in another run <select name=other><option value=\"\">none</option>"
    );
    for r in v.runs_with_images.iter().filter(|r| r.as_str() != v.run_id) {
        let sel = if v.other.is_some_and(|o| o.0 == r.as_str()) {
            " selected"
        } else {
            ""
        };
        let _ = write!(out, "<option{sel}>{}</option>", esc(r));
    }
    out.push_str("</select> <button>show</button></form>");
    let has_ref = present[0] && present[1];
    let _ = write!(
        out,
        "<div class=viewer id=viewer data-viewer=viewer-data><div class=controls><label>frame <input id=frame type=range min=0 max={} value=0 step=1> <span id=frameno>{}</span></label><button id=play type=button>play</button><label>zoom <input id=zoom type=range min=1 max=32 value=1 step=1> <span id=zoomval>1×</span></label><button id=fit type=button title=\"the whole frame in its pane\">fit</button>",
        frames.len() - 1,
        frames[0]
    );
    if has_ref {
        out.push_str("<button id=flicker type=button>flicker A/B</button> <span class=muted>(<kbd>F</kbd> or <kbd>space</kbd>)</span><label>wipe <input id=wipe type=range min=0 max=100 value=50></label>");
    } else {
        // The script expects the controls; without a reference they do nothing visible.
        out.push_str("<span hidden><button id=flicker type=button></button><input id=wipe type=range min=0 max=100 value=50></span>");
    }
    out.push_str("<span class=muted>drag to pan, <kbd>+</kbd>/<kbd>-</kbd> zoom, <kbd>←</kbd>/<kbd>→</kbd> frames</span></div><div class=panes>");
    // Every pane shows the scenario's size (a tile-resolution rate image is scaled up to it).
    let size = if v.width > 0 && v.height > 0 {
        format!(" width={} height={}", v.width, v.height)
    } else {
        String::new()
    };
    let img = |kind: &str, url: &str, alt: &str, extra: &str| {
        format!(
            "<img class=\"px{extra}\" data-kind=\"{kind}\" src=\"{}\" alt=\"{}\"{size}>",
            esc(url),
            esc(alt),
        )
    };
    if has_ref {
        // A and B side by side at any zoom: one row of two panes that share the width (they pan
        // together like every pane).
        let _ = write!(
            out,
            "<div class=pair id=pair><figure><figcaption>reference (A)</figcaption><div class=pane>{}</div></figure><figure><figcaption>variant (B)</figcaption><div class=pane>{}</div></figure></div>",
            img("reference", &first("reference"), "reference (A)", ""),
            img("output", &first("output"), "variant (B)", "")
        );
        let _ = write!(
            out,
            "<figure><figcaption id=ab-label>B: variant</figcaption><div class=pane><img class=px id=img-ab src=\"{}\" alt=\"A/B flicker\"{size}></div></figure>",
            esc(&first("output")),
        );
        // The wipe: the reference on top, shown left of the line; the variant under it, right.
        let _ = write!(
            out,
            "<figure><figcaption id=wipe-caption>wipe: A (reference) left, B (variant) right</figcaption><div class=pane><div class=stack id=wipe-stack data-left=reference data-right=output>{}{}<div id=wipe-line></div></div></div></figure>",
            img("output", &first("output"), "wipe: variant", ""),
            img("reference", &first("reference"), "wipe: reference", " top\" id=\"wipe-top")
        );
    } else {
        out.push_str("<img hidden id=img-ab alt=\"\"><span hidden id=ab-label></span><span hidden id=wipe-top></span><span hidden id=wipe-line></span>");
    }
    for (j, (kind, heading)) in KINDS.iter().enumerate() {
        if !present[j] || (has_ref && matches!(*kind, "reference" | "output")) {
            continue;
        }
        let heading = match (*kind, v.other) {
            ("other", Some((r, _))) => format!("variant in run {r}"),
            _ => heading.to_string(),
        };
        let _ = write!(
            out,
            "<figure><figcaption>{}</figcaption><div class=pane>{}</div></figure>",
            esc(&heading),
            img(kind, &first(kind), &heading, "")
        );
        if kind.starts_with("heatmap") {
            out.push_str(FLIP_SCALE);
        }
        if *kind == "rate" && present[1] {
            let _ = write!(
                out,
                "<figure><figcaption>shading rate over the variant</figcaption><div class=pane><div class=stack>{}{}</div></div></figure>",
                img("output", &first("output"), "variant under the rate", ""),
                img("rate", &first("rate"), "shading rate overlay", " top overlay")
            );
        }
    }
    out.push_str("</div>");
    out.push_str(&v.frame_charts);
    out.push_str("</div>");
    let spec = ViewerSpec {
        frames: frames.clone(),
        kinds: KINDS.iter().map(|k| k.0).collect(),
        urls,
        width: v.width,
        height: v.height,
    };
    let _ = write!(
        out,
        "<script type=application/json id=viewer-data>{}</script>",
        script_json(&spec)
    );
    Ok(out)
}

pub async fn page(
    State(state): State<AppState>,
    Path((run_id, scenario, variant)): Path<(String, String, String)>,
    Query(q): Query<ViewerQuery>,
) -> Result<Response, AppError> {
    match viewer_page(state, &run_id, &scenario, &variant, q).await {
        // A link a person followed: a page that says what is missing, not a JSON body.
        Err(AppError::NotFound(what)) => Ok(not_found_page(&run_id, &what)),
        other => other.map(IntoResponse::into_response),
    }
}

/// The viewer's 404 as a page: what is missing and a way back to the run.
pub fn not_found_page(run_id: &str, what: &str) -> Response {
    let body = format!(
        "<p class=neutral>{}.</p><p>This run saved no images here (a run keeps its frames only where its scenario asks for them, or with <code>tessera run --save-images</code>). Back to <a href=\"/runs/{}\">run {}</a>.</p>",
        crate::html::esc(what),
        crate::html::enc(run_id),
        crate::html::esc(run_id)
    );
    (
        axum::http::StatusCode::NOT_FOUND,
        Html(layout("No images", "runs", &body)),
    )
        .into_response()
}

async fn viewer_page(
    state: AppState,
    run_id: &str,
    scenario: &str,
    variant: &str,
    q: ViewerQuery,
) -> Result<Html<String>, AppError> {
    let (r, s, var) = (
        run_id.to_string(),
        scenario.to_string(),
        variant.to_string(),
    );
    let other_id = q.other.filter(|o| !o.is_empty());
    let (images, (w, h), other, runs, frame_charts) = state
        .db(move |c| {
            let images = read::run_images(c, &r, &s)?;
            let record = read::scenario_result(c, &r, &s).ok();
            let dims = record.as_ref().map_or((0, 0), |x| (x.width, x.height));
            let charts = record
                .as_ref()
                .and_then(|x| x.results.iter().find(|v| v.variant == var))
                .map(|v| super::frame_charts::render(&super::frame_charts::series_of(v)))
                .unwrap_or_default();
            let other = match other_id {
                Some(o) => Some((o.clone(), read::run_images(c, &o, &s)?)),
                None => None,
            };
            let runs = browse::runs_with_images(c, &s, &var)?;
            Ok((images, dims, other, runs, charts))
        })
        .await?;
    let body = render(&Viewer {
        run_id,
        scenario,
        variant,
        images: &images,
        width: w,
        height: h,
        other: other.as_ref().map(|(r, i)| (r.as_str(), i.as_slice())),
        runs_with_images: &runs,
        frame_charts,
    })?;
    Ok(Html(layout(
        &format!("{scenario} · {variant} · run {run_id}"),
        "runs",
        &body,
    )))
}
