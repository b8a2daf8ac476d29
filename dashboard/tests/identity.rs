//! Stable identities (issue 22, item 2): an alert group keeps its id and URL for life, the
//! commit-range keys it was shown under still find it, triage survives the deletion of the run
//! the alert names (the alert is re-pointed, not deleted), ids are never reused, and a one-night
//! outlier just before a step does not capture the split (item 1).

mod common;

use common::{range, sha};
use tessera_dashboard::db::Connection;
use tessera_dashboard::detect::{Params, Rng};
use tessera_dashboard::regressions::{delete_and_detect, ingest_and_detect};
use tessera_dashboard::store::alerts::{self, DetectionStatus, Select, TriageState};
use tessera_dashboard::store::groups::{self, Named};
use tessera_dashboard::store::triage::{self, Triage};

/// Runs `from..to` of one series history with a +20% step at run 20 and 1% noise.
fn fill(c: &mut dyn Connection, from: u64, to: u64, outlier_at: Option<u64>) {
    fill_with(c, from, to, outlier_at, 1.2, 0.01)
}

fn fill_with(
    c: &mut dyn Connection,
    from: u64,
    to: u64,
    outlier_at: Option<u64>,
    step: f64,
    noise: f64,
) {
    let template = common::template();
    for i in from..to {
        let mut rng = Rng::new(100 + i);
        let mut f = if i < 20 { 1.0 } else { step };
        if Some(i) == outlier_at {
            f = 1.5;
        }
        let b = tessera_dashboard::synth::run_from(&template, "id", i, f, noise, &mut rng);
        ingest_and_detect(c, &b, &Params::default()).unwrap();
    }
}

fn gpu_alerts(c: &mut dyn Connection) -> Vec<alerts::Alert> {
    let mut v = alerts::read(
        c,
        Select {
            limit: 10_000,
            ..Select::default()
        },
    )
    .unwrap();
    v.retain(|a| a.series.measure == "gpu_ms.median");
    v.sort_by_key(|a| a.id);
    v
}

#[test]
fn triage_and_ids_outlive_a_deleted_run_and_old_keys_redirect() {
    for store in common::stores("triage_and_ids_outlive_a_deleted_run_and_old_keys_redirect") {
        let mut c = store.pool.get().unwrap();
        fill(&mut *c, 0, 30, None);
        let before = gpu_alerts(&mut *c);
        assert!(!before.is_empty(), "{}: the step is found", store.name);
        for a in &before {
            assert_eq!(a.run_after, format!("id-{:06}", 20), "{}", store.name);
            assert_eq!(a.status, DetectionStatus::Confirmed);
            let p = a.location_probability.unwrap();
            assert!(p > 0.5 && p <= 1.0, "location probability {p}");
            let (lo, hi) = (a.change_low.unwrap(), a.change_high.unwrap());
            assert!(lo < a.relative_change && a.relative_change < hi);
            assert!(lo > 0.1 && hi < 0.3, "interval {lo}..{hi} around +20%");
        }
        let key = range(19);
        let gid = groups::resolve(&mut *c, &key).unwrap();
        assert!(matches!(gid, Named::Key(_)));
        let gid = gid.id();
        assert_eq!(
            groups::resolve(&mut *c, &gid.to_string()).unwrap(),
            Named::Id(gid)
        );
        triage::set_group(
            &mut *c,
            &gid.to_string(),
            &Triage {
                state: "acknowledged".into(),
                note: "known: new shadow pass".into(),
                bug_url: "https://bugs.example/9".into(),
            },
            "alice",
        )
        .unwrap();
        let max_id: i64 = before.iter().map(|a| a.id).max().unwrap();

        // Delete the run after the change: its alerts move to the next run, same rows.
        let (deleted, _) = delete_and_detect(&mut *c, "id-000020", &Params::default()).unwrap();
        assert!(deleted.alerts >= before.len() as u64, "{deleted:?}");
        let after = gpu_alerts(&mut *c);
        let ids: Vec<i64> = after.iter().map(|a| a.id).collect();
        assert_eq!(
            ids,
            before.iter().map(|a| a.id).collect::<Vec<_>>(),
            "{}: the same alerts",
            store.name
        );
        for a in &after {
            assert_eq!(a.group_id, gid);
            assert_eq!(a.state, TriageState::Acknowledged, "triage kept");
            assert_eq!(a.note, "known: new shadow pass");
            assert_eq!(a.bug_url, "https://bugs.example/9");
            assert_eq!(a.run_after, "id-000021");
            assert_ne!(a.status, DetectionStatus::Withdrawn);
        }
        // The old key and the id both still name the group; the new range is one of its keys.
        assert_eq!(groups::resolve(&mut *c, &key).unwrap().id(), gid);
        let g = groups::get(&mut *c, gid).unwrap();
        assert_eq!(g.key, format!("{}..{}", sha(19), sha(21)));
        assert_eq!(groups::resolve(&mut *c, &g.key).unwrap().id(), gid);
        assert_eq!(g.state, TriageState::Acknowledged);
        let history = alerts::events_of_group(&mut *c, gid).unwrap();
        assert!(history.iter().any(|e| e.kind == "repointed"), "{history:?}");

        // A new change later gets a new id, never one used before.
        fill(&mut *c, 30, 50, None);
        let template = common::template();
        for i in 50..60u64 {
            let b = tessera_dashboard::synth::run_from(
                &template,
                "id",
                i,
                1.5,
                0.01,
                &mut Rng::new(100 + i),
            );
            ingest_and_detect(&mut *c, &b, &Params::default()).unwrap();
        }
        let newer: Vec<i64> = gpu_alerts(&mut *c)
            .iter()
            .map(|a| a.id)
            .filter(|id| !ids.contains(id))
            .collect();
        assert!(
            !newer.is_empty(),
            "{}: the second step is found",
            store.name
        );
        assert!(newer.iter().all(|&id| id > max_id), "{newer:?} > {max_id}");
        let g2 = groups::resolve(&mut *c, &range(49)).unwrap().id();
        assert!(g2 > gid);
    }
}

#[test]
fn an_outlier_the_night_before_a_step_does_not_capture_it() {
    for store in common::stores("an_outlier_the_night_before_a_step_does_not_capture_it") {
        let mut c = store.pool.get().unwrap();
        // The case: 2% noise, run 18 a one-night outlier (+50%), two runs before a +10%
        // step at run 20. Clipped at 5 sigma, the outlier sits at the new level.
        fill_with(&mut *c, 0, 30, Some(18), 1.1, 0.02);
        let found = gpu_alerts(&mut *c);
        assert!(!found.is_empty());
        for a in found
            .iter()
            .filter(|a| a.status != DetectionStatus::Withdrawn)
        {
            assert_eq!(
                a.run_after, "id-000020",
                "{}: the step, not the outlier: {a:?}",
                store.name
            );
        }
    }
}
