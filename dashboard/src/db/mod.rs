//! The results store: a `Connection` trait with a SQLite and a PostgreSQL implementation, a small
//! pool, and the migrations of each backend.
//!
//! This module knows how to talk to a database and nothing about Tessera's records: the queries
//! that read and write runs live in [`crate::store`], written once against this trait (with `$1`
//! placeholders, rewritten for SQLite). The schema is documented in `schema.md` beside this file.
//! Not for: HTTP, HTML, record validation.

mod migrations;
mod pool;
mod postgres;
mod sqlite;
mod value;

pub use migrations::{current_version, known_version};
pub use pool::{Pool, PooledConnection};
pub use value::{Row, Value};

/// Which database a connection talks to; only migrations and a few statements differ.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    Sqlite,
    Postgres,
}

/// Errors from the database layer. The message says what failed; the source has the driver's words.
#[derive(Debug, thiserror::Error)]
pub enum DbError {
    #[error("cannot open the SQLite store {path}")]
    OpenSqlite {
        path: String,
        #[source]
        source: rusqlite::Error,
    },
    #[error("cannot connect to PostgreSQL at {url} (is the server running and the URL right?)")]
    ConnectPostgres {
        url: String,
        #[source]
        source: ::postgres::Error,
    },
    #[error("SQLite: {0}")]
    Sqlite(#[from] rusqlite::Error),
    #[error("PostgreSQL: {0}")]
    Postgres(#[from] ::postgres::Error),
    #[error("the store has schema version {found}, newer than this dashboard knows ({known}); upgrade tessera-dashboard")]
    SchemaTooNew { found: i64, known: i64 },
    #[error("unexpected column type in column {column}: {detail}")]
    Column { column: usize, detail: String },
}

impl DbError {
    /// A write conflict that a retry of the whole transaction resolves (PostgreSQL deadlock or
    /// serialization failure, SQLite busy after its timeout).
    pub fn is_retryable(&self) -> bool {
        match self {
            DbError::Postgres(e) => e.code().is_some_and(|c| {
                *c == ::postgres::error::SqlState::T_R_DEADLOCK_DETECTED
                    || *c == ::postgres::error::SqlState::T_R_SERIALIZATION_FAILURE
            }),
            DbError::Sqlite(rusqlite::Error::SqliteFailure(e, _)) => {
                e.code == rusqlite::ErrorCode::DatabaseBusy
            }
            _ => false,
        }
    }
}

/// One connection to the store. Statements use PostgreSQL's `$1, $2, ...` placeholders on both
/// backends, and parameters are always bound, never spliced into the SQL text.
pub trait Connection: Send {
    fn backend(&self) -> Backend;
    /// Runs one statement; returns the number of rows changed.
    fn execute(&mut self, sql: &str, params: &[Value]) -> Result<u64, DbError>;
    /// Runs one statement and returns all its rows.
    fn query(&mut self, sql: &str, params: &[Value]) -> Result<Vec<Row>, DbError>;
    /// Runs several statements without parameters (migrations, `BEGIN`, `COMMIT`).
    fn batch(&mut self, sql: &str) -> Result<(), DbError>;

    /// Runs one statement expected to return at most one row.
    fn query_opt(&mut self, sql: &str, params: &[Value]) -> Result<Option<Row>, DbError> {
        Ok(self.query(sql, params)?.into_iter().next())
    }
}

/// Runs `f` in a transaction: committed when `f` returns `Ok`, rolled back otherwise, so a failed
/// import leaves nothing behind. SQLite takes the write lock at `BEGIN` (`IMMEDIATE`) so that
/// concurrent writers queue instead of failing half-way.
pub fn transaction<T, E: From<DbError>>(
    conn: &mut dyn Connection,
    f: impl FnOnce(&mut dyn Connection) -> Result<T, E>,
) -> Result<T, E> {
    let begin = match conn.backend() {
        Backend::Sqlite => "BEGIN IMMEDIATE",
        Backend::Postgres => "BEGIN",
    };
    conn.batch(begin)?;
    match f(conn) {
        Ok(v) => {
            conn.batch("COMMIT")?;
            Ok(v)
        }
        Err(e) => {
            // The error that made us roll back is the one worth reporting.
            let _ = conn.batch("ROLLBACK");
            Err(e)
        }
    }
}

/// Runs `f` with SQLite's automatic checkpoint off on `conn`, then restores it: the commit of a
/// nightly run's upload dirties about 15,000 pages of `points` (one per series it adds a point
/// to), and the checkpoint that copies them from the write-ahead log into the store file took
/// 0.7 s of a 2.9 s upload on the 2.72-million-result store, holding the only writer. The caller
/// checkpoints afterwards ([`checkpoint`]), once the writer is free. PostgreSQL: `f` alone.
pub fn without_autocheckpoint<T>(
    conn: &mut dyn Connection,
    f: impl FnOnce(&mut dyn Connection) -> T,
) -> Result<T, DbError> {
    if conn.backend() != Backend::Sqlite {
        return Ok(f(conn));
    }
    let pages = conn.query("PRAGMA wal_autocheckpoint", &[])?[0].i64(0)?;
    conn.query("PRAGMA wal_autocheckpoint = 0", &[])?;
    let out = f(conn);
    conn.query(&format!("PRAGMA wal_autocheckpoint = {pages}"), &[])?;
    Ok(out)
}

/// Copies the write-ahead log into the SQLite store file as far as readers allow, waiting for
/// no one (`PASSIVE`); returns the log's frames and those copied. Nothing on PostgreSQL.
pub fn checkpoint(conn: &mut dyn Connection) -> Result<(i64, i64), DbError> {
    if conn.backend() != Backend::Sqlite {
        return Ok((0, 0));
    }
    let r = &conn.query("PRAGMA wal_checkpoint(PASSIVE)", &[])?[0];
    Ok((r.i64(1)?, r.i64(2)?))
}

/// Opens a pool on `url`: `postgres://...` or `postgresql://...` for PostgreSQL, anything else is
/// a SQLite file path (`sqlite://` prefix optional; `:memory:` for a throw-away store). Runs the
/// migrations before returning.
pub fn open(url: &str) -> Result<Pool, DbError> {
    open_at(url, known_version())
}

/// [`open`], migrating only up to schema version `version`: for tests of a later migration on a
/// store of an older schema.
pub fn open_at(url: &str, version: i64) -> Result<Pool, DbError> {
    let pool = if url.starts_with("postgres://") || url.starts_with("postgresql://") {
        Pool::new(Box::new(postgres::Factory::new(url)))
    } else {
        let path = url.strip_prefix("sqlite://").unwrap_or(url);
        Pool::new(Box::new(sqlite::Factory::new(path)))
    };
    let mut conn = pool.get()?;
    migrations::migrate_to(&mut *conn, version)?;
    Ok(pool)
}

/// Creates new connections for a [`Pool`].
pub trait Factory: Send + Sync {
    fn connect(&self) -> Result<Box<dyn Connection>, DbError>;
    /// How the store is named in logs and errors, without any password.
    fn describe(&self) -> String;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placeholders_are_rewritten_for_sqlite() {
        assert_eq!(
            sqlite::rewrite_placeholders("SELECT $1, $12 WHERE a = '$x'"),
            "SELECT ?1, ?12 WHERE a = '$x'"
        );
    }

    #[test]
    fn a_write_without_autocheckpoint_stays_in_the_log_until_checkpointed() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("store.sqlite");
        let pool = open(path.to_str().unwrap()).unwrap();
        let mut conn = pool.get().unwrap();
        conn.batch("CREATE TABLE t (x BLOB)").unwrap();
        // About 2,000 pages: twice what SQLite's automatic checkpoint lets the log hold.
        let write = |c: &mut dyn Connection| {
            transaction(c, |c| {
                for _ in 0..2000 {
                    c.execute(
                        "INSERT INTO t (x) VALUES ($1)",
                        &[Value::Blob(vec![7; 4000])],
                    )?;
                }
                Ok::<_, DbError>(())
            })
        };
        let size = || std::fs::metadata(&path).unwrap().len();
        let before = size();
        without_autocheckpoint(&mut *conn, write).unwrap().unwrap();
        let auto = conn.query("PRAGMA wal_autocheckpoint", &[]).unwrap()[0]
            .i64(0)
            .unwrap();
        assert_eq!(auto, 1000, "restored");
        // The 8 MB are in the log, not yet in the store file...
        assert!(size() < before + 1_000_000, "{before} {}", size());
        let (log, copied) = checkpoint(&mut *conn).unwrap();
        assert!(log > 2000 && copied == log, "{log} {copied}");
        // ...until the checkpoint copies them.
        let after = size();
        assert!(after > before + 8_000_000, "{before} {after}");
        // With the automatic checkpoint on, the commit copied the log itself.
        write(&mut *conn).unwrap();
        assert!(size() > after + 8_000_000, "{after} {}", size());
    }

    #[test]
    fn rolled_back_transaction_leaves_nothing() {
        let pool = open(":memory:").unwrap();
        let mut conn = pool.get().unwrap();
        conn.batch("CREATE TABLE t (x BIGINT)").unwrap();
        let r: Result<(), DbError> = transaction(&mut *conn, |c| {
            c.execute("INSERT INTO t (x) VALUES ($1)", &[Value::Int(1)])?;
            Err(DbError::Column {
                column: 0,
                detail: "test".into(),
            })
        });
        assert!(r.is_err());
        let n = conn.query("SELECT COUNT(*) FROM t", &[]).unwrap()[0]
            .i64(0)
            .unwrap();
        assert_eq!(n, 0);
    }
}
