//! Where a field path (`materials.sand.friction_angle_deg`, `bodies[0].min`) is in a scene's
//! text, and which field path a byte offset belongs to, so that every error can give a line and
//! column and a path.
//!
//! Paths: table keys joined by `.`, array (and array-of-tables) indices as `[i]`. Lines and
//! columns are 1-based; columns count characters.

use toml_edit::{ImDocument, Item, Table, Value};

/// A scene's text with its parsed layout (if it parses as TOML at all).
pub(crate) struct SourceMap {
    text: String,
    doc: Option<ImDocument<String>>,
}

/// One step of a field path.
#[derive(Clone, Debug, PartialEq)]
enum Segment {
    Key(String),
    Index(usize),
}

fn parse_path(path: &str) -> Vec<Segment> {
    let mut out = Vec::new();
    for part in path.split('.').filter(|s| !s.is_empty()) {
        let (key, mut rest) = match part.find('[') {
            Some(k) => (&part[..k], &part[k..]),
            None => (part, ""),
        };
        if !key.is_empty() {
            out.push(Segment::Key(key.to_string()));
        }
        while let Some(end) = rest.find(']') {
            if let Ok(i) = rest[1..end].parse() {
                out.push(Segment::Index(i));
            }
            rest = &rest[end + 1..];
        }
    }
    out
}

/// A node of the document, whatever its TOML form.
#[derive(Clone, Copy)]
enum Node<'a> {
    Item(&'a Item),
    Value(&'a Value),
    Table(&'a Table),
}

impl<'a> Node<'a> {
    fn span(self) -> Option<std::ops::Range<usize>> {
        match self {
            Node::Item(i) => i.span(),
            Node::Value(v) => v.span(),
            Node::Table(t) => t.span(),
        }
    }

    /// (key span, child) of `key`.
    fn key(self, key: &str) -> Option<(Option<std::ops::Range<usize>>, Node<'a>)> {
        match self {
            Node::Item(Item::Table(t)) | Node::Table(t) => {
                t.get_key_value(key).map(|(k, i)| (k.span(), Node::Item(i)))
            }
            Node::Item(Item::Value(Value::InlineTable(t))) | Node::Value(Value::InlineTable(t)) => {
                t.get_key_value(key).map(|(k, i)| (k.span(), Node::Item(i)))
            }
            _ => None,
        }
    }

    fn index(self, i: usize) -> Option<Node<'a>> {
        match self {
            Node::Item(Item::ArrayOfTables(a)) => a.get(i).map(Node::Table),
            Node::Item(Item::Value(Value::Array(a))) | Node::Value(Value::Array(a)) => {
                a.get(i).map(Node::Value)
            }
            _ => None,
        }
    }

    /// (name, child) pairs for a walk over the whole document.
    fn children(self) -> Vec<(Segment, Option<std::ops::Range<usize>>, Node<'a>)> {
        let mut out = Vec::new();
        match self {
            Node::Item(Item::Table(t)) | Node::Table(t) => {
                for (k, _) in t.iter() {
                    if let Some((key, item)) = t.get_key_value(k) {
                        out.push((Segment::Key(k.to_string()), key.span(), Node::Item(item)));
                    }
                }
            }
            Node::Item(Item::Value(Value::InlineTable(t))) | Node::Value(Value::InlineTable(t)) => {
                for (k, _) in t.iter() {
                    if let Some((key, item)) = t.get_key_value(k) {
                        out.push((Segment::Key(k.to_string()), key.span(), Node::Item(item)));
                    }
                }
            }
            Node::Item(Item::ArrayOfTables(a)) => {
                for (i, t) in a.iter().enumerate() {
                    out.push((Segment::Index(i), None, Node::Table(t)));
                }
            }
            Node::Item(Item::Value(Value::Array(a))) | Node::Value(Value::Array(a)) => {
                for (i, v) in a.iter().enumerate() {
                    out.push((Segment::Index(i), None, Node::Value(v)));
                }
            }
            _ => {}
        }
        out
    }
}

fn render(path: &[Segment]) -> String {
    let mut s = String::new();
    for seg in path {
        match seg {
            Segment::Key(k) => {
                if !s.is_empty() {
                    s.push('.');
                }
                s.push_str(k);
            }
            Segment::Index(i) => s.push_str(&format!("[{i}]")),
        }
    }
    s
}

impl SourceMap {
    /// parses `text`'s layout (a syntax error leaves only line/column arithmetic).
    pub(crate) fn new(text: &str) -> Self {
        Self { text: text.to_string(), doc: ImDocument::parse(text.to_string()).ok() }
    }

    /// length of the text in bytes.
    pub(crate) fn len(&self) -> usize {
        self.text.len()
    }

    /// 1-based (line, column) of byte offset `offset`.
    pub(crate) fn line_col(&self, offset: usize) -> (usize, usize) {
        let mut offset = offset.min(self.text.len());
        while !self.text.is_char_boundary(offset) {
            offset -= 1;
        }
        let before = &self.text[..offset];
        let line = before.matches('\n').count() + 1;
        let start = before.rfind('\n').map_or(0, |k| k + 1);
        (line, before[start..].chars().count() + 1)
    }

    /// (line, column) of the value at `path`, or of the nearest enclosing item that exists
    /// (a missing field is reported at its table).
    pub(crate) fn locate(&self, path: &str) -> Option<(usize, usize)> {
        let doc = self.doc.as_ref()?;
        let mut node = Node::Table(doc.as_table());
        let mut best = None;
        for seg in parse_path(path) {
            let next = match &seg {
                Segment::Key(k) => node.key(k).map(|(key_span, n)| {
                    // A table header's span is the header; a value's span is the value.
                    (n.span().or(key_span), n)
                }),
                Segment::Index(i) => node.index(*i).map(|n| (n.span(), n)),
            };
            match next {
                Some((span, n)) => {
                    if let Some(s) = span {
                        best = Some(s.start);
                    }
                    node = n;
                }
                None => break,
            }
        }
        best.map(|o| self.line_col(o))
    }

    /// the deepest field path whose key or value span contains byte `offset` ("" for none).
    pub(crate) fn path_at(&self, offset: usize) -> String {
        let Some(doc) = self.doc.as_ref() else {
            return String::new();
        };
        let mut path = Vec::new();
        let mut node = Node::Table(doc.as_table());
        'descend: loop {
            for (seg, key_span, child) in node.children() {
                let inside = |s: Option<std::ops::Range<usize>>| {
                    s.is_some_and(|s| s.start <= offset && offset < s.end.max(s.start + 1))
                };
                let contains_child = inside(child.span()) || inside(key_span);
                // A [table] header's span covers only the header, so also descend into a
                // table when the offset lies in one of its entries.
                let contains_entry = !contains_child && subtree_contains(child, offset);
                if contains_child || contains_entry {
                    path.push(seg);
                    node = child;
                    continue 'descend;
                }
            }
            break;
        }
        render(&path)
    }
}

fn subtree_contains(node: Node<'_>, offset: usize) -> bool {
    node.children().into_iter().any(|(_, key_span, child)| {
        let inside = |s: Option<std::ops::Range<usize>>| {
            s.is_some_and(|s| s.start <= offset && offset < s.end.max(s.start + 1))
        };
        inside(key_span) || inside(child.span()) || subtree_contains(child, offset)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "[grid]\nkind = \"terrain\"\nprofile = [[0, 1], [2, 0]]\n\n\
                        [materials.sand]\nyoung = 2e6\n\n[[bodies]]\nmaterial = \"sand\"\n\
                        [[bodies]]\nmaterial = \"rock\"\nmin = [1, 2]\n";

    #[test]
    fn paths_locate_their_values() {
        let m = SourceMap::new(TEXT);
        assert_eq!(m.locate("grid.kind"), Some((2, 8)));
        assert_eq!(m.locate("materials.sand.young"), Some((6, 9)));
        assert_eq!(m.locate("bodies[1].material"), Some((11, 12)));
        assert_eq!(m.locate("grid.profile[1]"), Some((3, 20)));
        // a missing field falls back to its table
        assert_eq!(m.locate("materials.sand.poisson").map(|p| p.0), Some(5));
    }

    #[test]
    fn offsets_give_paths() {
        let m = SourceMap::new(TEXT);
        let off = TEXT.find("2e6").unwrap();
        assert_eq!(m.path_at(off), "materials.sand.young");
        let off = TEXT.find("[1, 2]").unwrap();
        assert_eq!(m.path_at(off), "bodies[1].min");
        let off = TEXT.find("[2, 0]").unwrap();
        assert_eq!(m.path_at(off), "grid.profile[1]");
    }
}
