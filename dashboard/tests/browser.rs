//! Browser tests: the dashboard served on a loopback port from a temporary SQLite store, every page
//! type loaded in headless Chromium (driven over WebDriver by chromedriver), charts checked as
//! drawn (their marks have a non-empty box in the laid-out page), no error text and no console
//! errors, and every same-origin link and image of every page reached by crawling answers 200.
//!
//! The store holds the committed real lavapipe runs (imported with `import`), plus runs derived
//! from the newest real run because this machine has one adapter and two runs: 20 on the same
//! adapter with a 25% step half-way (so that a regression, a change point and triage forms exist)
//! and 2 under another adapter name (so that the adapter comparison has two sides).
//!
//! Chromium and chromedriver come from `dashboard/ci/setup-chromium.sh`. Without them the test
//! fails when `CI` is set and prints `skipped: chromium not installed` otherwise.

mod common;

use std::collections::{BTreeSet, VecDeque};
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::{json, Value};
use tessera_dashboard::bundle::RunBundle;
use tessera_dashboard::detect::{Params, Rng};
use tessera_dashboard::import::import;
use tessera_dashboard::server::{app, AppState};
use tessera_dashboard::store::ingest::{ingest, Ingested};
use tessera_dashboard::{regressions, synth};

const SETUP: &str = "dashboard/ci/setup-chromium.sh";
/// Most pages of one type that the crawl loads in Chromium (breadth first, so the seeds and the
/// pages they link to come first); further pages of that type are only fetched with HTTP GET.
const PER_TYPE: usize = 8;

// ---------------------------------------------------------------------------------------------
// Finding the browser.

fn find_tool(env: &str, names: &[&str]) -> Option<PathBuf> {
    if let Some(p) = std::env::var_os(env) {
        return Some(PathBuf::from(p)).filter(|p| p.is_file());
    }
    let path = std::env::var_os("PATH").unwrap_or_default();
    for name in names {
        let fixed = Path::new("/usr/bin").join(name);
        if fixed.is_file() {
            return Some(fixed);
        }
        for dir in std::env::split_paths(&path) {
            let p = dir.join(name);
            if p.is_file() {
                return Some(p);
            }
        }
    }
    None
}

/// Chromium and chromedriver, or `None` after saying the test was skipped (outside CI).
fn browser_tools() -> Option<(PathBuf, PathBuf)> {
    let chromium = find_tool(
        "TESSERA_CHROMIUM",
        &["chromium", "chromium-browser", "google-chrome"],
    );
    let driver = find_tool("TESSERA_CHROMEDRIVER", &["chromedriver"]);
    match (chromium, driver) {
        (Some(c), Some(d)) => Some((c, d)),
        (c, d) => {
            let missing = if c.is_none() {
                "chromium"
            } else {
                "chromedriver"
            };
            let _ = d;
            if std::env::var_os("CI").is_some() {
                panic!("{missing} is not installed (CI is set): run `bash {SETUP}` first");
            }
            eprintln!(
                "skipped: chromium not installed ({missing} missing; `bash {SETUP}` installs it)"
            );
            None
        }
    }
}

// ---------------------------------------------------------------------------------------------
// A small HTTP/1.1 client (one request per connection), for WebDriver and for checking links.

struct Reply {
    status: u16,
    content_type: String,
    body: Vec<u8>,
}

fn http(addr: SocketAddr, method: &str, path: &str, body: Option<&Value>) -> Reply {
    let mut s = TcpStream::connect_timeout(&addr, Duration::from_secs(5))
        .unwrap_or_else(|e| panic!("connect {addr}: {e}"));
    s.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
    let body = body.map(|b| b.to_string()).unwrap_or_default();
    let req = format!(
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\nContent-Type: application/json\r\nContent-Length: {}\r\n\r\n{body}",
        body.len()
    );
    s.write_all(req.as_bytes()).unwrap();
    // Read the header, then as much body as it announces: chromedriver keeps the connection open
    // whatever the request says, so reading to the end would wait for the timeout.
    let mut raw = Vec::new();
    let mut buf = [0u8; 16384];
    let split = loop {
        if let Some(i) = raw.windows(4).position(|w| w == b"\r\n\r\n") {
            break i;
        }
        let n = s
            .read(&mut buf)
            .unwrap_or_else(|e| panic!("{method} {path}: {e}"));
        assert!(
            n > 0,
            "{method} {path}: connection closed before the header"
        );
        raw.extend_from_slice(&buf[..n]);
    };
    let head = String::from_utf8_lossy(&raw[..split]).into_owned();
    let mut payload = raw[split + 4..].to_vec();
    let status = head
        .split_whitespace()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("{method} {path}: bad status line: {head}"));
    let header = |name: &str| {
        head.lines()
            .filter_map(|l| l.split_once(':'))
            .find(|(k, _)| k.trim().eq_ignore_ascii_case(name))
            .map(|(_, v)| v.trim().to_string())
    };
    let chunked = header("transfer-encoding").is_some_and(|v| v.eq_ignore_ascii_case("chunked"));
    let length: Option<usize> = header("content-length").and_then(|v| v.parse().ok());
    loop {
        let done = match length {
            Some(n) => payload.len() >= n,
            None if chunked => payload.ends_with(b"0\r\n\r\n"),
            None => false,
        };
        if done {
            break;
        }
        let n = s
            .read(&mut buf)
            .unwrap_or_else(|e| panic!("{method} {path}: {e}"));
        if n == 0 {
            break;
        }
        payload.extend_from_slice(&buf[..n]);
    }
    if chunked {
        payload = dechunk(&payload);
    }
    Reply {
        status,
        content_type: header("content-type").unwrap_or_default(),
        body: payload,
    }
}

fn dechunk(mut b: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    while let Some(eol) = b.windows(2).position(|w| w == b"\r\n") {
        let size = usize::from_str_radix(
            String::from_utf8_lossy(&b[..eol])
                .split(';')
                .next()
                .unwrap()
                .trim(),
            16,
        )
        .expect("chunk size");
        if size == 0 {
            break;
        }
        out.extend_from_slice(&b[eol + 2..eol + 2 + size]);
        b = &b[eol + 2 + size + 2..];
    }
    out
}

// ---------------------------------------------------------------------------------------------
// WebDriver.

struct Browser {
    driver: Child,
    addr: SocketAddr,
    session: String,
    _profile: tempfile::TempDir,
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = std::panic::catch_unwind(|| {
            http(
                self.addr,
                "DELETE",
                &format!("/session/{}", self.session),
                None,
            )
        });
        let _ = self.driver.kill();
        let _ = self.driver.wait();
    }
}

fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

impl Browser {
    fn start(chromium: &Path, chromedriver: &Path) -> Browser {
        let port = free_port();
        let addr: SocketAddr = ([127, 0, 0, 1], port).into();
        let mut driver = Command::new(chromedriver)
            .arg(format!("--port={port}"))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start {}: {e}", chromedriver.display()));
        let deadline = Instant::now() + Duration::from_secs(10);
        while TcpStream::connect(addr).is_err() {
            if Instant::now() > deadline {
                let _ = driver.kill();
                panic!("chromedriver did not listen on {addr} within 10 s");
            }
            std::thread::sleep(Duration::from_millis(25));
        }
        let profile = tempfile::tempdir().unwrap();
        let caps = json!({"capabilities": {"alwaysMatch": {
            "browserName": "chrome",
            "pageLoadStrategy": "normal",
            "goog:loggingPrefs": {"browser": "ALL"},
            "goog:chromeOptions": {
                "binary": chromium,
                "args": [
                    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                    "--no-first-run", "--disable-background-networking",
                    "--disable-component-update", "--disable-sync",
                    "--disable-dev-shm-usage", "--window-size=1280,1000",
                    format!("--user-data-dir={}", profile.path().display()),
                ]
            }
        }}});
        let r = http(addr, "POST", "/session", Some(&caps));
        let v: Value = serde_json::from_slice(&r.body).unwrap_or(Value::Null);
        let Some(session) = v["value"]["sessionId"].as_str().map(String::from) else {
            let _ = driver.kill();
            panic!(
                "chromedriver could not start {}: {} {}",
                chromium.display(),
                r.status,
                String::from_utf8_lossy(&r.body)
            );
        };
        Browser {
            driver,
            addr,
            session,
            _profile: profile,
        }
    }

    fn call(&self, method: &str, what: &str, body: Option<Value>) -> Value {
        let path = format!("/session/{}/{what}", self.session);
        let r = http(self.addr, method, &path, body.as_ref());
        let v: Value = serde_json::from_slice(&r.body).unwrap_or(Value::Null);
        assert_eq!(
            r.status,
            200,
            "WebDriver {method} {what}: {}",
            String::from_utf8_lossy(&r.body)
        );
        v["value"].clone()
    }

    fn goto(&self, url: &str) {
        self.call("POST", "url", Some(json!({ "url": url })));
    }

    fn eval(&self, script: &str) -> Value {
        self.call(
            "POST",
            "execute/sync",
            Some(json!({"script": script, "args": []})),
        )
    }

    /// The first element matching a CSS selector (its WebDriver reference).
    fn find(&self, css: &str) -> String {
        let v = self.call(
            "POST",
            "element",
            Some(json!({"using": "css selector", "value": css})),
        );
        v["element-6066-11e4-a52e-4f735466cecf"]
            .as_str()
            .unwrap_or_else(|| panic!("no element {css}: {v}"))
            .to_string()
    }

    /// Clicks the element as a user would (scrolled into view, hit-tested).
    fn click(&self, css: &str) {
        let el = self.find(css);
        self.call("POST", &format!("element/{el}/click"), Some(json!({})));
    }

    /// Types `text` into the element as key presses.
    fn type_into(&self, css: &str, text: &str) {
        let el = self.find(css);
        self.call(
            "POST",
            &format!("element/{el}/value"),
            Some(json!({ "text": text })),
        );
    }

    /// Saves a PNG of the viewport to `path`.
    fn screenshot(&self, path: &Path) {
        use base64::Engine;
        let v = self.call("GET", "screenshot", None);
        let png = base64::engine::general_purpose::STANDARD
            .decode(v.as_str().unwrap())
            .unwrap();
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, png).unwrap();
    }

    /// Evaluates `script` (which returns a value) until it is truthy, for at most 10 s.
    fn wait_for(&self, script: &str) -> Value {
        let deadline = Instant::now() + Duration::from_secs(10);
        loop {
            let v = self.eval(script);
            if !(v.is_null() || v == false || v == "") {
                return v;
            }
            assert!(Instant::now() < deadline, "timed out waiting for {script}");
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// Console messages since the last call, as `LEVEL message`.
    fn console(&self) -> Vec<String> {
        let v = self.call("POST", "se/log", Some(json!({"type": "browser"})));
        v.as_array()
            .into_iter()
            .flatten()
            .map(|e| format!("{} {}", e["level"].as_str().unwrap_or("?"), e["message"]))
            .collect()
    }
}

/// What a loaded page looks like to the browser. Links are resolved by the browser (SVG `<a>`
/// included); a chart mark counts as drawn when its box in the laid-out page is not empty.
const INSPECT: &str = r#"
const drawn = e => { const r = e.getBoundingClientRect(); return r.width > 0 || r.height > 0; };
const count = (root, sel) => Array.from(root.querySelectorAll(sel)).filter(drawn).length;
const href = a => (typeof a.href === 'string') ? a.href : new URL(a.href.baseVal, location.href).href;
return {
  url: location.href,
  title: document.title,
  text: document.body ? document.body.innerText : '',
  h1: (document.querySelector('h1') || {}).textContent || '',
  charts: Array.from(document.querySelectorAll('main svg')).map(s => ({
    width: s.getBoundingClientRect().width,
    points: count(s, 'circle.point'),
    bars: count(s, 'rect.bar'),
    lines: count(s, 'polyline'),
    fronts: count(s, 'polyline.front'),
    change_points: count(s, 'line.change-point'),
    text: s.textContent,
  })),
  links: Array.from(document.querySelectorAll('a')).map(href),
  images: Array.from(document.images).map(i => ({src: i.src, ok: i.complete && i.naturalWidth > 0, hidden: !!i.closest('[hidden]')})),
  tables: Array.from(document.querySelectorAll('main table')).map(t => ({id: t.id, rows: t.rows.length})),
  forms: document.forms.length,
};
"#;

// ---------------------------------------------------------------------------------------------
// The store and the server.

const SECOND_ADAPTER: &str = "llvmpipe (second adapter, derived from a real run)";

/// Imports the real fixture runs, then the derived runs described at the top.
fn fill(pool: &tessera_dashboard::db::Pool) -> Vec<String> {
    let summary = import(pool, &common::fixtures(), &Params::default()).unwrap();
    assert!(
        summary.failed.is_empty() && summary.stored >= 2,
        "{summary:?}"
    );
    let newest = tessera_dashboard::import::find_run_folders(&common::fixtures())
        .unwrap()
        .pop()
        .unwrap();
    let real = RunBundle::read_folder(&newest).unwrap();
    let mut rng = Rng::new(7);
    let mut conn = pool.get().unwrap();
    let mut touched = BTreeSet::new();
    let mut store = |b: &RunBundle| {
        if let Ingested::Stored { series, .. } = ingest(&mut *conn, b).unwrap() {
            touched.extend(series);
        }
    };
    for i in 0..20 {
        let factor = if i < 10 { 1.0 } else { 1.25 };
        store(&synth::run_from(&real, "hist", i, factor, 0.01, &mut rng));
    }
    for i in 0..2 {
        let mut b = synth::run_from(&real, "second", 100 + i, 0.8, 0.01, &mut rng);
        b.run.adapter.name = SECOND_ADAPTER.into();
        store(&b);
    }
    let touched: Vec<i64> = touched.into_iter().collect();
    let added = regressions::update(&mut *conn, &touched, &Params::default()).unwrap();
    assert!(added > 0, "the 25% step found no change point");
    std::fs::read_dir(common::fixtures())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect()
}

/// Serves `app` on a free loopback port from a thread of its own; returns the address.
fn serve(state: AppState) -> SocketAddr {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    listener.set_nonblocking(true).unwrap();
    let addr = listener.local_addr().unwrap();
    std::thread::spawn(move || {
        let rt = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .enable_all()
            .build()
            .unwrap();
        rt.block_on(async move {
            let listener = tokio::net::TcpListener::from_std(listener).unwrap();
            axum::serve(listener, app(state)).await.unwrap();
        });
    });
    addr
}

// ---------------------------------------------------------------------------------------------
// The test.

/// The path and query of a same-origin URL, without its fragment; `None` for other origins.
fn local(url: &str, origin: &str) -> Option<String> {
    let rest = url.strip_prefix(origin)?;
    if !(rest.is_empty() || rest.starts_with('/') || rest.starts_with('?')) {
        return None;
    }
    let rest = rest.split('#').next().unwrap();
    Some(if rest.starts_with('/') {
        rest.to_string()
    } else {
        format!("/{rest}")
    })
}

/// A page's type, from its path: the route it is served by.
fn page_type(path: &str) -> &'static str {
    let p = path.split('?').next().unwrap();
    let parts: Vec<&str> = p.trim_matches('/').split('/').collect();
    match parts.as_slice() {
        [""] => "runs",
        ["runs", _] => "run",
        ["runs", _, "images", _, _] => "images",
        ["series"] => "series list",
        ["series", _] => "series",
        ["regressions"] => "regressions",
        ["regressions", "groups", _] => "alert group",
        ["compare"] => "adapter comparison",
        ["pareto"] => "error vs time",
        ["images", _] => "png",
        ["api", ..] => "api",
        _ => "other",
    }
}

#[test]
fn every_page_draws_in_chromium_and_its_links_resolve() {
    let Some((chromium, chromedriver)) = browser_tools() else {
        return;
    };
    let start = Instant::now();
    let store = common::sqlite();
    let real_runs = fill(&store.pool);
    let addr = serve(AppState::new(
        store.pool.clone(),
        Some("browser-test".into()),
    ));
    let origin = format!("http://{addr}");
    let browser = Browser::start(&chromium, &chromedriver);
    let _ = browser.console();

    // Pages reached from the seeds (every page type; the crawl finds the rest) are loaded in
    // Chromium, up to PER_TYPE of each type; every same-origin link and image on them must answer
    // 200 to a plain GET.
    let mut queue: VecDeque<String> = VecDeque::new();
    let mut seen: BTreeSet<String> = BTreeSet::new();
    for p in ["/", "/series", "/regressions", "/compare", "/pareto"]
        .into_iter()
        .map(String::from)
        .chain(real_runs.iter().map(|r| format!("/runs/{r}")))
        .chain(
            real_runs
                .iter()
                .map(|r| format!("/runs/{r}/images/tiny/native")),
        )
    {
        seen.insert(p.clone());
        queue.push_back(p);
    }
    let mut problems: Vec<String> = Vec::new();
    let mut loaded: Vec<(String, Value)> = Vec::new();
    let mut checked_links = 0usize;
    while let Some(path) = queue.pop_front() {
        let kind = page_type(&path);
        let reply = http(addr, "GET", &path, None);
        checked_links += 1;
        if reply.status != 200 {
            problems.push(format!(
                "{path}: HTTP {}: {}",
                reply.status,
                String::from_utf8_lossy(&reply.body)
            ));
            continue;
        }
        if !reply.content_type.starts_with("text/html") {
            if kind == "png" && !reply.body.starts_with(b"\x89PNG") {
                problems.push(format!("{path}: not a PNG ({})", reply.content_type));
            }
            continue;
        }
        if loaded.iter().filter(|(p, _)| page_type(p) == kind).count() >= PER_TYPE {
            continue;
        }
        browser.goto(&format!("{origin}{path}"));
        let page = browser.eval(INSPECT);
        for msg in browser.console() {
            // Pages declare an empty inline icon, so no request for /favicon.ico may fail.
            if msg.starts_with("SEVERE") || msg.starts_with("WARNING") {
                problems.push(format!("{path}: console: {msg}"));
            }
        }
        let text = page["text"].as_str().unwrap_or_default();
        if page["h1"].as_str().unwrap_or_default().is_empty() || text.contains("\"error\"") {
            problems.push(format!("{path}: not a dashboard page: {text:.200}"));
        }
        for (i, chart) in page["charts"].as_array().into_iter().flatten().enumerate() {
            let marks = ["points", "bars", "lines"]
                .iter()
                .map(|k| chart[k].as_u64().unwrap_or(0))
                .sum::<u64>();
            if chart["width"].as_f64().unwrap_or(0.0) <= 0.0 || marks == 0 {
                problems.push(format!("{path}: chart {i} drew nothing: {chart}"));
            }
        }
        for img in page["images"].as_array().into_iter().flatten() {
            if !img["ok"].as_bool().unwrap_or(false) && !img["hidden"].as_bool().unwrap_or(false) {
                problems.push(format!("{path}: image did not decode: {img}"));
            }
        }
        let links = page["links"].as_array().cloned().unwrap_or_default();
        let srcs = page["images"].as_array().cloned().unwrap_or_default();
        for url in links
            .iter()
            .filter_map(|l| l.as_str())
            .chain(srcs.iter().filter_map(|i| i["src"].as_str()))
        {
            if url.is_empty() {
                continue;
            }
            let Some(p) = local(url, &origin) else {
                problems.push(format!("{path}: link leaves the dashboard: {url}"));
                continue;
            };
            if seen.insert(p.clone()) {
                queue.push_back(p);
            }
        }
        loaded.push((path, page));
    }

    // Each page type, with what its charts and tables must show.
    let of = |kind: &str| -> Vec<&Value> {
        loaded
            .iter()
            .filter(|(p, _)| page_type(p) == kind)
            .map(|(_, v)| v)
            .collect()
    };
    let chart_sum = |pages: &[&Value], key: &str| -> u64 {
        pages
            .iter()
            .flat_map(|p| p["charts"].as_array().cloned().unwrap_or_default())
            .map(|c| c[key].as_u64().unwrap_or(0))
            .sum()
    };
    let table_rows = |page: &Value, id: &str| -> u64 {
        page["tables"]
            .as_array()
            .into_iter()
            .flatten()
            .filter(|t| t["id"] == id)
            .map(|t| t["rows"].as_u64().unwrap_or(0))
            .sum()
    };
    for kind in [
        "runs",
        "run",
        "images",
        "series list",
        "series",
        "regressions",
        "adapter comparison",
        "error vs time",
    ] {
        assert!(!of(kind).is_empty(), "no {kind} page was loaded");
    }
    let runs = of("runs");
    assert!(
        table_rows(runs[0], "runs") > 20,
        "runs page lists the runs: {}",
        runs[0]["text"]
    );
    // Every run page draws its per-pass stacked bars (3 variants in the real runs).
    for page in of("run") {
        assert!(
            chart_sum(&[page], "bars") >= 3,
            "run page without stacked bars: {}",
            page["url"]
        );
    }
    for r in &real_runs {
        assert!(
            loaded.iter().any(|(p, _)| p == &format!("/runs/{r}")),
            "real run {r} not loaded"
        );
    }
    // Series: points for every run of the series (22 on the first adapter), and the change point.
    let series = of("series");
    assert!(
        series
            .iter()
            .any(|p| chart_sum(&[p], "points") >= 22 && chart_sum(&[p], "change_points") >= 1),
        "no series page draws 22 points with a change point"
    );
    assert!(series.iter().all(|p| chart_sum(&[p], "lines") >= 1));
    // Images: reference and variant shown and decoded, the frame slider works.
    for page in of("images") {
        let shown = page["images"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|i| i["ok"] == true)
            .count();
        assert!(shown >= 1, "images page shows no image: {}", page["url"]);
    }
    let images_url = &of("images")[0]["url"];
    browser.goto(images_url.as_str().unwrap());
    let frame = browser.eval(
        "const s = document.getElementById('frame'); s.value = s.max; s.dispatchEvent(new Event('input')); return document.getElementById('frameno').textContent;",
    );
    assert!(
        frame.as_str().is_some_and(|f| !f.is_empty()),
        "frame slider: {frame}"
    );
    let regressions = of("regressions");
    assert!(
        regressions
            .iter()
            .any(|p| table_rows(p, "regressions") > 1 && p["forms"].as_u64() > Some(0)),
        "regressions page lists no change with a triage form"
    );
    let compare = of("adapter comparison");
    assert!(
        compare.iter().any(|p| table_rows(p, "compare") >= 4
            && p["text"].as_str().unwrap().contains(SECOND_ADAPTER)),
        "adapter comparison shows no rows for two adapters: {}",
        compare[0]["text"]
    );
    let pareto = of("error vs time");
    assert!(
        pareto
            .iter()
            .any(|p| chart_sum(&[p], "points") >= 3 && chart_sum(&[p], "fronts") >= 1),
        "error-vs-time chart without points and front: {}",
        pareto[0]["charts"]
    );
    for msg in browser.console() {
        if msg.starts_with("SEVERE") {
            problems.push(format!("{images_url}: console after the slider: {msg}"));
        }
    }

    assert!(
        problems.is_empty(),
        "{} problem(s):\n{}",
        problems.len(),
        problems.join("\n")
    );
    let mut types = std::collections::BTreeMap::new();
    for (p, _) in &loaded {
        *types.entry(page_type(p)).or_insert(0) += 1;
    }
    eprintln!(
        "browser: {} pages loaded in Chromium {types:?}; {checked_links} same-origin URLs answered 200; {:.1} s",
        loaded.len(),
        start.elapsed().as_secs_f64()
    );
}

// ---------------------------------------------------------------------------------------------
// The regressions page: alert groups, bulk triage with the token entered once, filters, feed.

/// Where the screenshots of the browser tests are kept (under the workspace's `target/`).
fn artefacts() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/test-artefacts/browser")
}

/// What the regressions page shows: its groups, each with its key, state badge and series rows.
const GROUPS: &str = r#"
return Array.from(document.querySelectorAll('#regressions tbody.group')).map(g => ({
  key: g.id.slice(2),
  title: g.querySelector('h2').textContent,
  state: g.querySelector('[data-state-of]').textContent,
  rows: Array.from(g.querySelectorAll('tr.alert')).map(r => Array.from(r.cells).map(c => c.textContent)),
  worse_colour: (g.querySelector('.chg.worse') ? getComputedStyle(g.querySelector('.chg.worse')).color : ''),
  link_colour: getComputedStyle(g.querySelector('tr.alert a')).color,
}));
"#;

#[test]
fn regressions_page_triages_groups_with_the_token_entered_once() {
    let Some((chromium, chromedriver)) = browser_tools() else {
        return;
    };
    let store = common::sqlite();
    common::two_adapter_history(&store.pool, 0, 40);
    let addr = serve(AppState::new(
        store.pool.clone(),
        Some("browser-test".into()),
    ));
    let origin = format!("http://{addr}");
    let browser = Browser::start(&chromium, &chromedriver);
    let _ = browser.console();
    let shots = artefacts();

    // Two groups, newest first: the change at run 30 on both adapters, the one at run 15.
    browser.goto(&format!("{origin}/regressions"));
    let groups = browser.eval(GROUPS);
    let groups = groups.as_array().unwrap();
    assert_eq!(groups.len(), 2, "{groups:?}");
    assert_eq!(groups[0]["key"], common::range(29));
    assert_eq!(groups[1]["key"], common::range(14));
    let title = groups[0]["title"].as_str().unwrap();
    assert!(title.contains("series on 2 adapters"), "{title}");
    let rows = groups[0]["rows"].as_array().unwrap();
    assert!(rows.len() >= 6, "{rows:?}");
    let adapters: BTreeSet<&str> = rows.iter().map(|r| r[0].as_str().unwrap()).collect();
    assert_eq!(adapters.len(), 2, "{adapters:?}");
    assert!(rows
        .iter()
        .all(|r| r[7].as_str().unwrap().contains("worse")));
    // Worse is red whatever colour links have.
    assert_eq!(groups[0]["worse_colour"], "rgb(161, 20, 15)");
    assert_ne!(groups[0]["link_colour"], groups[0]["worse_colour"]);
    assert!(groups.iter().all(|g| g["state"] == "new"));
    browser.screenshot(&shots.join("regressions.png"));

    // The token, typed once; the first group triaged on this page.
    browser.type_into("#token", "browser-test");
    browser.click("#token-save");
    assert_eq!(
        browser.eval("return document.getElementById('token-state').textContent"),
        "write token set for this browser session"
    );
    let key30 = common::range(29);
    let key15 = common::range(14);
    let form = |key: &str| format!("form.triage[data-key=\"{key}\"]");
    browser.eval(&format!(
        "const f = document.querySelector('{}'); f.elements.state.value = 'acknowledged'; return true;",
        form(&key30)
    ));
    browser.type_into(
        &format!("{} input[name=note]", form(&key30)),
        "new reconstruct pass",
    );
    browser.type_into(
        &format!("{} input[name=bug_url]", form(&key30)),
        "https://bugs.example/42",
    );
    browser.click(&format!("{} button", form(&key30)));
    let said = browser.wait_for(&format!(
        "const t = document.querySelector('{} .result').textContent; return t.startsWith('saved') || t.startsWith('HTTP') ? t : '';",
        form(&key30)
    ));
    assert!(
        said.as_str()
            .unwrap()
            .starts_with(&format!("saved for {} series", rows.len())),
        "{said}"
    );
    browser.screenshot(&shots.join("regressions-triaged.png"));

    // A new page load (a filter), the second group triaged without typing the token again.
    browser.goto(&format!("{origin}/regressions?state=new"));
    let left = browser.eval(GROUPS);
    assert_eq!(left.as_array().unwrap().len(), 1, "{left}");
    assert_eq!(left[0]["key"], key15);
    assert_eq!(
        browser.eval("return document.getElementById('token').hidden"),
        true
    );
    browser.eval(&format!(
        "document.querySelector('{}').elements.state.value = 'invalid'; return true;",
        form(&key15)
    ));
    browser.click(&format!("{} button", form(&key15)));
    let said = browser.wait_for(&format!(
        "const t = document.querySelector('{} .result').textContent; return t.startsWith('saved') || t.startsWith('HTTP') ? t : '';",
        form(&key15)
    ));
    assert!(said.as_str().unwrap().starts_with("saved for"), "{said}");

    // The store has every alert of both groups triaged, by the token's holder.
    {
        let mut c = store.pool.get().unwrap();
        let rows = c
            .query(
                "SELECT g.state, g.note, g.bug_url, g.updated_by, rb.commit_sha FROM regressions g JOIN runs rb ON rb.id = g.run_pk_before",
                &[],
            )
            .unwrap();
        for r in &rows {
            let before = r.string(4).unwrap();
            let want = if before == common::sha(29) {
                (
                    "acknowledged",
                    "new reconstruct pass",
                    "https://bugs.example/42",
                )
            } else {
                ("invalid", "", "")
            };
            assert_eq!(
                (r.str(0).unwrap(), r.str(1).unwrap(), r.str(2).unwrap()),
                want
            );
            assert_eq!(r.str(3).unwrap(), "write token");
        }
    }

    // Filters narrow the list: by adapter (picked in the form), by direction, by state.
    browser.goto(&format!("{origin}/regressions"));
    let second_id = browser.eval(&format!(
        "return Array.from(document.querySelectorAll('select[name=adapter] option')).find(o => o.textContent === '{}').value",
        common::SECOND
    ));
    browser.eval(&format!(
        "document.querySelector('select[name=adapter]').value = '{}'; return true;",
        second_id.as_str().unwrap()
    ));
    browser.click("#filters button");
    browser.wait_for("return location.search.includes('adapter=')");
    let second = browser.eval(GROUPS);
    let second = second.as_array().unwrap();
    assert_eq!(second.len(), 1, "{second:?}");
    assert!(second[0]["rows"]
        .as_array()
        .unwrap()
        .iter()
        .all(|r| r[0] == common::SECOND));
    assert!(second[0]["rows"].as_array().unwrap().len() < rows.len());
    browser.screenshot(&shots.join("regressions-filtered.png"));
    for (query, n) in [
        ("direction=better", 0),
        ("direction=worse", 2),
        ("state=invalid", 1),
        ("measure=gpu_ms.median&sort=size", 2),
    ] {
        browser.goto(&format!("{origin}/regressions?{query}"));
        let g = browser.eval(GROUPS);
        assert_eq!(g.as_array().unwrap().len(), n, "{query}: {g}");
        if query.starts_with("measure") {
            assert_eq!(g[0]["key"], key15, "largest change first");
            assert!(g[0]["rows"]
                .as_array()
                .unwrap()
                .iter()
                .all(|r| r[4] == "gpu_ms.median"));
        }
    }

    // One group's page: a chart per series, drawn.
    browser.goto(&format!("{origin}/regressions/groups/{key30}"));
    let page = browser.eval(INSPECT);
    let charts = page["charts"].as_array().unwrap();
    assert_eq!(charts.len(), rows.len().min(24));
    assert!(charts
        .iter()
        .all(|c| c["points"].as_u64() > Some(10) && c["change_points"] == 1));
    assert!(page["text"]
        .as_str()
        .unwrap()
        .contains("https://bugs.example/42"));
    browser.screenshot(&shots.join("alert-group.png"));
    browser.eval("document.querySelector('.charts').scrollIntoView(); return true;");
    browser.screenshot(&shots.join("alert-group-charts.png"));
    // Better (none in this history) has a colour of its own, also inside a link.
    let better = browser.eval(
        "const a = document.createElement('a'); a.href = '#'; a.innerHTML = '<span class=\"chg better\">x</span>'; document.querySelector('#regressions td').append(a); return getComputedStyle(a.firstChild).color;",
    );
    assert_eq!(better, "rgb(13, 107, 44)");
    assert_ne!(better, groups[0]["worse_colour"]);
    let console: Vec<String> = browser
        .console()
        .into_iter()
        .filter(|m| m.starts_with("SEVERE") || m.starts_with("WARNING"))
        .collect();
    assert!(console.is_empty(), "{console:?}");

    // The Markdown a bot pastes.
    let md = http(
        addr,
        "GET",
        &format!("/regressions/groups/{key30}.md"),
        None,
    );
    assert_eq!(md.status, 200);
    assert!(md.content_type.starts_with("text/markdown"));
    let md = String::from_utf8(md.body).unwrap();
    assert!(md.contains("state **acknowledged**") && md.contains("<https://bugs.example/42>"));

    // The Atom feed parses as Atom 1.0 with the elements RFC 4287 requires.
    let feed = http(addr, "GET", "/regressions/feed.atom", None);
    assert_eq!(feed.status, 200);
    assert!(
        feed.content_type.starts_with("application/atom+xml"),
        "{}",
        feed.content_type
    );
    let text = String::from_utf8(feed.body).unwrap();
    std::fs::write(shots.join("feed.atom"), &text).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    const ATOM: &str = "http://www.w3.org/2005/Atom";
    let root = doc.root_element();
    assert_eq!(
        (root.tag_name().namespace(), root.tag_name().name()),
        (Some(ATOM), "feed")
    );
    fn child<'a, 'i>(n: roxmltree::Node<'a, 'i>, name: &str) -> Option<roxmltree::Node<'a, 'i>> {
        n.children()
            .find(|c| c.tag_name().namespace() == Some(ATOM) && c.tag_name().name() == name)
    }
    let rfc3339 = |n: roxmltree::Node<'_, '_>| {
        let t = child(n, "updated").unwrap().text().unwrap();
        chrono::DateTime::parse_from_rfc3339(t).unwrap_or_else(|e| panic!("{t}: {e}"));
    };
    for name in ["id", "title", "updated", "author"] {
        assert!(child(root, name).is_some(), "feed without {name}");
    }
    rfc3339(root);
    assert!(root
        .children()
        .any(|c| c.has_tag_name((ATOM, "link")) && c.attribute("rel") == Some("self")));
    let entries: Vec<_> = root
        .children()
        .filter(|c| c.has_tag_name((ATOM, "entry")))
        .collect();
    assert_eq!(entries.len(), 2);
    let mut ids = BTreeSet::new();
    for e in &entries {
        for name in ["id", "title", "updated", "summary"] {
            assert!(child(*e, name).is_some(), "entry without {name}");
        }
        rfc3339(*e);
        assert!(ids.insert(child(*e, "id").unwrap().text().unwrap().to_string()));
        let link = e
            .children()
            .find(|c| c.has_tag_name((ATOM, "link")) && c.attribute("type") == Some("text/html"))
            .unwrap();
        let href = link.attribute("href").unwrap();
        let path = local(href, &origin).unwrap_or_else(|| panic!("{href}"));
        assert_eq!(http(addr, "GET", &path, None).status, 200, "{href}");
    }
    assert!(child(entries[0], "title")
        .unwrap()
        .text()
        .unwrap()
        .contains("series on 2 adapters"));
}
