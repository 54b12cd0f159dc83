//! The documentation cannot drift from the code: the scene reference (`docs/scene.md`) is
//! generated from the scene's definition (`src/scene/raw.rs`: every key, its type, its default
//! and its doc comment) and compared here; every file a document, a doc comment or a scene
//! refers to exists, and every test named in the docs exists.
//!
//! After changing a scene key: `LINERCAV_UPDATE_DOCS=1 cargo test --release --test docs`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One field of a `Raw*` struct.
struct Field {
    name: String,
    ty: String,
    doc: String,
    default: Option<String>,
}

/// The `Raw*` structs of raw.rs with their fields, and the bodies of its `default_*` functions.
fn parse_raw(src: &str) -> (BTreeMap<String, Vec<Field>>, BTreeMap<String, String>) {
    let mut structs = BTreeMap::new();
    let mut defaults = BTreeMap::new();
    let lines: Vec<&str> = src.lines().collect();
    let mut i = 0;
    while i < lines.len() {
        let l = lines[i].trim();
        if let Some(rest) = l.strip_prefix("pub struct ") {
            let name = rest.trim_end_matches(" {").trim().to_string();
            let mut fields = Vec::new();
            let (mut doc, mut default) = (String::new(), None);
            i += 1;
            while i < lines.len() && lines[i].trim() != "}" {
                let f = lines[i].trim();
                if let Some(d) = f.strip_prefix("///") {
                    doc.push_str(d.trim());
                    doc.push(' ');
                } else if let Some(s) = f.strip_prefix("#[serde(default") {
                    default = Some(
                        s.trim_start_matches(" = \"")
                            .trim_end_matches(")]")
                            .trim_end_matches('"')
                            .to_string(),
                    );
                } else if let Some(decl) = f.strip_prefix("pub ") {
                    if let Some((n, t)) = decl.split_once(':') {
                        fields.push(Field {
                            name: n.trim().to_string(),
                            ty: t.trim().trim_end_matches(',').to_string(),
                            doc: doc.trim().to_string(),
                            default: default.take(),
                        });
                    }
                    doc.clear();
                }
                i += 1;
            }
            structs.insert(name, fields);
        } else if let Some(rest) = l.strip_prefix("fn default_") {
            let name = format!("default_{}", rest.split('(').next().unwrap());
            let body = lines
                .get(i + 1)
                .map(|b| b.trim().to_string())
                .unwrap_or_default();
            defaults.insert(name, body);
        }
        i += 1;
    }
    (structs, defaults)
}

/// The struct a field's type names (`Option<RawPiston>` -> `RawPiston`, maps of them too).
fn inner_struct(ty: &str) -> Option<String> {
    let start = ty.find("Raw")?;
    let name: String = ty[start..]
        .chars()
        .take_while(|c| c.is_alphanumeric())
        .collect();
    Some(name)
}

/// The `#[default]` variant of each enum of raw.rs, as the scene writes it (lowercase, as
/// `rename_all = "lowercase"` reads it).
fn enum_defaults(src: &str) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    let mut current: Option<String> = None;
    let mut marked = false;
    for line in src.lines().map(str::trim) {
        if let Some(rest) = line.strip_prefix("pub enum ") {
            current = rest.split_whitespace().next().map(str::to_string);
            marked = false;
        } else if line == "#[default]" {
            marked = true;
        } else if marked {
            if let Some(name) = &current {
                let variant = line.trim_end_matches(',').to_lowercase();
                out.insert(name.clone(), variant);
            }
            marked = false;
        }
    }
    out
}

/// A `#[serde(default)]` field's default, from its type: Default's value of a primitive, the
/// `#[default]` variant of an enum.
fn type_default(ty: &str, enums: &BTreeMap<String, String>) -> String {
    match ty {
        t if t.starts_with("Option") => "none".to_string(),
        t if t.starts_with("Vec") => "`[]`".to_string(),
        "String" => "empty".to_string(),
        "bool" => "`false`".to_string(),
        "f64" | "f32" | "usize" | "u64" | "u32" | "i64" | "i32" => "`0`".to_string(),
        t => enums
            .get(t)
            .map(|v| format!("`\"{v}\"`"))
            .unwrap_or_else(|| format!("`{t}::default()`")),
    }
}

/// Renders the scene reference: one table per section, in the order of the definition.
fn render(
    structs: &BTreeMap<String, Vec<Field>>,
    defaults: &BTreeMap<String, String>,
    enums: &BTreeMap<String, String>,
) -> String {
    let mut out = String::from(
        "# Scene reference\n\nGenerated from `src/scene/raw.rs` by `tests/docs.rs` \
         (`LINERCAV_UPDATE_DOCS=1 cargo test --release --test docs`); do not edit by hand.\n\n\
         Units: SI unless the key names another (`_mm`, `_um`, `_deg`, `_c`, `_bar`, `_kpa`, \
         `_kn`, `_gb`, ...); a length in mm lies in [0.01, 30000] unless its row says more. \
         *required*: the key must be given (in its section, when the section \
         is used). `--set KEY=VALUE` overrides any key. Values are checked when the scene is \
         loaded (ranges in the descriptions, refusals with the key named); see the README's \
         \"Bad input, limits, exit codes\".\n",
    );
    let mut stack: Vec<(String, String)> = vec![(String::new(), "RawScene".into())];
    let mut seen = std::collections::BTreeSet::new();
    while let Some((prefix, sname)) = stack.pop() {
        if !seen.insert((prefix.clone(), sname.clone())) {
            continue;
        }
        let Some(fields) = structs.get(&sname) else {
            continue;
        };
        let mut rows = String::new();
        let mut nested = Vec::new();
        for f in fields {
            let key = if prefix.is_empty() {
                f.name.clone()
            } else {
                format!("{prefix}.{}", f.name)
            };
            if let Some(inner) = inner_struct(&f.ty).filter(|s| structs.contains_key(s)) {
                let key = if f.ty.starts_with("BTreeMap") {
                    format!("{key}.NAME")
                } else {
                    key
                };
                nested.push((key, inner));
                continue;
            }
            let default = match &f.default {
                None if f.ty.starts_with("Option") => "optional".to_string(),
                None => "*required*".to_string(),
                Some(d) if d.is_empty() => type_default(&f.ty, enums),
                Some(d) => defaults
                    .get(d)
                    .map(|b| format!("`{b}`"))
                    .unwrap_or_else(|| format!("`{d}()`")),
            };
            // rustdoc's escapes of unit brackets (\[mm\]) read as plain brackets here
            let doc = f
                .doc
                .replace("\\[", "[")
                .replace("\\]", "]")
                .replace('|', "\\|");
            rows.push_str(&format!("| `{key}` | `{}` | {default} | {doc} |\n", f.ty));
        }
        if !rows.is_empty() {
            let title = if prefix.is_empty() {
                "(top level)".to_string()
            } else {
                format!("[{prefix}]")
            };
            out.push_str(&format!(
                "\n## {title}\n\n| key | type | default | meaning |\n|---|---|---|---|\n{rows}"
            ));
        }
        // keep the definition's order: push in reverse onto the stack
        for n in nested.into_iter().rev() {
            stack.push(n);
        }
    }
    out
}

/// Verification of the docs against the code: the committed scene reference equals the one
/// generated from `src/scene/raw.rs` now.
#[test]
fn verification_scene_reference_is_generated_from_the_code() {
    let src = std::fs::read_to_string("src/scene/raw.rs").unwrap();
    let (structs, defaults) = parse_raw(&src);
    assert!(structs.len() > 10, "parsed {} structs", structs.len());
    let text = render(&structs, &defaults, &enum_defaults(&src));
    for key in [
        "engine.bore_mm",
        "piston.clearance_um",
        "transient.tolerance",
        "limits.max_hours",
    ] {
        assert!(text.contains(&format!("`{key}`")), "{key} missing");
    }
    let path = Path::new("docs/scene.md");
    if std::env::var_os("LINERCAV_UPDATE_DOCS").is_some() {
        std::fs::write(path, &text).unwrap();
    }
    let committed = std::fs::read_to_string(path).unwrap_or_default();
    assert!(
        committed == text,
        "docs/scene.md is out of date with src/scene/raw.rs: run LINERCAV_UPDATE_DOCS=1 cargo test --release --test docs"
    );
}

/// Paths named on purpose although they do not exist in a checkout: made by the command the
/// text gives (the fuzz corpus), or a missing file a test asks for.
const NOT_FILES: [&str; 2] = ["fuzz/corpus", "tests/fixtures/missing.msh"];

fn files_under(dir: &Path, exts: &[&str], out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            files_under(&p, exts, out);
        } else if p
            .extension()
            .is_some_and(|x| exts.contains(&x.to_str().unwrap()))
        {
            out.push(p);
        }
    }
}

/// Every path like `tests/rom.rs` or `docs/physics.md` in the README, the docs, the sources'
/// comments, the scenes and the scripts names a file or directory that exists; every test
/// named `verification_*`, `regression_*` or `validation_*` in a document exists in `tests/` or
/// as a unit test in `src/`.
#[test]
fn verification_every_referenced_file_and_test_exists() {
    // a test is found by its whole name, not by a longer one that starts with it
    let sample = "fn verification_xy() {}";
    assert!(defines_fn(sample, "verification_xy") && !defines_fn(sample, "verification_x"));
    let mut docs = vec![PathBuf::from("README.md")];
    for (dir, exts) in [
        ("docs", &["md"][..]),
        ("src", &["rs"][..]),
        ("tests", &["rs", "toml", "py"][..]),
        ("models", &["toml"][..]),
        ("benches", &["sh", "rs", "md"][..]),
        ("scripts", &["sh", "py"][..]),
        ("reports", &["md"][..]),
    ] {
        if Path::new(dir).exists() {
            files_under(Path::new(dir), exts, &mut docs);
        }
    }
    let mut test_src = String::new();
    let mut tests = Vec::new();
    // integration tests and the unit tests beside the code they check
    files_under(Path::new("tests"), &["rs"], &mut tests);
    files_under(Path::new("src"), &["rs"], &mut tests);
    for t in &tests {
        test_src.push_str(&std::fs::read_to_string(t).unwrap());
    }
    let roots = [
        "src/", "tests/", "benches/", "docs/", "reports/", "scripts/", "models/", "fuzz/",
    ];
    let mut missing = Vec::new();
    for d in &docs {
        let text = std::fs::read_to_string(d).unwrap();
        for (i, line) in text.lines().enumerate() {
            for root in roots {
                let mut from = 0;
                while let Some(k) = line[from..].find(root) {
                    let s = from + k;
                    from = s + root.len();
                    // a path starts the token: not preceded by a letter, '/', '.' or '-'
                    if s > 0 {
                        let prev = line.as_bytes()[s - 1];
                        if prev.is_ascii_alphanumeric() || b"/.-_".contains(&prev) {
                            continue;
                        }
                    }
                    let token: String = line[s..]
                        .chars()
                        .take_while(|c| c.is_ascii_alphanumeric() || "/._-".contains(*c))
                        .collect();
                    let token = token.trim_end_matches(['.', '/']).to_string();
                    if token == root.trim_end_matches('/')
                        || NOT_FILES.iter().any(|n| token.starts_with(n))
                    {
                        continue;
                    }
                    if !Path::new(&token).exists() {
                        missing.push(format!("{}:{}: {token}", d.display(), i + 1));
                    }
                }
            }
            if d.extension().is_some_and(|x| x == "md") {
                for word in line.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_')) {
                    let named = ["verification_", "regression_", "validation_"]
                        .iter()
                        .any(|p| word.starts_with(p) && word.len() > p.len());
                    if named && !defines_fn(&test_src, word) {
                        missing.push(format!("{}:{}: test {word}", d.display(), i + 1));
                    }
                }
            }
        }
    }
    assert!(
        missing.is_empty(),
        "dangling references:\n{}",
        missing.join("\n")
    );
}

/// Test functions in `text` not named with one of `KINDS`: every `fn` after `#[test]` (other
/// attributes and comments between), and every `fn` inside a `proptest! { ... }` block (its
/// cases are tests, whatever their name).
fn unnamed_tests(text: &str) -> Vec<String> {
    const KINDS: [&str; 5] = [
        "verification_",
        "regression_",
        "validation_",
        "contract_",
        "fuzz_",
    ];
    let mut unnamed = Vec::new();
    let (mut marked, mut in_proptest) = (false, false);
    for raw in text.lines() {
        if raw.starts_with("proptest!") {
            in_proptest = true;
        } else if raw == "}" {
            in_proptest = false;
        }
        let line = raw.trim();
        if line == "#[test]" {
            marked = true;
            continue;
        }
        if (marked || in_proptest) && line.starts_with("fn ") {
            let name: String = line[3..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            if !KINDS.iter().any(|k| name.starts_with(k)) {
                unnamed.push(name);
            }
            marked = false;
        } else if marked && !line.starts_with("#[") && !line.starts_with("//") {
            marked = false;
        }
    }
    unnamed
}

/// Every test in `tests/` is named for what it is (docs/verification.md): a test without one
/// of the prefixes fails here with its file and name. The scanner itself is checked first on a
/// text with one badly named test of each kind (it once could not see proptest cases that were
/// not named `fuzz_*`).
#[test]
fn contract_every_test_is_named_for_what_it_is() {
    let sample = "#[test]\n#[ignore]\nfn plain_name() {}\n#[test]\nfn regression_ok() {}\nproptest! {\n    #[test]\n    fn case_without_kind(x in 0..1) {}\n    fn fuzz_ok(x in 0..1) {}\n}\nfn helper() {}\n";
    assert_eq!(
        unnamed_tests(sample),
        vec!["plain_name", "case_without_kind"]
    );
    let mut files = Vec::new();
    files_under(Path::new("tests"), &["rs"], &mut files);
    let mut unnamed = Vec::new();
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap();
        for name in unnamed_tests(&text) {
            unnamed.push(format!("{}: {name}", f.display()));
        }
    }
    assert!(
        unnamed.is_empty(),
        "tests not named for what they are: {unnamed:#?}"
    );
}

/// Whether `src` defines `fn name` exactly (not a longer name that starts with it).
fn defines_fn(src: &str, name: &str) -> bool {
    let needle = format!("fn {name}");
    src.match_indices(&needle).any(|(i, _)| {
        src[i + needle.len()..]
            .chars()
            .next()
            .is_none_or(|c| !(c.is_ascii_alphanumeric() || c == '_'))
    })
}
