//! The dashboard's own static files, compiled into the binary: the vendored uPlot chart library
//! (`assets/uplot/`, MIT, see its LICENSE there) and `tessera.js`, which draws the charts and runs
//! the image viewer. No CDN: the dashboard works offline.
//!
//! Not for: images of runs (see [`super::images`]).

use axum::extract::Path;
use axum::http::header;
use axum::response::{IntoResponse, Response};

use super::AppError;

/// (name, content type, bytes).
const FILES: [(&str, &str, &[u8]); 5] = [
    (
        "uPlot.iife.min.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../../assets/uplot/uPlot.iife.min.js"),
    ),
    (
        "uPlot.min.css",
        "text/css; charset=utf-8",
        include_bytes!("../../assets/uplot/uPlot.min.css"),
    ),
    (
        "uPlot.LICENSE.txt",
        "text/plain; charset=utf-8",
        include_bytes!("../../assets/uplot/LICENSE"),
    ),
    (
        "tessera.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../../assets/tessera.js"),
    ),
    (
        "regressions.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../../assets/regressions.js"),
    ),
];

pub async fn file(Path(name): Path<String>) -> Result<Response, AppError> {
    let Some((_, content_type, bytes)) = FILES.iter().find(|f| f.0 == name) else {
        return Err(AppError::NotFound(format!("no asset {name}")));
    };
    Ok((
        [
            (header::CONTENT_TYPE, *content_type),
            // Assets change with the binary: a short cache, revalidated after.
            (header::CACHE_CONTROL, "public, max-age=600"),
        ],
        *bytes,
    )
        .into_response())
}
