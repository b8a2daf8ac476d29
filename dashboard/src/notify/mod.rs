//! Notifications of confirmed alert groups: an Atom feed ([`atom`]), a Markdown rendering of a
//! group that a bot can paste into a pull request or issue ([`markdown`]), and a webhook worker
//! that POSTs each newly confirmed group once ([`webhook`]).
//!
//! Not for: grouping (see [`crate::store::groups`]) or the pages (see [`crate::server`]).

pub mod atom;
pub mod markdown;
pub mod webhook;

use crate::html::enc;

/// The group's page, absolute under `base` (the dashboard's public URL, no trailing slash).
pub fn group_url(base: &str, key: &str) -> String {
    format!("{base}/regressions/groups/{}", enc(key))
}

/// The group's Markdown, absolute under `base`.
pub fn markdown_url(base: &str, key: &str) -> String {
    format!("{}.md", group_url(base, key))
}
