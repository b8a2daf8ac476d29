//! The job queue on SQLite and PostgreSQL: concurrent claimers drain it with every job run
//! exactly once, an expired lease is claimed again by another runner, retries end in `failed`
//! with the runner's error, a label no runner serves waits without blocking others, and a runner
//! that lost its job cannot finish it.

mod common;

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};

use tessera_dashboard::db::Connection;
use tessera_dashboard::store::queue::{self, JobStatus, NewJob};
use tessera_results::queue::{Arm, Completion, JobKind, JobSpec, Registration};

fn spec(commit: &str) -> JobSpec {
    JobSpec {
        kind: JobKind::Run,
        scenarios: vec!["scenarios/smoke".into()],
        variant: None,
        arms: vec![Arm {
            name: "run".into(),
            commit: commit.into(),
            env: BTreeMap::new(),
        }],
        order: vec![0],
        list_commits: None,
    }
}

fn reg(name: &str, labels: &[&str]) -> Registration {
    Registration {
        name: name.into(),
        labels: labels.iter().map(|s| s.to_string()).collect(),
        adapter: "llvmpipe (LLVM 15.0.6, 256 bits)".into(),
        driver: "llvmpipe".into(),
        host: "test".into(),
    }
}

fn enqueue(c: &mut dyn Connection, label: &str, n: usize, max_attempts: i64) -> Vec<i64> {
    let jobs: Vec<NewJob> = (0..n)
        .map(|i| NewJob {
            label: label.into(),
            spec: spec(&format!("{:040x}", i + 1)),
        })
        .collect();
    let mut ids = Vec::new();
    // A request makes at most 16 jobs: queue them in chunks.
    for chunk in jobs.chunks(16) {
        let (_, mut j) = queue::enqueue(
            c,
            "backfill",
            &serde_json::json!({}),
            None,
            "test",
            chunk,
            max_attempts,
        )
        .unwrap();
        ids.append(&mut j);
    }
    ids
}

fn done(attempt: i64, runner: &str) -> Completion {
    Completion {
        runner: runner.into(),
        attempt,
        runs: vec![],
        samples: vec![],
        commits: None,
    }
}

#[test]
fn four_claimers_drain_400_jobs_each_run_exactly_once() {
    for store in common::stores("queue_drain") {
        let mut c = store.pool.get().unwrap();
        let ids = enqueue(&mut *c, "llvmpipe", 400, 3);
        let runners: Vec<i64> = (0..4)
            .map(|i| {
                queue::register(&mut *c, &reg(&format!("r{i}"), &["llvmpipe"]), "t", 0).unwrap()
            })
            .collect();
        drop(c);
        let runs: Arc<Mutex<BTreeMap<i64, usize>>> = Arc::default();
        let threads: Vec<_> = runners
            .iter()
            .map(|&rid| {
                let pool = store.pool.clone();
                let runs = runs.clone();
                std::thread::spawn(move || {
                    let mut c = pool.get().unwrap();
                    let mut mine = 0;
                    while let Some(job) = queue::claim(&mut *c, rid, 1_000, 60_000).unwrap() {
                        *runs.lock().unwrap().entry(job.job_id).or_insert(0) += 1;
                        queue::complete(&mut *c, rid, job.job_id, &done(job.attempt, "x")).unwrap();
                        mine += 1;
                    }
                    mine
                })
            })
            .collect();
        let per_runner: Vec<usize> = threads.into_iter().map(|t| t.join().unwrap()).collect();
        let runs = runs.lock().unwrap();
        assert_eq!(runs.len(), 400, "{}: every job ran", store.name);
        assert!(
            runs.values().all(|&n| n == 1),
            "{}: a job ran twice: {:?}",
            store.name,
            runs.iter().filter(|(_, &n)| n != 1).collect::<Vec<_>>()
        );
        assert_eq!(per_runner.iter().sum::<usize>(), 400);
        let mut c = store.pool.get().unwrap();
        for id in ids {
            let j = queue::job(&mut *c, id).unwrap();
            assert_eq!(
                (j.status, j.attempts),
                (JobStatus::Done, 1),
                "{}",
                store.name
            );
        }
    }
}

#[test]
fn an_expired_lease_is_claimed_by_another_runner_and_the_first_cannot_finish() {
    for store in common::stores("queue_lease") {
        let mut c = store.pool.get().unwrap();
        let [id] = enqueue(&mut *c, "nvidia", 1, 3)[..] else {
            panic!()
        };
        let a = queue::register(&mut *c, &reg("a", &["nvidia"]), "t", 0).unwrap();
        let b = queue::register(&mut *c, &reg("b", &["nvidia"]), "t", 0).unwrap();
        let first = queue::claim(&mut *c, a, 0, 10_000).unwrap().unwrap();
        assert_eq!((first.job_id, first.attempt), (id, 1));
        // Within the lease (extended by a heartbeat) nobody else gets it.
        assert!(queue::heartbeat(&mut *c, a, Some((id, 1)), 8_000, 10_000).unwrap());
        assert_eq!(queue::claim(&mut *c, b, 17_000, 10_000).unwrap(), None);
        // a stops heartbeating: after its lease (18 s), b takes the job as attempt 2.
        let second = queue::claim(&mut *c, b, 18_001, 10_000).unwrap().unwrap();
        assert_eq!((second.job_id, second.attempt), (id, 2), "{}", store.name);
        assert!(!queue::heartbeat(&mut *c, a, Some((id, 1)), 18_500, 10_000).unwrap());
        let err = queue::complete(&mut *c, a, id, &done(1, "a")).unwrap_err();
        assert!(err.to_string().contains("not held by this runner"), "{err}");
        queue::complete(&mut *c, b, id, &done(2, "b")).unwrap();
        let j = queue::job(&mut *c, id).unwrap();
        assert_eq!(
            (j.status, j.runner.as_deref()),
            (JobStatus::Done, Some("b"))
        );
    }
}

#[test]
fn retries_end_in_failed_with_the_runners_error_and_build_failures_are_final() {
    for store in common::stores("queue_retries") {
        let mut c = store.pool.get().unwrap();
        let ids = enqueue(&mut *c, "amd", 2, 2);
        let r = queue::register(&mut *c, &reg("r", &["amd"]), "t", 0).unwrap();
        let j = queue::claim(&mut *c, r, 0, 1000).unwrap().unwrap();
        assert_eq!(j.job_id, ids[0]);
        let s = queue::fail(&mut *c, r, j.job_id, 1, "device lost", false, None).unwrap();
        assert_eq!(s, JobStatus::Queued);
        let j = queue::claim(&mut *c, r, 0, 1000).unwrap().unwrap();
        assert_eq!((j.job_id, j.attempt), (ids[0], 2));
        let s = queue::fail(&mut *c, r, j.job_id, 2, "device lost again", false, None).unwrap();
        assert_eq!(s, JobStatus::Failed);
        let row = queue::job(&mut *c, ids[0]).unwrap();
        assert_eq!(
            (row.status, row.error.as_str()),
            (JobStatus::Failed, "device lost again")
        );
        // A job whose runner vanished on its last attempt is failed, not left hanging.
        let j = queue::claim(&mut *c, r, 0, 1000).unwrap().unwrap();
        assert_eq!(j.job_id, ids[1]);
        let j = queue::claim(&mut *c, r, 1001, 1000).unwrap().unwrap();
        assert_eq!((j.job_id, j.attempt), (ids[1], 2));
        assert_eq!(queue::claim(&mut *c, r, 2002, 1000).unwrap(), None);
        let row = queue::job(&mut *c, ids[1]).unwrap();
        assert_eq!(row.status, JobStatus::Failed, "{}", store.name);
        assert!(row.error.contains("stopped heartbeating"), "{}", row.error);
        // A build failure is final on the first attempt.
        let [id] = enqueue(&mut *c, "amd", 1, 3)[..] else {
            panic!()
        };
        let j = queue::claim(&mut *c, r, 3000, 1000).unwrap().unwrap();
        let s = queue::fail(&mut *c, r, id, j.attempt, "error[E0308]", true, None).unwrap();
        assert_eq!(s, JobStatus::BuildFailed);
    }
}

#[test]
fn a_label_nobody_serves_waits_visibly_without_blocking_others() {
    for store in common::stores("queue_labels") {
        let mut c = store.pool.get().unwrap();
        let amd = enqueue(&mut *c, "amd", 1, 3);
        let lvp = enqueue(&mut *c, "llvmpipe", 1, 3);
        let r = queue::register(&mut *c, &reg("r", &["llvmpipe", "intel"]), "t", 0).unwrap();
        let j = queue::claim(&mut *c, r, 0, 1000).unwrap().unwrap();
        assert_eq!(
            j.job_id, lvp[0],
            "{}: the older amd job does not block",
            store.name
        );
        assert_eq!(queue::claim(&mut *c, r, 0, 1000).unwrap(), None);
        let o = queue::overview(&mut *c, 500, 60_000, 10).unwrap();
        let waiting: Vec<_> = o.active.iter().map(|j| (j.id, j.waiting.clone())).collect();
        assert_eq!(
            waiting,
            vec![
                (
                    amd[0],
                    Some("no online runner has label \"amd\"".to_string())
                ),
                (lvp[0], None)
            ]
        );
        assert_eq!(o.runners[0].current_job, Some(lvp[0]));
        assert!(o.runners[0].online);
        // Given back (SIGTERM): queued again, the attempt not counted.
        queue::give_back(&mut *c, r, lvp[0], 1).unwrap();
        let row = queue::job(&mut *c, lvp[0]).unwrap();
        assert_eq!((row.status, row.attempts), (JobStatus::Queued, 0));
        let o = queue::overview(&mut *c, 120_000, 60_000, 10).unwrap();
        assert!(!o.runners[0].online);
        assert_eq!(o.queued_by_label.get("llvmpipe"), Some(&1));
    }
}

#[test]
fn bad_specs_and_registrations_are_refused_with_what_is_allowed() {
    let store = common::sqlite();
    let mut c = store.pool.get().unwrap();
    let mut s = spec("zz");
    let e = queue::enqueue(
        &mut *c,
        "nightly",
        &serde_json::json!({}),
        None,
        "t",
        &[NewJob {
            label: "x".into(),
            spec: s.clone(),
        }],
        3,
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "arm run commit \"zz\" is not a commit: give 7 to 40 hexadecimal digits"
    );
    s.arms[0].commit = "abcdef0".into();
    s.scenarios = vec!["../etc/passwd".into()];
    let e = queue::check_spec(&s).unwrap_err();
    assert!(e.to_string().contains("without '..'"), "{e}");
    let e = queue::register(&mut *c, &reg("a b", &["x"]), "t", 0).unwrap_err();
    assert!(e.to_string().starts_with("runner name \"a b\""), "{e}");
    queue::register(&mut *c, &reg("a", &["x"]), "t", 0).unwrap();
    let e = queue::register(&mut *c, &reg("a", &["x"]), "other", 0).unwrap_err();
    assert!(
        e.to_string().contains("registered with another token"),
        "{e}"
    );
    let n = c.query("SELECT COUNT(*) FROM queue_jobs", &[]).unwrap()[0]
        .i64(0)
        .unwrap();
    assert_eq!(n, 0, "nothing was queued");
}
