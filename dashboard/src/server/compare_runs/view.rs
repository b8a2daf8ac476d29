//! The compare page's HTML: the form, both runs, the rule, the verdict and its tally, the
//! regressions and improvements (a baseline's change once, with the speedups that moved with it),
//! the variants with too few frames, and one table per scenario (frame time with its 99% interval
//! and verdict, speedup, passes, metrics, status, images). Every word and number comes from the
//! engine's [`Comparison`]; every name is escaped.
//!
//! Not for: the API's formats ([`super::formats`]).

use std::fmt::Write;

use tessera_results::compare::words::{change_with_interval, p_value, pct};
use tessera_results::compare::{
    Comparison, Decision, Finding, PassComparison, ScenarioComparison, Time, TimeVerdict,
    VariantComparison, Verdict,
};
use tessera_results::RunInfo;

use super::query::CompareRunsQuery;
use crate::html::{commit, enc, esc, name, num};

/// A comparison of more variants than this opens on its per-scenario summary; each scenario's
/// table is `?scenario=NAME` (the run page's limit, [`crate::server::run::INLINE_RESULTS`]).
pub const INLINE_VARIANTS: usize = crate::server::run::INLINE_RESULTS;

/// Most regressions (and improvements) named at the top; the rest are in the scenarios' tables.
const FINDINGS_SHOWN: usize = 40;
/// Variants with too few frames named in the sentence that says so; the rest are counted.
const TOO_FEW_SHOWN: usize = 10;

fn plural(n: usize, word: &str) -> String {
    format!("{n} {word}{}", if n == 1 { "" } else { "s" })
}

fn opt(v: Option<f64>) -> String {
    v.map_or("–".into(), num)
}

/// The CSS class of a time verdict: red where it counts as a regression.
fn time_class(t: &Time, counts: bool) -> &'static str {
    match t.tested().map(|t| t.verdict) {
        Some(TimeVerdict::Slower) if counts => "worse",
        Some(TimeVerdict::Faster) if counts => "better",
        _ => "muted",
    }
}

fn verdict_class(v: Verdict) -> &'static str {
    match v {
        Verdict::Worse => "worse",
        Verdict::Better => "better",
        Verdict::Same => "muted",
    }
}

/// The threshold a variant's time was judged with, where its series' noise set it: `threshold
/// 1.0% (5σ of 0.08% nightly noise)`.
fn threshold_note(v: &VariantComparison, c: &Comparison) -> String {
    match (v.noise, c.rule.noise_sigmas) {
        (Some(sigma), Some(k)) if v.threshold_pct < c.rule.threshold_pct => format!(
            " <span class=muted title=\"a change of {k}σ of this series' night-to-night noise stands out; the fixed threshold is {}%\">threshold {:.1}% ({k}σ of {:.2}% nightly noise)</span>",
            c.rule.threshold_pct,
            v.threshold_pct,
            sigma * 100.0
        ),
        _ => String::new(),
    }
}

/// The verdict with its evidence: `slower p<0.001`, `too few frames (4 vs 4; 5 per side
/// needed)`, `baseline`.
fn time_words(t: &Time, frames_needed: usize) -> String {
    match t.tested() {
        Some(x) if x.verdict == TimeVerdict::TooFewFrames => format!(
            "too few frames <span class=muted>({} vs {}; {frames_needed} per side needed)</span>",
            x.frames[0], x.frames[1]
        ),
        Some(x) => format!(
            "{} <span class=muted>{}</span>",
            x.verdict.words(),
            p_value(x.p)
        ),
        None => esc(t.words()),
    }
}

fn change_cell(t: &Time) -> String {
    t.tested().map_or("–".into(), change_with_interval)
}

fn run_line(label: &str, r: &RunInfo) -> String {
    format!(
        "<p>{label}: <a href=\"/runs/{}\">{}</a> · commit <code>{}</code> · {} · {} · {} {} · suite {}</p>",
        enc(&r.run_id),
        esc(&r.run_id),
        esc(&commit(r.commit.as_ref().map(|c| c.sha.as_str()))),
        esc(&r.started_at),
        esc(&r.adapter.name),
        esc(&r.adapter.driver),
        esc(&r.adapter.driver_info),
        esc(r.suite.as_deref().unwrap_or("–"))
    )
}

fn finding_item(f: &Finding) -> String {
    let mut li = format!(
        "<li><a href=\"#s-{}\">{}</a> / {}: {} <span class={}>{}</span>",
        esc(&f.scenario),
        name(&f.scenario),
        name(&f.variant),
        esc(&f.what),
        verdict_class(f.verdict),
        esc(&f.change)
    );
    if !f.moves_speedups_of.is_empty() {
        let _ = write!(
            li,
            " <span class=muted>· the speedups of {} moved with it (counted here once)</span>",
            esc(&f.moves_speedups_of.join(", "))
        );
    }
    li.push_str("</li>");
    li
}

fn findings(b: &mut String, c: &Comparison) {
    for (title, v) in [
        ("Regressions", Verdict::Worse),
        ("Improvements", Verdict::Better),
    ] {
        let all: Vec<&Finding> = c.findings_of(v).collect();
        if !all.is_empty() {
            let mut items: String = all
                .iter()
                .take(FINDINGS_SHOWN)
                .map(|f| finding_item(f))
                .collect();
            if all.len() > FINDINGS_SHOWN {
                let _ = write!(
                    items,
                    "<li class=muted>and {} more: see the scenarios below</li>",
                    all.len() - FINDINGS_SHOWN
                );
            }
            let _ = write!(
                b,
                "<h2 class={}>{title}</h2><ul class=findings>{items}</ul>",
                verdict_class(v),
            );
        }
    }
    let few: Vec<String> = c
        .too_few_frames()
        .map(|(s, v)| format!("{} / {}", name(&s.scenario), name(&v.variant)))
        .collect();
    if !few.is_empty() {
        let mut named = few
            .iter()
            .take(TOO_FEW_SHOWN)
            .cloned()
            .collect::<Vec<_>>()
            .join(", ");
        if few.len() > TOO_FEW_SHOWN {
            let _ = write!(named, " and {} more", few.len() - TOO_FEW_SHOWN);
        }
        let _ = write!(
            b,
            "<p id=too-few><strong>Too few frames</strong> to tell a time change in {} (the test cannot reach p &lt; {} with so few frames, whatever the change): {}. It takes {} measured frames per side (<code>frames.measured</code>).</p>",
            few.len(),
            c.rule.alpha,
            named,
            c.rule.frames_needed
        );
    }
}

fn passes_cell(passes: &[PassComparison], counts: bool) -> String {
    passes
        .iter()
        .map(|p| {
            let change = p.time.tested().map_or("–".into(), |t| pct(t.change));
            format!(
                "<span class=nw>{} <span class={}>{change} {}</span></span>",
                esc(&p.name),
                time_class(&p.time, counts),
                esc(p.time.words())
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

fn metrics_cell(v: &VariantComparison) -> String {
    v.metrics
        .iter()
        .map(|m| {
            let unit = tessera_results::measure::Measure::from_name(&m.name)
                .map(|x| x.unit())
                .filter(|u| !u.is_empty())
                .map_or(String::new(), |u| format!(" {u}"));
            // One item never breaks inside: `psnr 18.85 → 18.85 dB`.
            format!(
                "<span class=nw>{} {} → <span class={}>{}</span>{}</span>",
                esc(&m.name),
                opt(m.values.a),
                verdict_class(m.verdict),
                opt(m.values.b),
                esc(&unit)
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

fn speedup_cell(v: &VariantComparison) -> String {
    let x = |s: Option<f64>| s.map_or("–".into(), |s| format!("{s:.2}x"));
    let mut out = format!("{} → {}", x(v.speedup.a), x(v.speedup.b));
    if v.speedup.a.is_none() && v.speedup.b.is_none() {
        out = "–".into();
    }
    if let Some(base) = &v.speedup_moved_with {
        let _ = write!(out, " <span class=muted>(moved with {})</span>", esc(base));
    }
    out
}

fn images_cell(c: &Comparison, s: &ScenarioComparison, v: &VariantComparison) -> String {
    let link = |run: &str, label: &str| {
        format!(
            "<a href=\"/runs/{}/images/{}/{}\">{label}</a>",
            enc(run),
            enc(&s.scenario),
            enc(&v.variant)
        )
    };
    let mut out = Vec::new();
    if v.images.a == Some(true) {
        out.push(link(&c.a.run_id, "A"));
    }
    if v.images.b == Some(true) {
        out.push(link(&c.b.run_id, "B"));
    }
    if v.images.a == Some(true) && v.images.b == Some(true) {
        out.push(format!(
            "<a href=\"/runs/{}/images/{}/{}?other={}\">A beside B</a>",
            enc(&c.b.run_id),
            enc(&s.scenario),
            enc(&v.variant),
            enc(&c.a.run_id)
        ));
    }
    out.join(" ")
}

fn scenario_table(b: &mut String, c: &Comparison, s: &ScenarioComparison) {
    let only = match s.only_in {
        Some(side) => format!(" <span class=muted>(only in {side:?})</span>"),
        None => String::new(),
    };
    let _ = write!(
        b,
        "<h2 id=\"s-{}\">{}{only}</h2><div class=scroll><table class=compare><tr><th>variant</th><th>status A → B</th><th class=n>GPU A (ms)</th><th class=n>GPU B (ms)</th><th class=n>change [{:.0}% interval]</th><th>verdict</th><th class=n>speed-up A → B (×)</th><th>passes (change, verdict)</th><th>metrics A → B</th><th>images</th></tr>",
        esc(&s.scenario),
        esc(&s.scenario),
        c.rule.confidence * 100.0
    );
    for v in &s.variants {
        let variant = match v.only_in {
            Some(side) => format!(
                "{} <span class=muted>(only in {side:?})</span>",
                name(&v.variant)
            ),
            None => name(&v.variant),
        };
        let label = |x: &Option<String>| x.as_deref().unwrap_or("–").to_string();
        let status = if v.status.a == v.status.b {
            esc(&label(&v.status.a))
        } else {
            format!(
                "<span class={}>{} → {}</span>",
                verdict_class(v.status_verdict),
                esc(&label(&v.status.a)),
                esc(&label(&v.status.b))
            )
        };
        let class = time_class(&v.time, c.timings_count);
        let _ = write!(
            b,
            "<tr><td>{variant}</td><td>{status}</td><td class=n>{}</td><td class=n>{}</td><td class=\"n {class}\">{}</td><td class={class}>{}</td><td class=n>{}</td><td class=wrap>{}</td><td class=wrap>{}</td><td>{}</td></tr>",
            opt(v.gpu_ms.a),
            opt(v.gpu_ms.b),
            change_cell(&v.time),
            time_words(&v.time, c.rule.frames_needed) + &threshold_note(v, c),
            speedup_cell(v),
            passes_cell(&v.passes, c.timings_count),
            metrics_cell(v),
            images_cell(c, s, v),
        );
    }
    b.push_str("</table></div>");
}

/// The page body below the form: the whole comparison, or with `focus` one scenario's table.
pub fn render(c: &Comparison, focus: Option<&str>) -> String {
    let q = format!("a={}&b={}", enc(&c.a.run_id), enc(&c.b.run_id));
    let thr = if c.rule.threshold_pct == tessera_results::stats::DEFAULT_THRESHOLD_PCT {
        String::new()
    } else {
        format!("&threshold={}", c.rule.threshold_pct)
    };
    let mut b = run_line("A (base)", &c.a);
    b.push_str(&run_line("B (new)", &c.b));
    let _ = write!(
        b,
        "<p><a id=permalink href=\"/compare/runs?{q}{thr}\">permalink</a> · export <a href=\"/api/compare/runs?{q}{thr}&format=md\">Markdown</a> <a href=\"/api/compare/runs?{q}{thr}&format=csv\">CSV</a> <a href=\"/api/compare/runs?{q}{thr}\">JSON</a> · <a href=\"/compare/runs?a={}&b={}{thr}\">swap A and B</a> · {}</p>",
        enc(&c.b.run_id),
        enc(&c.a.run_id),
        // On the shown scenario, else the first regression's, else B's first.
        crate::server::ab_form::link(
            &c.a.run_id,
            &c.b.run_id,
            focus.or_else(|| c.findings_of(Verdict::Worse).next().map(|f| f.scenario.as_str()))
        ),
    );
    let _ = write!(
        b,
        "<p class=muted>Time: a Mann-Whitney U test on per-frame GPU times, the test of <code>tessera compare</code>. <em>slower</em> or <em>faster</em> when p &lt; {alpha} and the Hodges-Lehmann shift (with its {conf:.0}% interval) is at least {thr}%{noise}; <em>below threshold</em> when significant but smaller; <em>within noise</em> when p ≥ {alpha}; <em>too few frames</em> when the frame counts cannot reach p &lt; {alpha} whatever the change (it takes {need} per side). Metrics by their direction beyond a tolerance; a baseline's change is counted once, on the baseline (<code>results/COMPARISON.md</code>).</p>",
        alpha = c.rule.alpha,
        conf = c.rule.confidence * 100.0,
        thr = c.rule.threshold_pct,
        need = c.rule.frames_needed,
        noise = match c.rule.noise_sigmas {
            Some(k) => format!(
                ", or at least {k}σ of the variant's own night-to-night noise on this adapter (never below {}%; from the history before B, where it has {} points)",
                tessera_results::compare::NOISE_FLOOR_PCT,
                crate::store::noise::MIN_POINTS
            ),
            None => String::new(),
        },
    );
    if !c.same_adapter {
        b.push_str("<p class=worse>The adapters or drivers differ: times are relative to each variant's baseline in its own run (a change means its speedup changed); the baseline itself reads <em>baseline</em>.</p>");
    }
    if !c.timings_count {
        b.push_str("<p class=muted>A run is on a CPU adapter (lavapipe): its timings measure CPU work and the machine's load, so time verdicts are shown but never count as regressions.</p>");
    }
    let decision = c.decision();
    let (class, why) = match decision {
        Decision::Regressed => ("worse", String::new()),
        Decision::NoRegression => ("better", String::new()),
        // Nothing could be decided: neither red nor green.
        Decision::Inconclusive => (
            "neutral",
            format!(
                " <span id=undecided>({})</span>",
                esc(&c.undecided().join("; "))
            ),
        ),
    };
    let _ = write!(
        b,
        "<p id=verdict><strong class={class}>Verdict: {}</strong>{why} · {} · {}</p><p id=tally><span class={slow}>{} slower</span> · <span class={fast}>{} faster</span> · {} within noise · {} below threshold · {} too few frames</p>",
        decision.words(),
        plural(c.findings_of(Verdict::Worse).count(), "regression"),
        plural(c.findings_of(Verdict::Better).count(), "improvement"),
        c.count_time(TimeVerdict::Slower),
        c.count_time(TimeVerdict::Faster),
        c.count_time(TimeVerdict::WithinNoise),
        c.count_time(TimeVerdict::BelowThreshold),
        c.count_time(TimeVerdict::TooFewFrames),
        // On a CPU adapter time verdicts are shown, not counted: not in colour.
        slow = if c.timings_count { "worse" } else { "muted" },
        fast = if c.timings_count { "better" } else { "muted" },
    );
    if let Some(f) = focus {
        // One scenario of a large comparison: its table under the whole comparison's verdict.
        let _ = write!(
            b,
            "<p id=crumbs><a href=\"/compare/runs?{q}{thr}#summary\">all {} scenarios of this comparison</a></p>",
            c.scenarios.len()
        );
        match c.scenarios.iter().find(|s| s.scenario == f) {
            Some(s) => scenario_table(&mut b, c, s),
            None => {
                let _ = write!(
                    b,
                    "<p class=neutral>Neither run has scenario {}.</p>",
                    name(f)
                );
            }
        }
        return b;
    }
    findings(&mut b, c);
    let inline = c.variants().count() <= INLINE_VARIANTS;
    if c.scenarios.len() > 1 || !inline {
        summary_table(&mut b, c, &format!("{q}{thr}"), inline);
    }
    if inline {
        for s in &c.scenarios {
            scenario_table(&mut b, c, s);
        }
    }
    b
}

/// Per scenario: variants, how many slower and faster (counted where time counts), within
/// noise or below threshold, too few frames, status changes, metric changes; a link to its table.
fn summary_table(b: &mut String, c: &Comparison, query: &str, inline: bool) {
    let _ = write!(
        b,
        "<h2 id=summary>Scenarios</h2>{}<div class=scroll><table id=compare-summary><tr><th>scenario</th><th class=n>variants</th><th class=n>slower</th><th class=n>faster</th><th class=n title=\"within noise or below threshold\">same</th><th class=n>too few frames</th><th class=n title=\"status changed (ok, skipped, failed, gate failed)\">status changes</th><th>worse metrics</th></tr>",
        if inline {
            ""
        } else {
            "<p class=muted>Each scenario's table (frame time with its interval, passes, metrics, images) opens on its own page.</p>"
        }
    );
    for s in &c.scenarios {
        let n = |v: TimeVerdict| {
            s.variants
                .iter()
                .filter(|x| x.time_verdict() == Some(v))
                .count()
        };
        let href = if inline {
            format!("#s-{}", enc(&s.scenario))
        } else {
            format!("/compare/runs?{query}&scenario={}", enc(&s.scenario))
        };
        let worse_metrics: Vec<String> = s
            .variants
            .iter()
            .flat_map(|v| {
                v.metrics
                    .iter()
                    .filter(|m| m.verdict == Verdict::Worse)
                    .map(move |m| format!("{} {}", esc(&v.variant), esc(&m.name)))
            })
            .collect();
        let status = s
            .variants
            .iter()
            .filter(|v| v.status.a != v.status.b)
            .count();
        let (slow, fast) = (n(TimeVerdict::Slower), n(TimeVerdict::Faster));
        let counted = |k: usize, class: &str| {
            if k > 0 && c.timings_count {
                format!("<td class=\"n {class}\">{k}</td>")
            } else {
                format!("<td class=n>{k}</td>")
            }
        };
        let _ = write!(
            b,
            "<tr><td><a href=\"{href}\">{}</a>{}</td><td class=n>{}</td>{}{}<td class=n>{}</td><td class=n>{}</td><td class=\"n{}\">{status}</td><td>{}</td></tr>",
            name(&s.scenario),
            match s.only_in {
                Some(side) => format!(" <span class=muted>(only in {side:?})</span>"),
                None => String::new(),
            },
            s.variants.len(),
            counted(slow, "worse"),
            counted(fast, "better"),
            n(TimeVerdict::WithinNoise) + n(TimeVerdict::BelowThreshold),
            n(TimeVerdict::TooFewFrames),
            if status > 0 { " neutral" } else { "" },
            {
                let mut w = worse_metrics.iter().take(3).cloned().collect::<Vec<_>>().join(", ");
                if worse_metrics.len() > 3 {
                    let _ = write!(w, " and {} more", worse_metrics.len() - 3);
                }
                w
            }
        );
    }
    b.push_str("</table></div>");
}

/// The page body below the form, with the conditions: the environment diff beside the verdict
/// and each variant's conditions in A and B.
pub fn render_with(l: &super::query::Loaded, focus: Option<&str>) -> String {
    let mut b = render(&l.comparison, focus);
    let env = if l.environment.is_empty() {
        "<p id=environment class=muted>Conditions: the same driver and harness; clocks, temperature and throttling alike where recorded.</p>".to_string()
    } else {
        format!(
            "<p id=environment class=neutral><strong>Conditions differ:</strong> {}</p>",
            esc(&l.environment.join("; "))
        )
    };
    // Beside the verdict: right after its tally.
    match b
        .find("<p id=tally>")
        .and_then(|i| b[i..].find("</p>").map(|j| i + j + 4))
    {
        Some(at) => b.insert_str(at, &env),
        None => b.push_str(&env),
    }
    // The conditions per variant: with the scenarios' tables, not under a summary.
    if focus.is_some() || l.comparison.variants().count() <= INLINE_VARIANTS {
        b.push_str(&conditions_table(l, focus));
    }
    b
}

fn conditions_table(l: &super::query::Loaded, focus: Option<&str>) -> String {
    use crate::server::conditions_view::{cells, HEADERS};
    let any = |s: &[tessera_results::ScenarioResult]| {
        s.iter().flat_map(|s| &s.results).any(|v| {
            v.conditions
                .as_ref()
                .is_some_and(|c| c.recorded().is_some())
        })
    };
    if !any(&l.a) && !any(&l.b) {
        return String::new();
    }
    let mut out = format!(
        "<h2 id=conditions>Conditions</h2><div class=scroll><table class=conditions><tr><th>scenario</th><th>variant</th><th>run</th>{HEADERS}</tr>"
    );
    for (s, v) in l
        .comparison
        .variants()
        .filter(|(s, _)| focus.is_none_or(|f| f == s.scenario))
    {
        for (side, runs) in [("A", &l.a), ("B", &l.b)] {
            let Some(r) = runs
                .iter()
                .find(|x| x.scenario == s.scenario)
                .and_then(|x| x.results.iter().find(|r| r.variant == v.variant))
            else {
                continue;
            };
            let _ = write!(
                out,
                "<tr><td>{}</td><td>{}</td><td>{side}</td>{}</tr>",
                name(&s.scenario),
                name(&v.variant),
                cells(r)
            );
        }
    }
    out.push_str("</table></div>");
    out
}

/// The form at the top of the page.
pub fn form(q: &CompareRunsQuery) -> String {
    format!(
        "<form id=pick>A <input name=a size=28 value=\"{}\" placeholder=\"run id or commit\"> B <input name=b size=28 value=\"{}\" placeholder=\"run id or commit\"> suite <input name=suite size=10 value=\"{}\"> adapter id <input name=adapter size=4 value=\"{}\"> threshold % <input name=threshold size=4 value=\"{}\"> <button>compare</button></form>",
        esc(q.a.as_deref().unwrap_or("")),
        esc(q.b.as_deref().unwrap_or("")),
        esc(q.suite.as_deref().unwrap_or("")),
        q.adapter.map_or(String::new(), |a| a.to_string()),
        q.threshold
    )
}
