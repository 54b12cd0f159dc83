//! Block subspace iteration with a shift-invert factor: the span of about the lowest modes at
//! a tenth of Lanczos's solve cost per vector (block solves read the factor once per panel).

use crate::linalg::factor::Llt;
use crate::linalg::sparse::SymCsc;
use faer::Mat;
use rayon::prelude::*;

/// `passes` passes of X <- (K - sigma M)^-1 M X (`llt` the factor of K - sigma M, `mass` M)
/// from a pseudo-random n x `count` block fixed by `seed` (xorshift, entries in [-0.5, 0.5)),
/// each pass an [`inverse_pass`]. A mode's share shrinks each pass by
/// (lambda_i - sigma) / (lambda_j - sigma) against a kept mode j: the span settles on the
/// lowest modes; the columns are not converged eigenvectors.
pub fn inverse_subspace(
    mass: &SymCsc,
    llt: &Llt<'_>,
    n: usize,
    count: usize,
    passes: usize,
    seed: u64,
) -> Mat<f64> {
    let mut x = super::dense_lanczos::random_block(n, count, seed);
    for _ in 0..passes {
        x = inverse_pass(mass, llt, &x);
    }
    x
}

/// One pass X <- orth((K - sigma M)^-1 M X): the block solved in panels of at most 64
/// columns on both cores (a block narrower than 64 in two panels of half its width, so that
/// both cores work), then orthonormalised (thin QR).
pub fn inverse_pass(mass: &SymCsc, llt: &Llt<'_>, x: &Mat<f64>) -> Mat<f64> {
    let (n, count) = (x.nrows(), x.ncols());
    let mut y = Mat::<f64>::zeros(n, count);
    mass.mul_dense(x.as_ref(), y.as_mut());
    let panel = if count < 64 {
        count.div_ceil(2).max(1)
    } else {
        64
    };
    y.par_col_chunks_mut(panel)
        .for_each(|p| llt.solve_in_place(p));
    y.qr().compute_thin_Q()
}
