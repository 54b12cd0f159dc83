//! Cut shapes enriched from a first assembly's force imbalance at the cuts.
//!
//! The slab's shapes make a cut's coupling exact only in their span; what the span misses of
//! the part's own low-frequency fields shows as a force imbalance at the cut. A first pass
//! reduces the components with the slab's shapes and assembles them (K_A, M_A in coordinates
//! [b | i], [`super::assemble`]). Its low-frequency fields are the columns of
//!
//!   V = [[I, 0], [X, Phi_k]],  X = -K_ii^-1 K_ib,  K_ii Phi_k = M_ii Phi_k Lambda_k,
//!
//! the static shapes of the part's interfaces and the assembled interior's modes up to the
//! cut-off (lambda = 0 for the static columns). Column v, mapped onto component c's DOFs by
//! its basis (u_c = Phi_c y_c), leaves at cut j the force imbalance
//!
//!   r_j = sum over the cut's two components of (K_c u_c - lambda M_c u_c) on the cut's DOFs,
//!
//! which the shapes cannot see (Psi_j^T r_j = 0 is the assembly's equilibrium; it holds the
//! cut's rigid motions, so r_j is self-equilibrated). The slab's response to it,
//! d_j = K_s^-1 r_j (the slab's near-static shifted factor, as for its modes), traced on the cut
//! with the shapes' span removed, is the part of v's trace the shapes miss. Each correction is
//! scaled by the size of v's own trace on the cut (a relative error), and the leading left
//! singular vectors of the scaled corrections, `enrichment` of them (directions below 1e-6 of
//! the largest dropped), are added to the cut's shapes. The components are then reduced again
//! with the enriched shapes (the second pass is what the part's reduction uses). A
//! component's fixed-interface modes do not depend on its cut shapes (every cut node is held
//! in its interior model), so the first pass leaves them in a [`ModeStore`] and the second
//! pass reads them instead of solving again: it factorises K_ii once for the constraint and
//! attachment modes and skips the Sturm count and the Lanczos solves.
//!
//! Measured (benches/RESULTS.md, session 76): the default engine in 3 components with 200
//! slab shapes per cut, system frequencies below half the cut-off against the one-piece
//! build: worst 5.1e-3, median 3.3e-4; with 100 shapes added per cut 2.1e-5 and 3.7e-6, MAC
//! >= 0.99994 for all 64 modes; 300 slab shapes alone do not come close.
//!
//! The enriched shapes depend on the whole part (every component's first pass), so they are
//! cached under the part's own key with the split's settings: a later build with the same
//! crankcase, or a component task of a job array, reads them instead of repeating the first
//! pass.

use super::{assemble, component, Interior, Prepared, Slab, Split};
use crate::fem::dofs::FIXED;
use crate::fem::model::FeModel;
use crate::reduce::craig_bampton::{CbSettings, Part, PartReduction, ReduceError};
use crate::reduce::part_cache::{cached_matrices, ModeStore, PartCacheError};
use faer::Mat;
use rayon::prelude::*;
use std::path::Path;
use std::time::Instant;

/// Replaces each cut's shapes in `prep` by the enriched ones (module doc): from the cache
/// `dir` when every cut's entry is there, else computed by a first pass over all components
/// (and stored), which leaves each component's fixed-interface modes in `modes` for the
/// second pass.
pub(super) fn enrich(
    p: &Part<'_>,
    prep: &mut Prepared,
    split: &Split,
    (settings, dir): (&CbSettings, Option<&Path>),
    modes: &ModeStore,
) -> Result<(), PartCacheError> {
    let key = enriched_key(p, split, settings);
    let files: Vec<String> = (0..prep.cuts.len())
        .map(|j| format!("cut-{}-{}-enriched", p.name, j + 1))
        .collect();
    let (shapes, _) = cached_matrices(dir, &files, &key, || {
        // a component task prepared its own cuts only
        if prep.cut_psi.iter().any(|m| m.ncols() == 0) {
            *prep = super::prepare(p, split, dir, &|_| true)?;
        }
        enriched_shapes(p, prep, split, settings.cutoff_hz, modes)
    })?;
    prep.cparts = super::component_parts(p, &prep.comps, &shapes)?;
    prep.cut_psi = shapes;
    Ok(())
}

/// Cache key of a part's enriched cut shapes: the part's own reduction key at the cut-off with
/// the split's settings and the method's constants.
fn enriched_key(p: &Part<'_>, split: &Split, settings: &CbSettings) -> String {
    let part = crate::reduce::part_cache::key(
        p,
        &CbSettings {
            cutoff_hz: settings.cutoff_hz,
            keep_basis: false,
        },
    );
    let mut h = blake3::Hasher::new();
    h.update(b"enriched cut shapes 1");
    h.update(part.as_bytes());
    let mut nums = vec![
        split.cut_shapes as f64,
        split.component_cutoff_factor,
        split.enrichment as f64,
        super::SLAB_LAYERS as f64,
        super::SUBSPACE_PASSES as f64,
        SINGULAR_CUT,
        COMPRESS,
    ];
    nums.extend(&split.cuts_x);
    for v in nums {
        h.update(&v.to_le_bytes());
    }
    h.finalize().to_hex()[..32].to_string()
}

/// Directions of the scaled corrections below this fraction of the largest singular value
/// are not added (they carry nothing the shapes lack).
const SINGULAR_CUT: f64 = 1e-6;

/// A component's cut rows from its first pass: for each of its cuts (by index), the cut DOFs'
/// rows of K Phi and M Phi (3 rows per cut node, zero where fixed).
type CutRows = Vec<(usize, Mat<f64>, Mat<f64>)>;

/// The enriched shapes of every cut (module doc) from a first pass with `prep`'s (slab)
/// shapes.
fn enriched_shapes(
    p: &Part<'_>,
    prep: &Prepared,
    split: &Split,
    cutoff_hz: f64,
    modes: &ModeStore,
) -> Result<Vec<Mat<f64>>, PartCacheError> {
    let t0 = Instant::now();
    let slab_psi = &prep.cut_psi;
    let mut reductions = Vec::with_capacity(prep.comps.len());
    let mut passes = Vec::with_capacity(prep.comps.len());
    for c in 0..prep.comps.len() {
        let (r, rows) = first_pass(p, prep, c, cutoff_hz * split.component_cutoff_factor, modes)?;
        reductions.push(r);
        passes.push(rows);
    }
    let t_first = t0.elapsed().as_secs_f64();
    let a = assemble(p, &prep.cparts, &reductions, slab_psi);
    let inner = Interior::of(p.name, &a, cutoff_hz)?;
    let (v, lambdas) = low_fields(&a, &inner);
    let t_fields = t0.elapsed().as_secs_f64() - t_first;
    let mut out = Vec::with_capacity(prep.cuts.len());
    for (j, psi) in slab_psi.iter().enumerate() {
        let r = imbalance((j, psi.nrows()), &a, &passes, (&v, &lambdas));
        let traces = super::ab(
            psi.as_ref(),
            v.as_ref().subrows(a.cut_cols[j].start, a.cut_cols[j].len()),
        );
        let added = added_shapes(p, prep, j, (&r, &traces), split.enrichment)?;
        out.push(added);
    }
    log::info!(
        "[{}] cut shapes enriched by {} ({}) from {} fields in {:.2} s (first pass {t_first:.2} s, assembly and fields {t_fields:.2} s, the cuts' slab solves {:.2} s)",
        p.name,
        split.enrichment,
        crate::text::joined(
            &out.iter()
                .zip(slab_psi)
                .map(|(m, s)| m.ncols() - s.ncols())
                .collect::<Vec<_>>(),
            ", "
        ),
        v.ncols(),
        t0.elapsed().as_secs_f64(),
        t0.elapsed().as_secs_f64() - t_first - t_fields
    );
    Ok(out)
}

/// The force imbalance at cut `j` (of `rows` rows) of every field of `v` (columns, eigenvalues `lambdas`):
/// r = sum over the cut's components of (K Phi_c - lambda M Phi_c) y_c on the cut's rows, y_c
/// the field's coordinates of component c in the assembly `a`.
fn imbalance(
    (j, rows): (usize, usize),
    a: &super::Assembled,
    passes: &[CutRows],
    (v, lambdas): (&Mat<f64>, &[f64]),
) -> Mat<f64> {
    let mut r = Mat::<f64>::zeros(rows, v.ncols());
    for (c, pass) in passes.iter().enumerate() {
        let y = Mat::from_fn(a.maps[c].len(), v.ncols(), |i, k| v[(a.maps[c][i], k)]);
        for (_, kr, mr) in pass.iter().filter(|(cut, _, _)| *cut == j) {
            let mut my = super::ab(mr.as_ref(), y.as_ref());
            for (k, lam) in lambdas.iter().enumerate() {
                my.col_mut(k).iter_mut().for_each(|x| *x *= lam);
            }
            r += super::ab(kr.as_ref(), y.as_ref()) - my;
        }
    }
    r
}

/// Component `c`'s reduction with its basis kept, the basis's cut rows of K Phi and M Phi
/// taken, the basis dropped, its fixed-interface modes stored in `modes` for the second pass.
fn first_pass(
    p: &Part<'_>,
    prep: &Prepared,
    c: usize,
    cutoff_hz: f64,
    modes: &ModeStore,
) -> Result<(PartReduction, CutRows), PartCacheError> {
    let sub = component(p, prep, c);
    let settings = CbSettings {
        cutoff_hz,
        keep_basis: true,
    };
    let mut reduction = crate::reduce::craig_bampton::reduce(&sub, &settings)?;
    let t0 = Instant::now();
    let phi = reduction.basis.take().expect("the basis was asked for");
    let model = FeModel::build_with(sub.mesh.clone(), p.material, sub.fix, p.surface).map_err(
        |source| ReduceError::Model {
            part: sub.name.into(),
            source,
        },
    )?;
    let comp = &prep.comps[c];
    let cut_rows = [c.checked_sub(1), (c < prep.cuts.len()).then_some(c)]
        .into_iter()
        .flatten()
        .map(|j| {
            let dofs = cut_dofs(&model.dofs.dof, &comp.nodes, &prep.cuts[j]);
            let km = &model.km;
            (
                j,
                rows_times(&km.pattern, &km.k, &dofs, &phi),
                rows_times(&km.pattern, &km.m, &dofs, &phi),
            )
        })
        .collect();
    drop(phi);
    let fixed = reduction.fixed_modes.take().expect("kept with the basis");
    modes.save(&sub, cutoff_hz, &fixed)?;
    log::info!(
        "[{}] cut rows taken and {} modes stored in {:.2} s",
        sub.name,
        fixed.lambdas.len(),
        t0.elapsed().as_secs_f64()
    );
    Ok((reduction, cut_rows))
}

/// The DOF of every cut node (part numbering, `cut`) and direction in a model of the nodes
/// `nodes` (part numbering, ascending) with DOF map `dof`: 3 per node, [`FIXED`] where held.
fn cut_dofs(dof: &[usize], nodes: &[usize], cut: &[usize]) -> Vec<usize> {
    cut.iter()
        .flat_map(|n| {
            let local = nodes
                .binary_search(n)
                .expect("a cut node lies in its model");
            (0..3).map(move |i| dof[3 * local + i])
        })
        .collect()
}

/// Rows `dofs` of A X for a symmetric sparse A (both triangles stored: column d holds row d),
/// a zero row where the DOF is [`FIXED`].
fn rows_times(
    pattern: &crate::linalg::sparse::Pattern,
    values: &[f64],
    dofs: &[usize],
    x: &Mat<f64>,
) -> Mat<f64> {
    let mut out = Mat::<f64>::zeros(dofs.len(), x.ncols());
    // column blocks on both cores, each column of x read where it is contiguous
    out.par_col_chunks_mut(16)
        .enumerate()
        .for_each(|(b, mut block)| {
            for j in 0..block.ncols() {
                let k = 16 * b + j;
                for (r, &d) in dofs.iter().enumerate().filter(|(_, &d)| d != FIXED) {
                    let mut sum = 0.0;
                    for q in pattern.col_ptr[d]..pattern.col_ptr[d + 1] {
                        sum += values[q] * x[(pattern.row_idx[q], k)];
                    }
                    block[(r, j)] = sum;
                }
            }
        });
    out
}

/// The imbalances `r` (one column per field) each scaled by its field's trace size (2-norm of
/// the column of `traces`; a field without a trace is dropped), compressed to their numerical
/// range: R D = U S V^T, returned as U_k S_k over the singular values above [`COMPRESS`] of the
/// largest. The slab's response is linear, so the corrections T = A R D (A: solve, trace,
/// remove the shapes' span) equal (A U_k S_k) V_k^T up to the dropped part, and V_k has
/// orthonormal rows: T's left singular vectors and values are those of A U_k S_k. The slab
/// then answers rank-many right-hand sides, not one per field (the default engine in 3
/// components: 552 of 990, the rest below 1e-12 of the largest).
fn compressed(part: &str, r: &Mat<f64>, traces: &Mat<f64>) -> Result<Mat<f64>, ReduceError> {
    let scale: Vec<f64> = (0..r.ncols())
        .map(|k| {
            let size = traces.col(k).norm_l2();
            if size > 0.0 {
                1.0 / size
            } else {
                0.0
            }
        })
        .collect();
    let scaled = Mat::from_fn(r.nrows(), r.ncols(), |i, k| r[(i, k)] * scale[k]);
    let svd = scaled.thin_svd().map_err(|e| ReduceError::Other {
        part: part.into(),
        msg: format!("substructuring: the cut imbalances' SVD failed: {e:?}"),
    })?;
    let s = svd.S().column_vector();
    let smax = (0..s.nrows()).map(|i| s[i]).fold(0.0f64, f64::max);
    let kept: Vec<usize> = (0..s.nrows()).filter(|&i| s[i] > COMPRESS * smax).collect();
    let u = svd.U();
    Ok(Mat::from_fn(r.nrows(), kept.len(), |i, c| {
        u[(i, kept[c])] * s[kept[c]]
    }))
}

/// Singular values of the scaled imbalances below this fraction of the largest are roundoff
/// (the measured spectrum falls from above 1e-8 to below 1e-12 with nothing between).
const COMPRESS: f64 = 1e-12;

/// The assembled model's low-frequency fields V = [[I, 0], [X, Phi_k]] (columns) and their
/// eigenvalues (0 for the static columns).
fn low_fields(a: &super::Assembled, inner: &Interior) -> (Mat<f64>, Vec<f64>) {
    let (n, nb, nk) = (a.k.nrows(), a.nb, inner.lambdas.len());
    let mut v = Mat::<f64>::zeros(n, nb + nk);
    for j in 0..nb {
        v[(j, j)] = 1.0;
    }
    v.as_mut()
        .submatrix_mut(nb, 0, n - nb, nb)
        .copy_from(&inner.x);
    v.as_mut()
        .submatrix_mut(nb, nb, n - nb, nk)
        .copy_from(&inner.phi_k);
    let mut lambdas = vec![0.0; nb];
    lambdas.extend(&inner.lambdas);
    (v, lambdas)
}

/// Cut `j`'s shapes with up to `count` added: the slab's near-static response to the
/// imbalances `r` (one column per field) each scaled by its field's trace `traces` (2-norm;
/// solved for their compressed range, [`compressed`]), traced on the cut, the present shapes'
/// span removed, then the leading left singular vectors (above [`SINGULAR_CUT`] of the
/// largest), each scaled to a largest entry of 1.
fn added_shapes(
    p: &Part<'_>,
    prep: &Prepared,
    j: usize,
    (r, traces): (&Mat<f64>, &Mat<f64>),
    count: usize,
) -> Result<Mat<f64>, ReduceError> {
    let cut = &prep.cuts[j];
    let psi = &prep.cut_psi[j];
    let slab = Slab::of(p, cut);
    let model =
        FeModel::build_with(slab.mesh.clone(), p.material, &slab.fix, &[]).map_err(|source| {
            ReduceError::Model {
                part: p.name.into(),
                source,
            }
        })?;
    let dofs = cut_dofs(&model.dofs.dof, &slab.nodes, cut);
    // a cut that keeps every DOF has nothing to add
    if psi.ncols() >= dofs.iter().filter(|&&d| d != FIXED).count() {
        return Ok(psi.clone());
    }
    let km = &model.km;
    let llt = model
        .analysis
        .llt(&km.pattern, &km.shifted(-1e-6 * km.eigenvalue_scale()))
        .map_err(|e| ReduceError::Model {
            part: p.name.into(),
            source: e.into(),
        })?;
    let loads = compressed(p.name, r, traces)?;
    let mut f = Mat::<f64>::zeros(model.n_free(), loads.ncols());
    for (row, &d) in dofs.iter().enumerate().filter(|(_, &d)| d != FIXED) {
        for k in 0..loads.ncols() {
            f[(d, k)] = loads[(row, k)];
        }
    }
    crate::eigen::subspace::solve_block(&llt, &mut f);
    let mut t = Mat::from_fn(dofs.len(), loads.ncols(), |row, k| {
        if dofs[row] == FIXED {
            0.0
        } else {
            f[(dofs[row], k)]
        }
    });
    let q = psi.qr().compute_thin_Q();
    t -= super::ab(q.as_ref(), super::atb(q.as_ref(), t.as_ref()).as_ref());
    let added = super::directions(p.name, "enriched cut shapes", &t, (SINGULAR_CUT, count))?;
    let mut out = Mat::<f64>::zeros(psi.nrows(), psi.ncols() + added.ncols());
    out.as_mut().subcols_mut(0, psi.ncols()).copy_from(psi);
    out.as_mut()
        .subcols_mut(psi.ncols(), added.ncols())
        .copy_from(&added);
    Ok(out)
}
