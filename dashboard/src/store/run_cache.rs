//! Decoded runs kept in memory by the server: a nightly run's 340 records are 6.5 MB of JSON that
//! take about 70 ms of CPU to inflate and parse, and the noise of its 1,500 frame-time series
//! about 55 ms of queries (measured on the 2.72-million-result store); the two-run comparison
//! needs both runs' records and B's noise, and the same few runs (last night's and the one
//! before) are what everyone opens the morning after.
//!
//! Each entry is checked against the store on every use: records by a digest of the stored
//! (deflated) bytes they were decoded from, read again each time (a millisecond), so a run
//! deleted and stored again under the same row id is decoded anew; noise by a stamp of the whole
//! `runs` table (its row count, newest id and newest import time: noise reads the points of
//! earlier runs, which change only when a run is stored or deleted; a run deleted and another
//! stored with its row id in the same second, before the run whose noise is kept, is the one
//! change it does not see). At most [`CAPACITY`] runs of each are kept, the least recently used
//! dropped first.
//!
//! Not for: decoding ([`super::records`]) or estimating noise ([`super::noise`]).

use std::collections::{BTreeMap, VecDeque};
use std::hash::{Hash, Hasher};
use std::sync::{Arc, Mutex};

use tessera_results::ScenarioResult;

use super::{noise, read, records, StoreError};
use crate::db::{Connection, Row, Value};

/// Runs kept, of records and of noise each.
pub const CAPACITY: usize = 4;

/// Relative frame-time noise per scenario and variant ([`noise::frame_time_noise`]).
pub type Noise = BTreeMap<String, BTreeMap<String, f64>>;

/// What a run's records were decoded from: its row id, the number of its record rows and a
/// digest of their stored bytes.
type RecordsKey = (i64, usize, u64);

/// The `runs` table's row count, newest id and newest import time.
type Stamp = (i64, i64, String);

/// The cache; one per server, shared by its requests.
#[derive(Default)]
pub struct RunCache {
    inner: Mutex<Inner>,
}

#[derive(Default)]
struct Inner {
    records: VecDeque<(RecordsKey, Arc<Vec<ScenarioResult>>)>,
    noise: VecDeque<((String, Stamp), Arc<Noise>)>,
}

/// Looks `key` up in `list`, moving a hit to the front.
fn hit<K: PartialEq, V: Clone>(list: &mut VecDeque<(K, V)>, key: &K) -> Option<V> {
    let at = list.iter().position(|(k, _)| k == key)?;
    let entry = list.remove(at).expect("found above");
    let value = entry.1.clone();
    list.push_front(entry);
    Some(value)
}

/// Puts `value` at the front of `list` under `key`, dropping the older entry of the same run
/// (`same`) and the least recently used beyond [`CAPACITY`].
fn put<K, V>(list: &mut VecDeque<(K, V)>, key: K, value: V, same: impl Fn(&K) -> bool) {
    list.retain(|(k, _)| !same(k));
    list.push_front((key, value));
    list.truncate(CAPACITY);
}

impl RunCache {
    /// The records of the run with row id `pk`, in scenario order ([`read::scenarios_of`]).
    pub fn records(
        &self,
        conn: &mut dyn Connection,
        pk: i64,
    ) -> Result<Arc<Vec<ScenarioResult>>, StoreError> {
        let rows = read::record_rows(conn, pk)?;
        let key = (pk, rows.len(), digest(&rows));
        if let Some(v) = hit(&mut self.lock().records, &key) {
            return Ok(v);
        }
        let v = Arc::new(records::decode_all(&rows, 0)?);
        put(&mut self.lock().records, key, v.clone(), |k| k.0 == pk);
        Ok(v)
    }

    /// The frame-time noise of run `run_id`'s series ([`noise::frame_time_noise`]).
    pub fn noise(&self, conn: &mut dyn Connection, run_id: &str) -> Result<Arc<Noise>, StoreError> {
        let key = (run_id.to_string(), stamp(conn)?);
        if let Some(v) = hit(&mut self.lock().noise, &key) {
            return Ok(v);
        }
        let v = Arc::new(noise::frame_time_noise(conn, run_id)?);
        put(&mut self.lock().noise, key, v.clone(), |k| k.0 == run_id);
        Ok(v)
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Inner> {
        // A panic while holding the lock leaves whole entries only: the cache stays usable.
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// A digest of the rows' stored records (their deflated bytes: about 4.5 KB a scenario, a
/// millisecond for a nightly run, where decoding them takes seventy).
fn digest(rows: &[Row]) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    for r in rows {
        for v in &r.0 {
            match v {
                Value::Blob(b) => b.hash(&mut h),
                Value::Text(t) => t.hash(&mut h),
                Value::Null => 0u8.hash(&mut h),
                Value::Int(i) => i.hash(&mut h),
                Value::Real(x) => x.to_bits().hash(&mut h),
            }
        }
    }
    h.finish()
}

fn stamp(conn: &mut dyn Connection) -> Result<Stamp, StoreError> {
    let r = conn.query(
        "SELECT COUNT(*), COALESCE(MAX(id), 0), COALESCE(MAX(imported_at), '') FROM runs",
        &[],
    )?;
    Ok((r[0].i64(0)?, r[0].i64(1)?, r[0].string(2)?))
}
