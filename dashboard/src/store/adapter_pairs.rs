//! Which runs the adapters page compares: for two adapters, the newest run on A that shares at
//! least one scenario with a run on B, paired with B's run of the same commit when one shares
//! scenarios, else B's newest run that does; and, when no pair shares anything, what each adapter
//! has (suites and scenarios) so the page can say why. A suite split over several runs is paired
//! by its scenarios, never by the suite's name alone.
//!
//! Not for: comparing the pair (the comparison engine, `tessera_results::compare`).

use serde::Serialize;

use super::StoreError;
use crate::db::{Connection, Value};

/// Newest runs on A tried before giving up.
pub const MAX_TRIED: i64 = 500;

/// A pair of runs sharing scenarios.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct RunPair {
    pub run_a: String,
    pub run_b: String,
    /// `same commit` or `newest run sharing scenarios`.
    pub how: String,
    /// The scenarios both runs hold, by name.
    pub scenarios: Vec<String>,
}

/// The newest pair of runs on adapters `a` and `b` that share scenarios (A's runs of `suite`
/// when given).
pub fn newest_sharing_pair(
    conn: &mut dyn Connection,
    a: i64,
    b: i64,
    suite: Option<&str>,
) -> Result<Option<RunPair>, StoreError> {
    let runs = conn.query(
        "SELECT id, run_id, commit_sha FROM runs WHERE adapter_id = $1
           AND (CAST($2 AS TEXT) IS NULL OR suite = $2)
         ORDER BY started_at DESC, id DESC LIMIT $3",
        &[Value::Int(a), suite.into(), Value::Int(MAX_TRIED)],
    )?;
    for r in &runs {
        let (pk, run_a, sha) = (r.i64(0)?, r.string(1)?, r.opt_string(2)?);
        let Some(partner) = conn.query_opt(
            "SELECT rb.id, rb.run_id, rb.commit_sha FROM runs rb WHERE rb.adapter_id = $1
               AND EXISTS (SELECT 1 FROM scenario_results sb JOIN scenario_results sa
                             ON sa.scenario = sb.scenario WHERE sb.run_pk = rb.id AND sa.run_pk = $2)
             ORDER BY CASE WHEN rb.commit_sha = $3 THEN 0 ELSE 1 END, rb.started_at DESC, rb.id DESC
             LIMIT 1",
            &[Value::Int(b), Value::Int(pk), sha.clone().into()],
        )?
        else {
            continue;
        };
        let (pk_b, run_b) = (partner.i64(0)?, partner.string(1)?);
        let same = sha.is_some() && partner.opt_string(2)? == sha;
        let scenarios = conn
            .query(
                "SELECT DISTINCT sa.scenario FROM scenario_results sa JOIN scenario_results sb
                   ON sb.scenario = sa.scenario WHERE sa.run_pk = $1 AND sb.run_pk = $2
                 ORDER BY sa.scenario",
                &[Value::Int(pk), Value::Int(pk_b)],
            )?
            .iter()
            .map(|r| r.string(0))
            .collect::<Result<Vec<_>, _>>()?;
        return Ok(Some(RunPair {
            run_a,
            run_b,
            how: if same {
                "same commit".into()
            } else {
                "newest run sharing scenarios".into()
            },
            scenarios,
        }));
    }
    Ok(None)
}

/// What two adapters have: their suites and scenarios, and the scenarios both have run.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct Holdings {
    pub suites_a: Vec<String>,
    pub suites_b: Vec<String>,
    pub scenarios_a: Vec<String>,
    pub scenarios_b: Vec<String>,
    pub shared_scenarios: Vec<String>,
}

fn names(conn: &mut dyn Connection, sql: &str, adapter: i64) -> Result<Vec<String>, StoreError> {
    conn.query(sql, &[Value::Int(adapter)])?
        .iter()
        .map(|r| Ok(r.opt_string(0)?.unwrap_or_else(|| "(no suite)".into())))
        .collect()
}

/// The suites and scenarios of adapters `a` and `b`.
pub fn holdings(conn: &mut dyn Connection, a: i64, b: i64) -> Result<Holdings, StoreError> {
    let suites = "SELECT DISTINCT suite FROM runs WHERE adapter_id = $1 ORDER BY suite";
    let scenarios =
        "SELECT DISTINCT s.scenario FROM scenario_results s JOIN runs r ON r.id = s.run_pk
                     WHERE r.adapter_id = $1 ORDER BY s.scenario";
    let scenarios_a = names(conn, scenarios, a)?;
    let scenarios_b = names(conn, scenarios, b)?;
    let shared_scenarios = scenarios_a
        .iter()
        .filter(|s| scenarios_b.contains(s))
        .cloned()
        .collect();
    Ok(Holdings {
        suites_a: names(conn, suites, a)?,
        suites_b: names(conn, suites, b)?,
        scenarios_a,
        scenarios_b,
        shared_scenarios,
    })
}
