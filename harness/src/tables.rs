//! `tessera report RUN...`: the measured tables of the READMEs, regenerated from run folders.
//!
//! Per scenario and adapter: the adapter, its driver and the graphics clock the variants ran at,
//! then one row per variant: median GPU ms, speed-up against `native`, every metric against the
//! reference, on which quality metric's Pareto front (error against GPU ms) the variant lies, and
//! the run ids the row comes from. A README table is this output with its command beside it, so
//! a table can be checked by re-running the command on the same run folders.
//!
//! Several runs of one scenario on one adapter (repeats) make one table: a row's values are the
//! median of the runs' values, and its run ids list them all.
//!
//! A ground-truth scenario that measured its reference's own noise (`reference_noise`) prints it
//! under the table, and differences smaller than it are ties on the fronts
//! ([`tessera_results::ReferenceNoise::tied`]): a row is not dominated by one that is better
//! only by less than the noise, and a faster row at a tied value dominates.
//!
//! Values are those of `results.csv` (the same medians, the same `measure::speedup`), rounded for
//! print only. Not for: comparing two runs (`compare.rs`), pixel-bound regimes (`regimes.rs`),
//! history (the dashboard).

use std::collections::BTreeMap;
use std::fmt::Write as _;

use tessera_results::measure::{self, Direction, DEFAULT_BASELINE};
use tessera_results::{ReferenceNoise, ScenarioResult, Status, VariantResult};

use crate::compare::Run;

/// How `tessera report` prints.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// Aligned columns for a terminal.
    Text,
    /// GitHub Markdown, for a README.
    Md,
}

/// One scenario on one adapter, over the runs that hold it.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    pub scenario: String,
    pub width: u32,
    pub height: u32,
    pub reference: String,
    pub adapter: String,
    pub backend: String,
    pub driver: String,
    /// Graphics clock over every measured variant (min, median of medians, max), where recorded.
    pub clock_mhz: Option<(f64, f64, f64)>,
    /// Variants whose conditions flagged throttling.
    pub throttled: Vec<String>,
    /// Quality metrics against the reference, in first-seen order, with unit and direction.
    pub metrics: Vec<(String, String, Direction)>,
    pub rows: Vec<Row>,
    pub run_ids: Vec<String>,
    /// The reference's own noise (of the newest run that measured it): differences below it
    /// are ties.
    pub noise: Option<ReferenceNoise>,
}

/// One variant's row.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub variant: String,
    /// `ok`, `skipped` or `failed` (of the newest run holding it).
    pub status: String,
    pub gpu_ms: Option<f64>,
    pub speedup: Option<f64>,
    /// Per metric of [`Table::metrics`], in order.
    pub metrics: Vec<Option<f64>>,
    /// Names of the metrics whose front (against GPU ms) holds this variant.
    pub front: Vec<String>,
    pub run_ids: Vec<String>,
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    v.retain(|x| !x.is_nan());
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    })
}

/// A metric against the reference (not a technique's own check).
fn is_quality(m: &tessera_results::MetricRecord) -> bool {
    m.check.is_none()
}

/// (scenario, adapter, driver): what one table holds.
type TableKey = (String, String, String);

/// The tables of `runs`, one per (scenario, adapter, driver), in the order first met.
pub fn tables(runs: &[Run]) -> Vec<Table> {
    let mut groups: Vec<(TableKey, Vec<(&Run, &ScenarioResult)>)> = Vec::new();
    for run in runs {
        for s in &run.scenarios {
            let key = (
                s.scenario.clone(),
                run.info.adapter.name.clone(),
                run.info.adapter.driver_info.clone(),
            );
            match groups.iter_mut().find(|(k, _)| *k == key) {
                Some((_, v)) => v.push((run, s)),
                None => groups.push((key, vec![(run, s)])),
            }
        }
    }
    groups.into_iter().map(|(_, g)| table(&g)).collect()
}

fn table(group: &[(&Run, &ScenarioResult)]) -> Table {
    let (run0, s0) = group[0];
    let mut metrics: Vec<(String, String, Direction)> = Vec::new();
    let mut variants: Vec<String> = Vec::new();
    let (mut clock_min, mut clock_max, mut clock_medians) = (f64::INFINITY, 0.0f64, Vec::new());
    let mut throttled = Vec::new();
    for (_, s) in group {
        for r in &s.results {
            if !variants.contains(&r.variant) {
                variants.push(r.variant.clone());
            }
            for m in r.metrics.iter().filter(|m| is_quality(m)) {
                if !metrics.iter().any(|(n, _, _)| *n == m.name) {
                    metrics.push((
                        m.name.clone(),
                        measure::metric_unit(m).to_string(),
                        measure::metric_direction(m),
                    ));
                }
            }
            if let Some(c) = r.conditions.as_ref().and_then(|c| c.recorded()) {
                if let Some(g) = c.graphics_clock_mhz {
                    clock_min = clock_min.min(g.min);
                    clock_max = clock_max.max(g.max);
                    clock_medians.push(g.median);
                }
                if c.throttled && !throttled.contains(&r.variant) {
                    throttled.push(r.variant.clone());
                }
            }
        }
    }
    let clock_mhz = median(clock_medians).map(|m| (clock_min, m, clock_max));
    let noise = group
        .iter()
        .rev()
        .find_map(|(_, s)| s.reference_noise.clone());
    let mut rows: Vec<Row> = variants.iter().map(|v| row(group, v, &metrics)).collect();
    mark_fronts(&mut rows, &metrics, noise.as_ref());
    let mut run_ids: Vec<String> = Vec::new();
    for (run, _) in group {
        if !run_ids.contains(&run.info.run_id) {
            run_ids.push(run.info.run_id.clone());
        }
    }
    Table {
        scenario: s0.scenario.clone(),
        width: s0.width,
        height: s0.height,
        reference: s0.reference.clone(),
        adapter: run0.info.adapter.name.clone(),
        backend: run0.info.adapter.backend.clone(),
        driver: run0.info.adapter.driver_info.clone(),
        clock_mhz,
        throttled,
        metrics,
        rows,
        run_ids,
        noise,
    }
}

fn row(
    group: &[(&Run, &ScenarioResult)],
    variant: &str,
    metrics: &[(String, String, Direction)],
) -> Row {
    let mut found: Vec<(&Run, &ScenarioResult, &VariantResult)> = Vec::new();
    for (run, s) in group {
        if let Some(r) = s.results.iter().find(|r| r.variant == variant) {
            found.push((run, s, r));
        }
    }
    let ok: Vec<_> = found
        .iter()
        .filter(|(_, _, r)| r.status == Status::Ok)
        .collect();
    let gpu_ms = median(
        ok.iter()
            .filter_map(|(_, _, r)| r.gpu_frame_ms.map(|t| t.median))
            .collect(),
    );
    let speedup = median(
        ok.iter()
            .filter_map(|(_, s, r)| measure::speedup(&s.results, r, DEFAULT_BASELINE))
            .collect(),
    );
    let metric_values = metrics
        .iter()
        .map(|(name, _, _)| {
            median(
                ok.iter()
                    .filter_map(|(_, _, r)| r.metrics.iter().find(|m| &m.name == name))
                    .map(|m| m.value)
                    .collect(),
            )
        })
        .collect();
    let status = found
        .last()
        .map(|(_, _, r)| r.status.label().to_string())
        .unwrap_or_default();
    let mut run_ids = Vec::new();
    for (run, _, _) in &found {
        if !run_ids.contains(&run.info.run_id) {
            run_ids.push(run.info.run_id.clone());
        }
    }
    Row {
        variant: variant.to_string(),
        status,
        gpu_ms,
        speedup,
        metrics: metric_values,
        front: Vec::new(),
        run_ids,
    }
}

/// Marks, per quality metric, the rows no other row dominates: none is at least as fast and at
/// least as good with one of the two strictly better. Rows without a GPU time or without the
/// metric are on no front; the reference itself (an infinite PSNR, a FLIP of 0) takes part like
/// any other row. With the reference's `noise`, two values it ties are equal: being better by
/// less than the noise dominates nothing, and a faster row at a tied value dominates.
pub fn mark_fronts(
    rows: &mut [Row],
    metrics: &[(String, String, Direction)],
    noise: Option<&ReferenceNoise>,
) {
    for (i, (name, _, dir)) in metrics.iter().enumerate() {
        if *dir == Direction::Neither {
            continue;
        }
        // Quality as "higher is better" so one comparison serves both directions.
        let q = |r: &Row| {
            let v = r.metrics[i]?;
            Some(if dir.higher_is_better() { v } else { -v })
        };
        let points: Vec<Option<(f64, f64)>> =
            rows.iter().map(|r| Some((r.gpu_ms?, q(r)?))).collect();
        let tied = |a: f64, b: f64| {
            let sign = if dir.higher_is_better() { 1.0 } else { -1.0 };
            noise.is_some_and(|n| n.tied(name, sign * a, sign * b))
        };
        for (a, pa) in points.iter().enumerate() {
            let Some((ta, qa)) = pa else { continue };
            let dominated = points.iter().enumerate().any(|(b, pb)| {
                let Some((tb, qb)) = pb else { return false };
                let (ta, qa, tb, qb) = (*ta, *qa, *tb, *qb);
                if b == a || tb > ta {
                    return false;
                }
                if tied(qa, qb) {
                    tb < ta
                } else {
                    qb >= qa && (tb < ta || qb > qa)
                }
            });
            if !dominated {
                rows[a].front.push(name.clone());
            }
        }
    }
}

/// A metric's value as printed: 2 decimals for dB, 3 for JOD, 4 significant places otherwise.
fn metric_text(v: Option<f64>, unit: &str) -> String {
    match v {
        None => "-".into(),
        Some(v) if v.is_infinite() => "inf".into(),
        Some(v) if unit == "dB" => format!("{v:.2}"),
        Some(v) if unit == "JOD" => format!("{v:.3}"),
        Some(v) if v != 0.0 && v.abs() < 0.1 => format!("{v:.5}"),
        Some(v) => format!("{v:.4}"),
    }
}

fn header(name: &str, unit: &str) -> String {
    if unit.is_empty() {
        name.to_string()
    } else {
        format!("{name} ({unit})")
    }
}

/// The cells of a table: header, then rows, all as text.
fn cells(t: &Table) -> (Vec<String>, Vec<Vec<String>>) {
    let mut head = vec![
        "variant".to_string(),
        "GPU ms".to_string(),
        "speed-up".to_string(),
    ];
    head.extend(t.metrics.iter().map(|(n, u, _)| header(n, u)));
    head.push("front".into());
    head.push("runs".into());
    let rows = t
        .rows
        .iter()
        .map(|r| {
            let mut c = vec![r.variant.clone()];
            if r.status != "ok" {
                c.push(r.status.clone());
                c.push(String::new());
            } else {
                c.push(r.gpu_ms.map_or("-".into(), |v| format!("{v:.3}")));
                c.push(r.speedup.map_or("-".into(), |v| format!("{v:.2}x")));
            }
            for (v, (_, unit, _)) in r.metrics.iter().zip(&t.metrics) {
                c.push(metric_text(*v, unit));
            }
            c.push(if r.front.is_empty() {
                "-".into()
            } else {
                r.front.join(", ")
            });
            c.push(r.run_ids.join(" "));
            c
        })
        .collect();
    (head, rows)
}

/// The reference's noise as one line: what it was measured against and its value per metric.
pub fn noise_line(n: &ReferenceNoise) -> String {
    let mut s = format!(
        "reference noise ({} samples against {}, measured frame {}):",
        n.reference_samples, n.samples, n.frame
    );
    if n.metrics.is_empty() {
        s.push_str(" not measured");
    }
    for (i, (name, v)) in n.metrics.iter().enumerate() {
        let unit = tessera_results::measure::Measure::from_name(name).map_or("", |m| m.unit());
        let sep = if i == 0 { " " } else { ", " };
        let _ = write!(s, "{sep}{name} {}", metric_text(Some(*v), unit));
        if !unit.is_empty() {
            let _ = write!(s, " {unit}");
        }
    }
    if let Some(e) = &n.error {
        let _ = write!(s, " ({e})");
    }
    if !n.metrics.is_empty() {
        s.push_str("; differences below it are ties");
    }
    s
}

fn preamble(t: &Table) -> String {
    let clock = match t.clock_mhz {
        Some((lo, med, hi)) => format!("graphics clock {med:.0} MHz (min {lo:.0}, max {hi:.0})"),
        None => "clocks not recorded".to_string(),
    };
    let mut s = format!(
        "{} on {} ({}, driver {}), {clock}",
        t.scenario,
        t.adapter,
        t.backend,
        if t.driver.is_empty() { "?" } else { &t.driver },
    );
    if !t.throttled.is_empty() {
        let _ = write!(s, "; THROTTLED: {}", t.throttled.join(", "));
    }
    let _ = write!(
        s,
        "\n{}x{}, reference: {}; runs: {}",
        t.width,
        t.height,
        t.reference,
        t.run_ids.join(" ")
    );
    s
}

/// Every table, printed.
pub fn render(tables: &[Table], format: Format) -> String {
    let mut out = String::new();
    for (i, t) in tables.iter().enumerate() {
        if i > 0 {
            out.push('\n');
        }
        let (head, rows) = cells(t);
        match format {
            Format::Md => {
                let _ = writeln!(out, "**{}**\n", preamble(t).replace('\n', "  \n"));
                let _ = writeln!(out, "| {} |", head.join(" | "));
                let align: Vec<&str> = head
                    .iter()
                    .enumerate()
                    .map(|(i, _)| {
                        if i == 0 || i + 1 == head.len() {
                            "---"
                        } else {
                            "---:"
                        }
                    })
                    .collect();
                let _ = writeln!(out, "|{}|", align.join("|"));
                for r in rows {
                    let _ = writeln!(out, "| {} |", r.join(" | "));
                }
                if let Some(n) = &t.noise {
                    let _ = writeln!(out, "\n{}", noise_line(n));
                }
            }
            Format::Text => {
                let _ = writeln!(out, "{}", preamble(t));
                let mut width: Vec<usize> = head.iter().map(|h| h.len()).collect();
                for r in &rows {
                    for (w, c) in width.iter_mut().zip(r) {
                        *w = (*w).max(c.chars().count());
                    }
                }
                let line = |cells: &[String]| {
                    let mut l = String::from("  ");
                    for (i, (c, w)) in cells.iter().zip(&width).enumerate() {
                        if i == 0 || i + 1 == cells.len() {
                            let _ = write!(l, "{c:<w$}  ");
                        } else {
                            let _ = write!(l, "{c:>w$}  ");
                        }
                    }
                    l.trim_end().to_string()
                };
                let _ = writeln!(out, "{}", line(&head));
                for r in &rows {
                    let _ = writeln!(out, "{}", line(r));
                }
                if let Some(n) = &t.noise {
                    let _ = writeln!(out, "  {}", noise_line(n));
                }
            }
        }
    }
    out
}

/// Run folders given on the command line, with folders of run folders descended into (one level
/// at a time, until a `run.json`), in name order.
pub fn run_folders(args: &[std::path::PathBuf]) -> std::io::Result<Vec<std::path::PathBuf>> {
    let mut out = Vec::new();
    for a in args {
        collect(a, &mut out, 0)?;
    }
    Ok(out)
}

fn collect(
    dir: &std::path::Path,
    out: &mut Vec<std::path::PathBuf>,
    depth: u32,
) -> std::io::Result<()> {
    if dir.join("run.json").is_file() || !dir.is_dir() {
        out.push(dir.to_path_buf());
        return Ok(());
    }
    let before = out.len();
    if depth < 3 {
        let mut entries: Vec<_> = std::fs::read_dir(dir)?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_dir())
            .collect();
        entries.sort();
        for e in entries {
            collect(&e, out, depth + 1)?;
        }
    }
    if depth == 0 && out.len() == before {
        // Neither a run nor a folder of runs: the reader says why.
        out.push(dir.to_path_buf());
    }
    Ok(())
}

/// Tables keyed by scenario name, for tests and callers that want one.
pub fn by_scenario(tables: &[Table]) -> BTreeMap<&str, &Table> {
    tables.iter().map(|t| (t.scenario.as_str(), t)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(variant: &str, gpu_ms: f64, psnr: f64, flip: f64) -> Row {
        Row {
            variant: variant.into(),
            status: "ok".into(),
            gpu_ms: Some(gpu_ms),
            speedup: None,
            metrics: vec![Some(psnr), Some(flip)],
            front: Vec::new(),
            run_ids: Vec::new(),
        }
    }

    fn metrics() -> Vec<(String, String, Direction)> {
        vec![
            ("psnr".into(), "dB".into(), Direction::HigherIsBetter),
            ("flip".into(), "".into(), Direction::LowerIsBetter),
        ]
    }

    fn noise(psnr: f64, flip: f64) -> ReferenceNoise {
        ReferenceNoise {
            reference_samples: 32,
            samples: 128,
            frame: 0,
            metrics: [("psnr".to_string(), psnr), ("flip".to_string(), flip)].into(),
            error: None,
        }
    }

    fn fronts(noise: Option<&ReferenceNoise>) -> Vec<Vec<String>> {
        // `b` is 0.1 ms slower than `a` and better by a hair in both metrics; `c` is slower
        // still and better by far more than any noise below.
        let mut rows = vec![
            row("a", 1.0, 30.0, 0.0500),
            row("b", 1.1, 30.02, 0.0498),
            row("c", 2.0, 36.0, 0.0200),
        ];
        mark_fronts(&mut rows, &metrics(), noise);
        rows.into_iter().map(|r| r.front).collect()
    }

    #[test]
    fn without_noise_a_hair_better_is_a_front() {
        let all = vec!["psnr".to_string(), "flip".to_string()];
        assert_eq!(fronts(None), vec![all.clone(), all.clone(), all]);
    }

    #[test]
    fn a_near_tie_within_the_noise_is_a_tie() {
        // A reference 40 dB and 0.001 FLIP from a denser one: `b`'s 0.02 dB and 0.0002 FLIP
        // are below it, so the faster `a` dominates it; `c` is better by more than the noise.
        let n = noise(40.0, 0.001);
        let all = vec!["psnr".to_string(), "flip".to_string()];
        assert_eq!(fronts(Some(&n)), vec![all.clone(), vec![], all]);
    }

    #[test]
    fn at_equal_time_better_by_less_than_the_noise_does_not_dominate() {
        let n = noise(40.0, 0.001);
        let mut rows = vec![row("a", 1.0, 30.0, 0.0500), row("b", 1.0, 30.02, 0.0498)];
        mark_fronts(&mut rows, &metrics(), Some(&n));
        assert!(rows.iter().all(|r| r.front.len() == 2), "{rows:?}");
        // Without the noise the better one wins alone.
        let mut rows = vec![row("a", 1.0, 30.0, 0.0500), row("b", 1.0, 30.02, 0.0498)];
        mark_fronts(&mut rows, &metrics(), None);
        assert_eq!(rows[0].front, Vec::<String>::new());
    }

    #[test]
    fn psnr_ties_grow_as_the_variant_nears_the_reference_noise() {
        let n = noise(40.0, 0.001);
        // Far below the noise's PSNR a tenth of a dB is a ranking; at it, a dB is not.
        assert!(!n.tied("psnr", 20.0, 20.1));
        assert!(n.tied("psnr", 39.0, 40.0));
        assert!(!n.tied("flip", 0.05, 0.0489));
        assert!(n.tied("flip", 0.05, 0.0491));
    }

    #[test]
    fn the_noise_line_says_ties() {
        let line = noise_line(&noise(41.234, 0.00312));
        assert_eq!(
            line,
            "reference noise (32 samples against 128, measured frame 0): flip 0.00312, psnr 41.23 dB; differences below it are ties"
        );
    }
}
