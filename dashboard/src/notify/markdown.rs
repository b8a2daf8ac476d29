//! A group as Markdown (GitHub-flavoured table), for a bot to paste into a pull request or an
//! issue: title, commits, triage, a link back, and one row per series, largest change first.
//! Not for: HTML (see [`crate::server::regressions`]).

use std::fmt::Write;

use crate::html::{commit, num, pct};
use crate::store::alerts::Alert;
use crate::store::groups::Group;
use crate::titles::group_title;

/// Most series rows written; the rest are counted.
pub const MAX_ROWS: usize = 50;

/// Text safe as Markdown: every character Markdown or a table gives a meaning to is escaped
/// with a backslash (pipes, backticks, emphasis, links, headings, HTML), line breaks are spaces.
pub fn text(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '\n' | '\r' => out.push(' '),
            '\\' | '`' | '*' | '_' | '{' | '}' | '[' | ']' | '(' | ')' | '#' | '+' | '-' | '!'
            | '|' | '<' | '>' | '~' | '&' => {
                out.push('\\');
                out.push(c);
            }
            c => out.push(c),
        }
    }
    out
}

/// Text safe inside a table cell.
fn cell(s: &str) -> String {
    text(s)
}

/// Text safe inside backticks (and a table cell): backticks and pipes cannot be escaped in a
/// code span, so they are replaced.
fn code(s: &str) -> String {
    format!(
        "`{}`",
        s.replace('`', "'")
            .replace('|', "¦")
            .replace(['\n', '\r'], " ")
    )
}

/// The Markdown of group `g`; links are absolute under `base`.
pub fn render(g: &Group, base: &str) -> String {
    let live: Vec<&Alert> = g
        .alerts
        .iter()
        .filter(|a| a.status != "withdrawn")
        .collect();
    let shown: Vec<&Alert> = if live.is_empty() {
        g.alerts.iter().collect()
    } else {
        live
    };
    let mut out = String::new();
    let _ = writeln!(
        out,
        "### Regression group {}\n",
        group_title(&commit(g.commit_after.as_deref()), &shown, true).replace('\n', " ")
    );
    let _ = writeln!(
        out,
        "Commits {} → {} · state **{}**{} · {} · {} · {} worse, {} better{} · [dashboard]({})\n",
        code(&commit(g.commit_before.as_deref())),
        code(&commit(g.commit_after.as_deref())),
        g.state,
        if g.mixed_state { " (mixed)" } else { "" },
        g.status,
        g.direction,
        g.worse,
        g.better,
        if g.via_baseline > 0 {
            format!(", {} through their baseline", g.via_baseline)
        } else {
            String::new()
        },
        super::group_url(base, g.id)
    );
    if !g.note.is_empty() || !g.bug_url.is_empty() {
        let mut line = String::new();
        if !g.note.is_empty() {
            let _ = write!(line, "Note: {}", text(&g.note));
        }
        if !g.bug_url.is_empty() {
            if !line.is_empty() {
                line.push_str(" · ");
            }
            let _ = write!(
                line,
                "Bug: <{}>",
                g.bug_url.replace('<', "%3C").replace('>', "%3E")
            );
        }
        if !g.updated_by.is_empty() {
            let _ = write!(
                line,
                " (set by {} at {})",
                text(&g.updated_by),
                text(&g.updated_at)
            );
        }
        let _ = writeln!(out, "{line}\n");
    }
    out.push_str(
        "| change | adapter | suite | scenario | variant | measure | before | after | series |\n",
    );
    out.push_str("|---:|---|---|---|---|---|---:|---:|---|\n");
    for a in shown.iter().take(MAX_ROWS) {
        let _ = writeln!(
            out,
            "| {} {} {} | {} | {} | {} | {} | {} | {} | {} | [chart]({base}/series/{}) |",
            if a.relative_change >= 0.0 {
                "▲"
            } else {
                "▼"
            },
            pct(a.relative_change),
            if a.via_baseline {
                "via baseline"
            } else if a.is_regression {
                "worse"
            } else {
                "better"
            },
            cell(&a.series.adapter),
            cell(&a.suite),
            cell(&a.series.scenario),
            code(&a.series.variant),
            code(&a.series.measure),
            num(a.value_before),
            num(a.value_after),
            a.series.id
        );
    }
    if shown.len() > MAX_ROWS {
        let _ = writeln!(
            out,
            "\n…and {} more series on the dashboard.",
            shown.len() - MAX_ROWS
        );
    }
    out
}
