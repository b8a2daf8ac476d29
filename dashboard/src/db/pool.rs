//! A small blocking connection pool: connections are made on demand up to a maximum and handed
//! back on drop. Not for: async use (the server calls it from `spawn_blocking`).

use std::ops::{Deref, DerefMut};
use std::sync::{Arc, Condvar, Mutex};

use super::{Connection, DbError, Factory};

struct Inner {
    factory: Box<dyn Factory>,
    idle: Mutex<(Vec<Box<dyn Connection>>, usize)>,
    returned: Condvar,
    max: usize,
}

/// Cheap to clone; all clones share the connections.
#[derive(Clone)]
pub struct Pool {
    inner: Arc<Inner>,
}

impl Pool {
    pub(super) fn new(factory: Box<dyn Factory>) -> Pool {
        let desc = factory.describe();
        let max = if desc == "SQLite :memory:" { 1 } else { 8 };
        Pool {
            inner: Arc::new(Inner {
                factory,
                idle: Mutex::new((Vec::new(), 0)),
                returned: Condvar::new(),
                max,
            }),
        }
    }

    /// How the store is named in logs, without passwords.
    pub fn describe(&self) -> String {
        self.inner.factory.describe()
    }

    /// An idle connection, a new one while fewer than the maximum exist, or else waits for one.
    pub fn get(&self) -> Result<PooledConnection, DbError> {
        let mut guard = self.inner.idle.lock().unwrap_or_else(|e| e.into_inner());
        loop {
            if let Some(conn) = guard.0.pop() {
                return Ok(PooledConnection {
                    conn: Some(conn),
                    pool: self.clone(),
                });
            }
            if guard.1 < self.inner.max {
                guard.1 += 1;
                drop(guard);
                return match self.inner.factory.connect() {
                    Ok(conn) => Ok(PooledConnection {
                        conn: Some(conn),
                        pool: self.clone(),
                    }),
                    Err(e) => {
                        self.inner.idle.lock().unwrap_or_else(|e| e.into_inner()).1 -= 1;
                        self.inner.returned.notify_one();
                        Err(e)
                    }
                };
            }
            guard = self
                .inner
                .returned
                .wait(guard)
                .unwrap_or_else(|e| e.into_inner());
        }
    }
}

/// A connection borrowed from a [`Pool`]; goes back to it when dropped.
pub struct PooledConnection {
    conn: Option<Box<dyn Connection>>,
    pool: Pool,
}

impl Deref for PooledConnection {
    type Target = dyn Connection;
    fn deref(&self) -> &Self::Target {
        &**self.conn.as_ref().expect("connection present until drop")
    }
}

impl DerefMut for PooledConnection {
    fn deref_mut(&mut self) -> &mut Self::Target {
        &mut **self.conn.as_mut().expect("connection present until drop")
    }
}

impl Drop for PooledConnection {
    fn drop(&mut self) {
        if let Some(conn) = self.conn.take() {
            let mut guard = self
                .pool
                .inner
                .idle
                .lock()
                .unwrap_or_else(|e| e.into_inner());
            // A connection dropped by a panic may be inside a transaction: close it instead.
            if std::thread::panicking() {
                guard.1 -= 1;
                drop(conn);
            } else {
                guard.0.push(conn);
            }
            drop(guard);
            self.pool.inner.returned.notify_one();
        }
    }
}
