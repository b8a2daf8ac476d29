//! Detection on generated series: the acceptance figures of issue 7 (a 3% step at 1% noise is
//! found within 5 points at least 90% of the time; noise alone gives at most 1 alert per 1000
//! points) and environment segmentation.

use super::*;

fn noisy(rng: &mut Rng, n: usize, level: f64, noise: f64) -> Vec<f64> {
    (0..n)
        .map(|_| level * (1.0 + noise * rng.normal()))
        .collect()
}

#[test]
fn three_percent_step_at_one_percent_noise_is_found_within_five_points() {
    let mut rng = Rng::new(1);
    let trials = 300;
    let mut found = 0;
    for _ in 0..trials {
        // 40 points of history, the step, then 5 points after it, checked as each one arrives
        // (as the dashboard does on every import).
        let mut v = noisy(&mut rng, 40, 10.0, 0.01);
        v.extend(noisy(&mut rng, 5, 10.3, 0.01));
        let hit = (41..=45).any(|n| {
            detect(&v[..n], &Params::default())
                .iter()
                .any(|c| c.index.abs_diff(40) <= 2 && c.relative_change > 0.0)
        });
        found += hit as usize;
    }
    eprintln!("found {found} of {trials}");
    assert!(found * 10 >= trials * 9, "found {found} of {trials}");
}

#[test]
fn step_location_and_size_are_reported() {
    let mut rng = Rng::new(2);
    let mut v = noisy(&mut rng, 60, 5.0, 0.01);
    v.extend(noisy(&mut rng, 60, 4.5, 0.01));
    let cps = detect(&v, &Params::default());
    assert_eq!(cps.len(), 1, "{cps:?}");
    assert_eq!(cps[0].index, 60);
    assert!((cps[0].relative_change + 0.1).abs() < 0.01, "{cps:?}");
    assert!(cps[0].confidence > 0.999);
}

#[test]
fn noise_alone_gives_at_most_one_alert_per_thousand_points() {
    let mut rng = Rng::new(3);
    let mut alerts = 0;
    let series = 10;
    for _ in 0..series {
        let v = noisy(&mut rng, 1000, 10.0, 0.01);
        alerts += detect(&v, &Params::default()).len();
    }
    eprintln!("{alerts} alerts in {series} series");
    assert!(
        alerts <= series,
        "{alerts} alerts in {series} series of 1000 points"
    );
}

#[test]
fn noise_alone_rechecked_after_every_new_point_stays_quiet() {
    // The dashboard re-runs detection whenever a run adds a point; alerts are kept once raised.
    let mut rng = Rng::new(4);
    let v = noisy(&mut rng, 400, 10.0, 0.01);
    let mut raised = std::collections::BTreeSet::new();
    for n in 8..=v.len() {
        for c in detect(&v[..n], &Params::default()) {
            raised.insert(c.index);
        }
    }
    eprintln!("raised {raised:?}");
    assert!(raised.len() <= 1, "raised at {raised:?}");
}

#[test]
fn heavy_outliers_do_not_make_a_step() {
    let mut rng = Rng::new(5);
    let mut v = noisy(&mut rng, 200, 10.0, 0.01);
    for i in (7..200).step_by(23) {
        v[i] *= 1.5;
    }
    assert_eq!(detect(&v, &Params::default()), vec![]);
}

#[test]
fn driver_change_starts_a_segment_instead_of_an_alert() {
    let mut rng = Rng::new(6);
    let mut v = noisy(&mut rng, 30, 10.0, 0.01);
    v.extend(noisy(&mut rng, 30, 11.0, 0.01));
    let env: Vec<&str> = (0..60)
        .map(|i| if i < 30 { "Mesa 22.3.6" } else { "Mesa 23.0.0" })
        .collect();
    let a = analyse(&v, &env, &Params::default());
    assert_eq!(a.segment_starts, vec![0, 30]);
    assert_eq!(a.change_points, vec![]);
    // The same values with one environment: the step is an alert.
    let same = vec!["Mesa 22.3.6"; 60];
    assert_eq!(
        analyse(&v, &same, &Params::default()).change_points.len(),
        1
    );
}

#[test]
fn deterministic_series_flags_any_real_change() {
    let mut v = vec![1_000_000.0; 20];
    v.extend(vec![1_100_000.0; 10]);
    let cps = detect(&v, &Params::default());
    assert_eq!(cps.len(), 1);
    assert_eq!(cps[0].index, 20);
}

#[test]
fn short_series_are_not_tested() {
    assert_eq!(
        detect(&[1.0, 2.0, 3.0, 10.0, 10.0, 10.0, 10.0], &Params::default()),
        vec![]
    );
}

#[test]
#[ignore]
fn print_thresholds() {
    for n in [8, 12, 20, 45, 100, 400, 1000] {
        eprintln!(
            "n={n} thr(0.001)={:.2} thr(0.005)={:.2}",
            null::threshold(n, 3, 0.001),
            null::threshold(n, 3, 0.005)
        );
    }
    let mut rng = Rng::new(1);
    let mut ts = vec![];
    for _ in 0..100 {
        let mut v = noisy(&mut rng, 40, 10.0, 0.01);
        v.extend(noisy(&mut rng, 5, 10.3, 0.01));
        ts.push((max_statistic(&v, 1e-12, 3).unwrap().1 * 10.0).round() / 10.0);
    }
    ts.sort_by(|a, b| a.total_cmp(b));
    eprintln!("{ts:?}");
}

#[test]
fn a_step_in_the_two_newest_points_is_placed_at_its_own_commit() {
    // FLIP of a deterministic render, +20% in the two newest runs: the 3-point minimum alone puts
    // the split one point early with a mean change of +13.3%.
    let mut v = vec![0.1844; 30];
    v.extend([0.1844 * 1.2; 2]);
    let cps = detect(&v, &Params::default());
    assert_eq!(cps.len(), 1, "{cps:?}");
    assert_eq!(cps[0].index, 30);
    assert!((cps[0].relative_change - 0.2).abs() < 1e-9, "{cps:?}");
    let (k, _) = max_statistic(&v, sigma_floor(&v), 3).unwrap();
    assert_eq!(
        k, 29,
        "the constrained split is the one the refinement corrects"
    );
}

#[test]
fn noisy_steps_in_the_newest_points_land_on_their_commit_most_of_the_time() {
    // 5σ steps at 2% noise, checked when the 2nd, 3rd and 4th point after the step arrive.
    let mut rng = Rng::new(8);
    let trials = 200;
    let mut exact = [0usize; 3];
    for _ in 0..trials {
        let mut v = noisy(&mut rng, 40, 10.0, 0.02);
        v.extend(noisy(&mut rng, 4, 11.0, 0.02));
        for (j, n) in (42..=44).enumerate() {
            exact[j] += detect(&v[..n], &Params::default())
                .iter()
                .any(|c| c.index == 40) as usize;
        }
    }
    eprintln!("exact after 2, 3, 4 points: {exact:?} of {trials}");
    assert!(exact[2] * 100 >= trials * 95, "{exact:?} of {trials}");
}

/// The replay's two misplaced steps (issue 22, acceptance): a whole-run outlier (1.5x) the night
/// before a small step, and a noisy night (3.5σ here) at the new level of a large step. The
/// first was blamed on the outlier, the second a night late, while residuals were capped at 3σ.
#[test]
fn outliers_next_to_a_step_and_noisy_nights_at_its_new_level_do_not_move_it() {
    let mut rng = Rng::new(11);
    let (mut before_hits, mut noisy_hits, trials) = (0, 0, 200);
    for _ in 0..trials {
        // 2% noise, +7% step at 40 (3.5σ), the night before it 1.5x.
        let mut v = noisy(&mut rng, 40, 1.0, 0.02);
        v.extend(noisy(&mut rng, 12, 1.07, 0.02));
        v[39] = 1.5;
        let cps = detect(&v, &Params::default());
        if cps.iter().any(|c| c.index == 40) {
            before_hits += 1;
        }
        assert!(
            cps.iter().all(|c| c.index != 39),
            "blamed on the outlier: {cps:?}"
        );
        // 0.1% noise, +6% step at 40 (60σ), its first night 3.5σ above the new level.
        let mut w = noisy(&mut rng, 40, 0.1078, 0.001);
        w.extend(noisy(&mut rng, 12, 0.1142, 0.001));
        w[40] = 0.1142 * (1.0 + 0.0035);
        let cps = detect(&w, &Params::default());
        noisy_hits += cps.iter().any(|c| c.index == 40) as usize;
        let c = cps.iter().find(|c| c.index.abs_diff(40) <= 1).unwrap();
        assert!(c.location_probability() > 0.5, "{c:?}");
    }
    eprintln!("outlier before: {before_hits} of {trials}; noisy first night: {noisy_hits}");
    assert_eq!(noisy_hits, trials);
    // A 3.5σ step at 2% noise is not always told apart from its neighbours; never the outlier.
    assert!(before_hits * 10 >= trials * 8, "{before_hits} of {trials}");
}

#[test]
fn an_outlier_splits_evenly_and_the_later_side_is_blamed() {
    // A 20σ step: only the outlier between the levels leaves its place open.
    let mut rng = Rng::new(5);
    let mut v = noisy(&mut rng, 20, 1.0, 0.005);
    v.extend(noisy(&mut rng, 20, 1.1, 0.005));
    v[19] = 1.6;
    let sigma = noise_sigma(&v);
    let c = locate(&v, 20, sigma, 3, 37);
    let p = |j: usize| c.iter().find(|x| x.0 == j).unwrap().1;
    assert_eq!(p(19), p(20), "{c:?}");
    assert!(p(19) + p(20) > 0.99, "{c:?}");
    assert_eq!(most_likely(&c).map(|i| c[i].0), Some(20));
}

/// The rule before issue 22's exact-commit work: squares (capped at 10σ) around the sides'
/// medians. Kept here only to measure the new rule against it.
fn old_locate(values: &[f64], k: usize, sigma: f64, lo: usize, hi: usize) -> Vec<(usize, f64)> {
    let from = k.saturating_sub(LOCATE_WITHIN).max(lo).max(1);
    let to = (k + LOCATE_WITHIN).min(hi).min(values.len() - 1);
    let cap = LOCATE_CAP_SIGMAS * sigma;
    let (ml, mr) = (level(&values[..k]), level(&values[k..]));
    let kept: Vec<bool> = values
        .iter()
        .map(|v| (v - ml).abs() <= cap || (v - mr).abs() <= cap)
        .collect();
    let side = |r: std::ops::Range<usize>| -> Vec<f64> {
        r.filter(|&i| kept[i]).map(|i| values[i]).collect()
    };
    let c2 = LOCATE_CAP_SIGMAS * LOCATE_CAP_SIGMAS;
    let cost = |j: usize| {
        let (l, r) = (side(0..j), side(j..values.len()));
        let (ml, mr) = (level(&l), level(&r));
        let c = |v: &f64, m: f64| ((v - m) / sigma).powi(2).min(c2);
        l.iter().map(|v| c(v, ml)).sum::<f64>() + r.iter().map(|v| c(v, mr)).sum::<f64>()
    };
    let costs: Vec<(usize, f64)> = (from..=to).map(|j| (j, cost(j))).collect();
    let best = costs.iter().map(|c| c.1).fold(f64::INFINITY, f64::min);
    let w: Vec<(usize, f64)> = costs
        .iter()
        .map(|&(j, c)| (j, (-(c - best) / 2.0).exp()))
        .collect();
    let t: f64 = w.iter().map(|x| x.1).sum();
    w.into_iter().map(|(j, x)| (j, x / t)).collect()
}

fn t5(rng: &mut Rng) -> f64 {
    let chi2: f64 = (0..5).map(|_| rng.normal().powi(2)).sum();
    rng.normal() / (chi2 / 5.0).sqrt() / (5.0f64 / 3.0).sqrt()
}

#[test]
#[ignore]
fn print_location_rules() {
    for (name, heavy) in [("gauss", false), ("t5", true)] {
        for step in [2.5, 3.0, 3.5, 4.0, 5.0] {
            for after in [4usize, 8, 30] {
                let mut rng = Rng::new(77);
                let (mut old, mut new, trials) = (0, 0, 4000);
                let (mut old_sure, mut new_sure) = (0, 0);
                for _ in 0..trials {
                    let v: Vec<f64> = (0..40 + after)
                        .map(|i| {
                            let e = if heavy { t5(&mut rng) } else { rng.normal() };
                            1.0 + 0.02 * e + if i >= 40 { 0.02 * step } else { 0.0 }
                        })
                        .collect();
                    let sigma = noise_sigma(&v);
                    let hi = v.len() - 1;
                    let pick = |c: Vec<(usize, f64)>| most_likely(&c).map(|i| c[i].0);
                    let (o, n) = (
                        old_locate(&v, 40, sigma, 3, hi),
                        locate(&v, 40, sigma, 3, hi),
                    );
                    let at = |c: &[(usize, f64)]| c.iter().find(|x| x.0 == 40).map_or(0.0, |x| x.1);
                    old_sure += (at(&o) < 0.01) as usize;
                    new_sure += (at(&n) < 0.01) as usize;
                    old += (pick(o) == Some(40)) as usize;
                    new += (pick(n) == Some(40)) as usize;
                }
                eprintln!("{name} {step}σ after {after}: old {old} new {new} of {trials}; truth below 1%: old {old_sure} new {new_sure}");
            }
        }
    }
}

type Locate = fn(&[f64], usize, f64, usize, usize) -> Vec<(usize, f64)>;

fn pick(c: &[(usize, f64)]) -> Option<usize> {
    most_likely(c).map(|i| c[i].0)
}

fn the_location_does_not_depend_on_the_statistics_split(locate: Locate) {
    // A 4σ step at 40 with a whole-run outlier (1.5x) beside it, at 2% noise: the statistic's
    // split is a noisier estimate of the change, up to a few points off as runs arrive.
    let mut rng = Rng::new(21);
    let mut v = noisy(&mut rng, 40, 1.0, 0.02);
    v.extend(noisy(&mut rng, 12, 1.08, 0.02));
    v[41] = 1.5 * 1.08;
    let sigma = noise_sigma(&v);
    let at = locate(&v, 40, sigma, 3, v.len() - 3);
    assert_eq!(pick(&at), Some(40), "{at:?}");
    for k in 37..=43 {
        assert_eq!(
            locate(&v, k, sigma, 3, v.len() - 3),
            at,
            "statistic's split {k}"
        );
    }
}

/// The replay's last misplaced step (issue 22; `tessera-dashboard replay --seed 1`, lavapipe,
/// tiny-009 `upscale[scale=0.5]` GPU time, the segment before the driver change): +6% (3.4σ) at
/// 53, the night before it (0.4467) 1.2σ above the old level. Squares around the sides'
/// medians put it on 52 (56% against 39%): with 52 on the right, that side's median fell by
/// half a gap between two of its points, which priced the noisy nights after the step lower.
const REPLAY_SEED_1: [f64; 72] = [
    0.436791, 0.436186, 0.431128, 0.441651, 0.433667, 0.439475, 0.441873, 0.440227, 0.434469,
    0.434556, 0.446496, 0.4359, 0.425626, 0.434715, 0.433012, 0.436958, 0.443717, 0.428377,
    0.441138, 0.440743, 0.437841, 0.421106, 0.441194, 0.441837, 0.438576, 0.443754, 0.42772,
    0.433195, 0.430739, 0.431003, 0.433752, 0.435269, 0.421717, 0.66248, 0.436952, 0.420233,
    0.422526, 0.440843, 0.436454, 0.436281, 0.438588, 0.430278, 0.431681, 0.436542, 0.434848,
    0.443503, 0.440126, 0.435669, 0.436255, 0.432849, 0.444233, 0.433903, 0.446708, 0.462205,
    0.702721, 0.466222, 0.442863, 0.438825, 0.458124, 0.465871, 0.694959, 0.447505, 0.464959,
    0.471177, 0.679102, 0.461312, 0.451115, 0.46731, 0.452643, 0.454261, 0.462896, 0.453247,
];

fn a_small_step_after_a_noisy_night_is_placed_on_its_commit(locate: Locate) {
    let v = &REPLAY_SEED_1;
    let sigma = noise_sigma(v);
    let c = locate(v, 53, sigma, 3, v.len() - 3);
    assert_eq!(pick(&c), Some(53), "{c:?}");
}

fn the_true_commit_is_seldom_ruled_out(locate: Locate) {
    // 3σ steps at 2% Student-t noise (5 degrees of freedom, as timings have), 8 runs after the
    // step: a location probability below 1% at the true commit lets a confirmed alert move away
    // from it (`regressions::STRONG_EVIDENCE`); the squares around medians did so in 2.9% of
    // trials (58 of 2000), the Student-t profile likelihood in 1.5% (29); both take the true commit
    // as the most likely in 86% (1,721 and 1,709).
    let mut rng = Rng::new(77);
    let (mut ruled_out, mut exact, trials) = (0, 0, 2000);
    for _ in 0..trials {
        let v: Vec<f64> = (0..48)
            .map(|i| 1.0 + 0.02 * t5(&mut rng) + if i >= 40 { 0.06 } else { 0.0 })
            .collect();
        let c = locate(&v, 40, noise_sigma(&v), 3, v.len() - 1);
        ruled_out += (c.iter().find(|x| x.0 == 40).map_or(0.0, |x| x.1) < 0.01) as usize;
        exact += (pick(&c) == Some(40)) as usize;
    }
    eprintln!("true commit below 1%: {ruled_out} of {trials}; most likely: {exact}");
    assert!(ruled_out * 50 <= trials, "{ruled_out} of {trials}");
    // What a 3σ step allows: a neighbouring night past the midpoint takes it (about 14%).
    assert!(exact * 100 >= trials * 84, "{exact} of {trials}");
}

#[test]
fn location_does_not_depend_on_the_statistics_split() {
    the_location_does_not_depend_on_the_statistics_split(locate);
}

#[test]
fn small_step_after_a_noisy_night_is_placed_on_its_commit() {
    a_small_step_after_a_noisy_night_is_placed_on_its_commit(locate);
}

#[test]
fn true_commit_is_seldom_ruled_out() {
    the_true_commit_is_seldom_ruled_out(locate);
}

#[test]
#[should_panic]
fn old_rule_depends_on_the_statistics_split() {
    the_location_does_not_depend_on_the_statistics_split(old_locate);
}

#[test]
#[should_panic]
fn old_rule_places_the_small_step_a_night_early() {
    a_small_step_after_a_noisy_night_is_placed_on_its_commit(old_locate);
}

#[test]
#[should_panic]
fn old_rule_rules_the_true_commit_out_more_often() {
    the_true_commit_is_seldom_ruled_out(old_locate);
}
