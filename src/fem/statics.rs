//! Static solve K u = f on the free DOFs (sparse Cholesky), e.g. the head-bolt preload whose
//! displacement u0 is the initial state of a transient.

use crate::linalg::factor::{Analysis, FactorError};
use crate::linalg::sparse::StiffnessMass;

/// Solves K u = f with a prepared analysis of K's pattern.
pub fn solve(km: &StiffnessMass, analysis: &Analysis, f: &[f64]) -> Result<Vec<f64>, FactorError> {
    let llt = analysis.llt(&km.pattern, &km.k)?;
    let mut u = f.to_vec();
    llt.solve_vec(&mut u);
    Ok(u)
}
