//! The replay benchmark of online detection (`tessera-dashboard replay`): synthetic nightly
//! histories made from a real run, with noise at measured levels and injected changes whose
//! commits are known, stored run by run through [`crate::regressions::ingest_and_detect`] (the
//! function `POST /api/runs` calls), then scored against the truth and against one batch pass.
//!
//! History: `nights` commits; each night one run per adapter profile (`lavapipe`: 2% per-night
//! noise, the spread of repeated lavapipe runs on this machine; `h200`: 0.1%, three back-to-back
//! H200 runs agreed within 0.2%, DESIGN.md). Noise is Student-t with 5 degrees of freedom (heavier
//! tails than a normal law, as timings have), drawn independently per pass time and CPU time; a
//! variant's frame time is the sum of its passes, `speedup` follows from the frame times. Each
//! scenario copy of each profile gets one injected change from a fixed rotation: a step in one pass
//! of one variant, a step in every pass of a variant ("times"), a step in one metric, or none;
//! sizes rotate through 1.5% to 35%, slower and faster. Per profile also: one driver change (every
//! timing 10% slower, a new environment segment: no alert expected), whole-run outliers (1.5x
//! slower for one night), and backfills (a run uploaded 1 to 6 nights late).
//!
//! Truth: the noise-free history (same runs, no noise, no outliers) gives each series' true changes
//! (a relative change of at least 0.1% from one night to the next, outside environment cuts); a
//! series' noise σ is measured as the spread of noisy minus noise-free values. Reported: recall and
//! exact-commit blame for changes of at least 3σ and 1% (the alert floor), false alerts per 1,000
//! series-nights (alerts ever confirmed that match no true change within 3 nights), latency in runs
//! to the first alert and to confirmation, and online-vs-batch agreement.
//!
//! Not for: the statistics themselves (see [`crate::detect`]).

use std::collections::{BTreeMap, BTreeSet};

use tessera_results::Summary;

use crate::bundle::RunBundle;
use crate::db::{Connection, Pool};
use crate::detect::{Params, Rng};
use crate::regressions::{self, WITHDRAWN};
use crate::store::StoreError;
use crate::synth::{time_after, widen};
use tessera_results::measure::points;

mod published;

/// What to replay.
#[derive(Clone, Debug)]
pub struct Config {
    pub nights: usize,
    /// Copies of the template's scenarios per run.
    pub scenarios: usize,
    pub seed: u64,
}

/// The fewest nights a history has room for its injections in: each lands after the first 12
/// nights, more than 8 nights from the driver change (at 3/5 of the history) and more than 6
/// before the end, which leaves a night first at 35. With fewer, [`schedule`] would look for one
/// for ever.
pub const MIN_NIGHTS: usize = 35;

impl Config {
    /// Why this replay cannot run, said before any store is made or template read.
    pub fn check(&self) -> Result<(), String> {
        if self.nights < MIN_NIGHTS {
            return Err(format!(
                "replay needs at least {MIN_NIGHTS} nights (--nights {} given): its changes are injected after night 12, away from the driver change at 3/5 of the history and from the last 6 nights",
                self.nights
            ));
        }
        Ok(())
    }
}

/// An adapter profile: its name in the store and its per-night noise.
#[derive(Clone, Copy, Debug)]
pub struct Profile {
    pub name: &'static str,
    pub cv: f64,
}

pub const PROFILES: [Profile; 2] = [
    Profile {
        name: "lavapipe",
        cv: 0.02,
    },
    Profile {
        name: "h200",
        cv: 0.001,
    },
];

const SIZES: [f64; 8] = [0.015, 0.03, 0.06, 0.10, 0.20, 0.35, -0.05, -0.10];

/// One injected change.
#[derive(Clone, Debug)]
enum Target {
    Pass { variant: usize, pass: usize },
    Variant { variant: usize },
    Metric { variant: usize, metric: usize },
}

#[derive(Clone, Debug)]
struct Injection {
    scenario: usize,
    target: Target,
    night: usize,
    factor: f64,
}

/// The schedule of one profile's history.
#[derive(Clone, Debug)]
struct Schedule {
    injections: Vec<Injection>,
    driver_change: usize,
    outliers: BTreeSet<usize>,
    /// Upload position of each night's run (a backfilled night comes later).
    upload_order: Vec<usize>,
    /// The acceptance cases of issue 22, on top of the random ones: the first injection's step
    /// has a whole-run outlier the night before it; the second's changed night is uploaded
    /// [`LATE_INSIDE`] nights late, after its alert is confirmed on the next night (a backfill
    /// inside a confirmed range); the third's night before the step is deleted
    /// [`DELETE_AFTER`] uploads after the step's night, once its alert is confirmed and triaged.
    outlier_before: Option<usize>,
    backfill_inside: Option<usize>,
    /// (night deleted, upload position after which it is deleted).
    delete: Option<(usize, usize)>,
}

/// How late the second injection's changed night is uploaded: after the 4 runs that confirm its
/// alert at the next night.
const LATE_INSIDE: usize = 7;
/// Uploads after the third injection's night at which the night before it is deleted.
const DELETE_AFTER: usize = 8;

fn schedule(template: &RunBundle, config: &Config, profile: usize) -> Schedule {
    let mut rng = Rng::new(config.seed ^ ((profile as u64 + 1) * 0x9E37));
    let n = config.nights;
    let driver_change = n * 3 / 5;
    let pick = |rng: &mut Rng, k: usize| (rng.next_u64() % k.max(1) as u64) as usize;
    let mut injections = Vec::new();
    let copies = template.scenarios.len();
    for scenario in 0..copies {
        let s = &template.scenarios[scenario];
        let variant = pick(&mut rng, s.results.len());
        let v = &s.results[variant];
        let target = match (scenario + profile) % 4 {
            0 if !v.passes.is_empty() => Target::Pass {
                variant,
                pass: pick(&mut rng, v.passes.len()),
            },
            1 => Target::Variant { variant },
            2 if v
                .metrics
                .iter()
                .any(|m| m.value.is_finite() && m.value != 0.0) =>
            {
                let finite: Vec<usize> = (0..v.metrics.len())
                    .filter(|&m| v.metrics[m].value.is_finite() && v.metrics[m].value != 0.0)
                    .collect();
                Target::Metric {
                    variant,
                    metric: finite[pick(&mut rng, finite.len())],
                }
            }
            _ => continue,
        };
        // Away from the first nights and from the driver change.
        let night = loop {
            let t = 12 + pick(&mut rng, n.saturating_sub(20).max(1));
            if t.abs_diff(driver_change) > 8 && t < n.saturating_sub(6) {
                break t;
            }
        };
        injections.push(Injection {
            scenario,
            target,
            night,
            factor: 1.0 + SIZES[(scenario / 4 + profile) % SIZES.len()],
        });
    }
    let mut outliers: BTreeSet<usize> =
        (0..n).filter(|&i| i > 10 && rng.uniform() < 0.02).collect();
    let mut keyed: Vec<(usize, usize)> = (0..n)
        .map(|i| {
            let late = if i > 10 && rng.uniform() < 0.05 {
                1 + pick(&mut rng, 6)
            } else {
                0
            };
            (i + late, i)
        })
        .collect();
    let night_of = |k: usize| injections.get(k).map(|i: &Injection| i.night);
    let outlier_before = night_of(0).map(|t| t - 1);
    if let Some(o) = outlier_before {
        outliers.insert(o);
    }
    let backfill_inside = night_of(1).filter(|&t| t + LATE_INSIDE < n);
    if let Some(t) = backfill_inside {
        keyed[t].0 = t + LATE_INSIDE;
        // The nights that confirm the alert arrive on time.
        for k in &mut keyed[t + 1..=t + LATE_INSIDE] {
            k.0 = k.1;
        }
    }
    keyed.sort();
    let upload_order: Vec<usize> = keyed.into_iter().map(|(_, i)| i).collect();
    let delete = night_of(2)
        .filter(|&t| Some(t - 1) != outlier_before && Some(t - 1) != backfill_inside)
        .and_then(|t| {
            let pos = upload_order.iter().position(|&i| i == t)? + DELETE_AFTER;
            (pos < n).then_some((t - 1, pos))
        });
    Schedule {
        injections,
        driver_change,
        outliers,
        upload_order,
        outlier_before,
        backfill_inside,
        delete,
    }
}

fn scale(s: &mut Summary, f: f64) {
    for v in [
        &mut s.median,
        &mut s.p5,
        &mut s.p95,
        &mut s.min,
        &mut s.max,
        &mut s.mean,
    ] {
        *v *= f;
    }
}

/// Unit-variance Student-t draw with 5 degrees of freedom.
fn t5(rng: &mut Rng) -> f64 {
    let chi2: f64 = (0..5).map(|_| rng.normal().powi(2)).sum();
    rng.normal() / (chi2 / 5.0).sqrt() / (5.0f64 / 3.0).sqrt()
}

/// Night `night` of profile `p`: with noise from `rng`, or noise-free when `rng` is `None`.
fn night_run(
    template: &RunBundle,
    profile: usize,
    sched: &Schedule,
    night: usize,
    mut rng: Option<&mut Rng>,
) -> RunBundle {
    let p = PROFILES[profile];
    let mut b = template.clone();
    let id = format!("{}-{night:04}", p.name);
    b.run.run_id = id.clone();
    // Runs start at 02:00 after commits made at midnight; a backfilled run starts later, but its
    // commit time says where it belongs.
    b.run.commit_time = Some(time_after(night as u64 * 1440));
    b.run.started_at = time_after(night as u64 * 1440 + 120 + profile as u64);
    b.run.finished_at = Some(b.run.started_at.clone());
    b.run.commit = Some(tessera_results::CommitInfo {
        sha: format!("{:040x}", night + 1),
        dirty: false,
    });
    b.run.adapter.name = format!("{} (replay)", p.name);
    let driver_late = night >= sched.driver_change;
    if driver_late {
        b.run.adapter.driver_info = format!("{} (next)", b.run.adapter.driver_info);
    }
    let outlier = rng.is_some() && sched.outliers.contains(&night);
    let env = if driver_late { 1.1 } else { 1.0 } * if outlier { 1.5 } else { 1.0 };
    for (si, s) in b.scenarios.iter_mut().enumerate() {
        s.run_id = id.clone();
        for (vi, v) in s.results.iter_mut().enumerate() {
            let steps = |target: &dyn Fn(&Target) -> bool| -> f64 {
                sched
                    .injections
                    .iter()
                    .filter(|i| i.scenario == si && night >= i.night && target(&i.target))
                    .map(|i| i.factor)
                    .product()
            };
            let variant_step =
                steps(&|t| matches!(t, Target::Variant { variant } if *variant == vi));
            let noise = |rng: &mut Option<&mut Rng>| match rng {
                Some(r) => 1.0 + p.cv * t5(r),
                None => 1.0,
            };
            let (mut before, mut after) = (0.0, 0.0);
            for (pi, pass) in v.passes.iter_mut().enumerate() {
                let pass_step = steps(
                    &|t| matches!(t, Target::Pass { variant, pass } if *variant == vi && *pass == pi),
                );
                let f = env * variant_step * pass_step * noise(&mut rng);
                if let Some(g) = pass.gpu_ms.as_mut() {
                    before += g.median;
                    scale(g, f);
                    after += g.median;
                }
                pass.samples_ms.iter_mut().for_each(|x| *x *= f);
            }
            if let Some(g) = v.gpu_frame_ms.as_mut() {
                let f = if before > 0.0 { after / before } else { env };
                scale(g, f);
            }
            let f = env * noise(&mut rng);
            scale(&mut v.cpu_frame_ms, f);
            for (mi, m) in v.metrics.iter_mut().enumerate() {
                m.value *= steps(
                    &|t| matches!(t, Target::Metric { variant, metric } if *variant == vi && *metric == mi),
                );
            }
        }
    }
    b
}

/// Series values of a run by (scenario, variant, measure).
fn values(b: &RunBundle) -> BTreeMap<(String, String, String), f64> {
    let mut out = BTreeMap::new();
    for s in &b.scenarios {
        for v in &s.results {
            for m in points(&s.results, v) {
                out.insert((s.scenario.clone(), v.variant.clone(), m.key), m.value);
            }
        }
    }
    out
}

/// (adapter name, scenario, variant, measure).
pub type SeriesName = (String, String, String, String);

/// A true change of a series: the first night after it, its relative size and its size in σ.
#[derive(Clone, Debug)]
struct Truth {
    night: usize,
    relative: f64,
    sigmas: f64,
}

/// An alert as scored: series, first night after the change, direction, status.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct AlertKey {
    pub series: SeriesName,
    pub night: usize,
    pub up: bool,
    pub status: String,
}

/// The figures of one replay.
#[derive(Clone, Debug, Default)]
pub struct Report {
    pub runs: usize,
    pub series: usize,
    pub series_nights: usize,
    pub eligible: usize,
    pub found: usize,
    pub exact: usize,
    pub below_floor_found: usize,
    pub below_floor: usize,
    pub false_confirmed: usize,
    pub false_pending_only: usize,
    /// Runs from the change to the first alert, and to confirmation, over found eligible changes.
    pub first_latency: Vec<usize>,
    pub confirm_latency: Vec<usize>,
    pub online_alerts: usize,
    pub batch_alerts: usize,
    pub disagreements: Vec<String>,
    /// Eligible changes not blamed on their exact commit, and false confirmed alerts, described.
    pub misses: Vec<String>,
    pub false_list: Vec<String>,
    pub upload_ms: Vec<f64>,
    /// Moves of confirmed alerts (each with its reason), and of those, moves by a backfill
    /// inside the alert's range; moves of pending alerts.
    pub confirmed_moves: usize,
    pub backfill_moves: usize,
    pub pending_moves: usize,
    /// Confirmed alerts kept at their commit although one analysis of the final points would
    /// place them within a few commits (no backfill, no strong new evidence).
    pub held: usize,
    /// The acceptance cases played (`outlier before a step at night N`, ...).
    pub cases: Vec<String>,
    /// Published URLs and triage, checked at the end ([`published`]).
    pub published: published::Checked,
}

fn pct(a: usize, b: usize) -> f64 {
    if b == 0 {
        100.0
    } else {
        100.0 * a as f64 / b as f64
    }
}

fn quantile(v: &[f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mut s = v.to_vec();
    s.sort_by(|a, b| a.total_cmp(b));
    s[((s.len() - 1) as f64 * q).round() as usize]
}

impl Report {
    /// Whether the targets are met: every eligible change found and on its exact commit,
    /// at most 1 false alert per 1,000 series-nights, online = batch, no confirmed alert moved
    /// except by a backfill, every published URL answering and every triage kept.
    pub fn meets_targets(&self) -> bool {
        self.found == self.eligible
            && self.exact == self.eligible
            && self.false_per_thousand() <= 1.0
            && self.disagreements.is_empty()
            && self.confirmed_moves == self.backfill_moves
            && self.published.broken.is_empty()
            && self.published.triage_lost.is_empty()
    }

    pub fn false_per_thousand(&self) -> f64 {
        1000.0 * self.false_confirmed as f64 / self.series_nights.max(1) as f64
    }

    /// The aligned figures printed by the command.
    pub fn lines(&self) -> Vec<String> {
        let mean = |v: &[usize]| v.iter().sum::<usize>() as f64 / v.len().max(1) as f64;
        let max = |v: &[usize]| v.iter().copied().max().unwrap_or(0);
        let lat_f: Vec<f64> = self.upload_ms.clone();
        vec![
            format!(
                "replayed       {} runs, {} series, {} series-nights",
                self.runs, self.series, self.series_nights
            ),
            format!(
                "recall         {:5.1}%  ({} of {} changes >= 3 sigma and >= 1%)",
                pct(self.found, self.eligible),
                self.found,
                self.eligible
            ),
            format!(
                "exact commit   {:5.1}%  ({} of {})",
                pct(self.exact, self.eligible),
                self.exact,
                self.eligible
            ),
            format!(
                "below floor    {:5.1}%  found ({} of {} changes < 3 sigma or < 1%)",
                pct(self.below_floor_found, self.below_floor),
                self.below_floor_found,
                self.below_floor
            ),
            format!(
                "false alerts   {:5.2} per 1,000 series-nights ({} confirmed; {} more only pending)",
                self.false_per_thousand(),
                self.false_confirmed,
                self.false_pending_only
            ),
            format!(
                "latency        first alert {:.1} runs (max {}), confirmed {:.1} runs (max {})",
                mean(&self.first_latency),
                max(&self.first_latency),
                mean(&self.confirm_latency),
                max(&self.confirm_latency)
            ),
            format!(
                "online/batch   {} / {} alerts, {} disagreements, {} confirmed alerts held at their commit",
                self.online_alerts,
                self.batch_alerts,
                self.disagreements.len(),
                self.held
            ),
            format!(
                "moves          {} of confirmed alerts ({} by a backfill inside the range), {} of pending alerts",
                self.confirmed_moves, self.backfill_moves, self.pending_moves
            ),
            format!(
                "published      {} URLs, {} not answering 200 (directly or by redirect); triage of {} groups ({} alerts), {} lost",
                self.published.urls,
                self.published.broken.len(),
                self.published.triaged_groups,
                self.published.triaged_alerts,
                self.published.triage_lost.len()
            ),
            format!("cases          {}", self.cases.join("; ")),
            format!(
                "upload         p50 {:.1} ms, p95 {:.1} ms (store and detect, one transaction)",
                quantile(&lat_f, 0.5),
                quantile(&lat_f, 0.95)
            ),
            if self.meets_targets() {
                "verdict        targets met (every change found on its exact commit, <= 1 false alert per 1,000 series-nights, online = batch except confirmed alerts held, confirmed alerts moved only by backfills, every URL answering, triage kept)".into()
            } else {
                "verdict        targets NOT met".into()
            },
        ]
    }
}

/// Open alerts by (series id, run pk after) with status.
fn open_alerts(conn: &mut dyn Connection) -> Result<Vec<(i64, i64, bool, String)>, StoreError> {
    conn.query(
        "SELECT series_id, run_pk_after, relative_change, status FROM regressions WHERE status <> $1",
        &[WITHDRAWN.as_str().into()],
    )?
    .iter()
    .map(|r| {
        Ok((
            r.i64(0)?,
            r.i64(1)?,
            r.opt_f64(2)?.unwrap_or(f64::INFINITY) > 0.0,
            r.string(3)?,
        ))
    })
    .collect()
}

/// Replays the history into `pool` (an empty store) and scores it.
pub fn run(
    pool: &Pool,
    template: &RunBundle,
    config: &Config,
    params: &Params,
) -> anyhow::Result<Report> {
    config.check().map_err(anyhow::Error::msg)?;
    let template = widen(template, config.scenarios);
    let mut conn = pool.get()?;
    let mut report = Report::default();
    // Truth per series from the noise-free history; noise σ from noisy minus noise-free.
    let mut truth: BTreeMap<SeriesName, Vec<Truth>> = BTreeMap::new();
    let mut schedules = Vec::new();
    let mut noisy_runs: Vec<Vec<RunBundle>> = Vec::new();
    for (pi, p) in PROFILES.iter().enumerate() {
        let sched = schedule(&template, config, pi);
        let mut rng = Rng::new(config.seed.wrapping_mul(31) + pi as u64);
        let clean: Vec<_> = (0..config.nights)
            .map(|n| values(&night_run(&template, pi, &sched, n, None)))
            .collect();
        let noisy: Vec<RunBundle> = (0..config.nights)
            .map(|n| night_run(&template, pi, &sched, n, Some(&mut rng)))
            .collect();
        let noisy_values: Vec<_> = noisy.iter().map(values).collect();
        for key in clean[0].keys() {
            let name = (
                format!("{} (replay)", p.name),
                key.0.clone(),
                key.1.clone(),
                key.2.clone(),
            );
            let c: Vec<f64> = clean.iter().map(|v| v[key]).collect();
            let resid: Vec<f64> = (0..config.nights)
                .filter(|n| !sched.outliers.contains(n))
                .map(|n| noisy_values[n][key] - c[n])
                .collect();
            let sigma = (resid.iter().map(|r| r * r).sum::<f64>() / resid.len() as f64).sqrt();
            let mut changes = Vec::new();
            for n in 1..config.nights {
                let rel = (c[n] - c[n - 1]) / c[n - 1].abs();
                if n != sched.driver_change && rel.abs() >= 0.001 {
                    changes.push(Truth {
                        night: n,
                        relative: rel,
                        sigmas: (c[n] - c[n - 1]).abs() / sigma.max(1e-300),
                    });
                }
            }
            truth.insert(name, changes);
        }
        schedules.push(sched);
        noisy_runs.push(noisy);
    }

    // Replay: nights in upload order, the profiles' runs of one night in turn.
    let mut first_seen: BTreeMap<(i64, i64), usize> = BTreeMap::new();
    let mut confirmed_at: BTreeMap<(i64, i64), usize> = BTreeMap::new();
    let mut ever_confirmed: BTreeSet<(i64, i64)> = BTreeSet::new();
    let mut ever: BTreeSet<(i64, i64, bool)> = BTreeSet::new();
    let mut published = published::Published::default();
    let mut deleted_nights: BTreeMap<i64, usize> = BTreeMap::new();
    for (pi, s) in schedules.iter().enumerate() {
        let p = PROFILES[pi].name;
        if let Some(n) = s.outlier_before {
            report.cases.push(format!(
                "{p}: outlier at night {n}, the night before a step"
            ));
        }
        if let Some(n) = s.backfill_inside {
            report.cases.push(format!(
                "{p}: night {n} (a step's) uploaded {LATE_INSIDE} nights late"
            ));
        }
        if let Some((n, _)) = s.delete {
            report.cases.push(format!(
                "{p}: run of night {n} (before a step) deleted {DELETE_AFTER} uploads after the step"
            ));
        }
    }
    for pos in 0..config.nights {
        for (pi, runs) in noisy_runs.iter().enumerate() {
            let night = schedules[pi].upload_order[pos];
            let start = std::time::Instant::now();
            regressions::ingest_and_detect(&mut *conn, &runs[night], params)?;
            report.upload_ms.push(start.elapsed().as_secs_f64() * 1e3);
            report.runs += 1;
        }
        published.record(&mut *conn)?;
        for (pi, s) in schedules.iter().enumerate() {
            if let Some((night, _)) = s.delete.filter(|d| d.1 == pos) {
                let id = format!("{}-{night:04}", PROFILES[pi].name);
                // Alerts seen before the deletion may name its run: keep its night.
                let pk = conn.query(
                    "SELECT id FROM runs WHERE run_id = $1",
                    &[id.as_str().into()],
                )?[0]
                    .i64(0)?;
                deleted_nights.insert(pk, night);
                regressions::delete_and_detect(&mut *conn, &id, params)?;
                published.record(&mut *conn)?;
            }
        }
        for (s, pk, up, status) in open_alerts(&mut *conn)? {
            first_seen.entry((s, pk)).or_insert(pos);
            ever.insert((s, pk, up));
            if status == regressions::CONFIRMED.as_str() {
                confirmed_at.entry((s, pk)).or_insert(pos);
                ever_confirmed.insert((s, pk));
            }
        }
    }

    // Names of series and nights of runs.
    let names: BTreeMap<i64, SeriesName> = conn
        .query(
            "SELECT s.id, a.name, s.scenario, s.variant, s.measure FROM series s JOIN adapters a ON a.id = s.adapter_id",
            &[],
        )?
        .iter()
        .map(|r| {
            Ok((
                r.i64(0)?,
                (r.string(1)?, r.string(2)?, r.string(3)?, r.string(4)?),
            ))
        })
        .collect::<Result<_, StoreError>>()?;
    // Run pk -> night, and (adapter name, night) -> run pk, from run ids `<profile>-<night>`.
    let mut nights: BTreeMap<i64, usize> = BTreeMap::new();
    let mut run_of: BTreeMap<(String, usize), i64> = BTreeMap::new();
    for r in conn.query("SELECT id, run_id FROM runs", &[])? {
        let id = r.string(1)?;
        let (profile, night) = id.rsplit_once('-').unwrap_or(("", "0"));
        let night: usize = night.parse().unwrap_or(0);
        nights.insert(r.i64(0)?, night);
        run_of.insert((format!("{profile} (replay)"), night), r.i64(0)?);
    }
    nights.extend(deleted_nights);
    report.series = names.len();
    report.series_nights = names.len() * config.nights;

    // Online alerts at the end, and what one batch pass over the same data finds.
    let online: BTreeSet<AlertKey> = open_alerts(&mut *conn)?
        .into_iter()
        .map(|(s, pk, up, status)| AlertKey {
            series: names[&s].clone(),
            night: nights[&pk],
            up,
            status,
        })
        .collect();
    let mut batch = BTreeSet::new();
    let mut envs = regressions::Environments::default();
    for (&id, name) in &names {
        let pts = regressions::window(&mut *conn, id, params.window, &mut envs)?;
        for f in regressions::find(&pts, params) {
            batch.insert(AlertKey {
                series: name.clone(),
                night: nights[&pts[f.change.index].run_pk],
                up: f.change.relative_change > 0.0,
                status: f.status.to_string(),
            });
        }
    }
    report.online_alerts = online.len();
    report.batch_alerts = batch.len();
    // A confirmed alert that detection would now place a few commits away but that had no strong
    // new evidence to move stays where it was announced (crate::regressions::move_reason): such a
    // pair is "held", not a disagreement.
    let only_online: Vec<&AlertKey> = online.difference(&batch).collect();
    let only_batch: Vec<&AlertKey> = batch.difference(&online).collect();
    let mut held: BTreeSet<&AlertKey> = BTreeSet::new();
    for o in &only_online {
        if o.status != regressions::CONFIRMED.as_str() {
            continue;
        }
        if let Some(b) = only_batch.iter().find(|b| {
            b.series == o.series
                && b.up == o.up
                && b.status == o.status
                && b.night.abs_diff(o.night) <= regressions::SAME_CHANGE_WITHIN
                && !held.contains(*b)
        }) {
            held.insert(o);
            held.insert(b);
            report.held += 1;
        }
    }
    for a in online
        .symmetric_difference(&batch)
        .filter(|a| !held.contains(a))
    {
        report.disagreements.push(format!(
            "{} {:?} night {} {}",
            if online.contains(a) {
                "online only:"
            } else {
                "batch only:"
            },
            a.series,
            a.night,
            a.status
        ));
    }

    // Moves, from the alerts' histories: a confirmed alert's move names its reason.
    for r in conn.query(
        "SELECT detail FROM regression_events WHERE kind = 'moved'",
        &[],
    )? {
        let d = r.string(0)?;
        if d.contains("alerts follow the data") {
            report.pending_moves += 1;
        } else {
            report.confirmed_moves += 1;
            report.backfill_moves += d.contains("(backfill") as usize;
        }
    }

    report.published = published.check(pool)?;

    // Score against the truth.
    let pos_of_night: Vec<Vec<usize>> = schedules
        .iter()
        .map(|s| {
            let mut v = vec![0; config.nights];
            for (pos, &n) in s.upload_order.iter().enumerate() {
                v[n] = pos;
            }
            v
        })
        .collect();
    let by_series: BTreeMap<&SeriesName, Vec<&AlertKey>> =
        online.iter().fold(BTreeMap::new(), |mut m, a| {
            m.entry(&a.series).or_default().push(a);
            m
        });
    let ids: BTreeMap<&SeriesName, i64> = names.iter().map(|(id, n)| (n, *id)).collect();
    for (name, changes) in &truth {
        let profile = PROFILES
            .iter()
            .position(|p| name.0.starts_with(p.name))
            .unwrap_or(0);
        for t in changes {
            let alerts = by_series.get(name).cloned().unwrap_or_default();
            let near = alerts
                .iter()
                .find(|a| a.night.abs_diff(t.night) <= 3 && a.up == (t.relative > 0.0));
            let eligible = t.sigmas >= 3.0 && t.relative.abs() >= 0.01;
            if !eligible {
                report.below_floor += 1;
                report.below_floor_found += near.is_some() as usize;
                continue;
            }
            report.eligible += 1;
            if near.is_some() {
                report.found += 1;
            }
            let exact = alerts
                .iter()
                .find(|a| a.night == t.night && a.up == (t.relative > 0.0));
            if exact.is_none() {
                report.misses.push(format!(
                    "{name:?}: {:+.1}% ({:.1} sigma) at night {}, alert at {:?}",
                    t.relative * 100.0,
                    t.sigmas,
                    t.night,
                    near.map(|a| a.night)
                ));
            }
            if let Some(a) = exact {
                report.exact += 1;
                let sid = ids[name];
                let pk = run_of.get(&(name.0.clone(), a.night)).copied();
                if let Some(pk) = pk {
                    let change_pos = pos_of_night[profile][t.night];
                    if let Some(&f) = first_seen.get(&(sid, pk)) {
                        report.first_latency.push(f.saturating_sub(change_pos));
                    }
                    if let Some(&c) = confirmed_at.get(&(sid, pk)) {
                        report.confirm_latency.push(c.saturating_sub(change_pos));
                    }
                }
            }
        }
    }
    // False alerts: any alert raised during the replay that matches no true change.
    for &(sid, pk, up) in &ever {
        let name = &names[&sid];
        let night = nights[&pk];
        let real = truth[name]
            .iter()
            .any(|t| t.night.abs_diff(night) <= 3 && (t.relative > 0.0) == up);
        if !real {
            if ever_confirmed.contains(&(sid, pk)) {
                report.false_confirmed += 1;
                report.false_list.push(format!(
                    "{name:?}: night {night}, {}",
                    if up { "up" } else { "down" }
                ));
            } else {
                report.false_pending_only += 1;
            }
        }
    }
    Ok(report)
}
