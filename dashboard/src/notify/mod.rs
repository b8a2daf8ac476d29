//! Notifications of confirmed alert groups: an Atom feed ([`atom`]), a Markdown rendering of a
//! group that a bot can paste into a pull request or issue ([`markdown`]), and a webhook worker
//! that POSTs each newly confirmed group once ([`webhook`]). Only groups in which some series got
//! worse on its own are announced as regressions (improvements never are).
//!
//! Not for: grouping (see [`crate::store::groups`]) or the pages (see [`crate::server`]).

pub mod atom;
pub mod markdown;
pub mod webhook;

/// The group's page, absolute under `base` (the dashboard's public URL, no trailing slash): by
/// its id, which it keeps for life, so a link sent once keeps answering.
pub fn group_url(base: &str, id: i64) -> String {
    format!("{base}/regressions/groups/{id}")
}

/// The group's Markdown, absolute under `base`.
pub fn markdown_url(base: &str, id: i64) -> String {
    format!("{}.md", group_url(base, id))
}
