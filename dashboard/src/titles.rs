//! What an alert group is called: the one-line title its page, the regressions list, the JSON
//! API, the Atom feed, the webhook and the Markdown export show ("`c0ffee`: 12 series on 2
//! adapters; checkerboard gpu_ms +6.0%, reconstruct +35.0%"), made from the group the store
//! read ([`crate::store::groups::Group`]'s `basis`).
//!
//! Not for: grouping, counting or triage (see [`crate::store::groups`]).

use std::collections::{BTreeMap, BTreeSet};

use serde::Serialize;
use tessera_results::measure::Measure;

use crate::store::alerts::Alert;
use crate::store::baseline_moves;
use crate::store::groups::Group;

/// A group as the JSON API sends it: its title, then the group's fields.
#[derive(Clone, Debug, Serialize)]
pub struct Titled {
    pub title: String,
    #[serde(flatten)]
    pub group: Group,
}

/// `g` with its title, for the JSON API.
pub fn titled(g: Group) -> Titled {
    Titled {
        title: of(&g),
        group: g,
    }
}

/// The group's title as pages, the API, the feed and the webhook show it.
pub fn of(g: &Group) -> String {
    let basis: Vec<&Alert> = g.basis.iter().collect();
    group_title(
        &crate::html::commit(g.commit_after.as_deref()),
        &basis,
        false,
    )
}

/// The short name of a measure in a title: `gpu_ms`, a pass name, a metric.
pub fn measure_label(measure: &str) -> &str {
    // The parts of the key are the measure table's (`tessera_results::measure::Key`): a pass's GPU
    // time is named by its pass, a median by its measure.
    match tessera_results::measure::Key::parse(measure) {
        Some(k)
            if k.measure == Measure::GpuMs && k.pass.is_some() && k.statistic == Some("median") =>
        {
            let pass = k.pass.as_deref().unwrap_or_default();
            &measure["pass.".len().."pass.".len() + pass.len()]
        }
        Some(k) if k.pass.is_none() && k.statistic == Some("median") => k.measure.name(),
        _ => measure,
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    }
}

/// How surely an alert shows a change: its size over the half-width of its 95% interval, times
/// the probability that it lies at the located commit. Orders a title's variants.
fn lead_score(a: &Alert) -> f64 {
    let half = match (a.change_low, a.change_high) {
        (Some(l), Some(h)) if h > l => (h - l) / 2.0,
        _ => 0.0,
    };
    let size = a.relative_change.abs().min(1e6);
    let z = if half > 0.0 { size / half } else { size * 1e3 };
    z * a.location_probability.unwrap_or(1.0)
}

/// The group's one-line title. With `code`, names are wrapped in backticks (Markdown).
pub fn title(commit_after: &str, alerts: &[&Alert], code: bool) -> String {
    counted_title(commit_after, alerts, alerts, code)
}

/// The title naming the changes of `alerts`, with the series and adapters of `all` counted (so
/// the HTML and the Markdown of a group count the same series).
fn counted_title(commit_after: &str, alerts: &[&Alert], all: &[&Alert], code: bool) -> String {
    // In Markdown, names are code spans, in which nothing can be escaped: backticks and pipes
    // are replaced (names are validated on upload; older stores may hold anything).
    let q = |s: &str| {
        if code {
            format!(
                "`{}`",
                s.replace('`', "'")
                    .replace('|', "¦")
                    .replace(['\n', '\r'], " ")
            )
        } else {
            s.to_string()
        }
    };
    let adapters: BTreeSet<&str> = all.iter().map(|a| a.series.adapter.as_str()).collect();
    let mut t = format!(
        "{}: {} series on {} adapter{}",
        q(commit_after),
        all.len(),
        adapters.len(),
        if adapters.len() == 1 { "" } else { "s" }
    );
    // Per variant, its measures with the median change over scenarios and adapters.
    let mut by_variant: BTreeMap<&str, BTreeMap<&str, Vec<f64>>> = BTreeMap::new();
    let mut scenarios: BTreeMap<&str, BTreeSet<&str>> = BTreeMap::new();
    // The variant whose change leads: the surest one, not the largest (a noisy adapter's
    // +40% located at 58% must not lead a group whose real change is a quiet GPU's exact +5%).
    let mut lead: BTreeMap<&str, f64> = BTreeMap::new();
    for a in alerts {
        let e = lead.entry(&a.series.variant).or_insert(0.0);
        *e = e.max(lead_score(a));
    }
    for a in alerts {
        by_variant
            .entry(&a.series.variant)
            .or_default()
            .entry(measure_label(&a.series.measure))
            .or_default()
            .push(a.relative_change);
        scenarios
            .entry(&a.series.variant)
            .or_default()
            .insert(&a.series.scenario);
    }
    let mut parts: Vec<(f64, String)> = by_variant
        .into_iter()
        .map(|(variant, measures)| {
            let mut ms: Vec<(f64, &str)> =
                measures.into_iter().map(|(m, v)| (median(v), m)).collect();
            ms.sort_by(|x, y| y.0.abs().total_cmp(&x.0.abs()).then(x.1.cmp(y.1)));
            let largest = lead.get(variant).copied().unwrap_or(0.0);
            let shown: Vec<String> = ms
                .iter()
                .take(2)
                .map(|(v, m)| format!("{} {}", q(m), crate::html::pct(*v)))
                .collect();
            let more = if ms.len() > 2 {
                format!(" and {} more", ms.len() - 2)
            } else {
                String::new()
            };
            let on = match scenarios.get(variant) {
                Some(s) if s.len() == 1 => format!(" on {}", q(s.iter().next().unwrap())),
                _ => String::new(),
            };
            (
                largest,
                format!("{} {}{more}{on}", q(variant), shown.join(", ")),
            )
        })
        .collect();
    parts.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
    for (i, (_, p)) in parts.iter().enumerate() {
        if i == 3 {
            t.push_str(&format!("; {} more variants", parts.len() - 3));
            break;
        }
        t.push_str("; ");
        t.push_str(p);
    }
    t
}

/// The title of a group whose only changes are speed-ups that moved with their baseline (the
/// baseline's own alert not detected yet, or in another group): led by the baseline's change.
fn baseline_title(commit_after: &str, alerts: &[&Alert], code: bool) -> Option<String> {
    let q = |s: &str| {
        if code {
            format!("`{s}`")
        } else {
            s.to_string()
        }
    };
    // (baseline, scenario) → (the baseline's changes, the variants whose speed-ups moved).
    type Moved<'a> = BTreeMap<(&'a str, &'a str), (Vec<f64>, BTreeSet<&'a str>)>;
    let mut by_base: Moved = BTreeMap::new();
    for a in alerts {
        let m = a.moved_with_change?;
        let base = baseline_moves::baseline_of(&a.series.measure)?;
        let e = by_base.entry((base, &a.series.scenario)).or_default();
        e.0.push(m);
        e.1.insert(&a.series.variant);
    }
    let adapters: BTreeSet<&str> = alerts.iter().map(|a| a.series.adapter.as_str()).collect();
    let mut parts: Vec<(f64, String)> = by_base
        .into_iter()
        .map(|((base, scenario), (changes, variants))| {
            let m = median(changes);
            (
                m.abs(),
                format!(
                    "{} GPU time {} on {} (the speed-ups of {} moved with it)",
                    q(base),
                    crate::html::pct(m),
                    q(scenario),
                    variants.into_iter().map(q).collect::<Vec<_>>().join(", ")
                ),
            )
        })
        .collect();
    parts.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
    let lead = parts
        .into_iter()
        .map(|p| p.1)
        .collect::<Vec<_>>()
        .join("; ");
    Some(format!(
        "{}: {} series on {} adapter{}; {lead}",
        q(commit_after),
        alerts.len(),
        adapters.len(),
        if adapters.len() == 1 { "" } else { "s" }
    ))
}

/// The one-line title of a group's alerts: led by the changes of their own, else by the
/// baseline change the speed-ups moved with.
pub fn group_title(commit_after: &str, basis: &[&Alert], code: bool) -> String {
    let own: Vec<&Alert> = basis.iter().copied().filter(|a| !a.via_baseline).collect();
    if own.is_empty() {
        if let Some(t) = baseline_title(commit_after, basis, code) {
            return t;
        }
        return title(commit_after, basis, code);
    }
    counted_title(commit_after, &own, basis, code)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn measure_labels() {
        assert_eq!(measure_label("gpu_ms.median"), "gpu_ms");
        assert_eq!(
            measure_label("pass.reconstruct.gpu_ms.median"),
            "reconstruct"
        );
        assert_eq!(measure_label("flip"), "flip");
        assert_eq!(measure_label("pass.a.b.gpu_ms.median"), "a.b");
        assert_eq!(
            measure_label("not-a-measure.median"),
            "not-a-measure.median"
        );
    }
}
