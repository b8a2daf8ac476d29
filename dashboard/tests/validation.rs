//! Input validation at the door (issue 22, item 3): every bad upload answers 4xx with a JSON error
//! naming the field and stores nothing; the same run id with other content is a 409; retention
//! places runs by commit time (or storing time), never by the client's `started_at`.

mod common;

use axum::body::Body;
use axum::http::{header, Request, StatusCode};
use axum::Router;
use http_body_util::BodyExt;
use tessera_dashboard::bundle::RunBundle;
use tessera_dashboard::db::Pool;
use tessera_dashboard::detect::Rng;
use tessera_dashboard::server::{app, AppState};
use tessera_dashboard::store::delete::{expired, Retention};
use tower::ServiceExt;

const TOKEN: &str = "validation-test-token";

fn runtime() -> tokio::runtime::Runtime {
    tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap()
}

fn upload(app: &Router, body: String) -> (StatusCode, serde_json::Value) {
    let req = Request::builder()
        .method("POST")
        .uri("/api/runs")
        .header(header::CONTENT_TYPE, "application/json")
        .header(header::AUTHORIZATION, format!("Bearer {TOKEN}"))
        .body(Body::from(body))
        .unwrap();
    runtime().block_on(async {
        let res = app.clone().oneshot(req).await.unwrap();
        let status = res.status();
        let bytes = res.into_body().collect().await.unwrap().to_bytes();
        let json = serde_json::from_slice(&bytes)
            .unwrap_or_else(|e| panic!("not JSON ({e}): {}", String::from_utf8_lossy(&bytes)));
        (status, json)
    })
}

fn run(index: u64) -> RunBundle {
    tessera_dashboard::synth::run_from(
        &common::template(),
        "v",
        index,
        1.0,
        0.01,
        &mut Rng::new(index),
    )
}

fn body(b: &RunBundle) -> serde_json::Value {
    serde_json::to_value(b.to_upload()).unwrap()
}

fn count(pool: &Pool, table: &str) -> i64 {
    pool.get()
        .unwrap()
        .query(&format!("SELECT COUNT(*) FROM {table}"), &[])
        .unwrap()[0]
        .i64(0)
        .unwrap()
}

/// Each case: what it does to a good upload body, and the field the refusal must name.
type Case = (
    &'static str,
    Box<dyn Fn(&mut serde_json::Value)>,
    &'static str,
);

fn cases() -> Vec<Case> {
    vec![
        (
            "started_at not a date",
            Box::new(|b| b["run"]["started_at"] = "not a date".into()),
            "run.started_at",
        ),
        (
            "started_at in the year 9999",
            Box::new(|b| b["run"]["started_at"] = "9999-01-01T00:00:00Z".into()),
            "run.started_at",
        ),
        (
            "finished_at before started_at",
            Box::new(|b| b["run"]["finished_at"] = "2020-01-01T00:00:00Z".into()),
            "run.finished_at",
        ),
        (
            "commit_time in 1970",
            Box::new(|b| b["run"]["commit_time"] = "1970-01-01T00:00:00Z".into()),
            "run.commit_time",
        ),
        (
            "a pass time of 1.7e308 ms",
            Box::new(|b| {
                b["scenarios"][0]["results"][0]["passes"][0]["gpu_ms"]["median"] = 1.7e308.into()
            }),
            "gpu_ms.median",
        ),
        (
            "a negative per-frame sample",
            Box::new(|b| {
                b["scenarios"][0]["results"][0]["passes"][0]["samples_ms"][0] = (-3.0).into()
            }),
            "samples_ms[0]",
        ),
        (
            "a negative CPU frame time",
            Box::new(|b| b["scenarios"][0]["results"][0]["cpu_frame_ms"]["mean"] = (-1.0).into()),
            "cpu_frame_ms.mean",
        ),
        (
            "a variant name with a pipe and backticks",
            Box::new(|b| b["scenarios"][0]["results"][0]["variant"] = "na|ti`ve`".into()),
            "results[0].variant",
        ),
        (
            "a scenario name with a space",
            Box::new(|b| b["scenarios"][0]["scenario"] = "tiny scene".into()),
            "scenarios[0].scenario",
        ),
        (
            "a scenario name of 161 bytes",
            Box::new(|b| b["scenarios"][0]["scenario"] = "s".repeat(161).into()),
            "scenarios[0].scenario",
        ),
        (
            "a branch with a newline",
            Box::new(|b| b["run"]["branch"] = "main\n| injected |".into()),
            "run.branch",
        ),
    ]
}

#[test]
fn each_bad_input_is_refused_naming_its_field_and_stores_nothing() {
    for store in common::stores("each_bad_input_is_refused_naming_its_field_and_stores_nothing") {
        let app = app(AppState::new(store.pool.clone(), Some(TOKEN.into())));
        let good = body(&run(1));
        for (what, spoil, field) in cases() {
            let mut b = good.clone();
            spoil(&mut b);
            let (status, json) = upload(&app, b.to_string());
            assert!(
                status.is_client_error(),
                "{}: {what}: HTTP {status} {json}",
                store.name
            );
            assert_eq!(status, StatusCode::UNPROCESSABLE_ENTITY, "{what}: {json}");
            let named = json["field"].as_str().unwrap_or_default();
            assert!(
                named.ends_with(field),
                "{what}: field {named:?} should end with {field:?}: {json}"
            );
            assert!(
                json["error"].as_str().unwrap().starts_with(named),
                "{what}: the message names the field: {json}"
            );
            for table in ["runs", "results", "points", "images", "blobs"] {
                assert_eq!(count(&store.pool, table), 0, "{what}: {table} stays empty");
            }
        }
        // The good body itself is stored.
        let (status, json) = upload(&app, good.to_string());
        assert_eq!(status, StatusCode::CREATED, "{json}");
    }
}

#[test]
fn the_same_run_id_with_other_content_is_a_conflict() {
    for store in common::stores("the_same_run_id_with_other_content_is_a_conflict") {
        let app = app(AppState::new(store.pool.clone(), Some(TOKEN.into())));
        let first = run(7);
        let (status, json) = upload(&app, body(&first).to_string());
        assert_eq!(status, StatusCode::CREATED, "{json}");
        let points = count(&store.pool, "points");

        // The same upload again: idempotent.
        let (status, json) = upload(&app, body(&first).to_string());
        assert_eq!(status, StatusCode::OK, "{json}");
        assert_eq!(json["stored"], false);

        // Other timings under the same run id.
        let mut other = first.clone();
        let v = &mut other.scenarios[0].results[0];
        v.cpu_frame_ms.median *= 2.0;
        let (status, json) = upload(&app, body(&other).to_string());
        assert_eq!(status, StatusCode::CONFLICT, "{json}");
        assert!(
            json["error"].as_str().unwrap().contains(&first.run.run_id),
            "{json}"
        );

        // Another commit under the same run id.
        let mut other = first.clone();
        other.run.commit.as_mut().unwrap().sha = "f".repeat(40);
        let (status, json) = upload(&app, body(&other).to_string());
        assert_eq!(status, StatusCode::CONFLICT, "{json}");
        assert!(
            json["error"].as_str().unwrap().contains("run.json"),
            "{json}"
        );

        assert_eq!(count(&store.pool, "runs"), 1);
        assert_eq!(count(&store.pool, "points"), points, "nothing changed");
    }
}

#[test]
fn retention_orders_by_commit_time_never_by_the_clients_clock() {
    for store in common::stores("retention_orders_by_commit_time_never_by_the_clients_clock") {
        let mut c = store.pool.get().unwrap();
        // Five commits in order; the runner's clock is wrong on the oldest (far in the future)
        // and on the newest (far in the past), as a bad upload could have it before validation.
        for i in 0..5u64 {
            let mut b = run(i * 1440);
            b.run.started_at = match i {
                0 => "2026-12-01T23:00:00Z".into(),
                4 => "2017-01-01T00:00:00Z".into(),
                _ => b.run.started_at,
            };
            tessera_dashboard::store::ingest::ingest(&mut *c, &b).unwrap();
        }
        let now = chrono::DateTime::parse_from_rfc3339("2026-01-06T00:00:00Z")
            .unwrap()
            .with_timezone(&chrono::Utc);
        let gone: Vec<String> = expired(
            &mut *c,
            Retention {
                keep_days: None,
                keep_runs: Some(2),
            },
            now,
        )
        .unwrap()
        .into_iter()
        .map(|e| {
            assert_eq!(e.by, "commit");
            e.run_id
        })
        .collect();
        let id = |i: u64| format!("v-{:06}", i * 1440);
        assert_eq!(
            gone,
            vec![id(0), id(1), id(2)],
            "the two newest commits stay"
        );

        // By age: the cut-off (2026-01-03) applies to commit times: days 2, 3 and 4 stay.
        let gone: Vec<String> = expired(
            &mut *c,
            Retention {
                keep_days: Some(3),
                keep_runs: None,
            },
            now,
        )
        .unwrap()
        .into_iter()
        .map(|e| e.run_id)
        .collect();
        assert_eq!(gone, vec![id(0), id(1)]);
    }
}

#[test]
fn retention_without_commit_times_orders_by_storing_time() {
    let store = common::sqlite();
    let mut c = store.pool.get().unwrap();
    for i in 0..3u64 {
        let mut b = run(i);
        b.run.commit_time = None;
        // The newest stored run claims the oldest start.
        b.run.started_at = format!("2026-01-0{}T00:00:00Z", 3 - i);
        tessera_dashboard::store::ingest::ingest(&mut *c, &b).unwrap();
    }
    let gone: Vec<String> = expired(
        &mut *c,
        Retention {
            keep_days: None,
            keep_runs: Some(1),
        },
        chrono::Utc::now(),
    )
    .unwrap()
    .into_iter()
    .map(|e| {
        assert_eq!(e.by, "stored");
        e.run_id
    })
    .collect();
    assert_eq!(gone, vec!["v-000000".to_string(), "v-000001".into()]);
}
