//! Generated runs for tests and the benchmark: copies of a template run with new run ids, start
//! times, commits and timings scaled by a factor with noise. Deterministic for a seed.
//!
//! Not for: anything a real run could be used for instead.

use tessera_results::Summary;

use crate::bundle::RunBundle;
use crate::detect::Rng;

/// RFC 3339 time `minutes` after 2026-01-01T00:00:00Z (valid for up to about a year of minutes).
pub fn time_after(minutes: u64) -> String {
    let (days, rem) = (minutes / 1440, minutes % 1440);
    let (month, day) = {
        const LENGTHS: [u64; 12] = [31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31];
        let mut d = days % 365;
        let mut m = 0;
        while d >= LENGTHS[m] {
            d -= LENGTHS[m];
            m += 1;
        }
        (m + 1, d + 1)
    };
    format!(
        "2026-{month:02}-{day:02}T{:02}:{:02}:00Z",
        rem / 60,
        rem % 60
    )
}

fn scale(s: &mut Summary, f: f64) {
    for v in [
        &mut s.median,
        &mut s.p5,
        &mut s.p95,
        &mut s.min,
        &mut s.max,
        &mut s.mean,
    ] {
        *v *= f;
    }
}

/// Run `index` made from `template`: run id `<prefix>-<index>`, start and commit time `index` minutes
/// after the epoch above, commit `c<index>`, and every GPU time multiplied by `factor · (1 + noise·N(0,1))`
/// (one draw per variant).
pub fn run_from(
    template: &RunBundle,
    prefix: &str,
    index: u64,
    factor: f64,
    noise: f64,
    rng: &mut Rng,
) -> RunBundle {
    let mut b = template.clone();
    let id = format!("{prefix}-{index:06}");
    b.run.run_id = id.clone();
    b.run.started_at = time_after(index);
    b.run.finished_at = Some(time_after(index));
    // A generated history is one commit per run, committed when its run starts: retention and
    // series order by commit time.
    b.run.commit_time = Some(time_after(index));
    b.run.commit = Some(tessera_results::CommitInfo {
        sha: format!("{:040x}", index + 1),
        dirty: false,
    });
    for s in &mut b.scenarios {
        s.run_id = id.clone();
        for v in &mut s.results {
            let f = factor * (1.0 + noise * rng.normal());
            if let Some(g) = v.gpu_frame_ms.as_mut() {
                scale(g, f);
            }
            for p in &mut v.passes {
                if let Some(g) = p.gpu_ms.as_mut() {
                    scale(g, f);
                }
                p.samples_ms.iter_mut().for_each(|x| *x *= f);
            }
        }
    }
    b
}

/// `template` with its scenarios repeated `copies` times under names `<scenario>-<k>`, to make
/// runs with many results for the benchmark.
pub fn widen(template: &RunBundle, copies: usize) -> RunBundle {
    let mut b = template.clone();
    b.scenarios = (0..copies)
        .flat_map(|k| {
            template.scenarios.iter().map(move |s| {
                let mut s = s.clone();
                s.scenario = format!("{}-{k:03}", s.scenario);
                s
            })
        })
        .collect();
    b
}

#[cfg(test)]
mod tests {
    #[test]
    fn times_are_valid_rfc3339() {
        assert_eq!(super::time_after(0), "2026-01-01T00:00:00Z");
        assert_eq!(super::time_after(1440 * 31 + 61), "2026-02-01T01:01:00Z");
    }
}
