//! The library's modules follow the pipeline with no back-edges: a module may use the shared
//! utilities and the stages before it, never a later stage or the command layer. Read from the
//! `crate::` paths of every source file.
//!
//! `KNOWN` lists accepted back-edges (none). A new back-edge fails this test; removing a known
//! one fails it too, until it is struck from the list. Comments are not read: a doc comment
//! may point at the stage that uses an item.

use std::collections::BTreeSet;
use std::path::Path;

/// Pipeline position of each top-level module (utilities at -1, the command layer last).
fn level(module: &str) -> Option<i32> {
    Some(match module {
        "text" | "files" | "machine" | "linalg" => -1,
        "scene" => 0,
        "mesh" => 1,
        "fem" => 2,
        "eigen" => 3,
        "reduce" => 4,
        "piston" => 5,
        "transient" => 6,
        "analysis" => 7,
        "cavitation" => 8,
        "report" => 9,
        "error" => 10,
        "app" => 11,
        _ => return None,
    })
}

const KNOWN: [&str; 0] = [];

fn sources(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            sources(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The top-level modules named right after `crate::`: one name, or each of a group
/// `crate::{a, b::c}`.
fn targets(after: &str) -> Vec<String> {
    let ident = |s: &str| -> String {
        s.trim_start()
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect()
    };
    match after.strip_prefix('{') {
        Some(group) => {
            let (mut depth, mut items, mut start) = (0, Vec::new(), 0);
            for (i, ch) in group.char_indices() {
                match ch {
                    '{' => depth += 1,
                    '}' if depth == 0 => {
                        items.push(ident(&group[start..i]));
                        break;
                    }
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        items.push(ident(&group[start..i]));
                        start = i + 1;
                    }
                    _ => {}
                }
            }
            items
        }
        None => vec![ident(after)],
    }
}

#[test]
fn verification_grouped_imports_are_read() {
    assert_eq!(targets("scene::Scene;"), ["scene"]);
    assert_eq!(
        targets("{app::rom, fem::{a, b}, report};"),
        ["app", "fem", "report"]
    );
}

#[test]
fn verification_no_module_imports_a_later_stage() {
    let mut files = Vec::new();
    sources(Path::new("src"), &mut files);
    let mut edges = BTreeSet::new();
    for f in &files {
        let rel = f.strip_prefix("src").unwrap();
        let first = rel
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_string_lossy();
        let module = first.trim_end_matches(".rs").to_string();
        let Some(from) = level(&module) else {
            continue; // lib.rs, main.rs
        };
        // code only: a doc comment may point at a later stage's item
        let text: String = std::fs::read_to_string(f)
            .unwrap()
            .lines()
            .filter(|l| !l.trim_start().starts_with("//"))
            .map(|l| format!("{l}\n"))
            .collect();
        for (at, _) in text.match_indices("crate::") {
            for target in targets(&text[at + 7..]) {
                let Some(to) = level(&target) else { continue };
                // a later stage, or a sibling stage at the same level
                if target != module && to >= from && to >= 0 {
                    edges.insert(format!("{module} -> {target}"));
                }
            }
        }
    }
    let known: BTreeSet<String> = KNOWN.iter().map(|s| s.to_string()).collect();
    let new: Vec<_> = edges.difference(&known).collect();
    let gone: Vec<_> = known.difference(&edges).collect();
    assert!(new.is_empty(), "new back-edges in the pipeline: {new:?}");
    assert!(
        gone.is_empty(),
        "back-edges removed: strike them from KNOWN: {gone:?}"
    );
}
