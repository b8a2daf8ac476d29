//! Triage by change and notifications, on SQLite and (when `TESSERA_TEST_POSTGRES_URL` is set)
//! PostgreSQL: alerts of one commit range on two adapters are one group, bulk triage sets every
//! alert of a group in one go, detection's `pending`/`withdrawn` status is shown and not
//! notified, and the webhook worker retries with backoff against a local HTTP server that fails
//! twice, survives a restart in the middle and never sends a group twice.
//!
//! The history: 40 runs per adapter at the same commits; on the first adapter every GPU time
//! steps by +25% at run 15 and +10% at run 30, on the second by +10% at run 30 only. So the
//! commit range of runs 29..30 is one group on two adapters, 14..15 one on the first adapter.

mod common;

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpListener};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use chrono::{DateTime, TimeZone, Utc};
use tessera_dashboard::db::{Connection, Value};
use tessera_dashboard::notify::webhook::{Config, Notifier};
use tessera_dashboard::notify::{atom, markdown};
use tessera_dashboard::store::groups::{self, Filter, Sort};
use tessera_dashboard::store::outbox;
use tessera_dashboard::store::triage::{self, Triage};
use tessera_dashboard::store::StoreError;

use common::{range, sha, two_adapter_history as fill, SECOND};

fn alerts_of(c: &mut dyn Connection, before: u64) -> Vec<(i64, String, String, String, String)> {
    c.query(
        "SELECT g.id, g.state, g.note, g.bug_url, g.updated_by FROM regressions g
         JOIN runs rb ON rb.id = g.run_pk_before JOIN runs ra ON ra.id = g.run_pk_after
         WHERE rb.commit_sha = $1 AND ra.commit_sha = $2 ORDER BY g.id",
        &[sha(before).into(), sha(before + 1).into()],
    )
    .unwrap()
    .iter()
    .map(|r| {
        (
            r.i64(0).unwrap(),
            r.string(1).unwrap(),
            r.string(2).unwrap(),
            r.string(3).unwrap(),
            r.string(4).unwrap(),
        )
    })
    .collect()
}

fn list(c: &mut dyn Connection, filter: Filter, sort: Sort) -> Vec<groups::Group> {
    groups::list(c, &filter, sort, 100).unwrap()
}

#[test]
fn one_commit_range_on_two_adapters_is_one_group() {
    for store in common::stores("one_commit_range_on_two_adapters_is_one_group") {
        fill(&store.pool, 0, 40);
        let mut c = store.pool.get().unwrap();
        let n30 = alerts_of(&mut *c, 29).len();
        let n15 = alerts_of(&mut *c, 14).len();
        assert!(
            n30 >= 6 && n15 >= 3,
            "{}: {n30} and {n15} alerts",
            store.name
        );

        let all = list(&mut *c, Filter::default(), Sort::Date);
        let keys: Vec<&str> = all.iter().map(|g| g.key.as_str()).collect();
        assert_eq!(keys, [range(29), range(14)], "{}: newest first", store.name);
        let g30 = &all[0];
        let g30_title = tessera_dashboard::titles::of(g30);
        assert_eq!(g30.adapters.len(), 2, "{}", store.name);
        assert_eq!((g30.series_count, g30.alerts.len()), (n30, n30));
        assert_eq!((g30.worse, g30.better), (n30, 0));
        assert_eq!(
            (g30.state.as_str(), g30.status.as_str()),
            ("new", "confirmed")
        );
        assert!(
            g30_title.starts_with(&format!("{}: {n30} series on 2 adapters; ", &sha(30)[..10])),
            "{}",
            g30_title
        );
        // Per variant, its largest changes (all GPU times moved by about +10%) and the scenario.
        assert!(
            g30_title.contains("native ") && g30_title.contains("% on tiny"),
            "{}",
            g30_title
        );
        assert_eq!(all[1].adapters.len(), 1);
        assert!(
            all[1].size > 0.2 && g30.size < 0.15,
            "{} {}",
            all[1].size,
            g30.size
        );

        // Sorting by size puts the 25% step first.
        let by_size = list(&mut *c, Filter::default(), Sort::Size);
        assert_eq!(by_size[0].key, range(14));
        // Filters: the second adapter only has the later change; nothing got better; one measure.
        let second = all[0]
            .alerts
            .iter()
            .find(|a| a.series.adapter == SECOND)
            .unwrap()
            .series
            .adapter_id;
        let only_second = list(
            &mut *c,
            Filter {
                adapter: Some(second),
                ..Filter::default()
            },
            Sort::Date,
        );
        assert_eq!(only_second.len(), 1);
        assert_eq!(only_second[0].key, range(29));
        assert!(only_second[0]
            .alerts
            .iter()
            .all(|a| a.series.adapter == SECOND));
        assert!(only_second[0].alerts.len() < only_second[0].series_count);
        let better = Filter {
            direction: Some("better".into()),
            ..Filter::default()
        };
        assert!(list(&mut *c, better, Sort::Date).is_empty());
        let gpu = list(
            &mut *c,
            Filter {
                measure: Some("gpu_ms.median".into()),
                ..Filter::default()
            },
            Sort::Date,
        );
        assert!(gpu
            .iter()
            .flat_map(|g| &g.alerts)
            .all(|a| a.series.measure == "gpu_ms.median"));
        // The suite is the scenario file's folder (the fixture ran /tmp/fx/tiny.toml).
        assert!(all[0].alerts.iter().all(|a| a.suite == "fx"));
        let bad = Filter {
            state: Some("closed".into()),
            ..Filter::default()
        };
        assert!(groups::list(&mut *c, &bad, Sort::Date, 10).is_err());

        // One group read by key has the same alerts.
        let one = groups::get_named(&mut *c, &range(29)).unwrap();
        assert_eq!(one.alerts.len(), n30);
        assert!(matches!(
            groups::get_named(&mut *c, "nope"),
            Err(StoreError::NotFound(_))
        ));
        assert!(matches!(
            groups::get_named(&mut *c, &range(3)),
            Err(StoreError::NotFound(_))
        ));

        // Markdown and Atom of the group.
        let md = markdown::render(&one, "https://dash.example");
        assert!(md.starts_with(&format!("### Regression group `{}`", &sha(30)[..10])));
        assert!(md.contains(&format!(
            "(https://dash.example/regressions/groups/{})",
            one.id
        )));
        assert_eq!(md.matches("| ▲ +").count(), n30, "{md}");
        let feed = atom::feed(&all, "https://dash.example", "2026-01-01T00:00:00Z");
        let doc = roxmltree::Document::parse(&feed).unwrap();
        assert_eq!(
            doc.root_element().tag_name().namespace(),
            Some("http://www.w3.org/2005/Atom")
        );
        assert_eq!(
            doc.root_element()
                .children()
                .filter(|n| n.has_tag_name("entry"))
                .count(),
            2
        );
    }
}

#[test]
fn bulk_triage_sets_every_alert_of_a_group_at_once() {
    for store in common::stores("bulk_triage_sets_every_alert_of_a_group_at_once") {
        fill(&store.pool, 0, 40);
        let mut c = store.pool.get().unwrap();
        let t = Triage {
            state: "acknowledged".into(),
            note: "new shadow pass on purpose".into(),
            bug_url: "https://bugs.example/123".into(),
        };
        let n = triage::set_group(&mut *c, &range(29), &t, "alice")
            .unwrap()
            .1;
        let set = alerts_of(&mut *c, 29);
        assert_eq!(n, set.len(), "{}", store.name);
        for (_, state, note, bug, who) in &set {
            assert_eq!(
                (state.as_str(), note.as_str(), bug.as_str(), who.as_str()),
                (
                    "acknowledged",
                    "new shadow pass on purpose",
                    "https://bugs.example/123",
                    "alice"
                )
            );
        }
        // The other group is untouched.
        assert!(alerts_of(&mut *c, 14)
            .iter()
            .all(|a| a.1 == "new" && a.4.is_empty()));
        let g = groups::get_named(&mut *c, &range(29)).unwrap();
        assert_eq!(
            (g.state.as_str(), g.mixed_state, g.updated_by.as_str()),
            ("acknowledged", false, "alice")
        );
        assert_eq!(g.bug_url, "https://bugs.example/123");
        let acked = list(
            &mut *c,
            Filter {
                state: Some("acknowledged".into()),
                ..Filter::default()
            },
            Sort::Date,
        );
        assert_eq!(acked.len(), 1);

        // Refused input changes nothing.
        for bad in [
            Triage {
                state: "closed".into(),
                ..t.clone()
            },
            Triage {
                bug_url: "javascript:alert(1)".into(),
                ..t.clone()
            },
        ] {
            assert!(matches!(
                triage::set_group(&mut *c, &range(29), &bad, "mallory"),
                Err(StoreError::Invalid(_))
            ));
        }
        assert!(matches!(
            triage::set_group(&mut *c, &range(3), &t, "alice"),
            Err(StoreError::NotFound(_))
        ));
        assert_eq!(alerts_of(&mut *c, 29), set);

        // An alert that differs (as one joining after triage would) makes the group mixed and new.
        triage::set(&mut *c, set[0].0, "new", "").unwrap();
        let g = groups::get_named(&mut *c, &range(29)).unwrap();
        assert_eq!((g.state.as_str(), g.mixed_state), ("new", true));
    }
}

/// Adds detection's `status` column as its migration will, unless it is already there.
fn with_status_column(c: &mut dyn Connection) {
    if !groups::has_status_column(c).unwrap() {
        c.batch("ALTER TABLE regressions ADD COLUMN status TEXT NOT NULL DEFAULT 'confirmed'")
            .unwrap();
    }
}

fn set_status(c: &mut dyn Connection, ids: &[i64], status: &str) {
    for id in ids {
        c.execute(
            "UPDATE regressions SET status = $1 WHERE id = $2",
            &[status.into(), Value::Int(*id)],
        )
        .unwrap();
    }
}

// ---------------------------------------------------------------------------------------------
// A local HTTP server for the webhook: answers each request with the next status of a script
// (the last one repeats; 0 means "never answer") and records what it got.

#[derive(Clone, Debug)]
struct Received {
    headers: String,
    body: String,
}

struct Hook {
    addr: SocketAddr,
    got: Arc<Mutex<Vec<Received>>>,
}

fn hook(script: Vec<u16>) -> Hook {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap();
    let got = Arc::new(Mutex::new(Vec::new()));
    let log = got.clone();
    std::thread::spawn(move || {
        for (n, stream) in listener.incoming().enumerate() {
            let Ok(mut stream) = stream else { continue };
            let mut reader = BufReader::new(stream.try_clone().unwrap());
            let mut headers = String::new();
            loop {
                let mut line = String::new();
                if reader.read_line(&mut line).unwrap_or(0) == 0 || line == "\r\n" {
                    break;
                }
                headers.push_str(&line);
            }
            let len = headers
                .lines()
                .find_map(|l| {
                    l.to_ascii_lowercase()
                        .strip_prefix("content-length:")
                        .map(|v| v.trim().parse::<usize>().unwrap())
                })
                .unwrap_or(0);
            let mut body = vec![0; len];
            reader.read_exact(&mut body).unwrap();
            log.lock().unwrap().push(Received {
                headers,
                body: String::from_utf8(body).unwrap(),
            });
            let status = *script.get(n).or(script.last()).unwrap();
            if status == 0 {
                // Hold the connection without answering until the client gives up.
                std::thread::spawn(move || {
                    std::thread::sleep(Duration::from_secs(30));
                    drop(stream);
                });
                continue;
            }
            let text = if status == 200 { "ok" } else { "try later" };
            let _ = write!(
                stream,
                "HTTP/1.1 {status} X\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{text}",
                text.len()
            );
        }
    });
    Hook { addr, got }
}

fn config(h: &Hook) -> Config {
    let mut c = Config::new(&format!("http://{}/hook", h.addr), "https://dash.example/");
    c.timeout = Duration::from_secs(2);
    c.backoff = Duration::from_secs(10);
    c
}

fn at(seconds: i64) -> DateTime<Utc> {
    Utc.with_ymd_and_hms(2026, 12, 1, 0, 0, 0).unwrap() + chrono::TimeDelta::seconds(seconds)
}

#[test]
fn webhook_retries_with_backoff_and_never_repeats_after_a_restart() {
    for store in common::stores("webhook_retries_with_backoff_and_never_repeats") {
        let h = hook(vec![500, 503, 200]);
        // The first 25 runs hold the change at run 15: it is there before the webhook, so it is
        // the baseline and never sent.
        fill(&store.pool, 0, 25);
        let first = Notifier::new(store.pool.clone(), config(&h));
        let t = first.tick(at(0)).unwrap();
        assert_eq!((t.baseline, t.queued, t.sent), (1, 0, 0), "{}", store.name);
        // The change at run 30 arrives: queued and tried at once; the server fails.
        fill(&store.pool, 25, 40);
        let t = first.tick(at(1)).unwrap();
        assert_eq!((t.queued, t.sent, t.failed), (1, 0, 1), "{}", store.name);
        // The outbox and the webhook name a group by its id for life.
        let id = |r: String| {
            groups::get_named(&mut *store.pool.get().unwrap(), &r)
                .unwrap()
                .id
                .to_string()
        };
        let (id29, id14) = (id(range(29)), id(range(14)));
        let d = first.deliveries().unwrap();
        let pending = d
            .iter()
            .find(|d| d.group_key == id29)
            .unwrap_or_else(|| panic!("{id29} {id14} {d:?}"));
        assert_eq!(
            (pending.state.as_str(), pending.attempts),
            (outbox::PENDING, 1)
        );
        assert_eq!(pending.next_attempt_at, "2026-12-01T00:00:11Z");
        assert!(pending.last_error.contains("500"), "{}", pending.last_error);
        // Not due yet: nothing sent.
        assert_eq!(first.tick(at(5)).unwrap().failed, 0);
        assert_eq!(h.got.lock().unwrap().len(), 1);

        // A restart: the retry state is in the store, not in the worker.
        drop(first);
        let second = Notifier::new(store.pool.clone(), config(&h));
        let t = second.tick(at(11)).unwrap();
        assert_eq!((t.baseline, t.queued, t.sent, t.failed), (0, 0, 0, 1));
        let d = second.deliveries().unwrap();
        let pending = d.iter().find(|d| d.group_key == id29).unwrap();
        assert_eq!(pending.attempts, 2);
        // Backoff doubles: 20 s after the second failure.
        assert_eq!(pending.next_attempt_at, "2026-12-01T00:00:31Z");
        assert_eq!(second.tick(at(30)).unwrap().sent, 0);
        assert_eq!(second.tick(at(31)).unwrap().sent, 1);

        let got = h.got.lock().unwrap().clone();
        assert_eq!(got.len(), 3, "{}", store.name);
        for r in &got {
            assert!(
                r.headers.starts_with("POST /hook HTTP/1.1"),
                "{}",
                r.headers
            );
            assert!(r
                .headers
                .to_ascii_lowercase()
                .contains(&format!("idempotency-key: group-{id29}")));
            let v: serde_json::Value = serde_json::from_str(&r.body).unwrap();
            assert_eq!(v["key"], range(29));
            assert_eq!(
                v["url"],
                format!("https://dash.example/regressions/groups/{id29}")
            );
            assert_eq!(v["adapters"].as_array().unwrap().len(), 2);
            assert_eq!(
                v["alerts"].as_array().unwrap().len(),
                v["series_count"].as_u64().unwrap() as usize
            );
            assert!(v["text"].as_str().unwrap().contains("series on 2 adapters"));
        }

        // Another restart: nothing is sent again.
        drop(second);
        let third = Notifier::new(store.pool.clone(), config(&h));
        let t = third.tick(at(100)).unwrap();
        assert_eq!((t.baseline, t.queued, t.sent, t.failed), (0, 0, 0, 0));
        assert_eq!(h.got.lock().unwrap().len(), 3);
        let d = third.deliveries().unwrap();
        let states: Vec<(&str, &str, i64)> = d
            .iter()
            .map(|d| (d.group_key.as_str(), d.state.as_str(), d.attempts))
            .collect();
        assert!(states.contains(&(id14.as_str(), outbox::BASELINE, 0)));
        assert!(states.contains(&(id29.as_str(), outbox::SENT, 3)));
    }
}

#[test]
fn webhook_requests_time_out_and_are_retried() {
    let store = common::sqlite();
    let h = hook(vec![0, 200]);
    let mut cfg = config(&h);
    cfg.timeout = Duration::from_secs(1);
    let n = Notifier::new(store.pool.clone(), cfg.clone());
    n.tick(at(0)).unwrap();
    fill(&store.pool, 0, 25);
    let t = n.tick(at(1)).unwrap();
    assert_eq!((t.queued, t.failed), (1, 1));
    let d = n.deliveries().unwrap();
    assert!(
        d[0].last_error.to_ascii_lowercase().contains("timeout"),
        "{:?}",
        d[0]
    );
    assert_eq!(n.tick(at(11)).unwrap().sent, 1);
}

#[test]
fn pending_groups_are_shown_but_not_notified_and_withdrawn_ones_hidden() {
    for store in common::stores("pending_groups_are_shown_but_not_notified") {
        fill(&store.pool, 0, 40);
        let mut c = store.pool.get().unwrap();
        with_status_column(&mut *c);
        let late: Vec<i64> = alerts_of(&mut *c, 29).iter().map(|a| a.0).collect();
        let early: Vec<i64> = alerts_of(&mut *c, 14).iter().map(|a| a.0).collect();
        set_status(&mut *c, &late, "pending");
        set_status(&mut *c, &early[..1], "withdrawn");

        let all = list(&mut *c, Filter::default(), Sort::Date);
        assert_eq!(all[0].key, range(29));
        assert_eq!(all[0].status, "pending", "{}", store.name);
        assert_eq!(all[1].status, "confirmed");
        assert_eq!(all[1].alerts.len(), early.len() - 1, "withdrawn hidden");
        let with_withdrawn = list(
            &mut *c,
            Filter {
                status: Some("all".into()),
                ..Filter::default()
            },
            Sort::Date,
        );
        assert_eq!(with_withdrawn[1].alerts.len(), early.len());
        let confirmed = Filter {
            status: Some("confirmed".into()),
            ..Filter::default()
        };
        assert_eq!(list(&mut *c, confirmed, Sort::Date).len(), 1);

        // The webhook: the confirmed group is the baseline, the pending one waits.
        let h = hook(vec![200]);
        let n = Notifier::new(store.pool.clone(), config(&h));
        assert_eq!(n.tick(at(0)).unwrap().baseline, 1);
        assert_eq!(n.tick(at(1)).unwrap().queued, 0);
        set_status(&mut *c, &late, "confirmed");
        let t = n.tick(at(2)).unwrap();
        assert_eq!((t.queued, t.sent), (1, 1), "{}", store.name);
        assert_eq!(h.got.lock().unwrap().len(), 1);
    }
}

#[test]
fn a_queued_group_that_detection_moved_away_is_dropped_not_retried() {
    let store = common::sqlite();
    let h = hook(vec![500]);
    let n = Notifier::new(store.pool.clone(), config(&h));
    assert_eq!(n.tick(at(0)).unwrap().baseline, 0);
    fill(&store.pool, 0, 25);
    assert_eq!(n.tick(at(1)).unwrap().failed, 1);
    // Detection moved, merged or withdrew the alerts (it never deletes one): the group's commit
    // range has no live alert left.
    store
        .pool
        .get()
        .unwrap()
        .execute("UPDATE regressions SET status = 'withdrawn'", &[])
        .unwrap();
    let t = n.tick(at(100)).unwrap();
    assert_eq!((t.sent, t.failed), (0, 0));
    let d = n.deliveries().unwrap();
    assert_eq!(d[0].state, outbox::FAILED);
    assert!(d[0].last_error.contains("no longer exists"), "{:?}", d[0]);
    assert_eq!(h.got.lock().unwrap().len(), 1);
    assert_eq!(n.tick(at(1000)).unwrap(), Default::default());
}

#[test]
fn a_data_stoppage_goes_through_the_webhook_once_per_silence() {
    use tessera_dashboard::detect::Params;
    use tessera_dashboard::regressions::ingest_and_detect;
    use tessera_dashboard::steps::StepHistory;
    for store in common::stores("a_data_stoppage_goes_through_the_webhook") {
        let h = hook(vec![503, 200]);
        let steps = StepHistory::h200(10, 99, "native", 1.0);
        let runs = steps.runs(&common::template());
        {
            let mut c = store.pool.get().unwrap();
            for run in &runs[..9] {
                ingest_and_detect(&mut *c, run, &Params::default()).unwrap();
            }
        }
        // Night 8's commit is at day 8 00:00 of 2026 (`synth::time_after`).
        let day = |d: i64| {
            Utc.with_ymd_and_hms(2026, 1, 1, 10, 0, 0).unwrap() + chrono::TimeDelta::days(d)
        };
        let n = Notifier::new(store.pool.clone(), config(&h));
        // Configured while the adapter reports: nothing to send.
        assert_eq!(n.tick(day(9)).unwrap().queued, 0);
        // Three nights later it has stopped: queued, first attempt fails, the retry is sent.
        let t = n.tick(day(12)).unwrap();
        assert_eq!((t.queued, t.sent, t.failed), (1, 0, 1), "{}", store.name);
        let t = n.tick(day(12) + chrono::TimeDelta::seconds(11)).unwrap();
        assert_eq!((t.queued, t.sent), (0, 1));
        // Sent once, however often the worker looks.
        let t = n.tick(day(13)).unwrap();
        assert_eq!((t.queued, t.sent), (0, 0));
        let got = h.got.lock().unwrap().clone();
        assert_eq!(got.len(), 2);
        let body: serde_json::Value = serde_json::from_str(&got[1].body).unwrap();
        assert_eq!(body["event"], "data_stoppage");
        assert_eq!(
            body["title"],
            "NVIDIA H200 (replay): no fx run for 4 nights (usually every night)"
        );
        assert_eq!(body["last_run"], "h200-0008");
        assert_eq!(body["last_run_url"], "https://dash.example/runs/h200-0008");
        assert!(got[1]
            .headers
            .to_ascii_lowercase()
            .contains("idempotency-key: stoppage:"));
        // The adapter reports again, then stops again: a new silence, a new notice.
        {
            let mut c = store.pool.get().unwrap();
            ingest_and_detect(&mut *c, &runs[9], &Params::default()).unwrap();
        }
        assert_eq!(n.tick(day(10)).unwrap().queued, 0);
        let t = n.tick(day(14)).unwrap();
        assert_eq!((t.queued, t.sent), (1, 1));
        let body: serde_json::Value =
            serde_json::from_str(&h.got.lock().unwrap().last().unwrap().body).unwrap();
        assert_eq!(body["last_run"], "h200-0009");
    }
}
