//! The queue's endpoints through the router (`oneshot`): what a runner-scope token may and may not
//! do, and hostile input (unknown commits, huge attempt counts, labels no runner has, an upload
//! for a job the runner does not hold) answered with a clear 4xx that changes nothing.

mod common;

use axum::body::Body;
use axum::http::{header, Request, StatusCode};
use axum::Router;
use http_body_util::BodyExt;
use tessera_dashboard::db::Pool;
use tessera_dashboard::detect::Rng;
use tessera_dashboard::server::auth::Scope;
use tessera_dashboard::server::{app, app as app_of, AppState};
use tessera_dashboard::store::tokens;
use tower::ServiceExt;

async fn send(
    app: &Router,
    method: &str,
    uri: &str,
    token: &str,
    job: Option<i64>,
    body: String,
) -> (StatusCode, serde_json::Value) {
    let mut r = Request::builder()
        .method(method)
        .uri(uri)
        .header(header::CONTENT_TYPE, "application/json")
        .header(header::AUTHORIZATION, format!("Bearer {token}"));
    if let Some(j) = job {
        r = r.header("x-tessera-job", j.to_string());
    }
    let res = app
        .clone()
        .oneshot(r.body(Body::from(body)).unwrap())
        .await
        .unwrap();
    let status = res.status();
    let bytes = res.into_body().collect().await.unwrap().to_bytes();
    let v = serde_json::from_slice(&bytes).unwrap_or(serde_json::Value::Null);
    (status, v)
}

fn count(pool: &Pool, table: &str) -> i64 {
    pool.get()
        .unwrap()
        .query(&format!("SELECT COUNT(*) FROM {table}"), &[])
        .unwrap()[0]
        .i64(0)
        .unwrap()
}

fn run_body(index: u64) -> (String, String) {
    let b = tessera_dashboard::synth::run_from(
        &common::template(),
        "q",
        index,
        1.0,
        0.01,
        &mut Rng::new(index),
    );
    let commit = b.run.commit.as_ref().unwrap().sha.clone();
    (serde_json::to_string(&b.to_upload()).unwrap(), commit)
}

#[tokio::test]
async fn a_runner_token_serves_the_queue_and_uploads_only_its_jobs_runs() {
    let store = common::sqlite();
    let runner = tokens::add(&mut *store.pool.get().unwrap(), "box-1", Scope::Runner).unwrap();
    let other = tokens::add(&mut *store.pool.get().unwrap(), "box-2", Scope::Runner).unwrap();
    let admin = tokens::add(&mut *store.pool.get().unwrap(), "admin", Scope::Write).unwrap();
    let app = app(AppState::new(store.pool.clone(), None));
    let reg = serde_json::json!({"name": "r1", "labels": ["llvmpipe"], "adapter": "llvmpipe",
        "driver": "mesa", "host": "h"})
    .to_string();
    let (s, v) = send(
        &app,
        "POST",
        "/api/runners/register",
        &runner,
        None,
        reg.clone(),
    )
    .await;
    assert_eq!(s, StatusCode::OK, "{v}");
    // Another token cannot take over the name.
    let (s, v) = send(&app, "POST", "/api/runners/register", &other, None, reg).await;
    assert_eq!(s, StatusCode::CONFLICT, "{v}");
    let claim = serde_json::json!({"runner": "r1"}).to_string();
    let (s, _) = send(
        &app,
        "POST",
        "/api/queue/claim",
        &runner,
        None,
        claim.clone(),
    )
    .await;
    assert_eq!(s, StatusCode::NO_CONTENT);
    let (s, v) = send(
        &app,
        "POST",
        "/api/queue/claim",
        &other,
        None,
        claim.clone(),
    )
    .await;
    assert_eq!(s, StatusCode::FORBIDDEN, "{v}");

    // A runner token cannot queue work or write anything but its jobs' runs.
    let (body, commit) = run_body(3);
    let request =
        serde_json::json!({"commit": commit, "suites": ["smoke"], "labels": ["llvmpipe"]})
            .to_string();
    let (s, v) = send(
        &app,
        "POST",
        "/api/queue/requests",
        &runner,
        None,
        request.clone(),
    )
    .await;
    assert_eq!(s, StatusCode::FORBIDDEN, "{v}");
    assert!(v["error"].as_str().unwrap().contains("scope runner"), "{v}");
    let (s, v) = send(&app, "POST", "/api/runs", &runner, None, body.clone()).await;
    assert_eq!(s, StatusCode::FORBIDDEN, "{v}");
    assert!(
        v["error"].as_str().unwrap().contains("x-tessera-job"),
        "{v}"
    );
    assert_eq!(count(&store.pool, "runs"), 0);

    let (s, v) = send(&app, "POST", "/api/queue/requests", &admin, None, request).await;
    assert_eq!(s, StatusCode::CREATED, "{v}");
    let job = v["jobs"][0].as_i64().unwrap();
    // Not claimed yet: the upload naming it is refused and stores nothing.
    let (s, v) = send(&app, "POST", "/api/runs", &runner, Some(job), body.clone()).await;
    assert_eq!(s, StatusCode::FORBIDDEN, "{v}");
    assert_eq!(count(&store.pool, "runs"), 0);
    let (s, v) = send(&app, "POST", "/api/queue/claim", &runner, None, claim).await;
    assert_eq!(
        (s, v["job_id"].as_i64()),
        (StatusCode::OK, Some(job)),
        "{v}"
    );
    let attempt = v["attempt"].as_i64().unwrap();
    // A run at another commit is not this job's.
    let (wrong, _) = run_body(4);
    let (s, v) = send(&app, "POST", "/api/runs", &runner, Some(job), wrong).await;
    assert_eq!(s, StatusCode::FORBIDDEN, "{v}");
    assert!(
        v["error"]
            .as_str()
            .unwrap()
            .contains("is not a commit of job"),
        "{v}"
    );
    // The other runner's token cannot upload for it either.
    let (s, _) = send(&app, "POST", "/api/runs", &other, Some(job), body.clone()).await;
    assert_eq!(s, StatusCode::FORBIDDEN);
    assert_eq!(count(&store.pool, "runs"), 0);
    let (s, v) = send(&app, "POST", "/api/runs", &runner, Some(job), body).await;
    assert_eq!(s, StatusCode::CREATED, "{v}");
    let run_id = v["run_id"].as_str().unwrap().to_string();
    // A completion with another attempt number is refused; the right one is stored.
    let done = |attempt: i64| {
        serde_json::json!({"runner": "r1", "attempt": attempt, "runs": [run_id]}).to_string()
    };
    let uri = format!("/api/queue/jobs/{job}/complete");
    let (s, _) = send(&app, "POST", &uri, &runner, None, done(attempt + 1)).await;
    assert_eq!(s, StatusCode::CONFLICT);
    let (s, v) = send(&app, "POST", &uri, &runner, None, done(attempt)).await;
    assert_eq!(s, StatusCode::OK, "{v}");
    // A runner token cannot delete runs.
    let (s, _) = send(
        &app,
        "DELETE",
        &format!("/api/runs/{run_id}"),
        &runner,
        None,
        String::new(),
    )
    .await;
    assert_eq!(s, StatusCode::FORBIDDEN);
}

#[tokio::test]
async fn hostile_requests_get_a_clear_4xx_and_change_nothing() {
    let store = common::sqlite();
    let runner = tokens::add(&mut *store.pool.get().unwrap(), "box", Scope::Runner).unwrap();
    let admin = tokens::add(&mut *store.pool.get().unwrap(), "admin", Scope::Write).unwrap();
    let app = app(AppState::new(store.pool.clone(), None));
    let reg = serde_json::json!({"name": "r", "labels": ["llvmpipe"], "adapter": "a", "driver": "d",
        "host": "h"});
    let (s, _) = send(
        &app,
        "POST",
        "/api/runners/register",
        &runner,
        None,
        reg.to_string(),
    )
    .await;
    assert_eq!(s, StatusCode::OK);
    let sha = "0123456789abcdef0123456789abcdef01234567";
    let ab = |attempts: u64, label: &str, commit: &str| {
        serde_json::json!({"scenario": "scenarios/smoke/basic.toml", "a": {"commit": sha},
            "b": {"commit": commit}, "labels": [label], "attempts": attempts})
        .to_string()
    };
    let cases = [
        ("/api/ab", ab(1_000_000, "llvmpipe", sha), StatusCode::UNPROCESSABLE_ENTITY, "attempts"),
        ("/api/ab", ab(10, "amdgpu-typo", sha), StatusCode::UNPROCESSABLE_ENTITY, "no runner has registered"),
        ("/api/ab", ab(10, "llvmpipe", "main; rm -rf /"), StatusCode::UNPROCESSABLE_ENTITY, "not a commit"),
        ("/api/ab", "{\"scenario\": 3}".to_string(), StatusCode::UNPROCESSABLE_ENTITY, ""),
        ("/api/ab", "not json".to_string(), StatusCode::BAD_REQUEST, ""),
        (
            "/api/queue/requests",
            serde_json::json!({"commit": sha, "suites": ["../x"], "labels": ["llvmpipe"]}).to_string(),
            StatusCode::UNPROCESSABLE_ENTITY,
            "suite",
        ),
        (
            "/api/bisections",
            serde_json::json!({"scenario": "s.toml", "variant": "native", "measure": "gpu_sm",
                "good": sha, "bad": "fedcba9876543210fedcba9876543210fedcba98", "label": "llvmpipe"})
            .to_string(),
            StatusCode::UNPROCESSABLE_ENTITY,
            "not a measure name",
        ),
        (
            "/api/runners/register",
            serde_json::json!({"name": "x", "labels": vec!["l"; 17], "adapter": "a", "driver": "d",
                "host": "h"})
            .to_string(),
            StatusCode::UNPROCESSABLE_ENTITY,
            "1 to 16 labels",
        ),
        (
            "/api/queue/jobs/999/complete",
            serde_json::json!({"runner": "r", "attempt": 1}).to_string(),
            StatusCode::CONFLICT,
            "not held",
        ),
    ];
    for (uri, body, status, words) in cases {
        let token = if uri.starts_with("/api/runners") || uri.contains("/jobs/") {
            &runner
        } else {
            &admin
        };
        let (s, v) = send(&app, "POST", uri, token, None, body.clone()).await;
        assert_eq!(s, status, "{uri} {body}: {v}");
        let msg = v["error"]
            .as_str()
            .unwrap_or_else(|| panic!("{uri}: no error: {v}"));
        assert!(msg.contains(words), "{uri}: {msg}");
    }
    // With the project's repository configured, a well-formed but unknown commit is refused.
    let mut with_repo = AppState::new(store.pool.clone(), None);
    with_repo.queue.repository = Some(std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")));
    let (s, v) = send(
        &app_of(with_repo),
        "POST",
        "/api/ab",
        &admin,
        None,
        ab(10, "llvmpipe", sha),
    )
    .await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert!(
        v["error"]
            .as_str()
            .unwrap()
            .contains("is not a commit of the dashboard's repository"),
        "{v}"
    );
    for table in ["queue_requests", "queue_jobs", "bisections"] {
        assert_eq!(count(&store.pool, table), 0, "{table}");
    }
    assert_eq!(count(&store.pool, "runners"), 1);
}
