//! The library's modules follow the pipeline with no back-edges: a module may use the shared
//! utilities and the stages before it, never a later stage. Read from the
//! `crate::` paths of every source file.
//!
//! `KNOWN` lists accepted back-edges (none). A new back-edge fails this test; removing a known
//! one fails it too, until it is struck from the list. Comments are not read: a doc comment
//! may point at the stage that uses an item.

use std::collections::BTreeSet;
use std::path::Path;

/// Pipeline position of each top-level module (utilities at -1, the front door `api` last).
fn level(module: &str) -> Option<i32> {
    Some(match module {
        "text" | "files" | "machine" | "linalg" | "coolant" => -1,
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
        "api" => 11,
        // the command line's own pieces (in the binary: they use `linercav::`, not `crate::`)
        "cli" => 12,
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
/// The code of a source file: its lines without the comment lines.
fn code_of(f: &Path) -> String {
    std::fs::read_to_string(f)
        .unwrap()
        .lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .map(|l| format!("{l}\n"))
        .collect()
}

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
        targets("{api::rom, fem::{a, b}, report};"),
        ["api", "fem", "report"]
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
            // lib.rs and main.rs only: every other module has its place in the pipeline
            assert!(
                ["lib", "main"].contains(&module.as_str()),
                "src/{module} has no layer: give it one in level()"
            );
            continue;
        };
        // code only: a doc comment may point at a later stage's item
        let text = code_of(f);
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

/// Within a stage, no two modules import each other (the transient's cycle and window did:
/// the shared pieces now sit in `bore`, `signal` and `error`). Reads `use super::x` and
/// `super::x::` in the code of each stage directory's files.
#[test]
fn verification_no_two_modules_of_a_stage_import_each_other() {
    let mut files = Vec::new();
    sources(Path::new("src"), &mut files);
    let mut edges = BTreeSet::new();
    for f in &files {
        let (Some(dir), Some(stem)) = (f.parent(), f.file_stem()) else {
            continue;
        };
        if dir == Path::new("src") || stem == "mod" {
            continue;
        }
        let stage = dir.display().to_string();
        let module = stem.to_string_lossy().to_string();
        let text = code_of(f);
        for (at, _) in text.match_indices("super::") {
            for target in targets(&text[at + 7..]) {
                if !target.is_empty() && target != module {
                    edges.insert((stage.clone(), module.clone(), target));
                }
            }
        }
    }
    let mutual: Vec<String> = edges
        .iter()
        .filter(|(s, a, b)| a < b && edges.contains(&(s.clone(), b.clone(), a.clone())))
        .map(|(s, a, b)| format!("{s}: {a} <-> {b}"))
        .collect();
    assert!(
        mutual.is_empty(),
        "modules importing each other: {mutual:?}"
    );
}

/// The library is the command line's engine, not its front end: no source outside the binary
/// (`src/main.rs`, `src/cli/`) names the front end's crates (argument parsing, terminal
/// progress, signal handling, the allocator), which are optional (the `cli` feature) so that a
/// library user does not build them (issue 40).
#[test]
fn verification_the_library_does_not_use_the_front_ends_crates() {
    let mut files = Vec::new();
    sources(Path::new("src"), &mut files);
    let mut users = Vec::new();
    for f in &files {
        let rel = f.strip_prefix("src").unwrap();
        if rel == Path::new("main.rs") || rel.starts_with("cli") {
            continue;
        }
        let code = code_of(f);
        for krate in ["clap", "indicatif", "signal_hook", "mimalloc"] {
            if code.contains(&format!("{krate}::")) || code.contains(&format!("use {krate}")) {
                users.push(format!("{}: {krate}", f.display()));
            }
        }
    }
    assert!(
        users.is_empty(),
        "front-end crates in the library: {users:?}"
    );
}

/// The longest function allowed outside the kernels (issue 40: "no function over 100 lines
/// outside at most three documented kernels").
const MAX_FUNCTION_LINES: usize = 100;

/// Numerical kernels allowed past [`MAX_FUNCTION_LINES`] (issue 24: "kernels with an equation may be
/// longer when splitting would hide it"), each with the equation its doc comment carries.
/// None now: `solve_modes` (196 lines of ARPACK plumbing) was split into its workspace, its
/// reverse-communication loop and its extraction (issue 40).
const KERNELS: [(&str, &str); 0] = [];

/// Lengths of the functions of one source file: (name, lines from `fn` to its closing brace
/// at the same indentation).
fn function_lengths(text: &str) -> Vec<(String, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        let t = l.trim_start();
        let indent = l.len() - t.len();
        // any visibility: `pub`, `pub(crate)`, `pub(super)`, `pub(in path)`
        let t = match t.strip_prefix("pub(") {
            Some(r) => r.split_once(") ").map_or(t, |(_, rest)| rest),
            None => t.strip_prefix("pub ").unwrap_or(t),
        };
        let t = t.strip_prefix("const ").unwrap_or(t);
        let t = t.strip_prefix("unsafe ").unwrap_or(t);
        let t = t.strip_prefix("extern \"C\" ").unwrap_or(t);
        let Some(rest) = t.strip_prefix("fn ") else {
            continue;
        };
        if l.trim_end().ends_with(';') {
            continue; // a declaration
        }
        let name: String = rest
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect();
        let close = " ".repeat(indent) + "}";
        let end = (i..lines.len())
            .find(|&j| lines[j].starts_with(&close) && !lines[j][indent..].starts_with("} else"))
            .unwrap_or(lines.len() - 1);
        out.push((name, end - i + 1));
    }
    out
}

#[test]
fn verification_function_length_scanner() {
    let text = "fn a() {\n    x;\n}\n\n    pub fn b(\n        y: u8,\n    ) {\n    }\npub(super) fn c() {\n}\n";
    assert_eq!(
        function_lengths(text),
        [
            ("a".to_string(), 3),
            ("b".to_string(), 4),
            ("c".to_string(), 2)
        ]
    );
}

#[test]
fn verification_no_function_over_100_lines_outside_the_kernels() {
    let mut files = Vec::new();
    sources(Path::new("src"), &mut files);
    let mut long = Vec::new();
    let mut exempted = BTreeSet::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        for (name, n) in function_lengths(&text) {
            let path = f.to_string_lossy().replace('\\', "/");
            let kernel = KERNELS.iter().any(|(p, k)| path == *p && name == *k);
            if n > MAX_FUNCTION_LINES && !kernel {
                long.push(format!("{path}: {name} ({n} lines)"));
            }
            if n > MAX_FUNCTION_LINES && kernel {
                exempted.insert((path, name));
            }
        }
    }
    assert!(
        long.is_empty(),
        "functions over {MAX_FUNCTION_LINES} lines: {long:?}"
    );
    // an exemption no longer needed (the kernel split or renamed) is struck from the list
    let stale: Vec<_> = KERNELS
        .iter()
        .filter(|(p, k)| !exempted.contains(&(p.to_string(), k.to_string())))
        .collect();
    assert!(stale.is_empty(), "strike from KERNELS: {stale:?}");
}
