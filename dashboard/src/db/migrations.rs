//! Schema migrations, one list for both backends: each step is SQL with `{id}`, `{real}` and
//! `{blob}` standing for the column types that differ (and `{without_rowid}` for SQLite's
//! clustered tables), or, where a value must be computed that the two dialects cannot compute
//! alike, code. Applied in order, each in a transaction,
//! and recorded in `schema_migrations`. Never edit a released step; append a new one.
//!
//! Not for: queries (see [`crate::store`]). The tables are documented in `schema.md`.

use super::{transaction, Backend, Connection, DbError, Value};

const STEPS: &[Step] = &[
    // 1: the initial schema.
    Sql(r#"
CREATE TABLE adapters (
    id {id},
    name TEXT NOT NULL,
    vendor BIGINT NOT NULL,
    device BIGINT NOT NULL,
    device_type TEXT NOT NULL,
    backend TEXT NOT NULL,
    UNIQUE (name, vendor, device, backend)
);
CREATE TABLE runs (
    id {id},
    run_id TEXT NOT NULL UNIQUE,
    commit_sha TEXT,
    dirty BIGINT NOT NULL,
    started_at TEXT NOT NULL,
    finished_at TEXT,
    status TEXT NOT NULL,
    harness_version TEXT NOT NULL,
    adapter_id BIGINT NOT NULL REFERENCES adapters (id),
    driver TEXT NOT NULL,
    driver_info TEXT NOT NULL,
    hostname TEXT NOT NULL,
    n_ok BIGINT NOT NULL,
    n_skipped BIGINT NOT NULL,
    n_failed BIGINT NOT NULL,
    run_json TEXT NOT NULL,
    imported_at TEXT NOT NULL
);
CREATE INDEX runs_started ON runs (started_at);
CREATE INDEX runs_adapter ON runs (adapter_id, started_at);
CREATE TABLE scenario_results (
    id {id},
    run_pk BIGINT NOT NULL REFERENCES runs (id),
    scenario TEXT NOT NULL,
    width BIGINT NOT NULL,
    height BIGINT NOT NULL,
    wall_ms {real} NOT NULL,
    record_json TEXT NOT NULL,
    UNIQUE (run_pk, scenario)
);
CREATE TABLE results (
    id {id},
    run_pk BIGINT NOT NULL REFERENCES runs (id),
    scenario TEXT NOT NULL,
    variant TEXT NOT NULL,
    technique TEXT NOT NULL,
    status TEXT NOT NULL,
    reason TEXT,
    gpu_ms {real},
    cpu_ms {real},
    speedup {real},
    allocated_bytes BIGINT NOT NULL,
    UNIQUE (run_pk, scenario, variant)
);
CREATE TABLE series (
    id {id},
    scenario TEXT NOT NULL,
    variant TEXT NOT NULL,
    adapter_id BIGINT NOT NULL REFERENCES adapters (id),
    measure TEXT NOT NULL,
    higher_is_better BIGINT NOT NULL,
    UNIQUE (scenario, variant, adapter_id, measure)
);
CREATE INDEX series_adapter ON series (adapter_id, scenario);
CREATE TABLE points (
    series_id BIGINT NOT NULL REFERENCES series (id),
    run_pk BIGINT NOT NULL REFERENCES runs (id),
    value {real} NOT NULL,
    PRIMARY KEY (series_id, run_pk)
);
CREATE INDEX points_run ON points (run_pk);
CREATE TABLE blobs (
    digest TEXT PRIMARY KEY,
    bytes {blob} NOT NULL
);
CREATE TABLE images (
    run_pk BIGINT NOT NULL REFERENCES runs (id),
    scenario TEXT NOT NULL,
    variant TEXT NOT NULL,
    frame BIGINT NOT NULL,
    kind TEXT NOT NULL,
    digest TEXT NOT NULL REFERENCES blobs (digest),
    PRIMARY KEY (run_pk, scenario, variant, frame, kind)
);
CREATE TABLE regressions (
    id {id},
    series_id BIGINT NOT NULL REFERENCES series (id),
    run_pk_before BIGINT NOT NULL REFERENCES runs (id),
    run_pk_after BIGINT NOT NULL REFERENCES runs (id),
    value_before {real} NOT NULL,
    value_after {real} NOT NULL,
    relative_change {real} NOT NULL,
    confidence {real} NOT NULL,
    state TEXT NOT NULL,
    note TEXT NOT NULL,
    detected_at TEXT NOT NULL,
    updated_at TEXT NOT NULL,
    UNIQUE (series_id, run_pk_after)
);
CREATE INDEX regressions_state ON regressions (state, detected_at);
"#),
    // Online detection (issue 12): runs ordered by commit, points carrying that order so that the
    // newest points of a series are one covering index range, alerts with a status and a history.
    Sql(r#"
ALTER TABLE runs ADD COLUMN commit_time TEXT;
ALTER TABLE points ADD COLUMN ord TEXT NOT NULL DEFAULT '';
UPDATE points SET ord = (SELECT r.started_at || ' ' || r.started_at FROM runs r WHERE r.id = points.run_pk);
CREATE INDEX points_order ON points (series_id, ord, run_pk, value);
ALTER TABLE regressions ADD COLUMN status TEXT NOT NULL DEFAULT 'confirmed';
CREATE TABLE regression_events (
    id {id},
    regression_id BIGINT NOT NULL REFERENCES regressions (id),
    at TEXT NOT NULL,
    kind TEXT NOT NULL,
    detail TEXT NOT NULL
);
CREATE INDEX regression_events_alert ON regression_events (regression_id, id);
"#),
    // i12-triage: triage by alert group (a bug link and who changed an alert last, set on every
    // alert of a group at once) and the webhook's outbox (what was sent where, so that a restart
    // neither loses nor repeats a notification). `target` is a hash of the webhook URL, which
    // may hold a secret.
    Sql(r#"
ALTER TABLE regressions ADD COLUMN bug_url TEXT NOT NULL DEFAULT '';
ALTER TABLE regressions ADD COLUMN updated_by TEXT NOT NULL DEFAULT '';
CREATE INDEX regressions_runs ON regressions (run_pk_after, run_pk_before);
CREATE TABLE webhook_targets (
    target TEXT PRIMARY KEY,
    created_at TEXT NOT NULL
);
CREATE TABLE webhook_deliveries (
    target TEXT NOT NULL REFERENCES webhook_targets (target),
    group_key TEXT NOT NULL,
    state TEXT NOT NULL,
    attempts BIGINT NOT NULL,
    next_attempt_at TEXT NOT NULL,
    last_error TEXT NOT NULL,
    created_at TEXT NOT NULL,
    sent_at TEXT,
    PRIMARY KEY (target, group_key)
);
"#),
    // Suite and branch of each run (runs list filters, same-suite comparisons), the p5-p95 band
    // of each timed point (series charts), and regressions by the run they appeared in (the
    // runs list's alert marker).
    Sql(r#"
ALTER TABLE runs ADD COLUMN suite TEXT;
ALTER TABLE runs ADD COLUMN branch TEXT;
CREATE INDEX runs_suite ON runs (suite, adapter_id, started_at);
CREATE TABLE point_bands (
    series_id BIGINT NOT NULL REFERENCES series (id),
    run_pk BIGINT NOT NULL REFERENCES runs (id),
    p5 {real} NOT NULL,
    p95 {real} NOT NULL,
    PRIMARY KEY (series_id, run_pk)
);
CREATE INDEX regressions_after ON regressions (run_pk_after);
"#),
    // i12-write: named API tokens, stored as SHA-256 of the secret (see store/tokens.rs).
    Sql(r#"
CREATE TABLE api_tokens (
    id {id},
    name TEXT NOT NULL UNIQUE,
    scope TEXT NOT NULL,
    secret_sha256 TEXT NOT NULL UNIQUE,
    created_at TEXT NOT NULL
);
"#),
    // i22: alert groups with an identity for life (old commit-range keys kept, so that links keep
    // answering), and where a change is apart from how sure it is: the interval of its size, the
    // probability of its split and its candidate range (`store/alerts.rs`). Candidates are run
    // ids without a foreign key: deleting a run shrinks a range that named it.
    Sql(r#"
CREATE TABLE alert_groups (
    id {id},
    created_at TEXT NOT NULL
);
CREATE TABLE alert_group_keys (
    key TEXT PRIMARY KEY,
    group_id BIGINT NOT NULL REFERENCES alert_groups (id),
    created_at TEXT NOT NULL
);
CREATE INDEX alert_group_keys_group ON alert_group_keys (group_id);
ALTER TABLE regressions ADD COLUMN group_id BIGINT REFERENCES alert_groups (id);
ALTER TABLE regressions ADD COLUMN change_low {real};
ALTER TABLE regressions ADD COLUMN change_high {real};
ALTER TABLE regressions ADD COLUMN location_probability {real};
ALTER TABLE regressions ADD COLUMN first_candidate BIGINT;
ALTER TABLE regressions ADD COLUMN last_candidate BIGINT;
CREATE INDEX regressions_group ON regressions (group_id);
CREATE INDEX regressions_before ON regressions (run_pk_before);
"#),
    // i35: approved frames. Per scenario, variant, adapter class and frame, the digests people
    // judged (`positive`: approved, `negative`: a regression) and the run they judged them from;
    // per uploaded run, every frame's digest with its triage (`positive`, `negative`,
    // `untriaged`) and how it matched (`exact`, `none`). See store/frames.rs.
    Sql(r#"
CREATE TABLE approved_frames (
    id {id},
    scenario TEXT NOT NULL,
    variant TEXT NOT NULL,
    adapter_class TEXT NOT NULL,
    frame BIGINT NOT NULL,
    digest TEXT NOT NULL,
    state TEXT NOT NULL,
    run_pk BIGINT REFERENCES runs (id),
    updated_by TEXT NOT NULL,
    updated_at TEXT NOT NULL,
    UNIQUE (scenario, variant, adapter_class, frame, digest)
);
CREATE INDEX approved_frames_class ON approved_frames (adapter_class, scenario);
CREATE TABLE run_frames (
    run_pk BIGINT NOT NULL REFERENCES runs (id),
    scenario TEXT NOT NULL,
    variant TEXT NOT NULL,
    frame BIGINT NOT NULL,
    adapter_class TEXT NOT NULL,
    digest TEXT NOT NULL,
    triage TEXT NOT NULL,
    matched TEXT NOT NULL,
    PRIMARY KEY (run_pk, scenario, variant, frame)
);
CREATE INDEX run_frames_triage ON run_frames (triage, run_pk);
CREATE INDEX run_frames_digest ON run_frames (scenario, variant, adapter_class, frame, digest);
"#),
    // i34: the job queue (`store/queue.rs`): requests split into jobs per adapter-class label,
    // claimed with a lease (epoch milliseconds) kept alive by heartbeats; runners and the labels
    // they serve; bisections whose steps are A/B requests.
    Sql(r#"
CREATE TABLE runners (
    id {id},
    name TEXT NOT NULL UNIQUE,
    token_name TEXT NOT NULL,
    adapter TEXT NOT NULL,
    driver TEXT NOT NULL,
    host TEXT NOT NULL,
    registered_at TEXT NOT NULL,
    last_heartbeat_ms BIGINT NOT NULL
);
CREATE TABLE runner_labels (
    runner_id BIGINT NOT NULL REFERENCES runners (id),
    label TEXT NOT NULL,
    PRIMARY KEY (runner_id, label)
);
CREATE INDEX runner_labels_label ON runner_labels (label, runner_id);
CREATE TABLE bisections (
    id {id},
    regression_id BIGINT REFERENCES regressions (id),
    scenario TEXT NOT NULL,
    variant TEXT NOT NULL,
    measure TEXT NOT NULL,
    label TEXT NOT NULL,
    good TEXT NOT NULL,
    bad TEXT NOT NULL,
    attempts BIGINT NOT NULL,
    state TEXT NOT NULL,
    commits TEXT NOT NULL,
    skipped TEXT NOT NULL,
    culprit TEXT,
    detail TEXT NOT NULL,
    created_by TEXT NOT NULL,
    created_at TEXT NOT NULL,
    updated_at TEXT NOT NULL
);
CREATE INDEX bisections_regression ON bisections (regression_id);
CREATE TABLE queue_requests (
    id {id},
    kind TEXT NOT NULL,
    spec TEXT NOT NULL,
    bisection_id BIGINT REFERENCES bisections (id),
    created_by TEXT NOT NULL,
    created_at TEXT NOT NULL
);
CREATE INDEX queue_requests_bisection ON queue_requests (bisection_id, id);
CREATE TABLE queue_jobs (
    id {id},
    request_id BIGINT NOT NULL REFERENCES queue_requests (id),
    label TEXT NOT NULL,
    spec TEXT NOT NULL,
    status TEXT NOT NULL,
    attempts BIGINT NOT NULL,
    max_attempts BIGINT NOT NULL,
    runner_id BIGINT REFERENCES runners (id),
    lease_expires_ms BIGINT,
    error TEXT NOT NULL,
    outcome TEXT,
    created_at TEXT NOT NULL,
    started_at TEXT,
    finished_at TEXT
);
CREATE INDEX queue_jobs_claim ON queue_jobs (status, label, id);
CREATE INDEX queue_jobs_request ON queue_jobs (request_id);
CREATE INDEX queue_jobs_runner ON queue_jobs (runner_id, status);
"#),
    // i37: compact storage for a year of results. A scenario's record is stored deflated
    // (`record_z`, see store/records.rs; `record_json` stays for rows stored before, new rows
    // leave it empty) with its scenario file as a column; points become one B-tree keyed by
    // (series, commit order, run) holding the value (SQLite `WITHOUT ROWID`: the table, its
    // primary key and the covering `points_order` index were three copies), and so do images.
    Sql(r#"
ALTER TABLE scenario_results ADD COLUMN record_z {blob};
ALTER TABLE scenario_results ADD COLUMN file TEXT;
CREATE TABLE points_compact (
    series_id BIGINT NOT NULL REFERENCES series (id),
    ord TEXT NOT NULL,
    run_pk BIGINT NOT NULL REFERENCES runs (id),
    value {real} NOT NULL,
    PRIMARY KEY (series_id, ord, run_pk)
){without_rowid};
INSERT INTO points_compact (series_id, ord, run_pk, value)
    SELECT series_id, ord, run_pk, value FROM points;
DROP TABLE points;
ALTER TABLE points_compact RENAME TO points;
CREATE INDEX points_run ON points (run_pk);
CREATE TABLE images_compact (
    run_pk BIGINT NOT NULL REFERENCES runs (id),
    scenario TEXT NOT NULL,
    variant TEXT NOT NULL,
    frame BIGINT NOT NULL,
    kind TEXT NOT NULL,
    digest TEXT NOT NULL REFERENCES blobs (digest),
    PRIMARY KEY (run_pk, scenario, variant, frame, kind)
){without_rowid};
INSERT INTO images_compact (run_pk, scenario, variant, frame, kind, digest)
    SELECT run_pk, scenario, variant, frame, kind, digest FROM images;
DROP TABLE images;
ALTER TABLE images_compact RENAME TO images;
"#),
    // i37: a result's per-frame GPU times (each measured frame's sum over passes, the samples
    // `tessera compare` tests; little-endian f64s, store/records.rs) beside its row, so a run's
    // summary against the previous run reads rows instead of decoding every scenario record.
    // NULL in rows stored before: their readers decode the records.
    Sql(r#"
ALTER TABLE results ADD COLUMN frame_ms {blob};
"#),
    // i37: a point's place in commit order as one integer (ingest::pack_order) instead of two
    // RFC 3339 times as text: 8 bytes where there were 41, in the primary key and again in the
    // `points_run` index. The integers are computed from the old text by code: the two dialects
    // parse times differently.
    Code(pack_point_order),
    // i37: a scenario's newest record found by one index seek. The alert pages name each
    // alerted scenario's suite from its newest record (store/alerts.rs); without an index led
    // by `scenario` that was a scan of every record row's key (544,000 of them in the
    // 2.72-million-result store): 90 ms of `/regressions` and of every series page.
    Sql(r#"
CREATE INDEX scenario_results_scenario ON scenario_results (scenario, id);
"#),
];

/// One migration step.
enum Step {
    Sql(&'static str),
    Code(fn(&mut dyn Connection) -> Result<(), DbError>),
}
use Step::{Code, Sql};

/// Step 11: `points.ord` from text (`<commit> <started>`, RFC 3339) to the packed integer of
/// [`crate::store::ingest::pack_order`]. Every point of a run has its run's key, so the text is
/// read once per run; the points are then copied into the new table through that map.
fn pack_point_order(c: &mut dyn Connection) -> Result<(), DbError> {
    let backend = c.backend();
    let runs = c.query("SELECT run_pk, MIN(ord) FROM points GROUP BY run_pk", &[])?;
    c.batch("CREATE TABLE points_order_map (run_pk BIGINT PRIMARY KEY, ord BIGINT NOT NULL)")?;
    for r in &runs {
        c.execute(
            "INSERT INTO points_order_map (run_pk, ord) VALUES ($1, $2)",
            &[
                Value::Int(r.i64(0)?),
                Value::Int(crate::store::ingest::order_of_text(r.str(1)?)),
            ],
        )?;
    }
    c.batch(&render(
        r#"
CREATE TABLE points_packed (
    series_id BIGINT NOT NULL REFERENCES series (id),
    ord BIGINT NOT NULL,
    run_pk BIGINT NOT NULL REFERENCES runs (id),
    value {real} NOT NULL,
    PRIMARY KEY (series_id, ord, run_pk)
){without_rowid};
INSERT INTO points_packed (series_id, ord, run_pk, value)
    SELECT p.series_id, m.ord, p.run_pk, p.value FROM points p JOIN points_order_map m ON m.run_pk = p.run_pk;
DROP TABLE points;
DROP TABLE points_order_map;
ALTER TABLE points_packed RENAME TO points;
CREATE INDEX points_run ON points (run_pk);
"#,
        backend,
    ))
}

fn render(step: &str, backend: Backend) -> String {
    let (id, real, blob, without_rowid) = match backend {
        Backend::Sqlite => ("INTEGER PRIMARY KEY", "REAL", "BLOB", " WITHOUT ROWID"),
        Backend::Postgres => (
            "BIGINT GENERATED BY DEFAULT AS IDENTITY PRIMARY KEY",
            "DOUBLE PRECISION",
            "BYTEA",
            "",
        ),
    };
    step.replace("{id}", id)
        .replace("{real}", real)
        .replace("{blob}", blob)
        .replace("{without_rowid}", without_rowid)
}

/// The schema version this binary migrates to.
pub fn known_version() -> i64 {
    STEPS.len() as i64
}

/// The store's schema version (the newest applied step; 0 for an empty store).
pub fn current_version(conn: &mut dyn Connection) -> Result<i64, DbError> {
    conn.query(
        "SELECT COALESCE(MAX(version), 0) FROM schema_migrations",
        &[],
    )?
    .first()
    .map(|r| r.i64(0))
    .transpose()
    .map(|v| v.unwrap_or(0))
}

/// Brings the store up to schema version `target` (at most [`known_version`]; the newest for a
/// store in use, an older one where a test checks that the newer steps migrate its rows); refuses
/// a store newer than this binary.
pub fn migrate_to(conn: &mut dyn Connection, target: i64) -> Result<(), DbError> {
    conn.batch(
        "CREATE TABLE IF NOT EXISTS schema_migrations (version BIGINT PRIMARY KEY, applied_at TEXT NOT NULL)",
    )?;
    let current = conn
        .query(
            "SELECT COALESCE(MAX(version), 0) FROM schema_migrations",
            &[],
        )?
        .first()
        .map(|r| r.i64(0))
        .transpose()?
        .unwrap_or(0);
    let known = STEPS.len() as i64;
    if current > known {
        return Err(DbError::SchemaTooNew {
            found: current,
            known,
        });
    }
    let backend = conn.backend();
    let steps = STEPS.iter().take(target.clamp(0, known) as usize);
    for (i, step) in steps.enumerate().skip(current as usize) {
        let version = i as i64 + 1;
        transaction(conn, |c| {
            match step {
                Sql(sql) => c.batch(&render(sql, backend))?,
                Code(f) => f(c)?,
            }
            c.execute(
                "INSERT INTO schema_migrations (version, applied_at) VALUES ($1, $2)",
                &[Value::Int(version), Value::Text(crate::now_rfc3339())],
            )?;
            Ok::<_, DbError>(())
        })?;
    }
    Ok(())
}
