//! A symmetric matrix that acts alike on three interleaved directions,
//!
//!   A = A_s ⊗ I_3:   A[3l + e, 3k + d] = delta_de a_lk,
//!
//! DOF 3k + d being direction d of node k. The consistent mass of isotropic solid elements is
//! one wherever every node keeps its three DOFs (a free or node-wise fixed part): the element
//! mass rho int N_a N_b couples like directions only, with the same value in each. Stored once
//! per node pair, with 32-bit rows, its product reads 12 bytes per node pair where the general
//! product ([`super::sparse::Pattern::matvec`]) reads 16 for each of the three directions: a
//! quarter of the memory traffic, which is what a sparse product on a large model costs.

use super::sparse::SymCsc;
use std::borrow::Cow;

/// A = A_s ⊗ I_3 with A_s stored by node columns (both triangles, rows ascending).
#[derive(Clone, Debug)]
pub struct Tripled {
    nodes: usize,
    col_ptr: Vec<usize>,
    rows: Vec<u32>,
    values: Vec<f64>,
}

/// Node columns per parallel task of [`Tripled::matvec`].
const CHUNK_NODES: usize = 2048;

impl Tripled {
    /// `a` as A_s ⊗ I_3 when it is exactly that: its order a multiple of 3, and the three
    /// columns 3k, 3k + 1, 3k + 2 of every node k holding the same nodes' rows (3l + d in
    /// column 3k + d) with the same values, bit for bit. None otherwise (a mass with a
    /// direction-dependent part, such as a coolant layer's normal mass, or a node with only
    /// some of its DOFs free).
    pub fn of(a: &SymCsc) -> Option<Self> {
        let p = &a.pattern;
        if p.n % 3 != 0 || p.n / 3 > u32::MAX as usize {
            return None;
        }
        let nodes = p.n / 3;
        let mut col_ptr = Vec::with_capacity(nodes + 1);
        col_ptr.push(0);
        let (mut rows, mut values) = (Vec::new(), Vec::new());
        for k in 0..nodes {
            let start = |d: usize| p.col_ptr[3 * k + d];
            let len = p.col_ptr[3 * k + 1] - start(0);
            for d in 1..3 {
                if p.col_ptr[3 * k + d + 1] - start(d) != len {
                    return None;
                }
            }
            for j in 0..len {
                let r0 = p.row_idx[start(0) + j];
                let v0 = a.values[start(0) + j];
                if r0 % 3 != 0 {
                    return None;
                }
                for d in 1..3 {
                    let q = start(d) + j;
                    if p.row_idx[q] != r0 + d || a.values[q].to_bits() != v0.to_bits() {
                        return None;
                    }
                }
                rows.push((r0 / 3) as u32);
                values.push(v0);
            }
            col_ptr.push(rows.len());
        }
        Some(Self {
            nodes,
            col_ptr,
            rows,
            values,
        })
    }

    /// y = A x: y_(3k+d) = sum_l a_lk x_(3l+d), the terms summed in the order column 3k + d
    /// of the general form holds them, so that the result is [`SymCsc::matvec`]'s bit for
    /// bit; parallel over node columns.
    pub fn matvec(&self, x: &[f64], y: &mut [f64]) {
        use rayon::prelude::*;
        assert_eq!(x.len(), 3 * self.nodes, "x has the matrix's order");
        y.par_chunks_mut(3 * CHUNK_NODES)
            .enumerate()
            .for_each(|(chunk, ys)| {
                let k0 = chunk * CHUNK_NODES;
                for (j, yk) in ys.chunks_exact_mut(3).enumerate() {
                    let k = k0 + j;
                    let (a, b) = (self.col_ptr[k], self.col_ptr[k + 1]);
                    let mut s = [-0.0f64; 3];
                    for (&l, &v) in self.rows[a..b].iter().zip(&self.values[a..b]) {
                        let xl = &x[3 * l as usize..3 * l as usize + 3];
                        s[0] += v * xl[0];
                        s[1] += v * xl[1];
                        s[2] += v * xl[2];
                    }
                    yk.copy_from_slice(&s);
                }
            });
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        8 * self.col_ptr.len() + 4 * self.rows.len() + 8 * self.values.len()
    }
}

/// y = A x by the cheaper exact form of a symmetric matrix: [`Tripled`] where `a` is one, the
/// general gather otherwise (the same bits either way).
pub struct Product<'a> {
    general: Option<Cow<'a, SymCsc>>,
    tripled: Option<Tripled>,
}

impl<'a> Product<'a> {
    /// The product of `general`, which stays the caller's (the tripled form beside it when
    /// `general` is one: a quarter of its bytes more).
    pub fn new(general: &'a SymCsc) -> Self {
        Self {
            tripled: Tripled::of(general),
            general: Some(Cow::Borrowed(general)),
        }
    }

    /// The product of `general`, kept only where it is not tripled (the tripled form takes a
    /// quarter of its bytes).
    pub fn owning(general: SymCsc) -> Product<'static> {
        match Tripled::of(&general) {
            Some(t) => Product {
                general: None,
                tripled: Some(t),
            },
            None => Product {
                general: Some(Cow::Owned(general)),
                tripled: None,
            },
        }
    }

    pub fn apply(&self, x: &[f64], y: &mut [f64]) {
        match (&self.tripled, &self.general) {
            (Some(t), _) => t.matvec(x, y),
            (None, Some(g)) => g.matvec(x, y),
            (None, None) => unreachable!("a product keeps one form"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::sparse::Pattern;

    /// A_s ⊗ I_3 of a random symmetric node matrix on a random node pattern (each node
    /// coupled with itself and a few others), both triangles, rows ascending.
    fn tripled_matrix(nodes: usize, seed: u64) -> SymCsc {
        let mut s = seed;
        let mut next = || {
            s = s
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut couple = vec![vec![0.0; nodes]; nodes];
        for k in 0..nodes {
            couple[k][k] = 1.0 + next();
            for _ in 0..3 {
                let l = (next() * nodes as f64) as usize % nodes;
                let v = next() - 0.5;
                couple[k][l] = v;
                couple[l][k] = v;
            }
        }
        let n = 3 * nodes;
        let (mut col_ptr, mut row_idx, mut values) = (vec![0], Vec::new(), Vec::new());
        for c in 0..n {
            for r in 0..n {
                let v = couple[r / 3][c / 3];
                if r % 3 == c % 3 && v != 0.0 {
                    row_idx.push(r);
                    values.push(v);
                }
            }
            col_ptr.push(row_idx.len());
        }
        SymCsc {
            pattern: Pattern {
                n,
                col_ptr,
                row_idx,
            },
            values,
        }
    }

    /// Verification: the tripled product equals the general one bit for bit (the same terms in
    /// the same order), on more nodes than one parallel chunk holds.
    #[test]
    fn verification_tripled_product_is_the_general_product() {
        let a = tripled_matrix(CHUNK_NODES + 77, 3);
        let t = Tripled::of(&a).expect("a tripled matrix is recognised");
        assert!(t.bytes() < a.values.len() * 16 / 2);
        let x: Vec<f64> = (0..a.pattern.n)
            .map(|i| ((i * 7919) % 1013) as f64 / 1013.0 - 0.4)
            .collect();
        let (mut y1, mut y2) = (vec![0.0; x.len()], vec![0.0; x.len()]);
        a.matvec(&x, &mut y1);
        t.matvec(&x, &mut y2);
        for (u, v) in y1.iter().zip(&y2) {
            assert_eq!(u.to_bits(), v.to_bits());
        }
    }

    /// Verification: a matrix that is not A_s ⊗ I_3 is left to the general product: one value
    /// of one direction changed, an entry coupling two directions, an order not a multiple
    /// of 3.
    #[test]
    fn verification_other_matrices_are_not_tripled() {
        let a = tripled_matrix(40, 5);
        assert!(Tripled::of(&a).is_some());
        let mut b = a.clone();
        let q = b.pattern.col_ptr[3 * 7 + 2];
        b.values[q] *= 1.0 + 1e-15;
        assert!(Tripled::of(&b).is_none(), "a direction-dependent value");
        // node 0's x column gains a y row of node 0: entries (1, 0) and (0, 1)
        let mut c = a.clone();
        let p = &mut c.pattern;
        let (mut col_ptr, mut rows, mut vals) = (vec![0], Vec::new(), Vec::new());
        for col in 0..p.n {
            let mut entries: Vec<(usize, f64)> = (p.col_ptr[col]..p.col_ptr[col + 1])
                .map(|q| (p.row_idx[q], c.values[q]))
                .collect();
            if col < 2 {
                entries.push((1 - col, 0.25));
                entries.sort_by_key(|e| e.0);
            }
            rows.extend(entries.iter().map(|e| e.0));
            vals.extend(entries.iter().map(|e| e.1));
            col_ptr.push(rows.len());
        }
        (p.col_ptr, p.row_idx, c.values) = (col_ptr, rows, vals);
        assert!(Tripled::of(&c).is_none(), "a coupling of two directions");
        let mut d = a;
        d.pattern.n -= 1;
        d.pattern.col_ptr.pop();
        assert!(Tripled::of(&d).is_none(), "an order not a multiple of 3");
    }
}
