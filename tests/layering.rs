//! The library's modules follow the pipeline with no back-edges: a module may use the shared
//! utilities and the stages before it, never a later stage or the command layer. Read from the
//! `crate::` paths of every source file.
//!
//! `KNOWN` lists the back-edges that exist today, to be removed (issue 24): the scene computes
//! the coolant's properties and the risk thresholds with the cavitation stage while it
//! validates. A new back-edge fails this test; removing a known one fails it too, until it is
//! struck from the list.

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
        "analysis" | "cavitation" => 7,
        "report" => 8,
        "error" => 9,
        "app" => 10,
        _ => return None,
    })
}

const KNOWN: [&str; 1] = ["scene -> cavitation"];

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
        let text = std::fs::read_to_string(f).unwrap();
        for (at, _) in text.match_indices("crate::") {
            let target: String = text[at + 7..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            let Some(to) = level(&target) else { continue };
            // a later stage, or a sibling stage at the same level (analysis <-> cavitation)
            if target != module && to >= from && to >= 0 {
                edges.insert(format!("{module} -> {target}"));
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
