//! `/queue`: the runners (online or offline, labels, adapter, last heartbeat, current job) and the
//! queue (active jobs, each queued one saying when no online runner has its label; the newest
//! finished jobs with their errors). The same data as `GET /api/queue`.

use std::fmt::Write;

use axum::extract::State;
use axum::response::Html;

use super::queue::now_ms;
use super::{AppError, AppState};
use crate::html::{esc, page as layout};
use crate::store::queue::{self, JobRow, JobStatus};

const STYLE: &str = "<style>
.dot{display:inline-block;width:9px;height:9px;border-radius:50%;margin-right:5px;vertical-align:middle}
.on{background:#1a8f3c}.off{background:#b9b9b9}.wait{color:#a15c00}
.st{padding:0 5px;border-radius:3px;white-space:nowrap}.st.queued{background:#eef}.st.in_progress{background:#e6f4ff}
.st.done{background:#e2f3e7}.st.failed,.st.build_failed{background:#fde8e6}
.err{color:#a1140f;max-width:420px;overflow-wrap:anywhere}
.wrap{overflow-x:auto}.wrap table{min-width:760px}.wrap td{overflow-wrap:normal;word-break:normal}
.chips span{background:#e8ebf0;border-radius:3px;padding:0 4px;margin-right:3px;white-space:nowrap}
@media (max-width:600px){.wide{display:none}.wrap table{min-width:0}.wrap td,.wrap th{padding:3px 4px}}
</style>";

fn ago(now_ms: i64, then_ms: i64) -> String {
    let s = (now_ms - then_ms).max(0) / 1000;
    match s {
        0..=59 => format!("{s} s ago"),
        60..=3599 => format!("{} min ago", s / 60),
        3600..=86399 => format!("{} h ago", s / 3600),
        _ => format!("{} d ago", s / 86400),
    }
}

fn what(j: &JobRow) -> String {
    let commits: Vec<String> = j
        .spec
        .arms
        .iter()
        .map(|a| {
            let env = if a.env.is_empty() {
                String::new()
            } else {
                format!(" +{} env", a.env.len())
            };
            format!(
                "{}={}{env}",
                a.name,
                a.commit.get(..10).unwrap_or(&a.commit)
            )
        })
        .collect();
    format!(
        "{} · {}{}",
        esc(&j.spec.scenarios.join(" ")),
        esc(&commits.join(" vs ")),
        if j.spec.order.len() > 1 {
            format!(" · {} runs", j.spec.order.len())
        } else {
            String::new()
        }
    )
}

fn job_row(out: &mut String, j: &JobRow, now: i64) {
    let status = j.status.as_str();
    let note = match (&j.waiting, j.status) {
        (Some(w), _) => format!("<span class=wait>waiting: {}</span>", esc(w)),
        (None, JobStatus::InProgress) => j
            .lease_expires_ms
            .map(|l| {
                if l < now {
                    "lease expired: back to the queue at the next claim".to_string()
                } else {
                    format!("lease {} s left", (l - now) / 1000)
                }
            })
            .unwrap_or_default(),
        _ => String::new(),
    };
    let _ = write!(
        out,
        "<tr><td class=num>{}<td class=wide>{}<td><code>{}</code><td><span class=\"st {status}\">{status}</span><td class=\"num wide\">{}/{}<td>{}<td class=wide>{}<td>{}<td class=err>{}</tr>",
        j.id,
        esc(&j.kind),
        esc(&j.label),
        j.attempts,
        j.max_attempts,
        esc(j.runner.as_deref().unwrap_or("–")),
        what(j),
        note,
        esc(&j.error)
    );
}

const JOB_HEAD: &str =
    "<tr><th>job<th class=wide>kind<th>label<th>status<th class=wide>tries<th>runner<th class=wide>what<th>state<th>error</tr>";

pub async fn page(State(state): State<AppState>) -> Result<Html<String>, AppError> {
    let offline = state.queue.offline_after_ms;
    let now = now_ms();
    let o = state
        .db(move |c| Ok(queue::overview(c, now, offline, 30)?))
        .await?;
    let online = o.runners.iter().filter(|r| r.online).count();
    let mut body = format!(
        "{STYLE}<p>{} runners, {online} online · {} active jobs · queued by label: {}</p>",
        o.runners.len(),
        o.active.len(),
        if o.queued_by_label.is_empty() {
            "none".to_string()
        } else {
            o.queued_by_label
                .iter()
                .map(|(l, n)| format!("<code>{}</code> {n}", esc(l)))
                .collect::<Vec<_>>()
                .join(", ")
        }
    );
    body.push_str("<h2>Runners</h2><div class=wrap><table><tr><th>runner<th>labels<th class=wide>adapter<th class=wide>driver<th class=wide>host<th>last heartbeat<th>current job</tr>");
    for r in &o.runners {
        let _ = write!(
            body,
            "<tr><td><span class=\"dot {}\"></span>{} <small>{}</small><td class=chips>{}<td class=wide>{}<td class=wide>{}<td class=wide>{}<td>{}<td>{}</tr>",
            if r.online { "on" } else { "off" },
            esc(&r.name),
            if r.online { "online" } else { "offline" },
            r.labels
                .iter()
                .map(|l| format!("<span>{}</span>", esc(l)))
                .collect::<String>(),
            esc(&r.adapter),
            esc(&r.driver),
            esc(&r.host),
            ago(now, r.last_heartbeat_ms),
            r.current_job.map_or_else(|| "idle".to_string(), |j| format!("job {j}"))
        );
    }
    if o.runners.is_empty() {
        body.push_str("<tr><td colspan=7>No runner has registered: start one with <code>tessera runner --dashboard URL --labels LABEL --repository PATH</code>.</tr>");
    }
    body.push_str("</table></div><h2>Active jobs</h2><div class=wrap><table>");
    body.push_str(JOB_HEAD);
    for j in &o.active {
        job_row(&mut body, j, now);
    }
    if o.active.is_empty() {
        body.push_str("<tr><td colspan=9>The queue is empty.</tr>");
    }
    body.push_str("</table></div><h2>Recently finished</h2><div class=wrap><table>");
    body.push_str(JOB_HEAD);
    for j in &o.finished {
        job_row(&mut body, j, now);
    }
    body.push_str("</table></div>");
    Ok(Html(layout("Runners and queue", "queue", &body)))
}
