//! Reader of Nastran bulk data (`.bdf`, `.nas`): the solid mesh and its node sets.
//!
//! Cards: GRID (basic coordinate system only: CP blank or 0), CTETRA with 4 or 10 nodes,
//! CHEXA with 8 or 20 nodes, SET1 (node ids, `THRU` ranges). Field formats: small (8
//! columns), large (`*` after the name, 16 columns, continuation lines starting with `*`) and
//! free (comma-separated, a large free card named with `*`); continuation lines start with
//! `+` or `*` or, in small field, with a blank name field; a line of the bulk section that ends
//! a card early is continued by the next such line. Real numbers in any Nastran form: `1.5E-3`,
//! `1.5D-3`, `1.5-3` (exponent without a letter), `.5`, `7.`. Everything before `BEGIN BULK`
//! (when present) and after `ENDDATA` is skipped, as are cards this tool does not use
//! (materials, properties, loads ...) and lower-dimensional elements; pentahedra and pyramids
//! are refused.
//!
//! Node sets: a SET1's name is given by a HyperMesh-style comment `$HMSET  SID  TYPE "name"`
//! anywhere in the file; without one the set is named by its id (`"7"`). Element sets: the
//! property id of the solid elements, `"PID<n>"` (none for a blank PID). Coordinates are taken as metres.

use super::collect::MshError;
use super::collect::{read_mesh_text, Loc, reorder, Collected, HEX20_NASTRAN, TET10_DECK};
use super::element::ElementKind;
use super::Mesh;
use std::collections::BTreeMap;
use std::path::Path;

/// Reads a bulk-data file from disk.
pub fn read(path: &Path) -> Result<Mesh, MshError> {
    let text = read_mesh_text(path, "expected Nastran bulk data (ASCII)")?;
    parse(path, &text)
}

/// One card: its name (upper case, without `*`), data fields and first line.
struct Card {
    name: String,
    fields: Vec<String>,
    line: usize,
}

/// Splits a physical line into (name field, data fields, whether it is a continuation).
fn split_line(l: &str) -> (String, Vec<String>, bool) {
    if l.contains(',') {
        let mut parts: Vec<String> = l.split(',').map(|f| f.trim().to_string()).collect();
        let first = parts.remove(0);
        let cont = first.starts_with('+') || first.starts_with('*') || first.is_empty();
        return (first, parts, cont);
    }
    let chars: Vec<char> = l.chars().collect();
    let field = |a: usize, b: usize| -> String {
        chars
            .get(a.min(chars.len())..b.min(chars.len()))
            .map(|s| s.iter().collect::<String>().trim().to_string())
            .unwrap_or_default()
    };
    let first = field(0, 8);
    let large = first.ends_with('*') || (first.starts_with('*'));
    let width = if large { 16 } else { 8 };
    let count = if large { 4 } else { 8 };
    let fields = (0..count)
        .map(|k| field(8 + k * width, 8 + (k + 1) * width))
        .collect();
    let cont = first.starts_with('+') || first.starts_with('*') || first.is_empty();
    (first, fields, cont)
}

/// A Nastran real: `1.5E-3`, `1.5D-3`, `1.5-3`, `-.5+2`, `7.`.
fn real(s: &str) -> Option<f64> {
    let t = s.trim().replace(['D', 'd'], "E");
    if let Ok(v) = t.parse::<f64>() {
        return v.is_finite().then_some(v);
    }
    // an exponent sign without its letter, after the first character
    let b = t.as_bytes();
    let k = (1..b.len())
        .find(|&i| (b[i] == b'+' || b[i] == b'-') && b[i - 1] != b'E' && b[i - 1] != b'e')?;
    let v: f64 = format!("{}E{}", &t[..k], &t[k..]).parse().ok()?;
    v.is_finite().then_some(v)
}

/// The cards of the bulk section.
fn cards(text: &str) -> (Vec<Card>, BTreeMap<i64, String>) {
    let bulk_from = text
        .lines()
        .position(|l| l.trim().to_ascii_uppercase().starts_with("BEGIN BULK"))
        .map_or(0, |k| k + 1);
    let mut out: Vec<Card> = Vec::new();
    let mut names = BTreeMap::new();
    for (i, raw) in text.lines().enumerate().skip(bulk_from) {
        let l = raw.trim_end();
        if let Some(c) = l.strip_prefix('$') {
            // $HMSET  SID  TYPE "name"
            let c = c.trim_start();
            if let Some(rest) = c.strip_prefix("HMSET") {
                let mut words = rest.split_whitespace();
                let sid = words.next().and_then(|w| w.parse::<i64>().ok());
                let name = rest.split('"').nth(1);
                if let (Some(sid), Some(name)) = (sid, name) {
                    names.insert(sid, name.to_string());
                }
            }
            continue;
        }
        if l.trim().is_empty() {
            continue;
        }
        if l.trim().to_ascii_uppercase().starts_with("ENDDATA") {
            break;
        }
        let (first, fields, cont) = split_line(l);
        match (cont, out.last_mut()) {
            (true, Some(card)) => card.fields.extend(fields),
            _ => out.push(Card {
                name: first.trim_end_matches('*').to_ascii_uppercase(),
                fields,
                line: i + 1,
            }),
        }
    }
    (out, names)
}

/// Parses bulk data; `path` is used in messages only.
pub fn parse(path: &Path, text: &str) -> Result<Mesh, MshError> {
    let (cards, names) = cards(text);
    let mut c = Collected::new(path);
    let mut sets: BTreeMap<i64, (Vec<i64>, Loc)> = BTreeMap::new();
    let mut props: BTreeMap<i64, (Vec<i64>, Loc)> = BTreeMap::new();
    for card in &cards {
        let at = |msg: String| MshError {
            path: path.to_path_buf(),
            line: card.line,
            msg: format!("{}: {msg}", card.name),
        };
        let int = |k: usize, what: &str| -> Result<i64, MshError> {
            let f = card.fields.get(k).map(|s| s.as_str()).unwrap_or("");
            f.parse::<i64>().map_err(|_| {
                at(format!(
                    "field {} ({what}) is '{f}', expected an integer",
                    k + 2
                ))
            })
        };
        match card.name.as_str() {
            "GRID" => {
                let id = int(0, "node id")?;
                let cp = card.fields.get(1).map(|s| s.trim()).unwrap_or("");
                if !(cp.is_empty() || cp == "0") {
                    return Err(at(format!(
                        "node {id} is given in coordinate system {cp}; only the basic system (CP blank or 0) is read: export the nodes in the basic system"
                    )));
                }
                let mut x = [0.0; 3];
                for (a, xa) in x.iter_mut().enumerate() {
                    let f = card.fields.get(2 + a).map(|s| s.as_str()).unwrap_or("");
                    *xa = real(f).ok_or_else(|| {
                        at(format!(
                            "node {id}: coordinate X{} is '{f}', expected a real number",
                            a + 1
                        ))
                    })?;
                }
                c.nodes.push((id, x, Loc::main(card.line)));
            }
            "CTETRA" | "CHEXA" => {
                let eid = int(0, "element id")?;
                // a blank property id (Nastran's default: the element id) puts the element
                // in no property set
                let pid = match card.fields.get(1).map(|f| f.trim()) {
                    None | Some("") => None,
                    Some(_) => Some(int(1, "property id")?),
                };
                let ids: Vec<i64> = card.fields[2.min(card.fields.len())..]
                    .iter()
                    .filter(|f| !f.is_empty())
                    .map(|f| f.parse::<i64>())
                    .collect::<Result<_, _>>()
                    .map_err(|_| at(format!("element {eid}: a node id is not an integer")))?;
                let kind = match (card.name.as_str(), ids.len()) {
                    ("CTETRA", 4) => ElementKind::Tet4,
                    ("CTETRA", 10) => ElementKind::Tet10,
                    ("CHEXA", 8) => ElementKind::Hex8,
                    ("CHEXA", 20) => ElementKind::Hex20,
                    (n, k) => {
                        return Err(at(format!(
                            "element {eid} has {k} nodes; {n} is read with {}",
                            if n == "CTETRA" { "4 or 10" } else { "8 or 20" }
                        )))
                    }
                };
                let ids = match kind {
                    ElementKind::Tet10 => reorder(kind, &TET10_DECK, &ids),
                    ElementKind::Hex20 => reorder(kind, &HEX20_NASTRAN, &ids),
                    _ => ids,
                };
                c.elements.push((eid, kind, ids, Loc::main(card.line)));
                if let Some(pid) = pid {
                    props
                        .entry(pid)
                        .or_insert((Vec::new(), Loc::main(card.line)))
                        .0
                        .push(eid);
                }
            }
            "CPENTA" | "CPYRA" => return Err(at(
                "pentahedra and pyramids are not supported: mesh with tetrahedra or hexahedra only"
                    .into(),
            )),
            "SET1" => {
                let sid = int(0, "set id")?;
                let f: Vec<&str> = card.fields[1.min(card.fields.len())..]
                    .iter()
                    .map(|s| s.as_str())
                    .filter(|s| !s.is_empty())
                    .collect();
                let entry = sets.entry(sid).or_insert((Vec::new(), Loc::main(card.line)));
                let mut k = 0;
                while k < f.len() {
                    let a: i64 = f[k]
                        .parse()
                        .map_err(|_| at(format!("set {sid}: '{}' is not a node id", f[k])))?;
                    if f.get(k + 1).is_some_and(|w| w.eq_ignore_ascii_case("THRU")) {
                        let b: i64 =
                            f.get(k + 2).and_then(|w| w.parse().ok()).ok_or_else(|| {
                                at(format!("set {sid}: THRU after {a} needs an end id"))
                            })?;
                        // a file defines fewer nodes than it has bytes: a longer range is hostile
                        if b < a || b - a > text.len() as i64 {
                            return Err(at(format!(
                                "set {sid}: {a} THRU {b} is not a range of this file's node ids"
                            )));
                        }
                        entry.0.extend(a..=b);
                        k += 3;
                    } else {
                        entry.0.push(a);
                        k += 1;
                    }
                }
            }
            _ => {}
        }
    }
    for (sid, v) in sets {
        let name = names.get(&sid).cloned().unwrap_or_else(|| sid.to_string());
        c.node_sets.insert(name, v);
    }
    for (pid, v) in props {
        c.element_sets.insert(format!("PID{pid}"), v);
    }
    c.into_mesh()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nastran_reals_in_every_form() {
        for (s, v) in [
            ("1.5E-3", 1.5e-3),
            ("1.5D-3", 1.5e-3),
            ("1.5-3", 1.5e-3),
            ("-.5+2", -50.0),
            ("7.", 7.0),
            (".7E1", 7.0),
            ("70.-1", 7.0),
            ("1.23456789012E+0", 1.23456789012),
        ] {
            assert!((real(s).unwrap() - v).abs() < 1e-12 * v.abs(), "{s}");
        }
        assert_eq!(real("abc"), None);
        assert_eq!(real(""), None);
    }

    #[test]
    fn small_large_and_free_fields_with_continuations_read_alike() {
        // one unit tetrahedron, written three ways, with a named set
        let small = "BEGIN BULK\n$HMSET        7       1 \"tip\"\nGRID    1               0.      0.      0.\nGRID    2               1.      0.      0.\nGRID    3               0.      1.0     0.\nGRID    4               0.      0.      1.-0\nCTETRA  1       1       1       2       3       4\nSET1    7       4\nENDDATA\n";
        // the small-field element's fourth node on a continuation (marker in columns 73-80)
        let large = format!(
            "GRID*   1                               0.0             0.0\n*       0.0\nGRID*   2                               1.0D+0          0.0\n*       0.0\nGRID*   3                               0.0             1.0\n*       0.0\nGRID*   4                               0.0             0.0\n*       1.0\n{:<72}+C1\n+C1     4\nSET1    7       4\n$HMSET 7 1 \"tip\"\n",
            "CTETRA  1       1       1       2       3"
        );
        let free = "GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,0.,1.,0.\nGRID,4,,0.,0.,1.\nCTETRA,1,1,1,2,3,\n+,4\nSET1,7,1,THRU,4\n$HMSET 7 1 \"tip\"\n";
        let p = Path::new("t.bdf");
        let a = parse(p, small).unwrap();
        let b = parse(p, &large).unwrap();
        let c = parse(p, free).unwrap();
        for m in [&a, &b, &c] {
            assert_eq!(m.nodes.len(), 4);
            assert_eq!(m.nodes[3], [0.0, 0.0, 1.0]);
            assert_eq!(m.nodes[1], [1.0, 0.0, 0.0]);
            assert_eq!(m.blocks[0].conn, vec![0, 1, 2, 3]);
            assert_eq!(m.element_sets["PID1"], vec![0]);
        }
        assert_eq!(a.node_sets["tip"], vec![3]);
        assert_eq!(b.node_sets["tip"], vec![3]);
        assert_eq!(c.node_sets["tip"], vec![0, 1, 2, 3]);
    }

    #[test]
    fn bad_cards_name_the_line_and_field() {
        let p = Path::new("t.bdf");
        let e = parse(p, "GRID,1,,0.,x,0.\n").unwrap_err();
        assert!(
            e.line == 1 && e.msg.contains("X2") && e.msg.contains("'x'"),
            "{e}"
        );
        let e = parse(p, "GRID,1,5,0.,0.,0.\n").unwrap_err();
        assert!(e.msg.contains("coordinate system 5"), "{e}");
        let e = parse(p, "GRID,1,,0.,0.,0.\nCTETRA,1,1,1,2,3\n").unwrap_err();
        assert!(e.line == 2 && e.msg.contains("3 nodes"), "{e}");
        let e = parse(p, "GRID,1,,0.,0.,0.\nCTETRA,1,1,1,2,3,9\n").unwrap_err();
        assert!(e.line == 2 && e.msg.contains("node 2"), "{e}");
        let e = parse(p, "GRID,1,,0.,0.,0.\nCPENTA,1,1,1,2,3,4,5,6\n").unwrap_err();
        assert!(e.msg.contains("pentahedra"), "{e}");
    }
}
