//! What the replay published and promised, checked at its end (issue 22's acceptance): every URL
//! of an alert group ever shown (its id page, every commit-range key it was shown under, its
//! Markdown, its series' pages) still answers 200 or a redirect to 200 through the real router,
//! and the triage set on each group when it was first confirmed is still on each of its alerts,
//! after moves, merges, backfills and a deleted run.
//!
//! Not for: scoring detection against the truth (see the parent module).

use std::collections::{BTreeMap, BTreeSet};

use axum::body::Body;
use axum::http::{header, Request};
use tower::ServiceExt;

use crate::db::{Connection, Pool};
use crate::server::{app, AppState};
use crate::store::alerts::{self, DetectionStatus, Select, TriageState};
use crate::store::groups::{self, Filter, Sort};
use crate::store::triage::{self, Triage};
use crate::store::StoreError;

/// URLs seen and triage set during a replay.
#[derive(Debug, Default)]
pub struct Published {
    pub urls: BTreeSet<String>,
    /// Alert id → (group id, the note set on it).
    pub triaged: BTreeMap<i64, (i64, String)>,
    groups_triaged: BTreeSet<i64>,
}

/// The outcome of [`Published::check`].
#[derive(Debug, Default, Clone)]
pub struct Checked {
    pub urls: usize,
    /// URLs that did not end in 200 (with what they answered).
    pub broken: Vec<String>,
    pub triaged_alerts: usize,
    pub triaged_groups: usize,
    /// Alerts whose triage changed (with what they hold now).
    pub triage_lost: Vec<String>,
}

impl Published {
    /// Records the URLs of every group now in the store, and triages (acknowledged, with a note
    /// naming the group) each group the first time it holds a confirmed alert: the published
    /// groups a user would have triaged.
    pub fn record(&mut self, conn: &mut dyn Connection) -> Result<(), StoreError> {
        let filter = Filter {
            status: Some("all".into()),
            ..Filter::default()
        };
        for g in groups::list(conn, &filter, Sort::Date, usize::MAX)? {
            self.urls.insert(format!("/regressions/groups/{}", g.id));
            self.urls.insert(format!("/regressions/groups/{}.md", g.id));
            self.urls.insert(format!("/regressions/groups/{}", g.key));
            for a in &g.alerts {
                self.urls.insert(format!("/series/{}", a.series.id));
            }
            let confirmed = g
                .alerts
                .iter()
                .any(|a| a.status == DetectionStatus::Confirmed);
            if confirmed && self.groups_triaged.insert(g.id) {
                let note = format!("replay: group {} triaged when confirmed", g.id);
                triage::set_group(
                    conn,
                    &g.id.to_string(),
                    &Triage {
                        state: "acknowledged".into(),
                        note: note.clone(),
                        bug_url: format!("https://bugs.example/{}", g.id),
                    },
                    "replay",
                )?;
                for a in &g.alerts {
                    self.triaged.insert(a.id, (g.id, note.clone()));
                }
            }
        }
        Ok(())
    }

    /// Requests every recorded URL through the router (following at most 3 redirects) and reads
    /// back the triage of every triaged alert.
    pub fn check(&self, pool: &Pool) -> anyhow::Result<Checked> {
        let mut out = Checked {
            urls: self.urls.len(),
            triaged_alerts: self.triaged.len(),
            triaged_groups: self.groups_triaged.len(),
            ..Checked::default()
        };
        let router = app(AppState::new(pool.clone(), None));
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()?;
        rt.block_on(async {
            for url in &self.urls {
                let mut path = url.clone();
                let mut trail = Vec::new();
                let mut ok = false;
                for _ in 0..4 {
                    let req = Request::get(&path).body(Body::empty())?;
                    let res = router.clone().oneshot(req).await?;
                    let status = res.status();
                    trail.push(status.as_u16().to_string());
                    if status.is_redirection() {
                        match res.headers().get(header::LOCATION) {
                            Some(l) => path = l.to_str()?.to_string(),
                            None => break,
                        }
                        continue;
                    }
                    ok = status.as_u16() == 200;
                    break;
                }
                if !ok {
                    out.broken
                        .push(format!("{url}: answered {}", trail.join(" -> ")));
                }
            }
            Ok::<_, anyhow::Error>(())
        })?;
        let mut conn = pool.get()?;
        for (&id, (group, note)) in &self.triaged {
            let now = alerts::read(
                &mut *conn,
                Select {
                    id: Some(id),
                    limit: 1,
                    ..Select::default()
                },
            )?;
            match now.first() {
                Some(a) if a.state == TriageState::Acknowledged && &a.note == note => {}
                Some(a) => out.triage_lost.push(format!(
                    "alert {id} (group {group}, now group {}): {:?} {:?}",
                    a.group_id, a.state, a.note
                )),
                None => out
                    .triage_lost
                    .push(format!("alert {id} (group {group}): gone")),
            }
        }
        Ok(out)
    }
}
