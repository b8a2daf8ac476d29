//! `tessera upload` and `run --upload` against a fake dashboard: a one-request HTTP server on
//! loopback that records what it got and answers as the dashboard would. No GPU needed.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpListener;
use std::path::Path;
use std::process::Command;
use std::thread::JoinHandle;

const RUN: &str = r#"{"schema_version": 2, "run_id": "r1", "status": "complete"}"#;
const SCENARIO: &str = r#"{"schema_version": 2, "run_id": "r1", "scenario": "tiny", "results": [
  {"variant": "native", "images": [
    {"frame": 0, "kind": "output", "path": "images/tiny/native-f000.png"},
    {"frame": 1, "kind": "output", "path": "images/tiny/native-f001.png"},
    {"frame": 0, "kind": "output", "path": "../outside.png"}]}]}"#;
const PNG: &[u8] = b"\x89PNG\r\n\x1a\nfake";

/// A run folder with one saved image (the second listed one is missing, the third unsafe).
fn run_folder(dir: &Path) -> String {
    let d = dir.join("r1");
    std::fs::create_dir_all(d.join("scenarios")).unwrap();
    std::fs::create_dir_all(d.join("images/tiny")).unwrap();
    std::fs::write(d.join("run.json"), RUN).unwrap();
    std::fs::write(d.join("scenarios/tiny.json"), SCENARIO).unwrap();
    std::fs::write(d.join("images/tiny/native-f000.png"), PNG).unwrap();
    std::fs::write(dir.join("outside.png"), PNG).unwrap();
    d.to_string_lossy().into_owned()
}

/// The body: the records brought to the current schema version (the shared reader upgrades
/// them), the one safe image that exists.
fn expected_body() -> serde_json::Value {
    let current = |text: &str| {
        let mut v = serde_json::from_str::<serde_json::Value>(text).unwrap();
        v["schema_version"] = tessera_results::SCHEMA_VERSION.into();
        v
    };
    serde_json::json!({
        "run": current(RUN),
        "scenarios": [current(SCENARIO)],
        "images": {"images/tiny/native-f000.png": "iVBORw0KGgpmYWtl"},
    })
}

struct Request {
    line: String,
    headers: Vec<(String, String)>,
    body: Vec<u8>,
}

impl Request {
    fn header(&self, name: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(name))
            .map(|(_, v)| v.as_str())
    }
}

/// Serves one upload, answering `/api/runs` (and any request, when `status` is not 2xx) with
/// `status` and JSON `answer`, as a dashboard without blob routes (404 to `/api/blobs*`); returns
/// the URL and the recorded requests.
fn fake_dashboard(
    status: &'static str,
    answer: &'static str,
) -> (String, JoinHandle<Vec<Request>>) {
    fake_dashboard_with(status, answer, true, None)
}

/// With `read_body` false it answers right after the request head and closes without reading
/// the body, as the dashboard does for a request without a valid token (it never sends
/// `100 Continue` then). With `blobs` it offers the blob routes, holding those digests at first.
fn fake_dashboard_with(
    status: &'static str,
    answer: &'static str,
    read_body: bool,
    blobs: Option<Vec<String>>,
) -> (String, JoinHandle<Vec<Request>>) {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let url = format!("http://{}", listener.local_addr().unwrap());
    let handle = std::thread::spawn(move || {
        let mut held = blobs.clone().unwrap_or_default();
        let mut requests = Vec::new();
        loop {
            let (stream, _) = listener.accept().unwrap();
            let mut reader = BufReader::new(stream.try_clone().unwrap());
            let mut line = String::new();
            reader.read_line(&mut line).unwrap();
            let mut headers = Vec::new();
            loop {
                let mut h = String::new();
                reader.read_line(&mut h).unwrap();
                let h = h.trim_end();
                if h.is_empty() {
                    break;
                }
                let (k, v) = h.split_once(':').unwrap();
                headers.push((k.trim().to_string(), v.trim().to_string()));
            }
            let length: usize = headers
                .iter()
                .find(|(k, _)| k.eq_ignore_ascii_case("content-length"))
                .map(|(_, v)| v.parse().unwrap())
                .unwrap_or(0);
            let mut stream = stream;
            let mut body = Vec::new();
            if read_body {
                let expects = headers.iter().any(|(k, v)| {
                    k.eq_ignore_ascii_case("expect") && v.eq_ignore_ascii_case("100-continue")
                });
                if expects {
                    stream.write_all(b"HTTP/1.1 100 Continue\r\n\r\n").unwrap();
                }
                body = vec![0; length];
                reader.read_exact(&mut body).unwrap();
            }
            let ok = status.starts_with('2');
            let blob_route = line.contains(" /api/blobs");
            let (st, ans): (&str, String) = if !ok || !blob_route {
                (status, answer.to_string())
            } else if blobs.is_none() {
                ("404 Not Found", r#"{"error":"no such page"}"#.to_string())
            } else if line.contains("/api/blobs/missing") {
                let asked: serde_json::Value = serde_json::from_slice(&body).unwrap();
                let missing: Vec<String> = asked["digests"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|d| d.as_str().unwrap().to_string())
                    .filter(|d| !held.contains(d))
                    .collect();
                (
                    "200 OK",
                    serde_json::json!({ "missing": missing }).to_string(),
                )
            } else {
                let got = tessera_results::upload::split_batch(&body, u64::MAX).unwrap();
                held.extend(got.iter().map(|(d, _)| d.clone()));
                (
                    "201 Created",
                    format!(r#"{{"stored":{},"already":0}}"#, got.len()),
                )
            };
            write!(
                stream,
                "HTTP/1.1 {st}\r\nContent-Type: application/json\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{ans}",
                ans.len()
            )
            .unwrap();
            let last = !ok || !blob_route;
            requests.push(Request {
                line: line.trim_end().to_string(),
                headers,
                body,
            });
            if last {
                return requests;
            }
        }
    });
    (url, handle)
}

fn tessera(args: &[&str], token: Option<&str>) -> (i32, String, String) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_tessera"));
    cmd.args(args);
    match token {
        Some(t) => cmd.env("TESSERA_DASHBOARD_TOKEN", t),
        None => cmd.env_remove("TESSERA_DASHBOARD_TOKEN"),
    };
    let out = cmd.output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

#[test]
fn bundle_is_the_dashboards_upload_body() {
    let dir = tempfile::tempdir().unwrap();
    let run = run_folder(dir.path());
    assert_eq!(
        serde_json::to_value(tessera::upload::bundle(Path::new(&run)).unwrap()).unwrap(),
        expected_body()
    );
}

#[test]
fn endpoint_appends_the_api_path_once() {
    use tessera::upload::endpoint;
    assert_eq!(endpoint("http://d:8080").unwrap(), "http://d:8080/api/runs");
    assert_eq!(endpoint("https://d/").unwrap(), "https://d/api/runs");
    assert_eq!(endpoint("http://d/api/runs").unwrap(), "http://d/api/runs");
    assert_eq!(
        endpoint("d:8080").unwrap_err().to_string(),
        "\"d:8080\" is not a dashboard URL: give http://host:port or https://host"
    );
}

#[test]
fn upload_posts_the_bundle_with_the_bearer_token() {
    let dir = tempfile::tempdir().unwrap();
    let run = run_folder(dir.path());
    let (url, server) = fake_dashboard(
        "201 Created",
        r#"{"run_id":"r1","stored":true,"results":3,"new_regressions":1}"#,
    );
    let (code, out, err) = tessera(&["upload", &run, "--url", &url], Some("s3cret"));
    assert_eq!((code, err.as_str()), (0, ""));
    assert!(
        out.starts_with("uploaded: r1 stored (3 results, 1 new regressions; sent ")
            && out.ends_with(" in all, 1 of 1 images new to the dashboard)\n"),
        "{out}"
    );
    // A dashboard without blob routes: the question is answered 404, the images go inline.
    let reqs = server.join().unwrap();
    assert_eq!(reqs.len(), 2);
    assert_eq!(reqs[0].line, "POST /api/blobs/missing HTTP/1.1");
    let req = &reqs[1];
    assert_eq!(req.line, "POST /api/runs HTTP/1.1");
    assert_eq!(req.header("authorization"), Some("Bearer s3cret"));
    assert_eq!(req.header("content-type"), Some("application/json"));
    assert_eq!(req.header("expect"), Some("100-continue"));
    let body: serde_json::Value = serde_json::from_slice(&req.body).unwrap();
    assert_eq!(body, expected_body());
}

#[test]
fn already_stored_is_success() {
    let dir = tempfile::tempdir().unwrap();
    let run = run_folder(dir.path());
    let (url, server) = fake_dashboard(
        "200 OK",
        r#"{"run_id":"r1","stored":false,"results":0,"new_regressions":0}"#,
    );
    let (code, out, _) = tessera(&["upload", &run, "--url", &url], Some("s3cret"));
    assert_eq!(code, 0);
    assert!(
        out.starts_with("uploaded: r1 was already stored (sent "),
        "{out}"
    );
    server.join().unwrap();
}

/// The dashboard's warnings about a run it took (this run records no commit) are printed on
/// stderr, one line each, after the summary on stdout; the upload still succeeds.
#[test]
fn the_dashboards_warnings_are_printed() {
    let dir = tempfile::tempdir().unwrap();
    let run = run_folder(dir.path());
    let (url, server) = fake_dashboard(
        "201 Created",
        r#"{"run_id":"r1","stored":true,"results":1,"new_regressions":0,
            "warnings":["run r1 records no commit (tessera ran outside a git checkout)"]}"#,
    );
    let (code, out, err) = tessera(&["upload", &run, "--url", &url], Some("s3cret"));
    assert_eq!(code, 0, "{err}");
    assert!(out.starts_with("uploaded: r1 stored"), "{out}");
    assert_eq!(
        err,
        "warning: run r1 records no commit (tessera ran outside a git checkout)\n"
    );
    server.join().unwrap();
}

#[test]
fn refused_upload_exits_4_with_the_dashboards_message() {
    let dir = tempfile::tempdir().unwrap();
    let run = run_folder(dir.path());
    let (url, server) = fake_dashboard("401 Unauthorized", r#"{"error":"wrong token"}"#);
    let (code, out, err) = tessera(&["upload", &run, "--url", &url], Some("wrong"));
    assert_eq!((code, out.as_str()), (4, ""));
    assert_eq!(
        err,
        format!(
            "error: the dashboard at {url}/api/blobs/missing refused the run with HTTP 401: wrong token\n"
        )
    );
    server.join().unwrap();
    assert!(
        Path::new(&run).join("run.json").is_file(),
        "results stay on disk"
    );
}

#[test]
fn refusal_before_a_large_body_is_reported_with_the_dashboards_message() {
    // The dashboard checks the token before reading the body: a client that sent the whole body
    // regardless would see a broken pipe instead of the answer.
    let dir = tempfile::tempdir().unwrap();
    let run = run_folder(dir.path());
    let big = vec![7u8; 24 << 20];
    std::fs::write(Path::new(&run).join("images/tiny/native-f000.png"), big).unwrap();
    let (url, server) = fake_dashboard_with(
        "401 Unauthorized",
        r#"{"error":"this request needs a write token"}"#,
        false,
        Some(Vec::new()),
    );
    let (code, _, err) = tessera(&["upload", &run, "--url", &url], Some("wrong"));
    assert_eq!(
        (code, err.as_str()),
        (
            4,
            format!("error: the dashboard at {url}/api/blobs/missing refused the run with HTTP 401: this request needs a write token\n").as_str()
        )
    );
    let reqs = server.join().unwrap();
    assert_eq!(reqs.len(), 1, "nothing is sent after a refusal");
    assert!(reqs[0].body.is_empty());
}

#[test]
fn images_travel_as_blobs_once() {
    let dir = tempfile::tempdir().unwrap();
    let run = run_folder(dir.path());
    // A second image, larger than everything else the upload sends.
    let big: Vec<u8> = PNG
        .iter()
        .copied()
        .chain((0..200_000u32).map(|i| (i % 251) as u8))
        .collect();
    std::fs::write(Path::new(&run).join("images/tiny/native-f001.png"), &big).unwrap();
    let answer = r#"{"run_id":"r1","stored":true,"results":1,"new_regressions":0}"#;
    let (url, server) = fake_dashboard_with("201 Created", answer, true, Some(Vec::new()));
    let (code, out, err) = tessera(&["upload", &run, "--url", &url], Some("s3cret"));
    assert_eq!((code, err.as_str()), (0, ""), "{out}");
    assert!(out.contains("2 of 2 images new"), "{out}");
    let reqs = server.join().unwrap();
    let lines: Vec<&str> = reqs.iter().map(|r| r.line.as_str()).collect();
    assert_eq!(
        lines,
        [
            "POST /api/blobs/missing HTTP/1.1",
            "POST /api/blobs HTTP/1.1",
            "POST /api/runs HTTP/1.1"
        ]
    );
    assert_eq!(
        reqs[1].header("content-type"),
        Some("application/octet-stream")
    );
    let sent = tessera_results::upload::split_batch(&reqs[1].body, u64::MAX).unwrap();
    assert_eq!(sent.len(), 2);
    let body: serde_json::Value = serde_json::from_slice(&reqs[2].body).unwrap();
    assert!(body.get("images").unwrap().as_object().unwrap().is_empty());
    let digests = body["image_digests"].as_object().unwrap();
    assert_eq!(
        digests["images/tiny/native-f001.png"],
        tessera_results::upload::blob_digest(&big)
    );
    assert!(reqs[2].body.len() < 10_000);

    // Again, to a dashboard holding both blobs: only the question and the records travel.
    let held: Vec<String> = sent.iter().map(|(d, _)| d.clone()).collect();
    let answer = r#"{"run_id":"r1","stored":false,"results":0,"new_regressions":0}"#;
    let (url, server) = fake_dashboard_with("200 OK", answer, true, Some(held));
    let (code, out, _) = tessera(&["upload", &run, "--url", &url], Some("s3cret"));
    assert_eq!(code, 0);
    assert!(out.contains("0 of 2 images new"), "{out}");
    let reqs = server.join().unwrap();
    assert_eq!(reqs.len(), 2);
    let total: usize = reqs.iter().map(|r| r.body.len()).sum();
    assert!(total < big.len() / 10, "{total} bytes sent again");
}

#[test]
fn unreachable_dashboard_and_missing_token_exit_4() {
    let dir = tempfile::tempdir().unwrap();
    let run = run_folder(dir.path());
    // A port that nothing listens on any more.
    let url = {
        let l = TcpListener::bind("127.0.0.1:0").unwrap();
        format!("http://{}", l.local_addr().unwrap())
    };
    let (code, _, err) = tessera(&["upload", &run, "--url", &url], Some("s3cret"));
    assert_eq!(code, 4, "{err}");
    assert!(
        err.starts_with(&format!(
            "error: cannot reach the dashboard at {url}/api/blobs/missing: "
        )),
        "{err}"
    );
    let (code, _, err) = tessera(&["upload", &run, "--url", &url], None);
    assert_eq!(code, 4);
    assert_eq!(
        err,
        "error: TESSERA_DASHBOARD_TOKEN is not set: export the dashboard's token to upload\n"
    );
}

#[test]
fn bad_run_folder_or_url_exits_2() {
    let (code, _, err) = tessera(&["upload", "/no/such/run", "--url", "http://d"], Some("t"));
    assert_eq!(code, 2);
    assert_eq!(err, "error: /no/such/run: no such run folder (expected <run-id>/run.json as written by `tessera run`)\n");
    let dir = tempfile::tempdir().unwrap();
    let run = run_folder(dir.path());
    let (code, _, _) = tessera(&["upload", &run, "--url", "ftp://d"], Some("t"));
    assert_eq!(code, 2);
}

#[test]
fn run_with_upload_refuses_a_missing_token_before_running() {
    let smoke = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenarios/smoke/basic.toml");
    let (code, out, err) = tessera(&["run", smoke, "--upload", "http://d:8080"], None);
    assert_eq!((code, out.as_str()), (2, ""));
    assert_eq!(
        err,
        "error: --upload: TESSERA_DASHBOARD_TOKEN is not set: export the dashboard's token to upload\n"
    );
}
