//! `GET /healthz`: 200 `{"status": "ok", "store", "schema_version", "known_schema_version"}` when
//! the store answers a query, 503 `{"status": "unavailable", "error"}` when it does not. Never
//! needs a token (load balancers and probes call it). Not for: metrics.

use axum::extract::State;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use axum::Json;

use super::AppState;
use crate::db::{self, Backend};

pub async fn healthz(State(state): State<AppState>) -> Response {
    let probe = state
        .db(|c| Ok((c.backend(), db::current_version(c)?)))
        .await;
    match probe {
        Ok((backend, version)) => Json(serde_json::json!({
            "status": "ok",
            "store": match backend {
                Backend::Sqlite => "sqlite",
                Backend::Postgres => "postgres",
            },
            "schema_version": version,
            "known_schema_version": db::known_version(),
        }))
        .into_response(),
        Err(e) => {
            eprintln!("tessera-dashboard: healthz: the store is unreachable: {e:?}");
            (
                StatusCode::SERVICE_UNAVAILABLE,
                Json(serde_json::json!({
                    "status": "unavailable",
                    "error": "the store is unreachable",
                })),
            )
                .into_response()
        }
    }
}
