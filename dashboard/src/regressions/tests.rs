//! Reconciliation planning on hand-made windows.

use super::*;

fn found(index: usize, rel: f64, status: DetectionStatus) -> Found {
    Found {
        change: ChangePoint {
            index,
            before: 1.0,
            after: 1.0 + rel,
            relative_change: rel,
            confidence: 0.999,
            sigma: 0.01,
            change_low: rel - 0.01,
            change_high: rel + 0.01,
            candidates: vec![(index, 1.0)],
            first_candidate: index,
            last_candidate: index,
        },
        status,
    }
}

fn alert(id: i64, pk: i64, rel: f64, status: DetectionStatus) -> StoredAlert {
    StoredAlert {
        id,
        run_pk_before: pk - 1,
        run_pk_after: pk,
        relative_change: rel,
        status,
    }
}

#[test]
fn an_alert_one_commit_early_moves_to_the_change() {
    let pks: Vec<i64> = (100..130).collect();
    let actions = plan(
        &pks,
        0,
        &[found(20, 0.2, CONFIRMED)],
        &[alert(7, 119, 0.133, PENDING)],
    );
    assert_eq!(actions, vec![Action::Update { id: 7, found: 0 }]);
}

#[test]
fn duplicates_merge_and_unsupported_alerts_are_withdrawn() {
    let pks: Vec<i64> = (0..40).collect();
    let alerts = [
        alert(1, 20, 0.1, CONFIRMED),
        alert(2, 22, 0.1, PENDING),
        alert(3, 30, -0.05, CONFIRMED),
        alert(4, 10, 0.1, WITHDRAWN),
    ];
    let actions = plan(&pks, 0, &[found(21, 0.1, CONFIRMED)], &alerts);
    assert_eq!(
        actions,
        vec![
            Action::Update { id: 1, found: 0 },
            Action::Withdraw {
                id: 2,
                into: Some(1)
            },
            Action::Withdraw { id: 3, into: None },
        ]
    );
}

#[test]
fn a_withdrawn_alert_at_the_change_is_reinstated_and_direction_matters() {
    let pks: Vec<i64> = (0..40).collect();
    let alerts = [alert(1, 20, 0.1, WITHDRAWN), alert(2, 25, -0.1, PENDING)];
    let actions = plan(
        &pks,
        0,
        &[found(20, 0.1, CONFIRMED), found(26, 0.1, PENDING)],
        &alerts,
    );
    assert_eq!(
        actions,
        vec![
            Action::Update { id: 1, found: 0 },
            Action::Insert { found: 1 },
            Action::Withdraw { id: 2, into: None },
        ]
    );
}

#[test]
fn alerts_before_the_open_part_are_final() {
    let pks: Vec<i64> = (0..300).collect();
    let actions = plan(
        &pks,
        64,
        &[found(10, 0.1, CONFIRMED)],
        &[alert(1, 30, 0.1, CONFIRMED)],
    );
    assert_eq!(actions, vec![]);
}

fn points(values: &[f64]) -> Vec<WindowPoint> {
    values
        .iter()
        .enumerate()
        .map(|(i, &value)| WindowPoint {
            run_pk: i as i64 + 1,
            environment: 0,
            value,
        })
        .collect()
}

/// A change is confirmed once `confirm_after` runs follow the *latest* commit it may lie at, and
/// while its range holds more than one commit, twice that: a night exactly between the levels
/// leaves it at either of two commits, so with 4 runs after the first it is still pending (it was
/// confirmed on the first before, and a confirmed alert stays where it was announced), and it is
/// confirmed with 8 runs after the second.
#[test]
fn a_change_spread_over_two_commits_waits_for_its_location() {
    let mut v = vec![1.0; 30];
    v.push(1.05);
    v.extend([1.1; 3]);
    let params = Params::default();
    for after_second in 3..8 {
        let f = find(&points(&v), &params);
        assert_eq!(f.len(), 1, "{f:?}");
        let c = &f[0].change;
        assert_eq!((c.first_candidate, c.last_candidate), (30, 31), "{c:?}");
        assert!(
            c.probability_at(30) > 0.4 && c.probability_at(31) > 0.4,
            "{c:?}"
        );
        assert_eq!(
            f[0].status, PENDING,
            "{after_second} runs after the second commit"
        );
        v.push(1.1);
    }
    let f = find(&points(&v), &params);
    assert_eq!(f[0].status, CONFIRMED, "{f:?}");
    // A change whose range is one commit is confirmed with 4 runs after it.
    let mut w = vec![1.0; 30];
    w.extend([1.1; 3]);
    assert_eq!(find(&points(&w), &params)[0].status, PENDING);
    w.push(1.1);
    assert_eq!(find(&points(&w), &params)[0].status, CONFIRMED);
}
