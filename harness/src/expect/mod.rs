//! Expectations: a suite's known outcomes per adapter, `scenarios/<suite>/expectations.toml`
//! beside its scenarios (the format is in `scenarios/README.md`, "Expectations"). Each entry
//! matches a scenario, optionally a variant, and optionally adapters (the match of `tessera run
//! --adapter`), and carries a label (`skip`, `slow`, `broken`, `flaky`, `no-perf`) and a reason.
//!
//! This module reads and checks the file (every error names the file, line, column and key, and
//! what is allowed) and finds the entry of a result; [`apply`] decides what a run does with it and
//! [`update`] rewrites the file from a run's outcomes. Not for: running scenarios.

pub mod apply;
pub mod digests;
pub mod update;

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

use tessera_results::expectation::Label;
use tessera_results::AdapterInfo;
use toml_edit::{Document, Item, Value};

use crate::scenario::pattern::matches as pattern_matches;
use crate::scenario::span::line_col;
use crate::scenario::Scenario;

/// The file name of a suite's expectations, in the suite's folder.
pub const FILE_NAME: &str = crate::scenario::EXPECTATIONS_FILE;

/// The keys of an `[[expectation]]` entry.
pub const KEYS: [&str; 5] = ["scenario", "variant", "adapter", "label", "reason"];

/// One entry of an expectations file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Entry {
    /// Scenario name pattern (`*` matches any run of characters).
    pub scenario: String,
    /// Variant name pattern; `None`: every variant of the scenario.
    pub variant: Option<String>,
    /// Texts that must each name the adapter as `--adapter` does; empty: every adapter.
    pub adapter: Vec<String>,
    pub label: Label,
    pub reason: String,
    /// 1-based line of the entry's `[[expectation]]` header.
    pub line: usize,
}

impl Entry {
    /// Whether this entry applies to `variant` of `scenario` on `adapter`.
    pub fn matches(&self, scenario: &str, variant: &str, adapter: &AdapterInfo) -> bool {
        pattern_matches(&self.scenario, scenario)
            && self
                .variant
                .as_deref()
                .is_none_or(|p| pattern_matches(p, variant))
            && self
                .adapter
                .iter()
                .all(|a| tessera_results::adapter::matches_info(a, adapter))
    }
}

/// A parsed expectations file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Expectations {
    pub file: PathBuf,
    pub entries: Vec<Entry>,
}

impl Expectations {
    /// Every entry that applies to this result, in file order.
    pub fn matching(&self, scenario: &str, variant: &str, adapter: &AdapterInfo) -> Vec<&Entry> {
        self.entries
            .iter()
            .filter(|e| e.matches(scenario, variant, adapter))
            .collect()
    }

    /// The entry that decides this result when several apply: a `skip`, else the first `broken`
    /// or `flaky` (what judges a failure), else the first in file order. (Whether a `slow`
    /// result runs is asked of every matching entry: [`apply::split`].)
    pub fn find(&self, scenario: &str, variant: &str, adapter: &AdapterInfo) -> Option<&Entry> {
        let all = self.matching(scenario, variant, adapter);
        all.iter()
            .find(|e| e.label == Label::Skip)
            .or_else(|| {
                all.iter()
                    .find(|e| matches!(e.label, Label::Broken | Label::Flaky))
            })
            .or(all.first())
            .copied()
    }

    /// `<file>:<line>` of an entry, as results record it.
    pub fn source(&self, e: &Entry) -> String {
        format!("{}:{}", self.file.display(), e.line)
    }
}

/// A problem in an expectations file, at a place in it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ExpectError {
    pub file: PathBuf,
    /// 1-based; 0 when the problem has no position (unreadable file).
    pub line: usize,
    pub column: usize,
    /// Dotted key path; empty for syntax errors.
    pub key: String,
    pub message: String,
}

impl fmt::Display for ExpectError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if self.line > 0 {
            write!(f, ":{}:{}", self.line, self.column)?;
        }
        if !self.key.is_empty() {
            write!(f, ": `{}`", self.key)?;
        }
        write!(f, ": {}", self.message)
    }
}

impl std::error::Error for ExpectError {}

/// Parses an expectations file's `source` as read from `path`: every problem, not only the first.
pub fn parse(path: &Path, source: &str) -> Result<Expectations, Vec<ExpectError>> {
    let err = |span: Option<std::ops::Range<usize>>, key: String, message: String| {
        let (line, column) = span.map_or((0, 0), |s| line_col(source, s.start));
        ExpectError {
            file: path.to_path_buf(),
            line,
            column,
            key,
            message,
        }
    };
    let doc: Document<String> = match source.to_string().parse() {
        Ok(d) => d,
        Err(e) => {
            return Err(vec![err(
                e.span(),
                String::new(),
                format!("not valid TOML: {}", e.message()),
            )])
        }
    };
    let mut errors = Vec::new();
    let mut entries = Vec::new();
    for (key, item) in doc.iter() {
        if key != "expectation" {
            let span = doc.key(key).and_then(|k| k.span());
            errors.push(err(
                span,
                key.to_string(),
                "unknown key: an expectations file holds `[[expectation]]` entries only".into(),
            ));
            continue;
        }
        let Item::ArrayOfTables(tables) = item else {
            let span = doc.key(key).and_then(|k| k.span());
            errors.push(err(
                span,
                key.to_string(),
                "must be an array of tables: write each entry as `[[expectation]]`".into(),
            ));
            continue;
        };
        for (i, table) in tables.iter().enumerate() {
            let at = |k: &str| format!("expectation[{i}].{k}");
            let header = table.span();
            let line = header.clone().map_or(0, |s| line_col(source, s.start).0);
            let mut fields: BTreeMap<&str, (&Value, Option<std::ops::Range<usize>>)> =
                BTreeMap::new();
            for (k, v) in table.iter() {
                let span = table.key(k).and_then(|key| key.span());
                if !KEYS.contains(&k) {
                    errors.push(err(
                        span,
                        at(k),
                        format!("unknown key; allowed: {}", KEYS.join(", ")),
                    ));
                    continue;
                }
                match v {
                    Item::Value(value) => {
                        fields.insert(k, (value, value.span().or(span)));
                    }
                    _ => errors.push(err(span, at(k), "must be a value, not a table".into())),
                }
            }
            let text = |k: &str, errors: &mut Vec<ExpectError>| -> Option<String> {
                let (v, span) = fields.get(k)?;
                match v.as_str() {
                    Some(s) if !s.trim().is_empty() => Some(s.to_string()),
                    Some(_) => {
                        errors.push(err(span.clone(), at(k), "must not be empty".into()));
                        None
                    }
                    None => {
                        errors.push(err(span.clone(), at(k), "must be a string".into()));
                        None
                    }
                }
            };
            let scenario = text("scenario", &mut errors);
            let variant = text("variant", &mut errors);
            let reason = text("reason", &mut errors);
            let label_text = text("label", &mut errors);
            let allowed = Label::ALL.map(Label::as_str).join(", ");
            let label = label_text.as_deref().and_then(|l| {
                let parsed = Label::parse(l);
                if parsed.is_none() {
                    let span = fields.get("label").and_then(|(_, s)| s.clone());
                    errors.push(err(
                        span,
                        at("label"),
                        format!("unknown label \"{l}\"; allowed: {allowed}"),
                    ));
                }
                parsed
            });
            let mut adapter = Vec::new();
            if let Some((v, span)) = fields.get("adapter") {
                match v {
                    Value::String(s) if !s.value().trim().is_empty() => {
                        adapter.push(s.value().clone())
                    }
                    Value::Array(a)
                        if !a.is_empty()
                            && a.iter()
                                .all(|x| x.as_str().is_some_and(|s| !s.trim().is_empty())) =>
                    {
                        adapter.extend(a.iter().filter_map(|x| x.as_str().map(String::from)))
                    }
                    _ => errors.push(err(
                        span.clone(),
                        at("adapter"),
                        "must be a non-empty string, or an array of them that must all match (the text `tessera run --adapter` takes: part of the name, driver or backend, or the vendor: nvidia, amd, intel, 0x10de)".into(),
                    )),
                }
            }
            for (k, missing) in [
                ("scenario", scenario.is_none()),
                ("label", label_text.is_none()),
                ("reason", reason.is_none()),
            ] {
                if missing && !fields.contains_key(k) {
                    let message = match k {
                        "reason" => "missing: every expectation says why (a sentence, the error or the issue)".to_string(),
                        "label" => format!("missing; one of: {allowed}"),
                        _ => "missing: the scenario's name (`*` matches any run of characters)".to_string(),
                    };
                    errors.push(err(header.clone(), at(k), message));
                }
            }
            if let (Some(scenario), Some(label), Some(reason)) = (scenario, label, reason) {
                entries.push(Entry {
                    scenario,
                    variant,
                    adapter,
                    label,
                    reason,
                    line,
                });
            }
        }
    }
    if errors.is_empty() {
        Ok(Expectations {
            file: path.to_path_buf(),
            entries,
        })
    } else {
        Err(errors)
    }
}

/// Reads `path`; `Ok(None)` when there is no such file.
pub fn load(path: &Path) -> Result<Option<Expectations>, Vec<ExpectError>> {
    match std::fs::read_to_string(path) {
        Ok(source) => parse(path, &source).map(Some),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(vec![ExpectError {
            file: path.to_path_buf(),
            line: 0,
            column: 0,
            key: String::new(),
            message: format!("cannot read the file: {e}"),
        }]),
    }
}

/// The expectations of every suite a run's scenarios come from: the `expectations.toml` in each
/// scenario file's folder.
#[derive(Clone, Debug, Default)]
pub struct Book {
    by_folder: BTreeMap<PathBuf, Expectations>,
}

impl Book {
    /// Reads the expectations beside each scenario's file; every error of every file.
    pub fn load_for(scenarios: &[Scenario]) -> Result<Book, Vec<ExpectError>> {
        let mut book = Book::default();
        let mut errors = Vec::new();
        let mut seen = std::collections::BTreeSet::new();
        for s in scenarios {
            let folder = s.file.parent().unwrap_or(Path::new("")).to_path_buf();
            if !seen.insert(folder.clone()) {
                continue;
            }
            match load(&folder.join(FILE_NAME)) {
                Ok(Some(e)) => {
                    book.by_folder.insert(folder, e);
                }
                Ok(None) => {}
                Err(e) => errors.extend(e),
            }
        }
        if errors.is_empty() {
            Ok(book)
        } else {
            Err(errors)
        }
    }

    /// A book of one file, for scenarios in `folder` (tests).
    pub fn of(folder: PathBuf, e: Expectations) -> Book {
        Book {
            by_folder: BTreeMap::from([(folder, e)]),
        }
    }

    /// The expectations that apply to `scenario`'s file.
    pub fn for_scenario(&self, scenario: &Scenario) -> Option<&Expectations> {
        self.by_folder
            .get(scenario.file.parent().unwrap_or(Path::new("")))
    }

    pub fn is_empty(&self) -> bool {
        self.by_folder.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn errors(src: &str) -> Vec<String> {
        parse(Path::new("s/expectations.toml"), src)
            .unwrap_err()
            .iter()
            .map(ToString::to_string)
            .collect()
    }

    #[test]
    fn parses_entries_with_their_lines() {
        let src = "# known outcomes\n\n[[expectation]]\nscenario = \"resolution-*\"\nadapter = \"llvmpipe\"\nlabel = \"slow\"\nreason = \"minutes on a CPU\"\n\n[[expectation]]\nscenario = \"hdr\"\nvariant = \"checkerboard*\"\nadapter = [\"nvidia\", \"vulkan\"]\nlabel = \"broken\"\nreason = \"issue 99\"\n";
        let e = parse(Path::new("s/expectations.toml"), src).unwrap();
        assert_eq!(e.entries.len(), 2);
        assert_eq!(e.entries[0].line, 3);
        assert_eq!(e.entries[0].label, Label::Slow);
        assert_eq!(e.entries[1].line, 9);
        assert_eq!(e.entries[1].variant.as_deref(), Some("checkerboard*"));
        assert_eq!(e.entries[1].adapter, vec!["nvidia", "vulkan"]);
        assert_eq!(e.source(&e.entries[1]), "s/expectations.toml:9");
    }

    #[test]
    fn errors_name_line_column_key_and_what_is_allowed() {
        let src = "[[expectation]]\nscenario = \"a\"\nlabel = \"broke\"\nreason = \"x\"\n\n[[expectation]]\nscenario = \"b\"\nlabel = \"skip\"\ncolour = 1\n";
        assert_eq!(
            errors(src),
            vec![
                "s/expectations.toml:3:9: `expectation[0].label`: unknown label \"broke\"; allowed: skip, slow, broken, flaky, no-perf",
                "s/expectations.toml:9:1: `expectation[1].colour`: unknown key; allowed: scenario, variant, adapter, label, reason",
                "s/expectations.toml:6:1: `expectation[1].reason`: missing: every expectation says why (a sentence, the error or the issue)",
            ]
        );
        assert_eq!(
            errors("[[expectation]]\nscenario = 3\nlabel = \"skip\"\nreason = \"\"\nadapter = []\n"),
            vec![
                "s/expectations.toml:2:12: `expectation[0].scenario`: must be a string",
                "s/expectations.toml:4:10: `expectation[0].reason`: must not be empty",
                "s/expectations.toml:5:11: `expectation[0].adapter`: must be a non-empty string, or an array of them that must all match (the text `tessera run --adapter` takes: part of the name, driver or backend, or the vendor: nvidia, amd, intel, 0x10de)",
            ]
        );
        assert_eq!(
            errors("expectations = 1\n"),
            vec!["s/expectations.toml:1:1: `expectations`: unknown key: an expectations file holds `[[expectation]]` entries only"]
        );
        assert!(errors("[[expectation]\n")[0].starts_with("s/expectations.toml:1:"));
    }

    #[test]
    fn matching_uses_patterns_and_the_adapter_rule() {
        let src = "[[expectation]]\nscenario = \"res*\"\nvariant = \"native\"\nadapter = \"llvmpipe\"\nlabel = \"no-perf\"\nreason = \"r\"\n";
        let e = parse(Path::new("x"), src).unwrap();
        let mut a = AdapterInfo {
            name: "llvmpipe (LLVM 15.0.6, 256 bits)".into(),
            vendor: 0x10005,
            device: 0,
            device_type: "cpu".into(),
            driver: "llvmpipe".into(),
            driver_info: String::new(),
            backend: "vulkan".into(),
            features: Default::default(),
        };
        assert!(e.find("resolution-1x1", "native", &a).is_some());
        assert!(e.find("resolution-1x1", "upscale", &a).is_none());
        assert!(e.find("black", "native", &a).is_none());
        a.name = "NVIDIA H200".into();
        a.driver = "NVIDIA".into();
        assert!(e.find("resolution-1x1", "native", &a).is_none());
    }
}
