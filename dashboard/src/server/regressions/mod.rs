//! Regressions, triaged by change: `/regressions` lists alert groups (the alerts of one change,
//! see [`crate::store::groups`]) with their series, filters (adapter, suite, measure, state,
//! direction, status) and sorting (date, size), and one triage form per group.
//! `/regressions/groups/{id}` shows one group with a chart per series and the history of its
//! alerts (moves with their reason), `{id}.md` is its Markdown; a commit-range key the group is
//! or was shown under (`/regressions/groups/c0ffee..beef42`) redirects to its id, so links already
//! sent keep answering. JSON: `GET /api/regressions/groups`, `GET /api/regressions/groups/{id}`,
//! triage `POST /api/regressions/groups/{id}` (`{"state", "note", "bug_url"}`, bearer token).
//!
//! Split by job: [`pages`] (HTML and its forms), [`api`] (JSON), [`feed`] (Atom), [`formats`]
//! (Markdown and one-line summaries). The write token is entered once per browser session: the
//! script `/assets/regressions.js` keeps it in `sessionStorage` and sends it as
//! `Authorization: Bearer`. Without JavaScript the pages still show everything, and each form
//! takes the token as a field instead. The flat per-alert API (`/api/regressions`, `POST
//! /api/regressions/{id}`, `POST /regressions/{id}`) is kept.

mod api;
mod feed;
pub(crate) mod formats;
mod pages;

pub use api::{api, group_api, group_triage_api, groups_api, triage_api, RegressionsQuery};
pub use feed::{feed, FeedQuery};
pub use formats::summary;
pub use pages::{group_form, group_page, page, render, render_group, triage_form};

use axum::http::{header, HeaderMap};
use serde::Deserialize;

use super::{auth, AppError, AppState};
use crate::store::groups::{self, Facets, Filter, Group, Named, Sort};

/// Filters and sorting of the page and `GET /api/regressions/groups`; empty values mean "all".
#[derive(Debug, Deserialize, Default, Clone)]
pub struct GroupsQuery {
    pub adapter: Option<String>,
    pub suite: Option<String>,
    pub measure: Option<String>,
    pub state: Option<String>,
    pub direction: Option<String>,
    pub status: Option<String>,
    pub sort: Option<String>,
    pub limit: Option<usize>,
}

fn non_empty(s: &Option<String>) -> Option<String> {
    s.as_ref()
        .map(|s| s.trim())
        .filter(|s| !s.is_empty())
        .map(str::to_string)
}

impl GroupsQuery {
    fn parse(&self) -> Result<(Filter, Sort, usize), AppError> {
        let adapter = match non_empty(&self.adapter) {
            Some(a) => Some(a.parse::<i64>().map_err(|_| {
                AppError::BadRequest(format!("adapter must be an adapter id, not {a:?}"))
            })?),
            None => None,
        };
        let filter = Filter {
            adapter,
            suite: non_empty(&self.suite),
            measure: non_empty(&self.measure),
            state: non_empty(&self.state),
            direction: non_empty(&self.direction),
            status: non_empty(&self.status),
            regressions_only: false,
        };
        filter
            .validate()
            .map_err(|e| AppError::BadRequest(e.to_string()))?;
        let sort = Sort::parse(non_empty(&self.sort).as_deref())
            .map_err(|e| AppError::BadRequest(e.to_string()))?;
        Ok((filter, sort, self.limit.unwrap_or(200).clamp(1, 2000)))
    }
}

async fn load_groups(state: &AppState, q: &GroupsQuery) -> Result<(Vec<Group>, Facets), AppError> {
    let (filter, sort, limit) = q.parse()?;
    state
        .db(move |c| Ok(groups::list_with_facets(c, &filter, sort, limit)?))
        .await
}

/// The group `name` (an id, or a key it is or was shown under) refers to.
async fn resolve(state: &AppState, name: String) -> Result<Named, AppError> {
    state.db(move |c| Ok(groups::resolve(c, &name)?)).await
}

async fn load_group(state: &AppState, id: i64) -> Result<Group, AppError> {
    state.db(move |c| Ok(groups::get(c, id)?)).await
}

/// The dashboard's public URL: `--public-url`, else `http://` and the request's `Host`.
pub fn base_url(state: &AppState, headers: &HeaderMap) -> String {
    if let Some(u) = &state.public_url {
        return u.trim_end_matches('/').to_string();
    }
    let host = headers
        .get(header::HOST)
        .and_then(|h| h.to_str().ok())
        .filter(|h| {
            h.bytes()
                .all(|b| b.is_ascii_alphanumeric() || b"-.:[]".contains(&b))
        })
        .unwrap_or("localhost");
    format!("http://{host}")
}

/// Who is changing triage, as recorded in `updated_by`: the write token's name (`legacy` for
/// `--token`).
pub fn writer(state: &AppState, headers: &HeaderMap) -> Result<String, AppError> {
    Ok(auth::require(state, headers, auth::Scope::Write)?.name)
}
