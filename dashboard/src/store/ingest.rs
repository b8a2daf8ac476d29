//! Storing a checked [`RunBundle`] in one transaction: all of it or nothing, idempotent by run id,
//! safe against concurrent uploads (conflicting inserts are `ON CONFLICT DO NOTHING`, rows are
//! taken in one global order, and a deadlocked transaction is retried).
//!
//! Every point carries its run's place in commit order (`points.ord`, see [`order_key`]), so that a
//! run uploaded late lands where its commit belongs in every series.
//!
//! Not for: checking the bundle (see [`crate::bundle`]) or regression detection (see
//! [`crate::regressions`], whose `ingest_and_detect` runs this and detection in one transaction).

use std::collections::BTreeMap;

use tessera_results::{RunInfo, Status};

use super::StoreError;
use crate::bundle::RunBundle;
use crate::db::{transaction, Connection, DbError, Value};
use tessera_results::measure::{points, speedup, DEFAULT_BASELINE};
use tessera_results::stats::frame_samples;

#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Ingested {
    /// Newly stored; `series` are the ids of the series that got a point.
    Stored {
        run_pk: i64,
        results: usize,
        series: Vec<i64>,
    },
    /// A run with this id and the same content was stored before; nothing changed.
    AlreadyStored { run_pk: i64 },
}

/// Stores `bundle`; retries the whole transaction a few times on a write conflict.
pub fn ingest(conn: &mut dyn Connection, bundle: &RunBundle) -> Result<Ingested, StoreError> {
    let mut attempt = 0;
    loop {
        match transaction(conn, |c| ingest_once(c, bundle)) {
            Err(StoreError::Db(e)) if e.is_retryable() && attempt < 5 => attempt += 1,
            other => return other,
        }
    }
}

/// The body of [`ingest`] for a caller that already holds a transaction.
pub fn ingest_in_transaction(
    conn: &mut dyn Connection,
    bundle: &RunBundle,
) -> Result<Ingested, StoreError> {
    ingest_once(conn, bundle)
}

pub fn adapter_id(conn: &mut dyn Connection, run: &RunInfo) -> Result<i64, DbError> {
    let a = &run.adapter;
    let key = [
        Value::from(a.name.as_str()),
        Value::Int(a.vendor.into()),
        Value::Int(a.device.into()),
        Value::from(a.backend.as_str()),
    ];
    if let Some(row) = conn.query_opt(
        "SELECT id FROM adapters WHERE name = $1 AND vendor = $2 AND device = $3 AND backend = $4",
        &key,
    )? {
        return row.i64(0);
    }
    let mut params = key.to_vec();
    params.push(a.device_type.as_str().into());
    conn.execute(
        "INSERT INTO adapters (name, vendor, device, backend, device_type) VALUES ($1, $2, $3, $4, $5)
         ON CONFLICT DO NOTHING",
        &params,
    )?;
    conn.query(
        "SELECT id FROM adapters WHERE name = $1 AND vendor = $2 AND device = $3 AND backend = $4",
        &key,
    )?[0]
        .i64(0)
}

/// A run's place in commit order, as stored in `points.ord`: the committer date (the start time
/// when it is unknown), then the start time, packed into one integer that sorts as the pair does
/// (see [`pack_order`]). Ties are broken by the run's row id.
pub fn order_key(run: &RunInfo) -> i64 {
    let started = epoch_seconds(&run.started_at);
    let commit = run
        .commit_time
        .as_deref()
        .map(epoch_seconds)
        .unwrap_or(started);
    pack_order(commit, started)
}

/// Seconds since 1970 of an RFC 3339 time; 0 for one that does not parse (uploads are checked,
/// so only rows of stores older than the check can hold one; they sort first).
pub fn epoch_seconds(t: &str) -> i64 {
    chrono::DateTime::parse_from_rfc3339(t).map_or(0, |d| d.timestamp())
}

/// (commit, started) seconds as one `BIGINT` that orders as the pair: the commit time in the high
/// bits (exact from 1902 to 2106), the start's delay after it in the low 31 bits (exact up to 68
/// years; a start before its commit, a skewed clock, counts as 0 and the row id breaks the tie).
/// Eight bytes where the text form (two RFC 3339 times) took 41, twice per point (the primary key
/// and the `points_run` index).
pub fn pack_order(commit: i64, started: i64) -> i64 {
    const DELAY_BITS: u32 = 31;
    let commit = commit.clamp(-(1 << 31), (1 << 32) - 2);
    let delay = (started - commit).clamp(0, (1 << DELAY_BITS) - 1);
    (commit << DELAY_BITS) | delay
}

/// The packed order of a text key written by schema steps before 11
/// (`<commit RFC 3339> <started RFC 3339>`), for the migration.
pub fn order_of_text(ord: &str) -> i64 {
    let (commit, started) = ord.split_once(' ').unwrap_or((ord, ord));
    pack_order(epoch_seconds(commit), epoch_seconds(started))
}

pub fn digest(bytes: &[u8]) -> String {
    tessera_results::upload::blob_digest(bytes)
}

/// Whether stored run `run_pk` holds what `bundle` holds: the same `run.json`, the same
/// scenario records and the same images. A repeated upload of one run is idempotent; the same run
/// id with different content is a [`StoreError::Conflict`] (409), never silently ignored.
fn same_content(
    conn: &mut dyn Connection,
    run_pk: i64,
    bundle: &RunBundle,
) -> Result<(), StoreError> {
    let id = &bundle.run.run_id;
    let conflict = |what: &str| {
        StoreError::Conflict(format!(
            "run {id} is already stored with a different {what}; a run id names one run: give this run a new run_id, or delete the stored one first (DELETE /api/runs/{id})"
        ))
    };
    let stored = conn.query(
        "SELECT run_json FROM runs WHERE id = $1",
        &[Value::Int(run_pk)],
    )?;
    let run_json = serde_json::to_string(&bundle.run).expect("records serialise");
    if stored.first().map(|r| r.string(0)).transpose()?.as_deref() != Some(run_json.as_str()) {
        return Err(conflict("run.json"));
    }
    let stored: BTreeMap<String, String> = conn
        .query(
            &format!(
                "SELECT scenario, {} FROM scenario_results WHERE run_pk = $1",
                super::records::COLUMNS
            ),
            &[Value::Int(run_pk)],
        )?
        .iter()
        .map(|r| Ok((r.string(0)?, super::records::text(r, 1)?)))
        .collect::<Result<_, StoreError>>()?;
    let incoming: BTreeMap<String, String> = bundle
        .scenarios
        .iter()
        .map(|s| {
            (
                s.scenario.clone(),
                serde_json::to_string(s).expect("records serialise"),
            )
        })
        .collect();
    if stored != incoming {
        return Err(conflict("set of scenario results"));
    }
    let stored: std::collections::BTreeSet<(String, String, String, i64, String)> = conn
        .query(
            "SELECT scenario, variant, kind, frame, digest FROM images WHERE run_pk = $1",
            &[Value::Int(run_pk)],
        )?
        .iter()
        .map(|r| {
            Ok((
                r.string(0)?,
                r.string(1)?,
                r.string(2)?,
                r.i64(3)?,
                r.string(4)?,
            ))
        })
        .collect::<Result<_, DbError>>()?;
    let mut incoming = std::collections::BTreeSet::new();
    let digests = bundle.digests_by_path();
    for s in &bundle.scenarios {
        for v in &s.results {
            for img in &v.images {
                if let Some(d) = digests.get(img.path.as_str()) {
                    incoming.insert((
                        s.scenario.clone(),
                        v.variant.clone(),
                        img.kind.clone(),
                        i64::from(img.frame),
                        d.clone(),
                    ));
                }
            }
        }
    }
    if stored != incoming {
        return Err(conflict("set of images"));
    }
    Ok(())
}

fn ingest_once(conn: &mut dyn Connection, bundle: &RunBundle) -> Result<Ingested, StoreError> {
    let run = &bundle.run;
    if let Some(row) = conn.query_opt(
        "SELECT id FROM runs WHERE run_id = $1",
        &[run.run_id.as_str().into()],
    )? {
        let run_pk = row.i64(0)?;
        same_content(conn, run_pk, bundle)?;
        return Ok(Ingested::AlreadyStored { run_pk });
    }
    let adapter = adapter_id(conn, run)?;
    let mut counts = [0i64; 3];
    for v in bundle.scenarios.iter().flat_map(|s| &s.results) {
        counts[match v.status {
            Status::Ok => 0,
            Status::Skipped { .. } => 1,
            Status::Failed { .. } => 2,
        }] += 1;
    }
    let run_json = serde_json::to_string(run).expect("records serialise");
    let inserted = conn.query(
        "INSERT INTO runs (run_id, commit_sha, dirty, started_at, finished_at, status, harness_version,
             adapter_id, driver, driver_info, hostname, n_ok, n_skipped, n_failed, run_json, imported_at,
             commit_time)
         VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12, $13, $14, $15, $16, $17)
         ON CONFLICT (run_id) DO NOTHING RETURNING id",
        &[
            run.run_id.as_str().into(),
            run.commit.as_ref().map(|c| c.sha.clone()).into(),
            run.commit.as_ref().is_some_and(|c| c.dirty).into(),
            run.started_at.as_str().into(),
            run.finished_at.clone().into(),
            serde_json::to_value(run.status).expect("status serialises").as_str().unwrap_or("").into(),
            run.harness_version.as_str().into(),
            Value::Int(adapter),
            run.adapter.driver.as_str().into(),
            run.adapter.driver_info.as_str().into(),
            run.host.hostname.as_str().into(),
            Value::Int(counts[0]),
            Value::Int(counts[1]),
            Value::Int(counts[2]),
            run_json.into(),
            crate::now_rfc3339().into(),
            run.commit_time.clone().into(),
        ],
    )?;
    let Some(row) = inserted.first() else {
        // Another upload of the same run committed first.
        let row = conn.query(
            "SELECT id FROM runs WHERE run_id = $1",
            &[run.run_id.as_str().into()],
        )?;
        let run_pk = row[0].i64(0)?;
        same_content(conn, run_pk, bundle)?;
        return Ok(Ingested::AlreadyStored { run_pk });
    };
    let run_pk = row.i64(0)?;

    // Images, content-addressed; in digest order so that concurrent uploads take rows in one order.
    let digests: BTreeMap<&str, String> = bundle.digests_by_path();
    let mut by_digest: BTreeMap<String, &[u8]> = BTreeMap::new();
    for (path, bytes) in &bundle.images {
        by_digest.insert(digests[path.as_str()].clone(), bytes);
    }
    // Images sent apart must have arrived first (`PUT /api/blobs/<digest>`).
    for (path, d) in &bundle.image_digests {
        if !by_digest.contains_key(d)
            && conn
                .query_opt(
                    "SELECT 1 FROM blobs WHERE digest = $1",
                    &[d.as_str().into()],
                )?
                .is_none()
        {
            return Err(StoreError::Invalid(format!(
                "image {path}: blob {d} is not stored; send it first with POST /api/blobs (dashboard README, Uploading)"
            )));
        }
    }
    for (d, bytes) in &by_digest {
        conn.execute(
            "INSERT INTO blobs (digest, bytes) VALUES ($1, $2) ON CONFLICT DO NOTHING",
            &[d.as_str().into(), Value::Blob(bytes.to_vec())],
        )?;
    }

    let mut series_points: BTreeMap<(String, String, String), (f64, bool)> = BTreeMap::new();
    let mut results = 0;
    for s in &bundle.scenarios {
        let record = serde_json::to_string(s).expect("records serialise");
        conn.execute(
            "INSERT INTO scenario_results (run_pk, scenario, width, height, wall_ms, record_json,
                 record_z, file)
             VALUES ($1, $2, $3, $4, $5, '', $6, $7)",
            &[
                Value::Int(run_pk),
                s.scenario.as_str().into(),
                Value::Int(s.width.into()),
                Value::Int(s.height.into()),
                Value::from(s.wall_ms),
                Value::Blob(super::records::encode(&record)),
                s.file.as_str().into(),
            ],
        )?;
        for v in &s.results {
            results += 1;
            let reason = match &v.status {
                Status::Ok => None,
                Status::Skipped { reason } => Some(reason.clone()),
                Status::Failed { error } => Some(error.clone()),
            };
            conn.execute(
                "INSERT INTO results (run_pk, scenario, variant, technique, status, reason, gpu_ms, cpu_ms,
                     speedup, allocated_bytes, frame_ms)
                 VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11)",
                &[
                    Value::Int(run_pk),
                    s.scenario.as_str().into(),
                    v.variant.as_str().into(),
                    v.technique.as_str().into(),
                    v.status.label().into(),
                    reason.into(),
                    v.gpu_frame_ms.map(|g| g.median).into(),
                    Value::from(v.cpu_frame_ms.median),
                    speedup(&s.results, v, DEFAULT_BASELINE).into(),
                    Value::Int(v.allocated_bytes.min(i64::MAX as u64) as i64),
                    // Empty where the variant has no frame timestamps (not NULL: that is a row
                    // stored before the column).
                    Value::Blob(super::records::encode_frames(
                        &frame_samples(v).unwrap_or_default(),
                    )),
                ],
            )?;
            for img in &v.images {
                if let Some(d) = digests.get(img.path.as_str()) {
                    conn.execute(
                        "INSERT INTO images (run_pk, scenario, variant, frame, kind, digest)
                         VALUES ($1, $2, $3, $4, $5, $6) ON CONFLICT DO NOTHING",
                        &[
                            Value::Int(run_pk),
                            s.scenario.as_str().into(),
                            v.variant.as_str().into(),
                            Value::Int(img.frame.into()),
                            img.kind.as_str().into(),
                            d.as_str().into(),
                        ],
                    )?;
                }
            }
            for m in points(&s.results, v) {
                series_points.insert(
                    (s.scenario.clone(), v.variant.clone(), m.key),
                    (m.value, m.higher_is_better),
                );
            }
        }
    }

    let ord = order_key(run);
    let mut series = Vec::with_capacity(series_points.len());
    for ((scenario, variant, measure), (value, hib)) in series_points {
        let id = super::series::id_or_insert(conn, &scenario, &variant, adapter, &measure, hib)?;
        super::series::insert_point(conn, id, run_pk, value, ord)?;
        series.push(id);
    }
    super::extras::store(conn, run_pk, adapter, bundle)?;
    super::frames::store(conn, run_pk, adapter, run, &bundle.scenarios)?;
    Ok(Ingested::Stored {
        run_pk,
        results,
        series,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_packed_order_sorts_as_the_pair_of_times() {
        let t = epoch_seconds;
        let keys = [
            // (commit, started), in the order a series must read them.
            ("1969-07-20T20:17:40Z", "1999-01-01T00:00:00Z"),
            ("2026-11-01T00:00:00Z", "2026-11-01T00:00:00Z"),
            ("2026-11-01T00:00:00Z", "2026-11-01T00:00:01Z"),
            // A bisection step run a year after its commit stays before the next commit's runs.
            ("2026-11-01T00:00:00Z", "2027-11-01T00:00:00Z"),
            ("2026-11-01T00:00:01Z", "2026-11-01T00:00:01Z"),
            ("2099-12-31T23:59:59Z", "2100-01-01T00:00:00Z"),
        ];
        let packed: Vec<i64> = keys.iter().map(|(c, s)| pack_order(t(c), t(s))).collect();
        for w in packed.windows(2) {
            assert!(w[0] < w[1], "{packed:?}");
        }
        // The text keys of schema steps before 11 convert to the same integers.
        for ((c, s), p) in keys.iter().zip(&packed) {
            assert_eq!(order_of_text(&format!("{c} {s}")), *p);
        }
        // A start before its commit (a skewed clock) ties with a start at the commit.
        let c = t("2026-11-01T00:00:00Z");
        assert_eq!(pack_order(c, c - 60), pack_order(c, c));
        // Offsets are taken as the instants they name.
        assert_eq!(
            epoch_seconds("2026-11-01T02:00:00+02:00"),
            t("2026-11-01T00:00:00Z")
        );
        assert_eq!(epoch_seconds("not a date"), 0);
    }
}
