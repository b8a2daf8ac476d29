//! Browser tests: the dashboard served on a loopback port from a temporary SQLite store, every page
//! type loaded in headless Chromium (driven over WebDriver by chromedriver) at 1400 px wide, canvas
//! charts checked as painted (pixels read back) with axis labels and a legend, no error text and
//! no console errors, images displayed at no less than their natural size, and every same-origin
//! link and image of every page reached by crawling answers 200. Chart zoom, the viewer's zoom,
//! wipe, A/B flicker and frame slider are driven by the test. A screenshot of each page type is
//! kept in `target/browser-screenshots/`.
//!
//! The store holds the committed real lavapipe runs (imported with `import`: the `tiny` runs and two
//! runs of a smoke suite with FLIP heat maps and a shading-rate image), plus runs derived
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
                    "--disable-dev-shm-usage", "--window-size=1400,1000",
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

    /// A PNG of the viewport.
    fn screenshot(&self) -> Vec<u8> {
        use base64::Engine;
        let v = self.call("GET", "screenshot", None);
        base64::engine::general_purpose::STANDARD
            .decode(v.as_str().unwrap_or_default())
            .unwrap_or_default()
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
    fn screenshot_to(&self, path: &Path) {
        let png = self.screenshot();
        assert!(!png.is_empty(), "no screenshot for {}", path.display());
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
  images: Array.from(document.images).map(i => ({src: i.src, ok: i.complete && i.naturalWidth > 0, hidden: !!i.closest('[hidden]'),
    natural: i.naturalWidth, shown: i.getBoundingClientRect().width})),
  canvases: Array.from(document.querySelectorAll('.chart')).map(c => {
    const cv = c.querySelector('canvas');
    const u = c.uplot;
    if (!cv || !u) return {drawn: false};
    const px = cv.getContext('2d').getImageData(0, 0, cv.width, cv.height).data;
    let painted = 0;
    for (let i = 3; i < px.length; i += 4) if (px[i] > 0) painted++;
    const spec = JSON.parse(document.getElementById(c.dataset.chart).textContent);
    return {drawn: true, width: cv.getBoundingClientRect().width, painted, rows: u.data[0].length,
      changes: (spec.marks || []).filter(m => m.kind === 'change').length,
      fronts: (spec.points || []).filter(p => p.front).length,
      bands: (u.bands || []).length,
      x_labels: (u.axes[0]._values || []).filter(v => v !== '' && v != null).length,
      y_labels: (u.axes[1]._values || []).filter(v => v !== '' && v != null).length,
      legend: Array.from(c.querySelectorAll('.u-legend .u-series .u-label')).map(l => l.textContent),
      // Where the legend's rows start, from the chart's left edge (left-aligned: a few px), and
      // the legend's value cells shown.
      legend_left: Math.min(...Array.from(c.querySelectorAll('.u-legend .u-series')).map(r => r.getBoundingClientRect().left)) - c.getBoundingClientRect().left,
      legend_values: Array.from(c.querySelectorAll('.u-legend .u-value')).filter(v => v.offsetParent !== null).length};
  }),
  overflow: Math.max(0, ...Array.from(document.querySelectorAll('main table')).map(t => t.getBoundingClientRect().right)) - window.innerWidth,
  tables: Array.from(document.querySelectorAll('main table')).map(t => ({id: t.id, rows: t.rows.length})),
  forms: document.forms.length,
};
"#;

// ---------------------------------------------------------------------------------------------
// The store and the server.

const SECOND_ADAPTER: &str = "llvmpipe (second adapter, derived from a real run)";

/// The two real runs of the smoke suite (with heat maps and a shading-rate image).
fn viewer_fixtures() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/viewer-runs")
}

/// Imports the real fixture runs, then the derived runs described at the top.
/// Returns the run ids of the `tiny` fixture runs and of the smoke runs, oldest first.
fn fill(pool: &tessera_dashboard::db::Pool) -> (Vec<String>, Vec<String>) {
    let summary = import(pool, &common::fixtures(), &Params::default()).unwrap();
    assert!(
        summary.failed.is_empty() && summary.stored >= 2,
        "{summary:?}"
    );
    let smoke = import(pool, &viewer_fixtures(), &Params::default()).unwrap();
    assert!(smoke.failed.is_empty() && smoke.stored == 2, "{smoke:?}");
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
    let names = |d: PathBuf| -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    };
    (names(common::fixtures()), names(viewer_fixtures()))
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
        ["compare", "runs"] => "run comparison",
        ["assets", _] => "asset",
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
    let (tiny_runs, smoke_runs) = fill(&store.pool);
    let real_runs: Vec<String> = tiny_runs.iter().chain(&smoke_runs).cloned().collect();
    let shots = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target/browser-screenshots");
    let _ = std::fs::remove_dir_all(&shots);
    std::fs::create_dir_all(&shots).unwrap();
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
    // The native frame-time series of `tiny` has the 22-run history with the step.
    let found: Value = serde_json::from_slice(
        &http(
            addr,
            "GET",
            "/api/series?scenario=tiny&variant=native&measure=gpu_ms.median&adapter=1",
            None,
        )
        .body,
    )
    .unwrap();
    let stepped = format!("/series/{}", found[0]["id"].as_i64().expect("tiny series"));
    for p in ["/", "/series", "/regressions", "/compare", "/pareto"]
        .into_iter()
        .map(String::from)
        .chain([stepped.clone()])
        .chain(real_runs.iter().map(|r| format!("/runs/{r}")))
        .chain(
            tiny_runs
                .iter()
                .map(|r| format!("/runs/{r}/images/tiny/native")),
        )
        .chain([
            format!("/compare/runs?a={}&b={}", smoke_runs[0], smoke_runs[1]),
            format!(
                "/runs/{}/images/basic/checkerboard%5Bsampling%3Dtwo-pass%5D",
                smoke_runs[1]
            ),
            format!(
                "/runs/{}/images/adaptive/adaptive-shading%5Bthreshold%3D0.5%5D",
                smoke_runs[1]
            ),
            "/compare/runs".to_string(),
        ])
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
        let n = loaded.iter().filter(|(p, _)| page_type(p) == kind).count();
        if n < 2 {
            let name = format!("{}-{n}.png", kind.replace(' ', "-"));
            std::fs::write(shots.join(name), browser.screenshot()).unwrap();
        }
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
            if img["hidden"].as_bool().unwrap_or(false) {
                continue;
            }
            if !img["ok"].as_bool().unwrap_or(false) {
                problems.push(format!("{path}: image did not decode: {img}"));
            }
            let (natural, shown) = (
                img["natural"].as_f64().unwrap_or(0.0),
                img["shown"].as_f64().unwrap_or(0.0),
            );
            if shown + 0.5 < natural {
                problems.push(format!(
                    "{path}: image shown at {shown} px, below its natural {natural} px: {img}"
                ));
            }
        }
        for (i, c) in page["canvases"]
            .as_array()
            .into_iter()
            .flatten()
            .enumerate()
        {
            let ok = c["drawn"] == true
                && c["painted"].as_u64().unwrap_or(0) > 1000
                && c["x_labels"].as_u64().unwrap_or(0) >= 2
                && c["y_labels"].as_u64().unwrap_or(0) >= 2
                && c["legend"].as_array().is_some_and(|l| l.len() >= 2);
            if !ok {
                problems.push(format!(
                    "{path}: canvas chart {i} not painted with axis labels and legend: {c}"
                ));
            }
            // The legend's rows start at the chart's left edge, one under the other, not
            // centred under it with each line starting elsewhere.
            if c["legend_left"].as_f64().is_none_or(|l| l > 12.0) {
                problems.push(format!(
                    "{path}: canvas chart {i}'s legend is not at its left edge: {c}"
                ));
            }
        }
        if page["overflow"].as_f64().unwrap_or(0.0) > 0.5 {
            problems.push(format!(
                "{path}: a table runs {} px past the 1400 px window",
                page["overflow"]
            ));
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
    let canvas_sum = |pages: &[&Value], key: &str| -> u64 {
        pages
            .iter()
            .flat_map(|p| p["canvases"].as_array().cloned().unwrap_or_default())
            .map(|c| c[key].as_u64().unwrap_or(0))
            .sum()
    };
    // Series: a canvas chart over every run of the series (22 on the first adapter) with the
    // change point marked and the p5-p95 band of the stored samples.
    let series = of("series");
    assert!(
        series.iter().any(|p| canvas_sum(&[p], "rows") >= 22
            && canvas_sum(&[p], "changes") >= 1
            && canvas_sum(&[p], "bands") >= 1),
        "no series chart with 22 runs, a change point and a band: {:?}",
        series.iter().map(|p| &p["canvases"]).collect::<Vec<_>>()
    );
    assert!(series.iter().all(|p| canvas_sum(&[p], "painted") > 0));
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
    // The viewer on a smoke run with a reference: zoom to 8x (pixels stay square, panes scroll
    // together), wipe to 25%, flicker to the reference with the F key, step the frame slider.
    browser.goto(&format!(
        "{origin}/runs/{}/images/basic/checkerboard%5Bsampling%3Dtwo-pass%5D",
        smoke_runs[1]
    ));
    let v = browser.eval(
        r#"
const root = document.getElementById('viewer');
const img = root.querySelector('img[data-kind="output"]');
const natural = img.naturalWidth;
const zoom = document.getElementById('zoom');
zoom.value = 8; zoom.dispatchEvent(new Event('input'));
const zoomed = img.getBoundingClientRect().width;
const rendering = getComputedStyle(img).imageRendering;
const panes = root.querySelectorAll('.pane');
panes[0].scrollLeft = 200; panes[0].dispatchEvent(new Event('scroll'));
const synced = panes[panes.length - 1].scrollLeft;
const wipe = document.getElementById('wipe');
wipe.value = 25; wipe.dispatchEvent(new Event('input'));
const clip = document.getElementById('wipe-top').style.clipPath;
const ab = document.getElementById('img-ab');
const before = ab.src;
document.dispatchEvent(new KeyboardEvent('keydown', {key: 'f', bubbles: true}));
const after = ab.src;
const label = document.getElementById('ab-label').textContent;
const ref = root.querySelector('img[data-kind="reference"]').src;
const frame = document.getElementById('frame');
frame.value = frame.max; frame.dispatchEvent(new Event('input'));
return {natural, zoomed, rendering, synced, clip, before, after, label, ref,
        frameno: document.getElementById('frameno').textContent,
        heatmaps: root.querySelectorAll('img[data-kind="heatmap"]').length};
"#,
    );
    std::fs::write(shots.join("images-zoomed-8x.png"), browser.screenshot()).unwrap();
    // The wipe shows the reference on the side its caption names (the top, clipped image is the
    // reference, visible left of the line), and the per-frame charts follow the frame slider
    // (set to the last saved frame above).
    let w = browser.eval(
        r#"
const root = document.getElementById('viewer');
const top = document.getElementById('wipe-top');
const svgs = Array.from(root.querySelectorAll('.frame-chart svg'));
const spec = JSON.parse(document.getElementById('viewer-data').textContent);
const last = spec.frames[spec.frames.length - 1];
return {
  top: top.dataset.kind, caption: document.getElementById('wipe-caption').textContent,
  left: document.getElementById('wipe-stack').dataset.left,
  charts: svgs.length,
  markers: svgs.map(s => [+s.querySelector('.frame-marker').getAttribute('x1'),
                          +s.dataset.x0 + (last - +s.dataset.f0) * +s.dataset.dx]),
  pair: getComputedStyle(document.getElementById('pair')).gridTemplateColumns.split(' ').length,
};
"#,
    );
    assert_eq!(w["top"], "reference", "wipe: {w}");
    assert_eq!(w["left"], "reference", "wipe: {w}");
    assert!(
        w["caption"]
            .as_str()
            .unwrap_or("")
            .contains("A (reference) left"),
        "wipe caption: {w}"
    );
    assert!(w["charts"].as_u64() >= Some(2), "per-frame charts: {w}");
    for m in w["markers"].as_array().unwrap() {
        let (got, want) = (m[0].as_f64().unwrap(), m[1].as_f64().unwrap());
        assert!(
            (got - want).abs() < 0.2 && got > 52.5,
            "the marker follows the slider: {w}"
        );
    }
    assert_eq!(w["pair"], 2, "A and B side by side: {w}");

    // At 390 px (a phone): the viewport tag, and no horizontal scroll on the runs, run,
    // regressions, alert group, comparison, adapters, error-against-time and image viewer pages.
    let groups: Value =
        serde_json::from_slice(&http(addr, "GET", "/api/regressions/groups?status=all", None).body)
            .unwrap();
    let group = format!(
        "/regressions/groups/{}",
        groups[0]["id"].as_i64().expect("an alert group")
    );
    browser.call(
        "POST",
        "window/rect",
        Some(json!({"width": 390, "height": 844})),
    );
    for (name, path) in [
        ("runs", "/".to_string()),
        ("run", format!("/runs/{}", smoke_runs[1])),
        ("regressions", "/regressions".to_string()),
        ("group", group.clone()),
        (
            "compare",
            format!("/compare/runs?a={}&b={}", smoke_runs[0], smoke_runs[1]),
        ),
        ("adapters", "/compare".to_string()),
        ("pareto", "/pareto".to_string()),
        (
            "viewer",
            format!(
                "/runs/{}/images/basic/checkerboard%5Bsampling%3Dtwo-pass%5D",
                smoke_runs[1]
            ),
        ),
    ] {
        browser.goto(&format!("{origin}{path}"));
        let n = browser.eval(NARROW);
        // Saved first, so a failing check leaves the picture to look at.
        std::fs::write(
            shots.join(format!("narrow-390-{name}.png")),
            browser.screenshot(),
        )
        .unwrap();
        // Nothing is cut off: no group heading, per-frame chart or alert table reaches past the
        // window or hides in a box that scrolls (the alert rows stack at this width).
        assert_eq!(n["clipped"], json!([]), "{name} at 390 px: {n}");
        // Names wrap at their separators, never inside a word.
        assert_eq!(n["broken_names"], json!([]), "{name} at 390 px: {n}");
        match name {
            "regressions" => assert!(n["groups"].as_u64() >= Some(1), "{n}"),
            "group" => assert!(n["group_charts"].as_u64() >= Some(1), "{n}"),
            "run" => assert!(n["frame_charts"].as_u64() >= Some(6), "{n}"),
            "compare" => assert!(n["names"].as_u64() >= Some(8), "{n}"),
            _ => {}
        }
        assert_eq!(n["viewport"], true, "{name}: {n}");
        assert!(
            n["scroll"].as_f64().unwrap() <= n["inner"].as_f64().unwrap(),
            "{name} scrolls sideways at 390 px: {n}"
        );
    }
    browser.call(
        "POST",
        "window/rect",
        Some(json!({"width": 1400, "height": 1000})),
    );
    // The alert group page at 1400 px as well: its charts and tables inside the window, no
    // sideways scroll.
    browser.goto(&format!("{origin}{group}"));
    let n = browser.eval(NARROW);
    std::fs::write(shots.join("wide-1400-group.png"), browser.screenshot()).unwrap();
    assert_eq!(n["clipped"], json!([]), "group at 1400 px: {n}");
    assert!(n["group_charts"].as_u64() >= Some(1), "{n}");
    assert!(
        n["scroll"].as_f64().unwrap() <= n["inner"].as_f64().unwrap(),
        "the group page scrolls sideways at 1400 px: {n}"
    );
    // The run page's per-frame charts: a line per variant, and a worst frame that was saved
    // (the harness saves each metric's worst frame) opens the viewer at that frame.
    browser.goto(&format!("{origin}/runs/{}", smoke_runs[1]));
    let r = browser.eval(
        "const a = document.querySelector('.run-frame-chart ul.legend a[href*=\"#f=\"]'); \
         return {charts: document.querySelectorAll('.run-frame-chart').length, \
         lines: document.querySelectorAll('.run-frame-chart polyline').length, \
         worst: a ? a.getAttribute('href') : null};",
    );
    std::fs::write(shots.join("run-frame-charts.png"), browser.screenshot()).unwrap();
    assert!(
        r["charts"].as_u64() >= Some(8),
        "run page per-frame charts: {r}"
    );
    assert!(r["lines"].as_u64() >= r["charts"].as_u64(), "{r}");
    let worst = r["worst"]
        .as_str()
        .expect("a worst frame links to the viewer");
    let frame = worst.rsplit_once("#f=").unwrap().1.to_string();
    browser.goto(&format!("{origin}{worst}"));
    let opened = browser
        .wait_for("const n = document.querySelector('#frameno'); return n && n.textContent;");
    assert_eq!(opened.as_str(), Some(frame.as_str()), "{worst}");
    let natural = v["natural"].as_f64().unwrap_or(0.0);
    assert!(natural > 0.0, "viewer: {v}");
    assert_eq!(v["zoomed"].as_f64(), Some(natural * 8.0), "zoom 8x: {v}");
    assert_eq!(v["rendering"], "pixelated", "{v}");
    assert!(
        v["synced"].as_f64().unwrap_or(0.0) > 0.0,
        "panes pan together: {v}"
    );
    assert_eq!(v["clip"], "inset(0px 75% 0px 0px)", "wipe: {v}");
    assert!(
        v["before"] != v["after"] && v["after"] == v["ref"],
        "flicker to A: {v}"
    );
    assert_eq!(v["label"], "A: reference", "{v}");
    assert_eq!(
        v["frameno"], "5",
        "frame slider reaches the last saved frame: {v}"
    );
    assert!(
        v["heatmaps"].as_u64() >= Some(1),
        "FLIP heat map shown: {v}"
    );
    // The shading-rate image and its overlay on the adaptive-shading viewer.
    browser.goto(&format!(
        "{origin}/runs/{}/images/adaptive/adaptive-shading%5Bthreshold%3D0.5%5D",
        smoke_runs[1]
    ));
    let rate =
        browser.eval("return document.querySelectorAll('#viewer img[data-kind=\"rate\"]').length;");
    assert!(
        rate.as_u64() >= Some(2),
        "rate image alone and over the variant: {rate}"
    );
    std::fs::write(shots.join("images-adaptive.png"), browser.screenshot()).unwrap();

    // Chart zoom on a series page: the mouse wheel and a drag both narrow the x range.
    let series_url = series
        .iter()
        .find(|p| canvas_sum(&[p], "rows") >= 22)
        .map(|p| p["url"].as_str().unwrap().to_string())
        .unwrap();
    browser.goto(&series_url);
    let z = browser.eval(
        r#"
// uPlot applies scale changes in a microtask: wait a little after each step.
const tick = () => new Promise(r => setTimeout(r, 50));
return (async () => {
const u = document.querySelector('.chart').uplot;
const r = u.over.getBoundingClientRect();
const full = u.scales.x.max - u.scales.x.min;
u.over.dispatchEvent(new WheelEvent('wheel', {deltaY: -100, clientX: r.left + r.width / 2, clientY: r.top + 10, bubbles: true, cancelable: true}));
await tick();
const wheeled = u.scales.x.max - u.scales.x.min;
u.setScale('x', {min: u.data[0][0], max: u.data[0][u.data[0].length - 1]});
await tick();
return {full, wheeled, left: r.left, top: r.top, width: r.width, height: r.height};
})();
"#,
    );
    // A real drag (WebDriver pointer actions) over 30% of the plot selects a range to zoom into.
    let (l, t, w, h) = (
        z["left"].as_f64().unwrap(),
        z["top"].as_f64().unwrap(),
        z["width"].as_f64().unwrap(),
        z["height"].as_f64().unwrap(),
    );
    let at = |f: f64| json!({"type": "pointerMove", "duration": 100, "origin": "viewport", "x": (l + w * f) as i64, "y": (t + h / 2.0) as i64});
    browser.call(
        "POST",
        "actions",
        Some(json!({"actions": [{"type": "pointer", "id": "mouse", "parameters": {"pointerType": "mouse"},
            "actions": [at(0.2), {"type": "pointerDown", "button": 0}, at(0.35), at(0.5), {"type": "pointerUp", "button": 0}]}]})),
    );
    let dragged = browser.eval(
        "return new Promise(r => setTimeout(() => { const u = document.querySelector('.chart').uplot; r(u.scales.x.max - u.scales.x.min); }, 100));",
    );
    let z = json!({"full": z["full"], "wheeled": z["wheeled"], "dragged": dragged});
    let full = z["full"].as_f64().unwrap_or(0.0);
    assert!(full > 0.0, "{z}");
    assert!(
        z["wheeled"].as_f64().unwrap_or(full) < full * 0.9,
        "wheel zoom: {z}"
    );
    assert!(
        z["dragged"].as_f64().unwrap_or(full) < full * 0.5,
        "drag zoom: {z}"
    );
    std::fs::write(shots.join("series-zoomed.png"), browser.screenshot()).unwrap();
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
            .any(|p| canvas_sum(&[p], "rows") >= 3 && canvas_sum(&[p], "fronts") >= 1),
        "error-vs-time chart without points and front: {}",
        pareto[0]["canvases"]
    );
    // Its legend names the runs and their fronts without values: no "run …: –" under it (the
    // values under the cursor are in the hover line).
    for p in &pareto {
        for c in p["canvases"].as_array().into_iter().flatten() {
            assert_eq!(
                c["legend_values"], 0,
                "error-vs-time legend with values: {c}"
            );
        }
    }
    // The default view is not empty: the scenario's metrics are offered and one is shown.
    assert!(
        pareto[0]["text"].as_str().unwrap().contains("on front"),
        "default error-vs-time view is empty: {}",
        pareto[0]["text"]
    );
    let compared = of("run comparison");
    assert!(
        compared.iter().any(|p| {
            let t = p["text"].as_str().unwrap();
            t.contains("checkerboard") && t.contains("Mann-Whitney") && t.contains("permalink")
        }),
        "compare page of the two smoke runs: {}",
        compared[0]["text"]
    );
    assert!(
        runs[0]["text"].as_str().unwrap().contains("smoke-viewer"),
        "runs list shows the suite"
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

/// What a page shows at 390 px: its width and scroll width, the viewport tag; the elements cut
/// off (group headings, alert tables, a group's series charts and their headings, per-frame
/// charts and their legends reaching past the window,
/// or boxes that hide their content in a horizontal scroll, the run page's wide tables aside);
/// and names broken inside a word: a `span.name` narrower than its widest unbreakable part
/// (between the separators it may wrap after).
const NARROW: &str = r#"
const inner = window.innerWidth;
const clipped = [];
const right = el => el.getBoundingClientRect().right;
for (const el of document.querySelectorAll('#regressions h2, #regressions .meta, #regressions tr.series-row, .run-frame-chart, .run-frame-chart ul.legend, .charts h3, .charts svg')) {
  if (right(el) > inner + 0.5) clipped.push(el.tagName + '.' + el.className + ' right ' + right(el));
}
for (const el of document.querySelectorAll('#regressions')) {
  if (el.scrollWidth > el.clientWidth + 1) clipped.push('#regressions scrolls: ' + el.scrollWidth + ' > ' + el.clientWidth);
}
const canvas = document.createElement('canvas').getContext('2d');
const broken = [];
const names = document.querySelectorAll('span.name');
for (const n of names) {
  const st = getComputedStyle(n);
  canvas.font = st.fontWeight + ' ' + st.fontSize + ' ' + st.fontFamily;
  const parts = n.textContent.split(/(?<=[\[,;\/])/);
  const widest = Math.max(...parts.map(p => canvas.measureText(p).width));
  const box = n.getBoundingClientRect();
  if (box.width + 1 < widest) broken.push(n.textContent + ': ' + box.width.toFixed(1) + ' < ' + widest.toFixed(1));
}
return {inner, scroll: document.documentElement.scrollWidth,
  viewport: !!document.querySelector('meta[name=viewport][content*="width=device-width"]'),
  clipped, broken_names: broken, names: names.length,
  groups: document.querySelectorAll('#regressions tbody.group').length,
  group_charts: document.querySelectorAll('.charts svg').length,
  frame_charts: document.querySelectorAll('.run-frame-chart svg polyline').length};
"#;

/// Where the screenshots of the browser tests are kept (under the workspace's `target/`).
fn artefacts() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/test-artefacts/browser")
}

/// What the regressions page shows: its groups, each with its key, state badge and series rows.
const GROUPS: &str = r#"
return Array.from(document.querySelectorAll('#regressions tbody.group')).map(g => ({
  key: g.dataset.key,
  id: g.id.slice(2),
  title: g.querySelector('h2').textContent,
  state: g.querySelector('[data-state-of]').textContent,
  rows: Array.from(g.querySelectorAll('tr.series-row')).map(r => Array.from(r.cells).map(c => c.textContent)),
  row_background: getComputedStyle(g.querySelector('tr.series-row')).backgroundColor,
  worse_colour: (g.querySelector('.chg.worse') ? getComputedStyle(g.querySelector('.chg.worse')).color : ''),
  link_colour: getComputedStyle(g.querySelector('tr.series-row a')).color,
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
    // Series rows keep the page's background: only the change cell carries worse/better colour
    // (a class shared with the runs list's red alert badge once painted whole rows red).
    assert_eq!(
        groups[0]["row_background"], "rgba(0, 0, 0, 0)",
        "{:?}",
        groups[0]
    );
    let adapters: BTreeSet<&str> = rows.iter().map(|r| r[0].as_str().unwrap()).collect();
    assert_eq!(adapters.len(), 2, "{adapters:?}");
    assert!(rows
        .iter()
        .all(|r| r[7].as_str().unwrap().contains("worse")));
    // Worse is red whatever colour links have.
    assert_eq!(groups[0]["worse_colour"], "rgb(161, 20, 15)");
    assert_ne!(groups[0]["link_colour"], groups[0]["worse_colour"]);
    assert!(groups.iter().all(|g| g["state"] == "new"));
    browser.screenshot_to(&shots.join("regressions.png"));

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
    browser.screenshot_to(&shots.join("regressions-triaged.png"));

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
            assert_eq!(r.str(3).unwrap(), "legacy");
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
    browser.screenshot_to(&shots.join("regressions-filtered.png"));
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
    browser.screenshot_to(&shots.join("alert-group.png"));
    browser.eval("document.querySelector('.charts').scrollIntoView(); return true;");
    browser.screenshot_to(&shots.join("alert-group-charts.png"));
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
    // An old commit-range URL answers 308 to the group's id, for life.
    let moved = http(
        addr,
        "GET",
        &format!("/regressions/groups/{key30}.md"),
        None,
    );
    assert_eq!(moved.status, 308);
    let id30 = groups[0]["id"].as_str().unwrap_or_default().to_string();
    let md = http(addr, "GET", &format!("/regressions/groups/{id30}.md"), None);
    assert_eq!(md.status, 200, "{id30}");
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

/// A frame wider than its pane (a 3840x2160 scenario) opens fitted to the pane, whole, and `fit`
/// returns there after a zoom; a series of one point gets an x axis of a day, not of years.
#[test]
fn a_4k_frame_opens_fitted_and_a_one_point_series_has_a_day_wide_axis() {
    let Some((chromium, chromedriver)) = browser_tools() else {
        return;
    };
    let store = common::sqlite();
    let folder = tessera_dashboard::import::find_run_folders(&viewer_fixtures())
        .unwrap()
        .remove(0);
    let mut run = RunBundle::read_folder(&folder).unwrap();
    for s in &mut run.scenarios {
        (s.width, s.height) = (3840, 2160);
    }
    {
        let mut conn = store.pool.get().unwrap();
        ingest(&mut *conn, &run).unwrap();
    }
    let addr = serve(AppState::new(store.pool.clone(), None));
    let browser = Browser::start(&chromium, &chromedriver);
    browser.goto(&format!(
        "http://{addr}/runs/{}/images/basic/checkerboard%5Bsampling%3Dtwo-pass%5D",
        run.run.run_id
    ));
    let state = || {
        browser.eval(
            "const v = document.getElementById('viewer'); const p = v.querySelector('.pane'); \
             const i = v.querySelector('img.px'); \
             return {zoom: +v.dataset.zoom, img: i.getBoundingClientRect().width, pane: p.clientWidth, \
                     label: document.getElementById('zoomval').textContent};",
        )
    };
    // The whole 3840 px width in the pane: zoom below 1, the image as wide as the pane.
    let fitted = || {
        let s = state();
        let zoom = s["zoom"].as_f64().unwrap();
        assert!(zoom < 1.0 && zoom > 0.0, "{s}");
        let (img, pane) = (s["img"].as_f64().unwrap(), s["pane"].as_f64().unwrap());
        assert!(img <= pane + 1.0 && img >= pane * 0.9, "{s}");
        assert!(s["label"].as_str().unwrap().ends_with("% (fit)"), "{s}");
    };
    fitted();
    browser.eval("document.getElementById('viewer').viewer.setZoom(4); return 0;");
    assert_eq!(state()["zoom"].as_f64().unwrap(), 4.0);
    browser.eval("document.getElementById('fit').click(); return 0;");
    fitted();

    // One run: every series has one point. Its time axis spans a day around it.
    browser.goto(&format!("http://{addr}/series/1"));
    let span = browser.eval(
        "const c = document.querySelector('[data-chart]'); const u = c.uplot; \
         return u ? u.scales.x.max - u.scales.x.min : -1;",
    );
    let span = span.as_f64().unwrap();
    assert!(
        span > 0.0 && span <= 2.0 * 86_400.0,
        "x axis spans {span} s"
    );
}
