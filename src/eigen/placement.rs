//! Where to put the shift of a certified modal solve ([`super::modal`]): bounds of the
//! highest wanted eigenvalue lambda_nev (from a first restart's Ritz values, from passes of
//! block subspace iteration on the factor at hand) and the rules that move a shift far below
//! the wanted modes toward them.
//!
//! Shift-invert maps lambda to theta = 1 / (lambda - sigma): a shift far below the wanted
//! eigenvalues maps them all close to -1 / sigma, where Lanczos separates them slowly. A shift
//! below zero with -sigma > [`SHIFT_REACH`] times an upper bound of lambda_nev is moved to
//! -[`SHIFT_FRACTION`] times that bound ([`moved_shift`]): still below every eigenvalue (the
//! factorisation stays a Cholesky) and near the wanted band.

use crate::linalg::sparse::SymCsc;

/// Checks of the shift, each on the factor of the last one it moved to ([`placed_shift`]).
pub const PLACEMENT_ROUNDS: usize = 2;
/// Passes of the shift check's block subspace iteration ([`placed_shift`]).
pub const SHIFT_CHECK_PASSES: usize = 4;
/// A shift farther below zero than this many times the estimated highest wanted eigenvalue is
/// moved ([`placed_shift`]).
pub const SHIFT_REACH: f64 = 2.0;
/// Where [`placed_shift`] puts the shift: this fraction of the estimated highest wanted
/// eigenvalue, below zero.
pub const SHIFT_FRACTION: f64 = 0.25;

/// A Ritz bound (an upper bound of lambda_nev, [`ritz_bound`]) below this many times -sigma
/// leaves a shift below zero in doubt, to be checked ([`placed_shift`]). Far shifts give
/// bounds below -sigma (the 754k-DOF casting at -(2 pi 20 kHz)^2: 0.87 times -sigma), shifts
/// near the band bounds hundreds to thousands of times -sigma (the casting and the liner at
/// the default 100 Hz).
pub const SHIFT_DOUBT: f64 = 16.0;

/// Whether the Ritz bound `bound` of lambda_nev leaves the shift `sigma` in doubt: below zero
/// and `bound` < [`SHIFT_DOUBT`] (-sigma).
pub fn shift_in_doubt(bound: f64, sigma: f64) -> bool {
    sigma < 0.0 && bound < SHIFT_DOUBT * -sigma
}

/// An upper bound of lambda_nev from the Ritz values `ritz` of the operator
/// (K - sigma M)^-1 M on a Lanczos basis: sigma + 1 / theta_nev, theta_nev the nev-th largest.
/// By Cauchy interlacing theta_nev <= 1 / (lambda_nev - sigma) for sigma below the spectrum,
/// so the bound is at least lambda_nev; infinite when fewer than nev Ritz values are positive.
pub fn ritz_bound(ritz: &[f64], nev: usize, sigma: f64) -> f64 {
    let mut theta: Vec<f64> = ritz.iter().copied().filter(|t| *t > 0.0).collect();
    theta.sort_by(|a, b| b.total_cmp(a));
    match nev.checked_sub(1).and_then(|k| theta.get(k)) {
        Some(&t) => sigma + 1.0 / t,
        None => f64::INFINITY,
    }
}

/// Bounds or eigenvalues at or below this fraction of their scale are roundoff around zero
/// ([`above_roundoff`]): the rigid-body modes'.
pub const ROUNDOFF: f64 = 1e-8;

/// Whether `value` is clearly above zero against `scale` (the largest value of its kind at
/// hand): above [`ROUNDOFF`] `scale`. A shift is never moved on a value that is not: when
/// every wanted mode is a rigid-body mode its bound is roundoff, and a shift moved to a quarter
/// of it would sit at zero, where K - sigma M is singular.
pub fn above_roundoff(value: f64, scale: f64) -> bool {
    value > ROUNDOFF * scale.abs()
}

/// The shift [`placed_shift`] moves to, given `top`, an estimate or upper bound of the highest
/// wanted eigenvalue: min(-[`SHIFT_FRACTION`] top, `floor`) when -sigma > [`SHIFT_REACH`] top
/// and that lies closer to zero than sigma, else None. `floor` (<= 0; 0 for none) is the
/// closest to zero a shift may come ([`crate::eigen::modal::SHIFT_FLOOR`]): a free body whose
/// wanted modes all lie below it (a slender bar of fine elements) is solved there, where its
/// rigid-body modes' residuals are not round-off against |sigma|.
pub fn moved_shift(top: f64, sigma: f64, floor: f64) -> Option<f64> {
    let to = (-SHIFT_FRACTION * top).min(floor);
    (sigma < 0.0 && top > 0.0 && -sigma > SHIFT_REACH * top && to > sigma).then_some(to)
}

/// A shift [`placed_shift`] moved to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Moved {
    /// The new shift \[rad^2/s^2\].
    pub sigma: f64,
    /// The estimate it was placed from had settled ([`settled`]), or was a converged
    /// eigenvalue: the new shift is solved without a further check.
    pub settled: bool,
}

/// Whether the bounds `values` of lambda_nev, one per pass of the block check, have settled:
/// with d_p the last decrease and r = d_p / d_(p-1) its ratio to the one before, r is at most
/// [`SETTLED_RATIO`] and the limit of a linearly converging sequence (Aitken's extrapolation)
/// v_p - d_p r / (1 - r) is at least [`SETTLED_FRACTION`] v_p. An extrapolation, not a proof: a shift wrongly taken as settled
/// costs Lanczos solves, never a wrong answer (the Sturm count certifies the result).
pub fn settled(values: &[f64]) -> bool {
    let [.., a, b, c] = values else {
        return false;
    };
    let (d_before, d_last) = (a - b, b - c);
    // a last change at roundoff: converged (a converged bound may rise by roundoff)
    let tiny = 1e-12 * c.abs();
    if d_last.abs() <= tiny {
        return d_before >= -tiny && *c > 0.0;
    }
    if d_before <= 0.0 || d_last < 0.0 {
        return false;
    }
    let r = d_last / d_before;
    r <= SETTLED_RATIO && c - d_last * r / (1.0 - r) >= SETTLED_FRACTION * c
}

/// The last decrease of the check's bounds must be at most this fraction of the one before
/// for them to count as settled ([`settled`]): a slowly falling sequence (a block that the
/// far shift barely filters: ratios of 0.8 on a free block at -(2 pi 1 MHz)^2, whose bounds
/// were still 1e12 above the true zero) extrapolates unreliably.
pub const SETTLED_RATIO: f64 = 0.5;

/// The extrapolated limit of the check's bounds must be at least this fraction of the last
/// bound for the estimate to count as settled ([`settled`]).
pub const SETTLED_FRACTION: f64 = 0.5;

/// A better shift when `sigma` lies far below the lowest `nev` eigenvalues, else None.
///
/// Shift-invert maps lambda to theta = 1 / (lambda - sigma); a shift far below the wanted
/// eigenvalues maps them all close to -1 / sigma, and Lanczos separates them slowly (a mm deck
/// read as metres, modes near 3-8 Hz under the default -(2 pi 100 Hz)^2, took 19 min and missed
/// modes). Estimate: up to [`SHIFT_CHECK_PASSES`] passes of block subspace iteration
/// X <- (K - sigma M)^-1 M X on the factor at hand, from a fixed pseudo-random block of
/// 2 `nev` columns, each with the Rayleigh-Ritz values of (K, M) on its span
/// (`checked_pass`, formed without K, which may wait on disk); the `nev`-th,
/// theta_max, is an upper bound of lambda_nev (the k-th Ritz value bounds the k-th eigenvalue
/// from above). When -sigma > [`SHIFT_REACH`] theta_max the shift is moved to
/// -[`SHIFT_FRACTION`] theta_max:
/// still below every eigenvalue (the factorisation stays a Cholesky; rigid-body modes have
/// lambda = 0) and near the wanted band, which then spreads over theta in
/// [1 / (1.25 theta_max), 4 / theta_max]. The shift only ever moves up toward the band; a shift
/// the user placed near the wanted modes is kept. The certificate (Sturm count) is unchanged.
/// The bound falls with the passes, fastest in the first ones; so from the second pass on the
/// check stops, keeping the shift, when the passes left, each lowering the bound by the last
/// pass's ratio, would still leave it [`SHIFT_CHECK_MARGIN`] times beyond the reach of a move
/// (an extrapolation, not a proof: a shift kept wrongly costs Lanczos solves, never a wrong
/// answer, since the Sturm count certifies the result). A shift already near the band costs
/// two passes, not four.
/// Measured on a free-free hex20 block 10,000 times too large (20 modes below 1.4 Hz, shift
/// 100 Hz): 517 Lanczos solves unmoved, 129 moved (80 at the best shift for this band).
pub fn placed_shift(
    mass: &SymCsc,
    llt: &crate::linalg::factor::Llt<'_>,
    nev: usize,
    (sigma, floor): (f64, f64),
) -> Option<Moved> {
    let n = mass.pattern.n;
    let nev = nev.min(n.saturating_sub(1));
    let b = (2 * nev).min(n.saturating_sub(1));
    if nev == 0 || sigma >= 0.0 {
        return None;
    }
    // the fixed start block, its rows put in the factor's order (the check works there)
    let mut x = super::dense_lanczos::random_block(n, b, 0x2545_f491_4f6c_dd1d);
    let (fwd, _) = llt.order();
    let mut column = vec![0.0; n];
    for j in 0..b {
        column
            .iter_mut()
            .zip(x.col(j).iter())
            .for_each(|(c, v)| *c = *v);
        x.col_mut(j)
            .iter_mut()
            .zip(fwd)
            .for_each(|(v, &old)| *v = column[old]);
    }
    drop(column);
    let mut bounds = Vec::with_capacity(SHIFT_CHECK_PASSES);
    for pass in 1..=SHIFT_CHECK_PASSES {
        let (next, ritz) = checked_pass(mass, llt, x, sigma)?;
        x = next;
        let theta_max = ritz[nev - 1];
        log::debug!("shift check pass {pass}: lambda_{nev} <= {theta_max:.4e} (shift {sigma:.4e})");
        let last = bounds.last().copied();
        bounds.push(theta_max);
        // a bound at roundoff (every wanted mode a rigid-body mode) moves nothing; roundoff
        // against the block's largest Ritz value and the shift (a mesh of several free bodies
        // may fill the whole block with rigid-body modes, whose values are roundoff of the
        // shift)
        let scale = ritz[ritz.len() - 1].max(-sigma);
        let top = Some(theta_max).filter(|&t| above_roundoff(t, scale));
        let moved = |settled| {
            top.and_then(|t| moved_shift(t, sigma, floor))
                .map(|sigma| Moved { sigma, settled })
        };
        if pass == SHIFT_CHECK_PASSES {
            return moved(settled(&bounds));
        }
        if settled(&bounds) && moved(true).is_some() {
            return moved(true);
        }
        if let Some(prev) = last {
            // the passes left, each lowering the bound by the last pass's ratio, cannot
            // bring it within reach of a move, by a margin
            let ratio = (prev / theta_max).max(1.0);
            let reach = theta_max / ratio.powi((SHIFT_CHECK_PASSES - pass) as i32);
            if reach > SHIFT_CHECK_MARGIN * -sigma / SHIFT_REACH {
                return None;
            }
        }
    }
    None
}

/// The shift check ends early, keeping the shift, when even the passes left, each lowering
/// the bound by the ratio of the last pass, would leave it this many times above the reach
/// of a move ([`placed_shift`]).
pub const SHIFT_CHECK_MARGIN: f64 = 4.0;

/// One pass of the shift check on a block X held in the factor's row order (P X,
/// [`Llt::order`]): Y = (K - sigma M)^-1 M X, the Rayleigh-Ritz values of (K, M) on span(Y),
/// ascending, and the next block, Y made M-orthonormal (None when Y^T M Y is not positive
/// definite: the block's columns are numerically dependent, which a shift near the wanted band
/// causes, and such a shift is kept). With K - sigma M = P^T L L^T P and Z = L^-1 P M X (the
/// forward half of the solve), P Y = L^-T Z, so Y^T M X = Z^T Z: the block is transformed in
/// place and no second n x b block is alive (the check's memory adds to the factor's). K is not read: K Y = M X + sigma M Y, so
/// Y^T K Y = Y^T (M X) + sigma Y^T M Y. With D scaling Y^T M Y to a unit diagonal and
/// C C^T = D Y^T M Y D, the values are the eigenvalues of C^-1 D (Y^T K Y) D C^-T (the k-th
/// bounds the k-th eigenvalue from above), and Y D C^-T is M-orthonormal.
///
/// [`Llt::order`]: crate::linalg::factor::Llt::order
pub(super) fn checked_pass(
    mass: &SymCsc,
    llt: &crate::linalg::factor::Llt<'_>,
    mut x: faer::Mat<f64>,
    sigma: f64,
) -> Option<(faer::Mat<f64>, Vec<f64>)> {
    let order = llt.order();
    mass.mul_dense_permuted_in_place(order, x.as_mut());
    super::subspace::forward_block(llt, &mut x);
    let ymx = x.transpose() * &x;
    super::subspace::backward_block(llt, &mut x);
    let ymy = mass_gram(mass, order, &x);
    let (ritz, d, c) = rayleigh_ritz(&ymx, &ymy, sigma)?;
    // X <- Y D C^-T, i.e. (C^-1 (Y D)^T)^T, then once more on its own Gram matrix (CholQR2:
    // the second pass restores M-orthonormality to roundoff for condition numbers of Y up to
    // about 1e8)
    for (j, dj) in d.iter().enumerate() {
        x.col_mut(j).iter_mut().for_each(|v| *v *= dj);
    }
    right_solve_lower_transposed(&c, &mut x);
    if let Ok(again) = mass_gram(mass, order, &x).llt(faer::Side::Lower) {
        right_solve_lower_transposed(&again.L().to_owned(), &mut x);
    }
    Some((x, ritz))
}

/// X <- X C^-T in place for a lower triangular C: (C^-1 X^T)^T.
fn right_solve_lower_transposed(c: &faer::Mat<f64>, x: &mut faer::Mat<f64>) {
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(
        c.as_ref(),
        x.as_mut().transpose_mut(),
        faer::get_global_parallelism(),
    );
}

/// Columns of M Y formed at a time by [`mass_gram`].
pub(super) const GRAM_COLUMNS: usize = 8;

/// Y^T M Y for a block Y in the factor's row order (`order`, P Y): (P Y)^T (P M P^T) (P Y),
/// [`GRAM_COLUMNS`] columns of the product at a time.
pub(super) fn mass_gram(
    mass: &SymCsc,
    order: (&[usize], &[usize]),
    y: &faer::Mat<f64>,
) -> faer::Mat<f64> {
    let b = y.ncols();
    let mut gram = faer::Mat::<f64>::zeros(b, b);
    for c0 in (0..b).step_by(GRAM_COLUMNS) {
        let w = GRAM_COLUMNS.min(b - c0);
        let mut my = y.subcols(c0, w).to_owned();
        mass.mul_dense_permuted_in_place(order, my.as_mut());
        faer::linalg::matmul::matmul(
            gram.as_mut().subcols_mut(c0, w),
            faer::Accum::Replace,
            y.transpose(),
            my.as_ref(),
            1.0,
            faer::get_global_parallelism(),
        );
    }
    gram
}

/// The eigenvalues of (Y^T M X + sigma Y^T M Y, Y^T M Y) (both symmetrised), ascending, by a
/// scaled Cholesky of the second ([`checked_pass`]), with the scaling D and the factor C
/// (C C^T = D Y^T M Y D); None when Y^T M Y is not positive definite.
fn rayleigh_ritz(
    ymx: &faer::Mat<f64>,
    ymy: &faer::Mat<f64>,
    sigma: f64,
) -> Option<(Vec<f64>, Vec<f64>, faer::Mat<f64>)> {
    use faer::Mat;
    let b = ymy.nrows();
    let d: Vec<f64> = (0..b)
        .map(|i| 1.0 / ymy[(i, i)].max(f64::MIN_POSITIVE).sqrt())
        .collect();
    let sym = |m: &Mat<f64>, i: usize, j: usize| 0.5 * (m[(i, j)] + m[(j, i)]) * d[i] * d[j];
    let bm = Mat::from_fn(b, b, |i, j| sym(ymy, i, j));
    let a = Mat::from_fn(b, b, |i, j| sym(ymx, i, j) + sigma * bm[(i, j)]);
    let c = bm.llt(faer::Side::Lower).ok()?.L().to_owned();
    let mut s = a;
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(
        c.as_ref(),
        s.as_mut(),
        faer::Par::Seq,
    );
    let mut st = s.transpose().to_owned();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(
        c.as_ref(),
        st.as_mut(),
        faer::Par::Seq,
    );
    let mut ritz = st.self_adjoint_eigenvalues(faer::Side::Lower).ok()?;
    ritz.sort_by(f64::total_cmp);
    Some((ritz, d, c))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Verification of Aitken's test: a geometric sequence v_p = lambda + e r^p is
    /// extrapolated exactly, so it has settled when lambda >= SETTLED_FRACTION v_p (fast
    /// convergence, r = 0.1) and not when the last bound is still far above its limit
    /// (r = 0.9, or r = 0.8 whatever its limit); a rising or flat-then-falling sequence, or
    /// fewer than three bounds, has not;
    /// a converged one whose last bound moves by roundoff only has.
    #[test]
    fn verification_settled_bounds_extrapolate_a_geometric_sequence() {
        let seq = |lambda: f64, e: f64, r: f64| -> Vec<f64> {
            (1..=3).map(|p| lambda + e * r.powi(p)).collect()
        };
        assert!(settled(&seq(1.0, 10.0, 0.1)));
        assert!(!settled(&seq(1.0, 10.0, 0.9)));
        // the limit is exactly half the last bound at r = 0.5 and e = 8: 1 vs 0.5 * 2
        assert!(settled(&seq(1.0, 8.0, 0.5)));
        assert!(!settled(&seq(1.0, 9.0, 0.5)));
        // slowly falling (r = 0.8): not settled even where the extrapolated limit would pass
        assert!(!settled(&seq(10.0, 1.0, 0.8)));
        // the free block's bounds at -(2 pi 1 MHz)^2 (true limit 0)
        assert!(!settled(&[1.8882e12, 1.6527e12, 1.4646e12, 1.3136e12]));
        assert!(!settled(&[1.0, 2.0, 1.5]));
        assert!(!settled(&[2.0, 2.0, 1.5]));
        assert!(!settled(&[2.0, 1.5]));
        // converged: the last bound rises by roundoff (1e-15 of it), or does not move
        assert!(settled(&[3.0, 1.0, 1.0 + 1e-15]));
        assert!(settled(&[1.0, 1.0, 1.0]));
    }
}
