//! What the Nastran and Abaqus readers collect from an input deck, with the deck's own node
//! and element ids, and its assembly into a [`Mesh`] (ids to indices, element node order to
//! ours, sets to node and element sets).

use super::{DeckMaterial, ElementBlock, ElementLines, Mesh, NO_MATERIAL};

use crate::scene::spec::ElementKind;

/// Why a mesh file could not be read: the file, the line and what was expected.
#[derive(Debug, thiserror::Error)]
#[error("{}{}: {msg}", path.display(), if *line > 0 { format!(":{line}") } else { String::new() })]
pub struct DeckError {
    pub path: PathBuf,
    pub line: usize,
    pub msg: String,
}
use crate::files::{read_text_within, ReadError, LIMIT_MESH};
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};

/// A file index or line number as stored per element (saturating at u32::MAX: a deck's
/// size is bounded far below).
pub(crate) fn small(v: usize) -> u32 {
    u32::try_from(v).unwrap_or(u32::MAX)
}

/// Where a record of a deck came from: an index into [`Collected::files`] and a 1-based line.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Loc {
    pub file: usize,
    pub line: usize,
}

impl Loc {
    /// A line of the main file.
    pub fn main(line: usize) -> Self {
        Loc { file: 0, line }
    }
}

/// A deck's contents by id, each record with the file and line it came from (for messages).
/// Coordinates are in the basic (rectangular, global) system of the deck, in the deck's unit;
/// material constants in the deck's unit system.
#[derive(Default)]
pub(crate) struct Collected {
    /// The main file first, then every included file in the order first read.
    pub files: Vec<PathBuf>,
    pub nodes: Vec<(i64, [f64; 3], Loc)>,
    /// (element id, kind, node ids in our order, where)
    pub elements: Vec<(i64, ElementKind, Vec<i64>, Loc)>,
    /// name -> (node ids, where the set's first record is)
    pub node_sets: BTreeMap<String, (Vec<i64>, Loc)>,
    pub element_sets: BTreeMap<String, (Vec<i64>, Loc)>,
    /// Materials by name (`MAT1 <id>`, an Abaqus material's name): constants and definition.
    pub materials: BTreeMap<String, (crate::scene::spec::Elastic, Loc)>,
    /// Element id -> (material name, where the assignment was made: PSOLID, *SOLID SECTION).
    pub element_material: HashMap<i64, (String, Loc)>,
    /// What placed an element defined once for several bodies (an Abaqus part's instances):
    /// the labels, and element id -> index into them (empty for a flat deck).
    pub scopes: Vec<String>,
    pub element_scope: HashMap<i64, u32>,
}

/// Reorders a quadratic element's nodes from a deck's edge convention to ours: the corners
/// keep their places, the mid-edge node of edge (a, b) moves to where our
/// [`ElementKind::mid_edges`] has that edge.
pub(crate) fn reorder(kind: ElementKind, theirs: &[(usize, usize)], ids: &[i64]) -> Vec<i64> {
    let nc = kind.num_corners();
    let mut out = ids.to_vec();
    for (i, &(a, b)) in theirs.iter().enumerate() {
        let j = kind
            .mid_edges()
            .iter()
            .position(|&(p, q)| (p, q) == (a, b) || (p, q) == (b, a))
            .expect("the same edges in both conventions");
        out[nc + j] = ids[nc + i];
    }
    out
}

/// Mid-edge nodes of 10-node tetrahedra in Nastran (CTETRA) and Abaqus (C3D10): edges
/// 1-2, 2-3, 3-1, 1-4, 2-4, 3-4 (0-based here).
pub(crate) const TET10_DECK: [(usize, usize); 6] = [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)];
/// Abaqus C3D20(R): bottom edges, top edges, then the vertical ones.
pub(crate) const HEX20_ABAQUS: [(usize, usize); 12] = [
    (0, 1),
    (1, 2),
    (2, 3),
    (3, 0),
    (4, 5),
    (5, 6),
    (6, 7),
    (7, 4),
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7),
];
/// Nastran CHEXA with 20 nodes: bottom edges, the vertical ones, then the top edges.
pub(crate) const HEX20_NASTRAN: [(usize, usize); 12] = [
    (0, 1),
    (1, 2),
    (2, 3),
    (3, 0),
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7),
    (4, 5),
    (5, 6),
    (6, 7),
    (7, 4),
];

/// Memory a mesh file's reading takes per byte of its text: the text and the mesh made of it
/// (a node's coordinates and an element's node list take about as many bytes as their
/// text), with the readers' sets and maps beside them. A file that does not fit so is refused
/// before it is read (a 2 GB deck aborted in its allocation under a 1 GB cap).
const MESH_TEXT_FACTOR: u64 = 3;

/// The text of mesh file `path` (a regular file of at most [`LIMIT_MESH`] bytes, whose reading
/// the machine can hold: [`MESH_TEXT_FACTOR`]); a byte that is not text is reported with its
/// line and `expected` (what the reader takes).
pub(crate) fn read_mesh_text(path: &Path, expected: &str) -> Result<String, DeckError> {
    read_text_within(path, LIMIT_MESH, MESH_TEXT_FACTOR).map_err(|e| {
        let (line, msg) = match e {
            ReadError::NotText { line, byte } => {
                (line, format!("byte 0x{byte:02x} is not text: {expected}"))
            }
            other => (0, other.to_string()),
        };
        err(path, line, msg)
    })
}

fn err(path: &Path, line: usize, msg: String) -> DeckError {
    DeckError {
        path: path.to_path_buf(),
        line,
        msg,
    }
}

impl Collected {
    /// A collection whose main file is `path`.
    pub fn new(path: &Path) -> Self {
        Collected {
            files: vec![path.to_path_buf()],
            ..Default::default()
        }
    }

    /// An error at `loc`.
    pub fn err_at(&self, loc: Loc, msg: String) -> DeckError {
        err(
            &self.files[loc.file.min(self.files.len() - 1)],
            loc.line,
            msg,
        )
    }

    /// The file's node sets and element sets on `mesh` (`index`, `element_index`: mesh index
    /// of each node and solid element id); an element set without a node set of its name
    /// also gives its elements' nodes as one.
    fn assign_sets(
        &self,
        mesh: &mut Mesh,
        index: &HashMap<i64, usize>,
        element_index: &HashMap<i64, usize>,
    ) -> Result<(), DeckError> {
        let at = |loc: Loc, msg: String| self.err_at(loc, msg);
        let node = |id: i64, loc: Loc, what: &str| {
            index.get(&id).copied().ok_or_else(|| {
                at(
                    loc,
                    format!("{what} refers to node {id}, which is not defined"),
                )
            })
        };
        for (name, (ids, line)) in &self.node_sets {
            let set: BTreeSet<usize> = ids
                .iter()
                .map(|&n| node(n, *line, &format!("node set '{name}'")))
                .collect::<Result<_, _>>()?;
            mesh.node_sets
                .insert(name.clone(), set.into_iter().collect());
        }
        for (name, (ids, line)) in &self.element_sets {
            let mut elements = Vec::with_capacity(ids.len());
            for e in ids {
                let Some(&g) = element_index.get(e) else {
                    return Err(at(
                        *line,
                        format!("element set '{name}' refers to element {e}, which is not a solid element of the file"),
                    ));
                };
                elements.push(g);
            }
            elements.sort_unstable();
            elements.dedup();
            if !mesh.node_sets.contains_key(name) {
                let nodes: BTreeSet<usize> = mesh
                    .elements()
                    .enumerate()
                    .filter(|(g, _)| elements.binary_search(g).is_ok())
                    .flat_map(|(_, (_, c))| c.iter().copied())
                    .collect();
                mesh.node_sets
                    .insert(name.clone(), nodes.into_iter().collect());
            }
            mesh.element_sets.insert(name.clone(), elements);
        }
        Ok(())
    }

    /// The mesh: nodes in deck order, elements grouped by kind (in deck order within a kind),
    /// node sets as given, element sets as element indices, and each element set also as the
    /// node set of its elements' nodes unless a node set has its name.
    pub fn into_mesh(self) -> Result<Mesh, DeckError> {
        if self.files.is_empty() {
            return Err(err(Path::new("?"), 0, "no file was read".into()));
        }
        let at = |loc: Loc, msg: String| self.err_at(loc, msg);
        if self.nodes.is_empty() || self.elements.is_empty() {
            return Err(at(
                Loc::main(0),
                "no nodes or no solid elements (expected nodes and 4/10-node tetrahedra or 8/20-node hexahedra)".into(),
            ));
        }
        let mut index: HashMap<i64, usize> = HashMap::with_capacity(self.nodes.len());
        let mut nodes = Vec::with_capacity(self.nodes.len());
        for &(id, x, loc) in &self.nodes {
            if id <= 0 {
                return Err(at(
                    loc,
                    format!("node id {id}: ids must be positive integers"),
                ));
            }
            if index.insert(id, nodes.len()).is_some() {
                return Err(at(loc, format!("node {id} defined twice")));
            }
            nodes.push(x);
        }
        let node = |id: i64, loc: Loc, what: &str| {
            index.get(&id).copied().ok_or_else(|| {
                at(
                    loc,
                    format!("{what} refers to node {id}, which is not defined"),
                )
            })
        };
        let mut by_kind: BTreeMap<ElementKind, Vec<(i64, Vec<usize>, Loc)>> = BTreeMap::new();
        let mut seen = HashMap::new();
        for (eid, kind, ids, line) in &self.elements {
            if *eid <= 0 {
                return Err(at(
                    *line,
                    format!("element id {eid}: ids must be positive integers"),
                ));
            }
            if seen.insert(*eid, *line).is_some() {
                return Err(at(*line, format!("element {eid} defined twice")));
            }
            let conn = ids
                .iter()
                .map(|&n| node(n, *line, &format!("element {eid}")))
                .collect::<Result<Vec<_>, _>>()?;
            by_kind.entry(*kind).or_default().push((*eid, conn, *line));
        }
        // global element index of each element id (blocks in kind order)
        let mut element_index: HashMap<i64, usize> = HashMap::new();
        let mut blocks = Vec::new();
        let mut lines = Vec::with_capacity(self.elements.len());
        let mut scope = Vec::new();
        let mut acc = 0;
        for (kind, list) in by_kind {
            let mut conn = Vec::with_capacity(list.len() * kind.num_nodes());
            for (eid, c, loc) in list {
                element_index.insert(eid, acc);
                acc += 1;
                conn.extend(c);
                lines.push((small(loc.file), small(loc.line)));
                if !self.scopes.is_empty() {
                    scope.push(self.element_scope.get(&eid).copied().unwrap_or(u32::MAX));
                }
            }
            blocks.push(ElementBlock { kind, conn });
        }
        let mut mesh = Mesh {
            nodes,
            blocks,
            element_lines: Some(ElementLines {
                files: self.files.clone(),
                at: lines,
                unit: super::MeshUnit::M,
                scopes: self.scopes.clone(),
                scope,
            }),
            ..Default::default()
        };
        self.assign_materials(&mut mesh, &element_index)?;
        self.assign_sets(&mut mesh, &index, &element_index)?;
        Ok(mesh)
    }

    /// The deck's materials as a table and each element's index into it ([`NO_MATERIAL`] for
    /// an element no property or section reaches); nothing when the deck defines none.
    fn assign_materials(
        &self,
        mesh: &mut Mesh,
        element_index: &HashMap<i64, usize>,
    ) -> Result<(), DeckError> {
        if self.materials.is_empty() && self.element_material.is_empty() {
            return Ok(());
        }
        let names: Vec<&String> = self.materials.keys().collect();
        mesh.materials = self
            .materials
            .iter()
            .map(|(name, (elastic, _))| DeckMaterial {
                name: name.clone(),
                elastic: *elastic,
            })
            .collect();
        mesh.element_material = vec![NO_MATERIAL; mesh.num_elements()];
        for (eid, (name, loc)) in &self.element_material {
            let Some(&g) = element_index.get(eid) else {
                continue; // a property of an element that is not a solid of the file
            };
            let k = names.binary_search(&name).map_err(|_| {
                self.err_at(
                    *loc,
                    format!(
                        "material '{name}' is not defined (the deck defines: {})",
                        if names.is_empty() {
                            "none".to_string()
                        } else {
                            names
                                .iter()
                                .map(|s| s.as_str())
                                .collect::<Vec<_>>()
                                .join(", ")
                        }
                    ),
                )
            })?;
            mesh.element_material[g] = k as u32;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reordering_maps_each_mid_edge_node_to_our_edge() {
        // label every mid node by its edge in the deck's convention; after reordering, our
        // position j must hold the node of our edge j
        for (kind, theirs) in [
            (ElementKind::Tet10, &TET10_DECK[..]),
            (ElementKind::Hex20, &HEX20_ABAQUS[..]),
            (ElementKind::Hex20, &HEX20_NASTRAN[..]),
        ] {
            let nc = kind.num_corners();
            let code = |(a, b): (usize, usize)| (100 * a.min(b) + b.max(a)) as i64;
            let ids: Vec<i64> = (0..nc as i64)
                .chain(theirs.iter().map(|&e| 1000 + code(e)))
                .collect();
            let ours = reorder(kind, theirs, &ids);
            for (j, &e) in kind.mid_edges().iter().enumerate() {
                assert_eq!(ours[nc + j], 1000 + code(e));
            }
            assert_eq!(&ours[..nc], &ids[..nc]);
        }
    }
}
