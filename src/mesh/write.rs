//! Writers of meshes: Gmsh MSH 4.1 (`.msh`), Nastran bulk data (`.bdf`, `.nas`) and Abaqus
//! input (`.inp`), the format chosen by the file's extension.
//!
//! Coordinates are written in the output unit ([`MeshUnit`]: metres with SI constants, or
//! millimetres in the mm-t-s system: E in MPa, rho in t/mm^3). Nodes are numbered 1..N and
//! elements 1..E in the mesh's order (global element index + 1); element node lists are
//! converted from our (Gmsh) order to the deck's, the inverse of what the readers do, so that
//! reading a written file gives the mesh back.
//!
//! - Nastran: `GRID*` in large field (16 columns: 13 significant digits or more for
//!   magnitudes from 1e-2 to 1e14 and positive values from 1e-9 to 1e15, 11 or more for
//!   others), `CTETRA` / `CHEXA` in small field with continuations, per material a
//!   `MAT1` in large field (E, blank G, NU, RHO) and a `PSOLID` (PID = MID = material index +
//!   1), node sets as `SET1` named by `$HMSET` comments (element sets are not written).
//! - Abaqus: one part (named after the file) with its nodes, elements, sets and solid sections,
//!   one instance of it in the assembly, then the materials; reals in full precision.
//! - MSH: the Gmsh writer ([`super::gmsh::write`]); node sets become point physical groups,
//!   materials are not written (MSH has none).
//!
//! Writing is atomic ([`crate::files::write_atomic`]).

use super::collect::{HEX20_ABAQUS, HEX20_NASTRAN, TET10_DECK};
use super::{gmsh, Mesh, MeshUnit, NO_MATERIAL};
use crate::files::{write_atomic, WriteError};
use crate::scene::spec::Elastic;
use crate::scene::spec::ElementKind;
use std::borrow::Cow;
use std::collections::HashSet;
use std::io::{self, Write};
use std::path::Path;

/// The format of a mesh file to write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeckFormat {
    /// Gmsh MSH 4.1 ASCII (`.msh`).
    Msh,
    /// Nastran bulk data (`.bdf`, `.nas`).
    Nastran,
    /// Abaqus input (`.inp`).
    Abaqus,
}

impl DeckFormat {
    /// The format of `path` by its extension (case-insensitive): `.msh`, `.bdf` / `.nas`,
    /// `.inp`; `None` for any other.
    pub fn of_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "msh" => Some(Self::Msh),
            "bdf" | "nas" => Some(Self::Nastran),
            "inp" => Some(Self::Abaqus),
            _ => None,
        }
    }
}

/// What is written besides the mesh, and in which unit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WriteOptions {
    /// Length unit of the file: coordinates are x / `unit.metres()`; for millimetres the
    /// material constants are in the mm-t-s system (E in MPa, rho in t/mm^3).
    pub unit: MeshUnit,
    /// Whether node sets (and, in Abaqus input, element sets) are written.
    pub sets: bool,
    /// One material (SI) for every element; `None` writes the mesh's own deck materials
    /// (elements without one get none).
    pub material: Option<Elastic>,
}

impl Default for WriteOptions {
    /// Metres, sets written, the mesh's own materials.
    fn default() -> Self {
        WriteOptions {
            unit: MeshUnit::M,
            sets: true,
            material: None,
        }
    }
}

/// Writes `mesh` to `path` atomically in the format of its extension ([`DeckFormat::of_path`];
/// another extension is an error of kind `InvalidInput`, as are non-finite coordinates or
/// material constants).
pub fn write_mesh(path: &Path, mesh: &Mesh, opts: &WriteOptions) -> Result<(), WriteError> {
    let fail = |msg: String| WriteError {
        path: path.to_path_buf(),
        source: invalid(msg),
    };
    let Some(format) = DeckFormat::of_path(path) else {
        return Err(fail(
            "unknown mesh format: expected .msh (Gmsh MSH 4.1), .bdf or .nas (Nastran bulk data) or .inp (Abaqus input)".into(),
        ));
    };
    check_finite(mesh, opts).map_err(|e| fail(e.to_string()))?;
    match format {
        DeckFormat::Msh => {
            let m = msh_mesh(mesh, opts);
            write_atomic(path, |mut w| gmsh::write(&m, &mut w))
        }
        DeckFormat::Nastran => write_atomic(path, |w| write_nastran(w, mesh, opts)),
        DeckFormat::Abaqus => {
            let part = part_name(path);
            write_atomic(path, |w| write_abaqus(w, mesh, opts, &part))
        }
    }
}

/// An error of kind `InvalidInput`.
fn invalid(msg: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, msg)
}

/// A value no deck format can hold.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
enum NonFinite {
    /// A node (1-based) with a non-finite coordinate.
    #[error("node {0} has a non-finite coordinate")]
    Node(usize),
    #[error("a material constant is not a finite number")]
    Material,
}

/// Refuses a non-finite coordinate or material constant (it has no form in any deck).
fn check_finite(mesh: &Mesh, opts: &WriteOptions) -> Result<(), NonFinite> {
    if let Some(i) = mesh
        .nodes
        .iter()
        .position(|x| !x.iter().all(|v| v.is_finite()))
    {
        return Err(NonFinite::Node(i + 1));
    }
    let given = opts.material.iter();
    let deck = mesh.materials.iter().map(|m| &m.elastic);
    for e in given.chain(deck) {
        if ![e.young, e.poisson, e.density]
            .iter()
            .all(|v| v.is_finite())
        {
            return Err(NonFinite::Material);
        }
    }
    Ok(())
}

/// The mesh the Gmsh writer gets: coordinates in the output unit, node sets only if asked.
fn msh_mesh<'a>(mesh: &'a Mesh, opts: &WriteOptions) -> Cow<'a, Mesh> {
    if opts.unit == MeshUnit::M && opts.sets {
        return Cow::Borrowed(mesh);
    }
    let s = opts.unit.metres();
    Cow::Owned(Mesh {
        nodes: mesh
            .nodes
            .iter()
            .map(|p| [p[0] / s, p[1] / s, p[2] / s])
            .collect(),
        blocks: mesh.blocks.clone(),
        node_sets: if opts.sets {
            mesh.node_sets.clone()
        } else {
            Default::default()
        },
        ..Default::default()
    })
}

/// The materials a deck defines (name, constants in the output's unit system) and the
/// material of every element (global index), if any.
struct Materials {
    list: Vec<(String, Elastic)>,
    of_element: Vec<Option<usize>>,
}

/// The given material for every element, else the mesh's deck materials.
fn materials(mesh: &Mesh, opts: &WriteOptions) -> Materials {
    let n = mesh.num_elements();
    if let Some(e) = opts.material {
        return Materials {
            list: vec![("MATERIAL-1".into(), in_unit(e, opts.unit))],
            of_element: vec![Some(0); n],
        };
    }
    let list: Vec<(String, Elastic)> = mesh
        .materials
        .iter()
        .map(|m| (m.name.clone(), in_unit(m.elastic, opts.unit)))
        .collect();
    let of_element = (0..n)
        .map(|g| match mesh.element_material.get(g) {
            Some(&k) if k != NO_MATERIAL && (k as usize) < list.len() => Some(k as usize),
            _ => None,
        })
        .collect();
    Materials { list, of_element }
}

/// SI constants in the unit system of `unit` (mm-t-s: E in MPa, rho in t/mm^3).
fn in_unit(e: Elastic, unit: MeshUnit) -> Elastic {
    match unit {
        MeshUnit::M => e,
        MeshUnit::Mm => Elastic {
            // dividing by the exact 1e6 and 1e12 rounds once: 7850 kg/m^3 is 7.85e-9 t/mm^3
            young: e.young / 1e6,
            poisson: e.poisson,
            density: e.density / 1e12,
        },
    }
}

/// The unit system of a file, for its header.
fn unit_system(unit: MeshUnit) -> &'static str {
    match unit {
        MeshUnit::M => "m, kg, s, N, Pa (SI)",
        MeshUnit::Mm => "mm, t, s, N, MPa (mm-t-s)",
    }
}

/// An element's nodes in a deck's order: corners as ours, the mid-edge node of the deck's
/// edge i (`theirs[i]`) taken from where our [`ElementKind::mid_edges`] has that edge (the
/// inverse of `collect::reorder`).
fn deck_order(kind: ElementKind, theirs: &[(usize, usize)], ours: &[usize]) -> Vec<usize> {
    let nc = kind.num_corners();
    let mut out = ours.to_vec();
    for (i, &(a, b)) in theirs.iter().enumerate() {
        let j = kind
            .mid_edges()
            .iter()
            .position(|&(p, q)| (p, q) == (a, b) || (p, q) == (b, a));
        if let (Some(j), Some(slot)) = (j, out.get_mut(nc + i)) {
            if let Some(&n) = ours.get(nc + j) {
                *slot = n;
            }
        }
    }
    out
}

/// The deck's mid-edge convention for `kind`, with `hex20` the one of 20-node hexahedra.
fn deck_edges(kind: ElementKind, hex20: &'static [(usize, usize)]) -> &'static [(usize, usize)] {
    match kind {
        ElementKind::Tet10 => &TET10_DECK,
        ElementKind::Hex20 => hex20,
        _ => &[],
    }
}

// ---------------------------------------------------------------------------------------
// Nastran

/// The largest id of a small (8-column) field.
const NASTRAN_MAX_ID: usize = 99_999_999;

/// Writes Nastran bulk data: header, GRID*, CTETRA/CHEXA, MAT1*/PSOLID, SET1, ENDDATA.
fn write_nastran(out: &mut dyn Write, mesh: &Mesh, opts: &WriteOptions) -> io::Result<()> {
    if mesh.nodes.len().max(mesh.num_elements()) > NASTRAN_MAX_ID {
        return Err(invalid(format!(
            "more than {NASTRAN_MAX_ID} nodes or elements: too many for Nastran's 8-column ids"
        )));
    }
    let mats = materials(mesh, opts);
    let sets: Vec<(&String, &Vec<usize>)> = if opts.sets {
        mesh.node_sets
            .iter()
            .filter(|(_, v)| !v.is_empty())
            .collect()
    } else {
        Vec::new()
    };
    writeln!(out, "BEGIN BULK")?;
    writeln!(
        out,
        "$ Nastran bulk data written by linercav {}\n$ units: {}\n$ {} nodes (GRID), {} elements (CTETRA, CHEXA), {} materials (MAT1, PSOLID with PID = MID), {} node sets (SET1 named by $HMSET)",
        env!("CARGO_PKG_VERSION"),
        unit_system(opts.unit),
        mesh.nodes.len(),
        mesh.num_elements(),
        mats.list.len(),
        sets.len()
    )?;
    let s = opts.unit.metres();
    for (i, p) in mesh.nodes.iter().enumerate() {
        let f = [
            (i + 1).to_string(),
            String::new(),
            real16(p[0] / s),
            real16(p[1] / s),
            real16(p[2] / s),
        ];
        large_card(out, "GRID", &f)?;
    }
    nastran_elements(out, mesh, &mats)?;
    nastran_materials(out, &mats)?;
    nastran_sets(out, &sets)?;
    writeln!(out, "ENDDATA")
}

/// CTETRA / CHEXA cards with their PID: the material's index + 1, blank for an element
/// without a material, 1 for all when the deck has no materials.
fn nastran_elements(out: &mut dyn Write, mesh: &Mesh, mats: &Materials) -> io::Result<()> {
    for (g, (kind, nodes)) in mesh.elements().enumerate() {
        let name = if kind.is_tet() { "CTETRA" } else { "CHEXA" };
        let pid = match (mats.list.is_empty(), mats.of_element.get(g)) {
            (true, _) => "1".to_string(),
            (false, Some(Some(k))) => (k + 1).to_string(),
            _ => String::new(),
        };
        let mut f = vec![(g + 1).to_string(), pid];
        let ids = deck_order(kind, deck_edges(kind, &HEX20_NASTRAN), nodes);
        f.extend(ids.iter().map(|n| (n + 1).to_string()));
        small_card(out, name, &f)?;
    }
    Ok(())
}

/// Per material a comment with its name, a MAT1 in large field (E, blank G, NU, RHO) and a
/// PSOLID with PID = MID.
fn nastran_materials(out: &mut dyn Write, mats: &Materials) -> io::Result<()> {
    for (k, (name, e)) in mats.list.iter().enumerate() {
        let id = (k + 1).to_string();
        writeln!(out, "$ material {id}: {}", one_line(name))?;
        let f = [
            id.clone(),
            real16(e.young),
            String::new(),
            real16(e.poisson),
            real16(e.density),
        ];
        large_card(out, "MAT1", &f)?;
        small_card(out, "PSOLID", &[id.clone(), id])?;
    }
    Ok(())
}

/// Node sets as SET1 (ids 1, 2, ...) named by `$HMSET <sid> 1 "name"` comments.
fn nastran_sets(out: &mut dyn Write, sets: &[(&String, &Vec<usize>)]) -> io::Result<()> {
    for (k, (name, nodes)) in sets.iter().enumerate() {
        let sid = k + 1;
        let name = one_line(name).replace('"', "'");
        writeln!(out, "$HMSET {sid:>8} {:>8} \"{name}\"", 1)?;
        let mut ids: Vec<usize> = nodes.iter().map(|n| n + 1).collect();
        ids.sort_unstable();
        ids.dedup();
        let mut f = vec![sid.to_string()];
        f.extend(ids.iter().map(|n| n.to_string()));
        small_card(out, "SET1", &f)?;
    }
    Ok(())
}

/// A name on one comment line: control characters become spaces.
fn one_line(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect()
}

/// A small-field card: the name and 8 fields of 8 columns (right-justified) per line,
/// continuation lines starting with `+`.
fn small_card(out: &mut dyn Write, name: &str, fields: &[String]) -> io::Result<()> {
    fixed_card(out, name, "+", 8, 8, fields)
}

/// A large-field card: `NAME*` and 4 fields of 16 columns (left-justified) per line,
/// continuation lines starting with `*`.
fn large_card(out: &mut dyn Write, name: &str, fields: &[String]) -> io::Result<()> {
    fixed_card(out, &format!("{name}*"), "*", 4, 16, fields)
}

/// A fixed-field card of `per_line` fields of `width` columns after an 8-column name field.
fn fixed_card(
    out: &mut dyn Write,
    name: &str,
    cont: &str,
    per_line: usize,
    width: usize,
    fields: &[String],
) -> io::Result<()> {
    if let Some(f) = fields.iter().find(|f| f.len() > width) {
        return Err(invalid(format!(
            "{name}: '{f}' does not fit a field of {width} columns"
        )));
    }
    let mut chunks: Vec<&[String]> = fields.chunks(per_line).collect();
    if chunks.is_empty() {
        chunks.push(&[]);
    }
    for (k, chunk) in chunks.iter().enumerate() {
        let mut line = format!("{:<8}", if k == 0 { name } else { cont });
        for f in chunk.iter() {
            if width == 8 {
                line.push_str(&format!("{f:>8}"));
            } else {
                line.push_str(&format!("{f:<width$}"));
            }
        }
        writeln!(out, "{}", line.trim_end())?;
    }
    Ok(())
}

/// A Nastran real in at most 16 characters with as many significant digits as fit: fixed
/// point (`-12.3456789012345`, `.001234567890123`) or an exponent without its letter
/// (`1.234567890123-5`), whichever is nearer to `v`: at least 13 significant digits for
/// magnitudes from 1e-2 to 1e14 and for positive values from 1e-9 to 1e15, at least 11 for
/// others (a sign and a two-digit exponent take their room).
fn real16(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return "0.0".into();
    }
    let fixed = (0..=15).rev().find_map(|p| fixed_form(v, p));
    let expo = (0..=15).rev().find_map(|p| exp_form(v, p));
    // equally near: fixed point for everyday magnitudes, else the shorter
    let everyday = (1e-3..1e7).contains(&v.abs());
    let best = [fixed, expo].into_iter().flatten().min_by(|a, b| {
        let (ea, eb) = ((a.1 - v).abs(), (b.1 - v).abs());
        let tie = if everyday {
            std::cmp::Ordering::Equal
        } else {
            a.0.len().cmp(&b.0.len())
        };
        ea.total_cmp(&eb).then(tie)
    });
    best.map_or_else(|| format!("{v:.6e}"), |(s, _)| s)
}

/// `v` in fixed point with `p` decimals, trailing zeros dropped, if it fits 16 characters and
/// is not zero: (text, the value it reads as).
fn fixed_form(v: f64, p: usize) -> Option<(String, f64)> {
    let mut s = format!("{v:.p$}");
    if s.contains('.') {
        s.truncate(s.trim_end_matches('0').len());
    } else {
        s.push('.');
    }
    if s.ends_with('.') && s.len() < 16 {
        s.push('0');
    }
    if s.len() > 16 {
        // drop the leading zero of |v| < 1: "-0.123" -> "-.123"
        s = s.replacen("0.", ".", 1);
        if s.len() > 16 || !(s.starts_with('.') || s.starts_with("-.")) {
            return None;
        }
    }
    let x: f64 = s.parse().ok()?;
    (x != 0.0).then_some((s, x))
}

/// `v` as mantissa with `p` decimals and an exponent without its letter (`1.25-5`, `3.+12`),
/// if it fits 16 characters: (text, the value it reads as).
fn exp_form(v: f64, p: usize) -> Option<(String, f64)> {
    let s = format!("{v:.p$e}");
    let (m, e) = s.split_once('e')?;
    let e: i32 = e.parse().ok()?;
    let mut m = m.to_string();
    if m.contains('.') {
        m.truncate(m.trim_end_matches('0').len());
    } else {
        m.push('.');
    }
    let text = format!("{m}{}{}", if e < 0 { '-' } else { '+' }, e.abs());
    let x: f64 = format!("{m}e{e}").parse().ok()?;
    (text.len() <= 16).then_some((text, x))
}

// ---------------------------------------------------------------------------------------
// Abaqus

/// Element sets of an Abaqus part: one per element block (`*ELEMENT, ELSET=`), one per
/// material that has elements (`MAT_<k>`: name, members), the mesh's (when written).
struct AbaqusSets {
    blocks: Vec<String>,
    materials: Vec<(usize, String, Vec<usize>)>,
    mesh: Vec<(String, Vec<usize>)>,
}

/// Writes Abaqus input: heading, the part, an assembly with one instance, the materials.
fn write_abaqus(
    out: &mut dyn Write,
    mesh: &Mesh,
    opts: &WriteOptions,
    part: &str,
) -> io::Result<()> {
    let mats = materials(mesh, opts);
    let names = material_names(&mats);
    let sets = abaqus_sets(mesh, &mats, opts.sets);
    writeln!(
        out,
        "*HEADING\n{part}: mesh written by linercav {}; units: {}",
        env!("CARGO_PKG_VERSION"),
        unit_system(opts.unit)
    )?;
    writeln!(out, "*PART, NAME={part}\n*NODE")?;
    let s = opts.unit.metres();
    for (i, p) in mesh.nodes.iter().enumerate() {
        let [x, y, z] = [p[0] / s, p[1] / s, p[2] / s].map(real_e);
        writeln!(out, "{}, {x}, {y}, {z}", i + 1)?;
    }
    abaqus_elements(out, mesh, &sets.blocks)?;
    if opts.sets {
        abaqus_node_sets(out, mesh)?;
    }
    for (name, members) in &sets.mesh {
        writeln!(out, "*ELSET, ELSET={name}")?;
        write_ids(out, &element_ids(members), false)?;
    }
    for (k, elset, members) in &sets.materials {
        writeln!(out, "*ELSET, ELSET={elset}")?;
        write_ids(out, &element_ids(members), false)?;
        writeln!(
            out,
            "*SOLID SECTION, ELSET={elset}, MATERIAL={}\n,",
            names.get(*k).map_or("", |s| s.as_str())
        )?;
    }
    writeln!(
        out,
        "*END PART\n*ASSEMBLY, NAME=ASSEMBLY\n*INSTANCE, NAME={part}-1, PART={part}\n*END INSTANCE\n*END ASSEMBLY"
    )?;
    for ((_, e), name) in mats.list.iter().zip(&names) {
        writeln!(out, "*MATERIAL, NAME={name}\n*ELASTIC")?;
        writeln!(out, "{}, {}", real_e(e.young), real_e(e.poisson))?;
        writeln!(out, "*DENSITY\n{}", real_e(e.density))?;
    }
    Ok(())
}

/// `*ELEMENT` blocks (ids in the mesh's order from 1), node lists in Abaqus order, at most 16
/// entries a line.
fn abaqus_elements(out: &mut dyn Write, mesh: &Mesh, elsets: &[String]) -> io::Result<()> {
    let mut id = 0;
    for (blk, elset) in mesh.blocks.iter().zip(elsets) {
        writeln!(
            out,
            "*ELEMENT, TYPE={}, ELSET={elset}",
            abaqus_type(blk.kind)
        )?;
        let edges = deck_edges(blk.kind, &HEX20_ABAQUS);
        for e in 0..blk.len() {
            id += 1;
            let mut ids = vec![id];
            ids.extend(
                deck_order(blk.kind, edges, blk.element(e))
                    .iter()
                    .map(|n| n + 1),
            );
            write_ids(out, &ids, true)?;
        }
    }
    Ok(())
}

/// The mesh's non-empty node sets as `*NSET` (names sanitised, unique).
fn abaqus_node_sets(out: &mut dyn Write, mesh: &Mesh) -> io::Result<()> {
    let mut taken = HashSet::new();
    for (name, nodes) in mesh.node_sets.iter().filter(|(_, v)| !v.is_empty()) {
        let name = unique(abaqus_name(name, "SET-"), &mut taken);
        let mut ids: Vec<usize> = nodes.iter().map(|n| n + 1).collect();
        ids.sort_unstable();
        ids.dedup();
        writeln!(out, "*NSET, NSET={name}")?;
        write_ids(out, &ids, false)?;
    }
    Ok(())
}

/// Element ids (1-based, sorted, unique) of global element indices.
fn element_ids(members: &[usize]) -> Vec<usize> {
    let mut ids: Vec<usize> = members.iter().map(|g| g + 1).collect();
    ids.sort_unstable();
    ids.dedup();
    ids
}

/// Ids 16 a line, comma-separated; with `continued`, a line followed by more of the same
/// record ends with a comma (an element's node list).
fn write_ids(out: &mut dyn Write, ids: &[usize], continued: bool) -> io::Result<()> {
    let lines: Vec<&[usize]> = ids.chunks(16).collect();
    for (k, line) in lines.iter().enumerate() {
        let text: Vec<String> = line.iter().map(|i| i.to_string()).collect();
        let more = continued && k + 1 < lines.len();
        writeln!(out, "{}{}", text.join(", "), if more { "," } else { "" })?;
    }
    Ok(())
}

/// The element sets of the part: the blocks' (`SOLID_C3D8` ...), the materials'
/// (`MAT_<k>`, k from 1), then the mesh's (when `with_mesh`) with sanitised unique names; a
/// mesh set equal to one of the former, name and members (a file written here and read
/// back), is not repeated.
fn abaqus_sets(mesh: &Mesh, mats: &Materials, with_mesh: bool) -> AbaqusSets {
    let mut taken = HashSet::new();
    let blocks = mesh
        .blocks
        .iter()
        .map(|b| unique(format!("SOLID_{}", abaqus_type(b.kind)), &mut taken))
        .collect();
    let mut materials = Vec::new();
    for k in 0..mats.list.len() {
        let members: Vec<usize> = (0..mats.of_element.len())
            .filter(|&g| mats.of_element[g] == Some(k))
            .collect();
        if !members.is_empty() {
            let name = unique(format!("MAT_{}", k + 1), &mut taken);
            materials.push((k, name, members));
        }
    }
    let mut out = AbaqusSets {
        blocks,
        materials,
        mesh: Vec::new(),
    };
    if with_mesh {
        for (name, members) in mesh.element_sets.iter().filter(|(_, v)| !v.is_empty()) {
            let clean = abaqus_name(name, "SET-");
            if !out.generated(&clean, members, mesh) {
                out.mesh.push((unique(clean, &mut taken), members.clone()));
            }
        }
    }
    out
}

impl AbaqusSets {
    /// Whether a generated set has `name` (case-insensitive) and the elements `members`.
    fn generated(&self, name: &str, members: &[usize], mesh: &Mesh) -> bool {
        let same = |a: &[usize], b: &[usize]| element_ids(a) == element_ids(b);
        let mut start = 0;
        for (b, n) in mesh.blocks.iter().zip(&self.blocks) {
            let range: Vec<usize> = (start..start + b.len()).collect();
            start += b.len();
            if n.eq_ignore_ascii_case(name) && same(&range, members) {
                return true;
            }
        }
        self.materials
            .iter()
            .any(|(_, n, m)| n.eq_ignore_ascii_case(name) && same(m, members))
    }
}

/// Abaqus names of the materials: sanitised, unique (case-insensitive).
fn material_names(mats: &Materials) -> Vec<String> {
    let mut taken = HashSet::new();
    mats.list
        .iter()
        .map(|(name, _)| unique(abaqus_name(name, "MAT-"), &mut taken))
        .collect()
}

/// The Abaqus element type of a kind (full integration: linercav's own elements).
fn abaqus_type(kind: ElementKind) -> &'static str {
    match kind {
        ElementKind::Tet4 => "C3D4",
        ElementKind::Tet10 => "C3D10",
        ElementKind::Hex8 => "C3D8",
        ElementKind::Hex20 => "C3D20",
    }
}

/// The part's name: the file stem, sanitised (`PART-1` when nothing is left).
fn part_name(path: &Path) -> String {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    abaqus_name(&stem, "PART-")
}

/// An Abaqus label: characters outside [A-Za-z0-9_-] become `_`, `prefix` goes before one
/// that does not start with a letter (`prefix` + `1` for an empty one), at most 72
/// characters (room for a suffix within Abaqus's 80).
fn abaqus_name(raw: &str, prefix: &str) -> String {
    let mut s: String = raw
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() {
        s = "1".into();
    }
    if !s.starts_with(|c: char| c.is_ascii_alphabetic()) {
        s = format!("{prefix}{s}");
    }
    s.truncate(72);
    s
}

/// `name`, or `name-2`, `name-3` ... if taken (Abaqus names are case-insensitive); the
/// result is taken.
fn unique(name: String, taken: &mut HashSet<String>) -> String {
    let mut out = name.clone();
    let mut k = 2;
    while taken.contains(&out.to_ascii_uppercase()) {
        out = format!("{name}-{k}");
        k += 1;
    }
    taken.insert(out.to_ascii_uppercase());
    out
}

/// A real in full precision (the shortest text that reads back exactly), with a decimal
/// point in its mantissa: `1.0e0`, `-2.5e-3`.
fn real_e(v: f64) -> String {
    let s = format!("{v:e}");
    match s.split_once('e') {
        Some((m, e)) if !m.contains('.') => format!("{m}.0e{e}"),
        _ => s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::lattice::{Key, Lattice};
    use crate::mesh::DeckMaterial;

    const KINDS: [ElementKind; 4] = [
        ElementKind::Hex8,
        ElementKind::Hex20,
        ElementKind::Tet4,
        ElementKind::Tet10,
    ];

    fn steel() -> Elastic {
        Elastic {
            young: 2.1e11,
            poisson: 0.3,
            density: 7850.0,
        }
    }

    /// A distorted box of 2 x 2 x 1 cells with negative and positive coordinates, node sets
    /// `x0` and `top`, an element set `half`, two deck materials (names an Abaqus label
    /// cannot hold as they are) and every third element without a material.
    fn box_mesh(kind: ElementKind) -> Mesh {
        let n = [2usize, 2, 1];
        let coord = |k: Key| {
            let s: Vec<f64> = (0..3).map(|a| k[a] as f64 / (2 * n[a]) as f64).collect();
            let w = (3.1 * s[0] + 1.7 * s[1] + 0.9 * s[2]).sin();
            [
                -0.0317 + 0.1 * s[0] + 0.0031 * w,
                0.012_345_678 + 0.07 * s[1] - 0.0027 * w,
                -0.2 + 0.05 * s[2] + 0.0013 * w,
            ]
        };
        let active = |_: usize, _: usize, _: usize| true;
        let lat = Lattice {
            cells: n,
            periodic_j: false,
            active: &active,
            coord: &coord,
        };
        let lm = lat.generate(kind);
        let mut mesh = lm.mesh;
        let on = |a: usize, v: usize| -> Vec<usize> {
            (0..lm.keys.len()).filter(|&i| lm.keys[i][a] == v).collect()
        };
        mesh.node_sets.insert("x0".into(), on(0, 0));
        mesh.node_sets.insert("top".into(), on(2, 2 * n[2]));
        let ne = mesh.num_elements();
        mesh.element_sets
            .insert("half".into(), (0..ne / 2).collect());
        mesh.materials = vec![
            DeckMaterial {
                name: "grey cast iron".into(),
                elastic: Elastic {
                    young: 1.234_567_890_123_4e11,
                    poisson: 0.261_234_567_891_2,
                    density: 7_212.345_678_901,
                },
            },
            DeckMaterial {
                name: "7".into(),
                elastic: steel(),
            },
        ];
        // every element has a material: a deck with MAT1/PSOLID or sections must assign one to
        // each solid (the readers refuse an element left without)
        mesh.element_material = (0..ne).map(|g| (g % 2) as u32).collect();
        mesh
    }

    /// Writes the box of `kind` as `ext` and reads it back: (original, read).
    fn round_trip(kind: ElementKind, ext: &str, opts: &WriteOptions) -> (Mesh, Mesh) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(format!("liner {kind:?}.{ext}"));
        let mesh = box_mesh(kind);
        write_mesh(&path, &mesh, opts).unwrap();
        let back = crate::mesh::read(&path).unwrap_or_else(|e| panic!("{e}"));
        (mesh, back)
    }

    /// Same coordinates (in the file's unit), connectivity and node sets.
    fn check_mesh(orig: &Mesh, back: &Mesh, opts: &WriteOptions, what: &str) {
        let s = opts.unit.metres();
        let size = orig
            .nodes
            .iter()
            .flatten()
            .fold(0.0f64, |m, x| m.max(x.abs()))
            / s;
        assert_eq!(orig.nodes.len(), back.nodes.len(), "{what}");
        for (p, q) in orig.nodes.iter().zip(&back.nodes) {
            for a in 0..3 {
                let x = p[a] / s;
                // 13 significant digits; 12 for negative values below 1e-2 in magnitude
                let tol = 1e-12 * x.abs().max(1e-2 * size);
                assert!((q[a] - x).abs() <= tol, "{what}: {} vs {x}", q[a]);
            }
        }
        assert_eq!(orig.blocks, back.blocks, "{what}: connectivity");
        for (name, nodes) in &orig.node_sets {
            match (opts.sets, back.node_sets.get(name)) {
                (true, Some(got)) => assert_eq!(got, nodes, "{what}: node set {name}"),
                (true, None) => panic!("{what}: node set {name} missing"),
                (false, got) => assert!(got.is_none(), "{what}: node set {name} written"),
            }
        }
    }

    /// Same material constants (in the file's unit system) for every element.
    fn check_materials(orig: &Mesh, back: &Mesh, opts: &WriteOptions, what: &str) {
        let near = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs();
        for g in 0..orig.num_elements() {
            let want = match opts.material {
                Some(e) => Some(e),
                None => match orig.element_material[g] {
                    NO_MATERIAL => None,
                    k => Some(orig.materials[k as usize].elastic),
                },
            };
            let got = match back.element_material.get(g) {
                Some(&k) if k != NO_MATERIAL => Some(back.materials[k as usize].elastic),
                _ => None,
            };
            match (want.map(|e| in_unit(e, opts.unit)), got) {
                (None, None) => {}
                (Some(w), Some(b)) => assert!(
                    near(b.young, w.young)
                        && near(b.poisson, w.poisson)
                        && near(b.density, w.density),
                    "{what}: element {g}: {b:?} vs {w:?}"
                ),
                (w, b) => panic!("{what}: element {g}: {b:?} vs {w:?}"),
            }
        }
    }

    fn option_sets() -> [WriteOptions; 2] {
        [
            WriteOptions {
                unit: MeshUnit::Mm,
                sets: true,
                material: None,
            },
            WriteOptions {
                unit: MeshUnit::M,
                sets: false,
                material: Some(steel()),
            },
        ]
    }

    fn mesh_round_trips(ext: &str) {
        for kind in KINDS {
            for opts in option_sets() {
                let (orig, back) = round_trip(kind, ext, &opts);
                check_mesh(&orig, &back, &opts, &format!("{ext} {kind:?} {opts:?}"));
            }
        }
    }

    fn material_round_trips(ext: &str) {
        for kind in KINDS {
            for opts in option_sets() {
                let (orig, back) = round_trip(kind, ext, &opts);
                check_materials(&orig, &back, &opts, &format!("{ext} {kind:?} {opts:?}"));
            }
        }
    }

    #[test]
    fn msh_round_trip_every_kind() {
        mesh_round_trips("msh");
    }

    #[test]
    fn nastran_round_trip_every_kind() {
        mesh_round_trips("bdf");
        mesh_round_trips("nas");
    }

    #[test]
    fn abaqus_round_trip_every_kind() {
        mesh_round_trips("inp");
        // element sets too (with the block and material sets the reader adds)
        let opts = option_sets()[0];
        let (orig, back) = round_trip(ElementKind::Hex20, "inp", &opts);
        assert_eq!(back.element_sets["half"], orig.element_sets["half"]);
    }

    #[test]
    fn nastran_materials_round_trip() {
        material_round_trips("bdf");
    }

    #[test]
    fn abaqus_materials_round_trip() {
        material_round_trips("inp");
    }

    /// A Nastran real as the readers take it (an exponent sign without its letter).
    fn nastran_real(s: &str) -> f64 {
        let b = s.as_bytes();
        match (1..b.len()).find(|&i| (b[i] == b'+' || b[i] == b'-') && b[i - 1] != b'e') {
            Some(k) => format!("{}e{}", &s[..k], &s[k..]).parse().unwrap(),
            None => s.parse().unwrap(),
        }
    }

    #[test]
    fn sixteen_column_reals_keep_13_digits() {
        let mut x = 1.234_567_890_123_456_7e-9;
        while x < 1e15 {
            for v in [x, -x, x * 9.876_543_210_987, 1.0 / x] {
                let s = real16(v);
                assert!(s.len() <= 16, "{s}");
                let back = nastran_real(&s);
                let a = v.abs();
                let thirteen = (1e-2..1e14).contains(&a) || (v > 0.0 && (1e-9..1e15).contains(&a));
                let digits = if thirteen { 5e-13 } else { 5e-11 };
                assert!((back - v).abs() <= digits * v.abs(), "{v} as {s}");
            }
            x *= 7.3;
        }
        for (v, s) in [
            (0.0, "0.0"),
            (1.0, "1.0"),
            (0.1, "0.1"),
            (-200.0, "-200.0"),
            (2.1e5, "210000.0"),
            (2.1e11, "2.1+11"),
        ] {
            assert_eq!(real16(v), s);
        }
        assert_eq!(real16(7850e-12), "7.85-9");
    }

    /// The lines after the first one starting with `head`.
    fn after<'a>(text: &'a str, head: &str) -> Vec<&'a str> {
        text.lines()
            .skip_while(|l| !l.starts_with(head))
            .take(3)
            .collect()
    }

    #[test]
    fn material_cards_carry_the_constants() {
        let mesh = box_mesh(ElementKind::Tet4);
        let opts = WriteOptions {
            unit: MeshUnit::Mm,
            ..Default::default()
        };
        let want = in_unit(mesh.materials[0].elastic, MeshUnit::Mm);
        let near = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs();
        let mut buf = Vec::new();
        write_nastran(&mut buf, &mesh, &opts).unwrap();
        let text = String::from_utf8(buf).unwrap();
        let card = after(&text, "MAT1*");
        let field =
            |l: &str, k: usize| nastran_real(l[8 + 16 * k..(24 + 16 * k).min(l.len())].trim());
        assert!(near(field(card[0], 1), want.young), "{card:?}");
        assert_eq!(card[0][40..56].trim(), "", "G blank");
        assert!(near(field(card[0], 3), want.poisson), "{card:?}");
        assert!(near(field(card[1], 0), want.density), "{card:?}");
        assert_eq!(
            card[2].split_whitespace().collect::<Vec<_>>(),
            ["PSOLID", "1", "1"]
        );
        assert!(text.contains("$HMSET        1        1 \"top\""), "{text}");
        assert!(text.starts_with("BEGIN BULK\n") && text.ends_with("ENDDATA\n"));

        let mut buf = Vec::new();
        write_abaqus(&mut buf, &mesh, &opts, "liner").unwrap();
        let text = String::from_utf8(buf).unwrap();
        let el: Vec<f64> = after(&text, "*ELASTIC")[1]
            .split(',')
            .map(|f| f.trim().parse().unwrap())
            .collect();
        assert!(
            near(el[0], want.young) && near(el[1], want.poisson),
            "{el:?}"
        );
        let rho: f64 = after(&text, "*DENSITY")[1].parse().unwrap();
        assert!(near(rho, want.density));
        for l in [
            "*MATERIAL, NAME=grey_cast_iron",
            "*MATERIAL, NAME=MAT-7",
            "*SOLID SECTION, ELSET=MAT_1, MATERIAL=grey_cast_iron",
            "*SOLID SECTION, ELSET=MAT_2, MATERIAL=MAT-7",
            "*INSTANCE, NAME=liner-1, PART=liner",
        ] {
            assert!(text.contains(l), "{l} in {text}");
        }
    }

    #[test]
    fn long_element_records_continue_on_the_next_line() {
        let mesh = box_mesh(ElementKind::Hex20);
        let mut buf = Vec::new();
        write_abaqus(&mut buf, &mesh, &WriteOptions::default(), "p").unwrap();
        let text = String::from_utf8(buf).unwrap();
        let lines = after(&text, "*ELEMENT, TYPE=C3D20");
        assert_eq!(lines[1].split(',').count(), 17, "16 entries and a comma");
        assert_eq!(lines[2].split(',').count(), 5);
        let mut buf = Vec::new();
        write_nastran(&mut buf, &mesh, &WriteOptions::default()).unwrap();
        let text = String::from_utf8(buf).unwrap();
        let lines = after(&text, "CHEXA");
        assert!(lines.iter().all(|l| l.len() <= 72), "{lines:?}");
        assert!(lines[1].starts_with('+') && lines[2].starts_with('+'));
    }

    #[test]
    fn formats_by_extension_and_names_for_abaqus() {
        for (p, f) in [
            ("a.msh", Some(DeckFormat::Msh)),
            ("a.BDF", Some(DeckFormat::Nastran)),
            ("d/a.nas", Some(DeckFormat::Nastran)),
            ("a.inp", Some(DeckFormat::Abaqus)),
            ("a.vtk", None),
            ("a", None),
        ] {
            assert_eq!(DeckFormat::of_path(Path::new(p)), f, "{p}");
        }
        let dir = tempfile::tempdir().unwrap();
        let e = write_mesh(
            &dir.path().join("a.vtk"),
            &box_mesh(ElementKind::Tet4),
            &WriteOptions::default(),
        )
        .unwrap_err();
        assert_eq!(e.source.kind(), io::ErrorKind::InvalidInput);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        assert_eq!(part_name(Path::new("out/liner 2.inp")), "liner_2");
        assert_eq!(part_name(Path::new("3d.inp")), "PART-3d");
        let mut taken = HashSet::new();
        assert_eq!(unique("A".into(), &mut taken), "A");
        assert_eq!(unique("a".into(), &mut taken), "a-2");
        assert_eq!(real_e(1.0), "1.0e0");
        assert_eq!(real_e(-2.5e-3), "-2.5e-3");
    }
}
