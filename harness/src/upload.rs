//! Sending a finished run folder to a Tessera dashboard: `POST <url>/api/runs` with
//! `Authorization: Bearer $TESSERA_DASHBOARD_TOKEN` (used by `tessera upload` and
//! `tessera run --upload`).
//!
//! The body is `tessera_results::upload::UploadBody`, the type the dashboard's `POST /api/runs`
//! reads (`dashboard/README.md`, "Uploading"): `run` (run.json), `scenarios` (every
//! `scenarios/*.json`, by file name), both brought to the current schema version by the shared
//! run-folder reader, and `images` (every PNG the results list and the folder holds, keyed by its
//! path in the run folder, in base64). Images travel apart where the dashboard offers it: the
//! client asks which image digests the dashboard lacks (`POST /api/blobs/missing`), sends those
//! in batches under the request cap (`POST /api/blobs`), then posts the records with
//! `image_digests` instead of the bytes; so a 4K run with all its frames uploads, and a repeated
//! upload sends only its records. A dashboard without the blob routes (404) gets the images
//! inline, as before. Nothing here changes the run folder: an upload that fails
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

/// Most bytes of images one `POST /api/blobs` carries (the dashboard's default cap is 64 MiB;
/// one image is at most 16 MiB).
pub const BATCH_BYTES: usize = 24 << 20;

/// What the dashboard answered to an accepted upload, and what the upload sent.
#[derive(Clone, Debug, PartialEq, Eq, serde::Deserialize)]
pub struct Reply {
    pub run_id: String,
    /// `false` when the dashboard already had this run id (nothing changed).
    pub stored: bool,
    #[serde(default)]
    pub results: usize,
    #[serde(default)]
    pub new_regressions: usize,
    /// What the dashboard says about a run it took (a run without a commit: never the previous
    /// run of its suite); printed on stderr. Absent from older dashboards.
    #[serde(default)]
    pub warnings: Vec<String>,
    /// Request body bytes sent, every request of the upload together.
    #[serde(skip)]
    pub bytes_sent: u64,
    /// Images the run lists and holds, and how many of them the dashboard lacked and was sent.
    #[serde(skip)]
    pub images: usize,
    #[serde(skip)]
    pub images_sent: usize,
}

impl Reply {
    /// One line for the console.
    pub fn summary(&self) -> String {
        let sent = format!(
            "sent {} in all, {} of {} images new to the dashboard",
            human_bytes(self.bytes_sent),
            self.images_sent,
            self.images
        );
        if self.stored {
            format!(
                "uploaded: {} stored ({} results, {} new regressions; {sent})",
                self.run_id, self.results, self.new_regressions
            )
        } else {
            format!("uploaded: {} was already stored ({sent})", self.run_id)
        }
    }
}

fn human_bytes(n: u64) -> String {
    if n >= 1 << 20 {
        format!("{:.1} MiB", n as f64 / f64::from(1u32 << 20))
    } else if n >= 1 << 10 {
        format!("{:.1} KiB", n as f64 / 1024.0)
    } else {
        format!("{n} bytes")
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

/// POSTs `body` to `url` and returns the status and the answer's text, waiting out a rate
/// limit (429, its `Retry-After`) a few times.
fn send(
    url: &str,
    token: &str,
    content_type: &str,
    body: &[u8],
    job: Option<i64>,
) -> Result<(u16, String), UploadError> {
    let transport = |source| UploadError::Transport {
        url: url.to_string(),
        source,
    };
    let agent: ureq::Agent = ureq::Agent::config_builder()
        .http_status_as_error(false)
        .timeout_global(Some(TIMEOUT))
        .build()
        .into();
    let mut attempt = 0;
    loop {
        let mut request = agent.post(url);
        if let Some(job) = job {
            request = request.header(tessera_results::queue::JOB_HEADER, &job.to_string());
        }
        let mut response = request
            .header("Authorization", &format!("Bearer {token}"))
            .header("Content-Type", content_type)
            // The dashboard checks the token before it reads a body: with 100-continue a refused
            // upload gets the dashboard's answer instead of a broken pipe half-way through the body.
            .header("Expect", "100-continue")
            .send(body)
            .map_err(transport)?;
        let status = response.status().as_u16();
        let wait = response
            .headers()
            .get("retry-after")
            .and_then(|v| v.to_str().ok())
            .and_then(|v| v.trim().parse::<u64>().ok());
        let text = response.body_mut().read_to_string().map_err(transport)?;
        match (status, wait) {
            (429, Some(secs)) if attempt < 5 && secs <= 120 => {
                attempt += 1;
                std::thread::sleep(Duration::from_secs(secs.max(1)));
            }
            _ => return Ok((status, text)),
        }
    }
}

/// The dashboard's `{"error"}` message of a refusal, or its text.
fn refused(url: &str, status: u16, text: String) -> UploadError {
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
    UploadError::Refused {
        url: url.to_string(),
        status,
        message,
    }
}

/// POSTs `body` (JSON) to `<url>/api/runs` and reads the answer: 200 and 201 are success,
/// anything else is [`UploadError::Refused`] with the dashboard's `{"error"}` message.
pub fn post(url: &str, token: &str, body: &[u8]) -> Result<Reply, UploadError> {
    post_for_job(url, token, body, None)
}

/// [`post`] for a queue job: the `X-Tessera-Job` header names it, which a runner-scope token
/// needs to store a run (`tessera runner`; a runner sends its images inline, since blob routes
/// take a write token).
pub fn post_for_job(
    url: &str,
    token: &str,
    body: &[u8],
    job: Option<i64>,
) -> Result<Reply, UploadError> {
    let url = endpoint(url)?;
    let (status, text) = send(&url, token, "application/json", body, job)?;
    if status == 200 || status == 201 {
        let mut reply: Reply = serde_json::from_str(&text).map_err(|e| UploadError::Refused {
            url: url.clone(),
            status,
            message: format!("unexpected answer ({e}): {text}"),
        })?;
        reply.bytes_sent = body.len() as u64;
        return Ok(reply);
    }
    Err(refused(&url, status, text))
}

/// What [`send_blobs`] did: every image's digest by path, the bytes sent, the images sent.
type BlobsSent = (std::collections::BTreeMap<String, String>, u64, usize);

/// Sends the images the dashboard lacks as blob batches. `Ok(None)` when the dashboard has no
/// blob routes (an older one: the caller sends the images inline); otherwise the digests by
/// path, the bytes sent and how many images were new.
fn send_blobs(
    url: &str,
    token: &str,
    images: &std::collections::BTreeMap<String, Vec<u8>>,
) -> Result<Option<BlobsSent>, UploadError> {
    use tessera_results::upload::{blob_digest, blob_record, MissingReply, MissingRequest};
    let base = endpoint(url)?;
    let base = base.trim_end_matches("/api/runs");
    let digests: std::collections::BTreeMap<String, String> = images
        .iter()
        .map(|(p, b)| (p.clone(), blob_digest(b)))
        .collect();
    let ask = MissingRequest {
        digests: digests.values().cloned().collect(),
    };
    let ask = serde_json::to_vec(&ask).expect("the question serialises");
    let missing_url = format!("{base}/api/blobs/missing");
    let (status, text) = send(&missing_url, token, "application/json", &ask, None)?;
    if status == 404 || status == 405 {
        return Ok(None);
    }
    if status != 200 {
        return Err(refused(&missing_url, status, text));
    }
    let missing: MissingReply = serde_json::from_str(&text).map_err(|e| UploadError::Refused {
        url: missing_url.clone(),
        status,
        message: format!("unexpected answer ({e}): {text}"),
    })?;
    let mut sent = ask.len() as u64;
    let want: std::collections::BTreeSet<&str> =
        missing.missing.iter().map(String::as_str).collect();
    let blobs_url = format!("{base}/api/blobs");
    let mut batch: Vec<u8> = Vec::new();
    let mut done: std::collections::BTreeSet<String> = std::collections::BTreeSet::new();
    let flush = |batch: &mut Vec<u8>, sent: &mut u64| -> Result<(), UploadError> {
        if batch.is_empty() {
            return Ok(());
        }
        let (status, text) = send(&blobs_url, token, "application/octet-stream", batch, None)?;
        if status != 200 && status != 201 {
            return Err(refused(&blobs_url, status, text));
        }
        *sent += batch.len() as u64;
        batch.clear();
        Ok(())
    };
    for (path, bytes) in images {
        let d = digests[path].as_str();
        if !want.contains(d) || !done.insert(d.to_string()) {
            continue;
        }
        if !batch.is_empty() && batch.len() + bytes.len() > BATCH_BYTES {
            flush(&mut batch, &mut sent)?;
        }
        batch.extend(blob_record(bytes));
    }
    flush(&mut batch, &mut sent)?;
    Ok(Some((digests, sent, done.len())))
}

/// Sends the run folder `dir` to the dashboard at `url` with the token from the environment:
/// its images as blobs the dashboard lacks (inline to a dashboard without blob routes), then
/// its records.
pub fn upload(dir: &Path, url: &str) -> Result<Reply, UploadError> {
    endpoint(url)?;
    let token = token_from_env()?;
    let raw = read_raw(dir)?;
    let images = raw.read_images()?;
    let mut body = UploadBody {
        run: raw.run.clone(),
        scenarios: raw.scenarios.clone(),
        ..UploadBody::default()
    };
    let (mut sent, mut images_sent) = (0, 0);
    if !images.is_empty() {
        match send_blobs(url, &token, &images)? {
            Some((digests, bytes, new)) => {
                body.image_digests = digests;
                sent += bytes;
                images_sent = new;
            }
            None => {
                body.images = images
                    .iter()
                    .map(|(p, b)| (p.clone(), tessera_results::upload::encode(b)))
                    .collect();
                images_sent = images.len();
            }
        }
    }
    let json = serde_json::to_vec(&body).expect("the upload body serialises");
    let mut reply = post(url, &token, &json)?;
    reply.bytes_sent += sent;
    reply.images = images.len();
    reply.images_sent = images_sent;
    Ok(reply)
}
