//! Storage tests, run on SQLite and (when `TESSERA_TEST_POSTGRES_URL` is set) PostgreSQL: import of
//! real run folders, idempotence, all-or-nothing transactions, concurrent uploads, regression
//! detection on stored series and triage that persists.

mod common;

use tessera_dashboard::bundle::RunBundle;
use tessera_dashboard::db::{transaction, DbError, Value};
use tessera_dashboard::detect::{Params, Rng};
use tessera_dashboard::import::import;
use tessera_dashboard::store::ingest::{ingest, Ingested};
use tessera_dashboard::store::{read, triage};
use tessera_dashboard::{regressions, synth};

fn count(store: &common::TestStore, table: &str) -> i64 {
    let mut c = store.pool.get().unwrap();
    c.query(&format!("SELECT COUNT(*) FROM {table}"), &[])
        .unwrap()[0]
        .i64(0)
        .unwrap()
}

#[test]
fn imports_real_runs_once() {
    for store in common::stores("imports_real_runs_once") {
        let first = import(&store.pool, &common::fixtures(), &Params::default()).unwrap();
        assert_eq!(
            (first.stored, first.results, first.failed.len()),
            (2, 6, 0),
            "{}",
            store.name
        );
        let again = import(&store.pool, &common::fixtures(), &Params::default()).unwrap();
        assert_eq!(
            (again.stored, again.already_stored),
            (0, 2),
            "{}",
            store.name
        );
        assert_eq!(count(&store, "runs"), 2);
        assert_eq!(count(&store, "results"), 6);
        // Identical reference and native images are stored once (content-addressed).
        assert!(
            count(&store, "blobs") < count(&store, "images"),
            "{}",
            store.name
        );
        let mut c = store.pool.get().unwrap();
        let runs = read::runs(&mut *c, None, 10).unwrap();
        assert_eq!(runs.len(), 2);
        assert_eq!((runs[0].ok, runs[0].skipped, runs[0].failed), (3, 0, 0));
        assert!(runs[0].started_at >= runs[1].started_at, "newest first");
        let detail = read::run(&mut *c, &runs[0].run_id).unwrap();
        assert_eq!(detail.scenarios[0].results.len(), 3);
        assert!(detail.series.iter().any(|s| s.measure == "speedup"));
    }
}

#[test]
fn failed_transaction_stores_nothing() {
    for store in common::stores("failed_transaction_stores_nothing") {
        let bundle = common::template();
        let mut c = store.pool.get().unwrap();
        let r: Result<Ingested, tessera_dashboard::store::StoreError> = transaction(&mut *c, |c| {
            let out = ingest_inner(c, &bundle)?;
            // Fail after everything was written.
            c.execute(
                "INSERT INTO no_such_table (x) VALUES ($1)",
                &[Value::Int(1)],
            )?;
            Ok(out)
        });
        assert!(r.is_err());
        drop(c);
        for table in ["runs", "results", "points", "images", "blobs", "series"] {
            assert_eq!(count(&store, table), 0, "{} {table}", store.name);
        }
    }
}

/// `ingest` opens its own transaction; inside another one, run its body through a savepoint-free
/// path: the nested BEGIN is what the outer transaction already did, so call the public API on a
/// bundle and let the outer ROLLBACK undo it.
fn ingest_inner(
    c: &mut dyn tessera_dashboard::db::Connection,
    bundle: &RunBundle,
) -> Result<Ingested, tessera_dashboard::store::StoreError> {
    tessera_dashboard::store::ingest::ingest_in_transaction(c, bundle)
}

#[test]
fn concurrent_uploads_lose_nothing() {
    for store in common::stores("concurrent_uploads_lose_nothing") {
        let template = common::template();
        let mut rng = Rng::new(7);
        // 12 distinct runs; 4 of them uploaded twice, with the same content (the same run id
        // with other content is a conflict, see tests/validation.rs).
        let distinct: Vec<RunBundle> = (0..12)
            .map(|i| synth::run_from(&template, "conc", i, 1.0, 0.01, &mut rng))
            .collect();
        let bundles: Vec<RunBundle> = (0..16).map(|i| distinct[i % 12].clone()).collect();
        std::thread::scope(|s| {
            for chunk in bundles.chunks(2) {
                let pool = store.pool.clone();
                s.spawn(move || {
                    for b in chunk {
                        let mut c = pool.get().unwrap();
                        ingest(&mut *c, b).unwrap();
                    }
                });
            }
        });
        // 16 uploads of 12 distinct run ids.
        assert_eq!(count(&store, "runs"), 12, "{}", store.name);
        assert_eq!(count(&store, "results"), 36, "{}", store.name);
        let mut c = store.pool.get().unwrap();
        let n = c
            .query(
                "SELECT COUNT(*) FROM series WHERE measure = 'gpu_ms.median'",
                &[],
            )
            .unwrap()[0]
            .i64(0)
            .unwrap();
        assert_eq!(n, 3);
        let p = c.query("SELECT COUNT(*) FROM points", &[]).unwrap()[0]
            .i64(0)
            .unwrap();
        let per_run = p / 12;
        assert_eq!(p, per_run * 12, "{}", store.name);
    }
}

#[test]
fn step_in_stored_series_becomes_a_regression_with_persistent_triage() {
    for store in common::stores("step_in_stored_series") {
        let template = common::template();
        let mut rng = Rng::new(11);
        let mut c = store.pool.get().unwrap();
        let mut touched = std::collections::BTreeSet::new();
        for i in 0..40u64 {
            let factor = if i < 30 { 1.0 } else { 1.10 };
            let b = synth::run_from(&template, "step", i, factor, 0.01, &mut rng);
            if let Ingested::Stored { series, .. } = ingest(&mut *c, &b).unwrap() {
                touched.extend(series);
            }
        }
        let touched: Vec<i64> = touched.into_iter().collect();
        let added = regressions::update(&mut *c, &touched, &Params::default()).unwrap();
        assert!(added >= 3, "{}: {added}", store.name);
        let rows = read::regressions(&mut *c, None, None, 100).unwrap();
        let gpu: Vec<_> = rows
            .iter()
            .filter(|r| r.series.measure == "gpu_ms.median")
            .collect();
        assert_eq!(gpu.len(), 3, "{}: one per variant", store.name);
        assert!(gpu
            .iter()
            .all(|r| r.run_after == "step-000030" && r.is_regression && r.state == "new"));
        // Speedup does not move: every variant, native included, got 10% slower.
        assert!(
            !rows.iter().any(|r| r.series.measure == "speedup"),
            "{}",
            store.name
        );

        triage::set(
            &mut *c,
            gpu[0].id,
            "acknowledged",
            "driver update on the runner",
        )
        .unwrap();
        assert!(triage::set(&mut *c, gpu[0].id, "bogus", "").is_err());
        // Running detection again adds nothing and keeps the triage.
        assert_eq!(
            regressions::update(&mut *c, &touched, &Params::default()).unwrap(),
            0
        );
        let again = read::regressions(&mut *c, Some("acknowledged"), None, 100).unwrap();
        assert_eq!(again.len(), 1);
        assert_eq!(again[0].note, "driver update on the runner");
        let series = read::series(&mut *c, gpu[0].series.id).unwrap();
        assert_eq!(series.points.len(), 40);
        assert_eq!(series.segment_starts, vec![0]);
    }
}

#[test]
fn driver_change_in_stored_series_is_a_segment_not_a_regression() {
    for store in common::stores("driver_change_in_stored_series") {
        let template = common::template();
        let mut rng = Rng::new(12);
        let mut c = store.pool.get().unwrap();
        for i in 0..40u64 {
            let factor = if i < 30 { 1.0 } else { 1.10 };
            let mut b = synth::run_from(&template, "drv", i, factor, 0.01, &mut rng);
            if i >= 30 {
                b.run.adapter.driver_info = "Mesa 24.0.0".into();
            }
            ingest(&mut *c, &b).unwrap();
        }
        let all = regressions::all_series(&mut *c).unwrap();
        regressions::update(&mut *c, &all, &Params::default()).unwrap();
        let rows = read::regressions(&mut *c, None, None, 100).unwrap();
        assert!(rows.is_empty(), "{}: {rows:?}", store.name);
        let gpu = read::find_series(
            &mut *c,
            None,
            Some("native"),
            None,
            Some("gpu_ms.median"),
            10,
        )
        .unwrap();
        assert_eq!(
            read::series(&mut *c, gpu[0].id).unwrap().segment_starts,
            vec![0, 30]
        );
    }
}

#[test]
fn store_newer_than_binary_is_refused() {
    let store = common::sqlite();
    let mut c = store.pool.get().unwrap();
    c.execute(
        "INSERT INTO schema_migrations (version, applied_at) VALUES ($1, $2)",
        &[Value::Int(999), "x".into()],
    )
    .unwrap();
    drop(c);
    let path = {
        let mut c = store.pool.get().unwrap();
        c.query("PRAGMA database_list", &[]).unwrap()[0]
            .string(2)
            .unwrap()
    };
    match tessera_dashboard::db::open(&path) {
        // The number of known steps grows with every migration; the message names both.
        Err(e @ DbError::SchemaTooNew { .. }) => {
            let m = e.to_string();
            assert!(
                m.starts_with(
                    "the store has schema version 999, newer than this dashboard knows ("
                ) && m.ends_with("); upgrade tessera-dashboard"),
                "{m}"
            )
        }
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("opened a newer store"),
    }
}

/// The harness's schema-version-1 fixture (`results/tests/fixtures/v1/`), read through the shared
/// reader and stored: every series is named by the measure table, and the direction regression
/// detection reads (`series.higher_is_better`) is the table's.
#[test]
fn stored_series_take_the_measure_tables_names_and_directions() {
    use tessera_results::measure::Key;
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../results/tests/fixtures/v1/20261201T103009Z");
    let bundle = RunBundle::read_folder(&dir).unwrap();
    assert_eq!(bundle.run.schema_version, tessera_results::SCHEMA_VERSION);
    // Metric records that are no measure of the table, with their direction.
    let checks: std::collections::BTreeMap<&str, bool> = bundle
        .scenarios
        .iter()
        .flat_map(|s| &s.results)
        .flat_map(|v| &v.metrics)
        .filter(|m| tessera_results::measure::Measure::from_name(&m.name).is_none())
        .map(|m| (m.name.as_str(), m.higher_is_better))
        .collect();
    for store in common::stores("stored_series_take_the_measure_tables_names") {
        let mut c = store.pool.get().unwrap();
        assert!(matches!(
            ingest(&mut *c, &bundle).unwrap(),
            Ingested::Stored { .. }
        ));
        let rows = c
            .query("SELECT measure, higher_is_better FROM series", &[])
            .unwrap();
        assert!(rows.len() > 40, "{}", store.name);
        let mut seen = std::collections::BTreeSet::new();
        for r in rows {
            let (measure, hib) = (r.string(0).unwrap(), r.bool(1).unwrap());
            let Some(key) = Key::parse(&measure) else {
                // A technique's own check (adaptive shading's `shading-rate`): not a measure of
                // the table, stored with its record's direction.
                let record = checks
                    .get(measure.as_str())
                    .unwrap_or_else(|| panic!("{}: series {measure} is not a measure", store.name));
                assert_eq!(hib, *record, "{}: {measure}", store.name);
                seen.insert(measure.clone());
                continue;
            };
            assert_eq!(key.render(), measure);
            assert_eq!(
                hib,
                key.measure.direction().higher_is_better(),
                "{}: {measure}",
                store.name
            );
            seen.insert(key.measure.name().to_string());
        }
        for m in [
            "gpu_ms",
            "speedup",
            "psnr",
            "flip",
            "tde",
            "allocated_bytes",
        ] {
            assert!(seen.contains(m), "{}: no {m} series", store.name);
        }
    }
}

/// A store of the schema before compact storage (version 8: records as JSON text, points and
/// images with row ids) migrates: its records, points and images read back as they were stored,
/// and runs stored after the migration sit beside them in one series.
#[test]
fn a_store_of_the_previous_schema_migrates_to_compact_storage() {
    let test = "a_store_of_the_previous_schema_migrates_to_compact_storage";
    for store in std::iter::once(common::sqlite_at(8)).chain(common::postgres_at(test, 8)) {
        migrates_to_compact_storage(&store);
    }
}

fn migrates_to_compact_storage(store: &common::TestStore) {
    let old = tessera_dashboard::bundle::RunBundle::read_folder(
        &std::fs::read_dir(common::fixtures())
            .unwrap()
            .map(|e| e.unwrap().path())
            .min()
            .unwrap(),
    )
    .unwrap();
    let record = serde_json::to_string(&old.scenarios[0]).unwrap();
    let series = {
        let mut c = store.pool.get().unwrap();
        let mut id = |sql: &str, params: &[Value]| c.query(sql, params).unwrap()[0].i64(0).unwrap();
        let adapter = id(
            "INSERT INTO adapters (name, vendor, device, device_type, backend)
             VALUES ('llvmpipe (LLVM 15.0.6, 256 bits)', 65541, 0, 'cpu', 'vulkan') RETURNING id",
            &[],
        );
        let run = id(
            "INSERT INTO runs (run_id, dirty, started_at, status, harness_version, adapter_id, driver,
                 driver_info, hostname, n_ok, n_skipped, n_failed, run_json, imported_at, commit_time)
             VALUES ('old-run', 0, '2026-11-01T00:00:00Z', 'complete', '0.1.0', $1, 'llvmpipe', 'Mesa',
                 'h', 1, 0, 0, $2, '2026-11-01T00:00:00Z', '2026-11-01T00:00:00Z') RETURNING id",
            &[Value::Int(adapter), serde_json::to_string(&old.run).unwrap().into()],
        );
        id(
            "INSERT INTO scenario_results (run_pk, scenario, width, height, wall_ms, record_json)
             VALUES ($1, $2, 32, 24, 1.0, $3) RETURNING id",
            &[
                Value::Int(run),
                old.scenarios[0].scenario.as_str().into(),
                record.as_str().into(),
            ],
        );
        let series = id(
            "INSERT INTO series (scenario, variant, adapter_id, measure, higher_is_better)
             VALUES ('tiny', 'native', $1, 'gpu_ms.median', 0) RETURNING id",
            &[Value::Int(adapter)],
        );
        // A run stored later whose commit is older: commit order is not row order.
        let early = id(
            "INSERT INTO runs (run_id, dirty, started_at, status, harness_version, adapter_id, driver,
                 driver_info, hostname, n_ok, n_skipped, n_failed, run_json, imported_at, commit_time)
             VALUES ('old-early', 0, '2026-11-02T00:00:00Z', 'complete', '0.1.0', $1, 'llvmpipe', 'Mesa',
                 'h', 1, 0, 0, $2, '2026-11-02T00:00:00Z', '2026-10-01T00:00:00Z') RETURNING id",
            &[Value::Int(adapter), serde_json::to_string(&old.run).unwrap().into()],
        );
        c.execute(
            "INSERT INTO points (series_id, run_pk, value, ord)
             VALUES ($1, $2, 2.5, '2026-11-01T00:00:00Z 2026-11-01T00:00:00Z')",
            &[Value::Int(series), Value::Int(run)],
        )
        .unwrap();
        c.execute(
            "INSERT INTO points (series_id, run_pk, value, ord)
             VALUES ($1, $2, 2.0, '2026-10-01T00:00:00Z 2026-11-02T00:00:00Z')",
            &[Value::Int(series), Value::Int(early)],
        )
        .unwrap();
        c.execute(
            "INSERT INTO blobs (digest, bytes) VALUES ('d1', $1)",
            &[Value::Blob(vec![0])],
        )
        .unwrap();
        c.execute(
            "INSERT INTO images (run_pk, scenario, variant, frame, kind, digest)
             VALUES ($1, 'tiny', 'native', 0, 'output', 'd1')",
            &[Value::Int(run)],
        )
        .unwrap();
        series
    };
    let pool = tessera_dashboard::db::open(&store.url).unwrap();
    let mut c = pool.get().unwrap();
    assert_eq!(
        tessera_dashboard::db::current_version(&mut *c).unwrap(),
        tessera_dashboard::db::known_version()
    );
    // The old record reads back from its JSON text, the new one from its deflated column.
    let detail = read::run(&mut *c, "old-run").unwrap();
    assert_eq!(serde_json::to_string(&detail.scenarios[0]).unwrap(), record);
    assert_eq!(detail.images.len(), 1);
    assert_eq!(detail.images[0].digest, "d1");
    let mut run = old.clone();
    run.run.run_id = "new-run".into();
    run.run.started_at = "2026-12-01T00:00:00Z".into();
    run.run.commit_time = Some("2026-12-01T00:00:00Z".into());
    assert!(matches!(
        ingest(&mut *c, &run).unwrap(),
        Ingested::Stored { .. }
    ));
    assert_eq!(
        serde_json::to_string(&read::run(&mut *c, "new-run").unwrap().scenarios).unwrap(),
        serde_json::to_string(&run.scenarios).unwrap()
    );
    let (stored_json, stored_z): (String, Option<Vec<u8>>) = {
        let r = &c
            .query(
                "SELECT s.record_json, s.record_z FROM scenario_results s JOIN runs r ON r.id = s.run_pk
                 WHERE r.run_id = 'new-run'",
                &[],
            )
            .unwrap()[0];
        (
            r.string(0).unwrap(),
            r.opt_blob(1).unwrap().map(<[u8]>::to_vec),
        )
    };
    assert_eq!(stored_json, "");
    assert!(stored_z.unwrap().len() < record.len());
    // Old and new points of the series, in commit order.
    let pts = tessera_dashboard::store::series::points(&mut *c, series).unwrap();
    let runs: Vec<&str> = pts.iter().map(|p| p.run_id.as_str()).collect();
    assert_eq!(runs, ["old-early", "old-run", "new-run"]);
    assert_eq!(pts[0].value, 2.0);
    assert_eq!(pts[1].value, 2.5);
    // The order is stored as one integer per point (schema step 11), the old text converted.
    let ords: Vec<i64> = c
        .query(
            "SELECT ord FROM points WHERE series_id = $1 ORDER BY ord",
            &[Value::Int(series)],
        )
        .unwrap()
        .iter()
        .map(|r| r.i64(0).unwrap())
        .collect();
    let at = |t: &str| tessera_dashboard::store::ingest::epoch_seconds(t);
    assert_eq!(
        ords[..2],
        [
            tessera_dashboard::store::ingest::pack_order(
                at("2026-10-01T00:00:00Z"),
                at("2026-11-02T00:00:00Z")
            ),
            tessera_dashboard::store::ingest::pack_order(
                at("2026-11-01T00:00:00Z"),
                at("2026-11-01T00:00:00Z")
            ),
        ]
    );
    // The same upload again is recognised as stored (its deflated record compared as text).
    assert!(matches!(
        ingest(&mut *c, &run).unwrap(),
        Ingested::AlreadyStored { .. }
    ));
}
