//! Maps a dotted key path (`techniques[1].scale`) to a line and column of the scenario source.
//!
//! Validation works on the serde structs, which carry no positions; this module re-reads the source
//! with `toml_edit` (which keeps spans) to point errors at the right place. It does not validate.

use std::fmt;
use std::ops::Range;

use toml_edit::{Document, Item};

/// One step of a key path.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Seg {
    Key(String),
    Index(usize),
}

/// A dotted key path such as `scene.objects[2].radius`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct KeyPath(pub Vec<Seg>);

impl KeyPath {
    pub fn root() -> KeyPath {
        KeyPath(Vec::new())
    }

    pub fn key(&self, k: &str) -> KeyPath {
        let mut v = self.0.clone();
        v.push(Seg::Key(k.to_string()));
        KeyPath(v)
    }

    pub fn index(&self, i: usize) -> KeyPath {
        let mut v = self.0.clone();
        v.push(Seg::Index(i));
        KeyPath(v)
    }

    /// Parses the path notation of `serde_path_to_error` (`a.b[0].c`, or `a.b.0.c` for sequences).
    pub fn parse(s: &str) -> KeyPath {
        let mut segs = Vec::new();
        for part in s.split('.') {
            if part.is_empty() || part == "?" {
                continue;
            }
            let mut rest = part;
            if let Some(open) = rest.find('[') {
                let (head, tail) = rest.split_at(open);
                if !head.is_empty() {
                    segs.push(Seg::Key(head.to_string()));
                }
                rest = tail;
                while let Some(stripped) = rest.strip_prefix('[') {
                    let close = stripped.find(']').unwrap_or(stripped.len());
                    if let Ok(i) = stripped[..close].parse() {
                        segs.push(Seg::Index(i));
                    }
                    rest = stripped.get(close + 1..).unwrap_or("");
                }
            } else if let Ok(i) = rest.parse::<usize>() {
                segs.push(Seg::Index(i));
            } else {
                segs.push(Seg::Key(rest.to_string()));
            }
        }
        KeyPath(segs)
    }
}

impl fmt::Display for KeyPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0.is_empty() {
            return f.write_str("(top level)");
        }
        let mut first = true;
        for seg in &self.0 {
            match seg {
                Seg::Key(k) => {
                    if !first {
                        f.write_str(".")?;
                    }
                    f.write_str(k)?;
                }
                Seg::Index(i) => write!(f, "[{i}]")?,
            }
            first = false;
        }
        Ok(())
    }
}

/// Byte span of the deepest part of `path` present in the document: the value if the whole path
/// exists, otherwise the closest existing parent. `None` when not even the first key exists.
pub fn locate(doc: &Document<String>, path: &KeyPath) -> Option<Range<usize>> {
    let mut node = Node::Item(doc.as_item());
    let mut best = None;
    for seg in &path.0 {
        match node.child(seg) {
            Some((next, span)) => {
                best = span.or(best);
                node = next;
            }
            None => break,
        }
    }
    best
}

#[derive(Clone, Copy)]
enum Node<'a> {
    Item(&'a Item),
    Table(&'a toml_edit::Table),
    Value(&'a toml_edit::Value),
}

impl<'a> Node<'a> {
    /// The child at `seg` and the span that best marks it.
    fn child(self, seg: &Seg) -> Option<(Node<'a>, Option<Range<usize>>)> {
        match (self, seg) {
            (Node::Item(Item::Table(t)), _) => Node::Table(t).child(seg),
            (Node::Item(Item::Value(v)), _) => Node::Value(v).child(seg),
            (Node::Item(Item::ArrayOfTables(a)), Seg::Index(i)) => {
                let t = a.get(*i)?;
                Some((Node::Table(t), t.span()))
            }
            (Node::Table(t), Seg::Key(k)) => {
                let (key, value) = t.get_key_value(k)?;
                // Values have their own span; tables are marked by their key.
                let span = match value {
                    Item::Value(v) => v.span().or_else(|| key.span()),
                    _ => key.span(),
                };
                Some((Node::Item(value), span))
            }
            (Node::Value(toml_edit::Value::InlineTable(t)), Seg::Key(k)) => {
                let v = t.get(k)?;
                Some((Node::Value(v), v.span()))
            }
            (Node::Value(toml_edit::Value::Array(a)), Seg::Index(i)) => {
                let v = a.get(*i)?;
                Some((Node::Value(v), v.span()))
            }
            _ => None,
        }
    }
}

/// 1-based line and column of a byte offset.
pub fn line_col(source: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(source.len());
    let before = &source[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map(|p| p + 1).unwrap_or(0);
    let column = source[line_start..offset].chars().count() + 1;
    (line, column)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_serde_paths() {
        let p = KeyPath::parse("scene.objects[2].radius");
        assert_eq!(p.to_string(), "scene.objects[2].radius");
        let p = KeyPath::parse("techniques.0.scale");
        assert_eq!(p.to_string(), "techniques[0].scale");
    }

    #[test]
    fn locates_values_in_tables_and_arrays_of_tables() {
        let src = "resolution = [1, 2]\n[camera]\nnear = 0.1\n\n[[techniques]]\ntechnique = \"native\"\n\n[[techniques]]\ntechnique = \"upscale\"\nscale = [0.5, 2.0]\n";
        let doc: Document<String> = src.to_string().parse().unwrap();
        let at = |p: &str| {
            let span = locate(&doc, &KeyPath::parse(p)).unwrap();
            line_col(src, span.start)
        };
        assert_eq!(at("camera.near"), (3, 8));
        assert_eq!(at("resolution[1]"), (1, 18));
        assert_eq!(at("techniques[1].scale"), (10, 9));
        assert_eq!(at("techniques[1].scale[1]"), (10, 15));
        // A missing key points at its parent.
        assert_eq!(at("camera.far").0, 2);
    }
}
