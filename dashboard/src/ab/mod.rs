//! A/B: two environments (a commit plus environment variables) run back to back on one runner,
//! in a shuffled order, N attempts each, compared per measure with a paired test (Wilcoxon
//! signed-rank) and the Hodges-Lehmann size of the change with its interval.
//!
//! An A/B is one job of kind `ab` per label: its order holds N pairs, each `[A, B]` or `[B, A]`
//! at random, and the runner sends one sample per run. Pair i of the comparison is the two
//! samples of the i-th pair. Besides the measures of the result (`gpu_ms.median`, `psnr`,
//! `flip`, `cvvdp` (JOD), ...) every sample gives `frames_changed`: 1 when its frames' digest differs
//! from the first A attempt's, else 0, so "the frames changed" is tested like any other measure.
//!
//! Not for: HTTP (see `server/ab.rs`), the queue's SQL (see [`crate::store::queue`]), bisection
//! decisions (see [`bisect`]).

pub mod bisect;

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use tessera_results::queue::{Arm, JobKind, JobSpec, Sample};
use tessera_results::stats::signed_rank::{wilcoxon_signed_rank, Paired};

use crate::store::StoreError;

/// Significance level of an A/B's verdicts; intervals are at 1 - `ALPHA`.
pub const ALPHA: f64 = 0.05;
/// Attempts of each arm when none are asked for (Pinpoint starts with 30; lavapipe is slow).
pub const DEFAULT_ATTEMPTS: usize = 10;
/// Most attempts of each arm one A/B may ask for.
pub const MAX_ATTEMPTS: usize = 100;
/// The measure that says whether the frames changed.
pub const FRAMES_CHANGED: &str = "frames_changed";

/// `COMMIT [KEY=VALUE ...]`: an environment as the command line writes it.
pub fn parse_env(name: &str, text: &str) -> Result<Arm, StoreError> {
    let mut words = text.split_whitespace();
    let commit = words
        .next()
        .ok_or_else(|| StoreError::Invalid(format!("--{name}: give COMMIT [KEY=VALUE ...]")))?;
    let mut env = BTreeMap::new();
    for w in words {
        let (k, v) = w.split_once('=').ok_or_else(|| {
            StoreError::Invalid(format!(
                "--{name}: {w:?} is not KEY=VALUE (the environment is COMMIT [KEY=VALUE ...])"
            ))
        })?;
        env.insert(k.to_string(), v.to_string());
    }
    Ok(Arm {
        name: name.to_string(),
        commit: commit.to_string(),
        env,
    })
}

/// `attempts` pairs in a random order: each pair is `[0, 1]` or `[1, 0]`.
pub fn shuffled_pairs(attempts: usize) -> Result<Vec<usize>, StoreError> {
    let mut coin = vec![0u8; attempts];
    getrandom::getrandom(&mut coin)
        .map_err(|e| StoreError::Invalid(format!("no random source: {e}")))?;
    Ok(coin
        .iter()
        .flat_map(|c| if c & 1 == 0 { [0, 1] } else { [1, 0] })
        .collect())
}

/// The job spec of an A/B of `scenario` (and `variant`) between arms `a` and `b`.
pub fn spec(
    scenario: &str,
    variant: Option<&str>,
    a: Arm,
    b: Arm,
    attempts: usize,
    list_commits: Option<[String; 2]>,
) -> Result<JobSpec, StoreError> {
    if !(1..=MAX_ATTEMPTS).contains(&attempts) {
        return Err(StoreError::Invalid(format!(
            "attempts: 1 to {MAX_ATTEMPTS}, not {attempts}"
        )));
    }
    let spec = JobSpec {
        kind: JobKind::Ab,
        scenarios: vec![scenario.to_string()],
        variant: variant.map(str::to_string),
        arms: vec![a, b],
        order: shuffled_pairs(attempts)?,
        list_commits,
    };
    crate::store::queue::check_spec(&spec)?;
    Ok(spec)
}

/// One measure of an A/B.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    pub measure: String,
    pub a_median: f64,
    pub b_median: f64,
    /// Hodges-Lehmann B - A.
    pub estimate: f64,
    pub interval: Option<[f64; 2]>,
    /// `estimate` relative to A's median (`None` when that is 0).
    pub relative: Option<f64>,
    pub p: f64,
    pub pairs: usize,
    /// `changed` (p < ALPHA) or `no change`.
    pub verdict: String,
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        s[n / 2]
    } else {
        (s[n / 2 - 1] + s[n / 2]) / 2.0
    }
}

/// The per-measure table of an A/B from its samples, measures by name. Pairs missing a sample
/// or a measure on either side are left out of that measure.
pub fn table(samples: &[Sample]) -> Vec<Row> {
    let reference = samples
        .iter()
        .filter(|s| s.arm == 0)
        .min_by_key(|s| s.seq)
        .and_then(|s| s.frames_digest.clone());
    // pair index -> [A, B]
    let mut pairs: BTreeMap<usize, [Option<BTreeMap<String, f64>>; 2]> = BTreeMap::new();
    for s in samples.iter().filter(|s| s.arm < 2) {
        let mut m = s.measures.clone();
        if let (Some(r), Some(d)) = (&reference, &s.frames_digest) {
            m.insert(FRAMES_CHANGED.into(), f64::from(u8::from(r != d)));
        }
        pairs.entry(s.seq / 2).or_default()[s.arm] = Some(m);
    }
    let mut names: Vec<String> = pairs
        .values()
        .flat_map(|p| p.iter().flatten().flat_map(|m| m.keys().cloned()))
        .collect();
    names.sort();
    names.dedup();
    let mut rows = Vec::new();
    for name in names {
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for [pa, pb] in pairs.values() {
            if let (Some(x), Some(y)) = (
                pa.as_ref().and_then(|m| m.get(&name)),
                pb.as_ref().and_then(|m| m.get(&name)),
            ) {
                a.push(*x);
                b.push(*y);
            }
        }
        let Some(Paired {
            n,
            p,
            estimate,
            interval,
        }) = wilcoxon_signed_rank(&a, &b, ALPHA)
        else {
            continue;
        };
        let a_median = median(&a);
        rows.push(Row {
            measure: name,
            a_median,
            b_median: median(&b),
            estimate,
            interval,
            relative: (a_median != 0.0).then(|| estimate / a_median),
            p,
            pairs: n,
            verdict: if p < ALPHA { "changed" } else { "no change" }.into(),
        });
    }
    rows
}

/// The table as aligned text (the CLI's output).
pub fn text(rows: &[Row]) -> String {
    let mut out = format!(
        "{:<28} {:>12} {:>12} {:>12} {:>26} {:>8} {:>9}  verdict\n",
        "measure", "A median", "B median", "B - A", "interval (95%)", "rel", "p"
    );
    for r in rows {
        let interval = r
            .interval
            .map_or_else(|| "–".to_string(), |[l, h]| format!("[{l:.4}, {h:.4}]"));
        let rel = r
            .relative
            .map_or_else(|| "–".to_string(), |x| format!("{:+.2}%", x * 100.0));
        out.push_str(&format!(
            "{:<28} {:>12.4} {:>12.4} {:>12.4} {:>26} {:>8} {:>9.2e}  {}\n",
            r.measure, r.a_median, r.b_median, r.estimate, interval, rel, r.p, r.verdict
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(arm: usize, seq: usize, gpu: f64, digest: &str) -> Sample {
        Sample {
            arm,
            seq,
            measures: [("gpu_ms.median".to_string(), gpu)].into(),
            frames_digest: Some(digest.into()),
        }
    }

    #[test]
    fn a_slower_b_with_other_frames_is_changed_on_both_measures() {
        let mut samples = Vec::new();
        for i in 0..10 {
            let jitter = (i % 3) as f64 * 0.01;
            samples.push(sample(0, 2 * i, 1.0 + jitter, "aaa"));
            samples.push(sample(1, 2 * i + 1, 1.2 + jitter, "bbb"));
        }
        let rows = table(&samples);
        let names: Vec<&str> = rows.iter().map(|r| r.measure.as_str()).collect();
        assert_eq!(names, ["frames_changed", "gpu_ms.median"]);
        for r in &rows {
            assert_eq!(r.verdict, "changed", "{r:?}");
            // Ten positive differences: 2/1024 exactly without ties; frames_changed's ten tied
            // differences of 1 take the normal approximation, z = 27 / 8.70, p = 0.0019.
            assert!(r.p < 0.002, "{r:?}");
        }
        assert!((rows[1].estimate - 0.2).abs() < 1e-9);
        assert!((rows[1].relative.unwrap() - 0.2 / 1.01).abs() < 1e-9);
        assert_eq!(rows[0].estimate, 1.0);
    }

    #[test]
    fn the_same_environment_twice_reads_no_change() {
        let mut samples = Vec::new();
        for i in 0..10 {
            let (x, y) = (
                1.0 + (i % 4) as f64 * 0.01,
                1.0 + ((i + 1) % 4) as f64 * 0.01,
            );
            samples.push(sample(0, 2 * i, x, "aaa"));
            samples.push(sample(1, 2 * i + 1, y, "aaa"));
        }
        let rows = table(&samples);
        assert!(rows.iter().all(|r| r.verdict == "no change"), "{rows:?}");
        let [lo, hi] = rows[1].interval.unwrap();
        assert!(lo <= 0.0 && hi >= 0.0);
    }

    #[test]
    fn environments_parse_and_orders_are_pairs() {
        let a = parse_env("a", "abc1234 VK_ICD_FILENAMES=/x.json MESA=1").unwrap();
        assert_eq!(a.commit, "abc1234");
        assert_eq!(a.env.len(), 2);
        assert!(parse_env("b", "abc1234 NOVALUE").is_err());
        let order = shuffled_pairs(50).unwrap();
        assert_eq!(order.len(), 100);
        assert!(order.chunks(2).all(|p| p == [0, 1] || p == [1, 0]));
        assert!(spec("s.toml", None, a.clone(), a, 101, None).is_err());
    }
}
