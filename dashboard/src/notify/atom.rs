//! The Atom 1.0 feed (RFC 4287) of confirmed alert groups, newest detection first: each entry
//! has the group page as its id and link, the Markdown as a second link, the time its newest
//! alert was detected as `updated`, and triage in its summary and category.
//! Not for: choosing the groups (the caller does).

use std::fmt::Write;

use crate::store::groups::Group;
use crate::store::stoppage::Stoppage;

/// Escapes text for XML content and attribute values.
pub fn xml(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            // Characters XML 1.0 does not allow at all.
            c if (c as u32) < 0x20 && !matches!(c, '\t' | '\n' | '\r') => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

/// The feed of `groups` (already chosen and ordered); links absolute under `base`. `now` is
/// the feed's `updated` when it has no entries.
pub fn feed(groups: &[Group], base: &str, now: &str) -> String {
    feed_with_stoppages(groups, &[], base, now)
}

/// When a stoppage began: its newest run's time plus its usual gap and one night.
fn stopped_at(s: &Stoppage) -> String {
    chrono::DateTime::parse_from_rfc3339(&s.last_at)
        .map(|t| {
            (t + chrono::Duration::days(s.usual_gap + 1))
                .with_timezone(&chrono::Utc)
                .to_rfc3339_opts(chrono::SecondsFormat::Secs, true)
        })
        .unwrap_or_else(|_| s.last_at.clone())
}

/// The feed of `groups` with an entry per data stoppage before them (its id names the adapter,
/// the suite and the newest run, so a reader shows it once per silence).
pub fn feed_with_stoppages(
    groups: &[Group],
    stopped: &[Stoppage],
    base: &str,
    now: &str,
) -> String {
    let updated = groups
        .iter()
        .map(|g| g.detected_at.as_str())
        .max()
        .unwrap_or(now);
    let self_url = format!("{base}/regressions/feed.atom");
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n");
    let _ = write!(
        out,
        "<feed xmlns=\"http://www.w3.org/2005/Atom\">\n<id>{}</id>\n<title>Tessera: confirmed regressions by change</title>\n<updated>{}</updated>\n<author><name>tessera-dashboard</name></author>\n<generator>tessera-dashboard</generator>\n<link rel=\"self\" type=\"application/atom+xml\" href=\"{}\"/>\n<link rel=\"alternate\" type=\"text/html\" href=\"{}\"/>\n",
        xml(&self_url),
        xml(updated),
        xml(&self_url),
        xml(&format!("{base}/regressions"))
    );
    for x in stopped {
        let url = format!("{base}/regressions#stoppages");
        let id = format!(
            "{base}/regressions/stoppages/{}/{}/{}",
            x.adapter_id, x.suite, x.last_run
        );
        let _ = write!(
            out,
            "<entry>\n<id>{}</id>\n<title>{}</title>\n<updated>{}</updated>\n<link rel=\"alternate\" type=\"text/html\" href=\"{}\"/>\n<category term=\"data-stoppage\"/>\n<summary type=\"text\">{}</summary>\n</entry>\n",
            xml(&id),
            xml(&x.message),
            xml(&stopped_at(x)),
            xml(&url),
            xml(&format!("last run {} at {}", x.last_run, x.last_at))
        );
    }
    for g in groups {
        let url = super::group_url(base, g.id);
        let summary = format!(
            "{} · {}{} · {} worse, {} better · {}{}",
            g.status,
            g.state,
            if g.mixed_state { " (mixed)" } else { "" },
            g.worse,
            g.better,
            g.adapters.join(", "),
            if g.note.is_empty() {
                String::new()
            } else {
                format!(" · note: {}", g.note)
            }
        );
        let _ = write!(
            out,
            "<entry>\n<id>{}</id>\n<title>{}</title>\n<updated>{}</updated>\n<link rel=\"alternate\" type=\"text/html\" href=\"{}\"/>\n<link rel=\"alternate\" type=\"text/markdown\" href=\"{}\"/>\n<category term=\"{}\"/>\n<summary type=\"text\">{}</summary>\n</entry>\n",
            xml(&url),
            xml(&crate::titles::of(g)),
            xml(&g.detected_at),
            xml(&url),
            xml(&super::markdown_url(base, g.id)),
            xml(g.state.as_str()),
            xml(&summary)
        );
    }
    out.push_str("</feed>\n");
    out
}
