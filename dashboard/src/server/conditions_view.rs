//! The conditions a run's timings were taken in, as pages show them: per variant the graphics
//! and memory clocks, temperature, power, energy per frame and whether it was throttled
//! (`tessera_results::conditions`, recorded by the harness from NVML or hwmon), and for two runs
//! what differs between them (driver, harness, clocks, throttling): the environment diff the
//! compare page shows beside its verdict.
//!
//! Not for: judging timings (the comparison engine) or sampling sensors (the harness).

use std::fmt::Write;

use tessera_results::conditions::{RecordedConditions, Spread};
use tessera_results::{RunInfo, ScenarioResult, VariantResult};

use crate::html::{esc, name};

/// A graphics clock that differs by more than this fraction between two runs is a difference.
pub const CLOCK_DIFFERS: f64 = 0.05;
/// A temperature that differs by more than this many °C is a difference.
pub const TEMPERATURE_DIFFERS_C: f64 = 10.0;

fn recorded(v: &VariantResult) -> Option<&RecordedConditions> {
    v.conditions.as_ref()?.recorded()
}

/// `1980 (1965–1995)`, or the median alone when the spread is within rounding.
fn spread(s: Option<Spread>, digits: usize) -> String {
    match s {
        Some(s) if (s.max - s.min).abs() < 0.5 * 10f64.powi(-(digits as i32)) => {
            format!("{:.digits$}", s.median)
        }
        Some(s) => format!(
            "{:.digits$} <span class=muted>({:.digits$}–{:.digits$})</span>",
            s.median, s.min, s.max
        ),
        None => "–".into(),
    }
}

/// Header cells of the conditions columns, units in the headers.
pub const HEADERS: &str = "<th class=n>graphics clock (MHz)</th><th class=n>memory clock (MHz)</th><th class=n>temperature (°C)</th><th class=n>power (W)</th><th class=n>energy per frame (mJ)</th><th>throttled</th>";

/// The conditions cells of one variant (six cells), `–` where nothing was recorded.
pub fn cells(v: &VariantResult) -> String {
    let Some(c) = recorded(v) else {
        let why = match &v.conditions {
            Some(tessera_results::conditions::Conditions::NotAvailable { reason }) => {
                format!(" title=\"{}\"", esc(reason))
            }
            _ => String::new(),
        };
        return format!("<td class=n{why}>–</td>").repeat(5) + "<td>–</td>";
    };
    let throttled = if c.throttled {
        format!(
            "<span class=worse title=\"{}\">yes</span>",
            esc(&c.throttle_causes.join("; "))
        )
    } else {
        "no".into()
    };
    format!(
        "<td class=n>{}</td><td class=n>{}</td><td class=n>{}</td><td class=n>{}</td><td class=n>{}</td><td>{throttled}</td>",
        spread(c.graphics_clock_mhz, 0),
        spread(c.memory_clock_mhz, 0),
        spread(c.temperature_c, 0),
        spread(c.power_w, 0),
        c.energy
            .map_or("–".into(), |e| format!("{:.2}", e.mj_per_frame)),
    )
}

/// The run page's conditions table of a scenario; empty when no variant recorded any.
pub fn table(s: &ScenarioResult) -> String {
    if !s.results.iter().any(|v| recorded(v).is_some()) {
        return String::new();
    }
    let mut out = format!(
        "<details class=conditions open><summary>Conditions during the measured frames (median, min–max)</summary><div class=scroll><table class=conditions><tr><th>variant</th>{HEADERS}</tr>"
    );
    for v in &s.results {
        let _ = write!(out, "<tr><td>{}</td>{}</tr>", name(&v.variant), cells(v));
    }
    out.push_str("</table></div></details>");
    out
}

/// Median over the variants of both runs' median graphics clock, temperature; throttled counts.
struct Summary {
    clock: Option<f64>,
    temperature: Option<f64>,
    throttled: usize,
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[v.len() / 2])
}

fn summary(scenarios: &[ScenarioResult]) -> Summary {
    let all: Vec<&RecordedConditions> = scenarios
        .iter()
        .flat_map(|s| s.results.iter().filter_map(recorded))
        .collect();
    Summary {
        clock: median(
            all.iter()
                .filter_map(|c| c.graphics_clock_mhz.map(|s| s.median))
                .collect(),
        ),
        temperature: median(
            all.iter()
                .filter_map(|c| c.temperature_c.map(|s| s.median))
                .collect(),
        ),
        throttled: all.iter().filter(|c| c.throttled).count(),
    }
}

/// What differs between the conditions of run A and run B, one phrase each: adapter, driver,
/// harness, graphics clock, temperature, throttling. Empty when nothing does.
pub fn differences(
    a: &RunInfo,
    sa: &[ScenarioResult],
    b: &RunInfo,
    sb: &[ScenarioResult],
) -> Vec<String> {
    let mut out = Vec::new();
    if a.adapter.name != b.adapter.name {
        out.push(format!("adapter {} → {}", a.adapter.name, b.adapter.name));
    }
    let driver = |r: &RunInfo| format!("{} {}", r.adapter.driver, r.adapter.driver_info);
    if driver(a) != driver(b) {
        out.push(format!("driver {} → {}", driver(a), driver(b)));
    }
    if a.harness_version != b.harness_version {
        out.push(format!(
            "harness {} → {}",
            a.harness_version, b.harness_version
        ));
    }
    let (x, y) = (summary(sa), summary(sb));
    if let (Some(ca), Some(cb)) = (x.clock, y.clock) {
        if ca > 0.0 && ((cb - ca) / ca).abs() > CLOCK_DIFFERS {
            out.push(format!(
                "graphics clock {ca:.0} → {cb:.0} MHz ({:+.0}%, median over variants)",
                (cb - ca) / ca * 100.0
            ));
        }
    }
    if let (Some(ta), Some(tb)) = (x.temperature, y.temperature) {
        if (tb - ta).abs() > TEMPERATURE_DIFFERS_C {
            out.push(format!("temperature {ta:.0} → {tb:.0} °C"));
        }
    }
    if x.throttled != y.throttled {
        out.push(format!(
            "throttled variants {} → {}",
            x.throttled, y.throttled
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spreads_are_written_with_their_range_only_when_it_is_one() {
        let s = |min, median, max| Some(Spread { min, median, max });
        assert_eq!(spread(s(3201.0, 3201.0, 3201.0), 0), "3201");
        assert_eq!(
            spread(s(1965.0, 1980.0, 1995.0), 0),
            "1980 <span class=muted>(1965–1995)</span>"
        );
        assert_eq!(spread(None, 0), "–");
    }
}
