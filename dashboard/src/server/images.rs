//! Images: the viewer page (`/runs/{run}/images/{scenario}/{variant}`: reference, variant output
//! and FLIP heat map side by side with a frame slider), the list API, and `/images/{digest}` which
//! serves stored PNG bytes by SHA-256. Images live in the store, never on disk, so no route can
//! reach a file: a digest is 64 hex digits or a 404.

use std::fmt::Write;

use axum::extract::{Path, State};
use axum::http::header;
use axum::response::{Html, IntoResponse, Response};
use axum::Json;

use super::{AppError, AppState};
use crate::html::{enc, esc, page as layout};
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

/// Columns shown, in order: (image kind, heading). The reference may be listed under any variant
/// of the scenario.
const KINDS: [(&str, &str); 5] = [
    ("reference", "reference"),
    ("output", "variant"),
    ("heatmap", "FLIP heat map"),
    ("cvvdp", "ColorVideoVDP map (blue: invisible, red: 1 JOD)"),
    ("rate", "shading rate"),
];

pub fn render(
    run_id: &str,
    scenario: &str,
    variant: &str,
    images: &[ImageRow],
) -> Result<String, AppError> {
    let mut frames: Vec<i64> = images
        .iter()
        .filter(|i| i.variant == variant)
        .map(|i| i.frame)
        .collect();
    frames.sort();
    frames.dedup();
    if frames.is_empty() {
        return Err(AppError::NotFound(format!(
            "no images of {variant} in {scenario} of run {run_id}"
        )));
    }
    let pick = |frame: i64, kind: &str| {
        images
            .iter()
            .find(|i| i.frame == frame && i.kind == kind && i.variant == variant)
            .or_else(|| {
                (kind == "reference")
                    .then(|| images.iter().find(|i| i.frame == frame && i.kind == kind))
                    .flatten()
            })
            .map(|i| format!("/images/{}", i.digest))
    };
    let mut out = format!(
        "<p><a href=\"/runs/{}#s-{}\">back to the run</a></p>",
        enc(run_id),
        esc(scenario)
    );
    // Each frame's image URLs as data for the slider; absent kinds are empty strings.
    let data: Vec<Vec<String>> = frames
        .iter()
        .map(|&f| {
            KINDS
                .iter()
                .map(|(k, _)| pick(f, k).unwrap_or_default())
                .collect()
        })
        .collect();
    let _ = write!(
        out,
        "<p>frame <input id=frame type=range min=0 max={} value=0 oninput=\"show(this.value)\"> <span id=frameno>{}</span></p><div>",
        frames.len() - 1,
        frames[0]
    );
    for (i, (kind, heading)) in KINDS.iter().enumerate() {
        let src = &data[0][i];
        let hidden = if data.iter().all(|f| f[i].is_empty()) {
            " hidden"
        } else {
            ""
        };
        let _ = write!(
            out,
            "<figure style=\"display:inline-block;margin:4px\"{hidden}><figcaption>{heading}</figcaption><img class=shot id=\"img-{kind}\" src=\"{}\" alt=\"{heading}\"></figure>",
            esc(src)
        );
    }
    let json = serde_json::to_string(&data)
        .expect("strings serialise")
        .replace('<', "\\u003c");
    let frames_json = serde_json::to_string(&frames).expect("numbers serialise");
    let kinds_json = serde_json::to_string(&KINDS.iter().map(|k| k.0).collect::<Vec<_>>())
        .expect("strings serialise");
    let _ = write!(
        out,
        "</div><script>const F={json},N={frames_json},K={kinds_json};function show(i){{document.getElementById('frameno').textContent=N[i];K.forEach((k,j)=>{{const e=document.getElementById('img-'+k);if(F[i][j])e.src=F[i][j];}});}}</script>"
    );
    Ok(out)
}

pub async fn page(
    State(state): State<AppState>,
    Path((run_id, scenario, variant)): Path<(String, String, String)>,
) -> Result<Html<String>, AppError> {
    let (r, s) = (run_id.clone(), scenario.clone());
    let images = state.db(move |c| Ok(read::run_images(c, &r, &s)?)).await?;
    let body = render(&run_id, &scenario, &variant, &images)?;
    Ok(Html(layout(
        &format!("{scenario} · {variant} · run {run_id}"),
        "runs",
        &body,
    )))
}
