//! Degrees of freedom: three translations per node, node-major (dof = 3 node + component for
//! an unconstrained model). Dirichlet constraints remove all three DOFs of the nodes of named
//! sets; the remaining (free) DOFs are renumbered consecutively in node order.

use crate::mesh::Mesh;

/// Marker of a constrained DOF.
pub const FIXED: usize = usize::MAX;

/// Map from (node, component) to free DOF index.
#[derive(Clone, Debug, PartialEq)]
pub struct DofMap {
    /// `dof[3 node + i]` = free index or [`FIXED`].
    pub dof: Vec<usize>,
    pub n_free: usize,
}

/// A constraint that names a set the mesh does not have.
#[derive(Debug, thiserror::Error)]
#[error("unknown node set '{name}' to fix; the mesh has: {available}")]
pub struct UnknownSet {
    pub name: String,
    pub available: String,
}

impl DofMap {
    /// All DOFs free.
    pub fn free(n_nodes: usize) -> Self {
        Self {
            dof: (0..3 * n_nodes).collect(),
            n_free: 3 * n_nodes,
        }
    }

    /// Fixes all three DOFs of every node in the named sets.
    pub fn with_fixed_sets(mesh: &Mesh, sets: &[String]) -> Result<Self, UnknownSet> {
        let mut fixed = vec![false; mesh.nodes.len()];
        for name in sets {
            let nodes = mesh.node_set(name).ok_or_else(|| UnknownSet {
                name: name.clone(),
                available: mesh.set_names().join(", "),
            })?;
            for &n in nodes {
                fixed[n] = true;
            }
        }
        let mut dof = vec![FIXED; 3 * mesh.nodes.len()];
        let mut next = 0;
        for (n, &f) in fixed.iter().enumerate() {
            if !f {
                for i in 0..3 {
                    dof[3 * n + i] = next;
                    next += 1;
                }
            }
        }
        Ok(Self { dof, n_free: next })
    }

    /// Free DOFs of each node (empty for fully fixed nodes).
    pub fn node_dofs(&self) -> Vec<Vec<usize>> {
        self.dof
            .chunks(3)
            .map(|c| c.iter().copied().filter(|&d| d != FIXED).collect())
            .collect()
    }

    /// Expands a vector over free DOFs to all 3 n DOFs (zeros at constrained ones).
    pub fn expand(&self, free: &[f64]) -> Vec<f64> {
        self.dof
            .iter()
            .map(|&d| if d == FIXED { 0.0 } else { free[d] })
            .collect()
    }
}
