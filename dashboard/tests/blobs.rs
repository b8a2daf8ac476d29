//! Images sent apart from a run's records (`POST /api/blobs/missing`, `POST /api/blobs`, then
//! `POST /api/runs` with `image_digests`): a run whose images together exceed the request cap
//! is stored through batches that each fit it; a blob is sent once; a run that names a blob the
//! store lacks, a batch whose bytes do not match their digest and hostile questions are refused
//! with a clear 4xx and change nothing.

mod common;

use axum::body::Body;
use axum::http::{header, Request, StatusCode};
use axum::Router;
use http_body_util::BodyExt;
use tessera_dashboard::server::auth::Scope;
use tessera_dashboard::server::{app, AppState};
use tessera_dashboard::store::tokens;
use tessera_results::upload::{blob_digest, blob_record};
use tower::ServiceExt;

const CAP: usize = 150_000;

async fn send(
    app: &Router,
    method: &str,
    uri: &str,
    token: Option<&str>,
    body: Vec<u8>,
) -> (StatusCode, serde_json::Value) {
    let mut r = Request::builder().method(method).uri(uri);
    if let Some(t) = token {
        r = r.header(header::AUTHORIZATION, format!("Bearer {t}"));
    }
    r = r.header(header::CONTENT_TYPE, "application/json");
    let res = app
        .clone()
        .oneshot(r.body(Body::from(body)).unwrap())
        .await
        .unwrap();
    let status = res.status();
    let bytes = res.into_body().collect().await.unwrap().to_bytes();
    let json = serde_json::from_slice(&bytes).unwrap_or(serde_json::Value::Null);
    (status, json)
}

/// A PNG-signed payload of `n` bytes, distinct per `seed`.
fn png(n: usize, seed: u32) -> Vec<u8> {
    let mut b = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut x = seed.wrapping_mul(2_654_435_761).wrapping_add(1);
    while b.len() < n {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        b.push(x as u8);
    }
    b
}

fn count(state: &AppState, sql: &str) -> i64 {
    let mut c = state.pool.get().unwrap();
    c.query(sql, &[]).unwrap()[0].i64(0).unwrap()
}

#[tokio::test]
async fn a_run_larger_than_the_cap_uploads_through_blobs_once() {
    let store = common::sqlite();
    let mut state = AppState::new(store.pool.clone(), Some("tok".into()));
    state.max_upload_bytes = CAP;
    let app = app(state.clone());

    let mut bundle = common::template();
    let paths: Vec<String> = bundle.images.keys().cloned().collect();
    assert!(paths.len() >= 3, "the fixture run lists its images");
    for (i, p) in paths.iter().enumerate() {
        bundle.images.insert(p.clone(), png(100_000, i as u32));
    }
    let images = bundle.images.clone();

    // Inline, the images exceed the cap: refused, nothing stored.
    let inline = serde_json::to_vec(&bundle.to_upload()).unwrap();
    assert!(inline.len() > CAP);
    let (st, _) = send(&app, "POST", "/api/runs", Some("tok"), inline).await;
    assert_eq!(st, StatusCode::PAYLOAD_TOO_LARGE);
    assert_eq!(count(&state, "SELECT COUNT(*) FROM runs"), 0);

    // Which blobs are missing: all of them, each once, in the order asked.
    let digests: Vec<String> = paths.iter().map(|p| blob_digest(&images[p])).collect();
    let mut asked = digests.clone();
    asked.push(digests[0].clone());
    let q = serde_json::to_vec(&serde_json::json!({ "digests": asked })).unwrap();
    let (st, missing) = send(&app, "POST", "/api/blobs/missing", Some("tok"), q.clone()).await;
    assert_eq!(st, StatusCode::OK);
    assert_eq!(missing["missing"], serde_json::json!(digests));

    // One blob per batch fits the cap; the second batch of the same blob stores nothing new.
    for p in &paths {
        let (st, r) = send(
            &app,
            "POST",
            "/api/blobs",
            Some("tok"),
            blob_record(&images[p]),
        )
        .await;
        assert_eq!(st, StatusCode::CREATED, "{r}");
        assert_eq!(r, serde_json::json!({"stored": 1, "already": 0}));
    }
    let (_, r) = send(
        &app,
        "POST",
        "/api/blobs",
        Some("tok"),
        blob_record(&images[&paths[0]]),
    )
    .await;
    assert_eq!(r, serde_json::json!({"stored": 0, "already": 1}));
    let (_, missing) = send(&app, "POST", "/api/blobs/missing", Some("tok"), q).await;
    assert_eq!(missing["missing"], serde_json::json!([]));

    // The records name the images by digest, and the run is stored with its images.
    let mut body = bundle.to_upload();
    body.images.clear();
    body.image_digests = paths
        .iter()
        .map(|p| (p.clone(), blob_digest(&images[p])))
        .collect();
    let records = serde_json::to_vec(&body).unwrap();
    assert!(records.len() < CAP);
    let (st, r) = send(&app, "POST", "/api/runs", Some("tok"), records.clone()).await;
    assert_eq!(st, StatusCode::CREATED, "{r}");
    assert_eq!(
        count(&state, "SELECT COUNT(*) FROM images"),
        paths.len() as i64
    );
    let (st, _) = send(
        &app,
        "GET",
        &format!("/images/{}", digests[1]),
        None,
        Vec::new(),
    )
    .await;
    assert_eq!(st, StatusCode::OK);
    // The same upload again is idempotent, by digest.
    let (st, r) = send(&app, "POST", "/api/runs", Some("tok"), records).await;
    assert_eq!(
        (st, r["stored"].clone()),
        (StatusCode::OK, serde_json::json!(false))
    );
}

#[tokio::test]
async fn bad_blobs_and_dangling_digests_are_refused_and_change_nothing() {
    let store = common::sqlite();
    let state = AppState::new(store.pool.clone(), Some("tok".into()));
    let app = app(state.clone());
    let a = png(5_000, 1);

    // No token.
    let (st, _) = send(&app, "POST", "/api/blobs", None, blob_record(&a)).await;
    assert_eq!(st, StatusCode::UNAUTHORIZED);
    // Bytes that do not hash to their digest; the batch stores nothing, even its good record.
    let mut batch = blob_record(&png(300, 7));
    let mut bad = blob_record(&a);
    let n = bad.len();
    bad[n - 1] ^= 0xff;
    batch.extend(bad);
    let (st, r) = send(&app, "POST", "/api/blobs", Some("tok"), batch).await;
    assert_eq!(st, StatusCode::BAD_REQUEST);
    assert!(
        r["error"]
            .as_str()
            .unwrap()
            .contains("blob 1: its bytes do not hash"),
        "{r}"
    );
    // Not a PNG.
    let (st, r) = send(
        &app,
        "POST",
        "/api/blobs",
        Some("tok"),
        blob_record(b"GIF89a...."),
    )
    .await;
    assert_eq!(st, StatusCode::BAD_REQUEST);
    assert!(r["error"].as_str().unwrap().contains("not a PNG"), "{r}");
    assert_eq!(count(&state, "SELECT COUNT(*) FROM blobs"), 0);

    // Hostile questions.
    let q = serde_json::to_vec(&serde_json::json!({ "digests": ["../../etc/passwd"] })).unwrap();
    let (st, r) = send(&app, "POST", "/api/blobs/missing", Some("tok"), q).await;
    assert_eq!(st, StatusCode::BAD_REQUEST);
    assert!(
        r["error"].as_str().unwrap().contains("64 lowercase hex"),
        "{r}"
    );
    let many: Vec<String> = (0..100_001).map(|i| format!("{i:064x}")).collect();
    let q = serde_json::to_vec(&serde_json::json!({ "digests": many })).unwrap();
    let (st, _) = send(&app, "POST", "/api/blobs/missing", Some("tok"), q).await;
    assert_eq!(st, StatusCode::BAD_REQUEST);

    // A run naming a blob the store lacks: 422, naming the image and what to do.
    let bundle = common::template();
    let mut body = bundle.to_upload();
    let path = body.images.keys().next().unwrap().clone();
    body.images.remove(&path);
    body.image_digests.insert(path.clone(), blob_digest(&a));
    let (st, r) = send(
        &app,
        "POST",
        "/api/runs",
        Some("tok"),
        serde_json::to_vec(&body).unwrap(),
    )
    .await;
    assert_eq!(st, StatusCode::UNPROCESSABLE_ENTITY, "{r}");
    let msg = r["error"].as_str().unwrap();
    assert!(
        msg.contains(&path) && msg.contains("POST /api/blobs"),
        "{msg}"
    );
    assert_eq!(count(&state, "SELECT COUNT(*) FROM runs"), 0);
    // A digest of the wrong shape or for a path no result lists: 4xx before the store.
    body.image_digests.insert(path.clone(), "ABC".into());
    let (st, _) = send(
        &app,
        "POST",
        "/api/runs",
        Some("tok"),
        serde_json::to_vec(&body).unwrap(),
    )
    .await;
    assert!(st.is_client_error());
    body.image_digests.clear();
    body.image_digests
        .insert("images/elsewhere.png".into(), blob_digest(&a));
    let (st, r) = send(
        &app,
        "POST",
        "/api/runs",
        Some("tok"),
        serde_json::to_vec(&body).unwrap(),
    )
    .await;
    assert!(st.is_client_error(), "{r}");
    assert_eq!(count(&state, "SELECT COUNT(*) FROM runs"), 0);
}

#[tokio::test]
async fn a_runner_token_sends_blobs_and_a_read_token_does_not() {
    let store = common::sqlite();
    let conn = &mut *store.pool.get().unwrap();
    let runner = tokens::add(conn, "box-1", Scope::Runner).unwrap();
    let reader = tokens::add(conn, "viewer", Scope::Read).unwrap();
    let state = AppState::new(store.pool.clone(), None);
    let app = app(state.clone());
    let a = png(5_000, 3);
    let q = serde_json::to_vec(&serde_json::json!({ "digests": [blob_digest(&a)] })).unwrap();

    // A runner uploads the run of the job it holds with its images: it asks and sends blobs.
    let (st, missing) = send(&app, "POST", "/api/blobs/missing", Some(&runner), q.clone()).await;
    assert_eq!(st, StatusCode::OK);
    assert_eq!(missing["missing"], serde_json::json!([blob_digest(&a)]));
    let (st, r) = send(&app, "POST", "/api/blobs", Some(&runner), blob_record(&a)).await;
    assert_eq!(st, StatusCode::CREATED, "{r}");
    assert_eq!(count(&state, "SELECT COUNT(*) FROM blobs"), 1);

    // A read token is refused on both, and stores nothing.
    let b = png(5_000, 4);
    let (st, _) = send(&app, "POST", "/api/blobs/missing", Some(&reader), q).await;
    assert!(
        st == StatusCode::FORBIDDEN || st == StatusCode::UNAUTHORIZED,
        "{st}"
    );
    let (st, _) = send(&app, "POST", "/api/blobs", Some(&reader), blob_record(&b)).await;
    assert!(
        st == StatusCode::FORBIDDEN || st == StatusCode::UNAUTHORIZED,
        "{st}"
    );
    assert_eq!(count(&state, "SELECT COUNT(*) FROM blobs"), 1);
}
