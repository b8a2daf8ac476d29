//! Sending a finished run folder to a Tessera dashboard: `POST <url>/api/runs` with
//! `Authorization: Bearer $TESSERA_DASHBOARD_TOKEN` (used by `tessera upload` and
//! `tessera run --upload`).
//!
//! The body is `tessera_results::upload::UploadBody`, the type the dashboard's `POST /api/runs`
//! reads (`dashboard/README.md`, "Uploading"): `run` (run.json), `scenarios` (every
//! `scenarios/*.json`, by file name), both brought to the current schema version by the shared
//! run-folder reader, and `images` (every PNG the results list and the folder holds, keyed by its
//! path in the run folder, in base64). Nothing here changes the run folder: an upload that fails
//! leaves the results on disk for a later `tessera upload`.

use std::path::Path;
use std::time::Duration;

use tessera_results::upload::UploadBody;

use crate::compare::load::{read_raw, LoadError};

/// Environment variable holding the dashboard's bearer token.
pub const TOKEN_ENV: &str = "TESSERA_DASHBOARD_TOKEN";

/// The whole request, connection to answer, may take this long (bundles with images are large).
const TIMEOUT: Duration = Duration::from_secs(300);

#[derive(Debug, thiserror::Error)]
pub enum UploadError {
    #[error(transparent)]
    Load(#[from] LoadError),
    #[error("{TOKEN_ENV} is not set: export the dashboard's token to upload")]
    NoToken,
    #[error("{0:?} is not a dashboard URL: give http://host:port or https://host")]
    BadUrl(String),
    #[error("cannot reach the dashboard at {url}: {source}")]
    Transport {
        url: String,
        #[source]
        source: ureq::Error,
    },
    #[error("the dashboard at {url} refused the run with HTTP {status}: {message}")]
    Refused {
        url: String,
        status: u16,
        message: String,
    },
}

impl UploadError {
    /// The run folder or the URL is unusable (as opposed to the token, the dashboard or the
    /// network).
    pub fn is_bad_input(&self) -> bool {
        matches!(self, UploadError::Load(_) | UploadError::BadUrl(_))
    }
}

/// What the dashboard answered to an accepted upload.
#[derive(Clone, Debug, PartialEq, Eq, serde::Deserialize)]
pub struct Reply {
    pub run_id: String,
    /// `false` when the dashboard already had this run id (nothing changed).
    pub stored: bool,
    #[serde(default)]
    pub results: usize,
    #[serde(default)]
    pub new_regressions: usize,
}

impl Reply {
    /// One line for the console.
    pub fn summary(&self) -> String {
        if self.stored {
            format!(
                "uploaded: {} stored ({} results, {} new regressions)",
                self.run_id, self.results, self.new_regressions
            )
        } else {
            format!("uploaded: {} was already stored", self.run_id)
        }
    }
}

/// The upload body of a run folder. Listed images that are missing are left out (runs may be
/// saved without them), as the dashboard's own import does.
pub fn bundle(dir: &Path) -> Result<UploadBody, UploadError> {
    Ok(UploadBody::from_folder(&read_raw(dir)?)?)
}

/// `<url>/api/runs`, unless `url` already ends with it.
pub fn endpoint(url: &str) -> Result<String, UploadError> {
    if !(url.starts_with("http://") || url.starts_with("https://")) {
        return Err(UploadError::BadUrl(url.to_string()));
    }
    let base = url.trim_end_matches('/');
    Ok(if base.ends_with("/api/runs") {
        base.to_string()
    } else {
        format!("{base}/api/runs")
    })
}

/// The token from [`TOKEN_ENV`]; empty counts as unset.
pub fn token_from_env() -> Result<String, UploadError> {
    match std::env::var(TOKEN_ENV) {
        Ok(t) if !t.trim().is_empty() => Ok(t.trim().to_string()),
        _ => Err(UploadError::NoToken),
    }
}

/// POSTs `body` (JSON) and reads the answer: 200 and 201 are success, anything else is
/// [`UploadError::Refused`] with the dashboard's `{"error"}` message.
pub fn post(url: &str, token: &str, body: &[u8]) -> Result<Reply, UploadError> {
    post_for_job(url, token, body, None)
}

/// [`post`] for a queue job: the `X-Tessera-Job` header names it, which a runner-scope token
/// needs to store a run (`tessera runner`).
pub fn post_for_job(
    url: &str,
    token: &str,
    body: &[u8],
    job: Option<i64>,
) -> Result<Reply, UploadError> {
    let url = endpoint(url)?;
    let transport = |source| UploadError::Transport {
        url: url.clone(),
        source,
    };
    let agent: ureq::Agent = ureq::Agent::config_builder()
        .http_status_as_error(false)
        .timeout_global(Some(TIMEOUT))
        .build()
        .into();
    let mut request = agent.post(&url);
    if let Some(job) = job {
        request = request.header(tessera_results::queue::JOB_HEADER, &job.to_string());
    }
    let mut response = request
        .header("Authorization", &format!("Bearer {token}"))
        .header("Content-Type", "application/json")
        // The dashboard checks the token before it reads a body: with 100-continue a refused
        // upload gets the dashboard's answer instead of a broken pipe half-way through the body.
        .header("Expect", "100-continue")
        .send(body)
        .map_err(transport)?;
    let status = response.status().as_u16();
    let text = response.body_mut().read_to_string().map_err(transport)?;
    if status == 200 || status == 201 {
        return serde_json::from_str(&text).map_err(|e| UploadError::Refused {
            url: url.clone(),
            status,
            message: format!("unexpected answer ({e}): {text}"),
        });
    }
    let message = serde_json::from_str::<serde_json::Value>(&text)
        .ok()
        .and_then(|v| v["error"].as_str().map(str::to_string))
        .unwrap_or_else(|| {
            if text.is_empty() {
                "no message".into()
            } else {
                text
            }
        });
    Err(UploadError::Refused {
        url,
        status,
        message,
    })
}

/// Bundles the run folder `dir` and sends it to the dashboard at `url` with the token from the
/// environment.
pub fn upload(dir: &Path, url: &str) -> Result<Reply, UploadError> {
    endpoint(url)?;
    let token = token_from_env()?;
    let body = serde_json::to_vec(&bundle(dir)?).expect("the upload body serialises");
    post(url, &token, &body)
}
