//! What the interactive charts are drawn from: the JSON specs that `assets/tessera.js` turns into
//! uPlot canvas charts. Series are aligned on one x axis of runs (time, or commit order), with
//! `null` where a series has no point; markers stand for environment segments and change points.
//!
//! Not for: drawing (the browser does that; the server-side SVG fallback is in [`crate::svg`]).

use serde::Serialize;

use crate::store::browse::{parse_time, BandPoint};

/// One line of a time chart.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Line {
    pub label: String,
    pub color: String,
    pub values: Vec<Option<f64>>,
    /// The p5-p95 band, where every point of the line has one.
    pub p5: Option<Vec<Option<f64>>>,
    pub p95: Option<Vec<Option<f64>>>,
}

/// A vertical marker at row `at`.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Mark {
    pub at: usize,
    /// `segment` (the environment changed) or `change` (a detected change point).
    pub kind: &'static str,
    pub label: String,
    /// Drawn beside the marker.
    pub short: String,
}

/// A chart over runs: `x` (seconds since the epoch), `commits` and `runs` per row.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct TimeChart {
    pub kind: &'static str,
    pub y_label: String,
    pub log: bool,
    pub x: Vec<i64>,
    pub commits: Vec<String>,
    pub runs: Vec<String>,
    pub series: Vec<Line>,
    pub marks: Vec<Mark>,
}

/// Builds a chart from several series' points: rows are the union of their runs in start-time
/// order. Returns the chart and, per input series, the row of each of its points.
pub fn time_chart(
    y_label: &str,
    lines: &[(String, String, &[BandPoint])],
) -> (TimeChart, Vec<Vec<usize>>) {
    let mut rows: Vec<(i64, String, String)> = Vec::new();
    for (_, _, pts) in lines {
        for p in pts.iter() {
            rows.push((
                parse_time(&p.started_at).unwrap_or(0),
                p.run_id.clone(),
                crate::html::commit(p.commit.as_deref()),
            ));
        }
    }
    rows.sort();
    rows.dedup_by(|a, b| a.1 == b.1);
    let index: std::collections::HashMap<&str, usize> = rows
        .iter()
        .enumerate()
        .map(|(i, r)| (r.1.as_str(), i))
        .collect();
    let mut at = Vec::new();
    let mut series = Vec::new();
    for (label, color, pts) in lines {
        let mut values = vec![None; rows.len()];
        let mut p5 = vec![None; rows.len()];
        let mut p95 = vec![None; rows.len()];
        let mut mine = Vec::with_capacity(pts.len());
        for p in pts.iter() {
            let i = index[p.run_id.as_str()];
            values[i] = Some(p.value);
            p5[i] = p.p5;
            p95[i] = p.p95;
            mine.push(i);
        }
        let banded = pts.iter().all(|p| p.p5.is_some() && p.p95.is_some()) && !pts.is_empty();
        series.push(Line {
            label: label.clone(),
            color: color.clone(),
            values,
            p5: banded.then_some(p5),
            p95: banded.then_some(p95),
        });
        at.push(mine);
    }
    let x = rows.iter().map(|r| r.0).collect();
    let runs = rows.iter().map(|r| r.1.clone()).collect();
    let commits = rows.into_iter().map(|r| r.2).collect();
    (
        TimeChart {
            kind: "time",
            y_label: y_label.to_string(),
            log: false,
            x,
            commits,
            runs,
            series,
            marks: Vec::new(),
        },
        at,
    )
}

/// One point of an error-against-time chart.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ScatterPoint {
    pub x: f64,
    pub y: f64,
    /// Index into `groups`.
    pub group: usize,
    /// The row number in the table beside the chart; `None` for a point with no row there (a
    /// variant only the older run has), which the chart leaves unnumbered.
    pub num: Option<usize>,
    pub label: String,
    pub front: bool,
    /// The point's colour (by technique on the error-against-time page).
    pub colour: String,
    /// Error bars: 95% intervals of x and y, where the result has repeats.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub x_interval: Option<[f64; 2]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub y_interval: Option<[f64; 2]>,
}

#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ScatterChart {
    pub kind: &'static str,
    pub x_label: String,
    pub y_label: String,
    pub groups: Vec<String>,
    pub points: Vec<ScatterPoint>,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pt(run: &str, minute: u64, v: f64) -> BandPoint {
        BandPoint {
            run_id: run.into(),
            commit: Some(format!("{minute:040x}")),
            started_at: crate::synth::time_after(minute),
            environment: "e".into(),
            value: v,
            p5: Some(v - 1.0),
            p95: Some(v + 1.0),
        }
    }

    #[test]
    fn lines_are_aligned_on_the_union_of_runs() {
        let a = [pt("r1", 1, 10.0), pt("r3", 3, 30.0)];
        let b = [pt("r2", 2, 20.0), pt("r3", 3, 31.0)];
        let (c, at) = time_chart(
            "ms",
            &[
                ("a".into(), "#000".into(), &a[..]),
                ("b".into(), "#111".into(), &b[..]),
            ],
        );
        assert_eq!(c.runs, ["r1", "r2", "r3"]);
        assert_eq!(c.series[0].values, [Some(10.0), None, Some(30.0)]);
        assert_eq!(c.series[1].values, [None, Some(20.0), Some(31.0)]);
        assert_eq!(c.series[1].p95.as_ref().unwrap()[1], Some(21.0));
        assert_eq!(at, [vec![0, 2], vec![1, 2]]);
        assert_eq!(c.x[1] - c.x[0], 60);
    }
}
