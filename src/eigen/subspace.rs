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
        x = inverse_pass(mass, llt, x);
    }
    x
}

/// One pass X <- orth((K - sigma M)^-1 M X): the block solved by [`solve_block`], then
/// orthonormalised (thin QR). `x` is let go once M X is formed.
pub fn inverse_pass(mass: &SymCsc, llt: &Llt<'_>, x: Mat<f64>) -> Mat<f64> {
    let (n, count) = (x.nrows(), x.ncols());
    let mut y = Mat::<f64>::zeros(n, count);
    mass.mul_dense(x.as_ref(), y.as_mut());
    drop(x);
    solve_block(llt, &mut y);
    thin_q(y)
}

/// Y <- (K - sigma M)^-1 Y in place, in panels of at most 64 columns on both cores (a block
/// narrower than 64 in two panels of half its width, so that both cores work); each panel's
/// arithmetic is the same on any number of threads.
pub fn solve_block(llt: &Llt<'_>, y: &mut Mat<f64>) {
    y.par_col_chunks_mut(panel(y.ncols()))
        .for_each(|p| llt.solve_in_place(p));
}

/// Z <- L^-1 Z in place, rows in the factor's order ([`Llt::order`]); panels as
/// [`solve_block`].
pub fn forward_block(llt: &Llt<'_>, z: &mut Mat<f64>) {
    z.par_col_chunks_mut(panel(z.ncols()))
        .for_each(|p| llt.forward_in_place(p));
}

/// Z <- L^-T Z in place, rows in the factor's order ([`Llt::order`]); panels as
/// [`solve_block`].
pub fn backward_block(llt: &Llt<'_>, z: &mut Mat<f64>) {
    z.par_col_chunks_mut(panel(z.ncols()))
        .for_each(|p| llt.backward_in_place(p));
}

/// Panel width of the block solves: at most 64 columns, a narrower block in two panels so
/// that both cores work.
fn panel(count: usize) -> usize {
    if count < 64 {
        count.div_ceil(2).max(1)
    } else {
        64
    }
}

/// The thin Q of Y = Q R (Householder, blocked), with Y's storage holding the reflectors: one
/// n x b block besides Y, where `Mat::qr` copies Y first and splits the copy (three).
pub fn thin_q(mut y: Mat<f64>) -> Mat<f64> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::householder as hh;
    use faer::linalg::qr::no_pivoting::factor as qr;
    let (n, b) = y.shape();
    let size = n.min(b);
    let block = qr::recommended_block_size::<f64>(n, b);
    let par = faer::get_global_parallelism();
    let mut coeff = Mat::<f64>::zeros(block, size);
    qr::qr_in_place(
        y.as_mut(),
        coeff.as_mut(),
        par,
        MemStack::new(&mut MemBuffer::new(qr::qr_in_place_scratch::<f64>(
            n,
            b,
            block,
            par,
            Default::default(),
        ))),
        Default::default(),
    );
    let mut q = Mat::<f64>::identity(n, size);
    hh::apply_block_householder_sequence_on_the_left_in_place_with_conj(
        y.as_ref().subcols(0, size),
        coeff.as_ref(),
        faer::Conj::No,
        q.as_mut(),
        par,
        MemStack::new(&mut MemBuffer::new(
            hh::apply_block_householder_sequence_on_the_left_in_place_scratch::<f64>(
                n, block, size,
            ),
        )),
    );
    q
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Verification: the in-place thin Q equals faer's `Mat::qr` thin Q to roundoff (the same
    /// blocked Householder steps; 1e-13 of unit columns), on a tall block of mixed scales.
    #[test]
    fn thin_q_equals_faers_qr() {
        let y = Mat::<f64>::from_fn(3000, 40, |i, j| {
            ((i * 7 + j * 13) % 17) as f64 - 8.0 + 1e-3 * (j as f64) * (i as f64).sin()
        });
        let reference = y.qr().compute_thin_Q();
        let q = thin_q(y.clone());
        let diff = (&q - &reference).norm_max();
        assert!(diff < 1e-13, "{diff:e}");
        // and Q^T Y is upper triangular: Q spans Y column by column
        let r = q.transpose() * &y;
        let below = (0..40)
            .flat_map(|j| (j + 1..40).map(move |i| (i, j)))
            .map(|(i, j)| r[(i, j)].abs())
            .fold(0.0, f64::max);
        assert!(below < 1e-10 * r.norm_max(), "{below:e}");
    }
}
