//! Tidy checks of the repository's own documents (after rust-analyzer's `tidy`): every file and
//! type `ARCHITECTURE.md` names exists, and its table of crate dependencies is what the
//! `Cargo.toml` files say. A rename that leaves the map behind fails here.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("tests/ sits in the workspace").into()
}

/// every file under `dir` (recursively), skipping build output and hidden directories.
fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let p = e.path();
        let name = e.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') || name == "target" {
            continue;
        }
        if p.is_dir() {
            files(&p, out);
        } else {
            out.push(p);
        }
    }
}

/// the text between backticks in `doc` (code blocks included: their names are claims too).
fn quoted(doc: &str) -> Vec<String> {
    doc.split('`').skip(1).step_by(2).map(str::to_string).collect()
}

fn is_ident_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// the CamelCase identifiers of a quoted span: `Solver<M, S, N>` gives Solver, `Friction::Fixed`
/// Friction and Fixed.
fn camel_words(span: &str) -> Vec<String> {
    span.split(|c: char| !is_ident_char(c))
        .filter(|w| {
            let mut cs = w.chars();
            cs.next().is_some_and(|c| c.is_ascii_uppercase())
                && w.chars().any(|c| c.is_ascii_lowercase())
        })
        .map(str::to_string)
        .collect()
}

/// true when `word` occurs in `text` with no identifier character on either side.
fn has_word(text: &str, word: &str) -> bool {
    text.match_indices(word).any(|(i, _)| {
        let before = text[..i].chars().next_back().is_none_or(|c| !is_ident_char(c));
        let after = text[i + word.len()..].chars().next().is_none_or(|c| !is_ident_char(c));
        before && after
    })
}

#[test]
fn architecture_names_only_files_and_types_that_exist() {
    let root = root();
    let doc = std::fs::read_to_string(root.join("ARCHITECTURE.md")).unwrap();
    let mut all = Vec::new();
    for dir in ["crates", "xtask", "tests", "benches", "docs"] {
        files(&root.join(dir), &mut all);
    }
    let rel: Vec<String> = all
        .iter()
        .map(|p| p.strip_prefix(&root).unwrap().to_string_lossy().replace('\\', "/"))
        .collect();
    let sources: String = all
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "rs"))
        .map(|p| std::fs::read_to_string(p).unwrap())
        .collect::<Vec<_>>()
        .join("\n");
    let mut missing = BTreeSet::new();
    for span in quoted(&doc) {
        let span = span.trim();
        // A file: a path or a name with an extension, matched as a path suffix; placeholders
        // (`NAME.rs`), globs (`scenes/*.toml`) and what a run writes (`target/…`) are not names
        // of the repository's files.
        let looks_like_file =
            [".rs", ".toml", ".md"].iter().any(|ext| span.ends_with(ext)) && !span.contains(' ');
        if looks_like_file {
            if span.contains('*') || span.contains("NAME") || span.starts_with("target/") {
                continue;
            }
            let found = rel.iter().any(|r| r == span || r.ends_with(&format!("/{span}")));
            if !found {
                missing.insert(format!("file `{span}`"));
            }
            continue;
        }
        if span.contains(' ') && !span.contains("::") {
            continue; // a command line or a phrase
        }
        for w in camel_words(span) {
            if !has_word(&sources, &w) {
                missing.insert(format!("name `{w}` (in `{span}`)"));
            }
        }
    }
    assert!(missing.is_empty(), "ARCHITECTURE.md names what does not exist: {missing:#?}");
}

#[test]
fn architecture_states_each_crates_dependencies() {
    let root = root();
    let doc = std::fs::read_to_string(root.join("ARCHITECTURE.md")).unwrap();
    let section = doc
        .split("## Crate dependencies")
        .nth(1)
        .expect("ARCHITECTURE.md has a `## Crate dependencies` section");
    let mut stated = BTreeMap::new();
    for line in section.lines().skip_while(|l| !l.starts_with('|')) {
        if !line.starts_with('|') {
            break;
        }
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        if cells.len() < 3 || !cells[1].starts_with("mpm-") {
            continue;
        }
        let deps: BTreeSet<String> = cells[2]
            .split(',')
            .map(str::trim)
            .filter(|d| d.starts_with("mpm-"))
            .map(str::to_string)
            .collect();
        stated.insert(cells[1].to_string(), deps);
    }
    let mut actual = BTreeMap::new();
    for e in std::fs::read_dir(root.join("crates")).unwrap().flatten() {
        let Ok(manifest) = std::fs::read_to_string(e.path().join("Cargo.toml")) else { continue };
        let name = e.file_name().to_string_lossy().into_owned();
        let mut deps = BTreeSet::new();
        let mut in_deps = false;
        for line in manifest.lines() {
            let line = line.trim();
            if line.starts_with('[') {
                in_deps = line == "[dependencies]";
            } else if in_deps && line.starts_with("mpm-") {
                // a renamed dependency (`mpm-grid = { package = "mpm-grid3d", … }`, the 3D
                // builds) depends on the package it names
                let dep: String = match line.split("package = \"").nth(1) {
                    Some(rest) => rest.chars().take_while(|&c| c != '"').collect(),
                    None => line.chars().take_while(|&c| is_ident_char(c) || c == '-').collect(),
                };
                deps.insert(dep);
            }
        }
        actual.insert(name, deps);
    }
    assert_eq!(stated, actual, "ARCHITECTURE.md's crate table against the Cargo.toml files");
    // The leaves stay leaves.
    for leaf in
        ["mpm-constitutive", "mpm-grid", "mpm-contact", "mpm-dem", "mpm-grid3d", "mpm-contact3d"]
    {
        assert!(actual[leaf].is_empty(), "{leaf} must depend on no other mpm-* crate");
    }
}
