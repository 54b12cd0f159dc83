//! Meshes: nodes, solid elements by kind, and named node sets.
//!
//! Coordinates are metres. Parametric generators (`liner`) and the importers of Gmsh MSH 4.1
//! (`gmsh`), Nastran bulk data (`nastran`) and Abaqus input (`abaqus`) all produce a [`Mesh`];
//! `checks` validates it before any matrix is built.

pub mod abaqus;
pub mod checks;
pub(crate) mod collect;
pub mod crankcase;
pub mod element;
pub mod find;
pub mod gmsh;
pub mod import;
pub mod lattice;
pub mod liner;
pub mod merge;
pub mod nastran;
pub mod write;

use crate::scene::spec::ElementKind;
pub use crate::scene::spec::MeshUnit;
use std::collections::BTreeMap;

/// Reads a mesh file by its extension: `.msh` (Gmsh MSH 4.1), `.bdf` / `.nas` (Nastran bulk
/// data), `.inp` (Abaqus input).
pub fn read(path: &std::path::Path) -> Result<Mesh, collect::DeckError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    match ext.as_deref() {
        Some("msh") => gmsh::read(path),
        Some("bdf") | Some("nas") => nastran::read(path),
        Some("inp") => abaqus::read(path),
        _ => Err(collect::DeckError {
            path: path.to_path_buf(),
            line: 0,
            msg: "unknown mesh format: expected .msh (Gmsh MSH 4.1), .bdf or .nas (Nastran bulk data) or .inp (Abaqus input)".into(),
        }),
    }
}

/// A mesh file and every file it includes (Nastran `INCLUDE`, Abaqus `*INCLUDE`), nested, each
/// once (by its canonical path: `d/../a.inp` is `a.inp`), in the order found: what a cache key
/// must hash. At most `DECK_FILES` (4096) files and [`crate::files::LIMIT_MESH`] bytes are scanned;
/// unreadable includes, cycles and deep nesting are left to the reader to report.
pub fn deck_files(path: &std::path::Path) -> Vec<std::path::PathBuf> {
    let canonical = |p: &std::path::Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.into());
    let mut out = vec![path.to_path_buf()];
    let mut seen = std::collections::HashSet::from([canonical(path)]);
    let mut bytes = 0u64;
    let mut k = 0;
    while k < out.len() && out.len() < DECK_FILES && bytes <= crate::files::LIMIT_MESH {
        let p = out[k].clone();
        k += 1;
        let Ok(text) = crate::files::read_text(&p, crate::files::LIMIT_MESH) else {
            continue;
        };
        bytes += text.len() as u64;
        let dir = p.parent().unwrap_or(std::path::Path::new("."));
        for inc in include_names(&text) {
            let q = dir.join(inc);
            if out.len() < DECK_FILES && seen.insert(canonical(&q)) {
                out.push(q);
            }
        }
    }
    out
}

/// Files a deck may read with its includes (each include counted): a reader refuses a deck
/// with more, so [`deck_files`] lists every file of a deck it reads.
pub(crate) const DECK_FILES: usize = 4096;

/// File names a deck's text reads beside itself: Nastran `INCLUDE 'name'` (a quoted name may
/// go on over lines) or `INCLUDE name` in the bulk data (after `BEGIN BULK` when the file has
/// one, before `ENDDATA`: the reader skips the executive and case control sections), and the
/// `INPUT=name` parameter of any Abaqus keyword line (`*INCLUDE`, `*NODE`, `*ELEMENT`, ...;
/// spaces around `=` allowed, the name quoted or not).
fn include_names(text: &str) -> Vec<String> {
    let mut names = Vec::new();
    let bulk_start = text.lines().position(|l| {
        l.trim_start()
            .to_ascii_uppercase()
            .starts_with("BEGIN BULK")
    });
    let mut lines = text.lines().skip(bulk_start.map_or(0, |k| k + 1));
    while let Some(l) = lines.next() {
        let t = l.trim_start();
        let up = t.to_ascii_uppercase();
        if up.starts_with("ENDDATA") {
            break;
        }
        if t.starts_with('*') && !t.starts_with("**") {
            names.extend(abaqus_input(t));
        } else if up.starts_with("INCLUDE") {
            names.extend(nastran_include(t, &mut lines));
        }
    }
    names
}

/// The `INPUT=` parameter of an Abaqus keyword line, if any.
fn abaqus_input(line: &str) -> Option<String> {
    line.split(',').skip(1).find_map(|param| {
        let (key, value) = param.split_once('=')?;
        key.trim().eq_ignore_ascii_case("INPUT").then(|| {
            let v = value.trim();
            v.trim_matches('"').trim_matches('\'').to_string()
        })
    })
}

/// The file name of a Nastran `INCLUDE` line `line` (a quoted name may go on over the next
/// of `lines`).
fn nastran_include<'a>(line: &str, lines: &mut impl Iterator<Item = &'a str>) -> Option<String> {
    let rest = line[7..].trim();
    if let Some(q) = rest.strip_prefix('\'') {
        let mut name = String::new();
        let mut part = q.to_string();
        loop {
            if let Some(end) = part.find('\'') {
                name.push_str(part[..end].trim());
                break;
            }
            name.push_str(part.trim());
            match lines.next() {
                Some(n) => part = n.to_string(),
                None => break,
            }
        }
        Some(name)
    } else {
        rest.split_whitespace().next().map(str::to_string)
    }
}

/// A block of elements of one kind, connectivity flattened (`kind.num_nodes()` per element).
#[derive(Clone, Debug, PartialEq)]
pub struct ElementBlock {
    pub kind: ElementKind,
    pub conn: Vec<usize>,
}

impl ElementBlock {
    pub fn len(&self) -> usize {
        self.conn.len() / self.kind.num_nodes()
    }
    pub fn is_empty(&self) -> bool {
        self.conn.is_empty()
    }
    /// Node indices of element `e`.
    pub fn element(&self, e: usize) -> &[usize] {
        let nn = self.kind.num_nodes();
        &self.conn[e * nn..(e + 1) * nn]
    }
}

/// A solid mesh with named node sets (physical groups, interfaces, analysis points).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub nodes: Vec<[f64; 3]>,
    pub blocks: Vec<ElementBlock>,
    pub node_sets: BTreeMap<String, Vec<usize>>,
    /// Named element sets (volume physical groups), as global element indices in block order.
    pub element_sets: BTreeMap<String, Vec<usize>>,
    /// Materials a deck defines (Nastran MAT1 through PSOLID, Abaqus *MATERIAL through *SOLID
    /// SECTION), SI once [`Mesh::to_si`] has run; empty for meshes without materials.
    pub materials: Vec<DeckMaterial>,
    /// Index into `materials` of every element (global index in block order), or
    /// [`NO_MATERIAL`]; empty when `materials` is.
    pub element_material: Vec<u32>,
    /// Where each element was defined in the file(s) read, for messages; `None` for a
    /// generated mesh.
    pub element_lines: Option<ElementLines>,
}

/// The file and line of every element of a mesh read from files.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ElementLines {
    /// The files read, the main file first.
    pub files: Vec<std::path::PathBuf>,
    /// Per element (global index in block order): index into `files` and 1-based line.
    pub at: Vec<(u32, u32)>,
    /// The files' length unit (set by [`Mesh::to_si`]): messages give coordinates in it.
    pub unit: MeshUnit,
    /// What placed an element defined once for several bodies (an Abaqus part's instance):
    /// the labels, and per element an index into them (`u32::MAX`: none); `scope` is empty
    /// when the files place nothing so.
    pub scopes: Vec<String>,
    pub scope: Vec<u32>,
}

/// An element of a deck that no section or property gives a material.
pub const NO_MATERIAL: u32 = u32::MAX;

/// A material of a deck: its name there (`MAT1 3`, `*MATERIAL, NAME=steel`) and its constants.
#[derive(Clone, Debug, PartialEq)]
pub struct DeckMaterial {
    pub name: String,
    pub elastic: crate::scene::spec::Elastic,
}

impl Mesh {
    /// Converts a mesh read in `unit` to SI: x_SI = s x with s the metres per unit; in the
    /// mm-t-s system E_SI = 1e6 E (MPa -> Pa) and rho_SI = 1e12 rho (t/mm^3 -> kg/m^3).
    pub fn to_si(&mut self, unit: MeshUnit) {
        if let Some(l) = &mut self.element_lines {
            l.unit = unit;
        }
        if unit == MeshUnit::M {
            return;
        }
        let s = unit.metres();
        for p in &mut self.nodes {
            for x in p.iter_mut() {
                *x *= s;
            }
        }
        for m in &mut self.materials {
            m.elastic.young *= 1e6;
            m.elastic.density *= 1e12;
        }
    }
    /// Replaces a deck's materials by one given material (the scene's `material` key or the
    /// `--youngs/--poisson/--density` flags win over the deck).
    pub fn clear_materials(&mut self) {
        self.materials.clear();
        self.element_material.clear();
    }
    /// The material of element `e` (global index): the deck's, else `fallback`.
    pub fn material_of<'a>(
        &'a self,
        e: usize,
        fallback: &'a crate::scene::spec::Elastic,
    ) -> &'a crate::scene::spec::Elastic {
        match self.element_material.get(e) {
            Some(&k) if k != NO_MATERIAL => &self.materials[k as usize].elastic,
            _ => fallback,
        }
    }
    /// How messages name element `e` (global index in block order): the file and line that
    /// define it when the mesh was read from files, else its place among the solid elements.
    pub fn element_name(&self, e: usize) -> String {
        let place = self
            .element_lines
            .as_ref()
            .and_then(|l| Some((l.at.get(e)?, l)));
        match place {
            Some((&(f, line), l)) => {
                let within = l
                    .scope
                    .get(e)
                    .and_then(|&k| l.scopes.get(k as usize))
                    .map_or(String::new(), |s| format!(" ({s})"));
                match l.files.get(f as usize) {
                    Some(file) => format!("defined at {}:{line}{within}", file.display()),
                    None => format!("defined on line {line}{within}"),
                }
            }
            None => format!(
                "#{} (1-based, in the order of the mesh's solid elements)",
                e + 1
            ),
        }
    }
    /// How messages name node `n`: its place in the mesh for a generated mesh, its
    /// coordinates in the files' unit for a mesh read from files (whose node ids may be
    /// renumbered, as an Abaqus instance's are).
    pub fn node_name(&self, n: usize) -> String {
        match (&self.element_lines, self.nodes.get(n)) {
            (Some(l), Some(x)) => {
                let (s, name) = match l.unit {
                    MeshUnit::M => (1.0, "m"),
                    MeshUnit::Mm => (1e3, "mm"),
                };
                let [a, b, c] = x.map(|v| v * s);
                format!("the node at ({a:.6}, {b:.6}, {c:.6}) {name}")
            }
            _ => format!("the mesh's node #{}", n + 1),
        }
    }
    /// The first element (global index) without a deck material, if the deck has materials.
    pub fn element_without_material(&self) -> Option<usize> {
        self.element_material.iter().position(|&k| k == NO_MATERIAL)
    }
    /// Axis-aligned bounding box (min, max) of the nodes.
    pub fn bounding_box(&self) -> ([f64; 3], [f64; 3]) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &self.nodes {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        (lo, hi)
    }
    pub fn num_elements(&self) -> usize {
        self.blocks.iter().map(|b| b.len()).sum()
    }
    /// Iterates over (kind, node indices) of every element.
    pub fn elements(&self) -> impl Iterator<Item = (ElementKind, &[usize])> + '_ {
        self.blocks
            .iter()
            .flat_map(|b| (0..b.len()).map(move |e| (b.kind, b.element(e))))
    }
    /// Coordinates of the nodes of one element.
    pub fn coords_of(&self, nodes: &[usize]) -> Vec<[f64; 3]> {
        nodes.iter().map(|&n| self.nodes[n]).collect()
    }
    /// Looks up a named node set.
    pub fn node_set(&self, name: &str) -> Option<&[usize]> {
        self.node_sets.get(name).map(|v| v.as_slice())
    }
    /// Names of all node sets (for error messages).
    pub fn set_names(&self) -> Vec<String> {
        self.node_sets.keys().cloned().collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Regression: the scan of a deck's files (before any reading, for the cache key) told
    /// files apart by the path as written, so `*INCLUDE, INPUT=d/../a.inp` in `a.inp` read
    /// `a.inp` again under a longer name until 4096 names (1,600 opens, 6.6 s), and compared
    /// each new name with every listed one (5,000 includes: 88 s); names now go through
    /// their canonical path into a set.
    #[test]
    fn regression_deck_files_follow_canonical_paths_once() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("d")).unwrap();
        let a = dir.path().join("a.inp");
        let b = dir.path().join("b.inp");
        std::fs::write(&a, "*INCLUDE, INPUT=d/../a.inp\n*INCLUDE, INPUT=b.inp\n").unwrap();
        std::fs::write(&b, "*INCLUDE, INPUT=./d/../b.inp\n*INCLUDE, INPUT=a.inp\n").unwrap();
        assert_eq!(deck_files(&a), vec![a.clone(), b]);
        // many distinct missing names: each listed once, quickly
        let many: String = (0..20_000)
            .map(|k| format!("*INCLUDE, INPUT=p{k}/missing.inp\n"))
            .collect();
        std::fs::write(&a, many).unwrap();
        assert_eq!(deck_files(&a).len(), DECK_FILES);
    }

    /// Regression: the files a deck reads (the cache key and a study's digest hash them) missed
    /// an Abaqus data file given as `*NODE, INPUT=` or `*ELEMENT, INPUT=` and an `INPUT = name`
    /// with spaces, so an edited node file left a cached ROM in use; and they followed a
    /// Nastran INCLUDE of the executive or case control section, which the reader skips.
    #[test]
    fn regression_include_names_are_the_files_the_readers_read() {
        let abaqus = "*HEADING\n*NODE, INPUT = nodes.txt\n** *INCLUDE, INPUT=commented.inp\n\
                      *ELEMENT, TYPE=C3D4, ELSET=A, INPUT=\"elements.inp\"\n*include,input=more.inp\n";
        assert_eq!(
            include_names(abaqus),
            vec!["nodes.txt", "elements.inp", "more.inp"]
        );
        let nastran = "SOL 103\nINCLUDE 'case.dat'\nCEND\nBEGIN BULK\nINCLUDE 'grids.bdf'\n\
                       INCLUDE 'a\n long/name.bdf'\nENDDATA\nINCLUDE 'after.bdf'\n";
        assert_eq!(include_names(nastran), vec!["grids.bdf", "along/name.bdf"]);
        // a file without BEGIN BULK (an included one) is bulk data throughout
        assert_eq!(include_names("INCLUDE inner.bdf\n"), vec!["inner.bdf"]);
    }
}
