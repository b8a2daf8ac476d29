//! A scenario's record as stored: the whole `ScenarioResult` JSON, deflated into
//! `scenario_results.record_z` (about a quarter of its size: most of a record is per-frame arrays
//! and names that repeat across its variants). Rows stored before the compact schema keep their
//! text in `record_json`; readers take whichever the row has.
//!
//! Not for: the measures a series reads (points, see [`super::series`]) or the per-result columns
//! (`results`), which stay rows.

use std::io::{Read, Write};

use flate2::read::DeflateDecoder;
use flate2::write::DeflateEncoder;
use flate2::Compression;
use tessera_results::ScenarioResult;

use super::StoreError;
use crate::db::Row;

/// The columns a reader selects, in this order, for [`text`] and [`decode`].
pub const COLUMNS: &str = "record_json, record_z";

/// A record's JSON text as stored (deflated).
pub fn encode(json: &str) -> Vec<u8> {
    let mut e = DeflateEncoder::new(Vec::new(), Compression::default());
    e.write_all(json.as_bytes()).expect("deflate into memory");
    e.finish().expect("deflate into memory")
}

/// The record's JSON text from the row's [`COLUMNS`] starting at column `at`.
pub fn text(r: &Row, at: usize) -> Result<String, StoreError> {
    let corrupt = |e: std::io::Error| StoreError::Corrupt(format!("scenario record: {e}"));
    match r.opt_blob(at + 1)? {
        Some(z) => {
            let mut s = String::new();
            DeflateDecoder::new(z)
                .read_to_string(&mut s)
                .map_err(corrupt)?;
            Ok(s)
        }
        None => Ok(r.string(at)?),
    }
}

/// The record from the row's [`COLUMNS`] starting at column `at`.
pub fn decode(r: &Row, at: usize) -> Result<ScenarioResult, StoreError> {
    serde_json::from_str(&text(r, at)?).map_err(|e| StoreError::Corrupt(e.to_string()))
}

/// Every row's record (columns [`COLUMNS`] from `at`), in row order. A nightly run holds
/// hundreds of records of several megabytes of JSON in all, so they are inflated and parsed on
/// as many threads as the machine has (at most 8), in contiguous chunks.
pub fn decode_all(rows: &[Row], at: usize) -> Result<Vec<ScenarioResult>, StoreError> {
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(8);
    if threads < 2 || rows.len() < 16 {
        return rows.iter().map(|r| decode(r, at)).collect();
    }
    let chunk = rows.len().div_ceil(threads);
    std::thread::scope(|scope| {
        let parts: Vec<_> = rows
            .chunks(chunk)
            .map(|part| {
                scope.spawn(move || {
                    part.iter()
                        .map(|r| decode(r, at))
                        .collect::<Result<Vec<_>, _>>()
                })
            })
            .collect();
        let mut out = Vec::with_capacity(rows.len());
        for p in parts {
            out.extend(p.join().expect("a record decoder panicked")?);
        }
        Ok(out)
    })
}

/// Per-frame GPU times as `results.frame_ms` stores them: little-endian f64s, in frame order.
pub fn encode_frames(frames: &[f64]) -> Vec<u8> {
    frames.iter().flat_map(|f| f.to_le_bytes()).collect()
}

/// The per-frame GPU times of a `results.frame_ms` value.
pub fn decode_frames(bytes: &[u8]) -> Result<Vec<f64>, StoreError> {
    if !bytes.len().is_multiple_of(8) {
        return Err(StoreError::Corrupt(format!(
            "frame times of {} bytes, not a whole number of f64s",
            bytes.len()
        )));
    }
    Ok(bytes
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deflated_records_read_back_and_are_smaller() {
        let json =
            include_str!("../../tests/fixtures/runs/20261122T030520Z-34ab2b4/scenarios/tiny.json");
        let s: ScenarioResult = serde_json::from_str(json).unwrap();
        let compact = serde_json::to_string(&s).unwrap();
        let z = encode(&compact);
        assert!(
            z.len() * 2 < compact.len(),
            "{} of {}",
            z.len(),
            compact.len()
        );
        let mut back = String::new();
        DeflateDecoder::new(&z[..])
            .read_to_string(&mut back)
            .unwrap();
        assert_eq!(back, compact);
    }

    #[test]
    fn records_decoded_on_threads_keep_row_order_and_report_a_corrupt_one() {
        let json =
            include_str!("../../tests/fixtures/runs/20261122T030520Z-34ab2b4/scenarios/tiny.json");
        let s: ScenarioResult = serde_json::from_str(json).unwrap();
        let rows: Vec<Row> = (0..40)
            .map(|i| {
                let mut r = s.clone();
                r.scenario = format!("s{i:02}");
                let text = serde_json::to_string(&r).unwrap();
                Row(vec![
                    crate::db::Value::Text(String::new()),
                    crate::db::Value::Blob(encode(&text)),
                ])
            })
            .collect();
        let back = decode_all(&rows, 0).unwrap();
        let names: Vec<String> = back.iter().map(|r| r.scenario.clone()).collect();
        let want: Vec<String> = (0..40).map(|i| format!("s{i:02}")).collect();
        assert_eq!(names, want);
        let mut torn = rows;
        torn[33] = Row(vec![
            crate::db::Value::Text(String::new()),
            crate::db::Value::Blob(vec![1, 2, 3]),
        ]);
        assert!(matches!(decode_all(&torn, 0), Err(StoreError::Corrupt(_))));
    }

    #[test]
    fn frame_times_read_back_exactly_and_a_torn_value_is_corrupt() {
        let frames = [1.25, 0.1 + 0.2, f64::MIN_POSITIVE, 1.0 / 3.0];
        let bytes = encode_frames(&frames);
        assert_eq!(bytes.len(), 32);
        assert_eq!(decode_frames(&bytes).unwrap(), frames);
        assert!(decode_frames(&[]).unwrap().is_empty());
        assert!(matches!(
            decode_frames(&bytes[..31]),
            Err(StoreError::Corrupt(_))
        ));
    }
}
