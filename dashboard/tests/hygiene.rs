//! Hygiene of every answer (issue 22, item 7): the viewport tag on every page, X-Frame-Options and
//! a CSP that forbids inline scripts on every answer, errors included, long filters refused with
//! 400, Markdown that escapes what a name or note could inject.

mod common;

use axum::body::Body;
use axum::http::{header, Request, StatusCode};
use http_body_util::BodyExt;
use tessera_dashboard::server::{app, AppState};
use tower::ServiceExt;

async fn get(app: &axum::Router, uri: &str) -> (StatusCode, axum::http::HeaderMap, String) {
    let res = app
        .clone()
        .oneshot(Request::get(uri).body(Body::empty()).unwrap())
        .await
        .unwrap();
    let (s, h) = (res.status(), res.headers().clone());
    let b = res.into_body().collect().await.unwrap().to_bytes();
    (s, h, String::from_utf8_lossy(&b).into_owned())
}

#[tokio::test]
async fn every_answer_has_the_security_headers_and_pages_the_viewport() {
    let store = common::sqlite();
    common::two_adapter_history(&store.pool, 0, 40);
    let app = app(AppState::new(store.pool.clone(), None));
    for uri in [
        "/",
        "/series",
        "/series/1",
        "/regressions",
        "/regressions/groups/1",
        "/runs/a-000030",
        "/compare/runs",
        "/pareto",
        "/api/runs",
        "/no/such/page",
    ] {
        let (s, h, body) = get(&app, uri).await;
        assert_eq!(h[header::X_FRAME_OPTIONS], "DENY", "{uri}");
        let csp = h[header::CONTENT_SECURITY_POLICY].to_str().unwrap();
        assert!(
            csp.contains("frame-ancestors 'none'") && csp.contains("script-src 'self'"),
            "{uri}: {csp}"
        );
        assert!(
            !csp.contains("script-src 'self' 'unsafe-inline'"),
            "{uri}: {csp}"
        );
        if s == StatusCode::OK
            && h[header::CONTENT_TYPE]
                .to_str()
                .unwrap()
                .starts_with("text/html")
        {
            assert!(
                body.contains(
                    "<meta name=viewport content=\"width=device-width, initial-scale=1\">"
                ),
                "{uri}"
            );
            // No inline script: every <script> either loads a file or holds JSON data.
            for tag in body
                .match_indices("<script")
                .map(|(i, _)| &body[i..(i + 60).min(body.len())])
            {
                assert!(
                    tag.starts_with("<script src=")
                        || tag.starts_with("<script type=application/json"),
                    "{uri}: inline script {tag}"
                );
            }
        }
    }
}

#[tokio::test]
async fn long_filters_are_refused_with_400() {
    let store = common::sqlite();
    let app = app(AppState::new(store.pool.clone(), None));
    let long = "x".repeat(50_000);
    for uri in [
        format!("/?q={long}"),
        format!("/series?scenario={long}"),
        format!("/regressions?suite={long}"),
        format!("/api/regressions/groups?measure={}", "m".repeat(300)),
    ] {
        let (s, h, body) = get(&app, &uri).await;
        assert_eq!(s, StatusCode::BAD_REQUEST, "{}: {body}", &uri[..20]);
        assert!(h[header::CONTENT_TYPE]
            .to_str()
            .unwrap()
            .starts_with("application/json"));
    }
}

#[test]
fn markdown_escapes_names_and_notes() {
    use tessera_dashboard::notify::markdown::text;
    assert_eq!(text("a|b"), "a\\|b");
    assert_eq!(text("[x](javascript:y)"), "\\[x\\]\\(javascript:y\\)");
    assert_eq!(text("# heading\n<img>"), "\\# heading \\<img\\>");
    assert_eq!(text("`code`"), "\\`code\\`");
}
