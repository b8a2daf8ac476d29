//! The compare page and API (`/compare/runs`, `/api/compare/runs`) on stored runs: the engine's
//! words reach the page, the JSON, the CSV and the Markdown: "too few frames" on the committed
//! real lavapipe runs (4 measured frames in `adaptive`), and a slower baseline counted once on
//! runs uploaded with 10 frames on a GPU adapter. The rules themselves are tested in
//! `results/tests/compare.rs`.

mod common;

use axum::body::Body;
use axum::http::{header, Request, StatusCode};
use axum::Router;
use http_body_util::BodyExt;
use tessera_dashboard::bundle::RunBundle;
use tessera_dashboard::detect::Params;
use tessera_dashboard::import::import;
use tessera_dashboard::server::{app, AppState};
use tessera_results::Summary;
use tower::ServiceExt;

const TOKEN: &str = "compare-token";

async fn send(app: &Router, req: Request<Body>) -> (StatusCode, String) {
    let res = app.clone().oneshot(req).await.unwrap();
    let status = res.status();
    let body = res.into_body().collect().await.unwrap().to_bytes();
    (status, String::from_utf8_lossy(&body).into_owned())
}

async fn get(app: &Router, uri: &str) -> String {
    let (status, body) = send(app, Request::get(uri).body(Body::empty()).unwrap()).await;
    assert_eq!(status, StatusCode::OK, "{uri}: {body}");
    body
}

#[tokio::test]
async fn four_real_frames_read_too_few_frames_everywhere() {
    let store = common::sqlite();
    let viewer =
        std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/viewer-runs");
    import(&store.pool, &viewer, &Params::default()).unwrap();
    let app = app(AppState::new(store.pool.clone(), None));
    let (a, b) = ("20261201T045513Z-ab7188d", "20261201T045518Z-ab7188d");
    let q = format!("a={a}&b={b}");

    let c: serde_json::Value =
        serde_json::from_str(&get(&app, &format!("/api/compare/runs?{q}")).await).unwrap();
    assert_eq!(c["same_adapter"], true);
    assert_eq!(c["by_speedup"], false);
    assert_eq!(c["rule"]["frames_needed"], 5);
    let scenario = |name: &str| {
        c["scenarios"]
            .as_array()
            .unwrap()
            .iter()
            .find(|s| s["scenario"] == name)
            .unwrap()
            .clone()
    };
    for v in scenario("adaptive")["variants"].as_array().unwrap() {
        assert_eq!(v["time"]["verdict"], "too few frames", "{v}");
        assert_eq!(v["time"]["frames"], serde_json::json!([4, 4]), "{v}");
    }
    // Six frames per side can be tested: a verdict other than too few frames.
    let native = &scenario("basic")["variants"][0];
    assert_ne!(native["time"]["verdict"], "too few frames", "{native}");
    assert!(native["time"]["interval"].is_array(), "{native}");

    let md = get(&app, &format!("/api/compare/runs?{q}&format=md")).await;
    assert!(
        md.contains("| native | ")
            && md.contains("too few frames (4 vs 4; 5 per side needed)")
            && md.contains("**Too few frames**"),
        "{md}"
    );
    let csv = get(&app, &format!("/api/compare/runs?{q}&format=csv")).await;
    assert!(
        csv.contains("adaptive,native,gpu_ms.median,") && csv.contains(",too few frames\n"),
        "{csv}"
    );
    let page = get(&app, &format!("/compare/runs?{q}")).await;
    assert!(
        page.contains("too few frames <span class=muted>(4 vs 4; 5 per side needed)</span>")
            && page.contains("<p id=too-few><strong>Too few frames</strong>"),
        "{page}"
    );
}

/// `bundle` on a GPU adapter with 10 measured frames per variant, each pass's frames spread ±0.5%
/// around its median scaled by `scale(variant)`.
fn on_gpu(mut bundle: RunBundle, run_id: &str, scale: impl Fn(&str) -> f64) -> RunBundle {
    bundle.run.run_id = run_id.into();
    bundle.run.adapter.name = "NVIDIA H200".into();
    bundle.run.adapter.device_type = "discrete-gpu".into();
    for s in &mut bundle.scenarios {
        s.run_id = run_id.into();
        s.measured_frames = 10;
        for r in &mut s.results {
            let k = scale(&r.variant);
            for p in &mut r.passes {
                let median = p.gpu_ms.unwrap().median * k;
                p.samples_ms = (0..10)
                    .map(|i| median * (1.0 + 0.001 * (f64::from(i) - 4.5)))
                    .collect();
                p.gpu_ms = Summary::of(&p.samples_ms);
            }
            let frames: Vec<f64> = (0..10)
                .map(|i| r.passes.iter().map(|p| p.samples_ms[i]).sum())
                .collect();
            r.gpu_frame_ms = Summary::of(&frames);
        }
    }
    bundle
}

#[tokio::test]
async fn a_slower_native_is_one_regression_on_the_page() {
    let store = common::sqlite();
    let app = app(AppState::new(store.pool.clone(), Some(TOKEN.into())));
    let (a, b) = ("20261122T030520Z-34ab2b4", "20261122T040520Z-34ab2b4");
    let base = on_gpu(common::template(), a, |_| 1.0);
    let slower = on_gpu(
        common::template(),
        b,
        |v| if v == "native" { 1.3 } else { 1.0 },
    );
    for run in [base, slower] {
        let body = serde_json::to_string(&run.to_upload()).unwrap();
        let req = Request::post("/api/runs")
            .header(header::CONTENT_TYPE, "application/json")
            .header(header::AUTHORIZATION, format!("Bearer {TOKEN}"))
            .body(Body::from(body))
            .unwrap();
        let (status, body) = send(&app, req).await;
        assert!(status.is_success(), "{status}: {body}");
    }
    let q = format!("a={a}&b={b}");
    let c: serde_json::Value =
        serde_json::from_str(&get(&app, &format!("/api/compare/runs?{q}")).await).unwrap();
    let findings = c["findings"].as_array().unwrap();
    assert_eq!(findings.len(), 1, "{findings:?}");
    assert_eq!(findings[0]["variant"], "native");
    assert_eq!(findings[0]["verdict"], "worse");
    assert_eq!(
        findings[0]["moves_speedups_of"],
        serde_json::json!(["upscale[scale=0.5]", "upscale[scale=0.75]"])
    );
    let page = get(&app, &format!("/compare/runs?{q}")).await;
    assert!(
        page.contains(
            "<strong class=worse>Verdict: regressed</strong> · 1 regression · 0 improvements"
        ),
        "{page}"
    );
    assert!(
        page.contains("the speedups of upscale[scale=0.5], upscale[scale=0.75] moved with it (counted here once)"),
        "{page}"
    );
    assert_eq!(page.matches("(moved with native)").count(), 2, "{page}");
    let md = get(&app, &format!("/api/compare/runs?{q}&format=md")).await;
    assert!(
        md.ends_with("**Verdict: regressed** (1 regression, 0 improvements; time: Mann-Whitney U p < 0.01 and a Hodges-Lehmann shift of at least 5%; too few frames below 5 per side)\n"),
        "{md}"
    );
}
