//! Approved frames (issue 35), on SQLite and (when `TESSERA_TEST_POSTGRES_URL` is set)
//! PostgreSQL, from three real lavapipe runs committed under `tests/fixtures/frames/`: a suite of
//! two 32x24 scenarios (`lit`: a sphere, `still`: a box; native and upscale, 2 measured frames,
//! frame 1 saved), run twice at one commit (a, b), then once after a commit that changes the
//! sphere's colour from (0.8, 0.3, 0.2) to (0.8, 0.3, 0.25) (c).
//!
//! Run a approved, run b matches every approved frame; run c has exactly `lit`'s frames
//! untriaged, its quality series stay within noise (the blind spot approved frames close), the
//! change is an alert of its own in the groups and the feed, the triage page shows it beside the
//! approved frame, and approving clears the frames and withdraws the alerts.

mod common;

use std::path::PathBuf;

use axum::body::Body;
use axum::http::{header, Request, StatusCode};
use axum::Router;
use http_body_util::BodyExt;
use tessera_dashboard::bundle::RunBundle;
use tessera_dashboard::db::Connection;
use tessera_dashboard::detect::Params;
use tessera_dashboard::regressions::ingest_and_detect;
use tessera_dashboard::server::{app, AppState};
use tessera_dashboard::store::frames::{self, Judge};
use tower::ServiceExt;

const TOKEN: &str = "frames-token";
const A: &str = "20261203T180553Z-3cfa4c3";
const B: &str = "20261203T180554Z-3cfa4c3";
const C: &str = "20261203T180556Z-4bfa576";

fn bundle(run: &str) -> RunBundle {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/frames")
        .join(run);
    RunBundle::read_folder(&dir).unwrap()
}

fn ingest(c: &mut dyn Connection, run: &str) {
    ingest_and_detect(c, &bundle(run), &Params::default()).unwrap();
}

/// (scenario, variant, frame, triage) of a run's frames.
fn triage(c: &mut dyn Connection, run: &str) -> Vec<(String, String, i64, String)> {
    frames::of_run(c, run, None)
        .unwrap()
        .into_iter()
        .map(|f| (f.scenario, f.variant, f.frame, f.triage))
        .collect()
}

fn untriaged(c: &mut dyn Connection, run: &str) -> Vec<(String, String, i64)> {
    triage(c, run)
        .into_iter()
        .filter(|t| t.3 == "untriaged")
        .map(|t| (t.0, t.1, t.2))
        .collect()
}

/// (variant, status) of the frame alerts.
fn frame_alerts(c: &mut dyn Connection) -> Vec<(String, String, i64)> {
    c.query(
        "SELECT s.variant, g.status, g.group_id FROM regressions g JOIN series s ON s.id = g.series_id
         WHERE s.measure = 'frames.untriaged' ORDER BY s.variant",
        &[],
    )
    .unwrap()
    .iter()
    .map(|r| (r.string(0).unwrap(), r.string(1).unwrap(), r.i64(2).unwrap()))
    .collect()
}

async fn send(app: &Router, req: Request<Body>) -> (StatusCode, String) {
    let res = app.clone().oneshot(req).await.unwrap();
    let status = res.status();
    let body = res.into_body().collect().await.unwrap().to_bytes();
    (status, String::from_utf8_lossy(&body).into_owned())
}

async fn get(app: &Router, uri: &str) -> (StatusCode, String) {
    send(app, Request::get(uri).body(Body::empty()).unwrap()).await
}

fn psnr(b: &RunBundle, scenario: &str, variant: &str) -> f64 {
    let s = b.scenarios.iter().find(|s| s.scenario == scenario).unwrap();
    let v = s.results.iter().find(|v| v.variant == variant).unwrap();
    v.metrics.iter().find(|m| m.name == "psnr").unwrap().value
}

/// The store is used from the test's thread (PostgreSQL's client blocks), the router from a
/// runtime of its own.
#[test]
fn a_colour_change_is_untriaged_until_approved() {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .unwrap();
    for store in common::stores("a_colour_change_is_untriaged_until_approved") {
        let name = store.name;
        let mut c = store.pool.get().unwrap();

        // Run a: nothing approved yet, so every frame is untriaged, and no alert (nothing changed).
        ingest(&mut *c, A);
        assert_eq!(untriaged(&mut *c, A).len(), 8, "{name}");
        assert!(frame_alerts(&mut *c).is_empty(), "{name}");
        let n = frames::judge(
            &mut *c,
            &Judge {
                run_id: A.into(),
                state: frames::POSITIVE.into(),
                by: "reviewer".into(),
                ..Judge::default()
            },
        )
        .unwrap();
        assert_eq!(n, 8, "{name}");
        assert!(untriaged(&mut *c, A).is_empty(), "{name}");

        // Run b, the same commit: every frame matches an approved frame exactly.
        ingest(&mut *c, B);
        let b = triage(&mut *c, B);
        assert_eq!(b.len(), 8, "{name}");
        assert!(b.iter().all(|t| t.3 == "positive"), "{name}: {b:?}");
        assert!(frame_alerts(&mut *c).is_empty(), "{name}");

        // Run c, one object's colour changed: exactly `lit`'s variants are untriaged...
        ingest(&mut *c, C);
        let mut expected = Vec::new();
        for v in ["native", "upscale"] {
            for f in 0..2 {
                expected.push(("lit".to_string(), v.to_string(), f));
            }
        }
        assert_eq!(untriaged(&mut *c, C), expected, "{name}");
        // ...while its quality series stays within noise: the same-run diff cannot see it.
        let (before, after) = (
            psnr(&bundle(B), "lit", "upscale"),
            psnr(&bundle(C), "lit", "upscale"),
        );
        assert!((after - before).abs() < 0.5, "{before} dB -> {after} dB");
        // An alert per changed variant, confirmed, in one group (one commit range).
        let alerts = frame_alerts(&mut *c);
        assert_eq!(
            alerts
                .iter()
                .map(|a| (a.0.as_str(), a.1.as_str()))
                .collect::<Vec<_>>(),
            [("native", "confirmed"), ("upscale", "confirmed")],
            "{name}"
        );
        assert_eq!(alerts[0].2, alerts[1].2, "{name}: one group");
        drop(c);

        let mut state = AppState::new(store.pool.clone(), Some(TOKEN.into()));
        state.public_url = Some("http://dash".into());
        let router = app(state);
        let (status, feed) = rt.block_on(get(&router, "/regressions/feed.atom"));
        assert_eq!(status, StatusCode::OK);
        assert!(feed.contains("frames.untriaged"), "{name}: {feed}");

        // The triage list shows the change, and only it.
        let (status, list) = rt.block_on(get(&router, "/frames"));
        assert_eq!(status, StatusCode::OK);
        assert!(list.contains("4 untriaged frames."), "{name}: {list}");
        assert!(
            list.contains(&format!("/frames/{C}/lit/upscale/1")),
            "{list}"
        );
        assert!(!list.contains("still"), "{list}");
        // One frame beside its closest approved frame, in the image viewer.
        let (status, page) = rt.block_on(get(&router, &format!("/frames/{C}/lit/upscale/1")));
        assert_eq!(status, StatusCode::OK, "{page}");
        assert!(page.contains("Closest approved frame"), "{page}");
        assert!(page.contains(&format!("/runs/{A}")), "{page}");
        assert!(page.matches("/images/").count() >= 2, "{page}");
        assert!(page.contains("value=positive>approve</button>"), "{page}");
        let (status, detail) = rt.block_on(get(&router, &format!("/api/frames/{C}/lit/upscale/1")));
        assert_eq!(status, StatusCode::OK);
        let detail: serde_json::Value = serde_json::from_str(&detail).unwrap();
        assert_ne!(detail["image"], detail["approved_image"]);
        assert!(detail["approved_image"].is_string(), "{detail}");

        // Approving needs the write token: without it nothing changes.
        let form = |token: &str| {
            Request::post(format!("/frames/{C}/lit/upscale/1"))
                .header(header::CONTENT_TYPE, "application/x-www-form-urlencoded")
                .body(Body::from(format!("state=positive&token={token}")))
                .unwrap()
        };
        let (status, _) = rt.block_on(send(&router, form("wrong")));
        assert_eq!(status, StatusCode::UNAUTHORIZED, "{name}");
        let (status, _) = rt.block_on(send(&router, form(TOKEN)));
        assert_eq!(status, StatusCode::SEE_OTHER, "{name}");
        {
            let mut c = store.pool.get().unwrap();
            assert_eq!(untriaged(&mut *c, C).len(), 3, "{name}");
            // The upscale alert stays while one of its frames is untriaged.
            assert!(frame_alerts(&mut *c).iter().all(|a| a.1 == "confirmed"));
        }
        // The rest of the scenario by API.
        let (status, body) = rt.block_on(send(
            &router,
            Request::post("/api/frames/judge")
                .header(header::CONTENT_TYPE, "application/json")
                .header(header::AUTHORIZATION, format!("Bearer {TOKEN}"))
                .body(Body::from(format!(
                    r#"{{"run_id": "{C}", "scenario": "lit", "state": "positive"}}"#
                )))
                .unwrap(),
        ));
        assert_eq!(status, StatusCode::OK, "{body}");
        assert!(body.contains("\"judged\":4"), "{body}");
        let mut c = store.pool.get().unwrap();
        assert!(untriaged(&mut *c, C).is_empty(), "{name}");
        assert!(
            frame_alerts(&mut *c).iter().all(|a| a.1 == "withdrawn"),
            "{name}"
        );
        drop(c);
        let (_, list) = rt.block_on(get(&router, "/frames"));
        assert!(list.contains("No untriaged frames."), "{list}");

        // What `tessera run --expect URL` reads: both approved colours of `lit`.
        let (status, body) = rt.block_on(get(&router, "/api/approved-frames?class=llvmpipe"));
        assert_eq!(status, StatusCode::OK);
        let file: serde_json::Value = serde_json::from_str(&body).unwrap();
        assert_eq!(file["adapter_class"], "llvmpipe");
        let lit = file["frames"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|f| f["scenario"] == "lit")
            .count();
        assert_eq!(lit, 8, "{body}");
        let (status, _) = rt.block_on(get(&router, "/api/approved-frames"));
        assert_eq!(status, StatusCode::BAD_REQUEST);
    }
}
