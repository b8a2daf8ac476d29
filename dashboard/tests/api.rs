//! API tests with `oneshot` on the router: every page and JSON endpoint, status codes and JSON
//! error bodies, uploads (auth, idempotence, bad and oversized input, nothing partial stored),
//! triage, and image routes that cannot leave the store.

mod common;

use axum::body::Body;
use axum::http::{header, Request, StatusCode};
use axum::Router;
use http_body_util::BodyExt;
use tessera_dashboard::detect::Params;
use tessera_dashboard::import::import;
use tessera_dashboard::server::{app, AppState};
use tower::ServiceExt;

const TOKEN: &str = "test-token";

fn setup(imported: bool) -> (common::TestStore, Router) {
    let store = common::sqlite();
    if imported {
        import(&store.pool, &common::fixtures(), &Params::default()).unwrap();
    }
    let mut state = AppState::new(store.pool.clone(), Some(TOKEN.into()));
    state.max_upload_bytes = 1 << 20;
    let router = app(state);
    (store, router)
}

async fn send(app: &Router, req: Request<Body>) -> (StatusCode, String, String) {
    let res = app.clone().oneshot(req).await.unwrap();
    let status = res.status();
    let ctype = res
        .headers()
        .get(header::CONTENT_TYPE)
        .map(|v| v.to_str().unwrap().to_string())
        .unwrap_or_default();
    let body = res.into_body().collect().await.unwrap().to_bytes();
    (status, ctype, String::from_utf8_lossy(&body).into_owned())
}

async fn get(app: &Router, uri: &str) -> (StatusCode, String, String) {
    send(app, Request::get(uri).body(Body::empty()).unwrap()).await
}

fn upload(body: String, token: Option<&str>) -> Request<Body> {
    let mut r = Request::post("/api/runs").header(header::CONTENT_TYPE, "application/json");
    if let Some(t) = token {
        r = r.header(header::AUTHORIZATION, format!("Bearer {t}"));
    }
    r.body(Body::from(body)).unwrap()
}

fn json(body: &str) -> serde_json::Value {
    serde_json::from_str(body).unwrap_or_else(|e| panic!("not JSON ({e}): {body}"))
}

fn template_body() -> serde_json::Value {
    serde_json::to_value(common::template().to_upload()).unwrap()
}

#[tokio::test]
async fn every_page_renders_with_imported_runs() {
    let (_store, app) = setup(true);
    let (s, ctype, body) = get(&app, "/").await;
    assert_eq!(s, StatusCode::OK);
    assert!(ctype.starts_with("text/html"));
    assert!(body.contains("llvmpipe") && body.contains("Mesa"), "{body}");
    let runs = json(&get(&app, "/api/runs").await.2);
    let run_id = runs[0]["run_id"].as_str().unwrap().to_string();
    assert_eq!(runs.as_array().unwrap().len(), 2);

    let (s, _, body) = get(&app, &format!("/runs/{run_id}")).await;
    assert_eq!(s, StatusCode::OK);
    assert!(
        body.contains("upscale[scale=0.5]") && body.contains("class='bar'"),
        "stacked bars drawn"
    );
    let detail = json(&get(&app, &format!("/api/runs/{run_id}")).await.2);
    assert_eq!(
        detail["scenarios"][0]["results"].as_array().unwrap().len(),
        3
    );

    let series = json(
        &get(&app, "/api/series?scenario=tiny&measure=gpu_ms.median")
            .await
            .2,
    );
    // Filters match any part of the name: the frame time of 3 variants and their passes' times.
    let list = series.as_array().unwrap();
    assert!(list
        .iter()
        .all(|s| s["measure"].as_str().unwrap().contains("gpu_ms.median")));
    assert_eq!(
        list.iter()
            .filter(|s| s["measure"] == "gpu_ms.median")
            .count(),
        3
    );
    let id = series[0]["id"].as_i64().unwrap();
    let (s, _, body) = get(&app, &format!("/series/{id}")).await;
    assert_eq!(s, StatusCode::OK);
    assert_eq!(
        body.matches("class='point'").count(),
        2,
        "two runs, two points"
    );
    assert_eq!(
        json(&get(&app, &format!("/api/series/{id}")).await.2)["points"]
            .as_array()
            .unwrap()
            .len(),
        2
    );
    assert_eq!(get(&app, "/series").await.0, StatusCode::OK);

    for uri in [
        "/regressions",
        "/api/regressions",
        "/compare",
        "/api/compare",
        "/pareto",
        "/api/pareto?metric=psnr",
    ] {
        assert_eq!(get(&app, uri).await.0, StatusCode::OK, "{uri}");
    }
    let pareto = json(&get(&app, "/api/pareto?scenario=tiny&metric=flip").await.2);
    assert!(pareto["points"].as_array().unwrap().len() >= 2, "{pareto}");
    assert!(pareto["base"].is_string(), "the older run is the base");
    let (_, _, body) = get(&app, "/pareto?scenario=tiny").await;
    assert!(body.contains("class='front'"));

    let images = json(
        &get(&app, &format!("/api/runs/{run_id}/images/tiny"))
            .await
            .2,
    );
    let digest = images[0]["digest"].as_str().unwrap();
    let (s, ctype, _) = get(&app, &format!("/images/{digest}")).await;
    assert_eq!((s, ctype.as_str()), (StatusCode::OK, "image/png"));
    let (s, _, body) = get(
        &app,
        &format!("/runs/{run_id}/images/tiny/upscale%5Bscale%3D0.5%5D"),
    )
    .await;
    assert_eq!(s, StatusCode::OK, "{body}");
    // Reference and variant without JavaScript, with the viewer's controls.
    assert!(
        body.contains("data-kind=\"reference\" src=\"/images/")
            && body.contains("data-kind=\"output\" src=\"/images/")
            && body.contains("id=zoom type=range min=1 max=32")
            && body.contains("id=wipe"),
        "{body}"
    );
}

#[tokio::test]
async fn missing_things_are_json_404s() {
    let (_store, app) = setup(true);
    for uri in [
        "/runs/nope",
        "/api/runs/nope",
        "/series/999999",
        "/api/series/999999",
        "/images/0000000000000000000000000000000000000000000000000000000000000000",
        "/images/..%2F..%2Fetc%2Fpasswd",
        "/runs/x/images/..%2F..%2Fetc/passwd/y",
        "/no/such/page",
    ] {
        let (s, ctype, body) = get(&app, uri).await;
        assert_eq!(s, StatusCode::NOT_FOUND, "{uri}: {body}");
        assert_eq!(ctype, "application/json", "{uri}");
        assert!(json(&body)["error"].is_string());
    }
    assert_eq!(
        get(&app, "/api/regressions?state=bogus").await.0,
        StatusCode::BAD_REQUEST
    );
    assert_eq!(
        get(&app, "/api/series/abc").await.0,
        StatusCode::BAD_REQUEST
    );
}

#[tokio::test]
async fn upload_needs_the_token_and_is_idempotent() {
    let (store, app) = setup(false);
    let body = template_body().to_string();

    let (s, _, err) = send(&app, upload(body.clone(), None)).await;
    assert_eq!(s, StatusCode::UNAUTHORIZED);
    assert!(json(&err)["error"].as_str().unwrap().contains("Bearer"));
    assert_eq!(
        send(&app, upload(body.clone(), Some("wrong"))).await.0,
        StatusCode::UNAUTHORIZED
    );

    let (s, _, ok) = send(&app, upload(body.clone(), Some(TOKEN))).await;
    assert_eq!(s, StatusCode::CREATED, "{ok}");
    assert_eq!(json(&ok)["stored"], true);
    assert_eq!(json(&ok)["results"], 3);
    let (s, _, again) = send(&app, upload(body, Some(TOKEN))).await;
    assert_eq!(s, StatusCode::OK);
    assert_eq!(json(&again)["stored"], false);
    let runs = json(&get(&app, "/api/runs").await.2);
    assert_eq!(runs.as_array().unwrap().len(), 1);
    let detail = json(
        &get(
            &app,
            &format!("/api/runs/{}", runs[0]["run_id"].as_str().unwrap()),
        )
        .await
        .2,
    );
    assert_eq!(
        detail["images"].as_array().unwrap().len(),
        4,
        "uploaded images are stored"
    );
    drop(store);
}

/// A run started outside a git checkout records no commit; it is stored, but never the previous
/// run of its suite, so the one sending it is told: the upload's answer carries a warning (which
/// `tessera upload` prints) and `import` prints it. A run with a commit gets none.
#[tokio::test]
async fn a_run_without_a_commit_is_stored_with_a_warning_on_upload_and_import() {
    let (store, app) = setup(false);
    let mut body = template_body();
    let (s, _, ok) = send(&app, upload(body.to_string(), Some(TOKEN))).await;
    assert_eq!(s, StatusCode::CREATED, "{ok}");
    assert!(json(&ok).get("warnings").is_none(), "{ok}");
    body["run"]["commit"] = serde_json::Value::Null;
    body["run"]["run_id"] = "no-commit".into();
    for sc in body["scenarios"].as_array_mut().unwrap() {
        sc["run_id"] = "no-commit".into();
    }
    let (s, _, ok) = send(&app, upload(body.to_string(), Some(TOKEN))).await;
    assert_eq!(s, StatusCode::CREATED, "{ok}");
    let warnings = json(&ok)["warnings"].clone();
    assert_eq!(warnings.as_array().map(Vec::len), Some(1), "{ok}");
    let w = warnings[0].as_str().unwrap();
    assert!(
        w.starts_with("run no-commit records no commit") && w.contains("never the previous run"),
        "{w}"
    );
    // Sent again: already stored, and still told.
    let (s, _, again) = send(&app, upload(body.to_string(), Some(TOKEN))).await;
    assert_eq!(s, StatusCode::OK);
    assert_eq!(json(&again)["warnings"], warnings);
    drop(store);

    // `import` of a folder holding one run with a commit and one without: one warning, naming
    // the folder without.
    let dir = tempfile::tempdir().unwrap();
    let fixture = std::fs::read_dir(common::fixtures())
        .unwrap()
        .map(|e| e.unwrap().path())
        .min()
        .unwrap();
    for (name, commit) in [("with-commit", true), ("no-commit", false)] {
        let run = dir.path().join("runs").join(name);
        std::fs::create_dir_all(run.join("scenarios")).unwrap();
        let mut record = json(&std::fs::read_to_string(fixture.join("run.json")).unwrap());
        record["run_id"] = name.into();
        if !commit {
            record["commit"] = serde_json::Value::Null;
        }
        std::fs::write(run.join("run.json"), record.to_string()).unwrap();
        for e in std::fs::read_dir(fixture.join("scenarios")).unwrap() {
            let e = e.unwrap();
            let mut sc = json(&std::fs::read_to_string(e.path()).unwrap());
            sc["run_id"] = name.into();
            std::fs::write(run.join("scenarios").join(e.file_name()), sc.to_string()).unwrap();
        }
    }
    let db = dir.path().join("store.sqlite");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_tessera-dashboard"))
        .arg("import")
        .arg(dir.path().join("runs"))
        .arg("--db")
        .arg(&db)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        String::from_utf8_lossy(&out.stdout).contains("imported 2 runs"),
        "{out:?}"
    );
    let warnings: Vec<&str> = err.lines().filter(|l| l.starts_with("warning:")).collect();
    assert_eq!(warnings.len(), 1, "{err}");
    assert!(
        warnings[0].contains("runs/no-commit: run no-commit records no commit"),
        "{err}"
    );
}

#[tokio::test]
async fn writes_are_refused_without_a_configured_token() {
    let store = common::sqlite();
    let app = app(AppState::new(store.pool.clone(), None));
    let (s, _, body) = send(&app, upload(template_body().to_string(), Some("anything"))).await;
    assert_eq!(s, StatusCode::FORBIDDEN);
    assert!(json(&body)["error"]
        .as_str()
        .unwrap()
        .contains("TESSERA_DASHBOARD_TOKEN"));
}

#[tokio::test]
async fn bad_uploads_get_4xx_and_store_nothing() {
    let (store, app) = setup(false);
    let mut cases: Vec<(&str, String, StatusCode, &str)> = vec![
        (
            "not json",
            "{".into(),
            StatusCode::BAD_REQUEST,
            "not an upload bundle",
        ),
        (
            "empty object",
            "{}".into(),
            StatusCode::BAD_REQUEST,
            "not an upload bundle",
        ),
    ];
    let mut future = template_body();
    future["run"]["schema_version"] = 4.into();
    cases.push((
        "future schema",
        future.to_string(),
        StatusCode::UNPROCESSABLE_ENTITY,
        "reads versions 1 to 3",
    ));
    let mut bad_id = template_body();
    bad_id["run"]["run_id"] = "../../x".into();
    cases.push((
        "bad run id",
        bad_id.to_string(),
        StatusCode::UNPROCESSABLE_ENTITY,
        "run_id",
    ));
    let mut mismatched = template_body();
    mismatched["scenarios"][0]["run_id"] = "other".into();
    cases.push((
        "mismatched run id",
        mismatched.to_string(),
        StatusCode::UNPROCESSABLE_ENTITY,
        "has run_id",
    ));
    let mut traversal = template_body();
    traversal["images"]["../../etc/passwd"] = "iVBORw0KGgo=".into();
    cases.push((
        "image path",
        traversal.to_string(),
        StatusCode::UNPROCESSABLE_ENTITY,
        "relative path",
    ));
    let mut not_png = template_body();
    let first = not_png["images"]
        .as_object()
        .unwrap()
        .keys()
        .next()
        .unwrap()
        .clone();
    not_png["images"][&first] = "aGVsbG8=".into();
    cases.push((
        "not a png",
        not_png.to_string(),
        StatusCode::UNPROCESSABLE_ENTITY,
        "not a PNG",
    ));
    let mut bad_b64 = template_body();
    bad_b64["images"][&first] = "%%%".into();
    cases.push((
        "bad base64",
        bad_b64.to_string(),
        StatusCode::UNPROCESSABLE_ENTITY,
        "base64",
    ));
    let mut missing_field = template_body();
    missing_field["scenarios"][0]
        .as_object_mut()
        .unwrap()
        .remove("results");
    cases.push((
        "missing field",
        missing_field.to_string(),
        StatusCode::UNPROCESSABLE_ENTITY,
        "results",
    ));
    let mut huge = template_body();
    huge["images"][&first] = "A".repeat(2 << 20).into();
    cases.push((
        "oversized",
        huge.to_string(),
        StatusCode::PAYLOAD_TOO_LARGE,
        "larger than",
    ));

    for (what, body, status, text) in cases {
        let (s, ctype, err) = send(&app, upload(body, Some(TOKEN))).await;
        assert_eq!(s, status, "{what}: {err}");
        assert_eq!(ctype, "application/json", "{what}");
        let msg = json(&err)["error"].as_str().unwrap().to_string();
        assert!(msg.contains(text), "{what}: {msg}");
    }
    let mut c = store.pool.get().unwrap();
    for table in ["runs", "results", "blobs", "points"] {
        let n = c
            .query(&format!("SELECT COUNT(*) FROM {table}"), &[])
            .unwrap()[0]
            .i64(0)
            .unwrap();
        assert_eq!(n, 0, "{table}");
    }
}

#[tokio::test]
async fn triage_is_stored_and_needs_the_token() {
    let (store, app) = setup(false);
    // 40 generated runs with a 10% step at run 30 give regressions to triage.
    let template = common::template();
    let mut rng = tessera_dashboard::detect::Rng::new(3);
    for i in 0..40 {
        let b = tessera_dashboard::synth::run_from(
            &template,
            "t",
            i,
            if i < 30 { 1.0 } else { 1.1 },
            0.01,
            &mut rng,
        );
        let body = serde_json::to_string(&b.to_upload()).unwrap();
        assert_eq!(
            send(&app, upload(body, Some(TOKEN))).await.0,
            StatusCode::CREATED
        );
    }
    let regs = json(&get(&app, "/api/regressions?state=new").await.2);
    let id = regs[0]["id"].as_i64().unwrap();
    let (_, _, page) = get(&app, "/regressions").await;
    assert!(page.contains(&format!("id=r{id}")) && page.contains("worse"));
    // Where and how sure, apart: the location probability and the change's interval are shown;
    // the significance of *a* change is no column of its own (it reads ~100% everywhere).
    let p = regs[0]["location_probability"].as_f64().unwrap();
    assert!(
        page.contains(&format!("{:.0}% at this run", p * 100.0)) && page.contains("95%: "),
        "{page}"
    );
    assert!(page.contains("<th class=n>located</th>") && !page.contains(">confidence<"));

    let triage = |token: Option<&str>, body: &str| {
        let mut r = Request::post(format!("/api/regressions/{id}"))
            .header(header::CONTENT_TYPE, "application/json");
        if let Some(t) = token {
            r = r.header(header::AUTHORIZATION, format!("Bearer {t}"));
        }
        r.body(Body::from(body.to_string())).unwrap()
    };
    let ack = r#"{"state":"acknowledged","note":"known: new shadow pass"}"#;
    assert_eq!(
        send(&app, triage(None, ack)).await.0,
        StatusCode::UNAUTHORIZED
    );
    assert_eq!(
        send(&app, triage(Some(TOKEN), r#"{"state":"bogus"}"#))
            .await
            .0,
        StatusCode::UNPROCESSABLE_ENTITY
    );
    assert_eq!(
        send(&app, triage(Some(TOKEN), "nope")).await.0,
        StatusCode::BAD_REQUEST
    );
    assert_eq!(send(&app, triage(Some(TOKEN), ack)).await.0, StatusCode::OK);
    let acked = json(&get(&app, "/api/regressions?state=acknowledged").await.2);
    assert_eq!(acked[0]["note"], "known: new shadow pass");

    // The page's form, with the token as a field.
    let form = |token: &str| {
        Request::post(format!("/regressions/{id}"))
            .header(header::CONTENT_TYPE, "application/x-www-form-urlencoded")
            .body(Body::from(format!(
                "state=fixed&note=reverted&token={token}"
            )))
            .unwrap()
    };
    assert_eq!(send(&app, form("wrong")).await.0, StatusCode::UNAUTHORIZED);
    assert_eq!(send(&app, form(TOKEN)).await.0, StatusCode::SEE_OTHER);
    assert_eq!(
        json(&get(&app, "/api/regressions?state=fixed").await.2)[0]["note"],
        "reverted"
    );
    let missing = Request::post("/api/regressions/999999")
        .header(header::AUTHORIZATION, format!("Bearer {TOKEN}"))
        .header(header::CONTENT_TYPE, "application/json")
        .body(Body::from(ack))
        .unwrap();
    assert_eq!(send(&app, missing).await.0, StatusCode::NOT_FOUND);
    drop(store);
}

#[test]
fn regression_summary_text() {
    use tessera_dashboard::store::alerts::{DetectionStatus, TriageState};
    use tessera_dashboard::store::read::{RegressionRow, SeriesKey};
    let r = RegressionRow {
        id: 1,
        group_id: 1,
        series: SeriesKey {
            id: 1,
            scenario: "tiny".into(),
            variant: "upscale[scale=0.5]".into(),
            adapter_id: 1,
            adapter: "llvmpipe (LLVM 15.0.6, 256 bits)".into(),
            measure: "gpu_ms.median".into(),
            higher_is_better: false,
        },
        suite: "smoke".into(),
        run_before: "a".into(),
        commit_before: None,
        run_after: "b".into(),
        commit_after: None,
        started_at: String::new(),
        value_before: 3.476,
        value_after: 3.8236,
        relative_change: 0.1,
        change_low: Some(0.081),
        change_high: Some(0.119),
        is_regression: true,
        via_baseline: false,
        moved_with: None,
        moved_with_change: None,
        confidence: 0.9995,
        location_probability: Some(0.62),
        first_candidate: Some("a2".into()),
        last_candidate: Some("b".into()),
        status: DetectionStatus::Confirmed,
        state: TriageState::New,
        note: String::new(),
        bug_url: String::new(),
        updated_by: String::new(),
        detected_at: String::new(),
        updated_at: String::new(),
        run_pk_before: 1,
        run_pk_after: 2,
    };
    // Where the change is and how sure, apart from whether there is one.
    assert_eq!(
        tessera_dashboard::server::regressions::summary(&r),
        "tiny · upscale[scale=0.5] · llvmpipe (LLVM 15.0.6, 256 bits) · gpu_ms.median: 3.476 → 3.824 (+10.0%, 95% interval +8.1% to +11.9%, worse); at run b with 62% probability, runs a2 to b"
    );
}

#[tokio::test]
async fn alert_groups_api_triage_markdown_and_feed() {
    let (store, app) = setup(false);
    common::two_adapter_history(&store.pool, 0, 40);
    let key = common::range(29);

    let groups = json(&get(&app, "/api/regressions/groups").await.2);
    let keys: Vec<&str> = groups
        .as_array()
        .unwrap()
        .iter()
        .map(|g| g["key"].as_str().unwrap())
        .collect();
    assert_eq!(keys, [key.clone(), common::range(14)]);
    let n = groups[0]["series_count"].as_u64().unwrap();
    let id = groups[0]["id"].as_i64().unwrap();
    // A commit-range key answers a redirect to the group's id, which it keeps for life.
    for (from, to) in [
        (
            format!("/api/regressions/groups/{key}"),
            format!("/api/regressions/groups/{id}"),
        ),
        (
            format!("/regressions/groups/{key}"),
            format!("/regressions/groups/{id}"),
        ),
        (
            format!("/regressions/groups/{key}.md"),
            format!("/regressions/groups/{id}.md"),
        ),
    ] {
        let res = app
            .clone()
            .oneshot(Request::get(&from).body(Body::empty()).unwrap())
            .await
            .unwrap();
        assert_eq!(res.status(), StatusCode::PERMANENT_REDIRECT, "{from}");
        assert_eq!(res.headers()[header::LOCATION], to.as_str(), "{from}");
    }
    let sized = json(
        &get(&app, "/api/regressions/groups?sort=size&limit=1")
            .await
            .2,
    );
    assert_eq!(sized.as_array().unwrap().len(), 1);
    assert_eq!(sized[0]["key"], common::range(14));
    for bad in [
        "state=closed",
        "direction=up",
        "status=gone",
        "sort=name",
        "adapter=x",
    ] {
        let (s, ctype, body) = get(&app, &format!("/api/regressions/groups?{bad}")).await;
        assert_eq!(
            (s, ctype.as_str()),
            (StatusCode::BAD_REQUEST, "application/json"),
            "{bad}: {body}"
        );
        assert!(
            json(&body)["error"].as_str().unwrap().contains("not"),
            "{body}"
        );
    }
    // Empty form values mean "all".
    let all = json(
        &get(&app, "/api/regressions/groups?adapter=&state=&sort=")
            .await
            .2,
    );
    assert_eq!(all.as_array().unwrap().len(), 2);

    let triage = |token: Option<&str>, body: &str| {
        let mut r = Request::post(format!("/api/regressions/groups/{key}"))
            .header(header::CONTENT_TYPE, "application/json");
        if let Some(t) = token {
            r = r.header(header::AUTHORIZATION, format!("Bearer {t}"));
        }
        r.body(Body::from(body.to_string())).unwrap()
    };
    let ack = r#"{"state":"fixed","note":"reverted in c0ffee","bug_url":"https://bugs.example/7"}"#;
    assert_eq!(
        send(&app, triage(None, ack)).await.0,
        StatusCode::UNAUTHORIZED
    );
    assert_eq!(
        send(
            &app,
            triage(Some(TOKEN), r#"{"state":"fixed","bug_url":"javascript:x"}"#)
        )
        .await
        .0,
        StatusCode::UNPROCESSABLE_ENTITY
    );
    let (s, _, body) = send(&app, triage(Some(TOKEN), ack)).await;
    assert_eq!(s, StatusCode::OK, "{body}");
    assert_eq!(json(&body)["updated"].as_u64(), Some(n));
    let one = json(&get(&app, &format!("/api/regressions/groups/{id}")).await.2);
    assert_eq!(
        (
            &one["state"],
            &one["note"],
            &one["bug_url"],
            &one["updated_by"]
        ),
        (
            &serde_json::json!("fixed"),
            &serde_json::json!("reverted in c0ffee"),
            &serde_json::json!("https://bugs.example/7"),
            &serde_json::json!("legacy")
        )
    );
    // The form without JavaScript: token as a field, back to the group on the list.
    let form = Request::post(format!("/regressions/groups/{key}"))
        .header(header::CONTENT_TYPE, "application/x-www-form-urlencoded")
        .body(Body::from(format!(
            "state=ignored&note=&bug_url=&token={TOKEN}"
        )))
        .unwrap();
    assert_eq!(send(&app, form).await.0, StatusCode::SEE_OTHER);
    let ignored = json(&get(&app, "/api/regressions/groups?state=ignored").await.2);
    assert_eq!(ignored[0]["key"], key);

    // Markdown at its own URL, absolute links from the Host header.
    let md = send(
        &app,
        Request::get(format!("/regressions/groups/{id}.md"))
            .header(header::HOST, "dash.example:8080")
            .body(Body::empty())
            .unwrap(),
    )
    .await;
    assert_eq!(
        (md.0, md.1.as_str()),
        (StatusCode::OK, "text/markdown; charset=utf-8")
    );
    assert!(md.2.contains(&format!(
        "(http://dash.example:8080/regressions/groups/{id})"
    )));
    let (s, ctype, page) = get(&app, &format!("/regressions/groups/{id}")).await;
    assert_eq!(
        (s, ctype.as_str()),
        (StatusCode::OK, "text/html; charset=utf-8")
    );
    assert!(page.contains("<svg") && page.contains("<option selected>ignored</option>"));
    for missing in [
        format!("/regressions/groups/{}", common::range(3)),
        format!("/regressions/groups/{}.md", common::range(3)),
        "/regressions/groups/..%2F..%2Fetc".to_string(),
        "/api/regressions/groups/nope".to_string(),
        "/regressions/groups/999999".to_string(),
    ] {
        let (s, ctype, _) = get(&app, &missing).await;
        assert_eq!(
            (s, ctype.as_str()),
            (StatusCode::NOT_FOUND, "application/json"),
            "{missing}"
        );
    }

    // The feed: confirmed groups, filterable by state.
    let (s, ctype, feed) = get(&app, "/regressions/feed.atom").await;
    assert_eq!(
        (s, ctype.as_str()),
        (StatusCode::OK, "application/atom+xml; charset=utf-8")
    );
    assert_eq!(feed.matches("<entry>").count(), 2);
    let (_, _, only_new) = get(&app, "/regressions/feed.atom?state=new").await;
    assert_eq!(only_new.matches("<entry>").count(), 1);
    assert_eq!(
        get(&app, "/regressions/feed.atom?state=closed").await.0,
        StatusCode::BAD_REQUEST
    );
}

/// The browsing queries (filters, paging, suites, previous run, compare, exports, gzip) on every
/// store: SQLite, and PostgreSQL when `TESSERA_TEST_POSTGRES_URL` is set. The synchronous
/// PostgreSQL client is set up outside the async runtime.
#[test]
fn browsing_filters_compare_and_exports_on_every_store() {
    let viewer =
        std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/viewer-runs");
    for store in common::stores("browsing_filters_compare_and_exports_on_every_store") {
        import(&store.pool, &common::fixtures(), &Params::default()).unwrap();
        import(&store.pool, &viewer, &Params::default()).unwrap();
        let app = app(AppState::new(store.pool.clone(), None));
        tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .enable_all()
            .build()
            .unwrap()
            .block_on(browse_checks(app, store.name));
    }
}

async fn browse_checks(app: Router, name: &str) {
    {
        let ok = |r: &(StatusCode, String, String), what: &str| {
            assert_eq!(r.0, StatusCode::OK, "{name} {what}: {}", r.2);
        };
        // Runs list: suite and branch recorded, filters, paging with the total in a header.
        let all = json(&get(&app, "/api/runs").await.2);
        assert_eq!(all.as_array().unwrap().len(), 4, "{name}");
        let smoke = json(
            &get(
                &app,
                "/api/runs?suite=smoke-viewer&branch=main&status=complete&q=AB7188",
            )
            .await
            .2,
        );
        assert_eq!(smoke.as_array().unwrap().len(), 2, "{name}: {smoke}");
        assert_eq!(smoke[0]["suite"], "smoke-viewer");
        let (a, b) = (
            smoke[1]["run_id"].as_str().unwrap().to_string(),
            smoke[0]["run_id"].as_str().unwrap().to_string(),
        );
        let res = app
            .clone()
            .oneshot(
                Request::get("/api/runs?offset=1&limit=2")
                    .body(Body::empty())
                    .unwrap(),
            )
            .await
            .unwrap();
        assert_eq!(res.headers()["x-total-count"], "4", "{name}");
        let r = get(&app, "/?suite=fx&alerts=1&q=34ab").await;
        ok(&r, "runs page with filters");
        assert!(
            r.2.contains("0–0 of 0"),
            "{name}: no run of fx has alerts: {}",
            r.2
        );
        assert_eq!(get(&app, "/?status=bogus").await.0, StatusCode::BAD_REQUEST);
        // Series finder: substrings, ignoring case, and an adapter.
        let found = json(
            &get(
                &app,
                "/api/series?scenario=BAS&variant=board%5B&measure=gpu_ms.med&adapter=1",
            )
            .await
            .2,
        );
        let found = found.as_array().unwrap();
        assert!(!found.is_empty(), "{name}");
        assert!(found
            .iter()
            .all(|s| s["variant"].as_str().unwrap().contains("board[")));
        let id = found[0]["id"].as_i64().unwrap();
        let series = json(&get(&app, &format!("/api/series/{id}")).await.2);
        assert_eq!(series["points"].as_array().unwrap().len(), 2, "{name}");
        assert!(
            series["points"][0]["p95"].as_f64().unwrap()
                >= series["points"][0]["value"].as_f64().unwrap()
        );
        let csv = get(&app, &format!("/api/series/{id}?format=csv")).await;
        assert!(
            csv.1.starts_with("text/csv") && csv.2.starts_with("run_id,commit,started_at"),
            "{name}"
        );
        ok(
            &get(
                &app,
                &format!("/series/{id}?with={}", found.last().unwrap()["id"]),
            )
            .await,
            "overlay",
        );
        // The run page names the previous run of its suite; the CSV has results.csv's columns.
        let run = get(&app, &format!("/runs/{b}")).await;
        ok(&run, "run page");
        assert!(
            run.2.contains(&format!("/compare/runs?a={a}&amp;b={b}"))
                || run.2.contains(&format!("/compare/runs?a={a}&b={b}")),
            "{name}: {}",
            run.2
        );
        let csv = get(&app, &format!("/api/runs/{b}?format=csv")).await;
        assert!(csv.2.starts_with(
            "run_id,scenario,variant,technique,adapter,backend,status,measure,value,unit"
        ));
        assert!(
            csv.2
                .contains("checkerboard[sampling=msaa2x],checkerboard,\"llvmpipe (LLVM 15.0.6, 256 bits)\",vulkan,skipped,status,,"),
            "the skipped variant has its status row"
        );
        // Compare: by run ids, by commit with suite and adapter, as Markdown and CSV.
        let c = json(&get(&app, &format!("/api/compare/runs?a={a}&b={b}")).await.2);
        assert_eq!(c["by_speedup"], false);
        assert!(c["scenarios"].as_array().unwrap().len() == 2, "{name}");
        let by_commit = get(
            &app,
            "/api/compare/runs?a=ab7188d&b=34ab2b4&suite=smoke-viewer&adapter=1",
        )
        .await;
        assert_eq!(
            by_commit.0,
            StatusCode::NOT_FOUND,
            "34ab2b4 has no smoke-viewer run: {}",
            by_commit.2
        );
        let md = get(&app, &format!("/api/compare/runs?a={a}&b={b}&format=md")).await;
        assert!(
            md.1.starts_with("text/markdown")
                && md
                    .2
                    .contains("| variant | GPU ms | change [99% interval] | time |"),
            "{name}"
        );
        let csv = get(&app, &format!("/api/compare/runs?a={a}&b={b}&format=csv")).await;
        assert!(
            csv.2
                .starts_with("scenario,variant,measure,a,b,change,low,high,p,verdict\n"),
            "{name}"
        );
        ok(
            &get(&app, &format!("/compare/runs?pick={b}&pick={a}")).await,
            "ticked runs",
        );
        assert_eq!(
            get(&app, &format!("/compare/runs?pick={a}")).await.0,
            StatusCode::BAD_REQUEST
        );
        // Adapters and the viewer with another run.
        ok(&get(&app, "/compare?a=1&b=1&suite=fx").await, "adapters");
        ok(
            &get(
                &app,
                &format!(
                    "/runs/{b}/images/adaptive/adaptive-shading%5Bthreshold%3D0.5%5D?other={a}"
                ),
            )
            .await,
            "viewer",
        );
        // gzip when asked for.
        let res = app
            .clone()
            .oneshot(
                Request::get(format!("/api/runs/{b}"))
                    .header(header::ACCEPT_ENCODING, "gzip")
                    .body(Body::empty())
                    .unwrap(),
            )
            .await
            .unwrap();
        assert_eq!(res.headers()[header::CONTENT_ENCODING], "gzip", "{name}");
    }
}
