//! The pages a team reads the morning after a change (issue 38), on replayed nightly histories
//! with an injected step (`tessera_dashboard::steps`): the comparison of the step's night says
//! "inconclusive" with its reason when nothing could be decided (too few frames, a CPU adapter),
//! never a green "no regression"; a change many σ outside its series' nightly noise is called
//! even below the fixed 5%.

mod common;

use axum::body::Body;
use axum::http::{Request, StatusCode};
use axum::Router;
use http_body_util::BodyExt;
use tessera_dashboard::detect::Params;
use tessera_dashboard::regressions::ingest_and_detect;
use tessera_dashboard::server::{app, AppState};
use tessera_dashboard::steps::StepHistory;
use tower::ServiceExt;

async fn get(app: &Router, uri: &str) -> String {
    let res = app
        .clone()
        .oneshot(Request::get(uri).body(Body::empty()).unwrap())
        .await
        .unwrap();
    let status = res.status();
    let body = res.into_body().collect().await.unwrap().to_bytes();
    let body = String::from_utf8_lossy(&body).into_owned();
    assert_eq!(status, StatusCode::OK, "{uri}: {body}");
    body
}

/// Stores nights `0..=last` of `h` as uploads store them (detection on each; nights already
/// stored change nothing) and serves them. Outside an async runtime: the PostgreSQL client is
/// synchronous.
fn served(store: &common::TestStore, h: &StepHistory, last: usize) -> Router {
    let mut c = store.pool.get().unwrap();
    for run in h.runs(&common::template()).iter().take(last + 1) {
        ingest_and_detect(&mut *c, run, &Params::default()).unwrap();
    }
    app(AppState::new(store.pool.clone(), None))
}

/// Runs `f` to completion on a fresh multi-threaded runtime.
fn block_on<F: std::future::Future>(f: F) -> F::Output {
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap()
        .block_on(f)
}

fn compare_uri(h: &StepHistory, a: usize, b: usize) -> String {
    format!("a={}&b={}", h.run_id(a), h.run_id(b))
}

fn variant<'a>(c: &'a serde_json::Value, name: &str) -> &'a serde_json::Value {
    c["scenarios"][0]["variants"]
        .as_array()
        .unwrap()
        .iter()
        .find(|v| v["variant"] == name)
        .unwrap()
}

#[test]
fn the_steps_night_with_four_frames_is_inconclusive_not_green() {
    for store in common::stores("the_steps_night_with_four_frames_is_inconclusive_not_green") {
        let mut h = StepHistory::h200(21, 20, "native", 1.05);
        h.frames = 4;
        let app = served(&store, &h, 20);
        block_on(async {
            let q = compare_uri(&h, 19, 20);
            let c: serde_json::Value =
                serde_json::from_str(&get(&app, &format!("/api/compare/runs?{q}")).await).unwrap();
            assert_eq!(c["decision"], "inconclusive", "{}", store.name);
            assert_eq!(
                c["undecided"],
                serde_json::json!(["too few frames in 3 of 3 timed variants (5 per side needed)"])
            );
            assert_eq!(variant(&c, "native")["time"]["verdict"], "too few frames");

            let page = get(&app, &format!("/compare/runs?{q}")).await;
            assert!(
            page.contains("<strong class=neutral>Verdict: inconclusive</strong> <span id=undecided>(too few frames in 3 of 3 timed variants (5 per side needed))</span>"),
            "{page}"
        );
            assert!(!page.contains("class=better>Verdict"), "{page}");
            let md = get(&app, &format!("/api/compare/runs?{q}&format=md")).await;
            assert!(
                md.contains("**Verdict: inconclusive**: too few frames in 3 of 3 timed variants"),
                "{md}"
            );
            // The run page says the +5% is untested, not merely grey.
            let run = get(&app, &format!("/runs/{}", h.run_id(20))).await;
            assert!(
                run.contains("title=\"too few frames, Mann-Whitney U"),
                "{run}"
            );
        });
    }
}

#[tokio::test]
async fn a_cpu_adapters_comparison_is_inconclusive_with_its_reason() {
    let store = common::sqlite();
    let mut h = StepHistory::h200(6, 5, "native", 1.05);
    h.gpu = false;
    h.name = "lavapipe".into();
    let app = served(&store, &h, 5);
    let q = compare_uri(&h, 4, 5);
    let c: serde_json::Value =
        serde_json::from_str(&get(&app, &format!("/api/compare/runs?{q}")).await).unwrap();
    assert_eq!(c["decision"], "inconclusive");
    let why = c["undecided"][0].as_str().unwrap();
    assert!(
        why.starts_with("a CPU adapter (llvmpipe") && why.ends_with("are not judged"),
        "{why}"
    );
    let page = get(&app, &format!("/compare/runs?{q}")).await;
    assert!(
        page.contains("<strong class=neutral>Verdict: inconclusive</strong>"),
        "{page}"
    );
}

#[test]
fn a_three_percent_step_thirty_sigma_out_is_called_slower() {
    for store in common::stores("a_three_percent_step_thirty_sigma_out_is_called_slower") {
        let h = StepHistory::h200(21, 20, "native", 1.03);
        let app = served(&store, &h, 20);
        let early = StepHistory {
            name: "early".into(),
            ..StepHistory::h200(4, 3, "native", 1.03)
        };
        let store2 = common::sqlite();
        let app2 = served(&store2, &early, 3);
        block_on(async {
            let q = compare_uri(&h, 19, 20);
            let c: serde_json::Value =
                serde_json::from_str(&get(&app, &format!("/api/compare/runs?{q}")).await).unwrap();
            let native = variant(&c, "native");
            let change = native["time"]["change"].as_f64().unwrap();
            assert!((change - 0.03).abs() < 0.005, "{native}");
            let sigma = native["noise"].as_f64().unwrap();
            assert!(sigma > 0.0002 && sigma < 0.003, "nightly noise {sigma}");
            assert!(change / sigma > 10.0, "{change} / {sigma}");
            // Below the fixed 5%, but far outside the series' own noise: slower, and it counts.
            assert_eq!(native["time"]["verdict"], "slower", "{native}");
            assert!(native["threshold_pct"].as_f64().unwrap() < 3.0, "{native}");
            assert_eq!(c["decision"], "regressed");
            assert_eq!(c["rule"]["noise_sigmas"], 5.0);
            // The other variants did not move: within noise or below their own threshold.
            for v in ["upscale[scale=0.5]", "upscale[scale=0.75]"] {
                assert_ne!(variant(&c, v)["time"]["verdict"], "slower", "{v}");
            }
            let page = get(&app, &format!("/compare/runs?{q}")).await;
            assert!(
                page.contains("<strong class=worse>Verdict: regressed</strong>")
                    && page.contains("σ of the variant's own night-to-night noise"),
                "{page}"
            );
            // The run page's "vs prev" judges with the same threshold: red, not grey.
            let run = get(&app, &format!("/runs/{}", h.run_id(20))).await;
            assert!(run.contains("class=\"n worse\" title=\"slower"), "{run}");

            // Without a history (the first nights), the fixed threshold alone: below threshold.
            let c: serde_json::Value = serde_json::from_str(
                &get(
                    &app2,
                    &format!("/api/compare/runs?{}", compare_uri(&early, 2, 3)),
                )
                .await,
            )
            .unwrap();
            let native = variant(&c, "native");
            assert_eq!(native["time"]["verdict"], "below threshold", "{native}");
            assert!(native["noise"].is_null());
            assert_eq!(c["decision"], "no regression");
        });
    }
}

#[test]
fn the_second_mornings_groups_are_led_by_the_slowed_native() {
    for store in common::stores("the_second_mornings_groups_are_led_by_the_slowed_native") {
        let h = StepHistory::h200(24, 20, "native", 1.05);
        // Every morning from the step's on: no speed-up that rose with native counts as better.
        let mut speedups_seen = 0;
        for last in 20..24 {
            let app = served(&store, &h, last);
            block_on(async {
                let groups: serde_json::Value =
                    serde_json::from_str(&get(&app, "/api/regressions/groups?status=all").await)
                        .unwrap();
                for g in groups.as_array().unwrap() {
                    for a in g["alerts"].as_array().unwrap() {
                        if a["series"]["measure"] == "speedup" && a["status"] != "withdrawn" {
                            assert_eq!(a["via_baseline"], true, "night {last}: {a}");
                            speedups_seen += 1;
                            let moved = a["moved_with"].as_str().unwrap();
                            let pct = percent_after(moved, "native GPU time ");
                            assert!((4.0..6.0).contains(&pct), "{moved}");
                        }
                    }
                    assert_eq!(g["better"], 0, "night {last}: {}", g["title"]);
                }
                if last == 21 {
                    // The second morning: the newest group is led by native's change.
                    let top = &groups[0];
                    let title = top["title"].as_str().unwrap();
                    let lead = title.split("; ").nth(1).unwrap();
                    assert!(lead.starts_with("native "), "{title}");
                    let pct = percent_after(lead, "gpu_ms ");
                    assert!((4.0..6.0).contains(&pct), "{title}");
                    let page = get(&app, &format!("/regressions/groups/{}", top["id"])).await;
                    assert!(
                        page.contains("moved with their baseline")
                            && page.contains("moved with native GPU time +"),
                        "{page}"
                    );
                    let md = get(&app, &format!("/regressions/groups/{}.md", top["id"])).await;
                    let count = |s: &str| {
                        s.split(" series on ")
                            .next()
                            .unwrap()
                            .rsplit(' ')
                            .next()
                            .unwrap()
                            .to_string()
                    };
                    // The HTML and the Markdown count the same series.
                    assert_eq!(count(title), count(md.lines().next().unwrap()), "{md}");
                }
            });
        }
        // Both upscale variants' speed-ups rose with native and were alerted.
        assert!(speedups_seen >= 2, "{speedups_seen}");
    }
}

/// The signed percentage right after `prefix` in `text` (`+4.8%` → 4.8).
fn percent_after(text: &str, prefix: &str) -> f64 {
    let rest = &text[text
        .find(prefix)
        .unwrap_or_else(|| panic!("{prefix:?} in {text:?}"))
        + prefix.len()..];
    rest[..rest.find('%').unwrap()].parse().unwrap()
}

#[test]
fn an_alert_that_moves_leaves_a_group_whose_others_stay() {
    use tessera_dashboard::store::alerts::{self, DetectionStatus, Placement};
    use tessera_dashboard::store::groups::{self, Named};
    for store in common::stores("an_alert_that_moves_leaves_a_group_whose_others_stay") {
        let h = StepHistory::h200(10, 99, "native", 1.0);
        let mut c = store.pool.get().unwrap();
        for run in h.runs(&common::template()) {
            tessera_dashboard::store::ingest::ingest(&mut *c, &run).unwrap();
        }
        let pk = |c: &mut dyn tessera_dashboard::db::Connection, n: usize| {
            c.query(
                "SELECT id FROM runs WHERE run_id = $1",
                &[h.run_id(n).as_str().into()],
            )
            .unwrap()[0]
                .i64(0)
                .unwrap()
        };
        let series: Vec<i64> = c
            .query("SELECT id FROM series ORDER BY id LIMIT 6", &[])
            .unwrap()
            .iter()
            .map(|r| r.i64(0).unwrap())
            .collect();
        let at = |c: &mut dyn tessera_dashboard::db::Connection, n: usize| Placement {
            run_pk_before: pk(c, n - 1),
            run_pk_after: pk(c, n),
            value_before: 1.0,
            value_after: 1.1,
            relative_change: 0.1,
            change_low: 0.09,
            change_high: 0.11,
            confidence: 0.999,
            location_probability: 0.9,
            first_candidate: pk(c, n),
            last_candidate: pk(c, n),
            status: DetectionStatus::Pending,
        };
        let group_of = |c: &mut dyn tessera_dashboard::db::Connection, id: i64| {
            c.query(
                "SELECT group_id FROM regressions WHERE id = $1",
                &[id.into()],
            )
            .unwrap()[0]
                .i64(0)
                .unwrap()
        };
        // Two series placed a night early (night 4), one at night 5.
        let p4 = at(&mut *c, 4);
        let p5 = at(&mut *c, 5);
        let a = alerts::insert(&mut *c, series[0], &p4).unwrap();
        let b = alerts::insert(&mut *c, series[1], &p4).unwrap();
        let d = alerts::insert(&mut *c, series[2], &p5).unwrap();
        let (early, right) = (group_of(&mut *c, a), group_of(&mut *c, d));
        assert_eq!(group_of(&mut *c, b), early);
        assert_ne!(early, right);
        // a moves to night 5: it joins night 5's group; b stays where it is.
        alerts::place(&mut *c, a, &p5).unwrap();
        assert_eq!(group_of(&mut *c, a), right, "{}", store.name);
        assert_eq!(group_of(&mut *c, b), early);
        // b follows: the emptied group's id and key lead to where its alerts went.
        alerts::place(&mut *c, b, &p5).unwrap();
        assert_eq!(group_of(&mut *c, b), right);
        assert_eq!(
            groups::resolve(&mut *c, &early.to_string()).unwrap(),
            Named::Key(right)
        );
        // A group that moves with no other group at the new range: the first mover makes a
        // new group, the second joins it, the old id leads there.
        let p7 = at(&mut *c, 7);
        let p8 = at(&mut *c, 8);
        let e = alerts::insert(&mut *c, series[3], &p7).unwrap();
        let f = alerts::insert(&mut *c, series[4], &p7).unwrap();
        let old = group_of(&mut *c, e);
        alerts::place(&mut *c, e, &p8).unwrap();
        let new = group_of(&mut *c, e);
        assert_ne!(new, old);
        assert_eq!(group_of(&mut *c, f), old);
        alerts::place(&mut *c, f, &p8).unwrap();
        assert_eq!(group_of(&mut *c, f), new);
        assert_eq!(
            groups::resolve(&mut *c, &old.to_string()).unwrap(),
            Named::Key(new)
        );
        // One alert alone moving keeps its group's id.
        let p2 = at(&mut *c, 2);
        let p1 = at(&mut *c, 1);
        let g = alerts::insert(&mut *c, series[5], &p1).unwrap();
        let alone = group_of(&mut *c, g);
        alerts::place(&mut *c, g, &p2).unwrap();
        assert_eq!(group_of(&mut *c, g), alone);
        let history = alerts::events_of_group(&mut *c, right).unwrap();
        assert!(
            history.iter().any(|e| e.kind == "regrouped"
                && e.detail
                    .starts_with(&format!("left group {early} for group {right}"))),
            "{history:?}"
        );
        // No alert is left in a group it moved out of: every live alert's group has its range.
        for (id, want) in [
            (a, right),
            (b, right),
            (e, new),
            (f, new),
            (g, alone),
            (d, right),
        ] {
            assert_eq!(group_of(&mut *c, id), want, "alert {id}");
        }
    }
}

/// An H200 and a lavapipe history of 10 nights at the same commits (the nightly pair of one
/// commit shares its night), stored without detection: the tests below place alerts by hand.
/// Returns the store's run pk of (adapter, night), `h200` first.
fn two_adapters_nightly(
    c: &mut dyn tessera_dashboard::db::Connection,
) -> impl Fn(&mut dyn tessera_dashboard::db::Connection, &str, usize) -> i64 {
    let h200 = StepHistory::h200(10, 99, "native", 1.0);
    let lavapipe = StepHistory {
        name: "lavapipe".into(),
        gpu: false,
        ..h200.clone()
    };
    for h in [&h200, &lavapipe] {
        for run in h.runs(&common::template()) {
            tessera_dashboard::store::ingest::ingest(c, &run).unwrap();
        }
    }
    move |c: &mut dyn tessera_dashboard::db::Connection, adapter: &str, n: usize| {
        c.query(
            "SELECT id FROM runs WHERE run_id = $1",
            &[format!("{adapter}-{n:04}").as_str().into()],
        )
        .unwrap()[0]
            .i64(0)
            .unwrap()
    }
}

/// The frame-time series of `adapter` (a part of its name), by variant.
fn frame_series(
    c: &mut dyn tessera_dashboard::db::Connection,
    adapter: &str,
) -> Vec<(i64, String)> {
    c.query(
        "SELECT s.id, s.variant FROM series s JOIN adapters a ON a.id = s.adapter_id
         WHERE s.measure = 'gpu_ms.median' AND a.name LIKE $1 ORDER BY s.id",
        &[format!("%{adapter}%").as_str().into()],
    )
    .unwrap()
    .iter()
    .map(|r| (r.i64(0).unwrap(), r.string(1).unwrap()))
    .collect()
}

fn group_of(c: &mut dyn tessera_dashboard::db::Connection, id: i64) -> i64 {
    c.query(
        "SELECT group_id FROM regressions WHERE id = $1",
        &[id.into()],
    )
    .unwrap()[0]
        .i64(0)
        .unwrap()
}

#[test]
fn a_series_joins_a_group_by_its_own_located_commit_not_an_overlapping_range() {
    use tessera_dashboard::store::alerts::{self, DetectionStatus, Placement};
    for store in common::stores("a_series_joins_a_group_by_its_own_located_commit") {
        let mut c = store.pool.get().unwrap();
        let pk = two_adapters_nightly(&mut *c);
        let gpu = frame_series(&mut *c, "H200");
        // lavapipe's series of other variants than the H200's, so the title's lead tells them apart.
        let cpu: Vec<(i64, String)> = frame_series(&mut *c, "llvmpipe")
            .into_iter()
            .filter(|s| s.1 != gpu[0].1)
            .collect();
        // Located between nights `at - 1` and `at` of `adapter`; `first..=last` the candidates.
        let place = |c: &mut dyn tessera_dashboard::db::Connection,
                     adapter: &str,
                     at: usize,
                     (first, last): (usize, usize),
                     p: f64| Placement {
            run_pk_before: pk(c, adapter, at - 1),
            run_pk_after: pk(c, adapter, at),
            value_before: 1.0,
            value_after: 1.05,
            relative_change: 0.05,
            change_low: if p > 0.9 { 0.048 } else { 0.01 },
            change_high: if p > 0.9 { 0.052 } else { 0.09 },
            confidence: 0.999,
            location_probability: p,
            first_candidate: pk(c, adapter, first),
            last_candidate: pk(c, adapter, last),
            status: DetectionStatus::Pending,
        };
        // The morning after the step: the H200 places it on night 5, its candidates still
        // nights 4 to 6.
        let early = place(&mut *c, "h200", 5, (4, 6), 0.9);
        let h200 = alerts::insert(&mut *c, gpu[0].0, &early).unwrap();
        let g = group_of(&mut *c, h200);
        // lavapipe's noisy series locates a change on night 6 at 58%, over the same candidate
        // nights: its own commit is another, so it is not in the H200's group.
        let other_night = place(&mut *c, "lavapipe", 6, (4, 6), 0.58);
        let late = alerts::insert(&mut *c, cpu[0].0, &other_night).unwrap();
        assert_ne!(group_of(&mut *c, late), g, "{}", store.name);
        // A lavapipe series that locates it on night 5, however loosely, names the same commit:
        // it joins the H200's group (two adapters, one change).
        let same_night = place(&mut *c, "lavapipe", 5, (4, 6), 0.58);
        let joined = alerts::insert(&mut *c, cpu[1].0, &same_night).unwrap();
        assert_eq!(group_of(&mut *c, joined), g, "{}", store.name);
        // The H200's location turns exact on night 5: the same commit, the same group; the
        // night-6 series is still apart.
        let exact = place(&mut *c, "h200", 5, (5, 5), 0.99);
        alerts::place(&mut *c, h200, &exact).unwrap();
        assert_eq!(group_of(&mut *c, h200), g);
        assert_ne!(group_of(&mut *c, late), g);
        // The night-6 series moves to night 5: now it joins.
        alerts::place(&mut *c, late, &same_night).unwrap();
        assert_eq!(group_of(&mut *c, late), g);
        // The group is led by the H200's sure change, not a loose lavapipe one.
        let title = tessera_dashboard::titles::of(
            &tessera_dashboard::store::groups::get(&mut *c, g).unwrap(),
        );
        assert!(title.contains("3 series on 2 adapters"), "{title}");
        let lead = title.split("; ").nth(1).unwrap();
        assert!(lead.starts_with(&format!("{} ", gpu[0].1)), "{title}");
    }
}

#[test]
fn a_group_title_leads_with_the_surest_change_not_the_largest() {
    use tessera_dashboard::store::alerts::{self, DetectionStatus, Placement};
    for store in common::stores("a_group_title_leads_with_the_surest_change") {
        let mut c = store.pool.get().unwrap();
        let pk = two_adapters_nightly(&mut *c);
        // Two variants' frame times on one night, +5% with a tight interval and +40% with a
        // wide one located at 60%.
        let two = frame_series(&mut *c, "H200");
        let sure = Placement {
            run_pk_before: pk(&mut *c, "h200", 7),
            run_pk_after: pk(&mut *c, "h200", 8),
            value_before: 1.0,
            value_after: 1.05,
            relative_change: 0.05,
            change_low: 0.045,
            change_high: 0.055,
            confidence: 0.999,
            location_probability: 0.99,
            first_candidate: pk(&mut *c, "h200", 8),
            last_candidate: pk(&mut *c, "h200", 8),
            status: DetectionStatus::Pending,
        };
        let mut big = sure.clone();
        big.relative_change = 0.4;
        (big.change_low, big.change_high) = (0.05, 0.75);
        big.location_probability = 0.6;
        let x = alerts::insert(&mut *c, two[0].0, &sure).unwrap();
        let y = alerts::insert(&mut *c, two[1].0, &big).unwrap();
        let gid = group_of(&mut *c, x);
        assert_eq!(group_of(&mut *c, y), gid);
        let title = tessera_dashboard::titles::of(
            &tessera_dashboard::store::groups::get(&mut *c, gid).unwrap(),
        );
        let lead = title.split("; ").nth(1).unwrap();
        assert!(lead.starts_with(&format!("{} ", two[0].1)), "{title}");
        assert!(lead.contains("+5.0%"), "{title}");
    }
}

#[tokio::test]
async fn conditions_are_shown_and_a_lower_clock_is_named_beside_the_verdict() {
    let store = common::sqlite();
    let mut h = StepHistory::h200(12, 99, "native", 1.0);
    h.clock_from = Some(11);
    let app = served(&store, &h, 11);
    let run = get(&app, &format!("/runs/{}", h.run_id(10))).await;
    assert!(
        run.contains("<th class=n>graphics clock (MHz)</th>")
            && run.contains("<th class=n>energy per frame (mJ)</th>")
            && run.contains("1980 <span class=muted>(1965–1995)</span>")
            && run.contains("<td>no</td>"),
        "{run}"
    );
    let q = compare_uri(&h, 10, 11);
    let c: serde_json::Value =
        serde_json::from_str(&get(&app, &format!("/api/compare/runs?{q}")).await).unwrap();
    let env: Vec<&str> = c["environment"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e.as_str().unwrap())
        .collect();
    assert_eq!(
        env,
        [
            "graphics clock 1980 → 1410 MHz (-29%, median over variants)",
            "temperature 48 → 71 °C",
            "throttled variants 0 → 3"
        ]
    );
    let page = get(&app, &format!("/compare/runs?{q}")).await;
    let verdict = page.find("id=verdict").unwrap();
    let diff = page.find("<p id=environment class=neutral><strong>Conditions differ:</strong> graphics clock 1980 → 1410 MHz").unwrap();
    let first_table = page.find("<table class=compare>").unwrap();
    assert!(verdict < diff && diff < first_table, "{page}");
    assert!(
        page.contains("<span class=worse title=\"power limit reported (sw-power-cap)\">yes</span>")
    );
    // Same conditions: said so, not silent.
    let same = get(&app, &format!("/compare/runs?{}", compare_uri(&h, 9, 10))).await;
    assert!(same.contains("<p id=environment class=muted>Conditions: the same driver"));
}

/// Adapter ids by name (of `/api/compare`'s adapter list).
async fn adapter_id(app: &Router, name: &str) -> i64 {
    let c: serde_json::Value = serde_json::from_str(&get(app, "/api/compare").await).unwrap();
    c["adapters"]
        .as_array()
        .unwrap()
        .iter()
        .find(|a| a["name"].as_str().unwrap().starts_with(name))
        .unwrap()["id"]
        .as_i64()
        .unwrap()
}

#[tokio::test]
async fn adapters_are_compared_on_the_runs_that_share_scenarios() {
    let store = common::sqlite();
    let h200 = StepHistory::h200(4, 99, "native", 1.0);
    let mut lavapipe = StepHistory::h200(4, 99, "native", 1.0);
    lavapipe.gpu = false;
    lavapipe.name = "lavapipe".into();
    let template = common::template();
    {
        let mut c = store.pool.get().unwrap();
        for run in h200
            .runs(&template)
            .into_iter()
            .chain(lavapipe.runs(&template))
        {
            ingest_and_detect(&mut *c, &run, &Params::default()).unwrap();
        }
        // A newer lavapipe run of another scenario only (a suite split over runs): not paired.
        let mut other = lavapipe.runs(&template).pop().unwrap();
        other.run.run_id = "lavapipe-split".into();
        other.run.started_at = tessera_dashboard::synth::time_after(10 * 1440);
        for s in &mut other.scenarios {
            s.scenario = "elsewhere".into();
            s.run_id = "lavapipe-split".into();
        }
        ingest_and_detect(&mut *c, &other, &Params::default()).unwrap();
    }
    let app = app(AppState::new(store.pool.clone(), None));
    let (a, b) = (
        adapter_id(&app, "NVIDIA H200").await,
        adapter_id(&app, "llvmpipe").await,
    );
    let c: serde_json::Value =
        serde_json::from_str(&get(&app, &format!("/api/compare?a={a}&b={b}")).await).unwrap();
    assert_eq!(c["run_a"], "h200-0003");
    assert_eq!(c["run_b"], "lavapipe-0003");
    assert_eq!(c["matched_by"], "same commit");
    assert_eq!(c["scenarios"], serde_json::json!(["tiny"]));
    let rows = c["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 3);
    for r in rows.iter().filter(|r| r["variant"] != "native") {
        let ratio = r["ratio"].as_f64().unwrap();
        let [lo, hi] = [
            r["interval"][0].as_f64().unwrap(),
            r["interval"][1].as_f64().unwrap(),
        ];
        assert!(lo <= ratio && ratio <= hi, "{r}");
        // The same template on both: the saving is about the same.
        assert!((ratio - 1.0).abs() < 0.1, "{r}");
    }
    let g = c["geometric_mean"].as_f64().unwrap();
    assert!((g - 1.0).abs() < 0.1, "{g}");
    assert!(c["cpu_adapter"].as_str().unwrap().starts_with("llvmpipe"));
    let page = get(&app, &format!("/compare?a={a}&b={b}")).await;
    assert!(
        page.contains("<svg xmlns='http://www.w3.org/2000/svg' class=intervals")
            && page.matches("class=whisker").count() == 2
            && page.contains("id=cpu-warning")
            && page.contains("Geometric mean of the speed-up ratios B / A")
            && page.contains("scenario shared: tiny"),
        "{page}"
    );
}

#[tokio::test]
async fn adapters_without_a_shared_scenario_say_what_each_has() {
    let store = common::sqlite();
    let h200 = StepHistory::h200(2, 99, "native", 1.0);
    let mut lavapipe = StepHistory::h200(2, 99, "native", 1.0);
    lavapipe.gpu = false;
    lavapipe.name = "lavapipe".into();
    let template = common::template();
    {
        let mut c = store.pool.get().unwrap();
        for run in h200.runs(&template) {
            ingest_and_detect(&mut *c, &run, &Params::default()).unwrap();
        }
        for mut run in lavapipe.runs(&template) {
            run.run.suite = Some("quality".into());
            for s in &mut run.scenarios {
                s.scenario = "cut".into();
            }
            ingest_and_detect(&mut *c, &run, &Params::default()).unwrap();
        }
    }
    let app = app(AppState::new(store.pool.clone(), None));
    let (a, b) = (
        adapter_id(&app, "NVIDIA H200").await,
        adapter_id(&app, "llvmpipe").await,
    );
    let c: serde_json::Value =
        serde_json::from_str(&get(&app, &format!("/api/compare?a={a}&b={b}")).await).unwrap();
    assert!(c["run_a"].is_null() && c["rows"].as_array().unwrap().is_empty());
    assert_eq!(c["holdings"]["scenarios_a"], serde_json::json!(["tiny"]));
    assert_eq!(c["holdings"]["scenarios_b"], serde_json::json!(["cut"]));
    assert_eq!(c["holdings"]["suites_b"], serde_json::json!(["quality"]));
    let page = get(&app, &format!("/compare?a={a}&b={b}")).await;
    assert!(
        page.contains("id=nothing-shared")
            && page.contains("b has suites quality and scenarios cut")
            && page.contains("scenarios both have run: none"),
        "{page}"
    );
}

#[test]
fn an_adapter_that_stops_reporting_a_suite_raises_a_stoppage() {
    use tessera_dashboard::store::stoppage::stoppages;
    let store = common::sqlite();
    let h = StepHistory::h200(10, 99, "native", 1.0);
    let mut c = store.pool.get().unwrap();
    for run in h.runs(&common::template()) {
        ingest_and_detect(&mut *c, &run, &Params::default()).unwrap();
    }
    // Night 9's commit is at day 9 00:00: a night later is within the nightly gap...
    let at = |day: u64| tessera_dashboard::synth::time_after(day * 1440 + 600);
    assert!(stoppages(&mut *c, &at(10)).unwrap().is_empty());
    // ...four nights later is not.
    let s = stoppages(&mut *c, &at(13)).unwrap();
    assert_eq!(s.len(), 1, "{s:?}");
    assert_eq!(
        s[0].message,
        "NVIDIA H200 (replay): no fx run for 4 nights (usually every night)"
    );
    assert_eq!((s[0].nights, s[0].usual_gap), (4, 1));
    assert_eq!(s[0].last_run, "h200-0009");
    // A year of silence is a retired adapter, not a stoppage.
    assert!(stoppages(&mut *c, &at(300)).unwrap().is_empty());

    // Against today's clock: the same history moved to end 4 nights ago, on the page and in
    // the feed.
    let recent = common::sqlite();
    let now = chrono::Utc::now();
    let day = |n: usize| {
        (now - chrono::Duration::days(13 - n as i64))
            .to_rfc3339_opts(chrono::SecondsFormat::Secs, true)
    };
    let mut c = recent.pool.get().unwrap();
    for (n, mut run) in h.runs(&common::template()).into_iter().enumerate() {
        run.run.commit_time = Some(day(n));
        run.run.started_at = day(n);
        run.run.finished_at = Some(day(n));
        ingest_and_detect(&mut *c, &run, &Params::default()).unwrap();
    }
    let app = app(AppState::new(recent.pool.clone(), None));
    block_on(async {
        let page = get(&app, "/regressions").await;
        assert!(
            page.contains("<h2 class=worse>Data stopped</h2>")
                && page
                    .contains("NVIDIA H200 (replay): no fx run for 4 nights (usually every night)"),
            "{page}"
        );
        let feed = get(&app, "/regressions/feed.atom").await;
        let doc = roxmltree::Document::parse(&feed).unwrap();
        let entry = doc
            .descendants()
            .find(|n| n.has_tag_name("category") && n.attribute("term") == Some("data-stoppage"))
            .and_then(|n| n.parent())
            .unwrap();
        let text = |tag: &str| {
            entry
                .children()
                .find(|n| n.has_tag_name(tag))
                .unwrap()
                .text()
                .unwrap()
                .to_string()
        };
        assert_eq!(
            text("title"),
            "NVIDIA H200 (replay): no fx run for 4 nights (usually every night)"
        );
        // The newest run, plus the usual gap and one night.
        assert_eq!(text("updated"), day(11));
    });
}

#[test]
fn a_wrong_token_is_called_unknown_not_missing() {
    let store = common::sqlite();
    let app = app(AppState::new(store.pool.clone(), Some("right".into())));
    block_on(async {
        let send = |auth: Option<&'static str>| {
            let mut req = Request::delete("/api/runs/nothing");
            if let Some(a) = auth {
                req = req.header("Authorization", a);
            }
            app.clone().oneshot(req.body(Body::empty()).unwrap())
        };
        let body = |res: axum::response::Response| async move {
            let status = res.status();
            let b = res.into_body().collect().await.unwrap().to_bytes();
            (status, String::from_utf8_lossy(&b).into_owned())
        };
        let (status, missing) = body(send(None).await.unwrap()).await;
        assert_eq!(status, StatusCode::UNAUTHORIZED);
        assert!(missing.contains("needs the header"), "{missing}");
        let (status, wrong) = body(send(Some("Bearer wrong")).await.unwrap()).await;
        assert_eq!(status, StatusCode::UNAUTHORIZED);
        assert!(
            wrong.contains("is not a known write token") && !wrong.contains("needs the header"),
            "{wrong}"
        );
        // A header sent in another scheme, or Bearer with nothing: said, not "missing".
        for (sent, says) in [
            ("Token right", "uses the scheme \\\"Token\\\", not `Bearer`"),
            ("Bearer ", "`Bearer` is followed by no token"),
        ] {
            let (status, text) = body(send(Some(sent)).await.unwrap()).await;
            assert_eq!(status, StatusCode::UNAUTHORIZED);
            assert!(
                text.contains("header was sent") && text.contains(says),
                "{sent}: {text}"
            );
        }
    });
}

/// A store holding the image viewer's fixture runs (the error-against-time pages' data), served.
fn viewer_runs() -> (common::TestStore, Router) {
    let store = common::sqlite();
    let viewer =
        std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/viewer-runs");
    tessera_dashboard::import::import(&store.pool, &viewer, &Params::default()).unwrap();
    let app = app(AppState::new(store.pool.clone(), None));
    (store, app)
}

#[test]
fn error_against_time_lists_only_error_measures_and_shows_two_beside_each_other() {
    let (_store, app) = viewer_runs();
    block_on(async {
        let v: serde_json::Value =
            serde_json::from_str(&get(&app, "/api/pareto?scenario=adaptive").await).unwrap();
        let metrics: Vec<&str> = v["metrics"]
            .as_array()
            .unwrap()
            .iter()
            .map(|m| m.as_str().unwrap())
            .collect();
        assert!(!metrics.is_empty());
        for m in &metrics {
            assert!(
                tessera_dashboard::server::pareto::is_error_measure(m),
                "{m} in {metrics:?}"
            );
        }
        // The raw records do hold technique checks the menu leaves out.
        let run: serde_json::Value = serde_json::from_str(
            &get(&app, &format!("/api/runs/{}", v["run"].as_str().unwrap())).await,
        )
        .unwrap();
        let raw = run.to_string();
        assert!(
            raw.contains("\"shading-rate") || raw.contains("\"model-"),
            "{raw}"
        );
        let v: serde_json::Value =
            serde_json::from_str(&get(&app, "/api/pareto?scenario=basic&metric=flip").await)
                .unwrap();
        let second = v["metric2"].as_str().unwrap();
        assert_ne!(second, "flip");
        // The same variants, less those without a finite value (native's PSNR is infinite).
        let names = |k: &str| -> Vec<String> {
            v[k].as_array()
                .unwrap()
                .iter()
                .map(|p| p["variant"].as_str().unwrap().to_string())
                .collect()
        };
        let (first, beside) = (names("points"), names("points2"));
        assert!(
            beside.len() >= first.len() - 1 && !beside.is_empty(),
            "{beside:?}"
        );
        assert!(beside.iter().all(|n| first.contains(n)), "{beside:?}");
        let page = get(&app, "/pareto?scenario=basic&metric=flip").await;
        assert!(
            page.contains("id=pareto-second")
                && page.contains("<th class=n>speed-up (×)</th>")
                && page.contains("<ul class=\"legend techniques\">")
                && page.contains("></span>checkerboard</li>")
                && page.contains(&format!("<th>front ({second})</th>")),
            "{page}"
        );
        let one = get(&app, "/pareto?scenario=basic&metric=flip&metric2=none").await;
        assert!(!one.contains("id=pareto-second"));
    });
}

/// A number beside a point names a row of the table; a point with no row (`native` and
/// `native-deferred` have an SSIM but no PSNR, so the PSNR table has no row for them) gets none:
/// not the "1" every such point read before.
#[test]
fn error_against_time_numbers_only_the_points_with_a_table_row() {
    let (_store, app) = viewer_runs();
    block_on(async {
        let page = get(&app, "/pareto?scenario=adaptive&metric=psnr&metric2=ssim").await;
        // The table's rows: number and variant.
        let table = &page[page.find("<table id=pareto>").expect("table")..];
        let rows: Vec<(String, String)> = table
            .split("<tr><td class=n>")
            .skip(1)
            .map(|r| {
                let n = r[..r.find("</td>").unwrap()].to_string();
                let name = &r[r.find("</span>").unwrap() + "</span>".len()..];
                let name = &name[..name.find("</td>").unwrap()];
                let plain: String = name
                    .split('<')
                    .map(|part| part.split_once('>').map_or(part, |(_, t)| t))
                    .collect();
                (n, plain)
            })
            .collect();
        assert!(!rows.is_empty(), "{table}");
        // The canvas chart's points: a number only where the table has that row.
        let spec = &page[page.find("id=\"pareto-chart-data\">").unwrap()..];
        let spec = &spec[spec.find('>').unwrap() + 1..spec.find("</script>").unwrap()];
        let spec: serde_json::Value = serde_json::from_str(spec).unwrap();
        for p in spec["points"].as_array().unwrap() {
            let row = rows
                .iter()
                .find(|(_, v)| *v == p["label"].as_str().unwrap());
            match row {
                Some((n, _)) => assert_eq!(p["num"].to_string(), *n, "{p}"),
                None => assert!(p["num"].is_null(), "{p}"),
            }
        }
        // The SSIM chart beside it holds the two natives (no PSNR row): four points, two numbers.
        let second = &page[page.find("id=pareto-second").unwrap()..];
        let second = &second[..second.find("</svg>").unwrap()];
        let points = second.matches("<circle class='point'").count();
        let numbers: Vec<&str> = second
            .split("font-size='10'>")
            .skip(1)
            .map(|t| &t[..t.find("</text>").unwrap()])
            .filter(|t| t.chars().all(|c| c.is_ascii_digit()))
            .collect();
        assert!(second.contains("<title>native: "), "{second}");
        assert!(points > rows.len(), "{second}");
        let mut want: Vec<&str> = rows.iter().map(|(n, _)| n.as_str()).collect();
        let mut got = numbers.clone();
        want.sort();
        got.sort();
        assert_eq!(got, want, "{second}");
    });
}

#[test]
fn error_against_time_draws_error_bars_where_repeats_exist() {
    let (_store, app) = viewer_runs();
    block_on(async {
        let v: serde_json::Value =
            serde_json::from_str(&get(&app, "/api/pareto?scenario=basic&metric=psnr").await)
                .unwrap();
        let points = v["points"].as_array().unwrap();
        // Six compared frames with different PSNRs: an interval around the value.
        let up = points
            .iter()
            .find(|p| p["variant"] == "upscale[scale=0.5]")
            .unwrap();
        let value = up["value"].as_f64().unwrap();
        let [lo, hi] = [0, 1].map(|i| up["value_interval"][i].as_f64().unwrap());
        assert!(lo < value && value < hi && hi - lo < 1.0, "{up}");
        let page = get(&app, "/pareto?scenario=basic&metric=psnr").await;
        assert!(page.contains("\"y_interval\":["), "{page}");
        assert!(page.contains("title=\"95% interval\""), "{page}");
    });
}

#[test]
fn a_run_without_a_commit_is_flagged_and_never_the_previous_run() {
    let store = common::sqlite();
    let h = StepHistory::h200(4, 99, "native", 1.0);
    {
        let mut c = store.pool.get().unwrap();
        for (n, mut run) in h.runs(&common::template()).into_iter().enumerate() {
            if n == 2 {
                run.run.commit = None;
            }
            ingest_and_detect(&mut *c, &run, &Params::default()).unwrap();
        }
    }
    let app = app(AppState::new(store.pool.clone(), None));
    block_on(async {
        let flagged = get(&app, &format!("/runs/{}", h.run_id(2))).await;
        assert!(flagged.contains("id=no-commit"), "{flagged}");
        // Night 3's previous run is night 1, not the commit-less night 2.
        let next = get(&app, &format!("/runs/{}", h.run_id(3))).await;
        assert!(!next.contains("id=no-commit"));
        assert!(
            next.contains(&format!("compare/runs?a={}&b={}", h.run_id(1), h.run_id(3))),
            "{next}"
        );
    });
}

#[test]
fn replay_with_a_bad_template_leaves_no_store() {
    let dir = tempfile::tempdir().unwrap();
    let bin = env!("CARGO_BIN_EXE_tessera-dashboard");
    // A template that does not exist: an error naming it, and no store made.
    let db = dir.path().join("bad.sqlite");
    let out = std::process::Command::new(bin)
        .current_dir(dir.path())
        .args([
            "replay",
            "no/such/run",
            "--nights",
            "40",
            "--scenarios",
            "1",
            "--db",
        ])
        .arg(&db)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("reading the template run no/such/run"),
        "{err}"
    );
    assert!(!db.exists(), "an empty store was left behind");
}

/// Runs `tessera-dashboard` with `args` in `dir`, killed after `limit`; its exit code (`None`
/// when it was killed), stdout and stderr, and its process id.
fn dashboard_in(
    dir: &std::path::Path,
    args: &[&str],
    limit: std::time::Duration,
) -> (Option<i32>, String, String, u32) {
    use std::io::Read;
    use std::process::{Command, Stdio};
    let mut child = Command::new(env!("CARGO_BIN_EXE_tessera-dashboard"))
        .current_dir(dir)
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let pid = child.id();
    // Read as it comes, so a full pipe never stops the child.
    let reader = |r: Option<Box<dyn std::io::Read + Send>>| {
        std::thread::spawn(move || {
            let mut s = String::new();
            if let Some(mut r) = r {
                r.read_to_string(&mut s).unwrap();
            }
            s
        })
    };
    let out = reader(child.stdout.take().map(|r| Box::new(r) as _));
    let err = reader(child.stderr.take().map(|r| Box::new(r) as _));
    let start = std::time::Instant::now();
    let code = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status.code();
        }
        if start.elapsed() > limit {
            child.kill().unwrap();
            child.wait().unwrap();
            break None;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    };
    let (out, err) = (out.join().unwrap(), err.join().unwrap());
    (code, out, err, pid)
}

#[test]
fn replay_runs_outside_the_repository_and_refuses_too_few_nights() {
    let dir = tempfile::tempdir().unwrap();
    let limit = std::time::Duration::from_secs(240);
    // Too few nights for its injections: refused at once (it looked for a night for ever), with
    // the least it needs, before a store or its temporary folder is made.
    let few = dir.path().join("few.sqlite");
    let few_arg = few.to_str().unwrap();
    let (code, _, err, pid) = dashboard_in(
        dir.path(),
        &["replay", "--nights", "20", "--db", few_arg],
        limit,
    );
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("replay needs at least 35 nights"), "{err}");
    assert!(!few.exists(), "a store was left behind");
    let (code, _, err, pid2) = dashboard_in(dir.path(), &["replay", "--nights", "34"], limit);
    assert_eq!(code, Some(1), "{err}");
    for p in [pid, pid2] {
        let prefix = format!("tessera-replay-{p}-");
        assert!(
            !std::fs::read_dir(std::env::temp_dir()).unwrap().any(|e| e
                .unwrap()
                .file_name()
                .to_string_lossy()
                .starts_with(&prefix)),
            "a temporary folder {prefix}* was left behind"
        );
    }
    // The least it needs, from a folder outside the repository: the default template (a path
    // relative to the repository) is found, and the replay runs to its report.
    let db = dir.path().join("replay.sqlite");
    let (code, out, err, _) = dashboard_in(
        dir.path(),
        &[
            "replay",
            "--nights",
            "35",
            "--scenarios",
            "1",
            "--db",
            db.to_str().unwrap(),
        ],
        limit,
    );
    assert!(
        code.is_some(),
        "35 nights did not finish in {limit:?}: {err}"
    );
    assert!(out.contains("replayed"), "{out}\n{err}");
    assert!(db.exists());
}

/// Each series chart on a group page has an x axis: its line, and ticks labelled with the short
/// commits of its points, oldest left; the chart of the step's series names the step's commit
/// among them or between two of them.
#[test]
fn a_groups_charts_have_an_x_axis_of_commits() {
    let store = common::sqlite();
    let h = StepHistory::h200(24, 20, "native", 1.05);
    let app = served(&store, &h, 22);
    block_on(async {
        let groups: serde_json::Value =
            serde_json::from_str(&get(&app, "/api/regressions/groups?status=all").await).unwrap();
        let id = &groups[0]["id"];
        let page = get(&app, &format!("/regressions/groups/{id}")).await;
        let charts = &page[page.find("<div class=charts>").expect("charts")..];
        let svgs: Vec<&str> = charts
            .split("<svg")
            .skip(1)
            .map(|s| &s[..s.find("</svg>").unwrap()])
            .collect();
        assert!(!svgs.is_empty(), "{page}");
        let short = |n: usize| tessera_dashboard::steps::sha(n)[..10].to_string();
        for svg in svgs {
            assert!(svg.contains("<line class='x-axis'"), "no x axis: {svg}");
            // The tick labels: the x axis's texts, centred under their points.
            let ticks: Vec<&str> = svg
                .split("text-anchor='middle' fill='#444'>")
                .skip(1)
                .map(|t| &t[..t.find("</text>").unwrap()])
                .collect();
            assert!(ticks.len() >= 3, "too few commits on the x axis: {ticks:?}");
            let nights: Vec<usize> = ticks
                .iter()
                .map(|t| {
                    (0..h.nights)
                        .find(|&n| short(n) == *t)
                        .unwrap_or_else(|| panic!("{t:?} is not a commit of the history"))
                })
                .collect();
            assert!(nights.windows(2).all(|w| w[0] < w[1]), "{nights:?}");
            assert!(
                nights[0] < h.step_night && *nights.last().unwrap() >= h.step_night - 1,
                "the axis does not span the step: {nights:?}"
            );
        }
    });
}
