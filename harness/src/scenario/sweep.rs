//! `[sweep]`: one scenario file run at every combination of some of its values, e.g. the city
//! from vertex-bound to shading-bound (issue 23, item 5):
//!
//! ```toml
//! [sweep]
//! "scene.shading_cost" = [0, 4, 16, 64]
//! "scene.city.blocks" = [2, 12]
//! resolution = [[1920, 1080], [3840, 2160]]
//! ```
//!
//! Each key is the dotted path of a value elsewhere in the file (its tables must be in the file;
//! the value itself may be left out there), each value the list to run. The file expands into one
//! scenario per combination, named `name[shading_cost=4,blocks=2,resolution=1920x1080]` (a key's
//! last part, or its whole path where two would read the same), with the swept values written in
//! place of the file's own, so that every other error still points at its own line.
//!
//! Not here: validation of the swept values, which is the ordinary validation of each expanded
//! scenario (its errors say which combination they come from).

use std::path::Path;

use toml_edit::{Document, DocumentMut, Item, Table, Value};

use super::span::{line_col, locate, KeyPath};
use super::{ScenarioError, ScenarioErrors};

/// Most scenarios one file may expand into.
pub const MAX_COMBINATIONS: usize = 256;

/// Keys a sweep cannot change: they name or shape the file rather than set a value.
const FIXED: [&str; 4] = ["sweep", "name", "techniques", "gates"];

/// One expanded scenario: the swept values (label, value as written in the name) and the source
/// with them in place.
#[derive(Clone, Debug, PartialEq)]
pub struct Expanded {
    pub values: Vec<(String, String)>,
    /// The swept keys' dotted paths, in the order of `values`.
    pub keys: Vec<String>,
    pub source: String,
}

/// One swept key: its path, where it is in the file and the values to run.
struct Axis {
    key: KeyPath,
    path: Vec<String>,
    values: Vec<Value>,
}

/// Expands `source` by its `[sweep]` table; one [`Expanded`] with no values when it has none (or
/// when the file does not parse: the ordinary parser reports that).
pub fn expand(path: &Path, source: &str) -> Result<Vec<Expanded>, ScenarioErrors> {
    let single = || {
        vec![Expanded {
            values: Vec::new(),
            keys: Vec::new(),
            source: source.to_string(),
        }]
    };
    let Ok(doc) = source.parse::<DocumentMut>() else {
        return Ok(single());
    };
    let Some(sweep) = doc.get("sweep") else {
        return Ok(single());
    };
    let spans: Option<Document<String>> = source.to_string().parse().ok();
    let error = |key: &KeyPath, message: String| {
        let (line, column) = spans
            .as_ref()
            .and_then(|d| locate(d, key))
            .map(|s| line_col(source, s.start))
            .unwrap_or((1, 1));
        ScenarioErrors(vec![ScenarioError {
            file: path.to_path_buf(),
            line,
            column,
            key: key.to_string(),
            message,
        }])
    };
    let root = KeyPath::root().key("sweep");
    let Some(table) = sweep.as_table_like() else {
        return Err(error(
            &root,
            "must be a table of dotted keys and the lists of values to run, e.g. \
             `\"scene.shading_cost\" = [0, 4, 16]`"
                .to_string(),
        ));
    };
    let mut axes = Vec::new();
    collect_axes(table, &root, &mut Vec::new(), &mut axes, &error)?;
    if axes.is_empty() {
        return Err(error(&root, "names no key to sweep".to_string()));
    }
    for axis in &axes {
        check_target(doc.as_table(), &axis.path).map_err(|m| error(&axis.key, m))?;
    }
    let count = axes
        .iter()
        .try_fold(1usize, |n, a| n.checked_mul(a.values.len()))
        .unwrap_or(usize::MAX);
    if count > MAX_COMBINATIONS {
        return Err(error(
            &root,
            format!("expands into {count} scenarios; at most {MAX_COMBINATIONS} are allowed"),
        ));
    }
    let labels = labels(&axes);
    let mut out = Vec::with_capacity(count);
    for n in 0..count {
        let mut doc = doc.clone();
        let mut values = Vec::new();
        let mut rest = n;
        // The last axis varies fastest, as nested loops over the keys in the file's order.
        let mut picks = vec![0; axes.len()];
        for (i, a) in axes.iter().enumerate().rev() {
            picks[i] = rest % a.values.len();
            rest /= a.values.len();
        }
        for ((axis, label), &pick) in axes.iter().zip(&labels).zip(&picks) {
            let value = &axis.values[pick];
            set(doc.as_table_mut(), &axis.path, value.clone());
            values.push((label.clone(), show(value)));
        }
        out.push(Expanded {
            values,
            keys: axes.iter().map(|a| a.path.join(".")).collect(),
            source: doc.to_string(),
        });
    }
    Ok(out)
}

/// Gathers the axes of a sweep table: quoted dotted keys (`"scene.city.blocks" = [...]`) and
/// nested tables (`scene.city.blocks = [...]`) alike.
fn collect_axes(
    table: &dyn toml_edit::TableLike,
    at: &KeyPath,
    prefix: &mut Vec<String>,
    axes: &mut Vec<Axis>,
    error: &dyn Fn(&KeyPath, String) -> ScenarioErrors,
) -> Result<(), ScenarioErrors> {
    for (key, item) in table.iter() {
        let here = at.key(key);
        let mut path = prefix.clone();
        path.extend(key.split('.').map(str::to_string));
        if path.iter().any(|p| p.is_empty()) {
            return Err(error(&here, "is not a dotted key path".to_string()));
        }
        if let Some(inner) = item.as_table_like() {
            prefix.push(key.to_string());
            collect_axes(inner, &here, prefix, axes, error)?;
            prefix.pop();
            continue;
        }
        let Some(list) = item.as_array() else {
            return Err(error(
                &here,
                "must be a list of the values to run, e.g. [0, 4, 16]".to_string(),
            ));
        };
        if list.is_empty() {
            return Err(error(&here, "lists no value to run".to_string()));
        }
        if FIXED.contains(&path[0].as_str()) {
            return Err(error(
                &here,
                format!(
                    "`{}` cannot be swept: list techniques' values in [[techniques]] and \
                     gates in [[gates]]",
                    path[0]
                ),
            ));
        }
        if axes.iter().any(|a: &Axis| a.path == path) {
            return Err(error(&here, "is swept twice".to_string()));
        }
        axes.push(Axis {
            key: here,
            path,
            values: list.iter().cloned().collect(),
        });
    }
    Ok(())
}

/// Checks that every table above the swept value is in the file (as a table, not a list of
/// tables or a value).
fn check_target(root: &Table, path: &[String]) -> Result<(), String> {
    let mut table: &dyn toml_edit::TableLike = root;
    for (depth, part) in path[..path.len() - 1].iter().enumerate() {
        let so_far = path[..=depth].join(".");
        table = match table.get(part) {
            None => {
                return Err(format!(
                    "`{so_far}` is not in the file: add its table first"
                ))
            }
            Some(item) => item.as_table_like().ok_or_else(|| {
                format!("`{so_far}` is not a table: only values in tables can be swept")
            })?,
        };
    }
    let leaf = &path[path.len() - 1];
    match table.get(leaf) {
        Some(item) if item.is_table_like() || item.is_array_of_tables() => Err(format!(
            "`{}` is a table, not a value: sweep the values in it",
            path.join(".")
        )),
        _ => Ok(()),
    }
}

/// Writes `value` at `path`, in place of the file's value (keeping its position) or added to its
/// table.
fn set(root: &mut Table, path: &[String], value: Value) {
    let mut table: &mut dyn toml_edit::TableLike = root;
    for part in &path[..path.len() - 1] {
        table = table
            .get_mut(part)
            .and_then(Item::as_table_like_mut)
            .expect("checked by check_target");
    }
    let leaf = &path[path.len() - 1];
    match table.get_mut(leaf).and_then(Item::as_value_mut) {
        Some(old) => {
            let decor = old.decor().clone();
            *old = value;
            *old.decor_mut() = decor;
        }
        None => {
            table.insert(leaf, Item::Value(value.decorated(" ", "")));
        }
    }
}

/// Each axis's label in the names: its key's last part, or the whole path where two axes share a
/// last part.
fn labels(axes: &[Axis]) -> Vec<String> {
    axes.iter()
        .map(|a| {
            let last = a.path.last().expect("paths are not empty");
            let shared = axes.iter().filter(|b| b.path.last() == Some(last)).count() > 1;
            if shared {
                a.path.join(".")
            } else {
                last.clone()
            }
        })
        .collect()
}

/// A swept value as it reads in a scenario name: `4`, `0.5`, `"name"` as `name`, a `[w, h]` pair
/// as `wxh`.
fn show(value: &Value) -> String {
    match value {
        Value::String(s) => s.value().clone(),
        Value::Array(a) => {
            let parts: Vec<String> = a.iter().map(show).collect();
            parts.join("x")
        }
        other => other.clone().decorated("", "").to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn expand_str(src: &str) -> Result<Vec<Expanded>, ScenarioErrors> {
        expand(Path::new("sweep.toml"), src)
    }

    #[test]
    fn a_file_without_a_sweep_is_itself() {
        let e = expand_str("resolution = [4, 4]\n").unwrap();
        assert_eq!(e.len(), 1);
        assert!(e[0].values.is_empty());
        assert_eq!(e[0].source, "resolution = [4, 4]\n");
    }

    #[test]
    fn every_combination_with_the_values_in_place() {
        let src = "resolution = [8, 8]\n[scene]\nshading_cost = 1\n[scene.city]\nseed = 1\n\
                   [sweep]\n\"scene.shading_cost\" = [0, 16]\nscene.city.blocks = [2, 12]\n\
                   resolution = [[1920, 1080], [3840, 2160]]\n";
        let e = expand_str(src).unwrap();
        assert_eq!(e.len(), 8);
        let names: Vec<String> = e
            .iter()
            .map(|x| {
                x.values
                    .iter()
                    .map(|(k, v)| format!("{k}={v}"))
                    .collect::<Vec<_>>()
                    .join(",")
            })
            .collect();
        assert_eq!(names[0], "shading_cost=0,blocks=2,resolution=1920x1080");
        assert_eq!(names[7], "shading_cost=16,blocks=12,resolution=3840x2160");
        let last: toml::Table = toml::from_str(&e[7].source).unwrap();
        assert_eq!(last["scene"]["shading_cost"].as_integer(), Some(16));
        assert_eq!(last["scene"]["city"]["blocks"].as_integer(), Some(12));
        assert_eq!(last["resolution"][0].as_integer(), Some(3840));
        // The file's own value is replaced where it stood: lines keep their numbers.
        let line = |s: &str, k: &str| s.lines().position(|l| l.starts_with(k));
        assert_eq!(
            line(&e[7].source, "shading_cost"),
            line(src, "shading_cost")
        );
    }

    #[test]
    fn bad_sweeps_name_the_key_and_the_line() {
        let cases = [
            ("[sweep]\n\"scene.cost\" = 4\n", "must be a list"),
            (
                "[sweep]\n\"scene.city.blocks\" = [1]\n",
                "`scene` is not in the file",
            ),
            (
                "[scene]\n[sweep]\n\"scene.city.blocks\" = [1]\n",
                "`scene.city` is not in",
            ),
            ("[sweep]\nname = [\"a\"]\n", "cannot be swept"),
            ("[sweep]\nresolution = []\n", "lists no value"),
            ("[scene]\n[sweep]\nscene = [1]\n", "is a table, not a value"),
            ("sweep = 3\n", "must be a table"),
        ];
        for (src, want) in cases {
            let e = expand_str(src).unwrap_err();
            let text = e.to_string();
            assert!(text.contains(want), "{src:?}: {text}");
            assert!(e.0[0].line > 0, "{src:?}: {text}");
        }
        let big = "[scene]\n[sweep]\n\"scene.a\" = [1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17]\n\
                   \"scene.b\" = [1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17]\n";
        assert!(expand_str(big)
            .unwrap_err()
            .to_string()
            .contains("expands into 289 scenarios"));
    }
}
