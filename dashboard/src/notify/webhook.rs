//! The webhook worker of `serve --webhook-url`: every poll it looks for confirmed alert groups
//! that the target has not seen and POSTs one JSON body per group, with a timeout per request and
//! retries with exponential backoff. What it sent, what waits for a retry and what it gave up on
//! is kept in the store's outbox ([`crate::store::outbox`]), so a restart neither loses nor
//! repeats a notification. The first time a URL is configured, the groups already confirmed are
//! recorded as its baseline and not sent: a new webhook announces changes from then on.
//!
//! Delivery is at least once: a server killed between a successful POST and recording it sends
//! that group again after the restart; the body's `key` (also the `Idempotency-Key` header) lets
//! a receiver drop the repeat. Groups triaged `invalid` or `ignored` before they were sent are
//! not sent.
//!
//! A data stoppage ([`crate::store::stoppage`]: an adapter that stopped reporting a suite) is
//! sent the same way, once per silence: its outbox name is `stoppage:<adapter id>:<suite>:<last
//! run>`, so the adapter's next run ends it and a later silence is a new notification; one that
//! ends before it was sent is dropped, not retried. Not for: the feed or Markdown (see
//! [`super::atom`], [`super::markdown`]).

use std::time::Duration;

use chrono::{DateTime, SecondsFormat, Utc};
use serde_json::json;
use sha2::{Digest, Sha256};

use crate::db::Pool;
use crate::store::groups::{self, Filter, Group, Sort};
use crate::store::outbox::{self, Delivery};
use crate::store::stoppage::{self, Stoppage};
use crate::store::StoreError;

/// Settings of the worker; [`Config::new`] has the defaults `serve` uses.
#[derive(Clone, Debug)]
pub struct Config {
    /// Where to POST.
    pub url: String,
    /// The dashboard's public URL (no trailing slash), for the links in the body.
    pub public_url: String,
    /// Limit on one whole request (connect, send, answer).
    pub timeout: Duration,
    /// Delay before the first retry; doubled for each further one.
    pub backoff: Duration,
    pub max_backoff: Duration,
    /// Attempts before a group is given up (`failed`, logged, never retried).
    pub max_attempts: i64,
    /// Time between two looks at the store.
    pub poll: Duration,
}

impl Config {
    pub fn new(url: &str, public_url: &str) -> Config {
        Config {
            url: url.to_string(),
            public_url: public_url.trim_end_matches('/').to_string(),
            timeout: Duration::from_secs(10),
            backoff: Duration::from_secs(30),
            max_backoff: Duration::from_secs(3600),
            max_attempts: 8,
            poll: Duration::from_secs(30),
        }
    }
}

/// What one look at the store did.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Tick {
    /// Groups recorded as the baseline of a newly configured URL (not sent).
    pub baseline: usize,
    /// Newly confirmed groups put in the outbox.
    pub queued: usize,
    pub sent: usize,
    /// Attempts that failed (retried later or, after the last one, given up).
    pub failed: usize,
}

pub struct Notifier {
    pool: Pool,
    config: Config,
    target: String,
    agent: ureq::Agent,
}

fn ts(t: DateTime<Utc>) -> String {
    t.to_rfc3339_opts(SecondsFormat::Secs, true)
}

/// The outbox's name for a URL: the first 16 hex digits of its SHA-256 (the URL may hold a secret).
pub fn target_of(url: &str) -> String {
    Sha256::digest(url.as_bytes())
        .iter()
        .take(8)
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// The JSON body POSTed for a group. `text` makes it readable by chat webhooks as it is.
pub fn body(g: &Group, base: &str) -> serde_json::Value {
    let url = super::group_url(base, g.id);
    let title = crate::titles::of(g);
    let alerts: Vec<serde_json::Value> = g
        .alerts
        .iter()
        .filter(|a| a.status != "withdrawn")
        .map(|a| {
            json!({
                "series_id": a.series.id,
                "series_url": format!("{base}/series/{}", a.series.id),
                "adapter": a.series.adapter,
                "suite": a.suite,
                "scenario": a.series.scenario,
                "variant": a.series.variant,
                "measure": a.series.measure,
                "value_before": a.value_before,
                "value_after": a.value_after,
                "relative_change": a.relative_change,
                "worse": a.is_regression,
                "via_baseline": a.via_baseline,
                "confidence": a.confidence,
                "status": a.status,
            })
        })
        .collect();
    json!({
        "event": "regression_group_confirmed",
        "id": g.id,
        "key": g.key,
        "title": title,
        "text": format!("{title} {url}"),
        "url": url,
        "markdown_url": super::markdown_url(base, g.id),
        "commit_before": g.commit_before,
        "commit_after": g.commit_after,
        "state": g.state,
        "status": g.status,
        "adapters": g.adapters,
        "series_count": g.series_count,
        "worse": g.worse,
        "better": g.better,
        "via_baseline": g.via_baseline,
        "direction": g.direction,
        "alerts": alerts,
    })
}

/// The outbox's name for one silence of an (adapter, suite): ended by the adapter's next run.
pub fn stoppage_name(s: &Stoppage) -> String {
    format!("stoppage:{}:{}:{}", s.adapter_id, s.suite, s.last_run)
}

/// The JSON body POSTed for a data stoppage; `text` as for a group.
pub fn stoppage_body(s: &Stoppage, base: &str) -> serde_json::Value {
    let run_url = format!("{base}/runs/{}", crate::html::enc(&s.last_run));
    json!({
        "event": "data_stoppage",
        "key": stoppage_name(s),
        "title": s.message,
        "text": format!("{} (last run {run_url})", s.message),
        "url": format!("{base}/regressions"),
        "adapter_id": s.adapter_id,
        "adapter": s.adapter,
        "suite": s.suite,
        "last_run": s.last_run,
        "last_run_url": run_url,
        "last_at": s.last_at,
        "nights": s.nights,
        "usual_gap": s.usual_gap,
    })
}

impl Notifier {
    pub fn new(pool: Pool, config: Config) -> Notifier {
        let agent = ureq::Agent::config_builder()
            .http_status_as_error(false)
            .timeout_global(Some(config.timeout))
            .user_agent("tessera-dashboard")
            .build()
            .into();
        Notifier {
            pool,
            target: target_of(&config.url),
            config,
            agent,
        }
    }

    /// The outbox's name for this notifier's URL.
    pub fn target(&self) -> &str {
        &self.target
    }

    /// POSTs one body; `Err` with what went wrong (transport error or non-2xx answer).
    fn post(&self, body: &serde_json::Value, key: &str) -> Result<(), String> {
        let bytes = serde_json::to_vec(body).map_err(|e| e.to_string())?;
        let mut res = self
            .agent
            .post(&self.config.url)
            .header("Content-Type", "application/json")
            .header("Idempotency-Key", key)
            .send(&bytes[..])
            .map_err(|e| e.to_string())?;
        let status = res.status().as_u16();
        if (200..300).contains(&status) {
            return Ok(());
        }
        let text = res
            .body_mut()
            .with_config()
            .limit(2048)
            .read_to_string()
            .unwrap_or_default();
        Err(format!("HTTP {status}: {}", text.trim()))
    }

    /// One look at the store at time `now`: queue newly confirmed groups, send those due.
    /// Puts `name` in the outbox once: as the baseline at the target's first look (not sent),
    /// else pending; counts it in `tick`.
    fn enqueue(
        &self,
        conn: &mut dyn crate::db::Connection,
        name: &str,
        first: bool,
        now_s: &str,
        tick: &mut Tick,
    ) -> Result<(), StoreError> {
        let state = if first {
            outbox::BASELINE
        } else {
            outbox::PENDING
        };
        if outbox::add(conn, &self.target, name, state, now_s)? {
            if first {
                tick.baseline += 1;
            } else {
                tick.queued += 1;
            }
        }
        Ok(())
    }

    pub fn tick(&self, now: DateTime<Utc>) -> Result<Tick, StoreError> {
        let mut tick = Tick::default();
        let now_s = ts(now);
        let stopped: Vec<Stoppage>;
        let due = {
            let mut conn = self.pool.get()?;
            let confirmed = Filter {
                status: Some("confirmed".into()),
                regressions_only: true,
                ..Filter::default()
            };
            let groups = groups::list(&mut *conn, &confirmed, Sort::Date, usize::MAX)?;
            stopped = stoppage::stoppages(&mut *conn, &now_s)?;
            let first = outbox::register_target(&mut *conn, &self.target, &now_s)?;
            let known: std::collections::BTreeSet<String> =
                outbox::known(&mut *conn, &self.target)?
                    .into_iter()
                    .collect();
            for g in &groups {
                // The outbox names a group by its id (older rows by a commit range, which
                // `get_named` still resolves).
                let name = g.id.to_string();
                if known.contains(&name)
                    || known.contains(&g.key)
                    || (!first && matches!(g.state.as_str(), "invalid" | "ignored"))
                {
                    continue;
                }
                self.enqueue(&mut *conn, &name, first, &now_s, &mut tick)?;
            }
            // Data stoppages, once per silence; those already there at the first look are the
            // baseline, as groups are.
            for st in &stopped {
                let name = stoppage_name(st);
                if known.contains(&name) {
                    continue;
                }
                self.enqueue(&mut *conn, &name, first, &now_s, &mut tick)?;
            }
            outbox::due(&mut *conn, &self.target, &now_s, 100)?
        };
        for mut d in due {
            if d.group_key.starts_with("stoppage:") {
                let outcome = match stopped.iter().find(|s| stoppage_name(s) == d.group_key) {
                    Some(st) => {
                        self.post(&stoppage_body(st, &self.config.public_url), &d.group_key)
                    }
                    // The adapter reported again before the notice went out.
                    None => {
                        d.state = outbox::FAILED.into();
                        d.last_error = "the adapter reported again before it was sent".into();
                        let mut conn = self.pool.get()?;
                        outbox::update(&mut *conn, &self.target, &d)?;
                        continue;
                    }
                };
                self.record(&mut d, outcome, now, &mut tick)?;
                continue;
            }
            let group = {
                let mut conn = self.pool.get()?;
                // Detection never deletes an alert; a group whose alerts were all withdrawn (moved
                // to another commit, merged, or no longer supported) is gone as far as a
                // notification goes.
                match groups::get_named(&mut *conn, &d.group_key) {
                    Ok(g) if g.status == "withdrawn" => {
                        Err(StoreError::NotFound(format!("group {}", g.key)))
                    }
                    other => other,
                }
            };
            let outcome = match group {
                Ok(g) => self.post(
                    &body(&g, &self.config.public_url),
                    &format!("group-{}", g.id),
                ),
                // A group that detection has since moved away: nothing left to announce, and
                // nothing a retry would change.
                Err(StoreError::NotFound(_)) => {
                    d.state = outbox::FAILED.into();
                    d.last_error = "the group no longer exists (its alerts moved)".into();
                    let mut conn = self.pool.get()?;
                    outbox::update(&mut *conn, &self.target, &d)?;
                    continue;
                }
                Err(e) => return Err(e),
            };
            self.record(&mut d, outcome, now, &mut tick)?;
        }
        Ok(tick)
    }

    /// Records one attempt's outcome: sent, or retried after a backoff, or given up.
    fn record(
        &self,
        d: &mut Delivery,
        outcome: Result<(), String>,
        now: DateTime<Utc>,
        tick: &mut Tick,
    ) -> Result<(), StoreError> {
        let now_s = ts(now);
        let what = if d.group_key.starts_with("stoppage:") {
            d.group_key.clone()
        } else {
            format!("alert group {}", d.group_key)
        };
        d.attempts += 1;
        match outcome {
            Ok(()) => {
                d.state = outbox::SENT.into();
                d.sent_at = Some(now_s);
                d.last_error.clear();
                tick.sent += 1;
                eprintln!("webhook: sent {what}");
            }
            Err(e) => {
                tick.failed += 1;
                d.last_error = e;
                if d.attempts >= self.config.max_attempts {
                    d.state = outbox::FAILED.into();
                    eprintln!(
                        "webhook: gave up on {what} after {} attempts: {}",
                        d.attempts, d.last_error
                    );
                } else {
                    let delay = self.backoff(d.attempts);
                    d.next_attempt_at = ts(now + delay);
                    eprintln!(
                        "webhook: {what}: attempt {} failed ({}); next at {}",
                        d.attempts, d.last_error, d.next_attempt_at
                    );
                }
            }
        }
        let mut conn = self.pool.get()?;
        outbox::update(&mut *conn, &self.target, d)
    }

    /// The wait after `attempts` failed attempts: `backoff · 2^(attempts-1)`, at most `max_backoff`.
    pub fn backoff(&self, attempts: i64) -> chrono::TimeDelta {
        let factor = 1u32 << (attempts - 1).clamp(0, 20);
        let d = self
            .config
            .backoff
            .saturating_mul(factor)
            .min(self.config.max_backoff);
        chrono::TimeDelta::from_std(d).unwrap_or(chrono::TimeDelta::MAX)
    }

    /// Every delivery this notifier's URL has in the outbox.
    pub fn deliveries(&self) -> Result<Vec<Delivery>, StoreError> {
        let mut conn = self.pool.get()?;
        outbox::all(&mut *conn, &self.target)
    }

    /// Runs [`Notifier::tick`] every poll on a thread of its own, logging errors, until the
    /// process ends.
    pub fn spawn(self) -> std::thread::JoinHandle<()> {
        std::thread::spawn(move || loop {
            if let Err(e) = self.tick(Utc::now()) {
                eprintln!("webhook: {e}");
            }
            std::thread::sleep(self.config.poll);
        })
    }
}
