//! Sparse assembly of K and the consistent M on one pattern built from the node graph.
//!
//! K = sum_e A_e^T K_e A_e and M = sum_e A_e^T M_e A_e, where A_e gathers the element's free
//! DOFs. Element matrices are computed in parallel chunks (rayon) and scattered serially through
//! precomputed positions, so the pattern is never rebuilt from triplets.

use super::dofs::{DofMap, FIXED};
use super::element::{stiffness_mass, ElementError};
use crate::linalg::sparse::{Pattern, StiffnessMass};
use crate::mesh::Mesh;
use crate::scene::spec::Elastic;
use rayon::prelude::*;

/// An element whose matrices could not be formed.
#[derive(Debug, thiserror::Error)]
#[error("solid element {element}: {source}")]
pub struct AssemblyError {
    /// The element as [`Mesh::element_name`] names it (file and line for a deck).
    pub element: String,
    #[source]
    pub source: ElementError,
}

/// Element stiffness and mass, dense row-major.
type ElementPair = (Vec<f64>, Vec<f64>);

/// Node adjacency (including the node itself) in CSR form, neighbours sorted.
pub struct NodeGraph {
    pub ptr: Vec<usize>,
    pub adj: Vec<usize>,
}

impl NodeGraph {
    pub fn new(mesh: &Mesh) -> Self {
        let n = mesh.nodes.len();
        let mut lists: Vec<Vec<usize>> = vec![Vec::new(); n];
        for (_, nodes) in mesh.elements() {
            for &a in nodes {
                lists[a].extend_from_slice(nodes);
            }
        }
        let mut ptr = Vec::with_capacity(n + 1);
        let mut adj = Vec::new();
        ptr.push(0);
        for l in &mut lists {
            l.sort_unstable();
            l.dedup();
            adj.extend_from_slice(l);
            ptr.push(adj.len());
            *l = Vec::new();
        }
        Self { ptr, adj }
    }
    /// Position of node b in the neighbour list of a.
    fn slot(&self, a: usize, b: usize) -> usize {
        let l = &self.adj[self.ptr[a]..self.ptr[a + 1]];
        self.ptr[a] + l.binary_search(&b).expect("b is a neighbour of a")
    }
    /// Graph without self loops, restricted to nodes with free DOFs, renumbered; for METIS.
    /// Returns (xadj, adjncy, node ids of the graph vertices).
    pub fn without_self_loops(&self, keep: &[bool]) -> (Vec<usize>, Vec<usize>, Vec<usize>) {
        let n = keep.len();
        let mut new_id = vec![usize::MAX; n];
        let mut ids = Vec::new();
        for (a, &k) in keep.iter().enumerate() {
            if k {
                new_id[a] = ids.len();
                ids.push(a);
            }
        }
        let mut xadj = vec![0];
        let mut adjncy = Vec::new();
        for &a in &ids {
            for &b in &self.adj[self.ptr[a]..self.ptr[a + 1]] {
                if b != a && keep[b] {
                    adjncy.push(new_id[b]);
                }
            }
            xadj.push(adjncy.len());
        }
        (xadj, adjncy, ids)
    }
}

/// The assembled pattern plus the maps needed to scatter into it.
pub struct Assembler {
    pub graph: NodeGraph,
    pub pattern: Pattern,
    /// For each adjacency slot (a, b): offset of b's first free DOF within a's columns.
    slot_offset: Vec<usize>,
    dofs: DofMap,
}

impl Assembler {
    /// Builds the DOF pattern once for `mesh` under `dofs`.
    pub fn new(mesh: &Mesh, dofs: &DofMap) -> Self {
        let graph = NodeGraph::new(mesh);
        let nfree_of = |node: usize| (0..3).filter(|&i| dofs.dof[3 * node + i] != FIXED).count();
        let mut slot_offset = vec![0; graph.adj.len()];
        let mut col_ptr = vec![0usize; dofs.n_free + 1];
        let mut row_idx = Vec::new();
        for a in 0..mesh.nodes.len() {
            let mut off = 0;
            let mut rows = Vec::new();
            for (s, &b) in graph
                .adj
                .iter()
                .enumerate()
                .take(graph.ptr[a + 1])
                .skip(graph.ptr[a])
            {
                slot_offset[s] = off;
                off += nfree_of(b);
                rows.extend((0..3).map(|j| dofs.dof[3 * b + j]).filter(|&d| d != FIXED));
            }
            for i in 0..3 {
                let c = dofs.dof[3 * a + i];
                if c != FIXED {
                    row_idx.extend_from_slice(&rows);
                    col_ptr[c + 1] = row_idx.len();
                }
            }
        }
        Self {
            graph,
            pattern: Pattern {
                n: dofs.n_free,
                col_ptr,
                row_idx,
            },
            slot_offset,
            dofs: dofs.clone(),
        }
    }

    /// Assembles K and M of the whole mesh: each element with the mesh's own material when it
    /// carries a deck's ([`Mesh::material_of`]), else with `mat`.
    pub fn assemble(&self, mesh: &Mesh, mat: &Elastic) -> Result<StiffnessMass, AssemblyError> {
        let nnz = self.pattern.nnz();
        let mut k = crate::linalg::touch::zeros(nnz);
        let mut m = crate::linalg::touch::zeros(nnz);
        let elems: Vec<(crate::scene::spec::ElementKind, &[usize])> = mesh.elements().collect();
        let (split, offset) = self.halves(mesh.nodes.len());
        const CHUNK: usize = 512;
        for (c, chunk) in elems
            .chunks(CHUNK * rayon::current_num_threads().max(1))
            .enumerate()
        {
            let mats: Vec<Result<ElementPair, AssemblyError>> = chunk
                .par_iter()
                .enumerate()
                .map(|(i, (kind, nodes))| {
                    let element = c * CHUNK * rayon::current_num_threads().max(1) + i;
                    let mat = mesh.material_of(element, mat);
                    stiffness_mass(*kind, &mesh.coords_of(nodes), mat).map_err(|source| {
                        AssemblyError {
                            element: mesh.element_name(element),
                            source,
                        }
                    })
                })
                .collect();
            let mats = mats.into_iter().collect::<Result<Vec<_>, _>>()?;
            // each half of the columns on its own core: every entry still gets its elements'
            // terms in element order (the same sums as one pass)
            let (k_lo, k_hi) = k.split_at_mut(offset);
            let (m_lo, m_hi) = m.split_at_mut(offset);
            rayon::join(
                || self.scatter_pair(chunk, &mats, (0..split, 0), (k_lo, m_lo)),
                || self.scatter_pair(chunk, &mats, (split..usize::MAX, offset), (k_hi, m_hi)),
            );
        }
        Ok(StiffnessMass {
            pattern: self.pattern.clone(),
            k,
            m,
        })
    }

    /// Where the values split into two halves of about equal size at a node: the first node
    /// of the second half and the index of its first value (the free DOFs are numbered in
    /// node order, a node's columns side by side).
    fn halves(&self, nodes: usize) -> (usize, usize) {
        let (ptr, d) = (&self.pattern.col_ptr, &self.dofs.dof);
        let half = self.pattern.nnz() / 2;
        (0..nodes)
            .find_map(|a| {
                let c = (0..3).map(|i| d[3 * a + i]).find(|&c| c != FIXED)?;
                (ptr[c] >= half).then_some((a, ptr[c]))
            })
            .unwrap_or((nodes, self.pattern.nnz()))
    }

    /// Adds the element matrices `mats` (K and M of each element of `chunk`, 3n x 3n,
    /// node-major) into the columns of the nodes in `nodes`, whose values start at `offset`
    /// of the whole arrays: `k` and `m` hold the values from there on. Per entry, the terms
    /// are added in element order, as [`Assembler::scatter`] adds them.
    fn scatter_pair(
        &self,
        chunk: &[(crate::scene::spec::ElementKind, &[usize])],
        mats: &[ElementPair],
        (nodes, offset): (std::ops::Range<usize>, usize),
        (k, m): (&mut [f64], &mut [f64]),
    ) {
        for ((_, el), (ke, me)) in chunk.iter().zip(mats) {
            self.for_each_entry(
                el,
                |a| nodes.contains(&a),
                |pos, e| {
                    k[pos - offset] += ke[e];
                    m[pos - offset] += me[e];
                },
            );
        }
    }

    /// Adds a dense element matrix (3n x 3n, node-major) into `values`.
    pub fn scatter(&self, nodes: &[usize], ae: &[f64], values: &mut [f64]) {
        self.for_each_entry(nodes, |_| true, |pos, e| values[pos] += ae[e]);
    }

    /// Calls `add(pos, e)` for every free entry of the element on `nodes` whose column node
    /// `a` passes `column`: `pos` its place in the values, `e` its index in a 3n x 3n
    /// node-major element matrix; column node by column node, in the same order for every
    /// caller.
    fn for_each_entry(
        &self,
        nodes: &[usize],
        column: impl Fn(usize) -> bool,
        mut add: impl FnMut(usize, usize),
    ) {
        let nd = 3 * nodes.len();
        let d = &self.dofs.dof;
        for (la, &a) in nodes.iter().enumerate().filter(|(_, &a)| column(a)) {
            for (lb, &b) in nodes.iter().enumerate() {
                let base = self.slot_offset[self.graph.slot(a, b)];
                // local index of each free component of b among b's free DOFs
                let mut jl = 0;
                for j in 0..3 {
                    if d[3 * b + j] == FIXED {
                        continue;
                    }
                    for i in 0..3 {
                        let c = d[3 * a + i];
                        if c != FIXED {
                            add(
                                self.pattern.col_ptr[c] + base + jl,
                                (3 * lb + j) * nd + 3 * la + i,
                            );
                        }
                    }
                    jl += 1;
                }
            }
        }
    }
}
