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
pub mod gmsh;
pub mod lattice;
pub mod liner;
pub mod merge;
pub mod nastran;

pub use element::ElementKind;
use std::collections::BTreeMap;

/// Reads a mesh file by its extension: `.msh` (Gmsh MSH 4.1), `.bdf` / `.nas` (Nastran bulk
/// data), `.inp` (Abaqus input).
pub fn read(path: &std::path::Path) -> Result<Mesh, collect::MshError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    match ext.as_deref() {
        Some("msh") => gmsh::read(path),
        Some("bdf") | Some("nas") => nastran::read(path),
        Some("inp") => abaqus::read(path),
        _ => Err(collect::MshError {
            path: path.to_path_buf(),
            line: 0,
            msg: "unknown mesh format: expected .msh (Gmsh MSH 4.1), .bdf or .nas (Nastran bulk data) or .inp (Abaqus input)".into(),
        }),
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
}

impl Mesh {
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
