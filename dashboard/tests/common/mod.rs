//! Shared test helpers: the committed fixture runs, and stores to test against: a temporary SQLite
//! file always, and PostgreSQL when `TESSERA_TEST_POSTGRES_URL` is set (each test in a schema of
//! its own, dropped afterwards). Without the URL the PostgreSQL half says it was skipped.
#![allow(dead_code)]

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

use tessera_dashboard::bundle::RunBundle;
use tessera_dashboard::db::{self, Pool};

pub fn fixtures() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/runs")
}

/// The first fixture run (two real lavapipe runs of a 32x24 scenario are committed).
pub fn template() -> RunBundle {
    let first = std::fs::read_dir(fixtures())
        .unwrap()
        .map(|e| e.unwrap().path())
        .min()
        .unwrap();
    RunBundle::read_folder(&first).unwrap()
}

pub struct TestStore {
    pub name: &'static str,
    pub pool: Pool,
    /// What `db::open` takes to open the store again.
    pub url: String,
    _dir: Option<tempfile::TempDir>,
    pg_schema: Option<(String, String)>,
}

impl Drop for TestStore {
    fn drop(&mut self) {
        if let Some((url, schema)) = &self.pg_schema {
            if let Ok(mut c) = postgres::Client::connect(url, postgres::NoTls) {
                let _ = c.batch_execute(&format!("DROP SCHEMA {schema} CASCADE"));
            }
        }
    }
}

pub fn sqlite() -> TestStore {
    sqlite_at(db::known_version())
}

/// A SQLite store migrated up to schema `version` only.
pub fn sqlite_at(version: i64) -> TestStore {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("store.sqlite");
    let url = path.to_str().unwrap().to_string();
    let pool = db::open_at(&url, version).unwrap();
    TestStore {
        name: "sqlite",
        pool,
        url,
        _dir: Some(dir),
        pg_schema: None,
    }
}

pub fn postgres(test: &str) -> Option<TestStore> {
    postgres_at(test, db::known_version())
}

/// A PostgreSQL store (a schema of its own) migrated up to schema `version` only.
pub fn postgres_at(test: &str, version: i64) -> Option<TestStore> {
    let Ok(url) = std::env::var("TESSERA_TEST_POSTGRES_URL") else {
        eprintln!("{test}: skipped PostgreSQL: TESSERA_TEST_POSTGRES_URL is not set (dashboard/ci/setup-postgres.sh prints it)");
        return None;
    };
    static N: AtomicUsize = AtomicUsize::new(0);
    let schema = format!(
        "t_{}_{}_{}",
        std::process::id(),
        N.fetch_add(1, Ordering::SeqCst),
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap()
            .subsec_nanos()
    );
    let mut c = postgres::Client::connect(&url, postgres::NoTls)
        .expect("TESSERA_TEST_POSTGRES_URL is set but unreachable");
    c.batch_execute(&format!("CREATE SCHEMA {schema}")).unwrap();
    let sep = if url.contains('?') { '&' } else { '?' };
    let scoped = format!("{url}{sep}options=-csearch_path%3D{schema}");
    let pool = db::open_at(&scoped, version).unwrap();
    Some(TestStore {
        name: "postgres",
        pool,
        url: scoped,
        _dir: None,
        pg_schema: Some((url, schema)),
    })
}

/// SQLite, and PostgreSQL when configured.
pub fn stores(test: &str) -> Vec<TestStore> {
    let mut v = vec![sqlite()];
    v.extend(postgres(test));
    v
}

/// The second adapter of [`two_adapter_history`].
pub const SECOND: &str = "llvmpipe (second adapter, derived from a real run)";

/// The commit of run `i` of generated histories (`synth::run_from`).
pub fn sha(i: u64) -> String {
    format!("{:040x}", i + 1)
}

/// The alert group key of the change between runs `before` and `before + 1`.
pub fn range(before: u64) -> String {
    format!("{}..{}", sha(before), sha(before + 1))
}

/// Stores runs `from..to` of a two-adapter history, then runs detection: 40 runs per adapter at
/// the same commits (`sha(i)`); on the first adapter every GPU time steps by +25% at run 15 and
/// +10% at run 30, on the second (named [`SECOND`]) by +10% at run 30 only. So the commit range
/// `range(29)` is one alert group on two adapters, `range(14)` one on the first adapter.
pub fn two_adapter_history(pool: &tessera_dashboard::db::Pool, from: u64, to: u64) {
    let template = template();
    let mut rng = tessera_dashboard::detect::Rng::new(11 + from);
    let mut c = pool.get().unwrap();
    for i in from..to {
        let a = match i {
            0..15 => 1.0,
            15..30 => 1.25,
            _ => 1.25 * 1.10,
        };
        let b = if i < 30 { 0.8 } else { 0.8 * 1.10 };
        tessera_dashboard::store::ingest::ingest(
            &mut *c,
            &tessera_dashboard::synth::run_from(&template, "a", i, a, 0.01, &mut rng),
        )
        .unwrap();
        let mut second = tessera_dashboard::synth::run_from(&template, "b", i, b, 0.01, &mut rng);
        second.run.adapter.name = SECOND.into();
        tessera_dashboard::store::ingest::ingest(&mut *c, &second).unwrap();
    }
    let all = tessera_dashboard::regressions::all_series(&mut *c).unwrap();
    tessera_dashboard::regressions::update(
        &mut *c,
        &all,
        &tessera_dashboard::detect::Params::default(),
    )
    .unwrap();
}
