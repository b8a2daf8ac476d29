//! Expectations and approved frames, through the command line on the default adapter (lavapipe in
//! CI): `tessera run` honours a suite's `expectations.toml` (expected failures pass the run, an
//! unexpected pass fails it, `slow` waits for `--slow`, `no-perf` is recorded), `tessera
//! expectations update` turns a run with one new failure and one unexpected pass into a
//! two-entry diff, frame digests repeat across runs, and `--expect` fails a run whose frames
//! changed.

use std::path::{Path, PathBuf};
use std::process::Command;

use tessera_results::expectation::{Label, Outcome};
use tessera_results::ScenarioResult;

fn tessera(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_tessera"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

const SCENE: &str = r#"
resolution = [32, 24]
[frames]
warmup = 1
measured = 2
[[scene.objects]]
shape = "sphere"
position = [0, 0.5, 0]
color = [0.8, 0.3, 0.2]
[[scene.lights]]
type = "directional"
[camera]
[[camera.keyframes]]
time = 0
position = [0, 1, 4]
target = [0, 0.5, 0]
[[techniques]]
technique = "native"
[[techniques]]
technique = "upscale"
scale = 0.5
"#;

/// A gate no upscaled frame meets: the variant fails.
const FAILING_GATE: &str =
    "\n[[gates]]\nmeasure = \"psnr\"\nvariants = \"upscale*\"\nfail_below = 1000\n";

fn suite(dir: &Path) -> PathBuf {
    let s = dir.join("suite");
    std::fs::create_dir_all(&s).unwrap();
    std::fs::write(s.join("fails.toml"), format!("{SCENE}{FAILING_GATE}")).unwrap();
    std::fs::write(s.join("passes.toml"), SCENE).unwrap();
    s
}

/// The run folder a `tessera run` wrote (its stderr names it).
fn run_dir(stderr: &str) -> PathBuf {
    let line = stderr
        .lines()
        .find_map(|l| l.strip_prefix("results: "))
        .unwrap_or_else(|| panic!("no results line in: {stderr}"));
    PathBuf::from(line.trim())
}

fn scenario(run: &Path, name: &str) -> ScenarioResult {
    serde_json::from_str(
        &std::fs::read_to_string(run.join("scenarios").join(format!("{name}.json"))).unwrap(),
    )
    .unwrap()
}

fn run(suite: &Path, out: &Path, extra: &[&str]) -> (i32, String, String, PathBuf) {
    let mut args = vec![
        "run",
        suite.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ];
    args.extend_from_slice(extra);
    let (code, stdout, stderr) = tessera(&args);
    let dir = run_dir(&stderr);
    (code, stdout, stderr, dir)
}

#[test]
fn a_run_honours_expectations_and_the_update_is_a_two_entry_diff() {
    let dir = tempfile::tempdir().unwrap();
    let s = suite(dir.path());
    let out = dir.path().join("out");
    let exp = s.join("expectations.toml");

    // Without expectations: `fails` fails the run.
    let (code, _, _, _) = run(&s, &out, &[]);
    assert_eq!(code, 1);

    // `fails / upscale` expected to fail; `passes` slow; `fails / native` no-perf.
    std::fs::write(
        &exp,
        "# Known outcomes of this suite.\n\n[[expectation]]\nscenario = \"fails\"\nvariant = \"upscale*\"\nlabel = \"broken\"\nreason = \"no upscale reaches 1000 dB\"\n\n[[expectation]]\nscenario = \"fails\"\nvariant = \"native\"\nadapter = [\"vulkan\"]\nlabel = \"no-perf\"\nreason = \"timings of a test scene\"\n\n# Kept: a comment on the slow entry.\n[[expectation]]\nscenario = \"pass*\"\nlabel = \"slow\"\nreason = \"pretend it takes minutes\"\n",
    )
    .unwrap();
    let junit = dir.path().join("junit.xml");
    let (code, stdout, stderr, run1) = run(&s, &out, &["--junit", junit.to_str().unwrap()]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    assert!(
        stdout.contains("expected failure (broken: no upscale reaches 1000 dB): psnr"),
        "{stdout}"
    );
    assert!(
        stdout.contains("not run (slow: pretend it takes minutes)"),
        "{stdout}"
    );
    assert!(
        stdout.contains("expectations: 1 expected failures, 0 unexpected passes"),
        "{stdout}"
    );
    let fails = scenario(&run1, "fails");
    let up = fails
        .results
        .iter()
        .find(|r| r.variant != "native")
        .unwrap();
    let e = up.expectation.as_ref().unwrap();
    assert_eq!(
        (e.label, e.outcome),
        (Label::Broken, Outcome::ExpectedFailure)
    );
    assert!(e.source.ends_with("expectations.toml:3"), "{}", e.source);
    let native = &fails.results[0];
    assert_eq!(
        native.expectation.as_ref().map(|e| (e.label, e.outcome)),
        Some((Label::NoPerf, Outcome::Ran))
    );
    let passes = scenario(&run1, "passes");
    assert!(passes
        .results
        .iter()
        .all(
            |r| r.expectation.as_ref().unwrap().outcome == Outcome::NotRun
                && r.status.label() == "skipped"
        ));
    let xml = std::fs::read_to_string(&junit).unwrap();
    assert!(
        xml.contains("<skipped message=\"expected failure (broken: no upscale reaches 1000 dB, "),
        "{xml}"
    );
    assert!(
        xml.contains("<property name=\"expectation\" value=\"no-perf ("),
        "{xml}"
    );

    // `--slow` runs the slow scenario.
    let (code, stdout, _, _) = run(&s, &out, &["--slow"]);
    assert_eq!(code, 0);
    assert!(stdout.contains("passes ("), "{stdout}");

    // One new failure (`passes / upscale` now fails with no entry) and one unexpected pass
    // (`fails / upscale` now passes against its `broken` entry).
    std::fs::write(s.join("fails.toml"), SCENE).unwrap();
    std::fs::write(s.join("passes.toml"), format!("{SCENE}{FAILING_GATE}")).unwrap();
    let (code, stdout, _, run2) = run(&s, &out, &["--slow"]);
    assert_eq!(code, 1);
    assert!(
        stdout.contains("UNEXPECTED PASS: remove the entry at"),
        "{stdout}"
    );
    let before = std::fs::read_to_string(&exp).unwrap();
    let (code, diff, stderr) = tessera(&["expectations", "update", run2.to_str().unwrap()]);
    assert_eq!(code, 0, "{stderr}");
    let removed: Vec<&str> = diff
        .lines()
        .filter(|l| l.starts_with('-') && !l.starts_with("---"))
        .collect();
    let added: Vec<&str> = diff
        .lines()
        .filter(|l| l.starts_with('+') && !l.starts_with("+++"))
        .collect();
    assert_eq!(
        removed.iter().filter(|l| **l == "-[[expectation]]").count(),
        1,
        "{diff}"
    );
    assert!(
        removed.contains(&"-reason = \"no upscale reaches 1000 dB\""),
        "{diff}"
    );
    assert_eq!(
        added.iter().filter(|l| **l == "+[[expectation]]").count(),
        1,
        "{diff}"
    );
    assert!(added.contains(&"+scenario = \"passes\""), "{diff}");
    assert!(added.contains(&"+label = \"broken\""), "{diff}");
    assert!(added.contains(&"+adapter = \"llvmpipe\""), "{diff}");
    assert!(
        added.iter().any(|l| l.starts_with("+reason = \"psnr")),
        "{diff}"
    );
    let after = std::fs::read_to_string(&exp).unwrap();
    assert_ne!(before, after);
    assert!(
        after.contains("# Kept: a comment on the slow entry."),
        "{after}"
    );
    assert!(after.contains("# Known outcomes of this suite."), "{after}");
    // The refreshed file describes the run: the next one passes, and a second update is empty.
    let (code, stdout, _, run3) = run(&s, &out, &["--slow"]);
    assert_eq!(code, 0, "{stdout}");
    let (code, diff, _) = tessera(&["expectations", "update", run3.to_str().unwrap()]);
    assert_eq!((code, diff.as_str()), (0, ""));
}

#[test]
fn a_bad_expectations_file_is_exit_2_with_its_place() {
    let dir = tempfile::tempdir().unwrap();
    let s = suite(dir.path());
    std::fs::write(
        s.join("expectations.toml"),
        "[[expectation]]\nscenario = \"fails\"\nlabel = \"broke\"\nreason = \"x\"\n",
    )
    .unwrap();
    let (code, _, stderr) = tessera(&["run", s.to_str().unwrap(), "--quiet"]);
    assert_eq!(code, 2);
    assert!(
        stderr.contains("expectations.toml:3:9: `expectation[0].label`: unknown label \"broke\"; allowed: skip, slow, broken, flaky, no-perf"),
        "{stderr}"
    );
    let (code, _, stderr) = tessera(&[
        "expectations",
        "check",
        s.join("expectations.toml").to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
    assert!(stderr.contains("unknown label"), "{stderr}");
}

#[test]
fn digests_repeat_and_expect_catches_a_changed_colour() {
    let dir = tempfile::tempdir().unwrap();
    let s = suite(dir.path());
    std::fs::remove_file(s.join("fails.toml")).unwrap();
    let out = dir.path().join("out");
    let (code, _, _, a) = run(&s, &out, &[]);
    assert_eq!(code, 0);
    let (_, _, _, b) = run(&s, &out, &[]);
    let (ra, rb) = (scenario(&a, "passes"), scenario(&b, "passes"));
    for (x, y) in ra.results.iter().zip(&rb.results) {
        assert_eq!(x.frame_digests.len(), 2);
        assert!(x.frame_digests.iter().all(|d| d.len() == 64));
        assert_eq!(x.frame_digests, y.frame_digests, "{}", x.variant);
    }
    assert_ne!(ra.results[0].frame_digests, ra.results[1].frame_digests);

    // Approve run a's frames into the suite's digest file; run b matches them.
    let (code, stdout, stderr) = tessera(&["digests", "approve", a.to_str().unwrap()]);
    assert_eq!(code, 0, "{stderr}");
    let file = s.join("digests").join("llvmpipe.json");
    assert!(stdout.contains("4 frames approved"), "{stdout}");
    let expect = file.to_str().unwrap();
    let (code, stdout, _, _) = run(&s, &out, &["--expect", expect]);
    assert_eq!(code, 0, "{stdout}");
    assert!(stdout.contains("4 matched, 0 unapproved"), "{stdout}");

    // The same digests from a dashboard: `--expect URL` asks `/api/approved-frames?class=`.
    let body = std::fs::read_to_string(&file).unwrap();
    let (url, asked) = serve_once(body);
    let (code, stdout, _, _) = run(&s, &out, &["--expect", &url]);
    assert_eq!(code, 0, "{stdout}");
    assert!(stdout.contains("4 matched, 0 unapproved"), "{stdout}");
    let request = asked.join().unwrap();
    assert!(
        request.starts_with("GET /api/approved-frames?class=llvmpipe "),
        "{request}"
    );

    // One object's colour changes: every frame of the scenario is unapproved, exit 1.
    std::fs::write(
        s.join("passes.toml"),
        SCENE.replace("color = [0.8, 0.3, 0.2]", "color = [0.2, 0.3, 0.8]"),
    )
    .unwrap();
    let (code, stdout, stderr, _) = run(&s, &out, &["--expect", expect]);
    assert_eq!(code, 1, "{stdout}");
    assert!(stdout.contains("0 matched, 4 unapproved"), "{stdout}");
    assert!(
        stderr.contains("unapproved frame: passes / native frame 0: "),
        "{stderr}"
    );
    // A file of another adapter class is refused before the run.
    let (code, _, stderr) = tessera(&[
        "run",
        s.to_str().unwrap(),
        "--quiet",
        "--expect",
        expect,
        "--adapter-class",
        "nvidia",
    ]);
    assert_eq!(code, 2);
    assert!(
        stderr.contains("holds digests of adapter class `llvmpipe`"),
        "{stderr}"
    );
}

/// A one-request HTTP server answering `body` as JSON; returns its URL and the request line.
fn serve_once(body: String) -> (String, std::thread::JoinHandle<String>) {
    use std::io::{BufRead, BufReader, Write};
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let url = format!("http://{}", listener.local_addr().unwrap());
    let handle = std::thread::spawn(move || {
        let (mut stream, _) = listener.accept().unwrap();
        let mut reader = BufReader::new(stream.try_clone().unwrap());
        let mut first = String::new();
        reader.read_line(&mut first).unwrap();
        loop {
            let mut line = String::new();
            if reader.read_line(&mut line).unwrap() == 0 || line == "\r\n" {
                break;
            }
        }
        write!(
            stream,
            "HTTP/1.1 200 OK\r\ncontent-type: application/json\r\ncontent-length: {}\r\nconnection: close\r\n\r\n{body}",
            body.len()
        )
        .unwrap();
        first
    });
    (url, handle)
}
