//! Symmetric sparse matrices in compressed-column form with both triangles stored.
//!
//! K and M share one pattern ([`Pattern`]), so K - sigma M is a combination of two value arrays.
//! The pattern is built once from the node graph of the mesh: every node couples with the nodes
//! it shares an element with, each coupling a dense block over the free DOFs of the two nodes.
//! Rows within a column are sorted (faer requires it).

use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};

/// A symmetric sparse matrix (both triangles) on a pattern of its own.
#[derive(Clone, Debug)]
pub struct SymCsc {
    pub pattern: Pattern,
    pub values: Vec<f64>,
}

impl SymCsc {
    /// y = A x ([`Pattern::matvec`]).
    pub fn matvec(&self, x: &[f64], y: &mut [f64]) {
        self.pattern.matvec(&self.values, x, y)
    }
    /// Y = A X ([`Pattern::mul_dense`]).
    pub fn mul_dense(&self, x: faer::MatRef<'_, f64>, y: faer::MatMut<'_, f64>) {
        self.pattern.mul_dense(&self.values, x, y)
    }
    /// X <- P A P^T X in place ([`Pattern::mul_dense_permuted_in_place`]).
    pub fn mul_dense_permuted_in_place(
        &self,
        order: (&[usize], &[usize]),
        x: faer::MatMut<'_, f64>,
    ) {
        self.pattern
            .mul_dense_permuted_in_place(&self.values, order, x)
    }
}

/// Column-compressed symmetric pattern (both triangles), rows sorted in each column.
#[derive(Clone, Debug, PartialEq)]
pub struct Pattern {
    pub n: usize,
    pub col_ptr: Vec<usize>,
    pub row_idx: Vec<usize>,
}

impl Pattern {
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }
    /// faer view of the pattern.
    pub fn symbolic(&self) -> SymbolicSparseColMatRef<'_, usize> {
        // SAFETY-free: new_checked validates sortedness and bounds once.
        SymbolicSparseColMatRef::new_checked(self.n, self.n, &self.col_ptr, None, &self.row_idx)
    }
    /// faer view of a value array on this pattern.
    pub fn matrix<'a>(&'a self, values: &'a [f64]) -> SparseColMatRef<'a, usize, f64> {
        SparseColMatRef::new(self.symbolic(), values)
    }
    /// y = A x for a symmetric matrix stored with both triangles. By symmetry column c holds
    /// row c, so y_c = sum_p A[row_p, c] x\[row_p\]: a gather per column, parallel over columns.
    pub fn matvec(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        use rayon::prelude::*;
        y.par_chunks_mut(4096).enumerate().for_each(|(chunk, ys)| {
            let c0 = chunk * 4096;
            for (k, yc) in ys.iter_mut().enumerate() {
                let c = c0 + k;
                let (a, b) = (self.col_ptr[c], self.col_ptr[c + 1]);
                *yc = self.row_idx[a..b]
                    .iter()
                    .zip(&values[a..b])
                    .map(|(&r, &v)| v * x[r])
                    .sum();
            }
        });
    }
    /// Y = A X for a dense block X (column-major), blocked: 16 columns of X at a time are
    /// copied row-major so each stored entry of A is read once per block and multiplies a
    /// contiguous row of X (the single-vector gather is memory-bound on A).
    pub fn mul_dense(&self, values: &[f64], x: faer::MatRef<'_, f64>, y: faer::MatMut<'_, f64>) {
        const B: usize = 16;
        let n = self.n;
        self.blocked_product::<B, _>(
            values,
            x.ncols(),
            &mut (x, y),
            |(x, _), xr, c0, w| {
                for r in 0..n {
                    for k in 0..w {
                        xr[r * B + k] = x[(r, c0 + k)];
                    }
                }
            },
            |(_, y), yr, c0, w| {
                for r in 0..n {
                    for k in 0..w {
                        y[(r, c0 + k)] = yr[r * B + k];
                    }
                }
            },
        );
    }

    /// X <- P A P^T X in place for a dense block X whose rows are in the order `fwd`
    /// (fwd\[new\] = old, `inv` its inverse; (P x)\[new\] = x\[fwd\[new\]\]): the product
    /// of [`Pattern::mul_dense`] (the same sums in the same order) on 8 columns at a time, with
    /// two n x 8 buffers and no second block.
    pub fn mul_dense_permuted_in_place(
        &self,
        values: &[f64],
        (fwd, inv): (&[usize], &[usize]),
        mut x: faer::MatMut<'_, f64>,
    ) {
        const B: usize = 8;
        self.blocked_product::<B, _>(
            values,
            x.ncols(),
            &mut x,
            |x, xr, c0, w| {
                for (old, &new) in inv.iter().enumerate() {
                    for k in 0..w {
                        xr[old * B + k] = x[(new, c0 + k)];
                    }
                }
            },
            |x, yr, c0, w| {
                for (new, &old) in fwd.iter().enumerate() {
                    for k in 0..w {
                        x[(new, c0 + k)] = yr[old * B + k];
                    }
                }
            },
        );
    }

    /// The product A X of `ncol` columns, B at a time, X and the result reached through `blocks`:
    /// `gather(blocks, xr, c0, w)` puts columns c0 .. c0 + w of X interleaved into xr (row r's
    /// entries at r B ..), [`Pattern::interleaved_product`] forms yr = A xr, and
    /// `scatter(blocks, yr, c0, w)` takes them out. Two n x B buffers.
    fn blocked_product<const B: usize, S>(
        &self,
        values: &[f64],
        ncol: usize,
        blocks: &mut S,
        gather: impl Fn(&S, &mut [f64], usize, usize),
        scatter: impl Fn(&mut S, &[f64], usize, usize),
    ) {
        let mut xr = vec![0.0; self.n * B];
        let mut yr = vec![0.0; self.n * B];
        for c0 in (0..ncol).step_by(B) {
            let w = (ncol - c0).min(B);
            gather(blocks, &mut xr, c0, w);
            self.interleaved_product::<B>(values, &xr, &mut yr);
            scatter(blocks, &yr, c0, w);
        }
    }

    /// yr = A xr for B interleaved columns (row r's B entries at r B .. r B + B), rows on
    /// both cores; each row's sum runs over its stored entries in order.
    fn interleaved_product<const B: usize>(&self, values: &[f64], xr: &[f64], yr: &mut [f64]) {
        use rayon::prelude::*;
        yr.par_chunks_mut(B * 1024)
            .enumerate()
            .for_each(|(chunk, ys)| {
                let r0 = chunk * 1024;
                for (i, yrow) in ys.chunks_mut(B).enumerate() {
                    let r = r0 + i;
                    let mut acc = [0.0f64; B];
                    for p in self.col_ptr[r]..self.col_ptr[r + 1] {
                        let v = values[p];
                        let xrow = &xr[self.row_idx[p] * B..self.row_idx[p] * B + B];
                        for k in 0..B {
                            acc[k] += v * xrow[k];
                        }
                    }
                    yrow.copy_from_slice(&acc);
                }
            });
    }
    /// The entries of `values` on this pattern that are not exactly zero, on a pattern of
    /// their own. An assembled consistent mass matrix couples only like directions
    /// (M_ab = int rho N_a N_b dV I_3): two thirds of the node-block pattern it shares with K
    /// hold zeros, which its products would read for nothing. The products of the compressed
    /// matrix equal the full ones (each sum loses only exact zero terms).
    pub fn compress(&self, values: &[f64]) -> SymCsc {
        let mut col_ptr = Vec::with_capacity(self.n + 1);
        col_ptr.push(0);
        let (mut row_idx, mut kept) = (Vec::new(), Vec::new());
        for c in 0..self.n {
            for q in self.col_ptr[c]..self.col_ptr[c + 1] {
                if values[q] != 0.0 {
                    row_idx.push(self.row_idx[q]);
                    kept.push(values[q]);
                }
            }
            col_ptr.push(row_idx.len());
        }
        SymCsc {
            pattern: Pattern {
                n: self.n,
                col_ptr,
                row_idx,
            },
            values: kept,
        }
    }
    /// Entries (row, col, value) of the lower triangle, column by column.
    pub fn lower_entries<'a>(
        &'a self,
        values: &'a [f64],
    ) -> impl Iterator<Item = (usize, usize, f64)> + 'a {
        (0..self.n).flat_map(move |c| {
            (self.col_ptr[c]..self.col_ptr[c + 1])
                .filter(move |&p| self.row_idx[p] >= c)
                .map(move |p| (self.row_idx[p], c, values[p]))
        })
    }
    /// Dense copy (tests and small models only).
    pub fn to_dense(&self, values: &[f64]) -> Vec<Vec<f64>> {
        let mut a = vec![vec![0.0; self.n]; self.n];
        for c in 0..self.n {
            for p in self.col_ptr[c]..self.col_ptr[c + 1] {
                let r = self.row_idx[p];
                a[r][c] = values[p];
            }
        }
        a
    }
}

/// Sparse symmetric matrix on a shared pattern: K and M of one model.
#[derive(Clone, Debug)]
pub struct StiffnessMass {
    pub pattern: Pattern,
    pub k: Vec<f64>,
    pub m: Vec<f64>,
}

impl StiffnessMass {
    /// The principal submatrices on the indices `map` keeps: `map[old]` the new index (in the
    /// same order as the old ones) or `usize::MAX` for a dropped row and column.
    pub fn restrict(&self, map: &[usize], n: usize) -> Self {
        let p = &self.pattern;
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0);
        let (mut row_idx, mut k, mut m) = (Vec::new(), Vec::new(), Vec::new());
        for c in 0..p.n {
            if map[c] == usize::MAX {
                continue;
            }
            for q in p.col_ptr[c]..p.col_ptr[c + 1] {
                let r = map[p.row_idx[q]];
                if r != usize::MAX {
                    row_idx.push(r);
                    k.push(self.k[q]);
                    m.push(self.m[q]);
                }
            }
            col_ptr.push(row_idx.len());
        }
        Self {
            pattern: Pattern {
                n,
                col_ptr,
                row_idx,
            },
            k,
            m,
        }
    }

    /// The eigenvalues' scale trace(K) / trace(M) (their mean when M is a multiple of the
    /// identity; the order of the mesh's highest eigenvalues otherwise).
    pub fn eigenvalue_scale(&self) -> f64 {
        let p = &self.pattern;
        let (mut k, mut m) = (0.0, 0.0);
        for c in 0..p.n {
            let range = p.col_ptr[c]..p.col_ptr[c + 1];
            if let Some(q) = range.clone().find(|&q| p.row_idx[q] == c) {
                k += self.k[q];
                m += self.m[q];
            }
        }
        k / m
    }

    /// Values of K - sigma M on the shared pattern.
    pub fn shifted(&self, sigma: f64) -> Vec<f64> {
        self.k
            .iter()
            .zip(&self.m)
            .map(|(k, m)| k - sigma * m)
            .collect()
    }
}
