//! Rayleigh-Ritz bounds of the lowest eigenvalues from a block of trial vectors, with no
//! factorisation: the cheap first look at where the wanted modes lie.
//!
//! For a block X (n x p) the Ritz values of (K, M) on span(X) are the eigenvalues of
//! (X^T K X, X^T M X); by the Courant-Fischer minimax theorem the k-th of them bounds the
//! k-th eigenvalue of (K, M) from above, whatever X is. X^T M X is diagonalised first
//! (X^T M X = V D V^T) and directions with D_ii below [`DEPENDENT`] max D dropped, so a block
//! of nearly dependent columns (monomials on a slender part) loses directions, never the
//! bound: the values are those of a subspace of span(X).

use crate::fem::fields::SmoothFields;
use crate::linalg::sparse::{Pattern, StiffnessMass};
use faer::Mat;
use rayon::prelude::*;

/// Rows of A X formed per task by [`gram`].
pub const ROWS_PER_TASK: usize = 4096;

/// Directions of X^T M X below this fraction of its largest eigenvalue are dropped
/// (numerically dependent trial vectors: their Ritz values would be roundoff).
pub const DEPENDENT: f64 = 1e-10;

/// The `nev`-th Ritz value of (K, M) on the span of the smooth trial fields `x` (module
/// docs): an upper bound of lambda_nev. None when the span has fewer than `nev` independent
/// directions, its projection is not finite, or the value is roundoff around zero (every
/// wanted mode a rigid-body mode, [`TRIAL_ROUNDOFF`]).
pub fn trial_bound(km: &StiffnessMass, x: &SmoothFields, nev: usize) -> Option<f64> {
    if nev == 0 || x.count() < nev {
        return None;
    }
    let ritz = ritz_values(km, x)?;
    let top = ritz[ritz.len() - 1];
    // a value at roundoff (a rigid-body field's) bounds nothing a shift could move to
    ritz.get(nev - 1)
        .copied()
        .filter(|&b| b > TRIAL_ROUNDOFF * top.abs())
}

/// Ritz values at or below this fraction of the largest are roundoff around zero (the
/// rigid-body fields'): [`trial_bound`] gives none.
pub const TRIAL_ROUNDOFF: f64 = 1e-8;

/// The Ritz values of (K, M) on the span of `x`, ascending, over its independent directions
/// (module docs); None when X^T M X has no positive finite spectrum.
pub fn ritz_values(km: &StiffnessMass, x: &SmoothFields) -> Option<Vec<f64>> {
    let p = x.count();
    let (xkx, xmx) = (gram(&km.pattern, &km.k, x), gram(&km.pattern, &km.m, x));
    let finite = |a: &Mat<f64>| (0..p).all(|j| a.col(j).iter().all(|v| v.is_finite()));
    if !(finite(&xkx) && finite(&xmx)) {
        return None;
    }
    let evd = xmx.self_adjoint_eigen(faer::Side::Lower).ok()?;
    let (d, v) = (evd.S().column_vector(), evd.U());
    let top = (0..p).map(|i| d[i]).fold(0.0, f64::max);
    if !(top.is_finite() && top > 0.0) {
        return None;
    }
    let kept: Vec<usize> = (0..p).filter(|&i| d[i] > DEPENDENT * top).collect();
    // W = V_kept D_kept^-1/2: W^T (X^T M X) W = I; the Ritz values are eig(W^T X^T K X W)
    let w = Mat::from_fn(p, kept.len(), |i, j| v[(i, kept[j])] / d[kept[j]].sqrt());
    let reduced = w.transpose() * &xkx * &w;
    let sym = Mat::from_fn(kept.len(), kept.len(), |i, j| {
        0.5 * (reduced[(i, j)] + reduced[(j, i)])
    });
    let mut ritz = sym.self_adjoint_eigenvalues(faer::Side::Lower).ok()?;
    if ritz.is_empty() || !ritz.iter().all(|v| v.is_finite()) {
        return None;
    }
    ritz.sort_by(f64::total_cmp);
    Some(ritz)
}

/// X^T A X for A = `values` on `pattern` (both triangles) and the fields X = `x`, without
/// forming X: row r of A X is sum_c A_rc X_c, where row X_c holds the q monomials of c's node
/// in the columns of c's direction, so q multiply-adds per stored entry; then
/// X^T A X += X_r^T (A X)_r, row by row, rows on both cores in fixed blocks of
/// [`ROWS_PER_TASK`] whose sums are added in order (the same bits on any number of threads).
pub fn gram(pattern: &Pattern, values: &[f64], x: &SmoothFields) -> Mat<f64> {
    let (q, p) = (x.per_node, x.count());
    let partial: Vec<Vec<f64>> = (0..pattern.n)
        .into_par_iter()
        .step_by(ROWS_PER_TASK)
        .map(|r0| {
            let mut g = vec![0.0; p * p];
            let mut ax = vec![0.0; p];
            for r in r0..(r0 + ROWS_PER_TASK).min(pattern.n) {
                ax.iter_mut().for_each(|v| *v = 0.0);
                for e in pattern.col_ptr[r]..pattern.col_ptr[r + 1] {
                    let a = values[e];
                    if a == 0.0 {
                        // the mass's cross-direction entries on the shared pattern
                        continue;
                    }
                    let (pc, i) = x.at(pattern.row_idx[e]);
                    ax[i * q..i * q + q]
                        .iter_mut()
                        .zip(pc)
                        .for_each(|(s, v)| *s += a * v);
                }
                let (pr, i) = x.at(r);
                for (j, &s) in pr.iter().enumerate() {
                    let row = &mut g[(i * q + j) * p..(i * q + j + 1) * p];
                    row.iter_mut().zip(&ax).for_each(|(g, a)| *g += s * a);
                }
            }
            g
        })
        .collect();
    let mut sum = vec![0.0; p * p];
    for g in &partial {
        sum.iter_mut().zip(g).for_each(|(s, v)| *s += v);
    }
    Mat::from_fn(p, p, |i, j| sum[i * p + j])
}
