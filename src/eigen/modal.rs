//! Certified modes of an assembled FE model: shift-invert ARPACK on K - sigma M = L L^T,
//! residuals, M-orthogonality, and a Sturm count at a shift in a spectral gap.

use super::certify::{self, SturmCheck};
use super::{solve_modes, EigenError, EigenSettings, Modes};
use crate::fem::model::{FeModel, Timings};
use crate::linalg::factor::{Analysis, FactorError};
use crate::linalg::sparse::StiffnessMass;
use std::time::Instant;

/// Why a certified modal solve failed.
#[derive(Debug, thiserror::Error)]
pub enum ModalError {
    #[error(transparent)]
    Factor(#[from] FactorError),
    #[error(transparent)]
    Eigen(#[from] EigenError),
}

impl ModalError {
    /// 2 when the request cannot be met by this model or machine (too many modes), else 1.
    pub fn exit_code(&self) -> i32 {
        match self {
            ModalError::Eigen(EigenError::TooMany { .. } | EigenError::TooLarge { .. }) => 2,
            _ => 1,
        }
    }
}

/// Modal solution with its certificate.
pub struct ModalSolution {
    pub modes: Modes,
    pub residuals: Vec<f64>,
    pub m_orthogonality: f64,
    pub sturm: Option<SturmCheck>,
    pub sigma: f64,
}

impl FeModel {
    /// The lowest `count` modes with shift `sigma`, certified (residuals, M-orthogonality,
    /// Sturm count). `guard` extra modes are computed to locate a spectral gap for the check.
    pub fn modes(
        &mut self,
        count: usize,
        sigma: f64,
        guard: usize,
    ) -> Result<ModalSolution, ModalError> {
        let (sol, t) = certified_modes(&self.km, &self.analysis, count, sigma, guard)?;
        self.timings.factorisation = t.factorisation;
        self.timings.eigen = t.eigen;
        self.timings.certification = t.certification;
        Ok(sol)
    }
}

/// The lowest `count` modes of (K, M) on an analysed pattern, certified: shift-invert ARPACK
/// with K - sigma M = L L^T, residuals, M-orthogonality, and a Sturm count at a shift placed in
/// a spectral gap found among `guard` extra modes.
pub fn certified_modes(
    km: &StiffnessMass,
    analysis: &Analysis,
    count: usize,
    sigma: f64,
    guard: usize,
) -> Result<(ModalSolution, Timings), ModalError> {
    let mut timings = Timings::default();
    let n = km.pattern.n;
    let nev = (count + guard).min(n.saturating_sub(1)).max(count);
    let t = Instant::now();
    let shifted = km.shifted(sigma);
    let llt = analysis.llt(&km.pattern, &shifted)?;
    drop(shifted);
    timings.factorisation = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let pattern = &km.pattern;
    let m = &km.m;
    let all = solve_modes(
        n,
        &EigenSettings::new(nev, sigma),
        |x, y| pattern.matvec(m, x, y),
        |x| llt.solve_vec(x),
    )?;
    drop(llt);
    timings.eigen = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let sturm = match certify::sturm_shift(&all.eigenvalues, count, 1e-4) {
        Some((sigma_c, expected)) => {
            let found = analysis.negative_pivots(&km.pattern, &km.shifted(sigma_c))?;
            Some(SturmCheck {
                shift_hz: sigma_c.max(0.0).sqrt() / (2.0 * std::f64::consts::PI),
                expected,
                found,
                ok: found == expected,
            })
        }
        None => None,
    };
    let mut modes = all;
    modes.eigenvalues.truncate(count);
    modes.vectors.truncate(count * n);
    let residuals = certify::residuals(km, &modes, sigma);
    let m_orthogonality = certify::m_orthogonality_error(km, &modes);
    timings.certification = t.elapsed().as_secs_f64();
    Ok((
        ModalSolution {
            modes,
            residuals,
            m_orthogonality,
            sturm,
            sigma,
        },
        timings,
    ))
}
