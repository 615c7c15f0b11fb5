//! Every file in `tests/malformed/` is refused before any step, with the message its
//! `# expect: ...` lines give, a line and column, and a fix.

use std::path::Path;

use mpm_run::load_scene_str;

#[test]
fn every_malformed_scene_is_refused_with_its_specific_message() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/malformed");
    let mut entries: Vec<_> = std::fs::read_dir(&dir)
        .expect("malformed corpus")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    entries.sort();
    assert!(entries.len() >= 25, "only {} malformed scenes", entries.len());
    let mut failures = Vec::new();
    for path in &entries {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let text = std::fs::read_to_string(path).unwrap();
        let expects: Vec<&str> =
            text.lines().filter_map(|l| l.strip_prefix("# expect: ")).collect();
        if expects.is_empty() {
            failures.push(format!("{name}: no `# expect:` line"));
            continue;
        }
        match load_scene_str(&text, &name) {
            Ok(_) => failures.push(format!("{name}: accepted")),
            Err(e) => {
                let msg = e.to_string();
                for x in &expects {
                    if !msg.contains(x) {
                        failures.push(format!("{name}: message lacks {x:?}:\n{msg}"));
                    }
                }
                if !msg.starts_with(&format!("{name}:")) {
                    failures.push(format!("{name}: message does not start with the file:\n{msg}"));
                }
                // Every file but the empty one has the offending place in the text.
                if !text.lines().all(|l| l.starts_with('#'))
                    && (e.line.is_none() || e.column.is_none())
                {
                    failures.push(format!("{name}: no line/column:\n{msg}"));
                }
                if e.fix.is_empty() {
                    failures.push(format!("{name}: no fix:\n{msg}"));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{} problem(s):\n{}", failures.len(), failures.join("\n\n"));
}

#[test]
fn errors_point_at_the_offending_line() {
    let text =
        mpm_run::embedded_scene("free_fall").unwrap().replace("poisson = 0.3", "poisson = 0.7");
    let line = text.lines().position(|l| l.starts_with("poisson")).unwrap() + 1;
    let e = load_scene_str(&text, "x.toml").unwrap_err();
    assert_eq!(e.path, "materials.block.poisson");
    assert_eq!((e.line, e.column), (Some(line), Some(11)));
    assert_eq!(e.value.as_deref(), Some("0.7"));
}

#[test]
fn arbitrary_bytes_never_panic() {
    // A cheap fuzz: truncations and byte flips of a valid scene are refused or accepted, never a
    // panic.
    let text = mpm_run::embedded_scene("sliding_horizontal").unwrap();
    let bytes = text.as_bytes();
    for cut in (0..bytes.len()).step_by(7) {
        let _ = load_scene_str(&String::from_utf8_lossy(&bytes[..cut]), "cut.toml");
    }
    let mut state = 0x2545_f491_4f6c_dd1du64;
    for _ in 0..300 {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        let mut b = bytes.to_vec();
        let k = (state as usize) % b.len();
        b[k] = b"0123456789-.e[]=\"x \n"[(state >> 32) as usize % 20];
        let _ = load_scene_str(&String::from_utf8_lossy(&b), "flip.toml");
    }
}
