//! Pages at the width of a nightly run (issue 37 item 5): a run of more results than
//! `run::INLINE_RESULTS` opens on a per-scenario summary (what changed beyond noise, failures,
//! skips) with each scenario's detail on a page of its own; a comparison of two such runs opens on
//! the same summary with `scenario=` for one table; an alert group of more series than its chart
//! limit opens on a table by scenario and variant with a few charts; and the A/B button of these
//! pages opens a form that queues an A/B with a write token.

mod common;

use axum::body::Body;
use axum::http::{Request, StatusCode};
use axum::Router;
use http_body_util::BodyExt;
use tessera_dashboard::detect::Params;
use tessera_dashboard::regressions::ingest_and_detect;
use tessera_dashboard::server::{app, AppState};
use tessera_dashboard::steps::StepHistory;
use tessera_dashboard::synth::widen;
use tower::ServiceExt;

async fn send(app: &Router, req: Request<Body>) -> (StatusCode, String) {
    let res = app.clone().oneshot(req).await.unwrap();
    let status = res.status();
    let b = res.into_body().collect().await.unwrap().to_bytes();
    (status, String::from_utf8_lossy(&b).into_owned())
}

async fn get(app: &Router, uri: &str) -> (StatusCode, String) {
    send(app, Request::get(uri).body(Body::empty()).unwrap()).await
}

fn block_on<F: std::future::Future>(f: F) -> F::Output {
    tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap()
        .block_on(f)
}

/// Copies of the template's scenario in each run: 3 variants each, 180 results.
const COPIES: usize = 60;

/// Twelve wide nights with a 3% step in `native` on the last one, stored as uploads are.
fn nightly_step_store() -> (common::TestStore, StepHistory) {
    let store = common::sqlite();
    let h = StepHistory::h200(12, 11, "native", 1.03);
    let mut c = store.pool.get().unwrap();
    for run in h.runs(&common::template()) {
        ingest_and_detect(&mut *c, &widen(&run, COPIES), &Params::default()).unwrap();
    }
    drop(c);
    (store, h)
}

/// Three nights of a 180-result run; `native` 30% slower from night 2; one variant of one
/// scenario failed on night 2.
fn wide_store() -> (common::TestStore, StepHistory) {
    let store = common::sqlite();
    let h = StepHistory::h200(3, 2, "native", 1.3);
    let mut c = store.pool.get().unwrap();
    for (n, run) in h.runs(&common::template()).iter().enumerate() {
        let mut run = widen(run, COPIES);
        if n == 2 {
            run.scenarios[1].results[1].status = tessera_results::Status::Failed {
                error: "device lost".into(),
            };
        }
        ingest_and_detect(&mut *c, &run, &Params::default()).unwrap();
    }
    drop(c);
    (store, h)
}

#[test]
fn a_wide_run_opens_on_its_summary_and_each_scenario_has_a_page() {
    let (store, h) = wide_store();
    let app = app(AppState::new(store.pool.clone(), None));
    block_on(async {
        let run = h.run_id(2);
        let (status, page) = get(&app, &format!("/runs/{run}")).await;
        assert_eq!(status, StatusCode::OK);
        // The summary, one row per scenario, and none of the scenarios' tables.
        assert!(page.contains("<table id=run-summary>"), "{page}");
        assert_eq!(page.matches("<tr><td><a href=\"/runs/").count(), COPIES);
        assert!(!page.contains("<table class=variants>"));
        assert!(page.contains(&format!(
            "{} results in {COPIES} scenarios · <span class=worse>{COPIES} with a slower variant</span>",
            COPIES * 3
        )));
        // What changed beyond noise: native, 30% slower, named in each row.
        assert_eq!(
            page.matches("native</span></span> <span class=worse>+30.")
                .count(),
            COPIES,
            "{page}"
        );
        // The failure is counted and named in its scenario's row.
        assert!(page.contains("<span class=failed>1 with a failure</span>"));
        assert!(page.contains("<span title=\"device lost\">"));
        // The summary page is a fraction of the detail: under 1 KB per result.
        assert!(page.len() < COPIES * 3 * 1024, "{} bytes", page.len());

        // One scenario's page: its table against the same scenario of the previous run.
        let first = "tiny-000";
        let (status, one) = get(&app, &format!("/runs/{run}/scenarios/{first}")).await;
        assert_eq!(status, StatusCode::OK);
        assert!(one.contains(&format!("<h2 id=\"s-{first}\">")), "{one}");
        assert_eq!(one.matches("<table class=variants>").count(), 1);
        assert!(one.contains(&format!("next <a href=\"/runs/{run}/scenarios/tiny-001\">")));
        assert!(one.contains("class=\"n worse\" title=\"slower"), "{one}");
        let (status, _) = get(&app, &format!("/runs/{run}/scenarios/nothing")).await;
        assert_eq!(status, StatusCode::NOT_FOUND);
    });
}

/// A wide run's summary reads rows, not records, and asks for a series' noise only where it can
/// decide: a 3% step (below the fixed 5%) thirty σ outside `native`'s nightly noise is still
/// called slower in every scenario's row, and the other variants are not, as the run page of the
/// same nights says at a width where every series' noise is read (`morning_after.rs`).
#[test]
fn a_wide_summary_calls_a_step_below_the_threshold_by_its_noise() {
    let (store, h) = nightly_step_store();
    let app = app(AppState::new(store.pool.clone(), None));
    block_on(async {
        let (status, page) = get(&app, &format!("/runs/{}", h.run_id(11))).await;
        assert_eq!(status, StatusCode::OK);
        assert!(page.contains("<table id=run-summary>"), "{page}");
        assert!(page.contains(&format!(
            "<span class=worse>{COPIES} with a slower variant</span> · <span class=better>0 with a faster one</span>"
        )), "{page}");
        assert_eq!(
            page.matches("native</span></span> <span class=worse>+3.")
                .count(),
            COPIES,
            "{page}"
        );
        assert!(!page.contains("upscale[scale=0.5]</span></span> <span class=worse>"));
        // The night before the step: nothing changed.
        let (_, before) = get(&app, &format!("/runs/{}", h.run_id(10))).await;
        assert!(
            before.contains("<span class=worse>0 with a slower variant</span>"),
            "{before}"
        );
    });
}

#[test]
fn a_wide_comparison_opens_on_its_summary_with_one_scenario_on_demand() {
    let (store, h) = wide_store();
    let app = app(AppState::new(store.pool.clone(), None));
    block_on(async {
        let (a, b) = (h.run_id(1), h.run_id(2));
        let (status, page) = get(&app, &format!("/compare/runs?a={a}&b={b}")).await;
        assert_eq!(status, StatusCode::OK);
        assert!(page.contains("<table id=compare-summary>"), "{page}");
        assert!(!page.contains("<table class=compare>"));
        // Every scenario's row links to its table; native is slower in each.
        let rows = page
            .matches(&format!("href=\"/compare/runs?a={a}&b={b}&scenario=tiny-"))
            .count();
        assert_eq!(rows, COPIES);
        assert!(page.contains("<td class=\"n worse\">1</td>"));
        // The regressions named at the top stop at 40, the rest counted.
        assert!(page.contains(" more: see the scenarios below"), "{page}");
        let (_, one) = get(
            &app,
            &format!("/compare/runs?a={a}&b={b}&scenario=tiny-007"),
        )
        .await;
        assert_eq!(one.matches("<table class=compare>").count(), 1, "{one}");
        assert!(one.contains("<h2 id=\"s-tiny-007\">"));
        assert!(!one.contains("<h2 id=\"s-tiny-008\">"));
        // The A/B button: the two runs' commits, on the scenario shown.
        assert!(one.contains(&format!("href=\"/ab/new?a={a}&b={b}&scenario=tiny-007\"")));
    });
}

#[test]
fn a_large_alert_group_pivots_by_scenario_and_variant() {
    use tessera_dashboard::store::alerts::{self, DetectionStatus, Placement};
    let (store, h) = wide_store();
    let mut c = store.pool.get().unwrap();
    let pk = |c: &mut dyn tessera_dashboard::db::Connection, n: usize| {
        c.query(
            "SELECT id FROM runs WHERE run_id = $1",
            &[h.run_id(n).as_str().into()],
        )
        .unwrap()[0]
            .i64(0)
            .unwrap()
    };
    let series: Vec<i64> = c
        .query(
            "SELECT id FROM series WHERE measure = 'gpu_ms.median' ORDER BY scenario, variant LIMIT 90",
            &[],
        )
        .unwrap()
        .iter()
        .map(|r| r.i64(0).unwrap())
        .collect();
    assert_eq!(series.len(), 90);
    let p = Placement {
        run_pk_before: pk(&mut *c, 1),
        run_pk_after: pk(&mut *c, 2),
        value_before: 1.0,
        value_after: 1.3,
        relative_change: 0.3,
        change_low: 0.29,
        change_high: 0.31,
        confidence: 0.999,
        location_probability: 0.99,
        first_candidate: pk(&mut *c, 2),
        last_candidate: pk(&mut *c, 2),
        status: DetectionStatus::Confirmed,
    };
    let mut group = 0;
    for s in &series {
        let id = alerts::insert(&mut *c, *s, &p).unwrap();
        group = c
            .query(
                "SELECT group_id FROM regressions WHERE id = $1",
                &[id.into()],
            )
            .unwrap()[0]
            .i64(0)
            .unwrap();
    }
    drop(c);
    let app = app(AppState::new(store.pool.clone(), None));
    block_on(async {
        let (status, page) = get(&app, &format!("/regressions/groups/{group}")).await;
        assert_eq!(status, StatusCode::OK);
        // 30 scenarios x 3 variants: a table of 30 rows and 3 columns, and 6 charts, not 90.
        assert!(page.contains("90 series by scenario and variant"), "{page}");
        let pivot = &page[page.find("<table class=pivot>").unwrap()..];
        let pivot = &pivot[..pivot.find("</table>").unwrap()];
        assert_eq!(pivot.matches("<tr><th>").count(), 31);
        assert_eq!(pivot.matches("class=\"nw worse\"").count(), 90);
        assert_eq!(page.matches("<svg").count(), 6, "{page}");
    });
}

#[test]
fn the_ab_button_queues_an_ab_with_a_write_token() {
    let (store, h) = wide_store();
    let app = app(AppState::new(store.pool.clone(), Some("right".into())));
    block_on(async {
        let (a, b) = (h.run_id(1), h.run_id(2));
        let (_, run) = get(&app, &format!("/runs/{b}")).await;
        assert!(
            run.contains(&format!("href=\"/ab/new?a={a}&b={b}\"")),
            "{run}"
        );
        let (status, form) = get(&app, &format!("/ab/new?a={a}&b={b}&scenario=tiny-003")).await;
        assert_eq!(status, StatusCode::OK);
        // Prefilled: both commits and the scenario's file.
        let sha = tessera_dashboard::steps::sha;
        assert!(
            form.contains(&format!("name=a value=\"{}\"", sha(1))),
            "{form}"
        );
        assert!(
            form.contains(&format!("name=b value=\"{}\"", sha(2))),
            "{form}"
        );
        let file = common::template().scenarios[0].file.clone();
        assert!(
            form.contains(&format!("name=scenario value=\"{}\"", file)),
            "{form}"
        );
        let post = |token: &str, labels: &str| {
            // The fixture's file is where it was recorded; a job names a file in the repository.
            let body = format!(
                "scenario=scenarios/smoke/tiny.toml&variant=native&a={}&b={}&labels={labels}&attempts=5&token={token}",
                sha(1),
                sha(2)
            );
            Request::post("/ab/new")
                .header("Content-Type", "application/x-www-form-urlencoded")
                .body(Body::from(body))
                .unwrap()
        };
        // A wrong token writes nothing.
        let (status, _) = send(&app, post("wrong", "llvmpipe")).await;
        assert_eq!(status, StatusCode::UNAUTHORIZED);
        // A label no runner has is refused, as the API refuses it.
        let (status, text) = send(&app, post("right", "nobody")).await;
        assert!(status.is_client_error(), "{status} {text}");
        // With a runner of the label registered, the A/B is queued.
        let mut c = store.pool.get().unwrap();
        tessera_dashboard::store::queue::register(
            &mut *c,
            &tessera_results::queue::Registration {
                name: "r1".into(),
                labels: vec!["llvmpipe".into()],
                adapter: "llvmpipe".into(),
                driver: String::new(),
                host: "h".into(),
            },
            "t",
            0,
        )
        .unwrap();
        drop(c);
        let (status, done) = send(&app, post("right", "llvmpipe")).await;
        assert_eq!(status, StatusCode::CREATED, "{done}");
        assert!(done.contains("A/B request 1 queued: 1 job"), "{done}");
        let (_, jobs) = get(&app, "/api/ab/1").await;
        assert!(jobs.contains("\"label\":\"llvmpipe\""), "{jobs}");
    });
}

#[test]
fn an_image_link_without_images_answers_an_html_404_page() {
    let (store, h) = wide_store();
    let app = app(AppState::new(store.pool.clone(), None));
    block_on(async {
        let run = h.run_id(2);
        let res = app
            .clone()
            .oneshot(
                Request::get(format!("/runs/{run}/images/tiny-000/nothing"))
                    .body(Body::empty())
                    .unwrap(),
            )
            .await
            .unwrap();
        assert_eq!(res.status(), StatusCode::NOT_FOUND);
        let kind = res.headers()["content-type"].to_str().unwrap().to_string();
        assert!(kind.starts_with("text/html"), "{kind}");
        let b = res.into_body().collect().await.unwrap().to_bytes();
        let page = String::from_utf8_lossy(&b);
        assert!(page.contains("<title>No images"), "{page}");
        assert!(
            page.contains(&format!("<a href=\"/runs/{run}\">")),
            "{page}"
        );
    });
}

/// The comparison keeps the two runs it decoded and B's noise in memory
/// (`store::run_cache`): the page asked again, after the store changed under it (the oldest
/// nights deleted, so B's series have too few earlier points for a noise of their own) and after
/// B itself was deleted and stored again with other values, is byte for byte the page of a server
/// that kept nothing.
#[test]
fn a_comparison_from_kept_runs_is_the_page_a_fresh_server_writes() {
    let (store, h) = nightly_step_store();
    let kept = app(AppState::new(store.pool.clone(), None));
    let fresh = || app(AppState::new(store.pool.clone(), None));
    let url = format!("/compare/runs?a={}&b={}", h.run_id(10), h.run_id(11));
    block_on(async {
        let (status, first) = get(&kept, &url).await;
        assert_eq!(status, StatusCode::OK);
        // The 3% step is called by the series' noise alone.
        assert!(first.contains("<td class=\"n worse\">1</td>"), "{first}");
        assert_eq!(get(&kept, &url).await.1, first);
        assert_eq!(get(&fresh(), &url).await.1, first);

        let mut c = store.pool.get().unwrap();
        for night in 0..4 {
            tessera_dashboard::store::delete::delete_run(&mut *c, &h.run_id(night)).unwrap();
        }
        drop(c);
        let (_, fewer) = get(&kept, &url).await;
        assert_ne!(fewer, first);
        assert!(!fewer.contains("<td class=\"n worse\">1</td>"), "{fewer}");
        assert_eq!(get(&fresh(), &url).await.1, fewer);

        let mut c = store.pool.get().unwrap();
        tessera_dashboard::store::delete::delete_run(&mut *c, &h.run_id(11)).unwrap();
        let flat = StepHistory::h200(12, 11, "native", 1.5).runs(&common::template());
        ingest_and_detect(&mut *c, &widen(&flat[11], COPIES), &Params::default()).unwrap();
        drop(c);
        let (_, again) = get(&kept, &url).await;
        assert_ne!(again, fewer);
        assert!(again.contains("+50."), "{again}");
        assert_eq!(get(&fresh(), &url).await.1, again);
    });
}
