//! The runner's calls to the dashboard's queue endpoints (`dashboard/README.md`, "Runners"): JSON
//! bodies of `tessera_results::queue`, the bearer token of `TESSERA_DASHBOARD_TOKEN`, a short
//! timeout per call. Not for: uploading runs (see [`crate::upload`]).

use std::time::Duration;

use serde::de::DeserializeOwned;
use serde::Serialize;
use tessera_results::queue::{
    ClaimRequest, Claimed, Completion, Failure, Heartbeat, HeartbeatReply, JobRef, Registration,
    Return,
};

/// One call may take this long.
const TIMEOUT: Duration = Duration::from_secs(60);

#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    #[error("cannot reach the dashboard at {url}: {source}")]
    Transport {
        url: String,
        #[source]
        source: ureq::Error,
    },
    #[error("the dashboard answered {url} with HTTP {status}: {message}")]
    Refused {
        url: String,
        status: u16,
        message: String,
    },
}

impl ClientError {
    /// The dashboard said this job is not ours any more (409): stop working on it.
    pub fn is_lost_job(&self) -> bool {
        matches!(self, ClientError::Refused { status: 409, .. })
    }
}

/// A dashboard and a token.
#[derive(Clone)]
pub struct Client {
    base: String,
    token: String,
    agent: ureq::Agent,
}

impl Client {
    pub fn new(base: &str, token: &str) -> Client {
        Client {
            base: base.trim_end_matches('/').to_string(),
            token: token.to_string(),
            agent: ureq::Agent::config_builder()
                .http_status_as_error(false)
                .timeout_global(Some(TIMEOUT))
                .build()
                .into(),
        }
    }

    pub fn base(&self) -> &str {
        &self.base
    }

    pub fn token(&self) -> &str {
        &self.token
    }

    /// POSTs `body`; `None` for 204 No Content.
    fn post<B: Serialize, R: DeserializeOwned>(
        &self,
        path: &str,
        body: &B,
    ) -> Result<Option<R>, ClientError> {
        let url = format!("{}{path}", self.base);
        let transport = |source| ClientError::Transport {
            url: url.clone(),
            source,
        };
        let bytes = serde_json::to_vec(body).expect("queue bodies serialise");
        let mut res = self
            .agent
            .post(&url)
            .header("Authorization", &format!("Bearer {}", self.token))
            .header("Content-Type", "application/json")
            .send(&bytes[..])
            .map_err(transport)?;
        let status = res.status().as_u16();
        let text = res.body_mut().read_to_string().map_err(transport)?;
        match status {
            204 => Ok(None),
            200 | 201 => serde_json::from_str(&text)
                .map(Some)
                .map_err(|e| ClientError::Refused {
                    url,
                    status,
                    message: format!("unexpected answer ({e}): {text}"),
                }),
            _ => Err(ClientError::Refused {
                url,
                status,
                message: serde_json::from_str::<serde_json::Value>(&text)
                    .ok()
                    .and_then(|v| v["error"].as_str().map(str::to_string))
                    .unwrap_or(text),
            }),
        }
    }

    pub fn register(&self, reg: &Registration) -> Result<u64, ClientError> {
        let v: Option<serde_json::Value> = self.post("/api/runners/register", reg)?;
        Ok(v.and_then(|v| v["lease_secs"].as_u64()).unwrap_or(60))
    }

    pub fn claim(&self, runner: &str) -> Result<Option<Claimed>, ClientError> {
        self.post(
            "/api/queue/claim",
            &ClaimRequest {
                runner: runner.into(),
            },
        )
    }

    /// `Ok(false)`: the job is no longer ours.
    pub fn heartbeat(&self, runner: &str, job: Option<JobRef>) -> Result<bool, ClientError> {
        let r: Option<HeartbeatReply> = self.post(
            "/api/runners/heartbeat",
            &Heartbeat {
                runner: runner.into(),
                job,
            },
        )?;
        Ok(r.is_none_or(|r| r.job_kept))
    }

    pub fn complete(&self, job_id: i64, c: &Completion) -> Result<(), ClientError> {
        self.post::<_, serde_json::Value>(&format!("/api/queue/jobs/{job_id}/complete"), c)
            .map(drop)
    }

    pub fn fail(&self, job_id: i64, f: &Failure) -> Result<(), ClientError> {
        self.post::<_, serde_json::Value>(&format!("/api/queue/jobs/{job_id}/fail"), f)
            .map(drop)
    }

    pub fn give_back(&self, job_id: i64, r: &Return) -> Result<(), ClientError> {
        self.post::<_, serde_json::Value>(&format!("/api/queue/jobs/{job_id}/return"), r)
            .map(drop)
    }
}
