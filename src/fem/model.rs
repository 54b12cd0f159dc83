//! An assembled FE model of one part: mesh, DOF map, K and M on one pattern, the fill-reducing
//! order and the symbolic factorisation, ready for static and eigen solves.

use super::assembly::{Assembler, AssemblyError};
use super::dofs::{DofMap, UnknownSet, FIXED};
use super::surface::{self, SurfaceMass};
use crate::linalg::factor::{Analysis, FactorError};
use crate::linalg::ordering;
use crate::linalg::sparse::StiffnessMass;
use crate::mesh::Mesh;
use crate::scene::spec::Elastic;
use std::time::Instant;

/// Failures while building or solving a model.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    #[error(transparent)]
    Set(#[from] UnknownSet),
    #[error(transparent)]
    Assembly(#[from] AssemblyError),
    #[error("fill-reducing ordering failed: {0}")]
    Ordering(#[from] crate::linalg::ordering::OrderingError),
    #[error(transparent)]
    Factor(#[from] FactorError),
    #[error("the model has no free DOFs")]
    NoDofs,
    #[error(transparent)]
    Surface(#[from] super::surface::SurfaceError),
}

/// Wall-clock seconds of each phase (the modal phases filled by `eigen::modal`). The ordering
/// (with the symbolic factorisation) runs beside the numeric assembly, so the two overlap.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Timings {
    pub assembly: f64,
    pub ordering: f64,
    pub factorisation: f64,
    pub eigen: f64,
    pub certification: f64,
}

/// Assembled model of one part.
pub struct FeModel {
    pub mesh: Mesh,
    pub dofs: DofMap,
    pub km: StiffnessMass,
    pub analysis: Analysis,
    pub timings: Timings,
    /// The fill-reducing node order of the analysis (nodes with free DOFs, METIS nested
    /// dissection), kept so that a restricted model ([`FeModel::restrict`]) reuses it.
    node_order: Vec<usize>,
}

impl FeModel {
    /// Assembles K, M for `mesh` with `fixed` node sets constrained and analyses the pattern.
    pub fn build(mesh: Mesh, material: &Elastic, fixed: &[String]) -> Result<Self, ModelError> {
        Self::build_with(mesh, material, fixed, &[])
    }

    /// As [`FeModel::build`], with normal surface masses added to M (the coolant layer on a
    /// wet liner; `fem::surface`).
    pub fn build_with(
        mesh: Mesh,
        material: &Elastic,
        fixed: &[String],
        surface: &[SurfaceMass],
    ) -> Result<Self, ModelError> {
        let mut timings = Timings::default();
        let t = Instant::now();
        let dofs = DofMap::with_fixed_sets(&mesh, fixed)?;
        if dofs.n_free == 0 {
            return Err(ModelError::NoDofs);
        }
        let asm = Assembler::new(&mesh, &dofs);
        let setup = t.elapsed().as_secs_f64();
        // the order and the symbolic factorisation need the pattern only: they run beside the
        // numeric assembly (METIS and the symbolic analysis are serial, the assembly's element
        // loop takes the other core); each side's work and results are those of a serial run
        let (assembled, ordered) = rayon::join(
            || {
                let t = Instant::now();
                let km = assemble_with(&asm, &mesh, material, surface);
                (km, t.elapsed().as_secs_f64())
            },
            || {
                let t = Instant::now();
                let ordered = order_and_analyse(&asm, &dofs);
                (ordered, t.elapsed().as_secs_f64())
            },
        );
        let (km, t_assembly) = (assembled.0?, assembled.1);
        let ((node_perm, analysis), t_ordering) = (ordered.0?, ordered.1);
        timings.assembly = setup + t_assembly;
        timings.ordering = t_ordering;
        Ok(Self {
            mesh,
            dofs,
            km,
            analysis,
            timings,
            node_order: node_perm,
        })
    }

    /// The model with the nodes of `sets` fixed as well (`sets` names every fixed set, this
    /// model's included): K and M restricted to the remaining free DOFs (rows and columns
    /// dropped, no assembly), analysed with this model's node order restricted to the nodes
    /// still free (a nested-dissection order stays one on a subgraph: its separators still
    /// separate). The Craig-Bampton interior model K_ii, M_ii.
    pub fn restrict(&self, sets: &[String]) -> Result<Self, ModelError> {
        let t = Instant::now();
        let dofs = DofMap::with_fixed_sets(&self.mesh, sets)?;
        if dofs.n_free == 0 {
            return Err(ModelError::NoDofs);
        }
        // old free index -> new free index (FIXED when newly fixed); both numberings run in
        // node order, so kept indices keep their order
        let mut map = vec![FIXED; self.dofs.n_free];
        for (slot, &old) in self.dofs.dof.iter().enumerate() {
            let new = dofs.dof[slot];
            if new != FIXED {
                assert!(
                    old != FIXED,
                    "restrict: `sets` must include the model's fixed sets"
                );
                map[old] = new;
            }
        }
        let km = self.km.restrict(&map, dofs.n_free);
        let node_dofs = dofs.node_dofs();
        let node_perm: Vec<usize> = self
            .node_order
            .iter()
            .copied()
            .filter(|&n| !node_dofs[n].is_empty())
            .collect();
        let (fwd, inv) = ordering::expand_to_dofs(&node_perm, &node_dofs, dofs.n_free);
        let analysis = Analysis::new(&km.pattern, &fwd, &inv)?;
        Ok(Self {
            mesh: self.mesh.clone(),
            dofs,
            km,
            analysis,
            timings: Timings {
                ordering: t.elapsed().as_secs_f64(),
                ..Timings::default()
            },
            node_order: node_perm,
        })
    }

    pub fn n_free(&self) -> usize {
        self.dofs.n_free
    }
}
/// K and M of `mesh` on the assembler's pattern, with the normal surface masses `surface`
/// added to M.
fn assemble_with(
    asm: &Assembler,
    mesh: &Mesh,
    material: &Elastic,
    surface: &[SurfaceMass],
) -> Result<StiffnessMass, ModelError> {
    let mut km = asm.assemble(mesh, material)?;
    for sm in surface {
        for face in surface::boundary_faces(mesh, &sm.set)? {
            let (me, _) = surface::face_mass(&face, &mesh.coords_of(&face.nodes), sm.mass_per_area);
            asm.scatter(&face.nodes, &me, &mut km.m);
        }
    }
    Ok(km)
}

/// The fill-reducing node order (METIS nested dissection of the graph of the nodes with free
/// DOFs) and the symbolic factorisation of the assembler's pattern in that order, expanded to
/// DOFs node by node.
fn order_and_analyse(asm: &Assembler, dofs: &DofMap) -> Result<(Vec<usize>, Analysis), ModelError> {
    let node_dofs = dofs.node_dofs();
    let keep: Vec<bool> = node_dofs.iter().map(|d| !d.is_empty()).collect();
    let (xadj, adjncy, ids) = asm.graph.without_self_loops(&keep);
    let order = ordering::nested_dissection(&xadj, &adjncy)?;
    let node_perm: Vec<usize> = order.iter().map(|&v| ids[v]).collect();
    let (fwd, inv) = ordering::expand_to_dofs(&node_perm, &node_dofs, dofs.n_free);
    let analysis = Analysis::new(&asm.pattern, &fwd, &inv)?;
    Ok((node_perm, analysis))
}
