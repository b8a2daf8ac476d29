//! The write path through the router (`oneshot`): named tokens and their scopes, revocation,
//! secrets never stored, read protection, the per-token rate limit, JSON bodies for axum's own
//! rejections, `/healthz`, `DELETE /api/runs/{run_id}` and the retention rule. The tests that need
//! a real server process (memory under large unauthenticated bodies, slow clients) are in
//! `tests/write_path_server.rs`.

mod common;

use axum::body::Body;
use axum::http::{header, HeaderMap, Request, StatusCode};
use axum::Router;
use base64::Engine;
use http_body_util::BodyExt;
use tessera_dashboard::db::{self, Pool};
use tessera_dashboard::detect::Rng;
use tessera_dashboard::server::auth::{Auth, AuthConfig, Scope};
use tessera_dashboard::server::{app, AppState};
use tessera_dashboard::store::delete::{delete_run, expired, Retention};
use tessera_dashboard::store::ingest::ingest;
use tessera_dashboard::store::tokens;
use tower::ServiceExt;

struct Reply {
    status: StatusCode,
    headers: HeaderMap,
    body: String,
}

impl Reply {
    fn json(&self) -> serde_json::Value {
        serde_json::from_str(&self.body)
            .unwrap_or_else(|e| panic!("not JSON ({e}), HTTP {}: {}", self.status, self.body))
    }

    /// Asserts the documented error body: JSON `{"error": "..."}`; returns the message.
    fn error(&self) -> String {
        assert_eq!(
            self.headers
                .get(header::CONTENT_TYPE)
                .map(|v| v.to_str().unwrap()),
            Some("application/json"),
            "HTTP {}: {}",
            self.status,
            self.body
        );
        self.json()["error"]
            .as_str()
            .unwrap_or_else(|| panic!("no error message: {}", self.body))
            .to_string()
    }
}

async fn send(app: &Router, req: Request<Body>) -> Reply {
    let res = app.clone().oneshot(req).await.unwrap();
    let status = res.status();
    let headers = res.headers().clone();
    let body = res.into_body().collect().await.unwrap().to_bytes();
    Reply {
        status,
        headers,
        body: String::from_utf8_lossy(&body).into_owned(),
    }
}

/// A runtime for tests that also talk to PostgreSQL: its synchronous client must not be used
/// from inside a runtime, so store work stays outside `block_on`.
fn runtime() -> tokio::runtime::Runtime {
    tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap()
}

fn req(method: &str, uri: &str, token: Option<&str>, body: impl Into<Body>) -> Request<Body> {
    let mut r = Request::builder()
        .method(method)
        .uri(uri)
        .header(header::CONTENT_TYPE, "application/json");
    if let Some(t) = token {
        r = r.header(header::AUTHORIZATION, format!("Bearer {t}"));
    }
    r.body(body.into()).unwrap()
}

fn upload_body(index: u64) -> String {
    let b = tessera_dashboard::synth::run_from(
        &common::template(),
        "w",
        index,
        1.0,
        0.01,
        &mut Rng::new(index),
    );
    serde_json::to_string(&b.to_upload()).unwrap()
}

fn state(pool: &Pool, legacy: Option<&str>, config: AuthConfig) -> AppState {
    let mut s = AppState::new(pool.clone(), legacy.map(String::from));
    s.auth = Auth::new(config);
    s
}

fn add_token(pool: &Pool, name: &str, scope: Scope) -> String {
    tokens::add(&mut *pool.get().unwrap(), name, scope).unwrap()
}

#[tokio::test]
async fn named_tokens_have_scopes_and_can_be_revoked_alone() {
    let store = common::sqlite();
    let ci = add_token(&store.pool, "ci-runner", Scope::Write);
    let other = add_token(&store.pool, "nightly", Scope::Write);
    let viewer = add_token(&store.pool, "viewer", Scope::Read);
    let app = app(state(&store.pool, None, AuthConfig::default()));

    let r = send(
        &app,
        req("POST", "/api/runs", Some(&viewer), upload_body(1)),
    )
    .await;
    assert_eq!(r.status, StatusCode::FORBIDDEN);
    assert!(r.error().contains("scope read"), "{}", r.body);
    let r = send(
        &app,
        req("POST", "/api/runs", Some("tsr_guess"), upload_body(1)),
    )
    .await;
    assert_eq!(r.status, StatusCode::UNAUTHORIZED);
    assert!(r.error().contains("Bearer"));
    let r = send(&app, req("POST", "/api/runs", Some(&ci), upload_body(1))).await;
    assert_eq!(r.status, StatusCode::CREATED, "{}", r.body);

    // Revoking one token refuses it at once and leaves the others working.
    tokens::revoke(&mut *store.pool.get().unwrap(), "ci-runner").unwrap();
    let r = send(&app, req("POST", "/api/runs", Some(&ci), upload_body(2))).await;
    assert_eq!(r.status, StatusCode::UNAUTHORIZED, "{}", r.body);
    let r = send(&app, req("POST", "/api/runs", Some(&other), upload_body(2))).await;
    assert_eq!(r.status, StatusCode::CREATED, "{}", r.body);
    assert!(tokens::revoke(&mut *store.pool.get().unwrap(), "ci-runner").is_err());

    // Listing never shows a secret; the names are reserved and unique.
    let list = tokens::list(&mut *store.pool.get().unwrap()).unwrap();
    let names: Vec<_> = list.iter().map(|t| (t.name.as_str(), t.scope)).collect();
    assert_eq!(names, [("nightly", Scope::Write), ("viewer", Scope::Read)]);
    assert!(tokens::add(&mut *store.pool.get().unwrap(), "nightly", Scope::Read).is_err());
    assert!(tokens::add(&mut *store.pool.get().unwrap(), "legacy", Scope::Read).is_err());
}

#[test]
fn secrets_are_stored_hashed_never_in_clear() {
    for store in common::stores("secrets_are_stored_hashed_never_in_clear") {
        let secret = add_token(&store.pool, "ci", Scope::Write);
        assert!(secret.starts_with("tsr_") && secret.len() > 40);
        let mut c = store.pool.get().unwrap();
        let rows = c
            .query(
                "SELECT name, scope, secret_sha256, created_at FROM api_tokens",
                &[],
            )
            .unwrap();
        assert_eq!(rows.len(), 1);
        let stored = rows[0].string(2).unwrap();
        assert_eq!(stored.len(), 64, "{}: SHA-256 in hex", store.name);
        for i in 0..4 {
            assert!(!rows[0].string(i).unwrap().contains(&secret[4..]));
        }
        let expected: String = tokens::hash(&secret)
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        assert_eq!(stored, expected);
    }
    // And nowhere in the SQLite file itself, journal included.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.sqlite");
    let pool = db::open(path.to_str().unwrap()).unwrap();
    let secret = add_token(&pool, "ci", Scope::Write);
    drop(pool);
    for f in std::fs::read_dir(dir.path()).unwrap() {
        let bytes = std::fs::read(f.unwrap().path()).unwrap();
        assert!(!bytes
            .windows(secret.len() - 4)
            .any(|w| w == &secret.as_bytes()[4..]));
    }
}

#[tokio::test]
async fn the_legacy_token_still_writes() {
    let store = common::sqlite();
    let app = app(state(
        &store.pool,
        Some("old-secret"),
        AuthConfig::default(),
    ));
    let r = send(
        &app,
        req("POST", "/api/runs", Some("old-secret"), upload_body(1)),
    )
    .await;
    assert_eq!(r.status, StatusCode::CREATED, "{}", r.body);
}

#[tokio::test]
async fn reads_are_public_unless_a_read_token_is_required() {
    let store = common::sqlite();
    let viewer = add_token(&store.pool, "viewer", Scope::Read);
    let writer = add_token(&store.pool, "ci", Scope::Write);
    let open = app(state(&store.pool, None, AuthConfig::default()));
    assert_eq!(
        send(&open, req("GET", "/api/runs", None, "")).await.status,
        StatusCode::OK
    );

    let closed = app(state(
        &store.pool,
        None,
        AuthConfig {
            require_read_token: true,
            ..AuthConfig::default()
        },
    ));
    let r = send(&closed, req("GET", "/", None, "")).await;
    assert_eq!(r.status, StatusCode::UNAUTHORIZED);
    assert!(r.error().contains("read token"));
    assert_eq!(
        r.headers.get(header::WWW_AUTHENTICATE).unwrap(),
        "Basic realm=\"tessera-dashboard\"",
        "browsers are asked for the token"
    );
    for t in [&viewer, &writer] {
        let r = send(&closed, req("GET", "/api/runs", Some(t), "")).await;
        assert_eq!(r.status, StatusCode::OK, "{}", r.body);
    }
    let basic = |secret: &str| {
        let creds = base64::engine::general_purpose::STANDARD.encode(format!("me:{secret}"));
        let mut r = req("GET", "/", None, "");
        r.headers_mut().insert(
            header::AUTHORIZATION,
            format!("Basic {creds}").parse().unwrap(),
        );
        r
    };
    assert_eq!(send(&closed, basic(&viewer)).await.status, StatusCode::OK);
    assert_eq!(
        send(&closed, basic("wrong")).await.status,
        StatusCode::UNAUTHORIZED
    );
    // Basic is never enough for a write (a cross-site form would carry it).
    let mut w = basic(&writer);
    *w.method_mut() = axum::http::Method::POST;
    *w.uri_mut() = "/api/runs".parse().unwrap();
    assert_eq!(send(&closed, w).await.status, StatusCode::UNAUTHORIZED);
    // Probes need nothing.
    assert_eq!(
        send(&closed, req("GET", "/healthz", None, "")).await.status,
        StatusCode::OK
    );
}

#[tokio::test]
async fn writes_are_rate_limited_per_token() {
    let store = common::sqlite();
    let a = add_token(&store.pool, "a", Scope::Write);
    let b = add_token(&store.pool, "b", Scope::Write);
    let app = app(state(
        &store.pool,
        None,
        AuthConfig {
            require_read_token: false,
            writes_per_minute: 1,
            write_burst: 2,
        },
    ));
    let delete = |t: &str| req("DELETE", "/api/runs/nope", Some(t), "");
    for _ in 0..2 {
        assert_eq!(send(&app, delete(&a)).await.status, StatusCode::NOT_FOUND);
    }
    let r = send(&app, delete(&a)).await;
    assert_eq!(r.status, StatusCode::TOO_MANY_REQUESTS);
    assert!(r.error().contains("retry after"));
    let retry: u64 = r.headers[header::RETRY_AFTER]
        .to_str()
        .unwrap()
        .parse()
        .unwrap();
    assert!((1..=60).contains(&retry), "Retry-After {retry}");
    // Another token has its own allowance; reads are not limited.
    assert_eq!(send(&app, delete(&b)).await.status, StatusCode::NOT_FOUND);
    assert_eq!(
        send(&app, req("GET", "/api/runs", None, "")).await.status,
        StatusCode::OK
    );
}

#[tokio::test]
async fn axum_rejections_come_back_as_json_errors() {
    let store = common::sqlite();
    let t = add_token(&store.pool, "ci", Scope::Write);
    let mut s = state(&store.pool, None, AuthConfig::default());
    s.max_upload_bytes = 1 << 10;
    let app = app(s);
    let cases: Vec<(&str, Request<Body>, StatusCode)> = vec![
        (
            "unknown page",
            req("GET", "/no/such", None, ""),
            StatusCode::NOT_FOUND,
        ),
        (
            "method not allowed",
            req("PUT", "/api/runs", Some(&t), ""),
            StatusCode::METHOD_NOT_ALLOWED,
        ),
        (
            "bad path parameter",
            req("GET", "/api/series/abc", None, ""),
            StatusCode::BAD_REQUEST,
        ),
        (
            "bad query",
            req("GET", "/api/regressions?limit=many", None, ""),
            StatusCode::BAD_REQUEST,
        ),
        (
            "JSON body that is not JSON",
            req("POST", "/api/regressions/1", Some(&t), "{"),
            StatusCode::BAD_REQUEST,
        ),
        (
            "form above its cap, no length given",
            Request::post("/regressions/1")
                .header(header::CONTENT_TYPE, "application/x-www-form-urlencoded")
                .body(Body::from(format!(
                    "state=new&note={}",
                    "x".repeat(100_000)
                )))
                .unwrap(),
            StatusCode::PAYLOAD_TOO_LARGE,
        ),
        (
            "body above the limit, length given",
            {
                let mut r = req("POST", "/api/runs", Some(&t), "x".repeat(4 << 10));
                r.headers_mut().insert(
                    header::CONTENT_LENGTH,
                    (4 << 10).to_string().parse().unwrap(),
                );
                r
            },
            StatusCode::PAYLOAD_TOO_LARGE,
        ),
        (
            "form without its fields",
            Request::post("/regressions/1")
                .header(header::CONTENT_TYPE, "application/x-www-form-urlencoded")
                .body(Body::from("note=x"))
                .unwrap(),
            StatusCode::UNPROCESSABLE_ENTITY,
        ),
        (
            "form above its cap, length given",
            Request::post("/regressions/1")
                .header(header::CONTENT_TYPE, "application/x-www-form-urlencoded")
                .header(header::CONTENT_LENGTH, "100000")
                .body(Body::from("x".repeat(100_000)))
                .unwrap(),
            StatusCode::PAYLOAD_TOO_LARGE,
        ),
    ];
    for (what, request, status) in cases {
        let r = send(&app, request).await;
        assert_eq!(r.status, status, "{what}: {}", r.body);
        let msg = r.error();
        assert!(!msg.is_empty(), "{what}");
        if status == StatusCode::METHOD_NOT_ALLOWED {
            assert!(msg.contains("GET"), "{what}: {msg}");
            assert!(r.headers.contains_key(header::ALLOW));
        }
    }
}

#[test]
fn healthz_reports_the_store_and_its_schema() {
    let rt = runtime();
    for store in common::stores("healthz_reports_the_store_and_its_schema") {
        let app = app(AppState::new(store.pool.clone(), None));
        let r = rt.block_on(send(&app, req("GET", "/healthz", None, "")));
        assert_eq!(r.status, StatusCode::OK, "{}", r.body);
        let v = r.json();
        assert_eq!(v["status"], "ok");
        assert_eq!(v["store"], store.name);
        assert_eq!(v["schema_version"], db::known_version());
        assert_eq!(v["known_schema_version"], db::known_version());
    }
}

/// `n` generated runs a day apart with a 15% step at `step`, stored through `ingest` and
/// detection, so that regressions (alerts) exist.
fn history(pool: &Pool, prefix: &str, n: u64, step: u64) {
    let template = common::template();
    let mut rng = Rng::new(5);
    let mut c = pool.get().unwrap();
    let mut series = std::collections::BTreeSet::new();
    for i in 0..n {
        let f = if i < step { 1.0 } else { 1.15 };
        let b = tessera_dashboard::synth::run_from(&template, prefix, i * 1440, f, 0.01, &mut rng);
        if let tessera_dashboard::store::ingest::Ingested::Stored { series: s, .. } =
            ingest(&mut *c, &b).unwrap()
        {
            series.extend(s);
        }
    }
    let series: Vec<i64> = series.into_iter().collect();
    tessera_dashboard::regressions::update(&mut *c, &series, &Default::default()).unwrap();
}

fn count(pool: &Pool, sql: &str) -> i64 {
    pool.get().unwrap().query(sql, &[]).unwrap()[0]
        .i64(0)
        .unwrap()
}

#[test]
fn deleting_a_run_removes_everything_that_hangs_off_it() {
    let rt = runtime();
    let call = |app: &Router, r: Request<Body>| rt.block_on(send(app, r));
    for store in common::stores("deleting_a_run_removes_everything_that_hangs_off_it") {
        let pool = &store.pool;
        tessera_dashboard::import::import(pool, &common::fixtures(), &Default::default()).unwrap();
        history(pool, "h", 30, 20);
        let alert_run: String = pool
            .get()
            .unwrap()
            .query(
                "SELECT r.run_id FROM regressions g JOIN runs r ON r.id = g.run_pk_after LIMIT 1",
                &[],
            )
            .unwrap()[0]
            .string(0)
            .unwrap();
        let writer = add_token(pool, "ci", Scope::Write);
        let viewer = add_token(pool, "viewer", Scope::Read);
        let app = app(state(pool, None, AuthConfig::default()));
        let uri = format!("/api/runs/{alert_run}");

        assert_eq!(
            call(&app, req("DELETE", &uri, None, "")).status,
            StatusCode::UNAUTHORIZED
        );
        let r = call(&app, req("DELETE", &uri, Some(&viewer), ""));
        assert_eq!(r.status, StatusCode::FORBIDDEN, "{}", r.error());

        let runs_before = count(pool, "SELECT COUNT(*) FROM runs");
        let r = call(&app, req("DELETE", &uri, Some(&writer), ""));
        assert_eq!(r.status, StatusCode::OK, "{}: {}", store.name, r.body);
        let d = r.json();
        assert_eq!(d["run_id"], alert_run.as_str());
        assert!(d["results"].as_u64().unwrap() > 0 && d["points"].as_u64().unwrap() > 0);
        assert!(d["alerts"].as_u64().unwrap() >= 1, "{d}");
        assert_eq!(count(pool, "SELECT COUNT(*) FROM runs"), runs_before - 1);
        let gone = call(&app, req("GET", &uri, None, ""));
        assert_eq!(gone.status, StatusCode::NOT_FOUND);
        for orphan in [
            "SELECT COUNT(*) FROM points p WHERE NOT EXISTS (SELECT 1 FROM runs r WHERE r.id = p.run_pk)",
            "SELECT COUNT(*) FROM results p WHERE NOT EXISTS (SELECT 1 FROM runs r WHERE r.id = p.run_pk)",
            "SELECT COUNT(*) FROM images p WHERE NOT EXISTS (SELECT 1 FROM runs r WHERE r.id = p.run_pk)",
            "SELECT COUNT(*) FROM scenario_results p WHERE NOT EXISTS (SELECT 1 FROM runs r WHERE r.id = p.run_pk)",
            "SELECT COUNT(*) FROM regressions g WHERE NOT EXISTS (SELECT 1 FROM runs r WHERE r.id = g.run_pk_after) \
             OR NOT EXISTS (SELECT 1 FROM runs r WHERE r.id = g.run_pk_before)",
        ] {
            assert_eq!(count(pool, orphan), 0, "{}: {orphan}", store.name);
        }

        // Images: shared blobs stay while another run uses them; the last user takes them along.
        let real: Vec<String> = pool
            .get()
            .unwrap()
            .query(
                "SELECT run_id FROM runs WHERE run_id NOT LIKE 'h-%' ORDER BY run_id",
                &[],
            )
            .unwrap()
            .iter()
            .map(|r| r.string(0).unwrap())
            .collect();
        assert_eq!(real.len(), 2);
        let blobs = count(pool, "SELECT COUNT(*) FROM blobs");
        assert!(blobs > 0);
        for run in &real {
            let r = call(
                &app,
                req("DELETE", &format!("/api/runs/{run}"), Some(&writer), ""),
            );
            assert_eq!(r.status, StatusCode::OK, "{}", r.body);
            let unused = count(
                pool,
                "SELECT COUNT(*) FROM blobs b WHERE NOT EXISTS (SELECT 1 FROM images i WHERE i.digest = b.digest)",
            );
            assert_eq!(
                unused, 0,
                "{}: no blob is left without an image",
                store.name
            );
            assert_eq!(
                count(
                    pool,
                    "SELECT COUNT(*) FROM images i WHERE NOT EXISTS (SELECT 1 FROM blobs b WHERE b.digest = i.digest)"
                ),
                0
            );
        }
        assert_eq!(
            count(pool, "SELECT COUNT(*) FROM blobs"),
            count(pool, "SELECT COUNT(DISTINCT digest) FROM images")
        );

        let r = call(&app, req("DELETE", "/api/runs/nope", Some(&writer), ""));
        assert_eq!(r.status, StatusCode::NOT_FOUND);
        assert!(r.error().contains("nope"));
    }
}

#[test]
fn retention_keeps_recent_days_or_newest_runs_per_adapter() {
    for store in common::stores("retention_keeps_recent_days_or_newest_runs_per_adapter") {
        let pool = &store.pool;
        history(pool, "d", 10, 100); // days 0..9 of 2026-01
        let now = chrono::DateTime::parse_from_rfc3339("2026-01-11T00:00:00Z")
            .unwrap()
            .with_timezone(&chrono::Utc);
        let ids = |rule| -> Vec<String> {
            expired(&mut *pool.get().unwrap(), rule, now)
                .unwrap()
                .into_iter()
                .map(|e| e.run_id)
                .collect()
        };
        let d = |i: u64| format!("d-{:06}", i * 1440);
        assert!(
            ids(Retention::default()).is_empty(),
            "no rule keeps everything"
        );
        // Cut-off 2026-01-08T00:00: days 7, 8, 9 stay.
        let by_age = ids(Retention {
            keep_days: Some(3),
            keep_runs: None,
        });
        assert_eq!(by_age, (0..7).map(d).collect::<Vec<_>>());
        let by_count = ids(Retention {
            keep_days: None,
            keep_runs: Some(4),
        });
        assert_eq!(by_count, (0..6).map(d).collect::<Vec<_>>());
        // Either rule keeping a run is enough.
        let both = ids(Retention {
            keep_days: Some(3),
            keep_runs: Some(5),
        });
        assert_eq!(both, (0..5).map(d).collect::<Vec<_>>());

        for id in &by_count {
            delete_run(&mut *pool.get().unwrap(), id).unwrap();
        }
        assert_eq!(count(pool, "SELECT COUNT(*) FROM runs"), 4);
        assert!(ids(Retention {
            keep_days: None,
            keep_runs: Some(4)
        })
        .is_empty());
    }
}
