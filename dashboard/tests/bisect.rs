//! Bisection through the queue with simulated runners (no GPU): a history of 16 commits where one
//! commit slows the scenario and another changes its frames and PSNR, one commit that does not
//! build, and a runner that dies holding a step. On SQLite and PostgreSQL.

mod common;

use tessera_dashboard::ab::bisect::{self, Params};
use tessera_dashboard::db::{transaction, Connection};
use tessera_dashboard::store::queue;
use tessera_results::queue::{Claimed, Completion, Registration, Sample};

const SLOW: usize = 6;
const COLOUR: usize = 11;
const BROKEN: usize = 7;

fn sha(i: usize) -> String {
    format!("{:040x}", 0xc0ffee00 + i)
}

fn index(commit: &str) -> usize {
    (0..16)
        .find(|&i| sha(i) == commit)
        .expect("a history commit")
}

/// What the scenario measures at commit `i`, attempt `seq` (a little noise on the time). The
/// noise is the pair's (both arms of pair `seq / 2` share it, as a machine's drift would): with
/// noise of the sample's own, two arms of one commit read p < UNSURE_P one step in four under the
/// shuffled order, and the step runs again, as it should, but then the count of steps is luck.
fn measure(i: usize, seq: usize) -> Sample {
    let noise = [0.0, 0.004, -0.003, 0.002, -0.001][(seq / 2) % 5];
    let gpu = 2.0 + if i >= SLOW { 0.6 } else { 0.0 } + noise;
    let psnr = if i >= COLOUR { 31.5 } else { 33.0 };
    Sample {
        arm: 0,
        seq,
        measures: [
            ("gpu_ms.median".to_string(), gpu),
            ("psnr".to_string(), psnr),
        ]
        .into(),
        frames_digest: Some(if i >= COLOUR { "b" } else { "a" }.into()),
    }
}

/// Does what a runner does with `job`: list commits, "build" (commit BROKEN fails), measure.
fn work(c: &mut dyn Connection, runner: i64, job: &Claimed) {
    let commits = job
        .spec
        .list_commits
        .as_ref()
        .map(|[_, bad]| (1..=index(bad)).map(sha).collect::<Vec<_>>());
    if let Some(arm) = job.spec.arms.iter().find(|a| index(&a.commit) == BROKEN) {
        let status = transaction(c, |c| {
            let s = queue::fail(
                c,
                runner,
                job.job_id,
                job.attempt,
                "error[E0425]",
                true,
                None,
            )?;
            bisect::on_job_finished(c, job.job_id)?;
            Ok::<_, tessera_dashboard::store::StoreError>(s)
        })
        .unwrap();
        assert_eq!(status, queue::JobStatus::BuildFailed, "{}", arm.commit);
        return;
    }
    let samples = job
        .spec
        .order
        .iter()
        .enumerate()
        .map(|(seq, &arm)| {
            let mut s = Sample {
                arm,
                ..measure(index(&job.spec.arms[arm].commit), seq)
            };
            // A CPU adapter's times scale with the machine's load, which differs between jobs
            // (here up to 2x) but not within one: fractions of the change must not move with it.
            let load = 1.0 + (job.job_id % 3) as f64 * 0.5;
            *s.measures.get_mut("gpu_ms.median").unwrap() *= load;
            s
        })
        .collect();
    let done = Completion {
        runner: "sim".into(),
        attempt: job.attempt,
        runs: vec![],
        samples,
        commits,
    };
    transaction(c, |c| {
        queue::complete(c, runner, job.job_id, &done)?;
        bisect::on_job_finished(c, job.job_id)
    })
    .unwrap();
}

fn reg(name: &str) -> Registration {
    Registration {
        name: name.into(),
        labels: vec!["llvmpipe".into()],
        adapter: "llvmpipe".into(),
        driver: "mesa".into(),
        host: "sim".into(),
    }
}

#[test]
fn bisections_name_the_slowing_and_the_colour_commit_despite_a_dead_runner_and_a_broken_build() {
    for store in common::stores("bisect_sim") {
        let mut c = store.pool.get().unwrap();
        let mut ids = Vec::new();
        for measure in ["gpu_ms.median", "frames_changed", "psnr"] {
            let p = Params {
                scenario: "scenarios/smoke/shading-bound.toml".into(),
                variant: "checkerboard".into(),
                measure: measure.into(),
                good: sha(0),
                bad: sha(15),
                label: "llvmpipe".into(),
                attempts: 6,
                regression_id: None,
            };
            ids.push(transaction(&mut *c, |c| bisect::create(c, &p, "test", 3)).unwrap());
        }
        let dead = queue::register(&mut *c, &reg("dead"), "t", 0).unwrap();
        let live = queue::register(&mut *c, &reg("live"), "t", 0).unwrap();
        // The dead runner claims the first step and is never heard from again.
        let held = queue::claim(&mut *c, dead, 0, 10_000).unwrap().unwrap();
        let mut now = 10_001;
        let mut jobs = 0;
        while let Some(job) = queue::claim(&mut *c, live, now, 10_000).unwrap() {
            if job.job_id == held.job_id {
                assert_eq!(job.attempt, 2, "the dead runner's job is claimed again");
            }
            work(&mut *c, live, &job);
            jobs += 1;
            now += 1;
            assert!(jobs < 100, "the bisections do not end");
        }
        let got: Vec<(String, Option<String>)> = ids
            .iter()
            .map(|&id| {
                let b = bisect::get(&mut *c, id).unwrap();
                (b.state, b.culprit)
            })
            .collect();
        assert_eq!(
            got,
            vec![
                ("done".to_string(), Some(sha(SLOW))),
                ("done".to_string(), Some(sha(COLOUR))),
                ("done".to_string(), Some(sha(COLOUR))),
            ],
            "{}",
            store.name
        );
        let skipped: Vec<Vec<String>> = ids
            .iter()
            .map(|&id| bisect::get(&mut *c, id).unwrap().skipped)
            .collect();
        assert!(
            skipped.iter().any(|s| s == &[sha(BROKEN)]),
            "a bisection tried the broken commit and skipped it: {skipped:?}"
        );
        let first = bisect::get(&mut *c, ids[0]).unwrap();
        let steps = bisect::steps(&mut *c, &first).unwrap();
        assert!(steps.len() <= 6, "{} steps for 15 commits", steps.len());
        assert_eq!(steps[0].table.len(), 3, "gpu_ms, psnr and frames_changed");
        let o = queue::overview(&mut *c, now, 60_000, 100).unwrap();
        assert!(o.active.is_empty(), "no job is left queued or in progress");
    }
}

#[test]
fn a_change_spread_over_commits_is_reported_as_spread() {
    let store = common::sqlite();
    let mut c = store.pool.get().unwrap();
    let p = Params {
        scenario: "s.toml".into(),
        variant: "native".into(),
        measure: "gpu_ms.median".into(),
        good: sha(0),
        bad: sha(15),
        label: "llvmpipe".into(),
        attempts: 6,
        regression_id: None,
    };
    let id = transaction(&mut *c, |c| bisect::create(c, &p, "test", 3)).unwrap();
    let r = queue::register(&mut *c, &reg("r"), "t", 0).unwrap();
    while let Some(job) = queue::claim(&mut *c, r, 0, 10_000).unwrap() {
        // Every commit adds the same little: half the change sits on each side of the middle.
        let samples = job
            .spec
            .order
            .iter()
            .enumerate()
            .map(|(seq, &arm)| Sample {
                arm,
                seq,
                measures: [(
                    "gpu_ms.median".to_string(),
                    1.0 + 0.1 * index(&job.spec.arms[arm].commit) as f64 + seq as f64 * 1e-4,
                )]
                .into(),
                frames_digest: None,
            })
            .collect();
        let commits = job
            .spec
            .list_commits
            .as_ref()
            .map(|_| (1..16).map(sha).collect());
        let done = Completion {
            runner: "r".into(),
            attempt: job.attempt,
            runs: vec![],
            samples,
            commits,
        };
        transaction(&mut *c, |c| {
            queue::complete(c, r, job.job_id, &done)?;
            bisect::on_job_finished(c, job.job_id)
        })
        .unwrap();
    }
    let b = bisect::get(&mut *c, id).unwrap();
    assert_eq!((b.state.as_str(), b.culprit), ("spread", None));
    assert!(
        b.progress.message.contains("spread over"),
        "{}",
        b.progress.message
    );
}

#[test]
fn an_undecided_step_runs_again_with_twice_the_attempts() {
    // Four pairs that all differ the same way give p = 2/16 = 0.125 (exact Wilcoxon): not
    // significant, not the same either. Eight give 0.0078.
    let store = common::sqlite();
    let mut c = store.pool.get().unwrap();
    let p = Params {
        scenario: "s.toml".into(),
        variant: "native".into(),
        measure: "gpu_ms.median".into(),
        good: sha(0),
        bad: sha(15),
        label: "llvmpipe".into(),
        attempts: 4,
        regression_id: None,
    };
    let id = transaction(&mut *c, |c| bisect::create(c, &p, "test", 3)).unwrap();
    let r = queue::register(&mut *c, &reg("r"), "t", 0).unwrap();
    let mut pairs = Vec::new();
    while let Some(job) = queue::claim(&mut *c, r, 0, 10_000).unwrap() {
        pairs.push(job.spec.order.len() / 2);
        work(&mut *c, r, &job);
    }
    let b = bisect::get(&mut *c, id).unwrap();
    assert_eq!(pairs[..2], [4, 8], "step 0 ran again at twice the attempts");
    assert!(pairs[2..].iter().all(|&n| n == 8), "{pairs:?}");
    assert_eq!(b.attempts, 8);
    assert_eq!(
        (b.state.as_str(), b.culprit.as_deref()),
        ("done", Some(sha(SLOW).as_str())),
        "{}",
        b.progress.message
    );
}
