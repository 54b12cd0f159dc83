//! The lowest eigenpairs of a dense symmetric pencil K y = lambda M y (K and M positive
//! definite: an assembled reduced model) without decomposing the whole spectrum, and their
//! certificate.
//!
//! Block shift-invert Lanczos at zero shift in the standard form of the stiffness factor
//! K = L L^T: A = L^-1 M L^-T is symmetric with eigenvalues theta = 1 / lambda, so the lowest
//! lambda are the largest and best separated theta. From a pseudo-random orthonormal block Q_0
//! of b columns, each step forms W = A Q_j, orthogonalises it against every block so far
//! (classical Gram-Schmidt twice: H_ij = Q_i^T W) and factors W = Q_{j+1} R_{j+1} (Householder
//! QR). H = Q^T A Q is then block tridiagonal with the R blocks below the diagonal; Ritz pairs
//! H s = theta s, z = Q s have the residual |A z - theta z| = |R_{j+1} s_last| (s_last: the
//! last b entries of s), which bounds |theta - theta_exact| because A is symmetric. A pair is
//! accepted when that bound is below `tol * theta` (relative error of lambda below `tol`).
//! The eigenvectors y = L^-T z are finally put through one Rayleigh-Ritz step with K and M
//! (Y^T K Y x = lambda Y^T M Y x): M-orthonormal vectors and Rayleigh quotients (upper bounds of
//! the exact eigenvalues).
//!
//! Certificate ([`count_below`]): by Sylvester's law of inertia the number of negative pivots
//! of L D L^T = K - sigma M (Bunch-Kaufman, 1x1 and 2x2 blocks) is the number of eigenvalues
//! below sigma.
//!
//! A block of b >= 6 columns carries clusters of up to b nearly equal eigenvalues (six equal
//! liners) that single-vector Lanczos finds one at a time; the products and solves run as
//! matrix-matrix kernels.

use faer::linalg::solvers::Llt;
use faer::{Mat, MatRef, Par};
use rayon::prelude::*;

/// Columns per panel of the triangular solves (one panel per core for a block).
const PANEL: usize = 32;

/// Columns per Lanczos block.
pub const BLOCK: usize = 64;

/// The accepted lowest eigenpairs.
pub struct Lowest {
    /// Eigenvalues lambda, ascending (Rayleigh quotients of the vectors).
    pub lambdas: Vec<f64>,
    /// M-orthonormal eigenvectors (n x count).
    pub vectors: Mat<f64>,
    /// Columns of the Krylov basis used.
    pub basis: usize,
}

/// Why the Lanczos iteration gave no answer (the caller then decomposes densely).
#[derive(Debug, thiserror::Error)]
pub enum LanczosError {
    #[error("the Krylov basis reached {basis} of {n} columns before the wanted pairs converged")]
    Exhausted { basis: usize, n: usize },
    #[error("the projected problem could not be decomposed")]
    Projected,
}

/// Pseudo-random n x b block (xorshift from `seed`, entries in [-0.5, 0.5)).
pub(crate) fn random_block(n: usize, b: usize, seed: u64) -> Mat<f64> {
    let mut state = seed;
    Mat::from_fn(n, b, |_, _| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    })
}

/// C = A B on both cores: faer's parallel product splits the output into blocks, each summed
/// in the same order on any number of threads (unlike its dense factorisations, which stay
/// serial during a ROM build: [`crate::linalg::thread_count_invariant`]).
pub fn product(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let mut c = Mat::<f64>::zeros(a.nrows(), b.ncols());
    faer::linalg::matmul::matmul(c.as_mut(), faer::Accum::Replace, a, b, 1.0, Par::rayon(0));
    c
}

/// A x = L^-1 M L^-T x for a block x: two triangular solves (serial per panel of [`PANEL`]
/// columns, panels on both cores) around one product with M.
fn apply(l: MatRef<'_, f64>, m: MatRef<'_, f64>, x: MatRef<'_, f64>) -> Mat<f64> {
    let mut y = x.to_owned();
    upper_solve(l, &mut y);
    let mut w = product(m, y.as_ref());
    w.par_col_chunks_mut(PANEL).for_each(|c| {
        faer::linalg::triangular_solve::solve_lower_triangular_in_place(l, c, Par::Seq)
    });
    w
}

/// x <- L^-T x in panels of [`PANEL`] columns on both cores.
fn upper_solve(l: MatRef<'_, f64>, x: &mut Mat<f64>) {
    x.par_col_chunks_mut(PANEL).for_each(|c| {
        faer::linalg::triangular_solve::solve_upper_triangular_in_place(l.transpose(), c, Par::Seq)
    });
}

/// The growing Krylov basis and its projection H = Q^T A Q.
struct Krylov {
    q: Mat<f64>,
    h: Mat<f64>,
    /// Columns filled.
    m: usize,
}

impl Krylov {
    fn new(n: usize, cap: usize) -> Self {
        Self {
            q: Mat::zeros(n, cap),
            h: Mat::zeros(cap, cap),
            m: 0,
        }
    }

    /// Appends an orthonormal block; `r` (b x b) is its coupling to the previous block
    /// (H_{j+1,j} = R_{j+1}), `None` for the first block.
    fn push(&mut self, block: MatRef<'_, f64>, r: Option<MatRef<'_, f64>>) {
        let (m, b) = (self.m, block.ncols());
        if m + b > self.q.ncols() {
            let cap = (2 * self.q.ncols()).max(m + b);
            let n = self.q.nrows();
            self.q.resize_with(n, cap, |_, _| 0.0);
            self.h.resize_with(cap, cap, |_, _| 0.0);
        }
        self.q.as_mut().subcols_mut(m, b).copy_from(block);
        if let Some(r) = r {
            self.h.as_mut().submatrix_mut(m, m - b, b, b).copy_from(r);
            self.h
                .as_mut()
                .submatrix_mut(m - b, m, b, b)
                .copy_from(r.transpose());
        }
        self.m += b;
    }

    /// Orthogonalises `w` (= A Q_last) against the whole basis, twice, and records the
    /// coefficients as the last block column (and row) of H.
    fn orthogonalise(&mut self, w: &mut Mat<f64>, b: usize) {
        let (m, q) = (self.m, self.q.as_ref().subcols(0, self.m));
        let mut total = Mat::<f64>::zeros(m, b);
        for _ in 0..2 {
            let c = product(q.transpose(), w.as_ref());
            let qc = product(q, c.as_ref());
            *w -= &qc;
            total += &c;
        }
        // H's last block column is Q^T A Q_last; its diagonal block is symmetrised.
        self.h
            .as_mut()
            .submatrix_mut(0, m - b, m, b)
            .copy_from(&total);
        for i in 0..m - b {
            for j in 0..b {
                self.h[(m - b + j, i)] = total[(i, j)];
            }
        }
        for i in 0..b {
            for j in 0..i {
                let s = 0.5 * (self.h[(m - b + i, m - b + j)] + self.h[(m - b + j, m - b + i)]);
                self.h[(m - b + i, m - b + j)] = s;
                self.h[(m - b + j, m - b + i)] = s;
            }
        }
    }
}

/// Ritz pairs of the basis so far, by descending theta.
struct Ritz {
    theta: Vec<f64>,
    /// Residual bounds |R s_last|.
    residual: Vec<f64>,
    /// The coefficient vectors s (columns, same order).
    s: Mat<f64>,
}

/// The Ritz pairs of the basis so far (module docs).
fn ritz(kr: &Krylov, r: MatRef<'_, f64>) -> Result<Ritz, LanczosError> {
    let (m, b) = (kr.m, r.ncols());
    let h = kr.h.as_ref().submatrix(0, 0, m, m).to_owned();
    let e = h
        .self_adjoint_eigen(faer::Side::Lower)
        .map_err(|_| LanczosError::Projected)?;
    let (s, u) = (e.S().column_vector(), e.U());
    let order: Vec<usize> = (0..m).rev().collect();
    let theta: Vec<f64> = order.iter().map(|&i| s[i]).collect();
    let vecs = Mat::from_fn(m, m, |i, k| u[(i, order[k])]);
    let last = product(r, vecs.as_ref().subrows(m - b, b));
    let residual = (0..m)
        .map(|k| last.col(k).iter().map(|v| v * v).sum::<f64>().sqrt())
        .collect();
    Ok(Ritz {
        theta,
        residual,
        s: vecs,
    })
}

/// Which pairs [`lowest_modes`] must deliver, and how accurately.
pub struct Target<'a> {
    /// How many lowest pairs to return, from the current eigenvalue estimates (ascending); it
    /// may grow with them (e.g. half again the count below a cut-off).
    pub count: &'a dyn Fn(&[f64]) -> usize,
    /// Pairs with eigenvalues up to this are accepted when their relative error bound is
    /// below `tol`, the others (returned as approximations, e.g. start vectors) below
    /// `rest_tol`.
    pub accurate_below: f64,
    pub tol: f64,
    pub rest_tol: f64,
}

/// The lowest eigenpairs of K y = lambda M y (module docs); `llt` is K's Cholesky factor.
/// The projected problem is decomposed once the basis holds a quarter more columns than the
/// first estimate of the wanted count, then whenever it has grown by a block or an eighth,
/// whichever is more. Fails when the
/// basis would exceed `max_basis` columns (or n) first.
pub fn lowest_modes(
    k: MatRef<'_, f64>,
    m: MatRef<'_, f64>,
    llt: &Llt<f64>,
    target: &Target<'_>,
    max_basis: usize,
) -> Result<Lowest, LanczosError> {
    let n = k.nrows();
    let b = BLOCK.min(n);
    let l = llt.L();
    let mut kr = Krylov::new(n, (16 * b).min(n));
    let q0 = random_block(n, b, 0x9E37_79B9_7F4A_7C15)
        .qr()
        .compute_thin_Q();
    kr.push(q0.as_ref(), None);
    let mut next_check = (target.count)(&[]).min(n) * 5 / 4;
    loop {
        let m_now = kr.m;
        let mut w = apply(l, m, kr.q.as_ref().subcols(m_now - b, b));
        kr.orthogonalise(&mut w, b);
        let qr = w.qr();
        let (q_next, r) = (qr.compute_thin_Q(), qr.thin_R().to_owned());
        let last = m_now + b > max_basis.min(n);
        if m_now >= next_check || last {
            next_check = m_now + b.max(m_now / 8);
            let Ritz {
                theta,
                residual: res,
                s,
            } = ritz(&kr, r.as_ref())?;
            let lambdas: Vec<f64> = theta.iter().map(|t| 1.0 / t).collect();
            let p = (target.count)(&lambdas).min(n);
            let bound = |i: usize| {
                if lambdas[i] <= target.accurate_below {
                    target.tol
                } else {
                    target.rest_tol
                }
            };
            let converged = (0..m_now)
                .take_while(|&i| theta[i] > 0.0 && res[i] <= bound(i) * theta[i])
                .count();
            log::debug!("block Lanczos: basis {m_now}, {converged} of {p} wanted pairs accepted");
            if p + b <= m_now && converged >= p {
                log::info!(
                    "block Lanczos: accepted the lowest {p} pairs from {m_now} basis columns"
                );
                let z = product(kr.q.as_ref().subcols(0, m_now), s.as_ref().subcols(0, p));
                return rayleigh_ritz(k, m, l, z, m_now);
            }
        }
        if last {
            return Err(LanczosError::Exhausted { basis: m_now, n });
        }
        kr.push(q_next.as_ref(), Some(r.as_ref()));
    }
}

/// Y = L^-T Z, then Y^T K Y x = lambda Y^T M Y x (ascending, x M-normalised), Y <- Y X.
fn rayleigh_ritz(
    k: MatRef<'_, f64>,
    m: MatRef<'_, f64>,
    l: MatRef<'_, f64>,
    mut y: Mat<f64>,
    basis: usize,
) -> Result<Lowest, LanczosError> {
    upper_solve(l, &mut y);
    let mut kp = product(y.transpose(), product(k, y.as_ref()).as_ref());
    let mut mp = product(y.transpose(), product(m, y.as_ref()).as_ref());
    for a in [&mut kp, &mut mp] {
        let s = a.nrows();
        for i in 0..s {
            for j in 0..i {
                let v = 0.5 * (a[(i, j)] + a[(j, i)]);
                a[(i, j)] = v;
                a[(j, i)] = v;
            }
        }
    }
    let c = mp
        .llt(faer::Side::Lower)
        .map_err(|_| LanczosError::Projected)?;
    let mut a = kp;
    let cl = c.L();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(cl, a.as_mut(), Par::Seq);
    let mut at = a.transpose().to_owned();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(cl, at.as_mut(), Par::Seq);
    let e = at
        .self_adjoint_eigen(faer::Side::Lower)
        .map_err(|_| LanczosError::Projected)?;
    let mut x = e.U().to_owned();
    faer::linalg::triangular_solve::solve_upper_triangular_in_place(
        cl.transpose(),
        x.as_mut(),
        Par::Seq,
    );
    let s = e.S().column_vector();
    Ok(Lowest {
        lambdas: (0..s.nrows()).map(|i| s[i]).collect(),
        vectors: product(y.as_ref(), x.as_ref()),
        basis,
    })
}

/// Number of eigenvalues of K y = lambda M y below `sigma` (M positive definite): the negative
/// inertia of K - sigma M from its Bunch-Kaufman factorisation P (L B L^T) P^T, B of 1x1 and
/// 2x2 blocks (a 2x2 block [a c; c d] has one negative eigenvalue when ad - c^2 < 0, two when
/// it is positive and a < 0).
pub fn count_below(k: MatRef<'_, f64>, m: MatRef<'_, f64>, sigma: f64) -> usize {
    let n = k.nrows();
    let a = Mat::from_fn(n, n, |i, j| k[(i, j)] - sigma * m[(i, j)]);
    let f = a.lblt(faer::Side::Lower);
    let (d, e) = (f.B_diag().column_vector(), f.B_subdiag().column_vector());
    let mut count = 0;
    let mut i = 0;
    while i < n {
        if i + 1 < n && e[i] != 0.0 {
            // eigenvalues of [a c; c d]: product det, sum a + d
            let det = d[i] * d[i + 1] - e[i] * e[i];
            count += if det < 0.0 {
                1
            } else if det == 0.0 {
                usize::from(d[i] + d[i + 1] < 0.0)
            } else {
                2 * usize::from(d[i] < 0.0)
            };
            i += 2;
        } else {
            count += usize::from(d[i] < 0.0);
            i += 1;
        }
    }
    count
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::linalg::solvers::DenseSolveCore;

    /// A pencil with known eigenpairs: Y (well conditioned, pseudo-random) and Lambda give
    /// M = Y^-T Y^-1, K = Y^-T Lambda Y^-1, so Y^T M Y = I and Y^T K Y = Lambda. Lambda spreads
    /// over eight decades like an assembled ROM's, with clusters of six equal eigenvalues.
    fn known_pencil(n: usize) -> (Mat<f64>, Mat<f64>, Vec<f64>) {
        let r = random_block(n, n, 7);
        let s = 0.3 / (n as f64).sqrt();
        let y = Mat::from_fn(n, n, |i, j| r[(i, j)] * s + if i == j { 1.0 } else { 0.0 });
        let mut lambdas: Vec<f64> = (0..n)
            .map(|i| {
                let g = if i < 120 { (i / 6) * 6 } else { i };
                1e4 * 10f64.powf(8.0 * g as f64 / n as f64)
            })
            .collect();
        lambdas.sort_by(f64::total_cmp);
        let yi = y.partial_piv_lu().inverse();
        let lam = Mat::from_fn(n, n, |i, j| if i == j { lambdas[i] } else { 0.0 });
        let mut m = yi.transpose() * &yi;
        let mut k = yi.transpose() * (&lam * &yi);
        for a in [&mut m, &mut k] {
            for i in 0..n {
                for j in 0..i {
                    let v = 0.5 * (a[(i, j)] + a[(j, i)]);
                    a[(i, j)] = v;
                    a[(j, i)] = v;
                }
            }
        }
        (k, m, lambdas)
    }

    /// Verification against a pencil with known eigenvalues: the lowest 150 (25 clusters of six
    /// equal values, then distinct ones) within 1e-9 relative (the accepted bound is 1e-10; the
    /// construction of K and M itself rounds at about 1e-13 of the largest eigenvalue's
    /// share), the vectors M-orthonormal within 1e-10, and the Sturm count exact between
    /// clusters.
    #[test]
    fn verification_block_lanczos_finds_a_known_spectrum_and_counts_it() {
        let n = 700;
        let (k, m, exact) = known_pencil(n);
        let llt = k.llt(faer::Side::Lower).unwrap();
        let target = Target {
            count: &|_| 150,
            accurate_below: f64::INFINITY,
            tol: 1e-10,
            rest_tol: 1e-10,
        };
        let got = lowest_modes(k.as_ref(), m.as_ref(), &llt, &target, n).unwrap();
        assert_eq!(got.lambdas.len(), 150);
        for (i, (a, e)) in got.lambdas.iter().zip(&exact).enumerate() {
            assert!((a - e).abs() <= 1e-9 * e, "eigenvalue {i}: {a} against {e}");
        }
        let g = got.vectors.transpose() * (&m * &got.vectors);
        for i in 0..150 {
            for j in 0..150 {
                let d = if i == j { 1.0 } else { 0.0 };
                assert!((g[(i, j)] - d).abs() < 1e-10, "Y^T M Y at ({i}, {j})");
            }
        }
        for below in [6usize, 60, 120, 150] {
            let sigma = 0.5 * (exact[below - 1] + exact[below]);
            assert_eq!(count_below(k.as_ref(), m.as_ref(), sigma), below);
        }
    }
}
