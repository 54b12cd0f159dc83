//! The engine reduced-order model: crankcase + liners coupled through shared interface
//! coordinates, diagonalised into system modes with a static correction.
//!
//! Coordinates of the assembled model: all reduced coordinates of the crankcase (its interface
//! coordinates at every bore, its fixed-interface modes, its attachment modes), then per
//! modelled cylinder the liner's private coordinates (guide tangential/axial field, its
//! fixed-interface modes and attachment modes). The liner's seat field and guide radial field
//! are the crankcase's coordinates of that bore (shared), which couples the parts:
//! K_g = sum_p L_p^T K_p L_p, M_g likewise (L_p the 0/1 index map of part p).
//!
//! System modes: K_g y = lambda M_g y, solved densely by M_g = C C^T and the symmetric
//! eigenproblem of C^-1 K_g C^-T; modes kept up to the cut-off, mass-normalised. Static
//! correction at the contact DOFs (residual flexibility of the dropped modes):
//! R = G (sum_{dropped} y y^T / lambda) G^T, G the output rows of the contact DOFs.
//! Preload: K_g u0 = F_clamp (liner flange top pressed down, bolt reaction up on the deck).

use super::craig_bampton::{symmetrise, PartReduction};
use crate::eigen::dense_lanczos::{self, product as mul};
use faer::linalg::solvers::Solve;
use faer::{Mat, MatRef, Side};
use rayon::prelude::*;

pub use crate::linalg::dense::Dense;

/// Where a part's reduced coordinates go in the assembled model.
pub struct Placement<'a> {
    pub part: &'a PartReduction,
    /// Global index of each reduced coordinate of the part.
    pub map: Vec<usize>,
}

/// The system's lowest modes and what the dropped ones leave: the stiffness factor for static
/// solves and the flexibility of the modes above the kept ones.
pub struct SystemModes {
    /// Eigenvalues of the lowest system modes, ascending: the kept modes and a block above
    /// them (p = max(400, 3/2 x kept) of them from the whole decomposition, kept + 64 from
    /// block Lanczos; all when the system is smaller).
    pub lambdas: Vec<f64>,
    /// Mass-normalised eigenvectors (global coordinates x `lambdas.len()`).
    pub vectors: Mat<f64>,
    /// The assembled stiffness and mass.
    pub k: Mat<f64>,
    pub m: Mat<f64>,
    /// The unit-modal-mass scaling D and the Cholesky factor of K' = D K D.
    scale: Vec<f64>,
    kchol: faer::linalg::solvers::Llt<f64>,
}

/// Systems with more coordinates than this are solved for their lowest modes by block
/// Lanczos ([`crate::eigen::dense_lanczos`]); smaller ones are decomposed whole.
pub const LANCZOS_ABOVE: usize = 1500;

/// Accepted relative error bound of each Lanczos eigenvalue up to a tenth above the cut-off's
/// (the kept modes and any that could be among them) before the Rayleigh-Ritz step: 1e-8, far
/// below the 1e-5 the ROM is held to and above the roundoff floor of the shift-invert
/// products (1e-10 to 3e-9 near 9 kHz on the default engine).
const LANCZOS_TOL: f64 = 1e-8;

/// The same bound for the modes above, which only seed the error estimate's refinement.
const LANCZOS_REST_TOL: f64 = 1e-4;

/// Failure of the dense system solve.
#[derive(Debug, thiserror::Error)]
pub enum SystemError {
    #[error("the assembled reduced mass matrix is not positive definite: dependent reduced coordinates (interface shapes the part's mesh cannot carry?)")]
    MassNotPositive,
    #[error("the assembled reduced stiffness matrix is singular: the engine is not held (check the crankcase 'fix' sets)")]
    StiffnessSingular,
    #[error("dense eigen-decomposition did not converge")]
    Eigen,
}

/// Assembles the parts into global K_g, M_g of size `n`.
pub fn assemble(n: usize, parts: &[Placement<'_>]) -> (Mat<f64>, Mat<f64>) {
    let mut k = Mat::<f64>::zeros(n, n);
    let mut m = Mat::<f64>::zeros(n, n);
    for p in parts {
        let nr = p.part.size();
        for j in 0..nr {
            let gj = p.map[j];
            for i in 0..nr {
                let gi = p.map[i];
                k[(gi, gj)] += p.part.k[(i, j)];
                m[(gi, gj)] += p.part.m[(i, j)];
            }
        }
    }
    symmetrise(&mut k);
    symmetrise(&mut m);
    (k, m)
}

/// The lowest system modes of K y = lambda M y, mass-normalised: those up to `keep_lambda` (the
/// kept modes) and a block above them ([`SystemModes::lambdas`]), which the error estimate may
/// refine from. The dropped modes are not computed: what the ROM needs of them is their
/// flexibility, K^-1 less the kept modes' ([`SystemModes::dropped_flexibility`]).
///
/// The coordinates are first scaled to unit modal mass (D = diag(M)^-1/2, K' = D K D,
/// M' = D M D): constraint-mode columns carry metre-sized interface shapes next to
/// mass-normalised modes, and without the scaling roundoff grows with the spread of their
/// magnitudes. Systems above [`LANCZOS_ABOVE`] coordinates are solved by block Lanczos and
/// certified by a Sturm count at the gap above the kept modes; a count that disagrees (a
/// missed mode) or an iteration that does not converge falls back to the whole decomposition
/// (`dense_lowest`), which cannot miss one.
pub fn system_modes(
    k: Mat<f64>,
    m: &Mat<f64>,
    keep_lambda: f64,
) -> Result<SystemModes, SystemError> {
    system_modes_by(k, m, keep_lambda, Method::Auto)
}

/// How [`system_modes_by`] finds the lowest modes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Block Lanczos above [`LANCZOS_ABOVE`] coordinates (its basis at most half the system,
    /// else the whole decomposition), the whole decomposition below.
    Auto,
    /// The whole decomposition (`dense_lowest`).
    Dense,
    /// Block Lanczos whatever the size (basis up to the whole system), falling back as
    /// [`Method::Auto`] does (tests).
    Lanczos,
}

/// [`system_modes`] by a chosen method.
pub fn system_modes_by(
    k: Mat<f64>,
    m: &Mat<f64>,
    keep_lambda: f64,
    method: Method,
) -> Result<SystemModes, SystemError> {
    let n = k.nrows();
    let t0 = std::time::Instant::now();
    let (d, ks, ms) = unit_mass_scaling(&k, m);
    let kchol = ks
        .llt(Side::Lower)
        .map_err(|_| SystemError::StiffnessSingular)?;
    let below = |l: &[f64]| l.iter().take_while(|&&x| x <= keep_lambda).count();
    // the dense path's refinement block (module docs of `dense_lowest`)
    let wanted = |l: &[f64]| n.min(400.max(3 * below(l) / 2));
    // Lanczos needs no refinement block: the kept modes and a block above them.
    let wanted_lanczos = |l: &[f64]| n.min(below(l) + dense_lanczos::BLOCK);
    let lanczos = match method {
        Method::Auto if n > LANCZOS_ABOVE => {
            lanczos_lowest(&ks, &ms, &kchol, &wanted_lanczos, keep_lambda, n / 2)
        }
        Method::Lanczos => lanczos_lowest(&ks, &ms, &kchol, &wanted_lanczos, keep_lambda, n),
        _ => None,
    };
    let (lambdas, mut y) = match lanczos {
        Some(found) => found,
        None => dense_lowest(&ks, &ms, &kchol, &wanted)?,
    };
    log::info!(
        "system: lowest {} of {n} modes in {:.2} s",
        lambdas.len(),
        t0.elapsed().as_secs_f64()
    );
    for j in 0..y.ncols() {
        for i in 0..n {
            y[(i, j)] *= d[i];
        }
    }
    log::debug!(
        "system: n = {n}, lowest eigenvalues {:?}",
        &lambdas[..lambdas.len().min(4)]
    );
    if lambdas.first().is_some_and(|&l| l <= 0.0) {
        return Err(SystemError::StiffnessSingular);
    }
    Ok(SystemModes {
        lambdas,
        vectors: y,
        k,
        m: m.clone(),
        scale: d,
        kchol,
    })
}

/// Block Lanczos for the lowest modes of the scaled pencil, certified: the number of
/// eigenvalues below the midpoint of the gap above the kept ones (Sturm count) must equal the
/// number found there. `None` (with a log line) when the iteration gave no answer or the count
/// disagrees.
fn lanczos_lowest(
    ks: &Mat<f64>,
    ms: &Mat<f64>,
    kchol: &faer::linalg::solvers::Llt<f64>,
    wanted: &dyn Fn(&[f64]) -> usize,
    keep_lambda: f64,
    max_basis: usize,
) -> Option<(Vec<f64>, Mat<f64>)> {
    use crate::eigen::dense_lanczos::{count_below, lowest_modes, Target};
    let n = ks.nrows();
    let target = Target {
        count: wanted,
        accurate_below: 1.1 * keep_lambda,
        tol: LANCZOS_TOL,
        rest_tol: LANCZOS_REST_TOL,
    };
    let low = match lowest_modes(ks.as_ref(), ms.as_ref(), kchol, &target, max_basis) {
        Ok(low) => low,
        Err(e) => {
            log::warn!("system: block Lanczos gave no answer ({e}); decomposing all {n} modes");
            return None;
        }
    };
    let kept = low
        .lambdas
        .iter()
        .take_while(|&&l| l <= keep_lambda)
        .count();
    if kept < low.lambdas.len() {
        let lo = if kept > 0 { low.lambdas[kept - 1] } else { 0.0 };
        let sigma = 0.5 * (lo.max(keep_lambda) + low.lambdas[kept]);
        let t = std::time::Instant::now();
        let below = count_below(ks.as_ref(), ms.as_ref(), sigma);
        log::debug!("system: Sturm count in {:.2} s", t.elapsed().as_secs_f64());
        if below != kept {
            log::warn!(
                "system: the Sturm count at {:.1} Hz found {below} modes below, block Lanczos {kept}; decomposing all {n} modes",
                hz(sigma)
            );
            return None;
        }
        log::info!(
            "system: certified: {kept} modes below {:.1} Hz (Sturm count)",
            hz(sigma)
        );
    }
    Some((low.lambdas, low.vectors))
}

/// All modes of the scaled pencil by the symmetric eigenproblem of C^-1 K' C^-T (M' = C C^T),
/// then the lowest p = `wanted` refined by subspace iteration ([`subspace_refine`]) and the
/// rest dropped.
///
/// The dense solve has an absolute eigenvalue error of order eps times the largest eigenvalue
/// of the standard form, which on the default engine moved low modes by up to 15 % (a spurious
/// mode at 1094 Hz, others below the full FE model's, which a Ritz reduction cannot give).
/// Refining the lowest p modes by subspace iteration with K'^-1 M' (Rayleigh-Ritz each pass,
/// K' factorised once): W = K'^-1 M' Y, (W^T K' W) x = lambda (W^T M' W) x, Y = W X. The Ritz
/// values are upper bounds of the exact ones and converge at (lambda_i / lambda_{p+1})^k.
fn dense_lowest(
    ks: &Mat<f64>,
    ms: &Mat<f64>,
    kchol: &faer::linalg::solvers::Llt<f64>,
    wanted: &dyn Fn(&[f64]) -> usize,
) -> Result<(Vec<f64>, Mat<f64>), SystemError> {
    let chol = ms
        .llt(Side::Lower)
        .map_err(|_| SystemError::MassNotPositive)?;
    let c = chol.L();
    let at = standard_form(c, ks.clone());
    let (mut lambdas, mut y) = symmetric_evd(at.as_ref())?;
    // y = C^-T z
    faer::linalg::triangular_solve::solve_upper_triangular_in_place(
        c.transpose(),
        y.as_mut(),
        faer::Par::rayon(0),
    );
    let p = wanted(&lambdas);
    if p > 0 {
        let before: Vec<f64> = lambdas[..p].to_vec();
        let (ritz, ys) = subspace_refine(ks, ms, kchol, y.as_ref().subcols(0, p).to_owned())?;
        lambdas[..p].copy_from_slice(&ritz);
        y.as_mut().subcols_mut(0, p).copy_from(&ys);
        if log::log_enabled!(log::Level::Info) {
            let change = (0..p)
                .map(|i| ((lambdas[i] - before[i]) / before[i]).abs())
                .fold(0.0f64, f64::max);
            log::info!("system: refined {p} modes, largest relative eigenvalue change {change:e}");
        }
    }
    lambdas.truncate(p);
    Ok((lambdas, y.as_ref().subcols(0, p).to_owned()))
}

impl SystemModes {
    /// K^-1 x = D K'^-1 D x, solved in panels of 16 columns on both cores.
    pub fn static_solve(&self, f: MatRef<'_, f64>) -> Mat<f64> {
        let d = &self.scale;
        let mut x = Mat::from_fn(f.nrows(), f.ncols(), |i, j| d[i] * f[(i, j)]);
        let l = self.kchol.L();
        x.par_col_chunks_mut(16).for_each(|mut c| {
            faer::linalg::triangular_solve::solve_lower_triangular_in_place(
                l,
                c.as_mut(),
                faer::Par::Seq,
            );
            faer::linalg::triangular_solve::solve_upper_triangular_in_place(
                l.transpose(),
                c,
                faer::Par::Seq,
            );
        });
        for j in 0..x.ncols() {
            for i in 0..x.nrows() {
                x[(i, j)] *= d[i];
            }
        }
        x
    }

    /// The flexibility of the modes above the first `kept`, applied to the rows `g` (rows x
    /// global coordinates): F_d G^T = Y_d L_d^-1 Y_d^T G^T = K^-1 G^T - Y_k L_k^-1 (G Y_k)^T
    /// (global x rows), since K^-1 = Y L^-1 Y^T over all modes. Needs only the kept modes.
    pub fn dropped_flexibility(&self, kept: usize, g: MatRef<'_, f64>) -> Mat<f64> {
        let mut f = self.static_solve(g.transpose());
        let yk = self.vectors.as_ref().subcols(0, kept);
        let mut gy = mul(g, yk);
        for j in 0..kept {
            let s = 1.0 / self.lambdas[j];
            gy.col_mut(j).iter_mut().for_each(|v| *v *= s);
        }
        f -= mul(yk, gy.transpose());
        f
    }
}

/// Work split of [`symmetric_evd`]: a fixed degree, not the machine's thread count.
const EVD_SPLIT: usize = 2;

/// All eigenpairs A z = lambda z of a symmetric matrix (lower triangle read), ascending, on a
/// fixed two-way (`EVD_SPLIT`) split of faer's parallel kernels: the split, and so every sum, is
/// the same whatever number of threads runs it (a 1-CPU task gets the same bits as a 2-core
/// machine; unit test), unlike the machine-sized default, while the decomposition of the
/// system's few thousand coordinates, the largest serial cost of a ROM build, gets both cores.
pub fn symmetric_evd(a: faer::MatRef<'_, f64>) -> Result<(Vec<f64>, Mat<f64>), SystemError> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::evd;
    let n = a.nrows();
    let par = faer::Par::rayon(EVD_SPLIT);
    let params = Default::default();
    let mut mem = MemBuffer::new(evd::self_adjoint_evd_scratch::<f64>(
        n,
        evd::ComputeEigenvectors::Yes,
        par,
        params,
    ));
    let mut s = faer::diag::Diag::<f64>::zeros(n);
    let mut u = Mat::<f64>::zeros(n, n);
    evd::self_adjoint_evd(
        a,
        s.as_mut(),
        Some(u.as_mut()),
        par,
        MemStack::new(&mut mem),
        params,
    )
    .map_err(|_| SystemError::Eigen)?;
    let s = s.column_vector();
    Ok(((0..n).map(|i| s[i]).collect(), u))
}

/// The scaling to unit modal mass of [`system_modes`]: D = diag(M)^-1/2 (1 where M_ii <= 0),
/// K' = D K D, M' = D M D. Returns (D, K', M').
fn unit_mass_scaling(k: &Mat<f64>, m: &Mat<f64>) -> (Vec<f64>, Mat<f64>, Mat<f64>) {
    let n = k.nrows();
    let d: Vec<f64> = (0..n)
        .map(|i| {
            if m[(i, i)] > 0.0 {
                1.0 / m[(i, i)].sqrt()
            } else {
                1.0
            }
        })
        .collect();
    let ks = Mat::from_fn(n, n, |i, j| d[i] * k[(i, j)] * d[j]);
    let ms = Mat::from_fn(n, n, |i, j| d[i] * m[(i, j)] * d[j]);
    (d, ks, ms)
}

/// Three passes of subspace iteration with K'^-1 M' from the block `ys` (Rayleigh-Ritz each
/// pass, K' = `kchol` factorised once): W = K'^-1 M' Y, (W^T K' W) x = lambda (W^T M' W) x,
/// Y = W X. Returns the Ritz values (ascending, upper bounds of the exact eigenvalues,
/// converging at (lambda_i / lambda_{p+1})^k) and the M'-orthonormal Ritz vectors.
fn subspace_refine(
    ks: &Mat<f64>,
    ms: &Mat<f64>,
    kchol: &faer::linalg::solvers::Llt<f64>,
    mut ys: Mat<f64>,
) -> Result<(Vec<f64>, Mat<f64>), SystemError> {
    let p = ys.ncols();
    let mut ritz = vec![0.0; p];
    for _ in 0..3 {
        let w = kchol.solve(mul(ms.as_ref(), ys.as_ref()));
        let mut kp = mul(w.transpose(), mul(ks.as_ref(), w.as_ref()).as_ref());
        let mut mp = mul(w.transpose(), mul(ms.as_ref(), w.as_ref()).as_ref());
        symmetrise(&mut kp);
        symmetrise(&mut mp);
        let cp = mp
            .llt(Side::Lower)
            .map_err(|_| SystemError::MassNotPositive)?;
        let ap = standard_form(cp.L(), kp);
        let e = ap
            .self_adjoint_eigen(Side::Lower)
            .map_err(|_| SystemError::Eigen)?;
        let mut q = e.U().to_owned();
        faer::linalg::triangular_solve::solve_upper_triangular_in_place(
            cp.L().transpose(),
            q.as_mut(),
            faer::Par::rayon(0),
        );
        ys = mul(w.as_ref(), q.as_ref());
        let sv = e.S().column_vector();
        for (i, r) in ritz.iter_mut().enumerate() {
            *r = sv[i];
        }
    }
    Ok((ritz, ys))
}

/// The lowest eigenvalues of K y = lambda M y refined from a start block (columns: vectors in
/// the coordinates of K and M, e.g. the modes of a nearby system) by `subspace_refine` after
/// the unit-modal-mass scaling of [`system_modes`]: as many Ritz values as start vectors,
/// without the dense solve of the whole spectrum.
pub fn refined_eigenvalues(
    k: &Mat<f64>,
    m: &Mat<f64>,
    start: faer::MatRef<'_, f64>,
) -> Result<Vec<f64>, SystemError> {
    let n = k.nrows();
    let (d, ks, ms) = unit_mass_scaling(k, m);
    let kchol = ks
        .llt(Side::Lower)
        .map_err(|_| SystemError::StiffnessSingular)?;
    let ys = Mat::from_fn(n, start.ncols(), |i, j| start[(i, j)] / d[i]);
    Ok(subspace_refine(&ks, &ms, &kchol, ys)?.0)
}

/// The lowest `count` eigenvalues of K y = lambda M y by block Lanczos after the
/// unit-modal-mass scaling of [`system_modes`], those up to `accurate_below` to a relative
/// error bound `tol` (the others to 1e-4); `None` when the iteration gives no answer within
/// half the system.
pub fn lowest_eigenvalues(
    k: &Mat<f64>,
    m: &Mat<f64>,
    count: usize,
    accurate_below: f64,
    tol: f64,
) -> Option<Vec<f64>> {
    use crate::eigen::dense_lanczos::{lowest_modes, Target};
    let (_, ks, ms) = unit_mass_scaling(k, m);
    let kchol = ks.llt(Side::Lower).ok()?;
    let target = Target {
        count: &|_| count,
        accurate_below,
        tol,
        rest_tol: LANCZOS_REST_TOL,
    };
    let n = k.nrows();
    lowest_modes(ks.as_ref(), ms.as_ref(), &kchol, &target, n / 2)
        .ok()
        .map(|low| low.lambdas)
}

/// All eigenvalues of K y = lambda M y (ascending), rigid-body zeros allowed (diagnostics and
/// tests of free parts).
pub fn system_modes_allow_rigid(k: Mat<f64>, m: &Mat<f64>) -> Result<Vec<f64>, SystemError> {
    let chol = m
        .llt(Side::Lower)
        .map_err(|_| SystemError::MassNotPositive)?;
    standard_form(chol.L(), k)
        .self_adjoint_eigenvalues(Side::Lower)
        .map_err(|_| SystemError::Eigen)
}

/// A = C^-1 K C^-T for M = C C^T: the symmetric standard form of K y = lambda M y.
fn standard_form(c: faer::MatRef<'_, f64>, k: Mat<f64>) -> Mat<f64> {
    let mut a = k;
    let par = faer::Par::rayon(0);
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(c, a.as_mut(), par);
    let mut at = a.transpose().to_owned();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(c, at.as_mut(), par);
    symmetrise(&mut at);
    at
}

/// Frequency \[Hz\] of an eigenvalue lambda = omega^2.
pub fn hz(lambda: f64) -> f64 {
    lambda.max(0.0).sqrt() / (2.0 * std::f64::consts::PI)
}

/// Residual flexibility of the modes above the kept ones at the rows `g`, given
/// W = F_d G^T ([`SystemModes::dropped_flexibility`]): R = G W, symmetrised.
pub fn residual_flexibility(g: MatRef<'_, f64>, w: MatRef<'_, f64>) -> Mat<f64> {
    let mut r = mul(g, w);
    symmetrise(&mut r);
    r
}

/// Residual vectors (modal truncation augmentation) for loads G^T P (G: output rows x global,
/// P: rows x load patterns), given W = F_d G^T ([`SystemModes::dropped_flexibility`]): the
/// vectors X = W P = Y_d L_d^-1 Y_d^T G^T P span the dropped modes' static response to the
/// patterns; X is M-orthogonalised against the kept modes (it lies in span Y_d, so this only
/// removes roundoff). Projected on X, K_a = X^T K X (= P^T G X) and M_a = X^T M X; their
/// eigenvectors Z (M_a-normalised, directions with M_a ~ 0 dropped) give pseudo-modes
/// Y_a = X Z, mass-normalised and orthogonal to the kept modes, with frequencies above the
/// cut-off. Added to the kept modes they represent the patterns' static response exactly
/// (sum Y_a Y_a^T / mu = X K_a^-1 X^T) and the first inertia of the dropped modes: a fast
/// contact load sees the local liner mass, not only its static flexibility.
/// Returns Y_a (global x m) and mu (ascending).
pub fn residual_vectors(
    sys: &SystemModes,
    kept: usize,
    w: MatRef<'_, f64>,
    patterns: &Mat<f64>,
) -> Result<(Mat<f64>, Vec<f64>), SystemError> {
    let n = sys.k.nrows();
    if patterns.ncols() == 0 || kept >= n {
        return Ok((Mat::zeros(n, 0), Vec::new()));
    }
    let mut x = mul(w, patterns.as_ref());
    let yk = sys.vectors.as_ref().subcols(0, kept);
    let myk = mul(sys.m.as_ref(), yk);
    let c = mul(myk.transpose(), x.as_ref());
    x -= mul(yk, c.as_ref());
    let mut ka = mul(x.transpose(), mul(sys.k.as_ref(), x.as_ref()).as_ref());
    let mut ma = mul(x.transpose(), mul(sys.m.as_ref(), x.as_ref()).as_ref());
    symmetrise(&mut ka);
    symmetrise(&mut ma);
    let evd = ma
        .self_adjoint_eigen(Side::Lower)
        .map_err(|_| SystemError::Eigen)?;
    let s = evd.S().column_vector();
    let smax = (0..s.nrows()).map(|i| s[i]).fold(0.0f64, f64::max);
    let keep: Vec<usize> = (0..s.nrows()).filter(|&i| s[i] > 1e-12 * smax).collect();
    let q = evd.U();
    let t = Mat::from_fn(ma.nrows(), keep.len(), |i, k| {
        q[(i, keep[k])] / s[keep[k]].sqrt()
    });
    let kt = t.transpose() * (&ka * &t);
    let evd2 = kt
        .self_adjoint_eigen(Side::Lower)
        .map_err(|_| SystemError::Eigen)?;
    let mu: Vec<f64> = (0..keep.len())
        .map(|i| evd2.S().column_vector()[i])
        .collect();
    let z = &t * evd2.U();
    let ya = mul(x.as_ref(), z.as_ref());
    Ok((ya, mu))
}

#[cfg(test)]
mod evd_tests {
    use super::symmetric_evd;

    /// Verification: the fixed-split decomposition reproduces A (|A Z - Z Lambda| at roundoff:
    /// 1e-10 of |A| for n = 800, large enough for faer's blocked parallel kernels), and gives the same bits in a 1-thread pool as in a 2-thread
    /// one (the property ROM builds rely on).
    #[test]
    fn verification_fixed_split_evd_is_exact_and_ignores_the_thread_count() {
        let n = 800;
        let a = faer::Mat::<f64>::from_fn(n, n, |i, j| {
            let (i, j) = (i.max(j), i.min(j));
            (((i * 7919 + j * 104729) % 1013) as f64 - 506.0) / 506.0
                + if i == j { 3.0 } else { 0.0 }
        });
        let (l2, z2) = symmetric_evd(a.as_ref()).unwrap();
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let (l1, z1) = one.install(|| symmetric_evd(a.as_ref()).unwrap());
        assert_eq!(l1, l2);
        assert!((0..n).all(|j| (0..n).all(|i| z1[(i, j)].to_bits() == z2[(i, j)].to_bits())));
        let scale = a.norm_l2();
        let mut r = &a * &z2;
        for j in 0..n {
            for i in 0..n {
                r[(i, j)] -= z2[(i, j)] * l2[j];
            }
        }
        assert!(r.norm_l2() < 1e-10 * scale, "{}", r.norm_l2() / scale);
    }
}
