//! Certified modes of an assembled FE model: shift-invert ARPACK on K - sigma M = L L^T,
//! residuals, M-orthogonality, and a Sturm count at a shift in a spectral gap.

use super::certify::{self, SturmCheck};
use super::shift_invert::{solve_modes_watched, Watch, Watched};
use super::{solve_modes, EigenError, EigenSettings, Modes};
use crate::fem::fields::{monomial_count, SmoothFields};
use crate::fem::model::{FeModel, Timings};
use crate::linalg::factor::{Analysis, FactorError};
use crate::linalg::sparse::{Pattern, StiffnessMass, SymCsc};
use crate::linalg::spill::{lower_shifted, spill_threshold};
use crate::scene::budget::SolveSizes;
use std::time::Instant;

/// Why a certified modal solve failed.
#[derive(Debug, thiserror::Error)]
pub enum ModalError {
    #[error(transparent)]
    Factor(#[from] FactorError),
    #[error(transparent)]
    Eigen(#[from] EigenError),
    #[error("the stiffness and mass matrices put aside on disk during the factorisation could not be read back: {0}")]
    Aside(std::io::Error),
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
    /// The shift the modes were solved at: the one asked for, or the one the smooth trial
    /// fields or [`placed_shift`] moved it to.
    pub sigma: f64,
    /// Modes the first Lanczos solve missed and a second one found (0: none missed).
    pub recovered: usize,
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
        self.modes_at(count, sigma, guard, true)
    }

    /// As [`FeModel::modes`]; `place`: move a shift far below the wanted modes to them (first
    /// judged on the model's smooth trial fields, [`crate::fem::fields`], then
    /// [`placed_shift`]), else solve at `sigma` as given.
    pub fn modes_at(
        &mut self,
        count: usize,
        sigma: f64,
        guard: usize,
        place: bool,
    ) -> Result<ModalSolution, ModalError> {
        let nev = count + guard;
        // the fields can only move a shift below zero
        let trial = (place && sigma < 0.0 && 3 * monomial_count(TRIAL_DEGREE) >= 2 * nev)
            .then(|| SmoothFields::new(&self.mesh, &self.dofs, TRIAL_DEGREE));
        let (km, analysis) = (&mut self.km, &self.analysis);
        let (sol, t) = certified_modes(km, analysis, count, sigma, guard, place, trial)?;
        self.timings.factorisation = t.factorisation;
        self.timings.eigen = t.eigen;
        self.timings.certification = t.certification;
        Ok(sol)
    }

    /// What solving `count` + `guard` modes of this model will hold
    /// ([`crate::scene::budget::modal_solve`]): known exactly once the model is analysed, so a
    /// solve that cannot fit is refused before its factorisation starts.
    pub fn modal_solve_sizes(&self, count: usize, guard: usize) -> SolveSizes {
        let n = self.n_free();
        let nev = (count + guard).min(n.saturating_sub(1)).max(count);
        let ncv = EigenSettings::new(nev, 0.0).basis_size(n);
        let factor_entries = self.analysis.factor_nnz();
        let nnz = self.km.pattern.nnz();
        // the mass couples only like directions: about a third of the pattern
        let mass_entries = nnz.div_ceil(3);
        let model = 24 * nnz + 8 * (n + 1);
        SolveSizes {
            dofs: n,
            factor_entries,
            factor_scratch: self.analysis.factor_scratch_bytes(),
            model,
            // they wait on disk when the factor is large and the temporary directory has room
            model_resident: factor_entries.saturating_mul(8) < spill_threshold()
                || !crate::linalg::spill::room_for(model),
            mass: 16 * mass_entries,
            // row indices and values of the lower triangle and the diagonal
            lower: 8 * (nnz + n),
            // the check's block of 2 nev columns with its product buffers, or ARPACK's basis,
            // its eigenvectors and its three work vectors
            columns: (2 * nev + 2 * GRAM_COLUMNS).max(ncv + nev + 3),
        }
    }
}

/// Degree of the smooth trial fields that judge a shift before the first factorisation
/// ([`FeModel::modes_at`]): 60 fields, used for up to 30 wanted modes (a bound of lambda_nev
/// from at least twice nev fields).
pub const TRIAL_DEGREE: usize = 3;

/// Re-solves after a Sturm count that finds more eigenvalues below its shift than were
/// computed (modes the Lanczos iteration missed): at most this many times.
const RECOVERY_ATTEMPTS: usize = 2;

/// The lowest `count` modes of (K, M) on an analysed pattern, certified: shift-invert ARPACK
/// with K - sigma M = L L^T, residuals, M-orthogonality, and a Sturm count at a shift placed in
/// a spectral gap found among `guard` extra modes.
///
/// When the count finds more eigenvalues below its shift than were computed, the missed modes
/// are recovered by the solver itself: solved again with every counted eigenvalue plus the
/// guard asked for and another start vector (up to `RECOVERY_ATTEMPTS` times), each result
/// certified anew; `recovered` tells how many modes the first solve had missed. A count below
/// the computed number (spurious eigenvalues) is reported, not retried; a re-solve that fails
/// (not converged) leaves the previous result with its failed certificate.
///
/// `place`: move a shift far below the wanted modes toward them ([`placed_shift`]), judged first
/// on the smooth trial fields `trial` when given (let go before the first factorisation).
pub fn certified_modes(
    km: &mut StiffnessMass,
    analysis: &Analysis,
    count: usize,
    sigma: f64,
    guard: usize,
    place: bool,
    trial: Option<SmoothFields>,
) -> Result<(ModalSolution, Timings), ModalError> {
    // the shift is checked on the first solve; re-solves keep the one it chose. The trial
    // block is let go before the first factorisation.
    let mut trial = trial;
    let solve = |km: &mut StiffnessMass, nev: usize, attempt: usize, sigma: f64| {
        let placement = match place && attempt == 0 {
            true => Placement::of(km, trial.take(), nev, sigma),
            false => Placement::none(sigma),
        };
        lanczos(km, analysis, nev, attempt as u64, placement)
    };
    certify_with_recovery(km, analysis, count, sigma, guard, solve)
}

/// How [`lanczos`] treats the shift it is given.
#[derive(Clone, Copy, Debug)]
struct Placement {
    /// The shift to start from.
    sigma: f64,
    /// Block checks of the shift left ([`placed_shift`]): one on the factor of each shift
    /// solved at, until a check keeps its shift or its bounds settle.
    checks: usize,
    /// The first iteration is watched ([`ritz_bound`]) rather than checked before it starts.
    watch: bool,
    /// Seconds spent placing the shift before any factorisation.
    seconds: f64,
}

impl Placement {
    /// The shift solved as given.
    fn none(sigma: f64) -> Self {
        Self {
            sigma,
            checks: 0,
            watch: false,
            seconds: 0.0,
        }
    }

    /// The shift `sigma` placed for `nev` modes: first judged by the Rayleigh-Ritz bound of
    /// lambda_nev on the trial fields `trial` when given ([`super::trial::trial_bound`], no
    /// factorisation). A shift that bound proves far ([`moved_shift`]) is moved before the
    /// first factorisation and block-checked before its iteration; one it leaves in doubt
    /// ([`shift_in_doubt`], as a first restart's bound would) is block-checked before its
    /// iteration where it stands; any other is watched.
    fn of(km: &StiffnessMass, trial: Option<SmoothFields>, nev: usize, sigma: f64) -> Self {
        let t = Instant::now();
        let bound = trial.and_then(|x| super::trial::trial_bound(km, &x, nev));
        let moved = bound.and_then(|b| moved_shift(b, sigma));
        if let Some(b) = bound {
            log::info!(
                "smooth trial fields: lambda_{nev} <= {b:.4e} ({:.2} s)",
                t.elapsed().as_secs_f64()
            );
        }
        if let (Some(b), Some(better)) = (bound, moved) {
            log::info!(
                "the shift {:.1} Hz lies far below the lowest {nev} modes (up to at most {:.1} Hz by smooth trial fields): solving at {:.1} Hz instead",
                shift_hz(sigma),
                b.max(0.0).sqrt() / (2.0 * std::f64::consts::PI),
                shift_hz(better)
            );
        }
        let in_doubt = bound.is_some_and(|b| shift_in_doubt(b, sigma));
        Self {
            sigma: moved.unwrap_or(sigma),
            checks: PLACEMENT_ROUNDS,
            watch: moved.is_none() && !in_doubt,
            seconds: t.elapsed().as_secs_f64(),
        }
    }
}

/// The frequency of a shift below zero, -(2 pi f)^2 = sigma \[Hz\] (0 for a shift above zero).
fn shift_hz(sigma: f64) -> f64 {
    (-sigma).max(0.0).sqrt() / (2.0 * std::f64::consts::PI)
}

/// [`certified_modes`] with the Lanczos solve given: `solve(km, nev, attempt, sigma)` returns
/// `nev` modes, the shift it used (which later attempts are given), its (factorisation,
/// eigen) seconds and a spare factor array for the Sturm count ([`Solved`]); `attempt`
/// numbers the solves from 0.
fn certify_with_recovery(
    km: &mut StiffnessMass,
    analysis: &Analysis,
    count: usize,
    sigma: f64,
    guard: usize,
    mut solve: impl FnMut(&mut StiffnessMass, usize, usize, f64) -> Result<Solved, ModalError>,
) -> Result<(ModalSolution, Timings), ModalError> {
    let mut sigma = sigma;
    let mut timings = Timings::default();
    let n = km.pattern.n;
    let mut nev = (count + guard).min(n.saturating_sub(1)).max(count);
    let mut attempt = 0;
    let mut recovered = 0;
    let mut previous: Option<(Modes, Option<SturmCheck>)> = None;
    let (all, sturm) = loop {
        let (all, t, spare) = match (solve(km, nev, attempt, sigma), previous.take()) {
            (Ok(solved), _) => {
                sigma = solved.sigma;
                (solved.modes, solved.seconds, solved.spare)
            }
            // a re-solve that fails leaves the first result with its failed certificate
            (Err(e), Some(prev)) => {
                log::warn!("solving again for the missed modes failed: {e}");
                break prev;
            }
            (Err(e), None) => return Err(e),
        };
        timings.factorisation += t.0;
        timings.eigen += t.1;
        let t = Instant::now();
        let mut all = all;
        let sturm = sturm_check(km, analysis, (&mut all, spare), count)?;
        timings.certification += t.elapsed().as_secs_f64();
        let retry = match &sturm {
            Some(st) if st.found > st.expected && attempt < RECOVERY_ATTEMPTS => {
                Some((st.found, st.expected, st.shift_hz))
            }
            _ => None,
        };
        let Some((found, expected, shift_hz)) = retry else {
            break (all, sturm);
        };
        let missed = found - expected;
        log::warn!(
            "the Sturm count at {shift_hz:.1} Hz found {found} eigenvalues below, {expected} were computed: solving again for the {missed} missed"
        );
        if attempt == 0 {
            recovered = missed;
        }
        nev = (found + guard.max(missed)).min(n.saturating_sub(1));
        attempt += 1;
        previous = Some((all, sturm));
    };
    if sturm.as_ref().is_some_and(|s| !s.ok) {
        recovered = 0;
    }
    let t = Instant::now();
    let mut modes = all;
    modes.eigenvalues.truncate(count);
    modes.vectors.truncate(count * n);
    let residuals = certify::residuals(km, &modes, sigma);
    let m_orthogonality = certify::m_orthogonality_error(km, &modes);
    timings.certification += t.elapsed().as_secs_f64();
    Ok((
        ModalSolution {
            modes,
            residuals,
            m_orthogonality,
            sturm,
            sigma,
            recovered,
        },
        timings,
    ))
}

/// One shift-invert Lanczos solve of `nev` modes: factorises K - sigma M, runs ARPACK with the
/// start vector of `seed`, lets the factor go. K and M wait on disk meanwhile when the factor
/// is large ([`with_shifted`]). With checks in `placement`, a shift far below the wanted modes
/// is moved to them and the solve starts again on a new factor (up to [`PLACEMENT_ROUNDS`]
/// times, after the move the trial fields may have made before any factorisation,
/// [`Placement::of`]). A watched shift: at the iteration's first restart its Ritz values bound
/// lambda_nev from above ([`ritz_bound`]); a bound that leaves the shift in doubt
/// ([`shift_in_doubt`]) stops the iteration and the block check [`placed_shift`] decides on
/// the same factor (a shift it keeps is solved there afresh); an iteration that converges
/// before its first restart is judged by its eigenvalues ([`moved_shift`]). A shift moved
/// (here or by the smooth trial fields, [`Placement::of`]) is checked by the block check
/// before its iteration ([`check_then_solve`]). A shift near the band so costs no check (the
/// block check took 7 s of the 754k-DOF casting's 67 s); a far one costs the first restart's
/// ncv + 1 solves more unless the trial fields prove it far or leave it in doubt. Returns the
/// modes, the shift used, (factorisation, eigen) seconds and a resident factor's value array
/// ([`Solved`]).
fn lanczos(
    km: &mut StiffnessMass,
    analysis: &Analysis,
    nev: usize,
    seed: u64,
    placement: Placement,
) -> Result<Solved, ModalError> {
    let mass = km.pattern.compress(&km.m);
    let (mut sigma, mut t_factor, mut t_eigen) = (placement.sigma, 0.0, placement.seconds);
    // checks of the shift left: a second check on the new factor refines a first estimate
    // that the far shift kept coarse
    let (mut checks, mut watching) = (placement.checks, placement.watch);
    // a factor small enough to stay resident leaves its value array for the Sturm count
    let recycle = analysis.factor_nnz().saturating_mul(8) < spill_threshold();
    let mut spare = None;
    loop {
        let mut settings = EigenSettings::new(nev, sigma);
        settings.seed = seed;
        let solved = with_shifted((km, &mut Vec::new()), analysis, sigma, |pattern, values| {
            let t = Instant::now();
            let llt = analysis.llt(&pattern, &values)?;
            drop((values, pattern));
            crate::machine::release_memory();
            t_factor += t.elapsed().as_secs_f64();
            // the caller's shift is watched; a moved one is checked before the iteration
            // (its bound refined on the new factor)
            if checks > 0 && !watching {
                let (result, (tf, te)) = check_then_solve(&mass, llt, &settings)?;
                t_factor += tf;
                t_eigen += te;
                return Ok::<_, ModalError>(result);
            }
            let t = Instant::now();
            let ((result, spent), values) =
                watched_solve(&mass, llt, &settings, watching, recycle)?;
            // a block check's seconds count with the factorisation's, as above
            t_eigen += t.elapsed().as_secs_f64() - spent.0;
            t_factor += spent.0;
            spare = values.or(spare.take());
            Ok(result)
        })??;
        match solved {
            Ok(modes) => {
                return Ok(Solved {
                    modes,
                    sigma,
                    seconds: (t_factor, t_eigen),
                    spare,
                })
            }
            Err(better) => {
                log::info!(
                    "the shift {:.1} Hz lies far below the lowest {nev} modes (up to about {:.1} Hz): solving at {:.1} Hz instead",
                    shift_hz(sigma),
                    shift_hz(better.sigma / SHIFT_FRACTION),
                    shift_hz(better.sigma)
                );
                sigma = better.sigma;
                checks = if better.settled {
                    0
                } else {
                    checks.saturating_sub(1)
                };
                watching = false;
                // the next factorisation allocates its own array
                spare = None;
            }
        }
    }
}

/// A Lanczos solve's modes, the shift used, its (factorisation, eigen) seconds and, when its
/// factor was small enough to stay resident, the factor's value array for the Sturm count to
/// write into ([`Analysis::negative_pivots_in`]).
struct Solved {
    modes: Modes,
    sigma: f64,
    seconds: (f64, f64),
    spare: Option<Vec<f64>>,
}

/// The watched Lanczos iteration on the factor `llt` ([`lanczos`]): the modes, or the better
/// shift; the seconds of a block check it ran (check, solve; included in the whole); and,
/// with `recycle`, the factor's value array once converged. With `watching`, a first
/// restart's bound that leaves the shift in doubt stops the iteration and the block check
/// decides on the same factor ([`check_then_solve`]); an iteration that converges before its
/// first restart is judged by its eigenvalues ([`moved_shift`]).
fn watched_solve(
    mass: &SymCsc,
    llt: crate::linalg::factor::Llt<'_>,
    settings: &EigenSettings,
    watching: bool,
    recycle: bool,
) -> Result<(Checked, Option<Vec<f64>>), ModalError> {
    let (nev, sigma, n) = (settings.count, settings.sigma, mass.pattern.n);
    // the iteration lets the factor go once converged, before the Ritz vectors are formed
    // beside ARPACK's basis (keeping a resident one's values); one stopped to check the
    // shift leaves it
    let factor = std::cell::RefCell::new(Some(llt));
    let spare = std::cell::RefCell::new(None);
    let (mut bound, mut watched) = (f64::INFINITY, false);
    let watch = Watch {
        ritz: |ritz: &[f64]| {
            watched = true;
            bound = ritz_bound(ritz, nev, sigma);
            watching && shift_in_doubt(bound, sigma)
        },
        done: || {
            let llt = factor.borrow_mut().take();
            *spare.borrow_mut() = llt.filter(|_| recycle).map(|l| l.into_values());
        },
    };
    let solve = |x: &mut [f64]| {
        let llt = factor.borrow();
        llt.as_ref()
            .expect("the factor lives until the iteration has converged")
            .solve_vec(x);
    };
    let run = solve_modes_watched(n, settings, |x, y| mass.matvec(x, y), solve, watch)?;
    let Watched::Done(modes) = run else {
        // the first restart's bound leaves the shift in doubt: the block check decides
        let Some(llt) = factor.into_inner() else {
            unreachable!("a stopped iteration keeps its factor")
        };
        log::info!(
            "Lanczos stopped at its first restart (lambda_{nev} <= {bound:.4e}, shift {sigma:.4e})"
        );
        return Ok((check_then_solve(mass, llt, settings)?, None));
    };
    log::info!("{}", modes.work_summary());
    // converged before its first restart: its own eigenvalues judge the shift
    let top = modes.eigenvalues.get(nev.saturating_sub(1)).copied();
    let result = match top
        .filter(|&t| watching && !watched && above_roundoff(t, -sigma))
        .and_then(|top| moved_shift(top, sigma))
    {
        // converged eigenvalues: the new shift needs no check
        Some(sigma) => Err(Moved {
            sigma,
            settled: true,
        }),
        None => Ok(modes),
    };
    Ok(((result, (0.0, 0.0)), spare.into_inner()))
}

/// The modes solved at the shift, or the better shift the check found; with (check, solve)
/// seconds ([`check_then_solve`]).
type Checked = (Result<Modes, Moved>, (f64, f64));

/// The block shift check ([`placed_shift`]) on the factor `llt` of K - sigma M, then, when it
/// keeps the shift, a fresh Lanczos solve on that factor: the modes, or the better shift; with
/// (check, solve) seconds.
fn check_then_solve(
    mass: &crate::linalg::sparse::SymCsc,
    llt: crate::linalg::factor::Llt<'_>,
    settings: &EigenSettings,
) -> Result<Checked, ModalError> {
    let (nev, sigma, n) = (settings.count, settings.sigma, mass.pattern.n);
    let t = Instant::now();
    let better = placed_shift(mass, &llt, nev, sigma);
    let t_check = t.elapsed().as_secs_f64();
    log::info!("shift check {t_check:.2} s");
    crate::machine::release_memory();
    if let Some(better) = better {
        return Ok((Err(better), (t_check, 0.0)));
    }
    let t = Instant::now();
    let solve = move |x: &mut [f64]| llt.solve_vec(x);
    let modes = solve_modes(n, settings, |x, y| mass.matvec(x, y), solve)?;
    log::info!("{}", modes.work_summary());
    Ok((Ok(modes), (t_check, t.elapsed().as_secs_f64())))
}

/// Runs `work` on the lower triangle of K - sigma M (what the lower-side factorisations read,
/// half the memory of both triangles) and the pattern it lies on. When the factor of the
/// analysis will take [`crate::linalg::spill::SPILL_FACTOR_BYTES`] or more, K, M, the full
/// pattern's rows and `extra` (mode shapes, or nothing) wait on disk meanwhile ([`crate::linalg::spill`]): they are not read while a
/// factor exists, and the factor is most of the memory. They are taken back, bit for bit,
/// before this returns, whatever `work` returned. `work` owns the values, so it can let them
/// go, with their pattern, once factorised.
fn with_shifted<R>(
    (km, extra): (&mut StiffnessMass, &mut Vec<f64>),
    analysis: &Analysis,
    sigma: f64,
    work: impl FnOnce(Pattern, Vec<f64>) -> R,
) -> Result<R, ModalError> {
    let (lower, values) = lower_shifted(km, sigma);
    if analysis.factor_nnz().saturating_mul(8) < spill_threshold() {
        return Ok(work(lower, values));
    }
    let aside = km.put_aside(extra);
    crate::machine::release_memory();
    let result = work(lower, values);
    if let Some(aside) = aside {
        km.take_back(aside, extra).map_err(ModalError::Aside)?;
    }
    Ok(result)
}

/// Checks of the shift, each on the factor of the last one it moved to ([`placed_shift`]).
pub const PLACEMENT_ROUNDS: usize = 2;
/// Passes of the shift check's block subspace iteration ([`placed_shift`]).
pub const SHIFT_CHECK_PASSES: usize = 4;
/// A shift farther below zero than this many times the estimated highest wanted eigenvalue is
/// moved ([`placed_shift`]).
pub const SHIFT_REACH: f64 = 2.0;
/// Where [`placed_shift`] puts the shift: this fraction of the estimated highest wanted
/// eigenvalue, below zero.
pub const SHIFT_FRACTION: f64 = 0.25;

/// A Ritz bound (an upper bound of lambda_nev, [`ritz_bound`]) below this many times -sigma
/// leaves a shift below zero in doubt, to be checked ([`placed_shift`]). Far shifts give
/// bounds below -sigma (the 754k-DOF casting at -(2 pi 20 kHz)^2: 0.87 times -sigma), shifts
/// near the band bounds hundreds to thousands of times -sigma (the casting and the liner at
/// the default 100 Hz).
pub const SHIFT_DOUBT: f64 = 16.0;

/// Whether the Ritz bound `bound` of lambda_nev leaves the shift `sigma` in doubt: below zero
/// and `bound` < [`SHIFT_DOUBT`] (-sigma).
pub fn shift_in_doubt(bound: f64, sigma: f64) -> bool {
    sigma < 0.0 && bound < SHIFT_DOUBT * -sigma
}

/// An upper bound of lambda_nev from the Ritz values `ritz` of the operator
/// (K - sigma M)^-1 M on a Lanczos basis: sigma + 1 / theta_nev, theta_nev the nev-th largest.
/// By Cauchy interlacing theta_nev <= 1 / (lambda_nev - sigma) for sigma below the spectrum,
/// so the bound is at least lambda_nev; infinite when fewer than nev Ritz values are positive.
pub fn ritz_bound(ritz: &[f64], nev: usize, sigma: f64) -> f64 {
    let mut theta: Vec<f64> = ritz.iter().copied().filter(|t| *t > 0.0).collect();
    theta.sort_by(|a, b| b.total_cmp(a));
    match nev.checked_sub(1).and_then(|k| theta.get(k)) {
        Some(&t) => sigma + 1.0 / t,
        None => f64::INFINITY,
    }
}

/// Bounds or eigenvalues at or below this fraction of their scale are roundoff around zero
/// ([`above_roundoff`]): the rigid-body modes'.
pub const ROUNDOFF: f64 = 1e-8;

/// Whether `value` is clearly above zero against `scale` (the largest value of its kind at
/// hand): above [`ROUNDOFF`] `scale`. A shift is never moved on a value that is not: when
/// every wanted mode is a rigid-body mode its bound is roundoff, and a shift moved to a quarter
/// of it would sit at zero, where K - sigma M is singular.
pub fn above_roundoff(value: f64, scale: f64) -> bool {
    value > ROUNDOFF * scale.abs()
}

/// The shift [`placed_shift`] moves to, given `top`, an estimate or upper bound of the highest
/// wanted eigenvalue: -[`SHIFT_FRACTION`] top when -sigma > [`SHIFT_REACH`] top, else None.
pub fn moved_shift(top: f64, sigma: f64) -> Option<f64> {
    (sigma < 0.0 && top > 0.0 && -sigma > SHIFT_REACH * top).then_some(-SHIFT_FRACTION * top)
}

/// A shift [`placed_shift`] moved to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Moved {
    /// The new shift \[rad^2/s^2\].
    pub sigma: f64,
    /// The estimate it was placed from had settled ([`settled`]), or was a converged
    /// eigenvalue: the new shift is solved without a further check.
    pub settled: bool,
}

/// Whether the bounds `values` of lambda_nev, one per pass of the block check, have settled:
/// with d_p the last decrease and r = d_p / d_(p-1) its ratio to the one before, r is at most
/// [`SETTLED_RATIO`] and the limit of a linearly converging sequence (Aitken's extrapolation)
/// v_p - d_p r / (1 - r) is at least [`SETTLED_FRACTION`] v_p. An extrapolation, not a proof: a shift wrongly taken as settled
/// costs Lanczos solves, never a wrong answer (the Sturm count certifies the result).
pub fn settled(values: &[f64]) -> bool {
    let [.., a, b, c] = values else {
        return false;
    };
    let (d_before, d_last) = (a - b, b - c);
    // a last change at roundoff: converged (a converged bound may rise by roundoff)
    let tiny = 1e-12 * c.abs();
    if d_last.abs() <= tiny {
        return d_before >= -tiny && *c > 0.0;
    }
    if d_before <= 0.0 || d_last < 0.0 {
        return false;
    }
    let r = d_last / d_before;
    r <= SETTLED_RATIO && c - d_last * r / (1.0 - r) >= SETTLED_FRACTION * c
}

/// The last decrease of the check's bounds must be at most this fraction of the one before
/// for them to count as settled ([`settled`]): a slowly falling sequence (a block that the
/// far shift barely filters: ratios of 0.8 on a free block at -(2 pi 1 MHz)^2, whose bounds
/// were still 1e12 above the true zero) extrapolates unreliably.
pub const SETTLED_RATIO: f64 = 0.5;

/// The extrapolated limit of the check's bounds must be at least this fraction of the last
/// bound for the estimate to count as settled ([`settled`]).
pub const SETTLED_FRACTION: f64 = 0.5;

/// A better shift when `sigma` lies far below the lowest `nev` eigenvalues, else None.
///
/// Shift-invert maps lambda to theta = 1 / (lambda - sigma); a shift far below the wanted
/// eigenvalues maps them all close to -1 / sigma, and Lanczos separates them slowly (a mm deck
/// read as metres, modes near 3-8 Hz under the default -(2 pi 100 Hz)^2, took 19 min and missed
/// modes). Estimate: up to [`SHIFT_CHECK_PASSES`] passes of block subspace iteration
/// X <- (K - sigma M)^-1 M X on the factor at hand, from a fixed pseudo-random block of
/// 2 `nev` columns, each with the Rayleigh-Ritz values of (K, M) on its span
/// (`checked_pass`, formed without K, which may wait on disk); the `nev`-th,
/// theta_max, is an upper bound of lambda_nev (the k-th Ritz value bounds the k-th eigenvalue
/// from above). When -sigma > [`SHIFT_REACH`] theta_max the shift is moved to
/// -[`SHIFT_FRACTION`] theta_max:
/// still below every eigenvalue (the factorisation stays a Cholesky; rigid-body modes have
/// lambda = 0) and near the wanted band, which then spreads over theta in
/// [1 / (1.25 theta_max), 4 / theta_max]. The shift only ever moves up toward the band; a shift
/// the user placed near the wanted modes is kept. The certificate (Sturm count) is unchanged.
/// The bound falls with the passes, fastest in the first ones; so from the second pass on the
/// check stops, keeping the shift, when the passes left, each lowering the bound by the last
/// pass's ratio, would still leave it [`SHIFT_CHECK_MARGIN`] times beyond the reach of a move
/// (an extrapolation, not a proof: a shift kept wrongly costs Lanczos solves, never a wrong
/// answer, since the Sturm count certifies the result). A shift already near the band costs
/// two passes, not four.
/// Measured on a free-free hex20 block 10,000 times too large (20 modes below 1.4 Hz, shift
/// 100 Hz): 517 Lanczos solves unmoved, 129 moved (80 at the best shift for this band).
pub fn placed_shift(
    mass: &SymCsc,
    llt: &crate::linalg::factor::Llt<'_>,
    nev: usize,
    sigma: f64,
) -> Option<Moved> {
    let n = mass.pattern.n;
    let nev = nev.min(n.saturating_sub(1));
    let b = (2 * nev).min(n.saturating_sub(1));
    if nev == 0 || sigma >= 0.0 {
        return None;
    }
    // the fixed start block, its rows put in the factor's order (the check works there)
    let mut x = super::dense_lanczos::random_block(n, b, 0x2545_f491_4f6c_dd1d);
    let (fwd, _) = llt.order();
    let mut column = vec![0.0; n];
    for j in 0..b {
        column
            .iter_mut()
            .zip(x.col(j).iter())
            .for_each(|(c, v)| *c = *v);
        x.col_mut(j)
            .iter_mut()
            .zip(fwd)
            .for_each(|(v, &old)| *v = column[old]);
    }
    drop(column);
    let mut bounds = Vec::with_capacity(SHIFT_CHECK_PASSES);
    for pass in 1..=SHIFT_CHECK_PASSES {
        let (next, ritz) = checked_pass(mass, llt, x, sigma)?;
        x = next;
        let theta_max = ritz[nev - 1];
        log::debug!("shift check pass {pass}: lambda_{nev} <= {theta_max:.4e} (shift {sigma:.4e})");
        let last = bounds.last().copied();
        bounds.push(theta_max);
        // a bound at roundoff (every wanted mode a rigid-body mode) moves nothing
        let top = Some(theta_max).filter(|&t| above_roundoff(t, ritz[ritz.len() - 1]));
        let moved = |settled| {
            top.and_then(|t| moved_shift(t, sigma))
                .map(|sigma| Moved { sigma, settled })
        };
        if pass == SHIFT_CHECK_PASSES {
            return moved(settled(&bounds));
        }
        if settled(&bounds) && moved(true).is_some() {
            return moved(true);
        }
        if let Some(prev) = last {
            // the passes left, each lowering the bound by the last pass's ratio, cannot
            // bring it within reach of a move, by a margin
            let ratio = (prev / theta_max).max(1.0);
            let reach = theta_max / ratio.powi((SHIFT_CHECK_PASSES - pass) as i32);
            if reach > SHIFT_CHECK_MARGIN * -sigma / SHIFT_REACH {
                return None;
            }
        }
    }
    None
}

/// The shift check ends early, keeping the shift, when even the passes left, each lowering
/// the bound by the ratio of the last pass, would leave it this many times above the reach
/// of a move ([`placed_shift`]).
pub const SHIFT_CHECK_MARGIN: f64 = 4.0;

/// One pass of the shift check on a block X held in the factor's row order (P X,
/// [`Llt::order`]): Y = (K - sigma M)^-1 M X, the Rayleigh-Ritz values of (K, M) on span(Y),
/// ascending, and the next block, Y made M-orthonormal (None when Y^T M Y is not positive
/// definite: the block's columns are numerically dependent, which a shift near the wanted band
/// causes, and such a shift is kept). With K - sigma M = P^T L L^T P and Z = L^-1 P M X (the
/// forward half of the solve), P Y = L^-T Z, so Y^T M X = Z^T Z: the block is transformed in
/// place and no second n x b block is alive (the check's memory adds to the factor's). K is not read: K Y = M X + sigma M Y, so
/// Y^T K Y = Y^T (M X) + sigma Y^T M Y. With D scaling Y^T M Y to a unit diagonal and
/// C C^T = D Y^T M Y D, the values are the eigenvalues of C^-1 D (Y^T K Y) D C^-T (the k-th
/// bounds the k-th eigenvalue from above), and Y D C^-T is M-orthonormal.
///
/// [`Llt::order`]: crate::linalg::factor::Llt::order
fn checked_pass(
    mass: &SymCsc,
    llt: &crate::linalg::factor::Llt<'_>,
    mut x: faer::Mat<f64>,
    sigma: f64,
) -> Option<(faer::Mat<f64>, Vec<f64>)> {
    let order = llt.order();
    mass.mul_dense_permuted_in_place(order, x.as_mut());
    super::subspace::forward_block(llt, &mut x);
    let ymx = x.transpose() * &x;
    super::subspace::backward_block(llt, &mut x);
    let ymy = mass_gram(mass, order, &x);
    let (ritz, d, c) = rayleigh_ritz(&ymx, &ymy, sigma)?;
    // X <- Y D C^-T, i.e. (C^-1 (Y D)^T)^T, then once more on its own Gram matrix (CholQR2:
    // the second pass restores M-orthonormality to roundoff for condition numbers of Y up to
    // about 1e8)
    for (j, dj) in d.iter().enumerate() {
        x.col_mut(j).iter_mut().for_each(|v| *v *= dj);
    }
    right_solve_lower_transposed(&c, &mut x);
    if let Ok(again) = mass_gram(mass, order, &x).llt(faer::Side::Lower) {
        right_solve_lower_transposed(&again.L().to_owned(), &mut x);
    }
    Some((x, ritz))
}

/// X <- X C^-T in place for a lower triangular C: (C^-1 X^T)^T.
fn right_solve_lower_transposed(c: &faer::Mat<f64>, x: &mut faer::Mat<f64>) {
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(
        c.as_ref(),
        x.as_mut().transpose_mut(),
        faer::get_global_parallelism(),
    );
}

/// Columns of M Y formed at a time by [`mass_gram`].
const GRAM_COLUMNS: usize = 8;

/// Y^T M Y for a block Y in the factor's row order (`order`, P Y): (P Y)^T (P M P^T) (P Y),
/// [`GRAM_COLUMNS`] columns of the product at a time.
fn mass_gram(mass: &SymCsc, order: (&[usize], &[usize]), y: &faer::Mat<f64>) -> faer::Mat<f64> {
    let b = y.ncols();
    let mut gram = faer::Mat::<f64>::zeros(b, b);
    for c0 in (0..b).step_by(GRAM_COLUMNS) {
        let w = GRAM_COLUMNS.min(b - c0);
        let mut my = y.subcols(c0, w).to_owned();
        mass.mul_dense_permuted_in_place(order, my.as_mut());
        faer::linalg::matmul::matmul(
            gram.as_mut().subcols_mut(c0, w),
            faer::Accum::Replace,
            y.transpose(),
            my.as_ref(),
            1.0,
            faer::get_global_parallelism(),
        );
    }
    gram
}

/// The eigenvalues of (Y^T M X + sigma Y^T M Y, Y^T M Y) (both symmetrised), ascending, by a
/// scaled Cholesky of the second ([`checked_pass`]), with the scaling D and the factor C
/// (C C^T = D Y^T M Y D); None when Y^T M Y is not positive definite.
fn rayleigh_ritz(
    ymx: &faer::Mat<f64>,
    ymy: &faer::Mat<f64>,
    sigma: f64,
) -> Option<(Vec<f64>, Vec<f64>, faer::Mat<f64>)> {
    use faer::Mat;
    let b = ymy.nrows();
    let d: Vec<f64> = (0..b)
        .map(|i| 1.0 / ymy[(i, i)].max(f64::MIN_POSITIVE).sqrt())
        .collect();
    let sym = |m: &Mat<f64>, i: usize, j: usize| 0.5 * (m[(i, j)] + m[(j, i)]) * d[i] * d[j];
    let bm = Mat::from_fn(b, b, |i, j| sym(ymy, i, j));
    let a = Mat::from_fn(b, b, |i, j| sym(ymx, i, j) + sigma * bm[(i, j)]);
    let c = bm.llt(faer::Side::Lower).ok()?.L().to_owned();
    let mut s = a;
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(
        c.as_ref(),
        s.as_mut(),
        faer::Par::Seq,
    );
    let mut st = s.transpose().to_owned();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(
        c.as_ref(),
        st.as_mut(),
        faer::Par::Seq,
    );
    let mut ritz = st.self_adjoint_eigenvalues(faer::Side::Lower).ok()?;
    ritz.sort_by(f64::total_cmp);
    Some((ritz, d, c))
}

/// The Sturm certificate of computed eigenvalues: the negative pivots of K - sigma_c M at a
/// shift in the first spectral gap at or above mode `count` ([`certify::sturm_shift`]); None
/// when the computed spectrum offers no gap.
fn sturm_check(
    km: &mut StiffnessMass,
    analysis: &Analysis,
    (modes, spare): (&mut Modes, Option<Vec<f64>>),
    count: usize,
) -> Result<Option<SturmCheck>, ModalError> {
    let Some((sigma_c, expected)) = certify::sturm_shift(&modes.eigenvalues, count, 1e-4) else {
        return Ok(None);
    };
    // the mode shapes wait on disk with K and M while the L D L^T lives
    let aside = (km, &mut modes.vectors);
    let found = with_shifted(aside, analysis, sigma_c, |pattern, values| {
        analysis.negative_pivots_in(&pattern, &values, spare)
    })??;
    Ok(Some(SturmCheck {
        shift_hz: sigma_c.max(0.0).sqrt() / (2.0 * std::f64::consts::PI),
        expected,
        found,
        ok: found == expected,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::model::FeModel;
    use crate::mesh::lattice::Lattice;
    use crate::scene::spec::Elastic;

    /// The free-free steel model of [`block`] with cells of 50 m.
    fn steel_block() -> FeModel {
        let steel = Elastic {
            young: 210e9,
            poisson: 0.3,
            density: 7850.0,
        };
        FeModel::build(block(50.0), &steel, &[]).unwrap()
    }

    /// A 4 x 2 x 1 block of hex8 cells of `cell` metres.
    fn block(cell: f64) -> crate::mesh::Mesh {
        let coord = |k: [usize; 3]| [k[0] as f64 * cell, k[1] as f64 * cell, k[2] as f64 * cell];
        let active = |_: usize, _: usize, _: usize| true;
        let lat = Lattice {
            cells: [4, 2, 1],
            periodic_j: false,
            active: &active,
            coord: &coord,
        };
        lat.generate(crate::scene::spec::ElementKind::Hex8).mesh
    }

    /// The recovery itself: a first solve that misses mode 3 (its pair removed from a correct
    /// solve, as a Lanczos run that never saw it would return) is caught by the Sturm count and
    /// re-solved; the result is the complete lowest set (the direct solve's eigenvalues to
    /// 1e-10: both are ARPACK at machine-epsilon tolerance on the same factor) with
    /// `recovered` = 1. A second miss is not hidden: the certificate then fails.
    #[test]
    fn verification_a_missed_mode_is_recovered() {
        let mut mesh = block(0.05);
        let x0: Vec<usize> = (0..mesh.nodes.len())
            .filter(|&i| mesh.nodes[i][0] == 0.0)
            .collect();
        mesh.node_sets.insert("x0".into(), x0);
        let steel = Elastic {
            young: 210e9,
            poisson: 0.3,
            density: 7850.0,
        };
        let model = FeModel::build(mesh, &steel, &["x0".to_string()]).unwrap();
        let sigma = -1e4;
        let mut model = model;
        let (km, an) = (&mut model.km, &model.analysis);
        let (direct, _) = certified_modes(km, an, 8, sigma, 2, true, None).unwrap();
        let drop_mode = |mut m: Modes, j: usize| {
            let n = m.n;
            m.eigenvalues.remove(j);
            m.vectors.drain(j * n..(j + 1) * n);
            m
        };
        let mut calls = Vec::new();
        let (sol, _) = certify_with_recovery(km, an, 8, sigma, 2, |km, nev, attempt, sigma| {
            calls.push(nev);
            let mut solved = lanczos(km, an, nev, attempt as u64, Placement::none(sigma))?;
            if attempt == 0 {
                solved.modes = drop_mode(solved.modes, 3);
            }
            Ok(solved)
        })
        .unwrap();
        assert_eq!(sol.recovered, 1);
        assert!(sol.sturm.as_ref().unwrap().ok);
        assert_eq!(calls.len(), 2, "{calls:?}");
        for (a, b) in sol.modes.eigenvalues.iter().zip(&direct.modes.eigenvalues) {
            assert!((a - b).abs() <= 1e-10 * b, "{a} vs {b}");
        }
        // every solve misses one: two re-solves, then the failed certificate is returned
        let (sol, _) = certify_with_recovery(km, an, 8, sigma, 2, |km, nev, attempt, sigma| {
            let mut solved = lanczos(km, an, nev, attempt as u64, Placement::none(sigma))?;
            solved.modes = drop_mode(solved.modes, 3);
            Ok(solved)
        })
        .unwrap();
        assert!(!sol.sturm.unwrap().ok);
        assert_eq!(sol.recovered, 0);
        // a re-solve that fails (ARPACK not converged) leaves the first result and its failed
        // certificate, the exit 1 of `modes` (not the re-solve's error)
        let (sol, _) = certify_with_recovery(km, an, 8, sigma, 2, |km, nev, attempt, sigma| {
            if attempt > 0 {
                return Err(EigenError::NotConverged {
                    converged: 0,
                    wanted: nev,
                    restarts: 500,
                    msg: "test",
                }
                .into());
            }
            let mut solved = lanczos(km, an, nev, 0, Placement::none(sigma))?;
            solved.modes = drop_mode(solved.modes, 3);
            Ok(solved)
        })
        .unwrap();
        assert!(!sol.sturm.unwrap().ok);
    }

    /// The out-of-core path (K, M and the pattern's rows on disk while each factor lives)
    /// gives the modes of the in-memory one, on a free-free model whose far shift is moved
    /// (both factorisations, the shift check, the Sturm count), and leaves the model as it was,
    /// bit for bit. The eigenvalues agree to 1e-9 of the largest (the dense oracle's bound
    /// elsewhere; rigid-body eigenvalues are roundoff around 0), not to the bit: when ARPACK's
    /// Lanczos vectors span an invariant subspace (likely on 90 DOFs) it restarts from a
    /// random vector drawn from a process-wide seed, so two solves in one process may differ
    /// in the last bits whatever the path.
    #[test]
    fn verification_the_out_of_core_solve_gives_the_same_modes() {
        let mut model = steel_block();
        let before = model.km.clone();
        let sigma = -(2.0 * std::f64::consts::PI * 100.0_f64).powi(2);
        let (km, an) = (&mut model.km, &model.analysis);
        let (memory, _) = certified_modes(km, an, 10, sigma, 4, true, None).unwrap();
        crate::linalg::spill::set_spill_threshold(0);
        let (disk, _) = certified_modes(km, an, 10, sigma, 4, true, None).unwrap();
        crate::linalg::spill::set_spill_threshold(crate::linalg::spill::SPILL_FACTOR_BYTES);
        assert!(memory.sigma > sigma, "the test needs the shift moved");
        let top = memory.modes.eigenvalues[9];
        for (a, b) in memory.modes.eigenvalues.iter().zip(&disk.modes.eigenvalues) {
            assert!((a - b).abs() <= 1e-9 * top, "{a} vs {b}");
        }
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let (ms, ds) = (memory.sturm.unwrap(), disk.sturm.unwrap());
        assert!(ms.ok && ds.ok && ms.found == ds.found, "{ms:?} {ds:?}");
        assert!((memory.sigma - disk.sigma).abs() <= 1e-9 * -memory.sigma);
        assert_eq!(model.km.pattern, before.pattern);
        assert_eq!(bits(&model.km.k), bits(&before.k));
        assert_eq!(bits(&model.km.m), bits(&before.m));
    }

    /// Verification of Aitken's test: a geometric sequence v_p = lambda + e r^p is
    /// extrapolated exactly, so it has settled when lambda >= SETTLED_FRACTION v_p (fast
    /// convergence, r = 0.1) and not when the last bound is still far above its limit
    /// (r = 0.9, or r = 0.8 whatever its limit); a rising or flat-then-falling sequence, or
    /// fewer than three bounds, has not;
    /// a converged one whose last bound moves by roundoff only has.
    #[test]
    fn verification_settled_bounds_extrapolate_a_geometric_sequence() {
        let seq = |lambda: f64, e: f64, r: f64| -> Vec<f64> {
            (1..=3).map(|p| lambda + e * r.powi(p)).collect()
        };
        assert!(settled(&seq(1.0, 10.0, 0.1)));
        assert!(!settled(&seq(1.0, 10.0, 0.9)));
        // the limit is exactly half the last bound at r = 0.5 and e = 8: 1 vs 0.5 * 2
        assert!(settled(&seq(1.0, 8.0, 0.5)));
        assert!(!settled(&seq(1.0, 9.0, 0.5)));
        // slowly falling (r = 0.8): not settled even where the extrapolated limit would pass
        assert!(!settled(&seq(10.0, 1.0, 0.8)));
        // the free block's bounds at -(2 pi 1 MHz)^2 (true limit 0)
        assert!(!settled(&[1.8882e12, 1.6527e12, 1.4646e12, 1.3136e12]));
        assert!(!settled(&[1.0, 2.0, 1.5]));
        assert!(!settled(&[2.0, 2.0, 1.5]));
        assert!(!settled(&[2.0, 1.5]));
        // converged: the last bound rises by roundoff (1e-15 of it), or does not move
        assert!(settled(&[3.0, 1.0, 1.0 + 1e-15]));
        assert!(settled(&[1.0, 1.0, 1.0]));
    }

    /// The shift check's pass, formed in place from the halves of the solve: on a free-free
    /// block whose spectrum the certified solve gives, each pass's k-th Rayleigh-Ritz value
    /// bounds the k-th eigenvalue from above (Courant-Fischer; 1e-9 of the value for
    /// roundoff), the next block is M-orthonormal (1e-10: CholQR2 reaches roundoff times a
    /// small multiple of b while the block's condition number stays below 1e8), and after p passes the bound of the
    /// lowest elastic mode k = 7 is within the subspace iteration's error bound
    /// (lambda_b+1 / lambda_k) tan^2(angle of the start) r^2p, r = (lambda_k - sigma) /
    /// (lambda_b+1 - sigma), with tan^2 taken as n (generous for a random start on n DOFs).
    #[test]
    fn verification_the_shift_check_bounds_the_eigenvalues_from_above() {
        let mut model = steel_block();
        let sigma = -(2.0 * std::f64::consts::PI * 100.0_f64).powi(2);
        let (km, an) = (&mut model.km, &model.analysis);
        let b = 24;
        let (exact, _) = certified_modes(km, an, b + 1, sigma, 4, false, None).unwrap();
        let lambda = &exact.modes.eigenvalues;
        // a shift just below zero: the check's case of a shift near the wanted modes
        let sigma = -0.01 * lambda[6];
        let rate = (lambda[6] - sigma) / (lambda[b] - sigma);
        let mass = km.pattern.compress(&km.m);
        let (lower, values) = lower_shifted(km, sigma);
        let llt = an.llt(&lower, &values).unwrap();
        let n = km.pattern.n;
        let (fwd, _) = llt.order();
        let start = super::super::dense_lanczos::random_block(n, b, 7);
        let mut x = faer::Mat::from_fn(n, b, |new, j| start[(fwd[new], j)]);
        for pass in 0..SHIFT_CHECK_PASSES {
            let (next, ritz) = checked_pass(&mass, &llt, x, sigma).unwrap();
            for (k, (r, l)) in ritz.iter().zip(lambda).enumerate() {
                let scale = l.abs().max(lambda[6]);
                assert!(
                    *r >= l - 1e-9 * scale,
                    "pass {pass} value {k}: {r} below {l}"
                );
            }
            let p = (pass + 1) as i32;
            let bound = lambda[b] / lambda[6] * n as f64 * rate.powi(2 * p);
            let rel = (ritz[6] - lambda[6]) / lambda[6];
            assert!(
                rel <= bound.max(1e-9),
                "pass {p}: bound {rel:e} off, theory {bound:e}"
            );
            let gram = mass_gram(&mass, llt.order(), &next);
            let off = (0..b)
                .flat_map(|i| (0..b).map(move |j| (i, j)))
                .map(|(i, j)| (gram[(i, j)] - f64::from(u8::from(i == j))).abs())
                .fold(0.0, f64::max);
            assert!(off < 1e-10, "pass {pass}: X^T M X - I = {off:e}");
            x = next;
        }
    }
}
