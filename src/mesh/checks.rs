//! Mesh checks run before assembly: inverted or degenerate elements and misplaced mid-edge
//! nodes are errors; unused nodes are removed with a warning (they would make K and M
//! singular); disconnected pieces are reported as a warning (each adds six rigid-body modes).

use super::Mesh;
use crate::scene::spec::ElementKind;

/// A mesh defect that makes the model unusable.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    #[error("solid element {element} ({kind}) is inverted or degenerate: smallest Jacobian {ratio:.3e} of its mean size (must be > 0; negative: the corner nodes are ordered the wrong way round)")]
    Inverted {
        element: String,
        kind: String,
        ratio: f64,
    },
    #[error("solid element {element} ({kind}): its mid-edge node ({node}) lies {offset:.2} edge lengths from the midpoint of its edge (wrong node order or badly curved edge)")]
    MidNode {
        element: String,
        kind: String,
        node: String,
        offset: f64,
    },
    #[error("solid element {element} ({kind}) is degenerate: {what}")]
    Degenerate {
        element: String,
        kind: String,
        what: String,
    },
    #[error("the mesh has no solid elements")]
    Empty,
}

/// Non-fatal findings.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CheckReport {
    pub warnings: Vec<String>,
    pub pieces: usize,
    pub removed_nodes: usize,
}

fn find(parent: &mut [usize], mut x: usize) -> usize {
    while parent[x] != x {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    x
}

/// The mesh's connected pieces (elements joined through shared nodes): the number of
/// elements of each, largest first.
pub fn piece_sizes(mesh: &Mesh) -> Vec<usize> {
    let mut parent: Vec<usize> = (0..mesh.nodes.len()).collect();
    for (_, nodes) in mesh.elements() {
        let r0 = find(&mut parent, nodes[0]);
        for &n in &nodes[1..] {
            let r = find(&mut parent, n);
            if r != r0 {
                parent[r] = r0;
            }
        }
    }
    let mut count = std::collections::BTreeMap::new();
    for (_, nodes) in mesh.elements() {
        *count.entry(find(&mut parent, nodes[0])).or_insert(0usize) += 1;
    }
    let mut sizes: Vec<usize> = count.into_values().collect();
    sizes.sort_unstable_by(|a, b| b.cmp(a));
    sizes
}

/// Smallest Jacobian determinant of an element relative to its mean (the FE stage's
/// `fem::element::min_jacobian_ratio`, which knows the shape functions).
pub type JacobianRatio = fn(ElementKind, &[[f64; 3]]) -> f64;

/// Checks the mesh and compacts away unused nodes (renumbering elements and sets);
/// `min_jacobian_ratio` rates each element's shape (use `fem::element::check_mesh`).
pub fn check_and_compact(
    mesh: &mut Mesh,
    min_jacobian_ratio: JacobianRatio,
) -> Result<CheckReport, MeshError> {
    if mesh.num_elements() == 0 {
        return Err(MeshError::Empty);
    }
    let mut report = CheckReport::default();
    // the first bad element in the files' order (the mesh's own groups the kinds) for a mesh
    // read from files, else the first in the mesh
    let mut first: Option<((u32, u32), usize, ElementKind, Flaw)> = None;
    for (e, (kind, nodes)) in mesh.elements().enumerate() {
        if let Err(f) = check_element((kind, nodes), &mesh.coords_of(nodes), min_jacobian_ratio) {
            let place = mesh
                .element_lines
                .as_ref()
                .and_then(|l| l.at.get(e).copied());
            let key = place.unwrap_or((0, u32::try_from(e).unwrap_or(u32::MAX)));
            if first.as_ref().is_none_or(|(k, ..)| key < *k) {
                first = Some((key, e, kind, f));
            }
            if place.is_none() {
                break;
            }
        }
    }
    if let Some((_, e, kind, f)) = first {
        return Err(f.name(mesh, e, kind));
    }
    // unused nodes
    let mut used = vec![false; mesh.nodes.len()];
    for b in &mesh.blocks {
        for &n in &b.conn {
            used[n] = true;
        }
    }
    let unused = used.iter().filter(|u| !**u).count();
    if unused > 0 {
        let mut new_id = vec![usize::MAX; mesh.nodes.len()];
        let mut nodes = Vec::with_capacity(mesh.nodes.len() - unused);
        for (n, &u) in used.iter().enumerate() {
            if u {
                new_id[n] = nodes.len();
                nodes.push(mesh.nodes[n]);
            }
        }
        mesh.nodes = nodes;
        for b in &mut mesh.blocks {
            for n in &mut b.conn {
                *n = new_id[*n];
            }
        }
        for set in mesh.node_sets.values_mut() {
            *set = set
                .iter()
                .filter(|&&n| new_id[n] != usize::MAX)
                .map(|&n| new_id[n])
                .collect();
        }
        report.removed_nodes = unused;
        report.warnings.push(format!(
            "{unused} node(s) belong to no solid element and were removed"
        ));
    }
    let pieces = piece_sizes(mesh).len();
    report.pieces = pieces;
    if pieces > 1 {
        report.warnings.push(format!(
            "the mesh has {pieces} disconnected pieces (each free piece adds six rigid-body modes)"
        ));
    }
    Ok(report)
}

/// What is wrong with one element, before it is named ([`Flaw::name`]); node numbers are
/// the mesh's node indices.
enum Flaw {
    Inverted(f64),
    MidNode(usize, f64),
    Twice(usize),
    Flat,
    Coincident(usize, usize),
}

impl Flaw {
    /// The error for element `e` of `mesh`, named as [`Mesh::element_name`] and
    /// [`Mesh::node_name`] do.
    fn name(self, mesh: &Mesh, e: usize, kind: ElementKind) -> MeshError {
        let (element, kind) = (mesh.element_name(e), format!("{kind:?}"));
        let degenerate = |what: String| MeshError::Degenerate {
            element: element.clone(),
            kind: kind.clone(),
            what,
        };
        match self {
            Flaw::Inverted(ratio) => MeshError::Inverted {
                element,
                kind,
                ratio,
            },
            Flaw::MidNode(n, offset) => MeshError::MidNode {
                element,
                kind,
                node: mesh.node_name(n),
                offset,
            },
            Flaw::Twice(n) => degenerate(format!("{} is given twice", mesh.node_name(n))),
            Flaw::Flat => {
                degenerate("it has no volume (its nodes lie in a plane or on a line)".into())
            }
            Flaw::Coincident(a, b) => degenerate(format!(
                "two of its corner nodes are at one place: {} and {}",
                mesh.node_name(a),
                mesh.node_name(b)
            )),
        }
    }
}

/// The shape of one solid element with its `nodes` at `x`: no node given twice, no two corner
/// nodes at one place, it has volume, its mid-edge nodes near their edges' midpoints, and a
/// positive Jacobian.
fn check_element(
    (kind, nodes): (ElementKind, &[usize]),
    x: &[[f64; 3]],
    min_jacobian_ratio: JacobianRatio,
) -> Result<(), Flaw> {
    let nc = kind.num_corners();
    let ratio = min_jacobian_ratio(kind, x);
    if let Some((_, &n)) = nodes
        .iter()
        .enumerate()
        .find(|(k, n)| nodes[..*k].contains(n))
    {
        return Err(Flaw::Twice(n));
    }
    // two distinct corner nodes at one place (a hex8 so collapsed still has volume)
    for a in 0..nc {
        for b in a + 1..nc {
            if x[a] == x[b] {
                return Err(Flaw::Coincident(nodes[a], nodes[b]));
            }
        }
    }
    // an element without volume (a flat one) is degenerate whatever its mid-edge nodes
    if ratio.is_nan() || ratio.abs() <= 1e-6 {
        return Err(Flaw::Flat);
    }
    for (m, &(a, b)) in kind.mid_edges().iter().enumerate() {
        let len = (0..3)
            .map(|i| (x[a][i] - x[b][i]).powi(2))
            .sum::<f64>()
            .sqrt();
        let off = (0..3)
            .map(|i| (x[nc + m][i] - 0.5 * (x[a][i] + x[b][i])).powi(2))
            .sum::<f64>()
            .sqrt();
        if off > 0.25 * len {
            return Err(Flaw::MidNode(nodes[nc + m], off / len));
        }
    }
    if ratio < 0.0 {
        return Err(Flaw::Inverted(ratio));
    }
    Ok(())
}
