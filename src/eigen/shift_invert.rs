//! ARPACK shift-invert driver (dsaupd mode 3, bmat = 'G', which = 'LM').
//!
//! With A = K - sigma M factorised once, the Lanczos iteration runs on the operator
//! OP = A^{-1} M in the M inner product; its eigenvalues nu = 1 / (lambda - sigma) are largest
//! for lambda nearest sigma, so a shift just below zero yields the lowest modes first, rigid-body
//! modes included (A stays positive definite for sigma < 0 even for a free-free part).
//! Eigenvectors come back M-orthonormal: phi_i^T M phi_j = delta_ij.

use super::arpack::{
    dsaupd_c, dseupd_c, saupd_message, seupd_message, take_lapack_error, ARPACK_LOCK,
};
use std::os::raw::c_int;

/// Settings of one eigen-solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EigenSettings {
    /// Number of eigenpairs wanted (lowest, rigid-body modes included).
    pub count: usize,
    /// Shift sigma [rad^2/s^2]; negative for free-free parts.
    pub sigma: f64,
    /// Lanczos basis size; 0 picks max(2 nev + 1, nev + 16), at most n.
    pub ncv: usize,
    /// Relative accuracy of the Ritz values (ARPACK tol); machine epsilon by default.
    pub tol: f64,
    /// Maximum number of implicit restarts.
    pub max_restarts: usize,
    /// Start-vector sequence (0: the default; another value gives another start vector, for
    /// a second solve after a missed mode).
    pub seed: u64,
}

impl EigenSettings {
    /// The Lanczos basis size on n DOFs: `ncv`, or max(2 nev + 1, nev + 16) when it is 0; at
    /// most n.
    pub fn basis_size(&self, n: usize) -> usize {
        let nev = self.count;
        if self.ncv == 0 {
            (2 * nev + 1).max(nev + 16).min(n)
        } else {
            self.ncv.clamp(nev + 1, n)
        }
    }

    pub fn new(count: usize, sigma: f64) -> Self {
        Self {
            count,
            sigma,
            ncv: 0,
            tol: f64::EPSILON,
            max_restarts: 500,
            seed: 0,
        }
    }
}

/// Eigenpairs and the work they took.
#[derive(Clone, Debug)]
pub struct Modes {
    /// Eigenvalues lambda = omega^2, ascending.
    pub eigenvalues: Vec<f64>,
    /// Mode shapes, column-major n x count, M-orthonormal.
    pub vectors: Vec<f64>,
    pub n: usize,
    /// Applications of A^{-1} (factor solves).
    pub solves: usize,
    /// Products with M.
    pub mass_products: usize,
    /// ARPACK's count of Arnoldi update iterations.
    pub restarts: usize,
    pub ncv: usize,
    /// Seconds spent in factor solves, in M products, and inside ARPACK itself.
    pub seconds_solve: f64,
    pub seconds_mass: f64,
    pub seconds_arpack: f64,
}

impl Modes {
    /// What the iteration cost, for the log: "Lanczos: N solves (s), M products (s), ARPACK s".
    pub fn work_summary(&self) -> String {
        format!(
            "Lanczos: {} solves ({:.2} s), {} M products ({:.2} s), ARPACK {:.2} s",
            self.solves,
            self.seconds_solve,
            self.mass_products,
            self.seconds_mass,
            self.seconds_arpack,
        )
    }
    pub fn count(&self) -> usize {
        self.eigenvalues.len()
    }
    /// Mode shape j.
    pub fn vector(&self, j: usize) -> &[f64] {
        &self.vectors[j * self.n..(j + 1) * self.n]
    }
    /// Natural frequency f = sqrt(max(lambda, 0)) / (2 pi) \[Hz\].
    pub fn frequency_hz(&self, j: usize) -> f64 {
        self.eigenvalues[j].max(0.0).sqrt() / (2.0 * std::f64::consts::PI)
    }
}

/// Eigen-solver failures, with ARPACK's code and meaning.
#[derive(Debug, thiserror::Error)]
pub enum EigenError {
    #[error("requested {count} modes but the model has only {n} DOFs")]
    TooMany { count: usize, n: usize },
    #[error("{count} modes of {n} DOFs need a Lanczos basis of about {gb} GB, more than the {available_gb} GB available: ask for fewer modes")]
    TooLarge {
        count: usize,
        n: usize,
        gb: String,
        available_gb: String,
    },
    #[error("ARPACK dsaupd failed (info = {info}): {msg}")]
    Saupd { info: i32, msg: &'static str },
    #[error("ARPACK converged only {converged} of {wanted} eigenpairs after {restarts} restarts ({msg})")]
    NotConverged {
        converged: usize,
        wanted: usize,
        restarts: usize,
        msg: &'static str,
    },
    #[error("ARPACK dseupd failed (info = {info}): {msg}")]
    Seupd { info: i32, msg: &'static str },
    #[error("ARPACK returned a non-finite eigenvalue (mode {index})")]
    NonFinite { index: usize },
    #[error("LAPACK routine {routine} (inside ARPACK) rejected its argument {argument} as illegal: the operator is not finite or badly scaled (check the material and the shift)")]
    Lapack { routine: String, argument: i32 },
}

/// Deterministic start vector (a fixed linear congruential sequence from `seed`), so runs are
/// repeatable.
fn start_vector(n: usize, seed: u64) -> Vec<f64> {
    let mut s: u64 = 0x2545_f491_4f6c_dd1d ^ seed.wrapping_mul(0x9e37_79b9_7f4a_7c15);
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            0.5 + ((s >> 11) as f64) / ((1u64 << 53) as f64)
        })
        .collect()
}

/// Lowest `settings.count` eigenpairs of (K, M) given y = M x (`mass`) and x <- A^{-1} x
/// (`solve`, A = K - sigma M): ARPACK's workspace (`Workspace::new`, refused when it would not
/// fit in memory), its reverse-communication loop (`Workspace::iterate`) and the Ritz
/// vectors (`Workspace::extract`), under the process-wide ARPACK lock. `solve` is dropped when
/// the iteration ends (a solve that owns its factor lets it go before the Ritz vectors).
pub fn solve_modes(
    n: usize,
    settings: &EigenSettings,
    mass: impl FnMut(&[f64], &mut [f64]),
    solve: impl FnMut(&mut [f64]),
) -> Result<Modes, EigenError> {
    let watch = Watch {
        ritz: |_: &[f64]| false,
        done: || (),
    };
    match solve_modes_watched(n, settings, mass, solve, watch)? {
        Watched::Done(modes) => Ok(modes),
        Watched::Stopped => unreachable!("a watcher that never stops stopped"),
    }
}

/// How a watched solve ended.
pub enum Watched {
    Done(Modes),
    /// The watcher stopped the iteration at its first restart.
    Stopped,
}

/// What a watched solve calls: `ritz` with the Ritz values of its first restart (true stops
/// the iteration there), `done` when the iteration has converged, before the Ritz vectors are
/// formed (where a caller lets its factor go).
pub struct Watch<R, D> {
    pub ritz: R,
    pub done: D,
}

/// As [`solve_modes`], watched ([`Watch`]): the Ritz values theta of the operator
/// (K - sigma M)^-1 M at the first restart (the ncv-step Lanczos factorisation's, in ARPACK's
/// workl at `ipntr(6)` as dsaupd documents it) are shown to `watch.ritz`, which may stop the
/// iteration there. By Cauchy interlacing the k-th largest Ritz value is at most the k-th
/// largest eigenvalue of the operator, so sigma + 1 / theta_k bounds lambda_k from above (sigma
/// below the spectrum). An iteration that converges before its first restart is not shown.
pub fn solve_modes_watched(
    n: usize,
    settings: &EigenSettings,
    mass: impl FnMut(&[f64], &mut [f64]),
    solve: impl FnMut(&mut [f64]),
    watch: Watch<impl FnMut(&[f64]) -> bool, impl FnOnce()>,
) -> Result<Watched, EigenError> {
    let mut ws = Workspace::new(n, settings)?;
    let _guard = ARPACK_LOCK.lock().unwrap_or_else(|p| p.into_inner());
    super::arpack::single_threaded_blas();
    take_lapack_error();
    let Some(work) = ws.iterate(settings, mass, solve, watch.ritz)? else {
        return Ok(Watched::Stopped);
    };
    (watch.done)();
    let t0 = std::time::Instant::now();
    let (eigenvalues, vectors) = ws.extract(settings)?;
    drop(_guard);
    Ok(Watched::Done(Modes {
        eigenvalues,
        vectors,
        n,
        solves: work.solves,
        mass_products: work.mass_products,
        restarts: work.restarts,
        ncv: ws.ncv,
        seconds_solve: work.seconds_solve,
        seconds_mass: work.seconds_mass,
        seconds_arpack: work.seconds_arpack + t0.elapsed().as_secs_f64(),
    }))
}

/// The LAPACK argument error recorded inside ARPACK since the last check, as an error.
fn lapack_failed() -> Option<EigenError> {
    take_lapack_error().map(|(routine, argument)| EigenError::Lapack { routine, argument })
}

/// What the reverse-communication loop did.
struct Work {
    solves: usize,
    mass_products: usize,
    restarts: usize,
    seconds_solve: f64,
    seconds_mass: f64,
    seconds_arpack: f64,
}

/// ARPACK's arrays for one solve, sized as dsaupd documents them: resid n, v n x ncv, workd 3n,
/// workl ncv (ncv + 8), iparam and ipntr 11.
struct Workspace {
    n: usize,
    nev: usize,
    ncv: usize,
    resid: Vec<f64>,
    v: Vec<f64>,
    workd: Vec<f64>,
    workl: Vec<f64>,
    iparam: [c_int; 11],
    ipntr: [c_int; 11],
}

impl Workspace {
    /// The workspace of `settings` on n DOFs: ncv = max(2 nev + 1, nev + 16) (or the
    /// settings' own) at most n; refused when nev is not below n, or when the Lanczos basis
    /// n x ncv, the eigenvectors n x nev and ARPACK's work would take more than 80 % of the
    /// available memory.
    fn new(n: usize, settings: &EigenSettings) -> Result<Self, EigenError> {
        let nev = settings.count;
        if nev == 0 || nev >= n {
            return Err(EigenError::TooMany { count: nev, n });
        }
        let ncv = settings.basis_size(n);
        let need = 8.0 * (n as f64 * (ncv + nev) as f64 + (ncv * (ncv + 8)) as f64);
        let available = crate::machine::available_memory() as f64;
        if need > 0.8 * available {
            return Err(EigenError::TooLarge {
                count: nev,
                n,
                gb: crate::text::num(need / 1e9),
                available_gb: crate::text::num(available / 1e9),
            });
        }
        let mut iparam = [0 as c_int; 11];
        iparam[0] = 1; // exact shifts
        iparam[2] = settings.max_restarts as c_int;
        iparam[6] = 3; // shift-invert mode
        Ok(Workspace {
            n,
            nev,
            ncv,
            resid: start_vector(n, settings.seed),
            v: vec![0.0; n * ncv],
            workd: vec![0.0; 3 * n],
            workl: vec![0.0; ncv * (ncv + 8)],
            iparam,
            ipntr: [0 as c_int; 11],
        })
    }

    /// dsaupd's reverse-communication loop: y = A^{-1} M x (ido -1), y = A^{-1} (M x) with M x
    /// given (ido 1), y = M x (ido 2), until it is done (99); then its info and the number of
    /// converged Ritz values checked. Before the first solve past the ncv + 1 of the first
    /// Lanczos factorisation (the start vector's and ncv steps), `ritz` sees the Ritz values
    /// of that factorisation; None when it stops the loop there.
    fn iterate(
        &mut self,
        settings: &EigenSettings,
        mut mass: impl FnMut(&[f64], &mut [f64]),
        mut solve: impl FnMut(&mut [f64]),
        mut ritz: impl FnMut(&[f64]) -> bool,
    ) -> Result<Option<Work>, EigenError> {
        let (n, nev, ncv) = (self.n, self.nev, self.ncv);
        let mut work = Work {
            solves: 0,
            mass_products: 0,
            restarts: 0,
            seconds_solve: 0.0,
            seconds_mass: 0.0,
            seconds_arpack: 0.0,
        };
        let mut tmp = vec![0.0; n];
        let mut ido: c_int = 0;
        let mut info: c_int = 1; // use resid as the start vector
        let clock = std::time::Instant::now;
        loop {
            let t0 = clock();
            // SAFETY: all arrays have the sizes dsaupd documents (Workspace); strings are
            // NUL-terminated.
            unsafe {
                dsaupd_c(
                    &mut ido,
                    c"G".as_ptr(),
                    n as c_int,
                    c"LM".as_ptr(),
                    nev as c_int,
                    settings.tol,
                    self.resid.as_mut_ptr(),
                    ncv as c_int,
                    self.v.as_mut_ptr(),
                    n as c_int,
                    self.iparam.as_mut_ptr(),
                    self.ipntr.as_mut_ptr(),
                    self.workd.as_mut_ptr(),
                    self.workl.as_mut_ptr(),
                    self.workl.len() as c_int,
                    &mut info,
                );
            }
            work.seconds_arpack += t0.elapsed().as_secs_f64();
            if let Some(e) = lapack_failed() {
                return Err(e);
            }
            if ido == 99 {
                break;
            }
            let x0 = self.ipntr[0] as usize - 1;
            let y0 = self.ipntr[1] as usize - 1;
            // M x first, where ARPACK does not supply it
            match ido {
                -1 | 2 => {
                    let t = clock();
                    mass(&self.workd[x0..x0 + n], &mut tmp);
                    work.mass_products += 1;
                    work.seconds_mass += t.elapsed().as_secs_f64();
                }
                1 => {
                    let b0 = self.ipntr[2] as usize - 1;
                    tmp.copy_from_slice(&self.workd[b0..b0 + n]);
                }
                other => unreachable!("ARPACK asked for unknown ido = {other}"),
            }
            if ido != 2 && work.solves == ncv + 1 && self.ritz_values().is_some_and(&mut ritz) {
                return Ok(None);
            }
            if ido != 2 {
                let t = clock();
                solve(&mut tmp);
                work.solves += 1;
                work.seconds_solve += t.elapsed().as_secs_f64();
            }
            self.workd[y0..y0 + n].copy_from_slice(&tmp);
        }
        work.restarts = self.iparam[2] as usize;
        if info < 0 {
            return Err(EigenError::Saupd {
                info,
                msg: saupd_message(info),
            });
        }
        let converged = self.iparam[4] as usize;
        if converged < nev {
            return Err(EigenError::NotConverged {
                converged,
                wanted: nev,
                restarts: work.restarts,
                msg: saupd_message(info),
            });
        }
        Ok(Some(work))
    }

    /// The ncv Ritz values of the last Lanczos factorisation in workl (at `ipntr(6)`, 1-based;
    /// None for a pointer out of range, not set).
    fn ritz_values(&self) -> Option<&[f64]> {
        let r0 = usize::try_from(self.ipntr[5]).ok()?.checked_sub(1)?;
        self.workl.get(r0..r0 + self.ncv)
    }

    /// dseupd's Ritz values and vectors of a converged loop, ascending: (eigenvalues, vectors
    /// column-major n x nev); a non-finite eigenvalue is an error naming the mode.
    fn extract(&mut self, settings: &EigenSettings) -> Result<(Vec<f64>, Vec<f64>), EigenError> {
        let (n, nev, ncv) = (self.n, self.nev, self.ncv);
        let select = vec![0 as c_int; ncv];
        let mut d = vec![0.0; nev];
        let mut z = vec![0.0; n * nev];
        let mut info: c_int = 0;
        // SAFETY: as in `iterate`; z is n x nev, d has nev entries, select ncv.
        unsafe {
            dseupd_c(
                1,
                c"A".as_ptr(),
                select.as_ptr(),
                d.as_mut_ptr(),
                z.as_mut_ptr(),
                n as c_int,
                settings.sigma,
                c"G".as_ptr(),
                n as c_int,
                c"LM".as_ptr(),
                nev as c_int,
                settings.tol,
                self.resid.as_mut_ptr(),
                ncv as c_int,
                self.v.as_mut_ptr(),
                n as c_int,
                self.iparam.as_mut_ptr(),
                self.ipntr.as_mut_ptr(),
                self.workd.as_mut_ptr(),
                self.workl.as_mut_ptr(),
                self.workl.len() as c_int,
                &mut info,
            );
        }
        if let Some(e) = lapack_failed() {
            return Err(e);
        }
        if info != 0 {
            return Err(EigenError::Seupd {
                info,
                msg: seupd_message(info),
            });
        }
        if let Some(index) = d.iter().position(|x| !x.is_finite()) {
            return Err(EigenError::NonFinite { index });
        }
        let mut order: Vec<usize> = (0..nev).collect();
        order.sort_by(|&a, &b| d[a].total_cmp(&d[b]));
        let eigenvalues = order.iter().map(|&i| d[i]).collect();
        let mut vectors = Vec::with_capacity(n * nev);
        for &i in &order {
            vectors.extend_from_slice(&z[i * n..(i + 1) * n]);
        }
        Ok((eigenvalues, vectors))
    }
}
