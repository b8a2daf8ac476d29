//! The compare request: `a` and `b` (run ids, or commits of at least 4 hex digits resolved to the
//! newest run of that commit on `adapter` and in `suite` when given), or two `pick`s (the runs
//! list's tick boxes, the older is A), `threshold` (percent, 5 by default), `format` and `scenario`
//! (one scenario's table of a large comparison); and the
//! comparison of the two runs it names, read from the store.
//!
//! Not for: presenting the comparison ([`super::view`], [`super::formats`]).

use std::sync::Arc;

use tessera_results::compare::{self, Comparison, Options, RunRef};
use tessera_results::stats::DEFAULT_THRESHOLD_PCT;

use crate::server::conditions_view;
use crate::server::export::Format;
use crate::server::{AppError, AppState};
use crate::store::browse;
use crate::store::read;

/// The request, parsed from the query string (`pick` may repeat).
#[derive(Debug, Default, Clone)]
pub struct CompareRunsQuery {
    pub a: Option<String>,
    pub b: Option<String>,
    pub adapter: Option<i64>,
    pub suite: Option<String>,
    pub threshold: f64,
    pub format: Format,
    pub picks: Vec<String>,
    /// One scenario's table of a large comparison (the page shows a summary otherwise).
    pub scenario: Option<String>,
}

pub fn parse(raw: Option<&str>) -> Result<CompareRunsQuery, AppError> {
    let pairs: Vec<(String, String)> = serde_urlencoded::from_str(raw.unwrap_or(""))
        .map_err(|e| AppError::BadRequest(format!("bad query: {e}")))?;
    let mut q = CompareRunsQuery {
        threshold: DEFAULT_THRESHOLD_PCT,
        ..Default::default()
    };
    for (k, v) in pairs {
        let v = v.trim().to_string();
        if v.is_empty() {
            continue;
        }
        match k.as_str() {
            "a" => q.a = Some(v),
            "b" => q.b = Some(v),
            "pick" => q.picks.push(v),
            "suite" => q.suite = Some(v),
            "scenario" => q.scenario = Some(v),
            "adapter" => {
                q.adapter = Some(v.parse().map_err(|_| {
                    AppError::BadRequest(format!("adapter must be an id, not {v:?}"))
                })?)
            }
            "threshold" => {
                q.threshold = v
                    .parse()
                    .ok()
                    .filter(|t: &f64| t.is_finite() && *t >= 0.0)
                    .ok_or_else(|| {
                        AppError::BadRequest(format!("threshold must be a percentage, not {v:?}"))
                    })?
            }
            "format" => {
                q.format = match v.as_str() {
                    "json" => Format::Json,
                    "csv" => Format::Csv,
                    "md" => Format::Md,
                    _ => {
                        return Err(AppError::BadRequest(format!(
                            "format must be json, csv or md, not {v:?}"
                        )))
                    }
                }
            }
            _ => {}
        }
    }
    Ok(q)
}

/// A run id as given, or the newest run of the commit it starts.
fn resolve(
    c: &mut dyn crate::db::Connection,
    what: &str,
    q: &CompareRunsQuery,
) -> Result<String, AppError> {
    if c.query_opt("SELECT 1 FROM runs WHERE run_id = $1", &[what.into()])?
        .is_some()
    {
        return Ok(what.to_string());
    }
    browse::run_of_commit(c, what, q.adapter, q.suite.as_deref())?.ok_or_else(|| {
        AppError::NotFound(format!(
            "no run {what:?} and no run of a commit starting with it{}",
            if q.adapter.is_some() || q.suite.is_some() {
                " on that adapter and suite"
            } else {
                ""
            }
        ))
    })
}

/// A comparison with what the engine does not judge: the conditions of both runs.
pub struct Loaded {
    pub comparison: Comparison,
    /// What differs between A's and B's conditions ([`conditions_view::differences`]).
    pub environment: Vec<String>,
    /// Both runs' scenario records (their conditions per variant).
    pub a: Arc<Vec<tessera_results::ScenarioResult>>,
    pub b: Arc<Vec<tessera_results::ScenarioResult>>,
}

/// The comparison the request names; `None` when it names no runs (the empty form).
pub async fn load(state: &AppState, q: CompareRunsQuery) -> Result<Option<Loaded>, AppError> {
    let cache = state.runs.clone();
    state
        .db(move |c| {
            let (a, b) = match (&q.a, &q.b, q.picks.as_slice()) {
                (Some(a), Some(b), _) => (resolve(c, a, &q)?, resolve(c, b, &q)?),
                (_, _, [x, y]) => {
                    // Ticked in the runs list: the older is A.
                    let (x, y) = (resolve(c, x, &q)?, resolve(c, y, &q)?);
                    let rx = read::run_head(c, &x)?.run.started_at;
                    let ry = read::run_head(c, &y)?.run.started_at;
                    if rx <= ry {
                        (x, y)
                    } else {
                        (y, x)
                    }
                }
                (None, None, []) => return Ok(None),
                (_, _, picks) if !picks.is_empty() => {
                    return Err(AppError::BadRequest(format!(
                        "tick exactly two runs to compare ({} ticked)",
                        picks.len()
                    )))
                }
                _ => return Err(AppError::BadRequest("give both a= and b=".into())),
            };
            let (ha, hb) = (read::run_head(c, &a)?, read::run_head(c, &b)?);
            let sa = cache.records(c, ha.pk)?;
            let sb = cache.records(c, hb.pk)?;
            // The series' own noise, where a history on B's adapter gives it (times in ms only).
            let noise = if compare::same_adapter(&ha.info, &hb.info) {
                cache.noise(c, &b)?.as_ref().clone()
            } else {
                Default::default()
            };
            let comparison = compare::compare(
                RunRef {
                    info: &ha.info,
                    scenarios: &sa,
                },
                RunRef {
                    info: &hb.info,
                    scenarios: &sb,
                },
                &Options {
                    threshold_pct: q.threshold,
                    noise,
                },
            );
            Ok(Some(Loaded {
                environment: conditions_view::differences(&ha.info, &sa, &hb.info, &sb),
                comparison,
                a: sa,
                b: sb,
            }))
        })
        .await
}
