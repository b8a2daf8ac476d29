//! Tessera's results store and dashboard: imports run folders written by the harness, keeps them
//! in SQLite or PostgreSQL, detects regressions per series and serves the pages and their JSON API.
//!
//! Layout (rustc-perf's database / site split): [`db`] talks to the database, [`store`] holds the
//! queries, [`bundle`] checks incoming runs, [`detect`] finds change points, [`regressions`]
//! applies it to stored series, [`server`] serves pages and API, [`titles`] names alert groups, [`html`] and [`svg`] draw them.

pub mod ab;
pub mod bundle;
pub mod chart;
pub mod db;
pub mod detect;
pub mod html;
pub mod import;
pub mod interval_chart;
pub mod notify;
pub mod queue_cli;
pub mod regressions;
pub mod replay;
pub mod server;
pub mod steps;
pub mod store;
pub mod svg;
pub mod synth;
pub mod titles;
pub mod validate;

/// The current time, RFC 3339 in UTC, as stored in the `*_at` columns.
pub fn now_rfc3339() -> String {
    chrono::Utc::now().to_rfc3339_opts(chrono::SecondsFormat::Secs, true)
}
