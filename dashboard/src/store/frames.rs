//! Approved frames (issue 35): every uploaded run's frame digests, matched against the digests
//! people approved per (scenario, variant, adapter class, frame), and the triage that approves a
//! frame (`positive`) or marks it as a regression (`negative`). A frame that matches no approved
//! digest is `untriaged`; when the same frame had an approved digest before (a change in what
//! is drawn, which the same-run diff cannot see), its variant gets an alert in the same
//! `regressions` table, groups, feed and webhook as time and quality alerts: the series
//! `frames.untriaged` of that scenario, variant and adapter (value: its untriaged frames),
//! from the run the approved frame came from to this run, so that bisection has a range.
//! Frames with no approved digest at all (a new scenario) are untriaged without an alert.
//!
//! Tables (`db/schema.md`): `approved_frames`, `run_frames`. Not for: HTTP (see
//! `server/frames.rs`), detection over series (`regressions.rs` leaves `frames.untriaged` alone).

use std::collections::BTreeMap;

use serde::Serialize;
use tessera_results::{RunInfo, ScenarioResult};

use super::alerts::{self, DetectionStatus, Placement};
use super::StoreError;
use crate::db::{Connection, Value};

/// The measure of a frame alert's series.
pub use super::series::UNTRIAGED_MEASURE;

/// The variant name the separately rendered reference's frames are kept under.
pub const REFERENCE_VARIANT: &str = "(reference)";

/// Triage states of a frame.
pub const POSITIVE: &str = "positive";
pub const NEGATIVE: &str = "negative";
pub const UNTRIAGED: &str = "untriaged";

/// The adapter class of a run: what it declares (`adapter_class`), else derived from its adapter
/// (`tessera_results::adapter::class`).
pub fn class_of(run: &RunInfo) -> String {
    run.adapter_class
        .clone()
        .filter(|c| !c.is_empty())
        .unwrap_or_else(|| tessera_results::adapter::class(&run.adapter))
}

/// Every (variant, frame, digest) of a scenario result: each variant's, then the separate
/// reference's under [`REFERENCE_VARIANT`].
pub fn digests_of(s: &ScenarioResult) -> Vec<(String, i64, String)> {
    let mut out = Vec::new();
    for v in &s.results {
        for (i, d) in v.frame_digests.iter().enumerate() {
            out.push((v.variant.clone(), i as i64, d.clone()));
        }
    }
    for (i, d) in s.reference_digests.iter().enumerate() {
        out.push((REFERENCE_VARIANT.to_string(), i as i64, d.clone()));
    }
    out
}

/// The judged digests of one frame: (digest, state, run_pk).
fn judged(
    conn: &mut dyn Connection,
    scenario: &str,
    variant: &str,
    class: &str,
    frame: i64,
) -> Result<Vec<(String, String, Option<i64>)>, StoreError> {
    conn.query(
        "SELECT digest, state, run_pk FROM approved_frames
         WHERE scenario = $1 AND variant = $2 AND adapter_class = $3 AND frame = $4 ORDER BY id DESC",
        &[
            scenario.into(),
            variant.into(),
            class.into(),
            Value::Int(frame),
        ],
    )?
    .iter()
    .map(|r| Ok((r.string(0)?, r.string(1)?, r.opt_i64(2)?)))
    .collect()
}

/// Stores the frame digests of run `run_pk` (in its ingest transaction), matches each against
/// the approved ones and raises the alerts of changed frames. Returns how many are untriaged.
pub fn store(
    conn: &mut dyn Connection,
    run_pk: i64,
    adapter: i64,
    run: &RunInfo,
    scenarios: &[ScenarioResult],
) -> Result<usize, StoreError> {
    let class = class_of(run);
    let mut untriaged = 0;
    // Per (scenario, variant): untriaged frames that had an approved digest, and the run that
    // approved it (the alert's "before").
    let mut changed: BTreeMap<(String, String), (i64, Option<i64>)> = BTreeMap::new();
    for s in scenarios {
        for (variant, frame, digest) in digests_of(s) {
            let judged = judged(conn, &s.scenario, &variant, &class, frame)?;
            let state =
                judged
                    .iter()
                    .find(|(d, _, _)| *d == digest)
                    .map_or(
                        UNTRIAGED,
                        |(_, st, _)| {
                            if st == POSITIVE {
                                POSITIVE
                            } else {
                                NEGATIVE
                            }
                        },
                    );
            conn.execute(
                "INSERT INTO run_frames (run_pk, scenario, variant, frame, adapter_class, digest, triage, matched)
                 VALUES ($1, $2, $3, $4, $5, $6, $7, $8)",
                &[
                    Value::Int(run_pk),
                    s.scenario.as_str().into(),
                    variant.as_str().into(),
                    Value::Int(frame),
                    class.as_str().into(),
                    digest.as_str().into(),
                    state.into(),
                    (if state == UNTRIAGED { "none" } else { "exact" }).into(),
                ],
            )?;
            if state != UNTRIAGED {
                continue;
            }
            untriaged += 1;
            let approved_run = judged
                .iter()
                .find(|(_, st, _)| st == POSITIVE)
                .map(|(_, _, r)| *r);
            if let Some(before) = approved_run {
                let e = changed
                    .entry((s.scenario.clone(), variant.clone()))
                    .or_insert((0, before));
                e.0 += 1;
            }
        }
    }
    for ((scenario, variant), (count, before)) in changed {
        let series = untriaged_series(conn, &scenario, &variant, adapter)?;
        let before = before.unwrap_or(run_pk);
        let placement = Placement {
            run_pk_before: before,
            run_pk_after: run_pk,
            value_before: 0.0,
            value_after: count as f64,
            relative_change: 1e300,
            change_low: 1e300,
            change_high: 1e300,
            confidence: 1.0,
            location_probability: 1.0,
            first_candidate: run_pk,
            last_candidate: run_pk,
            status: DetectionStatus::Confirmed,
        };
        let id = alerts::insert(conn, series, &placement)?;
        alerts::event(
            conn,
            id,
            "detected",
            format!("{count} frames of {scenario} / {variant} match no approved frame of adapter class {class}"),
        )?;
    }
    Ok(untriaged)
}

/// The `frames.untriaged` series of a scenario, variant and adapter (made on first use; it has
/// no points: the alert is the record).
fn untriaged_series(
    conn: &mut dyn Connection,
    scenario: &str,
    variant: &str,
    adapter: i64,
) -> Result<i64, StoreError> {
    super::series::id_or_insert(conn, scenario, variant, adapter, UNTRIAGED_MEASURE, false)
}

/// One frame of a run with its triage.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct RunFrame {
    pub run_id: String,
    pub commit: Option<String>,
    pub scenario: String,
    pub variant: String,
    pub frame: i64,
    pub adapter_class: String,
    pub digest: String,
    pub triage: String,
    pub matched: String,
}

const RUN_FRAME_COLUMNS: &str = "r.run_id, r.commit_sha, f.scenario, f.variant, f.frame, f.adapter_class, f.digest, f.triage, f.matched";

fn run_frame(r: &crate::db::Row) -> Result<RunFrame, StoreError> {
    Ok(RunFrame {
        run_id: r.string(0)?,
        commit: r.opt_string(1)?,
        scenario: r.string(2)?,
        variant: r.string(3)?,
        frame: r.i64(4)?,
        adapter_class: r.string(5)?,
        digest: r.string(6)?,
        triage: r.string(7)?,
        matched: r.string(8)?,
    })
}

/// Untriaged frames, newest run first (at most `limit`).
pub fn untriaged(conn: &mut dyn Connection, limit: i64) -> Result<Vec<RunFrame>, StoreError> {
    conn.query(
        &format!(
            "SELECT {RUN_FRAME_COLUMNS} FROM run_frames f JOIN runs r ON r.id = f.run_pk
             WHERE f.triage = 'untriaged' ORDER BY r.started_at DESC, f.run_pk DESC, f.scenario, f.variant, f.frame LIMIT $1"
        ),
        &[Value::Int(limit)],
    )?
    .iter()
    .map(run_frame)
    .collect()
}

/// A run's frames (optionally one scenario's).
pub fn of_run(
    conn: &mut dyn Connection,
    run_id: &str,
    scenario: Option<&str>,
) -> Result<Vec<RunFrame>, StoreError> {
    let pk = super::run_pk(conn, run_id)?;
    conn.query(
        &format!(
            "SELECT {RUN_FRAME_COLUMNS} FROM run_frames f JOIN runs r ON r.id = f.run_pk
             WHERE f.run_pk = $1 AND ($2 = '' OR f.scenario = $2) ORDER BY f.scenario, f.variant, f.frame"
        ),
        &[Value::Int(pk), scenario.unwrap_or("").into()],
    )?
    .iter()
    .map(run_frame)
    .collect()
}

/// The approved frame closest to a run's frame: the newest positive digest of the same
/// scenario, variant, adapter class and frame, with the run it was approved from.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Approved {
    pub digest: String,
    pub run_id: Option<String>,
    pub updated_by: String,
    pub updated_at: String,
}

pub fn closest_approved(
    conn: &mut dyn Connection,
    f: &RunFrame,
) -> Result<Option<Approved>, StoreError> {
    let row = conn.query_opt(
        "SELECT a.digest, r.run_id, a.updated_by, a.updated_at FROM approved_frames a
         LEFT JOIN runs r ON r.id = a.run_pk
         WHERE a.scenario = $1 AND a.variant = $2 AND a.adapter_class = $3 AND a.frame = $4
           AND a.state = 'positive'
         ORDER BY a.id DESC LIMIT 1",
        &[
            f.scenario.as_str().into(),
            f.variant.as_str().into(),
            f.adapter_class.as_str().into(),
            Value::Int(f.frame),
        ],
    )?;
    row.map(|r| {
        Ok(Approved {
            digest: r.string(0)?,
            run_id: r.opt_string(1)?,
            updated_by: r.string(2)?,
            updated_at: r.string(3)?,
        })
    })
    .transpose()
}

/// What to judge: a run's frames, optionally one scenario's, variant's or frame's.
#[derive(Clone, Debug, Default)]
pub struct Judge {
    pub run_id: String,
    pub scenario: Option<String>,
    pub variant: Option<String>,
    pub frame: Option<i64>,
    /// [`POSITIVE`] (approve) or [`NEGATIVE`] (a regression).
    pub state: String,
    pub by: String,
}

/// Judges frames: records their digests as `state` for their scenario, variant, adapter class
/// and frame, sets every stored frame with the same digest to it (in any run), and settles the
/// frame alerts of the variants: approving withdraws an alert whose run has no untriaged frame
/// of that variant left; marking a regression acknowledges it. Returns the frames judged.
pub fn judge(conn: &mut dyn Connection, j: &Judge) -> Result<usize, StoreError> {
    if j.state != POSITIVE && j.state != NEGATIVE {
        return Err(StoreError::Invalid(format!(
            "state {:?} is not one of {POSITIVE}, {NEGATIVE}",
            j.state
        )));
    }
    let pk = super::run_pk(conn, &j.run_id)?;
    let frames: Vec<RunFrame> = of_run(conn, &j.run_id, j.scenario.as_deref())?
        .into_iter()
        .filter(|f| j.variant.as_ref().is_none_or(|v| *v == f.variant))
        .filter(|f| j.frame.is_none_or(|n| n == f.frame))
        .collect();
    if frames.is_empty() {
        return Err(StoreError::NotFound(format!(
            "frame digests of run {} matching that selection (runs written before result format 3 have none)",
            j.run_id
        )));
    }
    let now = crate::now_rfc3339();
    for f in &frames {
        let key = [
            f.scenario.as_str().into(),
            f.variant.as_str().into(),
            f.adapter_class.as_str().into(),
            Value::Int(f.frame),
            f.digest.as_str().into(),
        ];
        let updated = conn.execute(
            "UPDATE approved_frames SET state = $6, run_pk = $7, updated_by = $8, updated_at = $9
             WHERE scenario = $1 AND variant = $2 AND adapter_class = $3 AND frame = $4 AND digest = $5",
            &[
                key[0].clone(),
                key[1].clone(),
                key[2].clone(),
                key[3].clone(),
                key[4].clone(),
                j.state.as_str().into(),
                Value::Int(pk),
                j.by.as_str().into(),
                now.as_str().into(),
            ],
        )?;
        if updated == 0 {
            let mut params = key.to_vec();
            params.extend([
                j.state.as_str().into(),
                Value::Int(pk),
                j.by.as_str().into(),
                now.as_str().into(),
            ]);
            conn.execute(
                "INSERT INTO approved_frames (scenario, variant, adapter_class, frame, digest, state, run_pk, updated_by, updated_at)
                 VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9)",
                &params,
            )?;
        }
        conn.execute(
            "UPDATE run_frames SET triage = $6
             WHERE scenario = $1 AND variant = $2 AND adapter_class = $3 AND frame = $4 AND digest = $5",
            &[
                key[0].clone(),
                key[1].clone(),
                key[2].clone(),
                key[3].clone(),
                key[4].clone(),
                j.state.as_str().into(),
            ],
        )?;
    }
    settle_alerts(conn, &frames, &j.state, &j.by)?;
    Ok(frames.len())
}

/// Settles the frame alerts of the judged frames' variants, in every run with such an alert.
fn settle_alerts(
    conn: &mut dyn Connection,
    frames: &[RunFrame],
    state: &str,
    by: &str,
) -> Result<(), StoreError> {
    let mut variants: Vec<(&str, &str)> = frames
        .iter()
        .map(|f| (f.scenario.as_str(), f.variant.as_str()))
        .collect();
    variants.dedup();
    for (scenario, variant) in variants {
        let open = conn.query(
            "SELECT g.id, g.run_pk_after FROM regressions g JOIN series s ON s.id = g.series_id
             WHERE s.scenario = $1 AND s.variant = $2 AND s.measure = $3 AND g.status <> 'withdrawn'",
            &[scenario.into(), variant.into(), UNTRIAGED_MEASURE.into()],
        )?;
        for row in open {
            let (id, run_pk) = (row.i64(0)?, row.i64(1)?);
            if state == NEGATIVE {
                conn.execute(
                    "UPDATE regressions SET state = 'acknowledged', note = $1, updated_by = $2, updated_at = $3 WHERE id = $4",
                    &[
                        "frames marked as a regression".into(),
                        by.into(),
                        crate::now_rfc3339().into(),
                        Value::Int(id),
                    ],
                )?;
                continue;
            }
            let left = conn.query(
                "SELECT COUNT(*) FROM run_frames WHERE run_pk = $1 AND scenario = $2 AND variant = $3 AND triage = 'untriaged'",
                &[Value::Int(run_pk), scenario.into(), variant.into()],
            )?[0]
                .i64(0)?;
            if left == 0 {
                alerts::set_status(conn, id, DetectionStatus::Withdrawn)?;
                alerts::event(
                    conn,
                    id,
                    "withdrawn",
                    format!("every frame of {scenario} / {variant} approved by {by}"),
                )?;
            }
        }
    }
    Ok(())
}

/// The judged digests of an adapter class (optionally of one suite's scenarios), for `tessera run
/// --expect URL` and committed digest files: the format of `results/README.md`, "Approved
/// frame digests".
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct DigestFile {
    pub adapter_class: String,
    pub frames: Vec<DigestEntry>,
}

#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct DigestEntry {
    pub scenario: String,
    pub variant: String,
    pub frame: i64,
    pub digest: String,
    pub state: String,
}

pub fn digest_file(conn: &mut dyn Connection, class: &str) -> Result<DigestFile, StoreError> {
    let frames = conn
        .query(
            "SELECT scenario, variant, frame, digest, state FROM approved_frames WHERE adapter_class = $1
             ORDER BY scenario, variant, frame, digest",
            &[class.into()],
        )?
        .iter()
        .map(|r| {
            Ok(DigestEntry {
                scenario: r.string(0)?,
                variant: r.string(1)?,
                frame: r.i64(2)?,
                digest: r.string(3)?,
                state: r.string(4)?,
            })
        })
        .collect::<Result<_, StoreError>>()?;
    Ok(DigestFile {
        adapter_class: class.to_string(),
        frames,
    })
}
