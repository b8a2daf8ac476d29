//! The write path against the real `tessera-dashboard serve` process on a loopback port: 8
//! concurrent 60 MiB uploads without a valid token are refused (401 JSON) without the server's
//! resident memory growing by 50 MB, and 300 connections that send one byte and stall are closed
//! by the server within its header timeout, and bodies that stall or trickle get a 408 JSON error at
//! the body idle timeout or the request timeout. Also the `token` and `retention` commands. Raw sockets from plain threads keep the tests' own
//! cost low (the CI machine has 2 cores). Memory is the server's `VmRSS` from `/proc`.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

struct Server {
    child: Child,
    addr: SocketAddr,
    _dir: tempfile::TempDir,
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Server {
    /// `serve` on a temporary SQLite store and a free port; waits until it listens.
    fn start(extra: &[&str]) -> Server {
        let dir = tempfile::tempdir().unwrap();
        let db = dir.path().join("store.sqlite");
        let mut child = Command::new(env!("CARGO_BIN_EXE_tessera-dashboard"))
            .args(["serve", "--listen", "127.0.0.1:0", "--db"])
            .arg(&db)
            .args(extra)
            .env_remove("TESSERA_DASHBOARD_TOKEN")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
        let addr = loop {
            let line = lines
                .next()
                .expect("the server exited before listening")
                .unwrap();
            if let Some(a) = line.split("on http://").nth(1) {
                break a.trim().parse().unwrap();
            }
        };
        // Keep draining stderr so the server never blocks on a full pipe.
        std::thread::spawn(move || lines.for_each(drop));
        Server {
            child,
            addr,
            _dir: dir,
        }
    }

    fn rss_kib(&self) -> u64 {
        let status = std::fs::read_to_string(format!("/proc/{}/status", self.child.id())).unwrap();
        status
            .lines()
            .find_map(|l| l.strip_prefix("VmRSS:"))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
            .expect("VmRSS in /proc/<pid>/status")
    }

    /// A whole GET, answered with its status line and body.
    fn get(&self, path: &str) -> (String, String) {
        let mut s = TcpStream::connect(self.addr).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
        write!(
            s,
            "GET {path} HTTP/1.1\r\nHost: t\r\nConnection: close\r\n\r\n"
        )
        .unwrap();
        let mut text = String::new();
        s.read_to_string(&mut text).unwrap();
        split_response(&text)
    }
}

fn split_response(text: &str) -> (String, String) {
    let status = text.lines().next().unwrap_or("").to_string();
    let body = text.split_once("\r\n\r\n").map_or("", |b| b.1).to_string();
    (status, body)
}

#[test]
fn large_unauthenticated_uploads_are_refused_without_buffering() {
    const BODY: usize = 60 << 20;
    let server = Server::start(&["--token", "the-real-token"]);
    assert!(server.get("/healthz").0.contains("200"));
    std::thread::sleep(Duration::from_millis(300));
    let idle = server.rss_kib();

    // Sample the server's memory while the uploads run.
    let done = Arc::new(AtomicBool::new(false));
    let peak = Arc::new(AtomicU64::new(idle));
    let sampler = {
        let (done, peak) = (done.clone(), peak.clone());
        let pid = server.child.id();
        std::thread::spawn(move || {
            while !done.load(Ordering::Relaxed) {
                if let Ok(s) = std::fs::read_to_string(format!("/proc/{pid}/status")) {
                    if let Some(kib) = s
                        .lines()
                        .find_map(|l| l.strip_prefix("VmRSS:"))
                        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
                    {
                        peak.fetch_max(kib, Ordering::Relaxed);
                    }
                }
                std::thread::sleep(Duration::from_millis(5));
            }
        })
    };

    let start = Instant::now();
    let clients: Vec<_> = (0..8)
        .map(|i| {
            let addr = server.addr;
            std::thread::spawn(move || {
                let mut s = TcpStream::connect(addr).unwrap();
                s.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
                // Half send no token, half a wrong one.
                let auth = if i % 2 == 0 {
                    String::new()
                } else {
                    "Authorization: Bearer not-the-token\r\n".into()
                };
                write!(
                    s,
                    "POST /api/runs HTTP/1.1\r\nHost: t\r\nContent-Type: application/json\r\n{auth}Content-Length: {BODY}\r\n\r\n"
                )
                .unwrap();
                // Send the body as fast as the server takes it, while reading the answer.
                let mut w = s.try_clone().unwrap();
                w.set_write_timeout(Some(Duration::from_secs(30))).unwrap();
                let writer = std::thread::spawn(move || {
                    let chunk = vec![b'{'; 64 << 10];
                    let mut sent = 0;
                    while sent < BODY {
                        match w.write(&chunk[..chunk.len().min(BODY - sent)]) {
                            Ok(n) => sent += n,
                            Err(_) => break, // the server closed: expected once it answered
                        }
                    }
                    sent
                });
                let mut text = Vec::new();
                let _ = s.read_to_end(&mut text); // a reset after the answer is fine
                let sent = writer.join().unwrap();
                (String::from_utf8_lossy(&text).into_owned(), sent)
            })
        })
        .collect();
    let answers: Vec<(String, usize)> = clients.into_iter().map(|h| h.join().unwrap()).collect();
    let elapsed = start.elapsed();
    std::thread::sleep(Duration::from_millis(200));
    done.store(true, Ordering::Relaxed);
    sampler.join().unwrap();
    let peak = peak.load(Ordering::Relaxed);
    let after = server.rss_kib();

    for (i, (text, sent)) in answers.iter().enumerate() {
        let (status, body) = split_response(text);
        assert!(status.contains(" 401 "), "upload {i}: {status:?} {body:?}");
        assert!(text
            .to_ascii_lowercase()
            .contains("content-type: application/json"));
        let v: serde_json::Value = serde_json::from_str(&body)
            .unwrap_or_else(|e| panic!("upload {i}: not JSON ({e}): {body:?}"));
        assert!(v["error"].as_str().unwrap().contains("Bearer"), "{body}");
        assert!(
            *sent < BODY,
            "upload {i}: the server read the whole body ({sent} bytes)"
        );
    }
    let sent: Vec<usize> = answers.iter().map(|a| a.1 >> 10).collect();
    eprintln!(
        "8 x 60 MiB unauthenticated uploads: server VmRSS idle {} KiB, peak {} KiB (+{} KiB), after {} KiB; all 401 in {:.2} s; KiB sent before the server closed: {sent:?}",
        idle,
        peak,
        peak - idle,
        after,
        elapsed.as_secs_f64()
    );
    assert!(
        peak < idle + 50 * 1000,
        "the server grew from {idle} KiB to {peak} KiB"
    );
    assert!(server.get("/healthz").0.contains("200"), "still serving");
}

#[test]
fn slow_clients_are_dropped_at_the_header_timeout() {
    const N: usize = 300;
    const TIMEOUT: Duration = Duration::from_secs(2);
    const MARGIN: Duration = Duration::from_millis(1500);
    let server = Server::start(&["--header-timeout-secs", "2"]);
    let idle = server.rss_kib();

    // Each connection sends the first byte of a request and stalls.
    let mut conns: Vec<(TcpStream, Instant)> = (0..N)
        .map(|_| {
            let mut s = TcpStream::connect(server.addr).unwrap();
            s.write_all(b"P").unwrap();
            (s, Instant::now())
        })
        .collect();
    let opened = conns.last().unwrap().1 - conns[0].1;
    let held_rss = server.rss_kib();

    // One thread waits on each in turn: a closed connection reads as end of file (or a reset).
    let mut closed_after = Vec::with_capacity(N);
    for (i, (s, at)) in conns.iter_mut().enumerate() {
        let deadline = *at + TIMEOUT + MARGIN;
        let mut buf = [0u8; 512];
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            assert!(
                !left.is_zero(),
                "connection {i} still open {:?} after its byte",
                at.elapsed()
            );
            s.set_read_timeout(Some(left)).unwrap();
            match s.read(&mut buf) {
                Ok(0) => break,
                Ok(_) => continue, // an error answer before closing is allowed
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) =>
                {
                    continue
                }
                Err(_) => break, // reset
            }
        }
        closed_after.push(at.elapsed());
    }
    // Connections already closed when their turn came read at once: their times are upper bounds.
    let max = closed_after.iter().max().unwrap();
    let first = closed_after[0];
    eprintln!(
        "{N} slow connections (opened in {:.0} ms; server VmRSS {idle} KiB idle, {held_rss} KiB holding them): all closed; first closed after {:.2} s, latest observed {:.2} s (timeout {:?})",
        opened.as_secs_f64() * 1000.0,
        first.as_secs_f64(),
        max.as_secs_f64(),
        TIMEOUT
    );
    assert!(
        first >= TIMEOUT - Duration::from_millis(200),
        "closed after {first:?}, before the timeout: by something else?"
    );
    assert!(server.get("/healthz").0.contains("200"), "still serving");
}

/// Sends an upload head with a valid token and `Content-Length: 1000`, then `trickle` bytes of
/// body `every` apart; returns the answer and when it came, from the head.
fn stalled_upload(server: &Server, trickle: usize, every: Duration) -> (String, String, Duration) {
    let mut s = TcpStream::connect(server.addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(15))).unwrap();
    write!(
        s,
        "POST /api/runs HTTP/1.1\r\nHost: t\r\nAuthorization: Bearer t0ken\r\nContent-Type: application/json\r\nContent-Length: 1000\r\n\r\n{{"
    )
    .unwrap();
    let start = Instant::now();
    let mut w = s.try_clone().unwrap();
    let writer = std::thread::spawn(move || {
        for _ in 0..trickle {
            std::thread::sleep(every);
            if w.write_all(b" ").is_err() {
                break;
            }
        }
    });
    let mut text = Vec::new();
    let _ = s.read_to_end(&mut text);
    let at = start.elapsed();
    writer.join().unwrap();
    let (status, body) = split_response(&String::from_utf8_lossy(&text));
    (status, body, at)
}

#[test]
fn stalled_and_trickling_bodies_are_cut_off() {
    let server = Server::start(&[
        "--token",
        "t0ken",
        "--body-timeout-secs",
        "1",
        "--request-timeout-secs",
        "3",
    ]);
    // A body that stops: the body idle timeout (1 s).
    let (status, body, at) = stalled_upload(&server, 0, Duration::ZERO);
    eprintln!("stalled body: {status} after {at:?}: {body}");
    assert!(status.contains(" 408 "), "{status} {body}");
    assert!(
        serde_json::from_str::<serde_json::Value>(&body).unwrap()["error"]
            .as_str()
            .unwrap()
            .contains("paused")
    );
    assert!(
        at >= Duration::from_millis(900) && at < Duration::from_millis(2500),
        "{at:?}"
    );
    // A body that never pauses for long but never ends: the request timeout (3 s).
    let (status, body, at) = stalled_upload(&server, 12, Duration::from_millis(400));
    eprintln!("trickling body: {status} after {at:?}: {body}");
    assert!(status.contains(" 408 "), "{status} {body}");
    assert!(serde_json::from_str::<serde_json::Value>(&body).unwrap()["error"].is_string());
    assert!(
        at >= Duration::from_millis(2900) && at < Duration::from_millis(4500),
        "{at:?}"
    );
}

/// Runs the binary with `args`; returns the exit code, stdout and stderr.
fn cli(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_tessera-dashboard"))
        .args(args)
        .env_remove("TESSERA_DASHBOARD_DB")
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn token_and_retention_commands() {
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("s.sqlite");
    let db = db.to_str().unwrap();

    let (code, secret, err) = cli(&["token", "add", "ci", "--scope", "write", "--db", db]);
    assert_eq!(code, 0, "{err}");
    let secret = secret.trim();
    assert!(
        secret.starts_with("tsr_") && !secret.contains('\n'),
        "{secret}"
    );
    assert!(err.contains("shown only now"), "{err}");
    let (code, _, err) = cli(&["token", "add", "ci", "--scope", "read", "--db", db]);
    assert_eq!(code, 1);
    assert!(err.contains("exists"), "{err}");
    assert_eq!(
        cli(&["token", "add", "x", "--scope", "admin", "--db", db]).0,
        2
    );
    let (code, list, _) = cli(&["token", "list", "--db", db]);
    assert_eq!(code, 0);
    assert!(list.starts_with("ci\twrite\t"), "{list}");
    assert!(!list.contains(secret));
    assert_eq!(cli(&["token", "revoke", "ci", "--db", db]).0, 0);
    let (code, _, err) = cli(&["token", "revoke", "ci", "--db", db]);
    assert_eq!(code, 1);
    assert!(err.contains("not found"), "{err}");

    // Retention over the two committed runs (one adapter): dry run first.
    let fixtures = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/runs");
    assert_eq!(cli(&["import", fixtures, "--db", db]).0, 0);
    assert_eq!(cli(&["retention", "--db", db]).0, 2, "a rule is required");
    let (code, out, _) = cli(&["retention", "--keep-runs", "1", "--db", db]);
    assert_eq!(code, 0);
    assert!(
        out.starts_with("would delete ")
            && out.contains("1 runs would be deleted; nothing was changed"),
        "{out}"
    );
    let (_, again, _) = cli(&["retention", "--keep-runs", "1", "--db", db]);
    assert_eq!(again, out, "a dry run changes nothing");
    let (code, out, err) = cli(&["retention", "--keep-runs", "1", "--apply", "--db", db]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("deleted 1 runs"), "{out}");
    let (_, out, _) = cli(&["retention", "--keep-runs", "1", "--db", db]);
    assert!(out.starts_with("0 runs would be deleted"), "{out}");
}
