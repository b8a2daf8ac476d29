//! The Markdown of `tessera compare`: a header table of the two runs, one table per scenario,
//! the regressions and improvements as lists, and one verdict line. Formatting only: every number
//! and verdict comes from [`super::analysis`].

use std::fmt::Write as _;

use tessera_results::RunInfo;

use super::analysis::{
    Comparison, MetricChange, Side, Time, VariantChange, Verdict, ALPHA, JUDGED_METRICS,
};

/// Table cells cannot hold `|` or line breaks.
fn cell(s: &str) -> String {
    s.replace('|', "\\|").replace(['\n', '\r'], " ")
}

fn pair(a: Option<String>, b: Option<String>) -> String {
    match (a, b) {
        (Some(x), Some(y)) if x == y => x,
        (None, None) => "-".to_string(),
        (x, y) => format!(
            "{} → {}",
            x.unwrap_or_else(|| "-".into()),
            y.unwrap_or_else(|| "-".into())
        ),
    }
}

fn p_value(p: f64) -> String {
    if p < 0.001 {
        "p<0.001".to_string()
    } else {
        format!("p={p:.3}")
    }
}

fn pct(change: f64) -> String {
    format!("{:+.1}%", change * 100.0)
}

fn metric_number(name: &str, v: f64) -> String {
    if v.is_infinite() {
        "inf".to_string()
    } else if name == "psnr" {
        format!("{v:.2}")
    } else {
        format!("{v:.4}")
    }
}

fn metric_values(m: &MetricChange) -> String {
    pair(
        m.values.0.map(|v| metric_number(m.name, v)),
        m.values.1.map(|v| metric_number(m.name, v)),
    )
}

fn metric_cell(m: &MetricChange) -> String {
    let text = metric_values(m);
    match m.verdict {
        Verdict::Worse => format!("{text} **worse**"),
        Verdict::Better => format!("{text} better"),
        Verdict::Same => text,
    }
}

/// The change and the verdict; "slower" is bold only where it counts as a regression.
fn time_cell(t: &Time, timings_count: bool) -> (String, String) {
    match t {
        Time::Compared {
            change, p, verdict, ..
        } => {
            let word = match verdict {
                Verdict::Worse if timings_count => "**slower**",
                Verdict::Worse => "slower",
                Verdict::Better => "faster",
                Verdict::Same => "within noise",
            };
            (pct(*change), format!("{word} ({})", p_value(*p)))
        }
        Time::Baseline => ("-".to_string(), "baseline".to_string()),
        Time::NotCompared(why) => ("-".to_string(), why.to_string()),
    }
}

fn run_rows(out: &mut String, a: &RunInfo, b: &RunInfo) {
    let commit = |r: &RunInfo| match &r.commit {
        Some(c) => format!(
            "`{}`{}",
            &c.sha[..c.sha.len().min(7)],
            if c.dirty { " (dirty)" } else { "" }
        ),
        None => "-".to_string(),
    };
    let adapter = |r: &RunInfo| cell(&format!("{}, {}", r.adapter.name, r.adapter.backend));
    let driver = |r: &RunInfo| cell(&format!("{}, {}", r.adapter.driver, r.adapter.driver_info));
    let status = |r: &RunInfo| {
        serde_json::to_value(r.status)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_default()
    };
    out.push_str("| | A (base) | B (new) |\n|---|---|---|\n");
    let id = |r: &RunInfo| format!("`{}`", r.run_id);
    let rows = [
        ("run", id(a), id(b)),
        ("commit", commit(a), commit(b)),
        ("adapter", adapter(a), adapter(b)),
        ("driver", driver(a), driver(b)),
        ("status", status(a), status(b)),
    ];
    for (name, x, y) in rows {
        let _ = writeln!(out, "| {name} | {x} | {y} |");
    }
}

fn variant_row(out: &mut String, v: &VariantChange, timings_count: bool, shown: &[bool]) {
    let name = match v.only_in {
        Some(Side::A) => format!("{} (only in A)", v.variant),
        Some(Side::B) => format!("{} (only in B)", v.variant),
        None => v.variant.clone(),
    };
    let (change, time) = time_cell(&v.time, timings_count);
    let ms = pair(
        v.gpu_ms.0.map(|x| format!("{x:.3}")),
        v.gpu_ms.1.map(|x| format!("{x:.3}")),
    );
    let speedup = pair(
        v.speedup.0.map(|x| format!("{x:.2}x")),
        v.speedup.1.map(|x| format!("{x:.2}x")),
    );
    let metrics: Vec<String> = v
        .metrics
        .iter()
        .zip(shown)
        .filter(|(_, &show)| show)
        .map(|(m, _)| metric_cell(m))
        .collect();
    let mut status = cell(&pair(v.status.0.clone(), v.status.1.clone()));
    if v.status_verdict == Verdict::Worse {
        status = format!("**{status}**");
    }
    let _ = writeln!(
        out,
        "| {} | {ms} | {change} | {time} | {speedup} | {} | {status} |",
        cell(&name),
        metrics.join(" | ")
    );
}

/// One line per regressed (or improved) aspect of a variant.
fn findings(v: &VariantChange, wanted: Verdict, timings_count: bool) -> Vec<String> {
    let mut lines = Vec::new();
    if let Time::Compared {
        change,
        p,
        verdict,
        by_speedup,
    } = &v.time
    {
        if timings_count && *verdict == wanted {
            let what = if *by_speedup {
                "GPU time relative to native"
            } else {
                "GPU time"
            };
            lines.push(format!("{what} {} ({})", pct(*change), p_value(*p)));
        }
    }
    for (m, (_, label, _)) in v.metrics.iter().zip(JUDGED_METRICS) {
        if m.verdict == wanted {
            lines.push(format!("{label} {}", metric_values(m)));
        }
    }
    if v.status_verdict == wanted {
        lines.push(format!(
            "status {}",
            pair(v.status.0.clone(), v.status.1.clone())
        ));
    }
    lines
}

/// Energy per frame where either run recorded it: the values, their change and the energy saved
/// against native. Informational: energy is not judged as a regression.
fn energy_table(out: &mut String, c: &Comparison) {
    let rows: Vec<String> = c
        .scenarios
        .iter()
        .flat_map(|s| s.variants.iter().map(move |v| (s, v)))
        .filter(|(_, v)| v.energy_mj.0.is_some() || v.energy_mj.1.is_some())
        .map(|(s, v)| {
            let mj = pair(
                v.energy_mj.0.map(|x| format!("{x:.3}")),
                v.energy_mj.1.map(|x| format!("{x:.3}")),
            );
            let change = match v.energy_mj {
                (Some(a), Some(b)) if a > 0.0 => pct(b / a - 1.0),
                _ => "-".to_string(),
            };
            let saving = pair(
                v.energy_saving.0.map(|x| format!("{x:.2}x")),
                v.energy_saving.1.map(|x| format!("{x:.2}x")),
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
    out.push_str("### Energy per frame\n\n| scenario | variant | mJ/frame | change | saving vs native |\n|---|---|---:|---:|---:|\n");
    for r in rows {
        out.push_str(&r);
        out.push('\n');
    }
    out.push('\n');
}

/// The whole comparison as Markdown, ending with the verdict line.
pub fn render(c: &Comparison) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "## Tessera comparison: `{}` → `{}`\n",
        c.a.run_id, c.b.run_id
    );
    run_rows(&mut out, &c.a, &c.b);
    out.push('\n');
    if !c.same_adapter {
        out.push_str(
            "> **Warning:** the adapters or drivers differ: GPU times are compared by speedup \
             against native on each adapter, not in milliseconds.\n\n",
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
        if r.status != tessera_results::RunStatus::Complete {
            let _ = writeln!(
                out,
                "> **Warning:** run {side} did not complete: scenarios may be missing.\n"
            );
        }
    }
    for (side, pick) in [("A", 0), ("B", 1)] {
        let throttled: Vec<String> = c
            .scenarios
            .iter()
            .flat_map(|s| s.variants.iter().map(move |v| (s, v)))
            .filter(|(_, v)| if pick == 0 { v.throttled.0 } else { v.throttled.1 } == Some(true))
            .map(|(s, v)| format!("`{}` / `{}`", s.scenario, v.variant))
            .collect();
        if !throttled.is_empty() {
            let _ = writeln!(
                out,
                "> **Warning:** throttled during measured frames in run {side} (their times read lowered clocks): {}.\n",
                throttled.join(", ")
            );
        }
    }
    for s in &c.scenarios {
        // PSNR, SSIM and FLIP always have a column; later judged metrics (JOD) only where a
        // variant of the scenario has them.
        let shown: Vec<bool> = (0..JUDGED_METRICS.len())
            .map(|i| {
                i < 3
                    || s.variants.iter().any(|v| {
                        v.metrics
                            .get(i)
                            .is_some_and(|m| m.values.0.is_some() || m.values.1.is_some())
                    })
            })
            .collect();
        let metric_headers: Vec<&str> = JUDGED_METRICS
            .iter()
            .zip(&shown)
            .filter(|(_, &show)| show)
            .map(|(m, _)| m.1)
            .collect();
        let suffix = match s.only_in {
            Some(Side::A) => " (only in A)",
            Some(Side::B) => " (only in B)",
            None => "",
        };
        let _ = writeln!(out, "### {}{suffix}\n", s.scenario);
        let _ = writeln!(
            out,
            "| variant | GPU ms | change | time | speedup | {} | status |",
            metric_headers.join(" | ")
        );
        let _ = writeln!(
            out,
            "|---|---:|---:|---|---:|{}---|",
            "---:|".repeat(metric_headers.len())
        );
        for v in &s.variants {
            variant_row(&mut out, v, c.timings_count, &shown);
        }
        out.push('\n');
    }
    energy_table(&mut out, c);
    let mut counts = [0usize; 2];
    for (i, (title, wanted)) in [
        ("Regressions", Verdict::Worse),
        ("Improvements", Verdict::Better),
    ]
    .into_iter()
    .enumerate()
    {
        let mut lines = Vec::new();
        for s in &c.scenarios {
            for v in &s.variants {
                for f in findings(v, wanted, c.timings_count) {
                    lines.push(format!(
                        "- `{}` / `{}`: {}",
                        s.scenario,
                        v.variant,
                        cell(&f)
                    ));
                }
            }
        }
        counts[i] = lines.len();
        if !lines.is_empty() {
            let _ = writeln!(out, "**{title}**\n\n{}\n", lines.join("\n"));
        }
    }
    let rule = format!(
        "time: Mann-Whitney U p < {ALPHA} and a median change of at least {}%",
        c.options.threshold_pct
    );
    let plural = |n: usize, word: &str| format!("{n} {word}{}", if n == 1 { "" } else { "s" });
    let _ = writeln!(
        out,
        "**Verdict: {}** ({} beyond noise, {}; {rule})",
        if c.regressed() {
            "regressed"
        } else {
            "no regression"
        },
        plural(counts[0], "regression"),
        plural(counts[1], "improvement"),
    );
    out
}
