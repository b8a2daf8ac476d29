//! No import circle in the harness (issue 21's acceptance): reads every `.rs` file under
//! `harness/src/`, takes the modules each one names (`use crate::a::b`, `crate::a::b::X` in code,
//! `super::x`, a child's `pub use`), and fails listing every strongly connected set of files, so
//! "no import circle" is checked rather than claimed.
//!
//! File level: `render/scene.rs` naming `scenario::Scenario` is an edge from that file to
//! `scenario/mod.rs`; a path through a re-export is an edge to the file that defines the item.
//! A file naming an item of its own folder's `mod.rs` (`super::Options` in `interlace/gpu.rs`:
//! one module split in files) is no edge; the folder naming its files is. Code from the first `#[cfg(test)]` of a file on is
//! left out (unit tests may reach anywhere). Not for: the dashboard (its own crate), macros'
//! expansions, or `self::` paths (a file naming itself).
//!
//! Runs without a GPU and without building anything but this file; also usable by hand:
//! `cargo test -p tessera --test imports -- --nocapture` prints the graph's size.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

/// A module path from the crate root (`["render", "scene"]`), and the file that holds it.
type ModPath = Vec<String>;

fn src_dir() -> PathBuf {
    Path::new(option_env!("CARGO_MANIFEST_DIR").unwrap_or("harness")).join("src")
}

/// Every module file under `src/`, by module path. `main.rs` is the binary's root: it is left
/// out (it names the library as `tessera::`, never `crate::`).
fn module_files(src: &Path) -> BTreeMap<ModPath, PathBuf> {
    let mut out = BTreeMap::new();
    let mut stack = vec![src.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            if path.extension().and_then(|e| e.to_str()) != Some("rs") {
                continue;
            }
            let rel = path.strip_prefix(src).unwrap();
            let mut parts: Vec<String> = rel
                .iter()
                .map(|p| p.to_string_lossy().into_owned())
                .collect();
            let file = parts.pop().unwrap();
            let stem = file.trim_end_matches(".rs").to_string();
            if parts.is_empty() && stem == "main" {
                continue;
            }
            if !(stem == "mod" || (parts.is_empty() && stem == "lib")) {
                parts.push(stem);
            }
            out.insert(parts, path);
        }
    }
    out
}

/// The code of a file without comments, string literals and its unit tests.
fn code_of(text: &str) -> String {
    split_code(text).0
}

/// The code of a file without comments, string literals and its unit tests, and the contents of
/// those string literals (escapes left as written).
fn split_code(text: &str) -> (String, Vec<String>) {
    let text = match text.find("#[cfg(test)]") {
        Some(i) => &text[..i],
        None => text,
    };
    let mut literals = Vec::new();
    let mut out = String::with_capacity(text.len());
    let b = text.as_bytes();
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'/' && b.get(i + 1) == Some(&b'/') {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if b[i] == b'/' && b.get(i + 1) == Some(&b'*') {
            i += 2;
            while i + 1 < b.len() && !(b[i] == b'*' && b[i + 1] == b'/') {
                i += 1;
            }
            i += 2;
        } else if b[i] == b'"' {
            // A string literal; raw strings (`r#"..."#`, WGSL sources) end at `"` and their hashes.
            let mut hashes = 0;
            while i > hashes && b[i - 1 - hashes] == b'#' {
                hashes += 1;
            }
            let raw = i > hashes && b[i - 1 - hashes] == b'r';
            i += 1;
            let start = i;
            let end;
            if raw {
                let close: Vec<u8> = std::iter::once(b'"')
                    .chain(std::iter::repeat_n(b'#', hashes))
                    .collect();
                while i < b.len() && !b[i..].starts_with(&close) {
                    i += 1;
                }
                end = i;
                i += hashes;
            } else {
                while i < b.len() && b[i] != b'"' {
                    if b[i] == b'\\' {
                        i += 1;
                    }
                    i += 1;
                }
                end = i;
            }
            literals.push(text[start..end.min(b.len())].to_string());
            i += 1;
            out.push_str("\"\"");
        } else if b[i] == b'\'' && b.get(i + 2) == Some(&b'\'') {
            // A char literal such as '"' (not a lifetime).
            i += 3;
        } else if b[i] == b'\'' && b.get(i + 1) == Some(&b'\\') {
            // An escaped char literal ('\'', '\\', '\n').
            i += 2;
            while i < b.len() && b[i] != b'\'' {
                i += 1;
            }
            i += 1;
        } else {
            out.push(b[i] as char);
            i += 1;
        }
    }
    (out, literals)
}

/// Every path the code names, as segments, with `crate`/`super` resolved against `here`
/// (the module the file is) and `use` groups (`use crate::a::{b, c::d}`) expanded.
fn named_paths(code: &str, here: &[String], children: &[&String]) -> Vec<ModPath> {
    let mut out = Vec::new();
    let b = code.as_bytes();
    let is_ident = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    let mut i = 0;
    while i < b.len() {
        let at_word = i == 0 || !(is_ident(b[i - 1]) || b[i - 1] == b':');
        let starts = |w: &str| {
            b[i..].starts_with(w.as_bytes()) && !b.get(i + w.len()).is_some_and(|c| is_ident(*c))
        };
        let child = children
            .iter()
            .find(|c| starts(c.as_str()) && b[i + c.len()..].starts_with(b"::"));
        if at_word && child.is_some() {
            // A child module by its relative name (`vrs::Caps` in `gpu/mod.rs`).
            let (path, end) = read_path(code, i);
            i = end;
            for p in expand(&path) {
                out.push([here.to_vec(), p].concat());
            }
        } else if at_word && (starts("crate") || starts("super")) {
            let (path, end) = read_path(code, i);
            i = end;
            for p in expand(&path) {
                if let Some(resolved) = resolve(&p, here) {
                    out.push(resolved);
                }
            }
        } else {
            i += 1;
        }
    }
    // Re-exports of a folder's children (`pub use gpu::X` in `interlace/mod.rs`): relative.
    for line in code.lines() {
        let t = line.trim_start();
        let rest = match t
            .strip_prefix("pub use ")
            .or_else(|| t.strip_prefix("use "))
        {
            Some(r) => r,
            None => continue,
        };
        if rest.starts_with("crate") || rest.starts_with("super") || rest.starts_with("self") {
            continue;
        }
        let path: String = rest.chars().take_while(|c| *c != ';').collect();
        for p in expand(&path) {
            let mut full = here.to_vec();
            full.extend(p);
            out.push(full);
        }
    }
    out
}

/// The path starting at `start` (`crate::a::{b, c}`), up to where it ends, and its end.
fn read_path(code: &str, start: usize) -> (String, usize) {
    let b = code.as_bytes();
    let mut i = start;
    let mut depth = 0i32;
    while i < b.len() {
        let c = b[i];
        let ok = c.is_ascii_alphanumeric()
            || c == b'_'
            || c == b':'
            || (depth > 0 && (c == b',' || c.is_ascii_whitespace() || c == b'*'))
            || c == b'{'
            || (c == b'}' && depth > 0);
        if !ok {
            break;
        }
        if c == b'{' {
            depth += 1;
        }
        if c == b'}' {
            depth -= 1;
        }
        i += 1;
    }
    (code[start..i].to_string(), i)
}

/// `a::{b, c::{d, e}}` into `a::b`, `a::c::d`, `a::c::e` as segments.
fn expand(path: &str) -> Vec<ModPath> {
    let path: String = path.chars().filter(|c| !c.is_whitespace()).collect();
    let path = path.trim_end_matches("::");
    match path.find('{') {
        None => {
            let segs: Vec<String> = path
                .split("::")
                .filter(|s| !s.is_empty())
                .map(|s| s.split(" as ").next().unwrap().to_string())
                .collect();
            vec![segs]
        }
        Some(open) => {
            let prefix = &path[..open];
            let inner = &path[open + 1..path.rfind('}').unwrap_or(path.len())];
            let mut parts = Vec::new();
            let (mut depth, mut last) = (0, 0);
            for (j, c) in inner.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        parts.push(&inner[last..j]);
                        last = j + 1;
                    }
                    _ => {}
                }
            }
            parts.push(&inner[last..]);
            let mut out = Vec::new();
            for part in parts.into_iter().filter(|p| !p.is_empty()) {
                for tail in expand(part) {
                    let mut segs: Vec<String> = expand(prefix).pop().unwrap();
                    segs.extend(tail.into_iter().filter(|s| s != "self"));
                    out.push(segs);
                }
            }
            out
        }
    }
}

/// `crate::x` from the root, `super::x` from the parent of `here`.
fn resolve(path: &[String], here: &[String]) -> Option<ModPath> {
    let mut base: Vec<String> = Vec::new();
    let mut rest = path;
    match rest.first().map(String::as_str) {
        Some("crate") => rest = &rest[1..],
        Some("super") => {
            base = here.to_vec();
            while rest.first().map(String::as_str) == Some("super") {
                base.pop()?;
                rest = &rest[1..];
            }
        }
        _ => return None,
    }
    base.extend(rest.iter().cloned());
    Some(base)
}

/// The module file a path lands in: its longest prefix that is a module file.
fn owner<'a>(path: &[String], modules: &'a BTreeMap<ModPath, PathBuf>) -> Option<&'a ModPath> {
    (0..=path.len())
        .rev()
        .find_map(|n| modules.get_key_value(&path[..n]).map(|(k, _)| k))
}

/// What each module re-exports: `pub use gpu::{A, B}` in `interlace/mod.rs` maps `A` and `B` to
/// `techniques::interlace::gpu::A`, `...::B`.
fn reexports(modules: &BTreeMap<ModPath, PathBuf>) -> BTreeMap<ModPath, BTreeMap<String, ModPath>> {
    let mut out = BTreeMap::new();
    for (module, file) in modules {
        let code = code_of(&fs::read_to_string(file).unwrap());
        let mut names = BTreeMap::new();
        for line in code.split(';') {
            let Some(rest) = line.trim_start().strip_prefix("pub use ") else {
                continue;
            };
            for p in expand(rest) {
                let full = match p.first().map(String::as_str) {
                    Some("crate") | Some("super") => resolve(&p, module),
                    Some("self") => Some([module.clone(), p[1..].to_vec()].concat()),
                    Some(_)
                        if modules.keys().any(|m| {
                            m.starts_with(&[module.clone(), vec![p[0].clone()]].concat())
                        }) =>
                    {
                        Some([module.clone(), p.clone()].concat())
                    }
                    _ => None,
                };
                if let (Some(full), Some(last)) = (full, p.last()) {
                    names.insert(last.clone(), full);
                }
            }
        }
        out.insert(module.clone(), names);
    }
    out
}

/// The module file that holds what `path` names: its longest prefix that is a module file,
/// followed through that module's re-exports to where the item is defined.
fn holder(
    path: &[String],
    modules: &BTreeMap<ModPath, PathBuf>,
    reexports: &BTreeMap<ModPath, BTreeMap<String, ModPath>>,
) -> Option<ModPath> {
    let mut path = path.to_vec();
    for _ in 0..8 {
        let m = owner(&path, modules)?.clone();
        let Some(next) = path.get(m.len()) else {
            return Some(m);
        };
        match reexports.get(&m).and_then(|r| r.get(next)) {
            Some(target) if *target != path[..=m.len()] => {
                path = [target.clone(), path[m.len() + 1..].to_vec()].concat();
            }
            _ => return Some(m),
        }
    }
    None
}

/// The import graph: module -> modules it names (not itself, not the root `lib.rs`, not its own
/// ancestors). A path through a re-export is an edge to the file that defines the item.
fn graph(src: &Path) -> BTreeMap<ModPath, BTreeSet<ModPath>> {
    let modules = module_files(src);
    let reexports = reexports(&modules);
    let mut edges = BTreeMap::new();
    for (module, file) in &modules {
        let code = code_of(&fs::read_to_string(file).unwrap());
        let mut to = BTreeSet::new();
        let children: Vec<&String> = modules
            .keys()
            .filter(|m| m.len() == module.len() + 1 && m.starts_with(module))
            .map(|m| m.last().unwrap())
            .collect();
        for p in named_paths(&code, module, &children) {
            // The file the path names, as a reader sees it (`crate::scenario::Shape` is an import
            // of `scenario/mod.rs`, whatever that file re-exports), and the file that defines
            // the item, through the re-exports.
            let named = owner(&p, &modules).cloned();
            let defining = holder(&p, &modules, &reexports);
            for m in named.into_iter().chain(defining) {
                // A file naming its own folder's items (`super::Options` in
                // `interlace/gpu.rs`) is the folder split in files: no edge. The folder naming
                // its files, and every other edge, counts.
                if m != *module && !m.is_empty() && !module.starts_with(&m) {
                    to.insert(m);
                }
            }
        }
        edges.insert(module.clone(), to);
    }
    edges
}

/// Strongly connected sets of more than one module (Tarjan), each sorted.
fn circles(edges: &BTreeMap<ModPath, BTreeSet<ModPath>>) -> Vec<Vec<ModPath>> {
    struct State<'a> {
        edges: &'a BTreeMap<ModPath, BTreeSet<ModPath>>,
        index: BTreeMap<&'a ModPath, usize>,
        low: BTreeMap<&'a ModPath, usize>,
        stack: Vec<&'a ModPath>,
        on_stack: BTreeSet<&'a ModPath>,
        out: Vec<Vec<ModPath>>,
    }
    fn visit<'a>(s: &mut State<'a>, v: &'a ModPath) {
        let n = s.index.len();
        s.index.insert(v, n);
        s.low.insert(v, n);
        s.stack.push(v);
        s.on_stack.insert(v);
        for w in s.edges.get(v).into_iter().flatten() {
            let Some((w, _)) = s.edges.get_key_value(w) else {
                continue;
            };
            if !s.index.contains_key(w) {
                visit(s, w);
                let lw = s.low[w];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(lw);
            } else if s.on_stack.contains(w) {
                let iw = s.index[w];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(iw);
            }
        }
        if s.low[v] == s.index[v] {
            let mut set = Vec::new();
            loop {
                let w = s.stack.pop().unwrap();
                s.on_stack.remove(w);
                set.push(w.clone());
                if w == v {
                    break;
                }
            }
            if set.len() > 1 {
                set.sort();
                s.out.push(set);
            }
        }
    }
    let mut s = State {
        edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in edges.keys() {
        if !s.index.contains_key(v) {
            visit(&mut s, v);
        }
    }
    s.out
}

/// The folder-level circles: for every folder, its children (subfolders and files) as nodes, and
/// an edge between two of them wherever a file in one names a file in the other. Each circle is
/// the folder and the sorted children that import each other in a loop: `render/` ->
/// `scenario/` -> `techniques/` -> `render/` is a circle of the root folder even when no file
/// imports another that imports it back.
fn folder_circles(edges: &BTreeMap<ModPath, BTreeSet<ModPath>>) -> Vec<(ModPath, Vec<ModPath>)> {
    // Every folder: a module with a module below it (the root included).
    let folders: BTreeSet<ModPath> = edges
        .keys()
        .flat_map(|m| (0..m.len()).map(|n| m[..n].to_vec()))
        .collect();
    let mut out = Vec::new();
    for folder in folders {
        let child = |m: &ModPath| -> Option<ModPath> {
            (m.len() > folder.len() && m.starts_with(&folder)).then(|| m[..=folder.len()].to_vec())
        };
        let mut level: BTreeMap<ModPath, BTreeSet<ModPath>> = BTreeMap::new();
        for (from, to) in edges {
            let Some(a) = child(from) else { continue };
            level.entry(a.clone()).or_default();
            for b in to.iter().filter_map(child).filter(|b| *b != a) {
                level.entry(b.clone()).or_default();
                level.get_mut(&a).unwrap().insert(b);
            }
        }
        for set in circles(&level) {
            out.push((folder.clone(), set));
        }
    }
    out
}

fn name(m: &ModPath) -> String {
    if m.is_empty() {
        "lib".into()
    } else {
        m.join("::")
    }
}

#[test]
fn the_harness_has_no_import_circle() {
    let edges = graph(&src_dir());
    let n_edges: usize = edges.values().map(BTreeSet::len).sum();
    println!("{} modules, {n_edges} imports", edges.len());
    assert!(edges.len() > 50, "read only {} modules", edges.len());
    let found = circles(&edges);
    if std::env::var_os("TESSERA_IMPORTS_DEBUG").is_some() {
        for set in &found {
            for m in set {
                for t in edges[m].iter().filter(|t| set.contains(t)) {
                    println!("{} -> {}", name(m), name(t));
                }
            }
        }
    }
    let text: Vec<String> = found
        .iter()
        .map(|set| {
            let names: Vec<String> = set.iter().map(name).collect();
            format!("{} modules: {}", set.len(), names.join(", "))
        })
        .collect();
    assert!(
        found.is_empty(),
        "import circles in harness/src (each line one strongly connected set):\n{}",
        text.join("\n")
    );
}

/// Issue 39: no loop between folders either (`render/` -> `scenario/` -> `techniques/` ->
/// `render/`), as a reader of the tree sees it, though each file-level edge of it looks fine.
#[test]
fn the_harness_folders_have_no_import_circle() {
    let found = folder_circles(&graph(&src_dir()));
    let text: Vec<String> = found
        .iter()
        .map(|(folder, set)| {
            let names: Vec<String> = set.iter().map(name).collect();
            format!("in {}/: {}", name(folder), names.join(", "))
        })
        .collect();
    assert!(
        found.is_empty(),
        "folder-level import circles in harness/src (each line the folders or files of one \
         folder that import each other in a loop):\n{}",
        text.join("\n")
    );
}

#[test]
fn render_and_run_name_no_technique() {
    let src = src_dir();
    let edges = graph(&src);
    let mut offenders = Vec::new();
    for (module, to) in &edges {
        let first = module.first().map(String::as_str);
        if !matches!(first, Some("render") | Some("run")) {
            continue;
        }
        for t in to {
            // The registry is how run/ finds a technique by name; a folder is a technique.
            if t.first().map(String::as_str) == Some("techniques")
                && !matches!(
                    t.get(1).map(String::as_str),
                    None | Some("registry") | Some("definition")
                )
            {
                offenders.push(format!("{} -> {}", name(module), name(t)));
            }
        }
    }
    assert!(
        offenders.is_empty(),
        "render/ and run/ name techniques:\n{}",
        offenders.join("\n")
    );
}

/// Every technique's name as its folder declares it: the string literal its `fn name` returns,
/// or the constant it returns (`NAME`), read from `techniques/<folder>/mod.rs`.
fn technique_names(src: &Path) -> BTreeSet<String> {
    let mut names = BTreeSet::new();
    let dir = src.join("techniques");
    for entry in fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path().join("mod.rs");
        let Ok(text) = fs::read_to_string(&path) else {
            continue;
        };
        let header = "fn name(&self) -> &'static str {";
        for (at, _) in text.match_indices(header) {
            let body = &text[at + header.len()..];
            let body = body[..body.find('}').unwrap()].trim();
            let name = match body.strip_prefix('"') {
                Some(rest) => rest[..rest.find('"').unwrap()].to_string(),
                None => {
                    let decl = format!("const {body}: &str = \"");
                    let from = text.find(&decl).unwrap_or_else(|| {
                        panic!("{}: fn name returns {body}, not found", path.display())
                    }) + decl.len();
                    text[from..from + text[from..].find('"').unwrap()].to_string()
                }
            };
            names.insert(name);
        }
    }
    names
}

/// Issue 21: `render/` and `run/` ask `techniques::` by role (`is_reference`,
/// `is_reference_name`), never compare with a technique's name: no string literal of their code
/// (unit tests aside) is one.
#[test]
fn render_and_run_spell_no_technique_name() {
    let src = src_dir();
    let names = technique_names(&src);
    for expected in ["native", "checkerboard", "adaptive-shading", "native-vrs"] {
        assert!(names.contains(expected), "technique names read: {names:?}");
    }
    let mut offenders = Vec::new();
    for (module, path) in module_files(&src) {
        if !matches!(
            module.first().map(String::as_str),
            Some("render") | Some("run")
        ) {
            continue;
        }
        let (_, literals) = split_code(&fs::read_to_string(&path).unwrap());
        for l in literals.iter().filter(|l| names.contains(l.as_str())) {
            offenders.push(format!("{}: \"{l}\"", name(&module)));
        }
    }
    assert!(
        offenders.is_empty(),
        "render/ and run/ spell technique names (ask techniques:: by role):\n{}",
        offenders.join("\n")
    );
}

/// The checker itself finds a circle it is shown.
#[test]
fn string_literals_are_read() {
    let (code, literals) =
        split_code("let a = \"native\"; // \"x\"\nlet b = r#\"q\"#;\n#[cfg(test)]\n\"t\"");
    assert_eq!(literals, ["native", "q"]);
    assert!(!code.contains("native"));
}

#[test]
fn a_circle_is_found() {
    let dir = std::env::temp_dir().join(format!("tessera-imports-{}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(dir.join("a")).unwrap();
    fs::write(dir.join("lib.rs"), "pub mod a;\npub mod b;\n").unwrap();
    fs::write(dir.join("a/mod.rs"), "pub mod x;\n").unwrap();
    fs::write(
        dir.join("a/x.rs"),
        "use crate::b::{Y, self};\n// crate::c\n",
    )
    .unwrap();
    fs::write(dir.join("b.rs"), "fn f() { super::a::x::g() }\n").unwrap();
    let found = circles(&graph(&dir));
    fs::remove_dir_all(&dir).unwrap();
    assert_eq!(found.len(), 1, "{found:?}");
    let names: Vec<String> = found[0].iter().map(name).collect();
    assert_eq!(names, ["a::x", "b"]);
}

/// Writes `files` (path under `src/`, text) into a fresh temporary tree and returns its `src/`.
fn tree(label: &str, files: &[(&str, &str)]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tessera-imports-{label}-{}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    for (path, text) in files {
        let path = dir.join(path);
        fs::create_dir_all(path.parent().unwrap()).unwrap();
        fs::write(path, text).unwrap();
    }
    dir
}

/// A loop of folders whose every file-level edge runs one way: no file circle, one folder circle.
#[test]
fn a_folder_circle_is_found() {
    let dir = tree(
        "folders",
        &[
            (
                "lib.rs",
                "pub mod render;\npub mod scenario;\npub mod techniques;\n",
            ),
            ("render/mod.rs", "pub mod kit;\npub mod mesh;\n"),
            ("render/kit.rs", "pub fn bind_group() {}\n"),
            ("render/mesh.rs", "use crate::scenario::Shape;\n"),
            (
                "scenario/mod.rs",
                "pub mod scene;\npub mod validate;\npub use scene::Shape;\n",
            ),
            ("scenario/scene.rs", "pub enum Shape {}\n"),
            ("scenario/validate.rs", "use crate::techniques::Variant;\n"),
            ("techniques/mod.rs", "pub mod gpu;\npub struct Variant;\n"),
            (
                "techniques/gpu.rs",
                "fn f() { crate::render::kit::bind_group() }\n",
            ),
        ],
    );
    let edges = graph(&dir);
    let files = circles(&edges);
    let folders = folder_circles(&edges);
    fs::remove_dir_all(&dir).unwrap();
    assert!(files.is_empty(), "{files:?}");
    assert_eq!(folders.len(), 1, "{folders:?}");
    let (folder, set) = &folders[0];
    assert!(folder.is_empty(), "the root folder's: {folder:?}");
    let names: Vec<String> = set.iter().map(name).collect();
    assert_eq!(names, ["render", "scenario", "techniques"]);
}

/// Naming an item through a re-export is an import of the re-exporting file, as a reader sees it:
/// `a` names `b::X` (defined in `c`), `b` names `a`; a circle, though `a` never names `c`'s
/// importer.
#[test]
fn a_circle_through_a_reexport_is_found() {
    let dir = tree(
        "reexport",
        &[
            ("lib.rs", "pub mod a;\npub mod b;\npub mod c;\n"),
            ("a.rs", "use crate::b::X;\npub struct Y;\n"),
            ("b.rs", "pub use crate::c::X;\nuse crate::a::Y;\n"),
            ("c.rs", "pub struct X;\n"),
        ],
    );
    let found = circles(&graph(&dir));
    fs::remove_dir_all(&dir).unwrap();
    assert_eq!(found.len(), 1, "{found:?}");
    let names: Vec<String> = found[0].iter().map(name).collect();
    assert_eq!(names, ["a", "b"]);
}
