//! LU factorisation with partial pivoting of a small dense matrix (the lubricated contact
//! step's all-cylinder system, about 84 x 84, factorised at every Newton iteration), and its
//! solves.
//!
//! The algorithm and the floating-point operations are nalgebra's `LU` (right-looking Gaussian
//! elimination, column-major): at step i the pivot is the first entry of largest |a_ki|,
//! k >= i; rows i and the pivot's are swapped; the column below the diagonal is scaled by
//! 1 / a_ii (a product by the reciprocal, not a division); each trailing column j gets
//! a_.j <- a_.j + (-a_ij) a_.i. The solves apply the row swaps in order, then
//! L y = b (unit diagonal; b_(i+1..) += (-b_i) l_(i+1..),i) and U x = y (x_i = y_i / u_ii;
//! y_(..i) += (-x_i) u_(..i),i). The same operations in the same order give the same bits as
//! nalgebra; the elimination and the solves have an AVX2 compilation chosen at run time (the
//! crate is compiled for baseline x86-64, where nalgebra's loops use SSE2 only), their column
//! updates inlined into it.

/// The LU factors of an n x n matrix, P A = L U, stored column-major in one array (L below the
/// diagonal with its unit diagonal implied, U on and above it), and the row swaps of P.
pub struct Lu {
    n: usize,
    a: Vec<f64>,
    swaps: Vec<(usize, usize)>,
}

impl Lu {
    /// Factorises the n x n matrix `a` (column-major, length n^2). A column without a
    /// nonzero pivot is skipped, as nalgebra does; [`Lu::solve`] then reports the matrix
    /// singular.
    pub fn new(mut a: Vec<f64>, n: usize) -> Self {
        assert_eq!(a.len(), n * n, "an n x n matrix");
        let mut swaps = Vec::new();
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU supports AVX2 (checked just above).
                unsafe { avx2::factor(&mut a, n, &mut swaps) };
                return Self { n, a, swaps };
            }
        }
        factor(&mut a, n, &mut swaps);
        Self { n, a, swaps }
    }

    /// Solves A X = B for the `m` columns of `b` (column-major, n x m) in place; `None` when a
    /// diagonal entry of U is zero (the matrix is singular).
    pub fn solve(&self, b: &mut [f64], m: usize) -> Option<()> {
        assert_eq!(b.len(), self.n * m, "n x m right-hand sides");
        if self.n == 0 {
            return Some(());
        }
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU supports AVX2 (checked just above).
                return unsafe { avx2::solve(self, b) };
            }
        }
        solve(self, b)
    }
}

/// y <- y + s x, element by element (no fused multiply-add: the same bits in every
/// compilation); inlined into each compilation of its callers.
#[inline(always)]
fn axpy(y: &mut [f64], s: f64, x: &[f64]) {
    for (yi, &xi) in y.iter_mut().zip(x) {
        *yi += s * xi;
    }
}

/// The elimination of [`Lu::new`] on `a` (n x n, column-major), recording the row swaps.
#[inline(always)]
fn factor(a: &mut [f64], n: usize, swaps: &mut Vec<(usize, usize)>) {
    for i in 0..n {
        let col = &a[i * n..(i + 1) * n];
        let (mut piv, mut best) = (i, col[i].abs());
        for (k, v) in col.iter().enumerate().skip(i + 1) {
            if v.abs() > best {
                best = v.abs();
                piv = k;
            }
        }
        let diag = col[piv];
        if diag == 0.0 {
            continue;
        }
        if piv != i {
            swaps.push((i, piv));
            for j in 0..=i {
                a.swap(j * n + i, j * n + piv);
            }
        }
        let inv = 1.0 / diag;
        let (left, right) = a.split_at_mut((i + 1) * n);
        let coeffs = &mut left[i * n + i + 1..];
        coeffs.iter_mut().for_each(|c| *c *= inv);
        for col in right.chunks_exact_mut(n) {
            if piv != i {
                col.swap(i, piv);
            }
            let u = col[i];
            axpy(&mut col[i + 1..], -u, coeffs);
        }
    }
}

/// The solves of [`Lu::solve`] for the columns of `b`.
#[inline(always)]
fn solve(lu: &Lu, b: &mut [f64]) -> Option<()> {
    let n = lu.n;
    for &(i, p) in &lu.swaps {
        for col in b.chunks_exact_mut(n) {
            col.swap(i, p);
        }
    }
    for col in b.chunks_exact_mut(n) {
        for i in 0..n.saturating_sub(1) {
            let coeff = col[i];
            axpy(&mut col[i + 1..], -coeff, &lu.a[i * n + i + 1..(i + 1) * n]);
        }
        for i in (0..n).rev() {
            let diag = lu.a[i * n + i];
            if diag == 0.0 {
                return None;
            }
            let coeff = col[i] / diag;
            col[i] = coeff;
            axpy(&mut col[..i], -coeff, &lu.a[i * n..i * n + i]);
        }
    }
    Some(())
}

/// The AVX2 compilations of [`factor`] and [`solve`] (the same operations).
#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::Lu;

    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn factor(a: &mut [f64], n: usize, swaps: &mut Vec<(usize, usize)>) {
        super::factor(a, n, swaps)
    }

    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn solve(lu: &Lu, b: &mut [f64]) -> Option<()> {
        super::solve(lu, b)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use nalgebra::DMatrix;

    /// Deterministic pseudo-random numbers in [-1, 1) (a fixed LCG: tests need spread, not
    /// quality).
    pub(crate) fn lcg(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    /// Verification: the factors and the solutions are nalgebra's bit for bit (the same
    /// operations in the same order), on matrices that pivot at most steps (random) and that
    /// never pivot (diagonally dominant), of sizes with and without vector tails, with several
    /// right-hand sides; and the solution solves the system (residual at roundoff).
    #[test]
    fn verification_lu_is_nalgebras_bit_for_bit() {
        let mut st = 11u64;
        for n in [1usize, 2, 5, 8, 13, 84, 97] {
            for dominant in [false, true] {
                let m = 13;
                let a: Vec<f64> = (0..n * n)
                    .map(|k| {
                        let v = lcg(&mut st);
                        if dominant && k % (n + 1) == 0 {
                            v + 4.0 * n as f64
                        } else {
                            v
                        }
                    })
                    .collect();
                let b: Vec<f64> = (0..n * m).map(|_| lcg(&mut st)).collect();
                let am = DMatrix::from_column_slice(n, n, &a);
                let bm = DMatrix::from_column_slice(n, m, &b);
                let theirs = am.clone().lu();
                let want = theirs.solve(&bm).unwrap();
                let lu = Lu::new(a.clone(), n);
                assert_eq!(
                    bits(&lu.a),
                    bits(theirs.lu_internal().as_slice()),
                    "factors, n {n}"
                );
                let mut x = b.clone();
                lu.solve(&mut x, m).unwrap();
                assert_eq!(
                    bits(&x),
                    bits(want.as_slice()),
                    "n {n}, dominant {dominant}"
                );
                // the baseline compilation too (the AVX2 one runs above where the CPU has it)
                let (mut plain, mut swaps) = (a.clone(), Vec::new());
                factor(&mut plain, n, &mut swaps);
                let plain = Lu { n, a: plain, swaps };
                let mut y = b.clone();
                solve(&plain, &mut y).unwrap();
                assert_eq!(bits(&y), bits(want.as_slice()), "baseline, n {n}");
                let r = &am * DMatrix::from_column_slice(n, m, &x) - &bm;
                assert!(r.amax() < 1e-10, "n {n}: residual {:e}", r.amax());
            }
        }
    }

    /// The bit patterns of `v` (a float comparison takes -0.0 for 0.0).
    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    /// A singular matrix (a zero column) is reported, not solved; an empty one solves.
    #[test]
    fn verification_a_singular_matrix_is_reported() {
        let a = vec![1.0, 2.0, 0.0, 0.0];
        let mut b = vec![1.0, 1.0];
        assert!(Lu::new(a, 2).solve(&mut b, 1).is_none());
        assert!(Lu::new(Vec::new(), 0).solve(&mut [], 3).is_some());
    }
}
