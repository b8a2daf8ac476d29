//! The SQLite implementation of [`Connection`]: an embedded file, the default store.
//!
//! Each connection runs in WAL mode with a busy timeout, so readers never wait for a writer and
//! concurrent writers queue. Not for: PostgreSQL specifics, schema (see `migrations.rs`).

use rusqlite::types::{ToSqlOutput, ValueRef};

use super::{Backend, Connection, DbError, Factory as FactoryTrait, Row, Value};

pub struct Factory {
    path: String,
}

impl Factory {
    pub fn new(path: &str) -> Factory {
        Factory {
            path: path.to_string(),
        }
    }
}

impl FactoryTrait for Factory {
    fn connect(&self) -> Result<Box<dyn Connection>, DbError> {
        let open_err = |source| DbError::OpenSqlite {
            path: self.path.clone(),
            source,
        };
        let conn = rusqlite::Connection::open(&self.path).map_err(open_err)?;
        conn.busy_timeout(std::time::Duration::from_secs(30))
            .map_err(open_err)?;
        if self.path != ":memory:" {
            conn.pragma_update(None, "journal_mode", "WAL")
                .map_err(open_err)?;
            conn.pragma_update(None, "synchronous", "NORMAL")
                .map_err(open_err)?;
            // A large store: its B-tree pages read through a memory map and a 64 MiB page cache
            // per connection, not copied in from the file on every read (an upload touches the
            // newest points of thousands of series).
            conn.pragma_update(None, "mmap_size", 1i64 << 32)
                .map_err(open_err)?;
            conn.pragma_update(None, "cache_size", -65536)
                .map_err(open_err)?;
        }
        conn.pragma_update(None, "foreign_keys", "ON")
            .map_err(open_err)?;
        conn.set_prepared_statement_cache_capacity(64);
        // The query planner stability guarantee: a cached statement keeps its plan whatever is
        // bound to it. Without it, this SQLite (built with STAT4) marks any statement whose
        // `LIMIT $n` or range bound is a parameter to be compiled again whenever the bound
        // value changes, so the per-series queries (a two-run comparison reads 1,700 series'
        // noise) were parsed and planned on every call: a fifth of that page's time.
        conn.set_db_config(
            rusqlite::config::DbConfig::SQLITE_DBCONFIG_ENABLE_QPSG,
            true,
        )
        .map_err(open_err)?;
        Ok(Box::new(SqliteConnection { conn }))
    }

    fn describe(&self) -> String {
        format!("SQLite {}", self.path)
    }
}

pub struct SqliteConnection {
    conn: rusqlite::Connection,
}

/// `$1` → `?1`: SQLite's numbered placeholders, so that one SQL text serves both backends.
/// Placeholders inside single-quoted literals are left alone.
pub fn rewrite_placeholders(sql: &str) -> String {
    let mut out = String::with_capacity(sql.len());
    let mut in_literal = false;
    let mut chars = sql.chars().peekable();
    while let Some(c) = chars.next() {
        if c == '\'' {
            in_literal = !in_literal;
        }
        if c == '$' && !in_literal && chars.peek().is_some_and(|d| d.is_ascii_digit()) {
            out.push('?');
        } else {
            out.push(c);
        }
    }
    out
}

impl rusqlite::ToSql for Value {
    fn to_sql(&self) -> rusqlite::Result<ToSqlOutput<'_>> {
        Ok(match self {
            Value::Null => ToSqlOutput::Borrowed(ValueRef::Null),
            Value::Int(v) => ToSqlOutput::Borrowed(ValueRef::Integer(*v)),
            Value::Real(v) => ToSqlOutput::Borrowed(ValueRef::Real(*v)),
            Value::Text(v) => ToSqlOutput::Borrowed(ValueRef::Text(v.as_bytes())),
            Value::Blob(v) => ToSqlOutput::Borrowed(ValueRef::Blob(v)),
        })
    }
}

fn from_ref(v: ValueRef<'_>) -> Value {
    match v {
        ValueRef::Null => Value::Null,
        ValueRef::Integer(i) => Value::Int(i),
        ValueRef::Real(r) => Value::Real(r),
        ValueRef::Text(t) => Value::Text(String::from_utf8_lossy(t).into_owned()),
        ValueRef::Blob(b) => Value::Blob(b.to_vec()),
    }
}

impl Connection for SqliteConnection {
    fn backend(&self) -> Backend {
        Backend::Sqlite
    }

    fn execute(&mut self, sql: &str, params: &[Value]) -> Result<u64, DbError> {
        let mut stmt = self.conn.prepare_cached(&rewrite_placeholders(sql))?;
        Ok(stmt.execute(rusqlite::params_from_iter(params.iter()))? as u64)
    }

    fn query(&mut self, sql: &str, params: &[Value]) -> Result<Vec<Row>, DbError> {
        let mut stmt = self.conn.prepare_cached(&rewrite_placeholders(sql))?;
        let columns = stmt.column_count();
        let mut rows = stmt.query(rusqlite::params_from_iter(params.iter()))?;
        let mut out = Vec::new();
        while let Some(row) = rows.next()? {
            let mut values = Vec::with_capacity(columns);
            for i in 0..columns {
                values.push(from_ref(row.get_ref(i)?));
            }
            out.push(Row(values));
        }
        Ok(out)
    }

    fn batch(&mut self, sql: &str) -> Result<(), DbError> {
        Ok(self.conn.execute_batch(sql)?)
    }
}
