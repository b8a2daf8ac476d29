//! `tessera expectations update RUN...`: rewrites each suite's `expectations.toml` from runs'
//! outcomes, the way Mesa's CI script refreshes its trace lists: a result that failed with no
//! entry becomes a `broken` entry with the error as its reason, and an entry whose results all
//! passed (an unexpected pass) is removed. The file is edited with `toml_edit`, so comments and
//! the other entries stay as they were, and the change is shown as a unified diff for review.
//!
//! Not for: running scenarios or judging results (see [`super::apply`]).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use tessera_results::expectation::{Label, Outcome};
use tessera_results::folder::{self, Run};
use toml_edit::{ArrayOfTables, DocumentMut, Item, Table};

use super::apply::{failed, failure_text};
use super::{ExpectError, FILE_NAME};

/// Why an update could not be made.
#[derive(Debug, thiserror::Error)]
pub enum UpdateError {
    #[error(transparent)]
    Read(#[from] folder::ReadError),
    #[error("{}", .0.iter().map(ToString::to_string).collect::<Vec<_>>().join("\n"))]
    Expectations(Vec<ExpectError>),
    #[error("cannot write {path}: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// A `broken` entry to add.
#[derive(Clone, Debug, PartialEq, Eq)]
struct NewEntry {
    scenario: String,
    variant: String,
    adapter: String,
    reason: String,
}

/// What one expectations file gets.
#[derive(Default, Debug)]
struct FileChange {
    add: Vec<NewEntry>,
    /// Lines of entries whose results passed.
    passed: Vec<usize>,
    /// Lines of entries some of whose results still fail (kept even if another passed).
    still_failing: Vec<usize>,
}

/// One file's update: its path, old and new text.
#[derive(Debug)]
pub struct FileUpdate {
    pub path: PathBuf,
    pub before: String,
    pub after: String,
    /// Entries kept although one of their results passed, because another still fails: the
    /// pattern must be narrowed by hand.
    pub notes: Vec<String>,
}

impl FileUpdate {
    /// The change as a unified diff (`similar`), paths as `a/<file>` and `b/<file>`.
    pub fn diff(&self) -> String {
        let name = self.path.display().to_string();
        similar::TextDiff::from_lines(&self.before, &self.after)
            .unified_diff()
            .context_radius(3)
            .header(&format!("a/{name}"), &format!("b/{name}"))
            .to_string()
    }

    pub fn changed(&self) -> bool {
        self.before != self.after
    }
}

/// The adapter text an added entry names: the adapter class where `--adapter` matching finds it
/// (`llvmpipe`, `nvidia`, `amd`, `intel`), else the PCI vendor id.
fn adapter_text(run: &Run) -> String {
    let class = tessera_results::adapter::class(&run.info.adapter);
    if tessera_results::adapter::matches_info(&class, &run.info.adapter) {
        class
    } else {
        format!("0x{:04x}", run.info.adapter.vendor)
    }
}

/// The error as a reason: its first line, at most 200 characters.
fn reason_of(error: &str) -> String {
    let line = error.lines().next().unwrap_or("").trim();
    let mut out: String = line.chars().take(200).collect();
    if line.chars().count() > 200 {
        out.push('…');
    }
    if out.is_empty() {
        "failed (no error text)".to_string()
    } else {
        out
    }
}

/// Line of an entry from a result's `source` (`<file>:<line>`).
fn source_line(source: &str) -> Option<(PathBuf, usize)> {
    let (file, line) = source.rsplit_once(':')?;
    Some((PathBuf::from(file), line.parse().ok()?))
}

/// Works out every file's update from the run folders; nothing is written.
pub fn plan(runs: &[PathBuf]) -> Result<Vec<FileUpdate>, UpdateError> {
    let mut changes: BTreeMap<PathBuf, FileChange> = BTreeMap::new();
    for dir in runs {
        let run = folder::read(dir)?;
        let adapter = adapter_text(&run);
        for s in &run.scenarios {
            let file = Path::new(&s.file)
                .parent()
                .unwrap_or(Path::new(""))
                .join(FILE_NAME);
            for r in &s.results {
                // A failure no `broken` or `flaky` entry judged (none matched, or only a
                // `slow` or `no-perf` one) is new.
                let judged = r.expectation.as_ref().filter(|x| x.outcome != Outcome::Ran);
                match judged {
                    None if failed(r) => {
                        let e = NewEntry {
                            scenario: s.scenario.clone(),
                            variant: r.variant.clone(),
                            adapter: adapter.clone(),
                            reason: reason_of(&failure_text(r).unwrap_or_default()),
                        };
                        let c = changes.entry(file.clone()).or_default();
                        if !c.add.contains(&e) {
                            c.add.push(e);
                        }
                    }
                    Some(x) => {
                        let Some((path, line)) = source_line(&x.source) else {
                            continue;
                        };
                        let c = changes.entry(path).or_default();
                        match x.outcome {
                            Outcome::UnexpectedPass => c.passed.push(line),
                            Outcome::ExpectedFailure => c.still_failing.push(line),
                            _ => {}
                        }
                    }
                    None => {}
                }
            }
        }
    }
    changes
        .into_iter()
        .map(|(path, change)| apply(&path, &change))
        .collect()
}

/// Edits one file's text.
fn apply(path: &Path, change: &FileChange) -> Result<FileUpdate, UpdateError> {
    let before = match std::fs::read_to_string(path) {
        Ok(s) => s,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
        Err(source) => {
            return Err(UpdateError::Write {
                path: path.to_path_buf(),
                source,
            })
        }
    };
    let parsed = super::parse(path, &before).map_err(UpdateError::Expectations)?;
    let mut doc: DocumentMut = before.parse().map_err(|e: toml_edit::TomlError| {
        UpdateError::Expectations(vec![ExpectError {
            file: path.to_path_buf(),
            line: 0,
            column: 0,
            key: String::new(),
            message: e.to_string(),
        }])
    })?;
    let mut notes = Vec::new();
    // Entries (by index) to remove: every result they applied to passed.
    let mut remove: Vec<usize> = Vec::new();
    for (i, e) in parsed.entries.iter().enumerate() {
        if !change.passed.contains(&e.line) {
            continue;
        }
        if change.still_failing.contains(&e.line) {
            notes.push(format!(
                "{}:{}: kept: some results this `broken` entry matches passed and some still fail; narrow its `variant` by hand",
                path.display(),
                e.line
            ));
        } else {
            remove.push(i);
        }
    }
    if !doc.contains_key("expectation") {
        doc.insert("expectation", Item::ArrayOfTables(ArrayOfTables::new()));
    }
    let aot = doc["expectation"]
        .as_array_of_tables_mut()
        .expect("the file parsed as expectations: `expectation` is an array of tables");
    // A removed entry takes the comment lines right above it along; what stands before a blank
    // line (the file's own header, an earlier note) stays, in front of the next entry.
    let mut trailing_keep = String::new();
    for i in remove.into_iter().rev() {
        let prefix = aot
            .get(i)
            .and_then(|t| t.decor().prefix())
            .and_then(|p| p.as_str())
            .unwrap_or("")
            .to_string();
        let keep = prefix
            .rfind("\n\n")
            .map_or(String::new(), |p| prefix[..p + 2].to_string());
        aot.remove(i);
        if keep.is_empty() {
            continue;
        }
        match aot.get_mut(i) {
            Some(next) => {
                let old = next
                    .decor()
                    .prefix()
                    .and_then(|p| p.as_str())
                    .unwrap_or("")
                    .to_string();
                next.decor_mut().set_prefix(format!("{keep}{old}"));
            }
            None => trailing_keep = keep,
        }
    }
    for e in &change.add {
        let mut t = Table::new();
        t.insert("scenario", toml_edit::value(e.scenario.as_str()));
        t.insert("variant", toml_edit::value(e.variant.as_str()));
        t.insert("adapter", toml_edit::value(e.adapter.as_str()));
        t.insert("label", toml_edit::value(Label::Broken.as_str()));
        t.insert("reason", toml_edit::value(e.reason.as_str()));
        aot.push(t);
    }
    if !trailing_keep.is_empty() {
        let old = doc.trailing().as_str().unwrap_or("").to_string();
        doc.set_trailing(format!("{trailing_keep}{old}"));
    }
    let mut after = doc.to_string();
    // A file left without entries keeps its comments and nothing else.
    if doc["expectation"]
        .as_array_of_tables()
        .is_some_and(|a| a.is_empty())
    {
        after = after.trim_end().to_string();
        if !after.is_empty() {
            after.push('\n');
        }
    }
    Ok(FileUpdate {
        path: path.to_path_buf(),
        before,
        after,
        notes,
    })
}

/// Writes a file's new text.
pub fn write(u: &FileUpdate) -> Result<(), UpdateError> {
    crate::files::write_atomic(&u.path, u.after.as_bytes()).map_err(|e| UpdateError::Write {
        path: e.path,
        source: e.source,
    })
}
