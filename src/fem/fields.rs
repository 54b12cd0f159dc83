//! Smooth trial fields of a model: the nodal interpolants of polynomial displacement fields.
//!
//! u(x) = e_i p_j(x), e_i a unit direction (i = 0..3) and p_j a monomial xi^a eta^b zeta^c
//! with a + b + c <= degree, in the coordinates xi = (x - c) / s centred and scaled per axis to
//! [-1, 1] over the nodes with free DOFs. Their span holds the rigid-body fields (degree >= 1)
//! and the long-wave deformations that the lowest modes of a body are made of, so the
//! Rayleigh-Ritz values of (K, M) on it are cheap upper bounds of the lowest eigenvalues
//! (`eigen::trial`). A constrained DOF takes no value (the field is cut there), which keeps
//! every bound valid, only looser near the constraints.
//!
//! Field i q + j (q monomials) is held as the monomial values per node and the node and
//! direction of every free DOF: X_(d, i q + j) = p_j(node(d)) when direction(d) = i, else 0.
//! That is q values per node where the dense block takes 3 q per DOF.

use super::dofs::{DofMap, FIXED};
use crate::mesh::Mesh;
use faer::Mat;

/// Number of monomials of degree at most `degree` in three variables: C(degree + 3, 3).
pub fn monomial_count(degree: usize) -> usize {
    (degree + 1) * (degree + 2) * (degree + 3) / 6
}

/// The smooth trial fields of a model (module docs).
#[derive(Clone, Debug)]
pub struct SmoothFields {
    /// Monomials per node, q.
    pub per_node: usize,
    /// p_j(node) at `values[node q + j]`.
    pub values: Vec<f64>,
    /// The node of every free DOF.
    pub dof_node: Vec<u32>,
    /// The direction (0, 1, 2) of every free DOF.
    pub dof_direction: Vec<u8>,
}

impl SmoothFields {
    /// The fields of degree at most `degree` on the free DOFs of `dofs` (module docs).
    pub fn new(mesh: &Mesh, dofs: &DofMap, degree: usize) -> Self {
        let powers: Vec<[i32; 3]> = (0..=degree as i32)
            .flat_map(|t| (0..=t).flat_map(move |a| (0..=t - a).map(move |b| [a, b, t - a - b])))
            .collect();
        let q = powers.len();
        let (centre, scale) = free_box(mesh, dofs);
        let mut values = Vec::with_capacity(mesh.nodes.len() * q);
        for p in &mesh.nodes {
            let xi: [f64; 3] = std::array::from_fn(|k| (p[k] - centre[k]) / scale[k]);
            values.extend(
                powers
                    .iter()
                    .map(|pw| (0..3).map(|k| xi[k].powi(pw[k])).product::<f64>()),
            );
        }
        let (mut dof_node, mut dof_direction) = (vec![0; dofs.n_free], vec![0; dofs.n_free]);
        for (slot, &d) in dofs.dof.iter().enumerate() {
            if d != FIXED {
                dof_node[d] = (slot / 3) as u32;
                dof_direction[d] = (slot % 3) as u8;
            }
        }
        Self {
            per_node: q,
            values,
            dof_node,
            dof_direction,
        }
    }

    /// Number of fields, 3 q.
    pub fn count(&self) -> usize {
        3 * self.per_node
    }

    /// The monomial values at the node of free DOF `d` and its direction.
    pub fn at(&self, d: usize) -> (&[f64], usize) {
        let (node, q) = (self.dof_node[d] as usize, self.per_node);
        (
            &self.values[node * q..node * q + q],
            self.dof_direction[d] as usize,
        )
    }

    /// The fields as a dense n_free x 3 q block (tests and small models).
    pub fn to_dense(&self) -> Mat<f64> {
        let q = self.per_node;
        let mut x = Mat::<f64>::zeros(self.dof_node.len(), 3 * q);
        for d in 0..self.dof_node.len() {
            let (p, i) = self.at(d);
            for (j, v) in p.iter().enumerate() {
                x[(d, i * q + j)] = *v;
            }
        }
        x
    }
}

/// Centre and half-width of the bounding box of the nodes with a free DOF, per axis (a
/// half-width of zero taken as one: a flat model's monomials in that axis are constant).
fn free_box(mesh: &Mesh, dofs: &DofMap) -> ([f64; 3], [f64; 3]) {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for (node, p) in mesh.nodes.iter().enumerate() {
        if dofs.dof[3 * node..3 * node + 3].iter().any(|&d| d != FIXED) {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    }
    let centre = std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
    let scale = std::array::from_fn(|k| {
        let s = 0.5 * (hi[k] - lo[k]);
        if s > 0.0 && s.is_finite() {
            s
        } else {
            1.0
        }
    });
    (centre, scale)
}
