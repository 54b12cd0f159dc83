//! Craig-Bampton reduction of one part with interface fields (see [`super::interface`]).
//!
//! The part's DOFs split into boundary b (all DOFs of the interface nodes) and interior i. The
//! reduced basis Phi = [Phi_c | Phi_n | Phi_a] (full-part DOFs x reduced coordinates) holds:
//! - constraint modes: boundary displacement = one interface shape psi, interior in static
//!   equilibrium: u_i = -K_ii^-1 K_ib psi;
//! - fixed-interface normal modes: K_ii phi = lambda M_ii phi, phi^T M_ii phi = 1, all modes
//!   with frequency below the cut-off (their number from a Sturm count at the cut-off);
//! - residual attachment modes for loads f at interior DOFs (contact lines, clamp load):
//!   u_a = K_ii^-1 f - sum_j phi_j phi_j^T f / lambda_j, M-orthonormalised; they carry the
//!   static response the truncated modes miss (the static correction).
//!
//! Reduced matrices K_r = Phi^T K Phi, M_r = Phi^T M Phi. By construction K_cn = 0, K_an = 0,
//! K_ca = 0 and K_nn = diag(lambda). Rows of Phi at output DOFs (node, direction) are kept so
//! the engine ROM can report responses without the full basis.

use super::interface;
use crate::eigen::{solve_modes, EigenSettings};
use crate::fem::dofs::{DofMap, FIXED};
use crate::fem::material::Elastic;
use crate::fem::model::{FeModel, ModelError};
use crate::fem::surface::SurfaceMass;
use crate::mesh::Mesh;
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par};
use std::ops::Range;
use std::time::Instant;

/// A block of interface shapes on one node set.
pub struct InterfaceBlock {
    /// Node set of the part carrying the shapes.
    pub set: String,
    /// Shapes, 3 rows per node of the set (set order), one column per shape.
    pub psi: Mat<f64>,
}

/// A load pattern at interior DOFs: (node, force vector) pairs.
pub struct Load {
    pub name: String,
    pub entries: Vec<(usize, [f64; 3])>,
}

/// An output: the displacement of `node` along the unit vector `dir`.
#[derive(Clone, Debug)]
pub struct Output {
    pub node: usize,
    pub dir: [f64; 3],
}

/// Failures of a reduction, naming the part.
#[derive(Debug, thiserror::Error)]
pub enum ReduceError {
    #[error("part '{part}': {source}")]
    Model {
        part: String,
        #[source]
        source: ModelError,
    },
    #[error("part '{part}': interface set '{set}': {msg}")]
    Interface {
        part: String,
        set: String,
        msg: String,
    },
    #[error("part '{part}': {msg}")]
    Other { part: String, msg: String },
    #[error("part '{part}': {source}")]
    Eigen {
        part: String,
        #[source]
        source: crate::eigen::EigenError,
    },
    /// More modes below the cut-off than the machine can hold (a material far too soft, a
    /// cut-off far too high): found by the Sturm count, before the eigen-solve.
    #[error("part '{part}': {count} of its {dofs} interior DOFs' modes lie below the cut-off {cutoff_hz} Hz (basis about {gb} GB, {available_gb} GB available; more than a quarter of the spectrum is beyond what the mesh resolves): lower rom.band_hz or rom.cutoff_factor, or check the material (Young's modulus, density)")]
    TooManyModes {
        part: String,
        count: usize,
        dofs: usize,
        cutoff_hz: String,
        gb: String,
        available_gb: String,
    },
}

/// Work counters and timings of one reduction.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct CbStats {
    pub full_dofs: usize,
    pub interior_dofs: usize,
    pub constraint_modes: usize,
    pub normal_modes: usize,
    pub attachment_modes: usize,
    pub highest_mode_hz: f64,
    pub seconds: f64,
}

/// The reduced part.
pub struct PartReduction {
    pub k: Mat<f64>,
    pub m: Mat<f64>,
    /// Columns of each interface block, in input order.
    pub interface_cols: Vec<Range<usize>>,
    pub modes: Range<usize>,
    pub mode_frequencies_hz: Vec<f64>,
    pub attachments: Range<usize>,
    /// Rows of Phi along the output directions (outputs x reduced coordinates).
    pub outputs: Mat<f64>,
    /// Phi^T f of each load (reduced coordinates x loads).
    pub loads: Mat<f64>,
    /// Full basis in the part's free-DOF numbering (kept on request, for recovery).
    pub basis: Option<Mat<f64>>,
    pub dofs: DofMap,
    pub stats: CbStats,
}

impl PartReduction {
    pub fn size(&self) -> usize {
        self.k.nrows()
    }
}

/// Settings of one reduction.
pub struct CbSettings {
    pub cutoff_hz: f64,
    pub keep_basis: bool,
}

fn columns_solve(llt: &crate::linalg::factor::Llt<'_>, mut rhs: Mat<f64>) -> Mat<f64> {
    let n = rhs.ncols();
    let chunk = 64;
    let mut c0 = 0;
    while c0 < n {
        let c1 = (c0 + chunk).min(n);
        llt.solve_in_place(rhs.as_mut().subcols_mut(c0, c1 - c0));
        c0 = c1;
    }
    rhs
}

/// One part to reduce.
#[derive(Clone, Copy)]
pub struct Part<'a> {
    /// Name in messages ("liner", "crankcase").
    pub name: &'a str,
    pub mesh: &'a Mesh,
    pub material: &'a Elastic,
    /// Normal surface masses its M carries (the coolant layer).
    pub surface: &'a [SurfaceMass],
    /// Sets held fixed for good (e.g. the engine mounts).
    pub fix: &'a [String],
    /// The coupled boundaries.
    pub interfaces: &'a [InterfaceBlock],
    /// Attachment load patterns.
    pub loads: &'a [Load],
    /// Output DOFs whose rows the reduction returns.
    pub outputs: &'a [Output],
}

/// Reduces one part: the basis Phi = [Phi_c | Phi_n | Phi_a] of the module doc, built on the
/// full model (the part's own fixed sets) and the interior model (interfaces fixed too), and
/// K_r = Phi^T K Phi, M_r = Phi^T M Phi with the basis's rows at the outputs and Phi^T f of
/// the loads.
pub fn reduce(p: &Part<'_>, settings: &CbSettings) -> Result<PartReduction, ReduceError> {
    let part = p.name;
    let t0 = Instant::now();
    let tick = |what: &str| log::info!("[{part}] {:7.2} s  {what}", t0.elapsed().as_secs_f64());
    let err_model = |source| ReduceError::Model {
        part: part.to_string(),
        source,
    };
    let full =
        FeModel::build_with(p.mesh.clone(), p.material, p.fix, p.surface).map_err(err_model)?;
    let sets = interior_sets(p)?;
    let inner =
        FeModel::build_with(p.mesh.clone(), p.material, &sets, p.surface).map_err(err_model)?;
    let (na, nb) = (full.n_free(), inner.n_free());
    tick(&format!("assembled: {na} DOFs, {nb} interior"));
    let llt = inner
        .analysis
        .llt(&inner.km.pattern, &inner.km.k)
        .map_err(|e| err_model(e.into()))?;
    let (lambdas, modes_b) = fixed_interface_modes(p, &inner, &llt, settings.cutoff_hz, &tick)?;
    tick("modes");
    let b_to_a = interior_to_full(&full, &inner);
    let (phi_c, interface_cols) = constraint_modes(p, &full, &llt, &b_to_a);
    let nc = phi_c.ncols();
    tick(&format!("{nc} constraint modes"));
    let f_a = load_matrix(&full, p.loads);
    let interior = Interior {
        full: &full,
        llt: &llt,
        b_to_a: &b_to_a,
        lambdas: &lambdas,
        modes: &modes_b,
    };
    let att = attachment_modes(part, &interior, &f_a, &phi_c, &tick)?;
    drop(llt);
    let nm = lambdas.len();
    let na_cols = att.ncols();
    // assemble the basis in full numbering
    let nr = nc + nm + na_cols;
    let mut phi = Mat::<f64>::zeros(na, nr);
    phi.as_mut().subcols_mut(0, nc).copy_from(&phi_c);
    drop(phi_c);
    for j in 0..nm {
        for bi in 0..nb {
            phi[(b_to_a[bi], nc + j)] = modes_b[(bi, j)];
        }
    }
    phi.as_mut().subcols_mut(nc + nm, na_cols).copy_from(&att);
    drop(att);
    let (k, m) = project(&full, &phi, &tick);
    tick(&format!("projected onto {nr} coordinates"));
    log_conditioning(part, &k, &m);
    let loads_r = phi.transpose() * &f_a;
    let out = output_rows(&full, p.outputs, &phi);
    let freqs: Vec<f64> = lambdas
        .iter()
        .map(|l| l.max(0.0).sqrt() / (2.0 * std::f64::consts::PI))
        .collect();
    let stats = CbStats {
        full_dofs: na,
        interior_dofs: nb,
        constraint_modes: nc,
        normal_modes: nm,
        attachment_modes: na_cols,
        highest_mode_hz: freqs.last().copied().unwrap_or(0.0),
        seconds: t0.elapsed().as_secs_f64(),
    };
    let _ = interface::count; // shapes come from the caller
    Ok(PartReduction {
        k,
        m,
        interface_cols,
        modes: nc..nc + nm,
        mode_frequencies_hz: freqs,
        attachments: nc + nm..nr,
        outputs: out,
        loads: loads_r,
        basis: settings.keep_basis.then_some(phi),
        dofs: full.dofs.clone(),
        stats,
    })
}

/// The sets fixed in the interior model: the part's own fixed sets and every interface's,
/// each interface checked against the mesh (the set exists, is not empty, and its shapes have
/// 3 rows per node).
fn interior_sets(p: &Part<'_>) -> Result<Vec<String>, ReduceError> {
    let (part, mesh) = (p.name, p.mesh);
    let mut sets: Vec<String> = p.fix.to_vec();
    for b in p.interfaces {
        let nodes = mesh
            .node_set(&b.set)
            .ok_or_else(|| ReduceError::Interface {
                part: part.into(),
                set: b.set.clone(),
                msg: format!(
                    "the mesh has no such node set (it has: {})",
                    mesh.set_names().join(", ")
                ),
            })?;
        if nodes.is_empty() {
            return Err(ReduceError::Interface {
                part: part.into(),
                set: b.set.clone(),
                msg: "the set is empty: the part does not reach this interface".into(),
            });
        }
        if b.psi.nrows() != 3 * nodes.len() {
            return Err(ReduceError::Other {
                part: part.into(),
                msg: format!("interface '{}' shapes do not match its node set", b.set),
            });
        }
        sets.push(b.set.clone());
    }
    Ok(sets)
}

/// The fixed-interface normal modes below the cut-off: K_ii phi = lambda M_ii phi, their
/// number from a Sturm count (negative pivots of K_ii - omega_c^2 M_ii), solved by
/// shift-invert Lanczos on the factor of K_ii; refused when the Lanczos vectors would not fit
/// in memory or the cut-off takes in more than a quarter of the spectrum. Returns the
/// eigenvalues and the modes (interior DOFs x modes).
fn fixed_interface_modes(
    p: &Part<'_>,
    inner: &FeModel,
    llt: &crate::linalg::factor::Llt<'_>,
    cutoff_hz: f64,
    tick: &dyn Fn(&str),
) -> Result<(Vec<f64>, Mat<f64>), ReduceError> {
    let part = p.name;
    let nb = inner.n_free();
    let err_model = |source| ReduceError::Model {
        part: part.to_string(),
        source,
    };
    let omega_c2 = (2.0 * std::f64::consts::PI * cutoff_hz).powi(2);
    let count = inner
        .analysis
        .negative_pivots(&inner.km.pattern, &inner.km.shifted(omega_c2))
        .map_err(|e| err_model(e.into()))?;
    tick(&format!(
        "factorised; {count} fixed-interface modes below the cut-off"
    ));
    // the Lanczos basis (2 count + 1 vectors) and the modes: about 3 count vectors of nb; and
    // a cut-off that takes in more than a quarter of the spectrum lies beyond what the mesh
    // resolves (the upper modes of a discretisation are not the structure's)
    let need = 3.0 * count as f64 * nb as f64 * 8.0;
    let available = crate::machine::available_memory() as f64;
    if need > available || 4 * count > nb {
        return Err(ReduceError::TooManyModes {
            part: part.to_string(),
            count,
            dofs: nb,
            cutoff_hz: crate::text::num(cutoff_hz),
            gb: crate::text::num(need / 1e9),
            available_gb: crate::text::num(available / 1e9),
        });
    }
    if count == 0 {
        return Ok((Vec::new(), Mat::zeros(nb, 0)));
    }
    let pattern = &inner.km.pattern;
    let m = &inner.km.m;
    let modes = solve_modes(
        nb,
        &EigenSettings::new(count.min(nb - 1), 0.0),
        |x, y| pattern.matvec(m, x, y),
        |x| llt.solve_vec(x),
    )
    .map_err(|source| ReduceError::Eigen {
        part: part.to_string(),
        source,
    })?;
    let k = modes.count();
    let mat = Mat::from_fn(nb, k, |i, j| modes.vectors[j * nb + i]);
    Ok((modes.eigenvalues.clone(), mat))
}

/// For each interior DOF (the interior model's numbering) its DOF in the full model.
fn interior_to_full(full: &FeModel, inner: &FeModel) -> Vec<usize> {
    let (na, nb) = (full.n_free(), inner.n_free());
    let mut a_to_b = vec![FIXED; na];
    for (slot, &a) in full.dofs.dof.iter().enumerate() {
        if a != FIXED {
            a_to_b[a] = inner.dofs.dof[slot];
        }
    }
    let mut b_to_a = vec![0; nb];
    for (a, &b) in a_to_b.iter().enumerate() {
        if b != FIXED {
            b_to_a[b] = a;
        }
    }
    b_to_a
}

/// Constraint modes (full DOFs x interface shapes): the boundary displaced by one interface
/// shape psi, the interior in static equilibrium u_i = -K_ii^-1 K_ib psi; and each
/// interface's columns.
fn constraint_modes(
    p: &Part<'_>,
    full: &FeModel,
    llt: &crate::linalg::factor::Llt<'_>,
    b_to_a: &[usize],
) -> (Mat<f64>, Vec<Range<usize>>) {
    let (na, nb) = (full.n_free(), b_to_a.len());
    let nc: usize = p.interfaces.iter().map(|b| b.psi.ncols()).sum();
    let mut g = Mat::<f64>::zeros(na, nc);
    let mut interface_cols = Vec::new();
    let mut col = 0;
    for b in p.interfaces {
        let nodes = p.mesh.node_set(&b.set).expect("checked by interior_sets");
        for j in 0..b.psi.ncols() {
            for (a, &node) in nodes.iter().enumerate() {
                for i in 0..3 {
                    let d = full.dofs.dof[3 * node + i];
                    if d != FIXED {
                        g[(d, col + j)] = b.psi[(3 * a + i, j)];
                    }
                }
            }
        }
        interface_cols.push(col..col + b.psi.ncols());
        col += b.psi.ncols();
    }
    let kg = sparse_times(full, false, &g);
    let mut rhs = Mat::<f64>::zeros(nb, nc);
    for j in 0..nc {
        for bi in 0..nb {
            rhs[(bi, j)] = -kg[(b_to_a[bi], j)];
        }
    }
    let sol = columns_solve(llt, rhs);
    let mut phi_c = g;
    for j in 0..nc {
        for bi in 0..nb {
            phi_c[(b_to_a[bi], j)] = sol[(bi, j)];
        }
    }
    (phi_c, interface_cols)
}

/// The attachment loads as columns over the full model's DOFs (full DOFs x loads).
fn load_matrix(full: &FeModel, loads: &[Load]) -> Mat<f64> {
    let mut f_a = Mat::<f64>::zeros(full.n_free(), loads.len());
    for (j, l) in loads.iter().enumerate() {
        for &(node, f) in &l.entries {
            for i in 0..3 {
                let d = full.dofs.dof[3 * node + i];
                if d != FIXED {
                    f_a[(d, j)] += f[i];
                }
            }
        }
    }
    f_a
}

/// The interior problem the attachment modes are solved on.
struct Interior<'a> {
    full: &'a FeModel,
    llt: &'a crate::linalg::factor::Llt<'a>,
    b_to_a: &'a [usize],
    lambdas: &'a [f64],
    /// Fixed-interface modes (interior DOFs x modes).
    modes: &'a Mat<f64>,
}

/// Residual attachment modes, M-orthonormalised (full DOFs x kept columns): for each load
/// column f (the attachment loads `f_a`, then the inertia loads M Phi_c of the constraint
/// modes, the modal-truncation augmentation) u = K_ii^-1 f - Phi_n Lambda^-1 Phi_n^T f; the
/// block is M-orthonormalised through the eigen-decomposition of its Gram matrix U^T M U,
/// dropping directions below 1e-10 of the largest (dependent load shapes). The MTA columns
/// carry the quasi-static inertia of the interface motion that the truncated fixed-interface
/// modes miss, lifting CB accuracy from O((f/f_c)^2) towards O((f/f_c)^4).
fn attachment_modes(
    part: &str,
    interior: &Interior<'_>,
    f_a: &Mat<f64>,
    phi_c: &Mat<f64>,
    tick: &dyn Fn(&str),
) -> Result<Mat<f64>, ReduceError> {
    let Interior {
        full,
        llt,
        b_to_a,
        lambdas,
        modes: modes_b,
    } = *interior;
    let (na, nb) = (full.n_free(), b_to_a.len());
    let (nl, nc) = (f_a.ncols(), phi_c.ncols());
    let m_phi_c = sparse_times(full, true, phi_c);
    let nlt = nl + nc;
    let mut att = Mat::<f64>::zeros(nb, nlt);
    for j in 0..nl {
        for bi in 0..nb {
            att[(bi, j)] = f_a[(b_to_a[bi], j)];
        }
    }
    for j in 0..nc {
        for bi in 0..nb {
            att[(bi, nl + j)] = m_phi_c[(b_to_a[bi], j)];
        }
    }
    drop(m_phi_c);
    let nl = nlt;
    let f_b = att.clone();
    let mut att = columns_solve(llt, att);
    let nm = lambdas.len();
    if nm > 0 && nl > 0 {
        // u -= Phi_n Lambda^-1 Phi_n^T f
        let mut pf = modes_b.transpose() * &f_b;
        for r in 0..nm {
            for j in 0..nl {
                pf[(r, j)] /= lambdas[r];
            }
        }
        matmul(
            att.as_mut(),
            Accum::Add,
            modes_b.as_ref(),
            pf.as_ref(),
            -1.0,
            Par::rayon(0),
        );
    }
    tick(&format!("{nl} attachment modes"));
    if nl == 0 {
        return Ok(Mat::zeros(na, 0));
    }
    let mut att_a = Mat::<f64>::zeros(na, nl);
    for j in 0..nl {
        for bi in 0..nb {
            att_a[(b_to_a[bi], j)] = att[(bi, j)];
        }
    }
    let m_att = sparse_times(full, true, &att_a);
    let gram = att_a.transpose() * &m_att;
    let evd = gram
        .self_adjoint_eigen(faer::Side::Lower)
        .map_err(|e| ReduceError::Other {
            part: part.into(),
            msg: format!("attachment modes: eigen-decomposition failed: {e:?}"),
        })?;
    let s = evd.S().column_vector();
    let smax = (0..nl).map(|i| s[i]).fold(0.0f64, f64::max);
    let keep: Vec<usize> = (0..nl).filter(|&i| s[i] > 1e-10 * smax).collect();
    let u = evd.U();
    let tr = Mat::from_fn(nl, keep.len(), |r, c| u[(r, keep[c])] / s[keep[c]].sqrt());
    Ok(&att_a * &tr)
}

/// K_r = Phi^T K Phi and M_r = Phi^T M Phi, symmetrised.
fn project(full: &FeModel, phi: &Mat<f64>, tick: &dyn Fn(&str)) -> (Mat<f64>, Mat<f64>) {
    let nr = phi.ncols();
    let kphi = sparse_times(full, false, phi);
    let mut k = Mat::<f64>::zeros(nr, nr);
    matmul(
        k.as_mut(),
        Accum::Replace,
        phi.transpose(),
        kphi.as_ref(),
        1.0,
        Par::rayon(0),
    );
    drop(kphi);
    tick("K_r");
    let mphi = sparse_times(full, true, phi);
    let mut m = Mat::<f64>::zeros(nr, nr);
    matmul(
        m.as_mut(),
        Accum::Replace,
        phi.transpose(),
        mphi.as_ref(),
        1.0,
        Par::rayon(0),
    );
    drop(mphi);
    symmetrise(&mut k);
    symmetrise(&mut m);
    (k, m)
}

/// With info logging: the extreme eigenvalues of K_r and M_r scaled by M_r's diagonal (a
/// conditioning diagnostic of the basis).
fn log_conditioning(part: &str, k: &Mat<f64>, m: &Mat<f64>) {
    if !log::log_enabled!(log::Level::Info) {
        return;
    }
    let nr = k.nrows();
    let d: Vec<f64> = (0..nr)
        .map(|i| 1.0 / m[(i, i)].max(1e-300).sqrt())
        .collect();
    let ks = Mat::from_fn(nr, nr, |i, j| d[i] * k[(i, j)] * d[j]);
    let ms = Mat::from_fn(nr, nr, |i, j| d[i] * m[(i, j)] * d[j]);
    let ek = ks
        .self_adjoint_eigenvalues(faer::Side::Lower)
        .unwrap_or_default();
    let em = ms
        .self_adjoint_eigenvalues(faer::Side::Lower)
        .unwrap_or_default();
    log::info!(
        "[{part}] scaled K_r eigenvalues {:?} .. {:?}; M_r {:?} .. {:?}",
        &ek[..ek.len().min(8)],
        ek.last(),
        &em[..em.len().min(3)],
        em.last()
    );
}

/// Rows of Phi along the outputs' directions (outputs x reduced coordinates).
fn output_rows(full: &FeModel, outputs: &[Output], phi: &Mat<f64>) -> Mat<f64> {
    let nr = phi.ncols();
    let mut out = Mat::<f64>::zeros(outputs.len(), nr);
    for (r, o) in outputs.iter().enumerate() {
        for i in 0..3 {
            let d = full.dofs.dof[3 * o.node + i];
            if d != FIXED && o.dir[i] != 0.0 {
                for j in 0..nr {
                    out[(r, j)] += o.dir[i] * phi[(d, j)];
                }
            }
        }
    }
    out
}

/// K X or M X for the full model's sparse matrix and a dense block X.
fn sparse_times(model: &FeModel, mass: bool, x: &Mat<f64>) -> Mat<f64> {
    let vals = if mass { &model.km.m } else { &model.km.k };
    let mut y = Mat::<f64>::zeros(x.nrows(), x.ncols());
    model.km.pattern.mul_dense(vals, x.as_ref(), y.as_mut());
    y
}

/// A <- (A + A^T) / 2.
pub fn symmetrise(a: &mut Mat<f64>) {
    let n = a.nrows();
    for j in 0..n {
        for i in j + 1..n {
            let v = 0.5 * (a[(i, j)] + a[(j, i)]);
            a[(i, j)] = v;
            a[(j, i)] = v;
        }
    }
}
