//! Fill-reducing ordering by METIS nested dissection (`METIS_NodeND`, Debian `libmetis-dev`)
//! on the node graph, expanded to DOFs node by node. On 3-D solids nested dissection gives
//! about half the fill of minimum degree (measured on the default meshes), which is what makes the sparse
//! Cholesky of a 250k-DOF model fit in memory and time.

use std::os::raw::c_int;

extern "C" {
    fn METIS_NodeND(
        nvtxs: *const c_int,
        xadj: *const c_int,
        adjncy: *const c_int,
        vwgt: *const c_int,
        options: *const c_int,
        perm: *mut c_int,
        iperm: *mut c_int,
    ) -> c_int;
    fn METIS_SetDefaultOptions(options: *mut c_int) -> c_int;
}

const METIS_NOPTIONS: usize = 40;
const METIS_OK: c_int = 1;

/// Why METIS gave no order.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OrderingError {
    #[error("the graph has {0} adjacency entries, more than 32-bit METIS can index")]
    TooLarge(usize),
    #[error("METIS_NodeND failed with status {0}")]
    Metis(i32),
}

/// Nested-dissection order of a graph in CSR form (no self loops, symmetric).
/// Returns `perm` with `perm[new] = old`. Falls back to the identity for tiny graphs.
pub fn nested_dissection(xadj: &[usize], adjncy: &[usize]) -> Result<Vec<usize>, OrderingError> {
    let n = xadj.len() - 1;
    if n < 8 || adjncy.is_empty() {
        return Ok((0..n).collect());
    }
    if adjncy.len() > c_int::MAX as usize {
        return Err(OrderingError::TooLarge(adjncy.len()));
    }
    let x: Vec<c_int> = xadj.iter().map(|&v| v as c_int).collect();
    let a: Vec<c_int> = adjncy.iter().map(|&v| v as c_int).collect();
    let mut opts = [0 as c_int; METIS_NOPTIONS];
    let mut perm = vec![0 as c_int; n];
    let mut iperm = vec![0 as c_int; n];
    let nv = n as c_int;
    // SAFETY: arrays have the lengths METIS documents (n + 1, nnz, n, n, METIS_NOPTIONS);
    // METIS does not keep the pointers after return.
    let rc = unsafe {
        METIS_SetDefaultOptions(opts.as_mut_ptr());
        METIS_NodeND(
            &nv,
            x.as_ptr(),
            a.as_ptr(),
            std::ptr::null(),
            opts.as_ptr(),
            perm.as_mut_ptr(),
            iperm.as_mut_ptr(),
        )
    };
    if rc != METIS_OK {
        return Err(OrderingError::Metis(rc));
    }
    Ok(perm.into_iter().map(|v| v as usize).collect())
}

/// Expands a node order to a DOF order: the free DOFs of each node in the node order.
/// `node_dofs[node]` lists that node's free DOF indices. Returns (fwd, inv) with fwd\[new\] = old.
pub fn expand_to_dofs(
    node_perm: &[usize],
    node_dofs: &[Vec<usize>],
    n_dofs: usize,
) -> (Vec<usize>, Vec<usize>) {
    let mut fwd = Vec::with_capacity(n_dofs);
    for &node in node_perm {
        fwd.extend_from_slice(&node_dofs[node]);
    }
    let mut inv = vec![0; n_dofs];
    for (new, &old) in fwd.iter().enumerate() {
        inv[old] = new;
    }
    (fwd, inv)
}
