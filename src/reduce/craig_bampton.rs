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

use crate::eigen::{solve_modes, EigenSettings};
use crate::fem::dofs::{DofMap, FIXED};
use crate::fem::model::{FeModel, ModelError};
use crate::fem::surface::SurfaceMass;
use crate::linalg::sparse::{Pattern, SymCsc};
use crate::mesh::Mesh;
use crate::scene::spec::Elastic;
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef, Par};
use rayon::prelude::*;
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
    /// A substructuring the part's mesh or the scene does not allow (cut planes, interfaces
    /// across them, full bases asked of a substructured part): the user can change it.
    #[error("part '{part}': substructuring (rom.crankcase_components): {msg}")]
    Substructure { part: String, msg: String },
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
    /// The fixed-interface modes on the interior DOFs (kept with the basis): a later
    /// reduction of the same part with other interface shapes reuses them ([`reduce_with`]).
    pub fixed_modes: Option<FixedModes>,
    pub dofs: DofMap,
    pub stats: CbStats,
}

impl PartReduction {
    pub fn size(&self) -> usize {
        self.k.nrows()
    }
}

/// A part's fixed-interface modes: K_ii phi = lambda M_ii phi below the cut-off, on the
/// interior DOFs (interior model's numbering), certified by the Sturm count when solved.
/// They depend on the interior model only (the mesh, material, surface masses, fixed and
/// interface node sets), not on the interface shapes.
#[derive(Clone, Debug, PartialEq)]
pub struct FixedModes {
    pub lambdas: Vec<f64>,
    /// Interior DOFs x modes, M_ii-orthonormal.
    pub vectors: Mat<f64>,
}

impl FixedModes {
    /// A copy of `lambdas` and `vectors`.
    fn of(lambdas: &[f64], vectors: &Mat<f64>) -> Self {
        Self {
            lambdas: lambdas.to_vec(),
            vectors: vectors.clone(),
        }
    }
}

/// Settings of one reduction.
pub struct CbSettings {
    pub cutoff_hz: f64,
    pub keep_basis: bool,
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

/// Held by a running reduction: reductions in one process run one after the other. Two at
/// once (tests side by side, or a library user's threads) gave a part that differed from the
/// same part reduced alone (system frequencies up to 1.1e-6 relative apart, in 1 of 2 local
/// runs of tests/rom.rs and in a CI run; the state the two shared is not found), while one
/// reduction at a time is the same to the last bit from run to run, in one process or several,
/// and on 1 or 2 threads (3 of 3 runs after this lock). Each reduction keeps both cores through
/// its own column-block parallelism; the command line reduces one part at a time anyway.
static REDUCING: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Reduces one part: the basis Phi = [Phi_c | Phi_n | Phi_a] of the module doc, built on the
/// full model (the part's own fixed sets) and the interior model (interfaces fixed too), and
/// K_r = Phi^T K Phi, M_r = Phi^T M Phi with the basis's rows at the outputs and Phi^T f of
/// the loads.
pub fn reduce(p: &Part<'_>, settings: &CbSettings) -> Result<PartReduction, ReduceError> {
    reduce_with(p, settings, None)
}

/// [`reduce`] with the fixed-interface modes `known` of an earlier reduction of the same
/// interior model at the same cut-off (the same part with other interface shapes: the second
/// pass of enriched cuts), used instead of the Sturm count and the eigen-solve; modes that do
/// not fit the interior model are refused and solved for.
pub fn reduce_with(
    p: &Part<'_>,
    settings: &CbSettings,
    known: Option<FixedModes>,
) -> Result<PartReduction, ReduceError> {
    // one reduction at a time per process (see [`REDUCING`])
    let _one = REDUCING.lock().unwrap_or_else(|e| e.into_inner());
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
    let t_inner = Instant::now();
    let inner = full.restrict(&sets).map_err(err_model)?;
    let (na, nb) = (full.n_free(), inner.n_free());
    tick(&format!(
        "assembled: {na} DOFs, {nb} interior (assembly {:.2} s, ordering and analysis {:.2} s, interior {:.2} s)",
        full.timings.assembly,
        full.timings.ordering,
        t_inner.elapsed().as_secs_f64()
    ));
    let llt = inner
        .analysis
        .llt(&inner.km.pattern, &inner.km.k)
        .map_err(|e| err_model(e.into()))?;
    let (lambdas, modes_b) = interior_modes(p, (&inner, &llt), settings.cutoff_hz, known, &tick)?;
    let b_to_a = interior_to_full(&full, &inner);
    let mass = full.km.pattern.compress(&full.km.m);
    let boundary = boundary_dofs(na, &b_to_a);
    let interior = Interior {
        full: &full,
        mass: &mass,
        boundary: &boundary,
        llt: &llt,
        b_to_a: &b_to_a,
        lambdas: &lambdas,
        modes: &modes_b,
    };
    let (nc, nl) = (
        p.interfaces.iter().map(|b| b.psi.ncols()).sum::<usize>(),
        p.loads.len(),
    );
    let nm = lambdas.len();
    // one dense block holds the basis as it is built: [Phi_c | Phi_n | U], U the attachment
    // candidates, later replaced in place by the kept, M-orthonormal Phi_a
    let mut phi = crate::linalg::touch::zeros_mat(na, nc + nm + nl + nc);
    let interface_cols = constraint_modes(p, &interior, phi.as_mut().subcols_mut(0, nc));
    tick(&format!("{nc} constraint modes"));
    for j in 0..nm {
        for bi in 0..nb {
            phi[(b_to_a[bi], nc + j)] = modes_b[(bi, j)];
        }
    }
    let f_a = load_matrix(&full, p.loads);
    let (known, candidates) = phi.as_mut().split_at_col_mut(nc + nm);
    attachment_candidates(&interior, &f_a, known.as_ref().subcols(0, nc), candidates);
    tick(&format!("{} attachment candidates", nl + nc));
    drop(llt);
    let na_cols = orthonormalise_attachments(part, &mass, &mut phi, nc + nm)?;
    let nr = nc + nm + na_cols;
    let (k, m) = project(&full, &mass, &b_to_a, &lambdas, phi.as_ref(), nc);
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
        fixed_modes: settings
            .keep_basis
            .then(|| FixedModes::of(&lambdas, &modes_b)),
        dofs: full.dofs.clone(),
        stats,
    })
}

/// The fixed-interface modes of the interior model `inner` (factor `llt`): `known` when they
/// fit it (one row per interior DOF, one column per eigenvalue), else solved for
/// ([`fixed_interface_modes`]).
fn interior_modes(
    p: &Part<'_>,
    (inner, llt): (&FeModel, &crate::linalg::factor::Llt<'_>),
    cutoff_hz: f64,
    known: Option<FixedModes>,
    tick: &dyn Fn(&str),
) -> Result<(Vec<f64>, Mat<f64>), ReduceError> {
    let nb = inner.n_free();
    let known = known.filter(|m| {
        let fits = m.vectors.nrows() == nb && m.vectors.ncols() == m.lambdas.len();
        if !fits {
            log::warn!(
                "[{}] the earlier fixed-interface modes do not fit the interior model ({} rows, {nb} interior DOFs): solving for them",
                p.name,
                m.vectors.nrows()
            );
        }
        fits
    });
    if let Some(m) = known {
        tick(&format!(
            "factorised; {} fixed-interface modes reused",
            m.lambdas.len()
        ));
        return Ok((m.lambdas, m.vectors));
    }
    let solved = fixed_interface_modes(p, inner, llt, cutoff_hz, tick)?;
    tick("modes");
    Ok(solved)
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
/// shift-invert Lanczos on the factor of K_ii and certified by that count (all of them must
/// come out below the cut-off; a skipped mode is solved for again, up to [`RESOLVES`] times);
/// refused when the Lanczos vectors would not fit in memory or the cut-off takes in more than
/// a quarter of the spectrum. Returns the eigenvalues and the modes (interior DOFs x modes).
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
    let product = crate::linalg::tripled::Product::owning(inner.km.pattern.compress(&inner.km.m));
    // certified by the count: the `count` lowest computed must all lie below the cut-off (a
    // mode the iteration skipped shows as one above it); else solved again with a margin and
    // another start vector
    let mut missed = 0;
    for attempt in 0..=RESOLVES {
        let mut settings = EigenSettings::new((count + missed).min(nb - 1), 0.0);
        settings.seed = attempt as u64;
        let modes = solve_modes(
            nb,
            &settings,
            |x, y| product.apply(x, y),
            |x| llt.solve_vec(x),
        )
        .map_err(|source| ReduceError::Eigen {
            part: part.to_string(),
            source,
        })?;
        log::info!("[{part}] {}", modes.work_summary());
        let below = modes
            .eigenvalues
            .iter()
            .filter(|&&l| l <= omega_c2 * (1.0 + 1e-9))
            .count();
        if below >= count {
            let mat = Mat::from_fn(nb, count, |i, j| modes.vectors[j * nb + i]);
            return Ok((modes.eigenvalues[..count].to_vec(), mat));
        }
        log::warn!(
            "[{part}] the Sturm count finds {count} fixed-interface modes below the cut-off, the Lanczos solve {below}: solving again"
        );
        missed = (count - below).max(missed) + 4;
    }
    Err(ReduceError::Other {
        part: part.to_string(),
        msg: format!(
            "the fixed-interface modes below the cut-off could not all be found: the Sturm count gives {count}, {} solves found fewer",
            RESOLVES + 1
        ),
    })
}

/// Solves again after a fixed-interface mode was missed: at most this many times.
const RESOLVES: usize = 2;

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

/// The DOFs of a model with `na` DOFs that `b_to_a` does not map to (the boundary), ascending.
fn boundary_dofs(na: usize, b_to_a: &[usize]) -> Vec<usize> {
    let mut interior = vec![false; na];
    for &a in b_to_a {
        interior[a] = true;
    }
    (0..na).filter(|&a| !interior[a]).collect()
}

/// Columns per block of right-hand sides: a 64-column block solve costs about a tenth per
/// column of a single-vector solve (the factor is read once per block).
const PANEL: usize = 64;

/// Constraint modes written into `phi_c` (full DOFs x interface shapes, zero on entry): the
/// boundary displaced by one interface shape psi, the interior in static equilibrium
/// u_i = -K_ii^-1 K_ib psi, solved in blocks of [`PANEL`] columns on both cores. Returns each
/// interface's columns.
fn constraint_modes(
    p: &Part<'_>,
    interior: &Interior<'_>,
    mut phi_c: MatMut<'_, f64>,
) -> Vec<Range<usize>> {
    let full = interior.full;
    let mut interface_cols = Vec::new();
    let mut col = 0;
    for b in p.interfaces {
        let nodes = p.mesh.node_set(&b.set).expect("checked by interior_sets");
        for j in 0..b.psi.ncols() {
            for (a, &node) in nodes.iter().enumerate() {
                for i in 0..3 {
                    let d = full.dofs.dof[3 * node + i];
                    if d != FIXED {
                        phi_c[(d, col + j)] = b.psi[(3 * a + i, j)];
                    }
                }
            }
        }
        interface_cols.push(col..col + b.psi.ncols());
        col += b.psi.ncols();
    }
    phi_c.par_col_chunks_mut(PANEL).for_each(|mut panel| {
        let mut rhs = interior.boundary_load(panel.as_ref());
        interior.llt.solve_in_place(rhs.as_mut());
        interior.scatter(rhs.as_ref(), panel.as_mut());
    });
    interface_cols
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

/// The interior problem the constraint and attachment modes are solved on.
struct Interior<'a> {
    full: &'a FeModel,
    /// The full model's M without its zero entries ([`Pattern::compress`]).
    mass: &'a SymCsc,
    /// The full model's DOFs that are not interior, ascending.
    boundary: &'a [usize],
    llt: &'a crate::linalg::factor::Llt<'a>,
    b_to_a: &'a [usize],
    lambdas: &'a [f64],
    /// Fixed-interface modes (interior DOFs x modes).
    modes: &'a Mat<f64>,
}

impl Interior<'_> {
    /// -K_ib X_b, the interior rows of -K X for a block X over the full DOFs that vanishes
    /// on the interior (constraint-mode loads), from the entries of K that couple the interior
    /// with the boundary alone (a twentieth of K's on the default crankcase): each row sums
    /// its boundary terms in its stored order, the terms a full product would add to zero
    /// left out (the same bits).
    fn boundary_load(&self, x: MatRef<'_, f64>) -> Mat<f64> {
        let (pattern, kv) = (&self.full.km.pattern, &self.full.km.k);
        let mut on_boundary = vec![false; self.full.n_free()];
        for &d in self.boundary {
            on_boundary[d] = true;
        }
        // the interior rows coupled to the boundary (column d holds row d: both triangles)
        let mut touched: Vec<usize> = self
            .boundary
            .iter()
            .flat_map(|&d| &pattern.row_idx[pattern.col_ptr[d]..pattern.col_ptr[d + 1]])
            .copied()
            .filter(|&a| !on_boundary[a])
            .collect();
        touched.sort_unstable();
        touched.dedup();
        let mut a_to_b = vec![usize::MAX; self.full.n_free()];
        for (b, &a) in self.b_to_a.iter().enumerate() {
            a_to_b[a] = b;
        }
        let mut y = Mat::<f64>::zeros(self.b_to_a.len(), x.ncols());
        for j in 0..x.ncols() {
            for &a in &touched {
                let mut sum = 0.0;
                for q in pattern.col_ptr[a]..pattern.col_ptr[a + 1] {
                    let d = pattern.row_idx[q];
                    if on_boundary[d] {
                        sum += kv[q] * x[(d, j)];
                    }
                }
                y[(a_to_b[a], j)] = -sum;
            }
        }
        y
    }

    /// The interior rows of a block over the full model's DOFs.
    fn gather(&self, x: MatRef<'_, f64>) -> Mat<f64> {
        Mat::from_fn(self.b_to_a.len(), x.ncols(), |bi, j| {
            x[(self.b_to_a[bi], j)]
        })
    }
    /// Writes interior rows into a block over the full model's DOFs.
    fn scatter(&self, x: MatRef<'_, f64>, mut y: MatMut<'_, f64>) {
        for j in 0..x.ncols() {
            for (bi, &a) in self.b_to_a.iter().enumerate() {
                y[(a, j)] = x[(bi, j)];
            }
        }
    }
}

/// Residual attachment candidates written into `u` (full DOFs x (loads + constraint modes),
/// zero on entry): for each load column f (the attachment loads `f_a`, then the inertia loads
/// M Phi_c of the constraint modes, the modal-truncation augmentation)
/// u = K_ii^-1 f - Phi_n Lambda^-1 Phi_n^T f on the interior, zero on the boundary; in blocks
/// of [`PANEL`] columns on both cores. The MTA columns carry the quasi-static inertia of the
/// interface motion that the truncated fixed-interface modes miss, lifting CB accuracy from
/// O((f/f_c)^2) towards O((f/f_c)^4).
fn attachment_candidates(
    interior: &Interior<'_>,
    f_a: &Mat<f64>,
    phi_c: MatRef<'_, f64>,
    u: MatMut<'_, f64>,
) {
    let full = interior.full;
    let nl = f_a.ncols();
    let (lambdas, modes_b) = (interior.lambdas, interior.modes);
    u.par_col_chunks_mut(PANEL)
        .enumerate()
        .for_each(|(p, mut panel)| {
            let (j0, w) = (p * PANEL, panel.ncols());
            // the panel's loads over the full DOFs: columns of f_a, then M Phi_c
            let mut f = Mat::<f64>::zeros(full.n_free(), w);
            let n_loads = nl.saturating_sub(j0).min(w);
            f.as_mut()
                .subcols_mut(0, n_loads)
                .copy_from(f_a.as_ref().subcols(j0.min(nl), n_loads));
            if n_loads < w {
                let c0 = j0 + n_loads - nl;
                let mphi = sparse_times(
                    &interior.mass.pattern,
                    &interior.mass.values,
                    phi_c.subcols(c0, w - n_loads),
                );
                f.as_mut()
                    .subcols_mut(n_loads, w - n_loads)
                    .copy_from(&mphi);
            }
            let f_b = interior.gather(f.as_ref());
            drop(f);
            let mut x = f_b.clone();
            interior.llt.solve_in_place(x.as_mut());
            if !lambdas.is_empty() {
                // u -= Phi_n Lambda^-1 Phi_n^T f
                let mut pf = modes_b.transpose() * &f_b;
                for (r, lam) in lambdas.iter().enumerate() {
                    for j in 0..w {
                        pf[(r, j)] /= lam;
                    }
                }
                matmul(
                    x.as_mut(),
                    Accum::Add,
                    modes_b.as_ref(),
                    pf.as_ref(),
                    -1.0,
                    Par::Seq,
                );
            }
            interior.scatter(x.as_ref(), panel.as_mut());
        });
}

/// M-orthonormalises the attachment candidates U, the columns `a0..` of `phi`, in place:
/// with D the diagonal that scales each to unit M-norm, through the eigen-decomposition
/// D U^T M U D = V S V^T of their scaled Gram matrix, keeping the directions above
/// [`gram_cut`] (nearly dependent candidates dropped), Phi_a = U D V_k S_k^-1/2,
/// computed one row block at a time over U's first columns; `phi` is truncated to
/// [.. | Phi_a]. Returns the number of kept columns.
fn orthonormalise_attachments(
    part: &str,
    mass: &SymCsc,
    phi: &mut Mat<f64>,
    a0: usize,
) -> Result<usize, ReduceError> {
    let nu = phi.ncols() - a0;
    if nu == 0 {
        return Ok(0);
    }
    let gram = lower_gram(&mass.pattern, &mass.values, phi.as_ref().subcols(a0, nu));
    // each candidate scaled to unit M-norm first: the loads' and the inertia loads' candidates
    // come in unrelated units, and a cut relative to the largest of them dropped inertia
    // directions that mattered (see [`GRAM_CUT`])
    let d: Vec<f64> = (0..nu)
        .map(|j| 1.0 / gram[(j, j)].max(f64::MIN_POSITIVE).sqrt())
        .collect();
    let gram = Mat::from_fn(nu, nu, |i, j| d[i] * gram[(i, j)] * d[j]);
    let evd = gram
        .self_adjoint_eigen(faer::Side::Lower)
        .map_err(|e| ReduceError::Other {
            part: part.into(),
            msg: format!("attachment modes: eigen-decomposition failed: {e:?}"),
        })?;
    let s = evd.S().column_vector();
    let mut order: Vec<usize> = (0..nu).collect();
    order.sort_by(|&i, &j| s[j].total_cmp(&s[i]));
    let sorted: Vec<f64> = order.iter().map(|&i| s[i]).collect();
    let mut keep: Vec<usize> = order[..gram_cut(&sorted)].to_vec();
    keep.sort_unstable();
    log::debug!(
        "{part}: {} of {nu} attachment directions kept (cut between {:.3e} and {:.3e} of the largest)",
        keep.len(),
        sorted.get(keep.len().wrapping_sub(1)).copied().unwrap_or(0.0) / sorted[0],
        sorted.get(keep.len()).copied().unwrap_or(0.0) / sorted[0]
    );
    let v = evd.U();
    let tr = Mat::from_fn(nu, keep.len(), |r, c| {
        d[r] * v[(r, keep[c])] / s[keep[c]].sqrt()
    });
    let nk = keep.len();
    let rows = phi.nrows();
    // row blocks in parallel, each product serial: the same bits on any number of threads
    phi.as_mut()
        .subcols_mut(a0, nu)
        .par_row_chunks_mut(1024)
        .for_each(|u| {
            let mut block = Mat::<f64>::zeros(u.nrows(), nk);
            matmul(
                block.as_mut(),
                Accum::Replace,
                u.as_ref(),
                tr.as_ref(),
                1.0,
                Par::Seq,
            );
            u.subcols_mut(0, nk).copy_from(&block);
        });
    phi.truncate(rows, a0 + nk);
    Ok(nk)
}

/// Cut of the Gram eigenvalues of the attachment candidates, each scaled to unit M-norm:
/// directions below carry less than 1e-3 of a candidate's norm (nearly dependent candidates).
///
/// Measured on the default engine (2026-11-26): with every candidate kept the first 20 system
/// frequencies move by at most 7e-8 relative from this cut's (2e-9 at a cut of 1e-8), and a
/// build whose single-vector solves sum in another order lands within 1e-10. The earlier cut,
/// 1e-10 relative to the largest *unscaled* candidate, mixed the point loads' scale with the
/// inertia loads' and dropped inertia directions worth 4e-5 in the frequencies; which of them
/// fell below it hung on roundoff (two orders of summation gave frequencies 2e-5 apart).
pub const GRAM_CUT: f64 = 1e-6;

/// The number of Gram eigenvalues kept (`s` sorted from the largest down): s_i > GRAM_CUT
/// max s (the largest is about 1 or more, the candidates having unit norm).
pub fn gram_cut(s: &[f64]) -> usize {
    let Some(&smax) = s.first() else {
        return 0;
    };
    s.iter().take_while(|&&x| x > GRAM_CUT * smax).count()
}

/// K_r = Phi^T K Phi and M_r = Phi^T M Phi of the basis [Phi_c | Phi_n | Phi_a] (`nc`
/// constraint modes, the modes with eigenvalues `lambdas`, then the attachments) from its
/// structure, computing only the blocks that are not known:
///
/// K_r = diag(K_cc, Lambda, K_aa),   M_r = [[M_cc, M_cn, M_ca], [M_nc, I, 0], [M_ac, 0, I]].
///
/// K Phi_c vanishes on the interior (static equilibrium), so K_cn = K_ca = 0 and K_cc needs
/// only the boundary rows: K_cc = (K Phi_c)_B^T (Phi_c)_B. Phi_n and Phi_a vanish on the
/// boundary; K_ii phi = lambda M_ii phi with phi^T M_ii phi = 1 gives K_nn = Lambda, M_nn = I;
/// the attachments are M-orthogonal to the modes (Phi_n^T M_ii K_ii^-1 f = Lambda^-1 Phi_n^T f)
/// and K_ii-orthogonal to them likewise, so K_na = M_na = 0, and M-orthonormal: M_aa = I.
/// Each known block holds to the solves' and the eigen-solve's residuals (checked against
/// the brute-force products in tests/rom.rs).
fn project(
    full: &FeModel,
    mass: &SymCsc,
    b_to_a: &[usize],
    lambdas: &[f64],
    phi: MatRef<'_, f64>,
    nc: usize,
) -> (Mat<f64>, Mat<f64>) {
    let (na, nm, nr) = (full.n_free(), lambdas.len(), phi.ncols());
    let (pattern, kv) = (&full.km.pattern, &full.km.k);
    let (mp, mv) = (&mass.pattern, &mass.values);
    let na_cols = nr - nc - nm;
    let (phi_c, phi_a) = (phi.subcols(0, nc), phi.subcols(nc + nm, na_cols));
    let boundary = boundary_dofs(na, b_to_a);
    let mut k = Mat::<f64>::zeros(nr, nr);
    let mut m = Mat::<f64>::zeros(nr, nr);
    // K_cc from the boundary rows of K Phi_c (column d of K is its row d: both triangles stored)
    let mut k_phi_b = Mat::<f64>::zeros(boundary.len(), nc);
    k_phi_b
        .as_mut()
        .par_col_chunks_mut(PANEL)
        .enumerate()
        .for_each(|(p, mut col)| {
            for j in 0..col.ncols() {
                for (r, &d) in boundary.iter().enumerate() {
                    col[(r, j)] = (pattern.col_ptr[d]..pattern.col_ptr[d + 1])
                        .map(|q| kv[q] * phi_c[(pattern.row_idx[q], p * PANEL + j)])
                        .sum::<f64>();
                }
            }
        });
    let phi_b = Mat::from_fn(boundary.len(), nc, |r, j| phi_c[(boundary[r], j)]);
    let mut k_cc = k_phi_b.transpose() * &phi_b;
    symmetrise(&mut k_cc);
    k.as_mut().submatrix_mut(0, 0, nc, nc).copy_from(&k_cc);
    for (j, &lam) in lambdas.iter().enumerate() {
        k[(nc + j, nc + j)] = lam;
    }
    k.as_mut()
        .submatrix_mut(nc + nm, nc + nm, na_cols, na_cols)
        .copy_from(&lower_gram(pattern, kv, phi_a));
    // M: the constraint modes' rows, the identities
    m.as_mut()
        .submatrix_mut(0, 0, nc, nc)
        .copy_from(&lower_gram(mp, mv, phi_c));
    let m_rest = cross_gram(mp, mv, phi_c, phi.subcols(nc, nm + na_cols));
    m.as_mut()
        .submatrix_mut(0, nc, nc, nm + na_cols)
        .copy_from(&m_rest);
    m.as_mut()
        .submatrix_mut(nc, 0, nm + na_cols, nc)
        .copy_from(m_rest.transpose());
    for j in nc..nr {
        m[(j, j)] = 1.0;
    }
    (k, m)
}

/// X^T A Y for a symmetric sparse A and dense blocks X, Y, in blocks of [`PANEL`] columns of Y
/// on both cores (each block serial: the same bits on any number of threads).
fn cross_gram(
    pattern: &Pattern,
    values: &[f64],
    x: MatRef<'_, f64>,
    y: MatRef<'_, f64>,
) -> Mat<f64> {
    let mut c = Mat::<f64>::zeros(x.ncols(), y.ncols());
    c.as_mut()
        .par_col_chunks_mut(PANEL)
        .enumerate()
        .for_each(|(p, mut col)| {
            let (j0, w) = (p * PANEL, col.ncols());
            let ay = sparse_times(pattern, values, y.subcols(j0, w));
            matmul(
                col.as_mut(),
                Accum::Replace,
                x.transpose(),
                ay.as_ref(),
                1.0,
                Par::Seq,
            );
        });
    c
}

/// X^T A X for a symmetric sparse A and a dense block X, in blocks of [`PANEL`] columns on both
/// cores: each block j gives Y_j = A X_j and the block column (X^T A X)_{i >= j, j} =
/// X_{i >= j}^T Y_j (the lower triangle, half the products); the upper triangle is the
/// mirror, the diagonal blocks averaged with their transposes.
fn lower_gram(pattern: &Pattern, values: &[f64], x: MatRef<'_, f64>) -> Mat<f64> {
    let nr = x.ncols();
    let mut c = Mat::<f64>::zeros(nr, nr);
    c.as_mut()
        .par_col_chunks_mut(PANEL)
        .enumerate()
        .for_each(|(p, mut col)| {
            let (j0, w) = (p * PANEL, col.ncols());
            let y = sparse_times(pattern, values, x.subcols(j0, w));
            matmul(
                col.as_mut().subrows_mut(j0, nr - j0),
                Accum::Replace,
                x.subcols(j0, nr - j0).transpose(),
                y.as_ref(),
                1.0,
                Par::Seq,
            );
        });
    for j in 0..nr {
        for i in j + 1..nr {
            let v = if i / PANEL == j / PANEL {
                0.5 * (c[(i, j)] + c[(j, i)])
            } else {
                c[(i, j)]
            };
            c[(i, j)] = v;
            c[(j, i)] = v;
        }
    }
    c
}

/// With debug logging: the extreme eigenvalues of K_r and M_r scaled by M_r's diagonal (a
/// conditioning diagnostic of the basis). Computed only then: two dense eigenvalue solves of
/// the reduced size (0.5 s for the default crankcase), which `-v` (info) used to pay for a
/// line it did not print.
fn log_conditioning(part: &str, k: &Mat<f64>, m: &Mat<f64>) {
    if !log::log_enabled!(log::Level::Debug) {
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
    log::debug!(
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

/// A X for a symmetric sparse A and a dense block X.
fn sparse_times(pattern: &Pattern, values: &[f64], x: MatRef<'_, f64>) -> Mat<f64> {
    let mut y = Mat::<f64>::zeros(x.nrows(), x.ncols());
    pattern.mul_dense(values, x, y.as_mut());
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

#[cfg(test)]
mod tests {
    use super::{gram_cut, GRAM_CUT};

    /// The threshold relative to the largest; an empty or one-value spectrum keeps everything
    /// it has; negative (roundoff) eigenvalues are dropped.
    #[test]
    fn verification_gram_cut_is_relative_to_the_largest() {
        assert_eq!(gram_cut(&[1.0, 0.5, 1e-3, 1e-14, 1e-15]), 3);
        assert_eq!(gram_cut(&[2.0]), 1);
        assert_eq!(gram_cut(&[]), 0);
        assert_eq!(gram_cut(&[1.0, 10.0 * GRAM_CUT, -1e-12]), 2);
        assert_eq!(gram_cut(&[1.0, 0.1 * GRAM_CUT]), 1);
    }
}
