//! The Markdown of a [`Comparison`]: what `tessera compare` prints and the dashboard's
//! `/api/compare/runs?format=md` answers (what a pull request comment would show). A header table
//! of the two runs, warnings, one table per scenario, the regressions and improvements, the
//! variants with too few frames, and one verdict line. Formatting only: every number and verdict
//! comes from the comparison; names are escaped so they cannot break a table or a code span.
//!
//! Not for: HTML (the dashboard's compare page).

use std::fmt::Write as _;

use crate::{RunInfo, RunStatus};

use super::findings::{metric_values, pair_text, Verdict};
use super::words::{change_with_interval, verdict_with_evidence};
use super::{Comparison, ScenarioComparison, Side, Time, VariantComparison};

/// Metrics with a column, in order; the first three always, the rest where a variant of the
/// scenario has them. Other metrics appear in the regressions and improvements when they move.
pub const COLUMNS: [&str; 4] = ["psnr", "ssim", "flip", "cvvdp"];

/// Table cells cannot hold `|` or line breaks.
pub fn cell(s: &str) -> String {
    s.replace('|', "\\|").replace(['\n', '\r'], " ")
}

/// `s` as a code span that its own backticks cannot end (CommonMark: a longer fence, padded).
pub fn code(s: &str) -> String {
    let s = cell(s);
    let mut longest = 0;
    let mut run = 0;
    for c in s.chars() {
        run = if c == '`' { run + 1 } else { 0 };
        longest = longest.max(run);
    }
    if longest == 0 {
        format!("`{s}`")
    } else {
        let fence = "`".repeat(longest + 1);
        format!("{fence} {s} {fence}")
    }
}

fn run_rows(out: &mut String, a: &RunInfo, b: &RunInfo) {
    let commit = |r: &RunInfo| match &r.commit {
        Some(c) => format!(
            "{}{}",
            code(c.sha.get(..7).unwrap_or(&c.sha)),
            if c.dirty { " (dirty)" } else { "" }
        ),
        None => "-".to_string(),
    };
    let adapter = |r: &RunInfo| cell(&format!("{}, {}", r.adapter.name, r.adapter.backend));
    let driver = |r: &RunInfo| cell(&format!("{}, {}", r.adapter.driver, r.adapter.driver_info));
    let status = |r: &RunInfo| match r.status {
        RunStatus::Running => "running",
        RunStatus::Complete => "complete",
        RunStatus::Interrupted => "interrupted",
    };
    out.push_str("| | A (base) | B (new) |\n|---|---|---|\n");
    let rows = [
        ("run", code(&a.run_id), code(&b.run_id)),
        ("commit", commit(a), commit(b)),
        ("adapter", adapter(a), adapter(b)),
        ("driver", driver(a), driver(b)),
        ("status", status(a).into(), status(b).into()),
    ];
    for (name, x, y) in rows {
        let _ = writeln!(out, "| {name} | {x} | {y} |");
    }
}

fn named(v: &VariantComparison) -> String {
    match v.only_in {
        Some(Side::A) => format!("{} (only in A)", v.variant),
        Some(Side::B) => format!("{} (only in B)", v.variant),
        None => v.variant.clone(),
    }
}

/// The change and the verdict cells; `slower` is bold only where it counts as a regression.
fn time_cells(v: &VariantComparison, c: &Comparison) -> (String, String) {
    match &v.time {
        Time::Tested { test, .. } => {
            let mut verdict = verdict_with_evidence(test, c.rule.frames_needed);
            if c.timings_count && test.verdict == super::TimeVerdict::Slower {
                verdict = format!("**{verdict}**");
            }
            (change_with_interval(test), verdict)
        }
        t => ("-".to_string(), t.words().to_string()),
    }
}

fn variant_row(out: &mut String, v: &VariantComparison, c: &Comparison, shown: &[&str]) {
    let (change, time) = time_cells(v, c);
    let ms = pair_text(
        v.gpu_ms.a.map(|x| format!("{x:.3}")),
        v.gpu_ms.b.map(|x| format!("{x:.3}")),
    );
    let mut speedup = pair_text(
        v.speedup.a.map(|x| format!("{x:.2}x")),
        v.speedup.b.map(|x| format!("{x:.2}x")),
    );
    if let Some(base) = &v.speedup_moved_with {
        let _ = write!(speedup, " (moved with {base})");
    }
    let metrics: Vec<String> = shown
        .iter()
        .map(|name| match v.metrics.iter().find(|m| m.name == *name) {
            Some(m) => {
                let text = metric_values(m);
                match m.verdict {
                    Verdict::Worse => format!("{text} **worse**"),
                    Verdict::Better => format!("{text} better"),
                    Verdict::Same => text,
                }
            }
            None => "-".to_string(),
        })
        .collect();
    let mut status = cell(&pair_text(v.status.a.clone(), v.status.b.clone()));
    if v.status_verdict == Verdict::Worse {
        status = format!("**{status}**");
    }
    let _ = writeln!(
        out,
        "| {} | {ms} | {change} | {time} | {} | {} | {status} |",
        cell(&named(v)),
        cell(&speedup),
        metrics.join(" | ")
    );
}

fn scenario_table(out: &mut String, s: &ScenarioComparison, c: &Comparison) {
    let shown: Vec<&str> = COLUMNS
        .iter()
        .enumerate()
        .filter(|(i, name)| {
            *i < 3
                || s.variants
                    .iter()
                    .any(|v| v.metrics.iter().any(|m| m.name == **name))
        })
        .map(|(_, n)| *n)
        .collect();
    let headers: Vec<String> = shown
        .iter()
        .map(|n| {
            crate::measure::Measure::from_name(n)
                .map_or_else(|| n.to_string(), |m| m.label().to_string())
        })
        .collect();
    let suffix = match s.only_in {
        Some(Side::A) => " (only in A)",
        Some(Side::B) => " (only in B)",
        None => "",
    };
    let _ = writeln!(out, "### {}{suffix}\n", cell(&s.scenario));
    let _ = writeln!(
        out,
        "| variant | GPU ms | change [{:.0}% interval] | time | speedup | {} | status |",
        c.rule.confidence * 100.0,
        headers.join(" | ")
    );
    let _ = writeln!(
        out,
        "|---|---:|---:|---|---:|{}---|",
        "---:|".repeat(headers.len())
    );
    for v in &s.variants {
        variant_row(out, v, c, &shown);
    }
    out.push('\n');
}

/// Energy per frame where either run recorded it. Informational: energy is not judged.
fn energy_table(out: &mut String, c: &Comparison) {
    let rows: Vec<String> = c
        .variants()
        .filter(|(_, v)| v.energy_mj.a.is_some() || v.energy_mj.b.is_some())
        .map(|(s, v)| {
            let mj = pair_text(
                v.energy_mj.a.map(|x| format!("{x:.3}")),
                v.energy_mj.b.map(|x| format!("{x:.3}")),
            );
            let change = match (v.energy_mj.a, v.energy_mj.b) {
                (Some(a), Some(b)) if a > 0.0 => super::words::pct(b / a - 1.0),
                _ => "-".to_string(),
            };
            let saving = pair_text(
                v.energy_saving.a.map(|x| format!("{x:.2}x")),
                v.energy_saving.b.map(|x| format!("{x:.2}x")),
            );
            format!(
                "| {} | {} | {mj} | {change} | {saving} |",
                cell(&s.scenario),
                cell(&v.variant)
            )
        })
        .collect();
    if rows.is_empty() {
        return;
    }
    out.push_str("### Energy per frame\n\n| scenario | variant | mJ/frame | change | saving vs baseline |\n|---|---|---:|---:|---:|\n");
    for r in rows {
        out.push_str(&r);
        out.push('\n');
    }
    out.push('\n');
}

fn warnings(out: &mut String, c: &Comparison) {
    if !c.same_adapter {
        out.push_str(
            "> **Warning:** the adapters or drivers differ: GPU times are compared relative to \
             each variant's baseline on each adapter (its speedup), not in milliseconds.\n\n",
        );
    }
    if !c.timings_count {
        out.push_str(
            "> **Note:** a run is on a CPU adapter (lavapipe): its timings measure CPU work and \
             depend on other load on the machine, so time verdicts are shown but never count as \
             regressions.\n\n",
        );
    }
    for (side, r) in [("A", &c.a), ("B", &c.b)] {
        if r.status != RunStatus::Complete {
            let _ = writeln!(
                out,
                "> **Warning:** run {side} did not complete: scenarios may be missing.\n"
            );
        }
    }
    for side in [Side::A, Side::B] {
        let throttled: Vec<String> = c
            .variants()
            .filter(|(_, v)| {
                let t = match side {
                    Side::A => v.throttled.a,
                    Side::B => v.throttled.b,
                };
                t == Some(true)
            })
            .map(|(s, v)| format!("{} / {}", code(&s.scenario), code(&v.variant)))
            .collect();
        if !throttled.is_empty() {
            let _ = writeln!(
                out,
                "> **Warning:** throttled during measured frames in run {side:?} (their times read lowered clocks): {}.\n",
                throttled.join(", ")
            );
        }
    }
}

fn findings(out: &mut String, c: &Comparison) {
    for (title, wanted) in [
        ("Regressions", Verdict::Worse),
        ("Improvements", Verdict::Better),
    ] {
        let lines: Vec<String> = c
            .findings_of(wanted)
            .map(|f| {
                let mut line = format!(
                    "- {} / {}: {} {}",
                    code(&f.scenario),
                    code(&f.variant),
                    cell(&f.what),
                    cell(&f.change)
                );
                if !f.moves_speedups_of.is_empty() {
                    let names: Vec<String> = f.moves_speedups_of.iter().map(|n| code(n)).collect();
                    let _ = write!(
                        line,
                        "; the speedups of {} moved with it (counted here once)",
                        names.join(", ")
                    );
                }
                line
            })
            .collect();
        if !lines.is_empty() {
            let _ = writeln!(out, "**{title}**\n\n{}\n", lines.join("\n"));
        }
    }
    let few: Vec<String> = c
        .too_few_frames()
        .map(|(s, v)| {
            let t = v.time.tested().expect("too few frames is a test's verdict");
            format!(
                "{} / {} ({} vs {})",
                code(&s.scenario),
                code(&v.variant),
                t.frames[0],
                t.frames[1]
            )
        })
        .collect();
    if !few.is_empty() {
        let _ = writeln!(
            out,
            "**Too few frames**\n\nThe time test cannot reach p < {} with so few measured frames, whatever the change: {}. It takes {} frames per side (`frames.measured`).\n",
            c.rule.alpha,
            few.join(", "),
            c.rule.frames_needed
        );
    }
}

/// The verdict line's first words: `regressed`, `inconclusive` (nothing regressed but the times
/// could not be judged: [`Comparison::undecided`]) or `no regression`.
pub fn verdict_words(c: &Comparison) -> &'static str {
    c.decision().words()
}

/// The whole comparison as Markdown, ending with the verdict line.
pub fn render(c: &Comparison) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "## Tessera comparison: {} → {}\n",
        code(&c.a.run_id),
        code(&c.b.run_id)
    );
    run_rows(&mut out, &c.a, &c.b);
    out.push('\n');
    warnings(&mut out, c);
    for s in &c.scenarios {
        scenario_table(&mut out, s, c);
    }
    energy_table(&mut out, c);
    findings(&mut out, c);
    let plural = |n: usize, word: &str| format!("{n} {word}{}", if n == 1 { "" } else { "s" });
    let few = c.too_few_frames().count();
    let why = c.undecided();
    let _ = writeln!(
        out,
        "**Verdict: {}**{} ({}, {}{}; {})",
        verdict_words(c),
        if c.decision() == super::Decision::Inconclusive {
            format!(": {}", cell(&why.join("; ")))
        } else {
            String::new()
        },
        plural(c.findings_of(Verdict::Worse).count(), "regression"),
        plural(c.findings_of(Verdict::Better).count(), "improvement"),
        if few > 0 {
            format!(", {few} too few frames")
        } else {
            String::new()
        },
        c.rule.sentence()
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_cannot_break_tables_or_code_spans() {
        assert_eq!(cell("a|b\nc"), "a\\|b c");
        assert_eq!(code("plain"), "`plain`");
        assert_eq!(code("a`b"), "`` a`b ``");
        assert_eq!(code("x``y|z"), "``` x``y\\|z ```");
    }
}
