//! Factorisations of shifted symmetric matrices A = K - sigma M with faer's sparse supernodal
//! Cholesky, the symbolic analysis done once per pattern and reused for every shift.
//!
//! - `llt`: A = L L^T for A positive definite (shift below the spectrum); the solver of the
//!   shift-invert eigen iteration and of static problems.
//! - `inertia`: A = L D L^T without pivoting; by Sylvester's law of inertia the number of
//!   negative entries of D equals the number of eigenvalues of (K, M) below sigma (the Sturm
//!   count). Used only to certify eigen results, with sigma placed in a spectral gap.

use super::sparse::Pattern;
use super::tree_solve::TreePlan;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::{LdltParams, LdltRegularization};
use faer::linalg::cholesky::llt::factor::{LltParams, LltRegularization};
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::supernodal::{
    SupernodalLdltRef, SupernodalLltRef, SymbolicSupernodalCholesky,
};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::{Conj, MatMut, Par, Side, Spec};

/// Failures of the sparse factorisation, with the pivot where they happened.
#[derive(Debug, thiserror::Error)]
pub enum FactorError {
    #[error("symbolic analysis failed: {0}")]
    Symbolic(String),
    #[error("K - sigma M is not positive definite (pivot {pivot} of {n}): the model has unconstrained rigid-body motion at this shift, or a shift above the lowest eigenvalue")]
    NotPositive { pivot: usize, n: usize },
    #[error("zero pivot {pivot} of {n} in the LDL^T factorisation: the shift coincides with an eigenvalue")]
    ZeroPivot { pivot: usize, n: usize },
}

/// Symbolic analysis (ordering + supernodal structure) of one pattern.
pub struct Analysis {
    symbolic: SymbolicCholesky<usize>,
    /// The elimination tree's split for single-vector solves on both cores.
    plan: TreePlan,
    n: usize,
}

/// Parallelism of the numeric factorisation: rayon's pool (RAYON_NUM_THREADS=1 makes it
/// sequential).
fn par() -> Par {
    Par::rayon(0)
}

impl Analysis {
    /// Analyses `pattern` with the fill-reducing order `fwd` (fwd\[new\] = old) and its inverse.
    pub fn new(pattern: &Pattern, fwd: &[usize], inv: &[usize]) -> Result<Self, FactorError> {
        let perm = PermRef::new_checked(fwd, inv, pattern.n);
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let symbolic = factorize_symbolic_cholesky(
            pattern.symbolic(),
            Side::Lower,
            SymmetricOrdering::Custom(perm),
            params,
        )
        .map_err(|e| FactorError::Symbolic(format!("{e:?}")))?;
        let SymbolicCholeskyRaw::Supernodal(sym) = symbolic.raw() else {
            unreachable!("supernodal factorisation is forced above")
        };
        let plan = TreePlan::new(sym);
        Ok(Self {
            symbolic,
            plan,
            n: pattern.n,
        })
    }

    /// The supernodal structure (the analysis forces a supernodal factorisation).
    fn supernodes(&self) -> &SymbolicSupernodalCholesky<usize> {
        let SymbolicCholeskyRaw::Supernodal(sup) = self.symbolic.raw() else {
            unreachable!("supernodal factorisation is forced in the analysis")
        };
        sup
    }

    /// Number of stored entries of the factor L.
    pub fn factor_nnz(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Bytes of scratch the numeric L L^T (or L D L^T) factorisation takes beside the factor.
    pub fn factor_scratch_bytes(&self) -> usize {
        let llt = self
            .symbolic
            .factorize_numeric_llt_scratch::<f64>(par(), Spec::<LltParams, f64>::default());
        let ldlt = self
            .symbolic
            .factorize_numeric_ldlt_scratch::<f64>(par(), Spec::<LdltParams, f64>::default());
        llt.size_bytes().max(ldlt.size_bytes())
    }

    /// L L^T factorisation of the matrix with `values` on `pattern`.
    pub fn llt(&self, pattern: &Pattern, values: &[f64]) -> Result<Llt<'_>, FactorError> {
        let mut l = super::touch::zeros(self.symbolic.len_val());
        let req = self
            .symbolic
            .factorize_numeric_llt_scratch::<f64>(par(), Spec::<LltParams, f64>::default());
        let mut mem = MemBuffer::new(req);
        self.symbolic
            .factorize_numeric_llt(
                &mut l,
                pattern.matrix(values),
                Side::Lower,
                LltRegularization::default(),
                par(),
                MemStack::new(&mut mem),
                Spec::<LltParams, f64>::default(),
            )
            .map_err(|e| {
                let faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } = e;
                FactorError::NotPositive {
                    pivot: index,
                    n: self.n,
                }
            })?;
        Ok(Llt { analysis: self, l })
    }

    /// Number of negative pivots of the L D L^T factorisation of the matrix with `values`:
    /// the inertia count (number of eigenvalues below the shift).
    pub fn negative_pivots(&self, pattern: &Pattern, values: &[f64]) -> Result<usize, FactorError> {
        self.negative_pivots_in(pattern, values, None)
    }

    /// [`Analysis::negative_pivots`] with the factor's values written into `spare` when it has
    /// the analysis's size (the value array of an earlier factorisation on this analysis,
    /// [`Llt::into_values`]: its pages are already the process's, where a new array's are
    /// first touched; faer sets every entry before use).
    pub fn negative_pivots_in(
        &self,
        pattern: &Pattern,
        values: &[f64],
        spare: Option<Vec<f64>>,
    ) -> Result<usize, FactorError> {
        let len = self.symbolic.len_val();
        let mut l = match spare {
            Some(v) if v.len() == len => v,
            _ => super::touch::zeros(len),
        };
        let req = self
            .symbolic
            .factorize_numeric_ldlt_scratch::<f64>(par(), Spec::<LdltParams, f64>::default());
        let mut mem = MemBuffer::new(req);
        self.symbolic
            .factorize_numeric_ldlt(
                &mut l,
                pattern.matrix(values),
                Side::Lower,
                LdltRegularization::default(),
                par(),
                MemStack::new(&mut mem),
                Spec::<LdltParams, f64>::default(),
            )
            .map_err(|e| {
                let faer::linalg::cholesky::ldlt::factor::LdltError::ZeroPivot { index } = e;
                FactorError::ZeroPivot {
                    pivot: index,
                    n: self.n,
                }
            })?;
        let sym = self.supernodes();
        let ldlt = SupernodalLdltRef::new(sym, &l);
        let mut negative = 0;
        for s in 0..sym.n_supernodes() {
            let node = ldlt.supernode(s);
            let val = node.val();
            let ncols = val.ncols();
            for j in 0..ncols {
                let d = val[(j, j)];
                if d == 0.0 || !d.is_finite() {
                    return Err(FactorError::ZeroPivot {
                        pivot: node.start() + j,
                        n: self.n,
                    });
                }
                if d < 0.0 {
                    negative += 1;
                }
            }
        }
        Ok(negative)
    }
}

/// A numeric L L^T factor bound to its analysis.
pub struct Llt<'a> {
    analysis: &'a Analysis,
    l: Vec<f64>,
}

impl Llt<'_> {
    /// The factor's value array, let go of as a factor, for a later factorisation on the same
    /// analysis to write into ([`Analysis::negative_pivots_in`]).
    pub fn into_values(self) -> Vec<f64> {
        self.l
    }

    /// Solves A X = B in place for the columns of `rhs` (n x k, column-major), on the calling
    /// thread: faer's parallel supernodal solve sums in an order that depends on the number of
    /// threads (a ROM built on 1 core differed from one built on 2 in the last bits, and a
    /// slap transient amplifies that), and it was no faster here (single vectors are bound by
    /// reading the factor). Callers with many right-hand sides solve column blocks in parallel
    /// themselves, which keeps every column's arithmetic the same on any machine.
    pub fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        let k = rhs.ncols();
        let sym = &self.analysis.symbolic;
        let mut mem = MemBuffer::new(sym.solve_in_place_scratch::<f64>(k, Par::Seq));
        LltRef::new(sym, &self.l).solve_in_place_with_conj(
            Conj::No,
            rhs,
            Par::Seq,
            MemStack::new(&mut mem),
        );
    }

    /// The factor's fill-reducing order (fwd, inv), fwd\[new\] = old: A = P^T L L^T P with
    /// (P b)\[new\] = b\[fwd\[new\]\].
    pub fn order(&self) -> (&[usize], &[usize]) {
        self.analysis
            .symbolic
            .perm()
            .expect("a fill-reducing order is given")
            .arrays()
    }

    /// Z = L^-1 Z in place (the forward half of a solve), on rows in the factor's order
    /// ([`Llt::order`]), on the calling thread.
    pub fn forward_in_place(&self, rhs: MatMut<'_, f64>) {
        let (sup, mut mem) = self.supernodal(rhs.ncols());
        sup.l_solve_with_conj(Conj::No, rhs, Par::Seq, MemStack::new(&mut mem));
    }

    /// Z = L^-T Z in place (the backward half of a solve), on rows in the factor's order
    /// ([`Llt::order`]), on the calling thread.
    pub fn backward_in_place(&self, rhs: MatMut<'_, f64>) {
        let (sup, mut mem) = self.supernodal(rhs.ncols());
        sup.l_transpose_solve_with_conj(Conj::No, rhs, Par::Seq, MemStack::new(&mut mem));
    }

    /// The supernodal factor and the scratch of a solve with `k` right-hand sides.
    fn supernodal(&self, k: usize) -> (SupernodalLltRef<'_, usize, f64>, MemBuffer) {
        let sup = self.analysis.supernodes();
        let mem = MemBuffer::new(sup.solve_in_place_scratch::<f64>(k, Par::Seq));
        (SupernodalLltRef::new(sup, &self.l), mem)
    }

    /// Solves A x = b in place for one vector, on both cores along the elimination tree
    /// ([`super::tree_solve`]; the same bits on any number of threads): x = P^T L^-T L^-1 P b.
    pub fn solve_vec(&self, x: &mut [f64]) {
        let (fwd, inv) = self.order();
        let mut y: Vec<f64> = fwd.iter().map(|&f| x[f]).collect();
        self.analysis
            .plan
            .solve(self.analysis.supernodes(), &self.l, &mut y);
        for (xi, &i) in x.iter_mut().zip(inv) {
            *xi = y[i];
        }
    }
}
