//! Reader of Abaqus input files (`.inp`): the solid mesh and its sets.
//!
//! Keywords (case-insensitive, parameters after commas): `*NODE` (optionally `NSET=`),
//! `*ELEMENT, TYPE=` C3D4, C3D10, C3D8 or C3D20 with any formulation letters (C3D8R, C3D10MH,
//! C3D20RH ...: read as their nodes; linercav integrates its own element) (optionally
//! `ELSET=`; an element's ids may continue on the next lines), `*NSET, NSET=` and
//! `*ELSET, ELSET=` with lists of ids or `GENERATE` lines `first, last[, step]`. A flat input
//! file (as written by Abaqus/CAE's "write input" without parts, meshio, or most
//! pre-processors' solver decks) is read; `*INCLUDE` is refused; other keywords and their
//! data (materials, steps ...) are skipped, other element types are refused. Comments start
//! with `**`. Every element set also becomes the node set of its elements' nodes (unless a
//! node set has the name). Coordinates are taken as metres.

use super::collect::MshError;
use super::collect::{read_mesh_text, Loc, reorder, Collected, HEX20_ABAQUS, TET10_DECK};
use super::element::ElementKind;
use super::Mesh;
use std::path::Path;

/// Reads an input file from disk.
pub fn read(path: &Path) -> Result<Mesh, MshError> {
    let text = read_mesh_text(path, "expected an Abaqus input file (ASCII)")?;
    parse(path, &text)
}

/// The data block being read.
enum Block {
    Skip,
    Node(Option<String>),
    Element {
        kind: ElementKind,
        abaqus: String,
        elset: Option<String>,
    },
    Set {
        nodes: bool,
        name: String,
        generate: bool,
    },
}

/// The solid of an Abaqus element type: C3D4, C3D10, C3D8 or C3D20 followed by formulation
/// letters (R reduced integration, I incompatible modes, H hybrid, M modified), which change
/// how Abaqus integrates the element, not its nodes: linercav integrates its own element.
fn solid_kind(t: &str) -> Option<ElementKind> {
    let rest = t.to_ascii_uppercase();
    let rest = rest.strip_prefix("C3D")?;
    let digits: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
    let letters = &rest[digits.len()..];
    if !letters.chars().all(|c| "RIHM".contains(c)) {
        return None;
    }
    match digits.as_str() {
        "4" => Some(ElementKind::Tet4),
        "10" => Some(ElementKind::Tet10),
        "8" => Some(ElementKind::Hex8),
        "20" => Some(ElementKind::Hex20),
        _ => None,
    }
}

/// Keyword parameter `key` (upper case) of a keyword line's parameters.
fn param(params: &[(String, String)], key: &str) -> Option<String> {
    params
        .iter()
        .find(|(k, _)| k == key)
        .map(|(_, v)| v.clone())
}

/// The data block a keyword line (without its `*`) opens.
fn keyword(kw: &str, at: &dyn Fn(String) -> MshError) -> Result<Block, MshError> {
    let mut parts = kw.split(',').map(|s| s.trim());
    let name = parts.next().unwrap_or("").to_ascii_uppercase();
    let params: Vec<(String, String)> = parts
        .filter(|p| !p.is_empty())
        .map(|p| match p.split_once('=') {
            Some((k, v)) => (k.trim().to_ascii_uppercase(), v.trim().to_string()),
            None => (p.to_ascii_uppercase(), String::new()),
        })
        .collect();
    Ok(match name.as_str() {
        "NODE" => Block::Node(param(&params, "NSET")),
        "ELEMENT" => {
            let t = param(&params, "TYPE").ok_or_else(|| at("*ELEMENT without TYPE=".into()))?;
            let kind = solid_kind(&t).ok_or_else(|| {
                at(format!(
                    "element type {t} is not supported (expected C3D4, C3D10, C3D8 or C3D20, with formulation letters R, I, H, M)"
                ))
            })?;
            Block::Element {
                kind,
                abaqus: t.to_ascii_uppercase(),
                elset: param(&params, "ELSET"),
            }
        }
        "NSET" | "ELSET" => {
            let nodes = name == "NSET";
            let name = param(&params, &name)
                .ok_or_else(|| at(format!("*{name} without {name}= (the set's name)")))?;
            Block::Set {
                nodes,
                name,
                generate: params.iter().any(|(k, _)| k == "GENERATE"),
            }
        }
        "INCLUDE" => {
            return Err(at(
                "*INCLUDE is not read: merge the included files into one input file".into(),
            ))
        }
        _ => Block::Skip,
    })
}

/// The ids of a set's data line `l` (fields `f`): a list, or `first, last[, step]` when
/// `generate` (at most `file_bytes` ids).
fn set_ids(
    f: &[&str],
    generate: bool,
    l: &str,
    file_bytes: usize,
    at: &dyn Fn(String) -> MshError,
) -> Result<Vec<i64>, MshError> {
    let mut ids = Vec::new();
    if generate {
        let n: Vec<i64> = f
            .iter()
            .map(|w| w.parse())
            .collect::<Result<_, _>>()
            .map_err(|_| at(format!("expected 'first, last[, step]', found '{l}'")))?;
        let (a, b, s) = match n[..] {
            [a, b] => (a, b, 1),
            [a, b, s] => (a, b, s),
            _ => return Err(at(format!("expected 'first, last[, step]', found '{l}'"))),
        };
        // a file defines fewer ids than it has bytes: a longer range is hostile
        if s <= 0 || b < a || (b - a) / s > file_bytes as i64 {
            return Err(at(format!("GENERATE {a}, {b}, {s} is not a range")));
        }
        ids.extend((a..=b).step_by(s as usize));
    } else {
        for w in f {
            ids.push(w.parse::<i64>().map_err(|_| {
                at(format!(
                    "'{w}' is not an id (sets of sets are not read: list the ids)"
                ))
            })?);
        }
    }
    Ok(ids)
}

/// Parses an input file; `path` is used in messages only.
pub fn parse(path: &Path, text: &str) -> Result<Mesh, MshError> {
    let mut c = Collected::new(path);
    let mut block = Block::Skip;
    // an element whose ids continue on the next line: (line, numbers so far)
    let mut pending: Option<(usize, Vec<i64>)> = None;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let at = |msg: String| MshError {
            path: path.to_path_buf(),
            line,
            msg,
        };
        let l = raw.trim();
        if l.is_empty() || l.starts_with("**") {
            continue;
        }
        if let Some(kw) = l.strip_prefix('*') {
            if let Some((first, _)) = &pending {
                return Err(at(format!(
                    "the element started on line {first} lacks nodes before this keyword"
                )));
            }
            block = keyword(kw, &at)?;
            continue;
        }
        let numbers = || -> Result<Vec<&str>, MshError> {
            Ok(l.split(',')
                .map(|s| s.trim())
                .filter(|s| !s.is_empty())
                .collect())
        };
        match &block {
            Block::Skip => {}
            Block::Node(nset) => {
                let f = numbers()?;
                if f.len() < 4 {
                    return Err(at(format!("expected 'id, x, y, z', found '{l}'")));
                }
                let id: i64 = f[0]
                    .parse()
                    .map_err(|_| at(format!("node id '{}' is not an integer", f[0])))?;
                let mut x = [0.0; 3];
                for (a, xa) in x.iter_mut().enumerate() {
                    *xa = f[1 + a]
                        .parse::<f64>()
                        .ok()
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| {
                            at(format!(
                                "node {id}: coordinate '{}' is not a finite number",
                                f[1 + a]
                            ))
                        })?;
                }
                c.nodes.push((id, x, Loc::main(line)));
                if let Some(n) = nset {
                    c.node_sets
                        .entry(n.clone())
                        .or_insert((Vec::new(), Loc::main(line)))
                        .0
                        .push(id);
                }
            }
            Block::Element {
                kind,
                abaqus,
                elset,
            } => {
                let (first, mut got) = pending.take().unwrap_or((line, Vec::new()));
                for w in numbers()? {
                    got.push(
                        w.parse()
                            .map_err(|_| at(format!("'{w}' is not an integer id")))?,
                    );
                }
                let need = 1 + kind.num_nodes();
                if got.len() < need {
                    pending = Some((first, got));
                    continue;
                }
                if got.len() > need {
                    return Err(at(format!(
                        "element {} has {} node ids, {abaqus} has {}",
                        got[0],
                        got.len() - 1,
                        kind.num_nodes()
                    )));
                }
                let ids = match kind {
                    ElementKind::Tet10 => reorder(*kind, &TET10_DECK, &got[1..]),
                    ElementKind::Hex20 => reorder(*kind, &HEX20_ABAQUS, &got[1..]),
                    _ => got[1..].to_vec(),
                };
                c.elements.push((got[0], *kind, ids, Loc::main(first)));
                if let Some(e) = elset {
                    c.element_sets
                        .entry(e.clone())
                        .or_insert((Vec::new(), Loc::main(first)))
                        .0
                        .push(got[0]);
                }
            }
            Block::Set {
                nodes,
                name,
                generate,
            } => {
                let ids = set_ids(&numbers()?, *generate, l, text.len(), &at)?;
                let sets = if *nodes {
                    &mut c.node_sets
                } else {
                    &mut c.element_sets
                };
                sets.entry(name.clone())
                    .or_insert((Vec::new(), Loc::main(line)))
                    .0
                    .extend(ids);
            }
        }
    }
    if let Some((first, _)) = pending {
        return Err(MshError {
            path: path.to_path_buf(),
            line: first,
            msg: "the file ends inside an element's node list".into(),
        });
    }
    c.into_mesh()
}

#[cfg(test)]
mod tests {
    use super::*;

    const TET: &str = "** a unit tetrahedron\n*Heading\n x\n*NODE, NSET=all\n1, 0., 0., 0.\n2, 1., 0., 0.\n3, 0., 1., 0.\n4, 0., 0., 1.\n*ELEMENT, TYPE=C3D4, ELSET=solid\n1, 1, 2,\n 3, 4\n*NSET, NSET=tip\n4\n*NSET, NSET=base, GENERATE\n1, 3, 1\n*ELSET, ELSET=again, generate\n1, 1\n*MATERIAL, NAME=steel\n*ELASTIC\n2e11, 0.3\n";

    #[test]
    fn sets_generate_and_continued_elements() {
        let m = parse(Path::new("t.inp"), TET).unwrap();
        assert_eq!(m.nodes.len(), 4);
        assert_eq!(m.blocks[0].conn, vec![0, 1, 2, 3]);
        assert_eq!(m.node_sets["tip"], vec![3]);
        assert_eq!(m.node_sets["base"], vec![0, 1, 2]);
        assert_eq!(m.node_sets["all"], vec![0, 1, 2, 3]);
        assert_eq!(m.element_sets["solid"], vec![0]);
        assert_eq!(
            m.node_sets["solid"],
            vec![0, 1, 2, 3],
            "an element set's nodes"
        );
        assert_eq!(m.element_sets["again"], vec![0]);
    }

    #[test]
    fn bad_input_names_the_line() {
        let p = Path::new("t.inp");
        let e = parse(p, &TET.replace("C3D4", "C3D6")).unwrap_err();
        assert!(e.line == 9 && e.msg.contains("C3D6"), "{e}");
        let e = parse(p, &TET.replace("2, 1., 0., 0.", "2, 1., zero, 0.")).unwrap_err();
        assert!(e.line == 6 && e.msg.contains("zero"), "{e}");
        let e = parse(p, &TET.replace("1, 1, 2,\n 3, 4", "1, 1, 2,\n 3, 9")).unwrap_err();
        assert!(e.line == 10 && e.msg.contains("node 9"), "{e}");
        let e = parse(p, &TET.replace("*Heading", "*INCLUDE, INPUT=x.inp")).unwrap_err();
        assert!(e.msg.contains("INCLUDE"), "{e}");
        let e = parse(p, &TET.replace("1, 3, 1\n", "3, 1\n")).unwrap_err();
        assert!(e.msg.contains("not a range"), "{e}");
    }
}
