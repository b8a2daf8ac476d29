//! The queue drained by runner processes, not threads: this test binary runs again as four
//! claimer processes on one store, after a fifth that claimed a job was killed with SIGKILL while
//! holding it. Every job runs exactly once (counted from what the processes print and from the
//! store), the killed runner's job once more, and not before its lease ran out. On SQLite and,
//! when configured, PostgreSQL.

mod common;

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use tessera_dashboard::db;
use tessera_dashboard::store::queue::{self, JobStatus, NewJob};
use tessera_results::queue::{Arm, Completion, JobKind, JobSpec, Registration};

const TEST: &str = "four_runner_processes_drain_400_jobs_after_one_is_killed";
/// `MODE<TAB>STORE<TAB>RUNNER_ID` makes this binary a claimer process (mode `hold` or `drain`).
const CHILD: &str = "TESSERA_QUEUE_CLAIMER";
/// The killed runner's lease.
const HOLD_LEASE_MS: i64 = 1_500;
/// How long a drainer waits before it asks again while a job is in progress elsewhere.
const POLL_MS: u64 = 50;

fn now_ms() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap()
        .as_millis() as i64
}

fn spec(i: usize) -> JobSpec {
    JobSpec {
        kind: JobKind::Run,
        scenarios: vec!["scenarios/smoke".into()],
        variant: None,
        arms: vec![Arm {
            name: "run".into(),
            commit: format!("{:040x}", i + 1),
            env: BTreeMap::new(),
        }],
        order: vec![0],
        list_commits: None,
    }
}

fn registration(name: &str) -> Registration {
    Registration {
        name: name.into(),
        labels: vec!["llvmpipe".into()],
        adapter: "llvmpipe".into(),
        driver: "llvmpipe".into(),
        host: "test".into(),
    }
}

/// A claimer process: `hold` claims one job and waits to be killed; `drain` claims and completes
/// jobs until none is queued or in progress. Each claim is printed `claimed ID ATTEMPT NOW_MS`.
fn claimer(arg: &str) {
    let mut parts = arg.split('\t');
    let (mode, store, runner) = (
        parts.next().unwrap(),
        parts.next().unwrap(),
        parts.next().unwrap().parse::<i64>().unwrap(),
    );
    let pool = db::open(store).unwrap();
    let mut c = pool.get().unwrap();
    loop {
        let now = now_ms();
        let lease = if mode == "hold" {
            HOLD_LEASE_MS
        } else {
            60_000
        };
        if let Some(job) = queue::claim(&mut *c, runner, now, lease).unwrap() {
            println!("claimed {} {} {now}", job.job_id, job.attempt);
            if mode == "hold" {
                std::thread::sleep(Duration::from_secs(120));
                return;
            }
            let done = Completion {
                runner: format!("r{runner}"),
                attempt: job.attempt,
                runs: vec![],
                samples: vec![],
                commits: None,
            };
            queue::complete(&mut *c, runner, job.job_id, &done).unwrap();
            continue;
        }
        let open = c
            .query(
                "SELECT COUNT(*) FROM queue_jobs WHERE status IN ('queued', 'in_progress')",
                &[],
            )
            .unwrap()[0]
            .i64(0)
            .unwrap();
        if open == 0 {
            return;
        }
        std::thread::sleep(Duration::from_millis(POLL_MS));
    }
}

fn spawn(mode: &str, url: &str, runner: i64) -> std::process::Child {
    Command::new(std::env::current_exe().unwrap())
        .args([TEST, "--exact", "--nocapture", "--test-threads=1", "-q"])
        .env(CHILD, format!("{mode}\t{url}\t{runner}"))
        .stdout(Stdio::piped())
        .spawn()
        .unwrap()
}

/// The `claimed` lines of a process's output: (job, attempt, when).
fn claims(out: &[u8]) -> Vec<(i64, i64, i64)> {
    String::from_utf8_lossy(out)
        .lines()
        .filter_map(|l| l.strip_prefix("claimed "))
        .map(|l| {
            let v: Vec<i64> = l.split(' ').map(|w| w.parse().unwrap()).collect();
            (v[0], v[1], v[2])
        })
        .collect()
}

#[test]
fn four_runner_processes_drain_400_jobs_after_one_is_killed() {
    if let Ok(arg) = std::env::var(CHILD) {
        claimer(&arg);
        return;
    }
    for store in common::stores("queue_processes") {
        let mut c = store.pool.get().unwrap();
        let mut ids = Vec::new();
        // A request makes at most 16 jobs: queue them in chunks.
        for chunk in (0..400).collect::<Vec<_>>().chunks(16) {
            let jobs: Vec<NewJob> = chunk
                .iter()
                .map(|&i| NewJob {
                    label: "llvmpipe".into(),
                    spec: spec(i),
                })
                .collect();
            let (_, mut j) = queue::enqueue(
                &mut *c,
                "backfill",
                &serde_json::json!({}),
                None,
                "test",
                &jobs,
                3,
            )
            .unwrap();
            ids.append(&mut j);
        }
        let runners: Vec<i64> = (0..5)
            .map(|i| queue::register(&mut *c, &registration(&format!("p{i}")), "t", 0).unwrap())
            .collect();
        drop(c);

        // Runner 4 claims a job, then is killed holding it.
        let mut holder = spawn("hold", &store.url, runners[4]);
        let mut out = BufReader::new(holder.stdout.take().unwrap());
        let (held, _, held_at) = loop {
            let mut line = String::new();
            assert!(
                out.read_line(&mut line).unwrap() > 0,
                "the holder claimed nothing"
            );
            if let Some(&claim) = claims(line.as_bytes()).first() {
                break claim;
            }
        };
        holder.kill().unwrap();
        holder.wait().unwrap();

        let drainers: Vec<_> = runners[..4]
            .iter()
            .map(|&r| spawn("drain", &store.url, r))
            .collect();
        let mut runs: BTreeMap<i64, Vec<(i64, i64)>> = BTreeMap::new();
        for d in drainers {
            let out = d.wait_with_output().unwrap();
            assert!(
                out.status.success(),
                "{}: a claimer process failed",
                store.name
            );
            for (job, attempt, at) in claims(&out.stdout) {
                runs.entry(job).or_default().push((attempt, at));
            }
        }
        assert_eq!(runs.len(), 400, "{}: every job ran", store.name);
        let twice: Vec<_> = runs.iter().filter(|(_, r)| r.len() != 1).collect();
        assert!(twice.is_empty(), "{}: ran twice: {twice:?}", store.name);
        let (attempt, rerun_at) = runs[&held][0];
        assert_eq!(
            attempt, 2,
            "{}: the killed runner's job ran again",
            store.name
        );
        assert!(
            rerun_at >= held_at + HOLD_LEASE_MS,
            "{}: re-run {} ms after the claim, before its lease of {HOLD_LEASE_MS} ms ran out",
            store.name,
            rerun_at - held_at
        );
        eprintln!(
            "{}: the killed runner's job ran again {} ms after it was claimed (lease {HOLD_LEASE_MS} ms, poll {POLL_MS} ms)",
            store.name,
            rerun_at - held_at
        );
        let mut c = store.pool.get().unwrap();
        for id in ids {
            let j = queue::job(&mut *c, id).unwrap();
            let attempts = if id == held { 2 } else { 1 };
            assert_eq!(
                (j.status, j.attempts),
                (JobStatus::Done, attempts),
                "{}",
                store.name
            );
        }
    }
}
