//! Certified modes of an assembled FE model: shift-invert ARPACK on K - sigma M = L L^T,
//! residuals, M-orthogonality, and a Sturm count at a shift in a spectral gap.

use super::certify::{self, SturmCheck};
use super::placement::{
    above_roundoff, moved_shift, placed_shift, ritz_bound, shift_in_doubt, Moved, GRAM_COLUMNS,
    PLACEMENT_ROUNDS, SHIFT_FRACTION,
};
use super::shift_invert::{solve_modes_watched, Watch, Watched};
use super::{solve_modes, EigenError, EigenSettings, Modes};
use crate::fem::fields::{monomial_count, SmoothFields};
use crate::fem::model::{FeModel, Timings};
use crate::linalg::factor::{Analysis, FactorError};
use crate::linalg::sparse::{Pattern, StiffnessMass, SymCsc};
use crate::linalg::spill::{lower_shifted, spill_threshold};
use crate::linalg::tripled::Product;
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
        // a solve that finds only rigid-body modes is extended (`certify_with_recovery`)
        let wanted = count + guard;
        let rigid = RIGID_MODES * RIGID_ROUNDS;
        let wanted = if wanted <= rigid {
            wanted + rigid
        } else {
            wanted
        };
        let nev = wanted.min(n.saturating_sub(1)).max(count);
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
            // with its tripled form for the Lanczos products (linalg::tripled): a third of
            // the entries at 12 bytes
            mass: 16 * mass_entries + 4 * mass_entries,
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

/// Missed modes a re-solve goes after, at most, for a solve of `nev` modes: max(nev, 16). An
/// iteration skips a mode or a cluster of a few (a multiplicity, a near-degenerate pair); a
/// count of thousands more than were computed (`--shift-hz 1e9 --keep-shift` on the test
/// engine's liner: 5,995 below the check's shift, 10 computed, and a re-solve for all of them
/// that ran past 2 minutes) means the computed modes are not the lowest (a shift far from
/// them, whose eigenvalues carry an error of eps |sigma|), which a re-solve of that size would
/// not mend in any time a user waits for.
fn recoverable(nev: usize) -> usize {
    nev.max(16)
}

/// A free body's rigid-body modes (three translations, three rotations): how many more a
/// solve whose modes were all rigid asks for.
const RIGID_MODES: usize = 6;

/// How many times a first solve whose modes were all rigid is extended by [`RIGID_MODES`]
/// (two free bodies); beyond, the certificate says what is missing.
const RIGID_ROUNDS: usize = 2;

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
    let sigma = if place {
        floored_shift(sigma, km.eigenvalue_scale())
    } else {
        sigma
    };
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

pub use super::certify::SHIFT_FLOOR;

/// `sigma`, or -[`SHIFT_FLOOR`] `scale` when a negative `sigma` lies closer to zero than that
/// (logged; `modes` warns of it): the modes are the same, solved at a shift their certificate
/// can judge.
fn floored_shift(sigma: f64, scale: f64) -> f64 {
    let floor = -SHIFT_FLOOR * scale;
    // a shift of a few 1e-160 Hz or less squares to -0 (underflow): moved as well
    if !(sigma <= 0.0 && sigma > floor) {
        return sigma;
    }
    log::info!(
        "the shift {} Hz lies so close to zero that a rigid-body mode's residual is round-off against it: solving at {:.1} Hz instead, 1e-8 of the model's eigenvalue scale (--keep-shift solves at the shift as given)",
        crate::text::num(shift_hz(sigma)),
        shift_hz(floor)
    );
    floor
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
    /// The closest to zero a move may bring the shift (-[`SHIFT_FLOOR`] times the eigenvalue
    /// scale; 0 when the shift is not placed).
    floor: f64,
}

impl Placement {
    /// The shift solved as given.
    fn none(sigma: f64) -> Self {
        Self {
            sigma,
            checks: 0,
            watch: false,
            seconds: 0.0,
            floor: 0.0,
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
        let floor = -SHIFT_FLOOR * km.eigenvalue_scale();
        let moved = bound.and_then(|b| moved_shift(b, sigma, floor));
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
                shift_hz(-b),
                shift_hz(better)
            );
        }
        let in_doubt = bound.is_some_and(|b| shift_in_doubt(b, sigma));
        Self {
            sigma: moved.unwrap_or(sigma),
            checks: PLACEMENT_ROUNDS,
            watch: moved.is_none() && !in_doubt,
            seconds: t.elapsed().as_secs_f64(),
            floor,
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
    let zero = certify::RIGID_FRACTION * km.eigenvalue_scale();
    let mut extended = 0;
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
        // a set that ends among the rigid-body modes has no gap to certify at: the whole
        // cluster and the first elastic mode are solved for
        if attempt == 0
            && extended < RIGID_ROUNDS
            && all.eigenvalues.last().is_some_and(|&l| l <= zero)
            && nev + 1 < n
        {
            extended += 1;
            nev = (nev + RIGID_MODES).min(n - 1);
            log::info!("the computed eigenvalues are all rigid-body modes: solving for {nev}");
            continue;
        }
        let t = Instant::now();
        let mut all = all;
        let sturm = sturm_check(km, analysis, (&mut all, spare), (count, zero))?;
        timings.certification += t.elapsed().as_secs_f64();
        let retry = match &sturm {
            Some(st) if st.found > st.expected + recoverable(nev) => {
                log::warn!(
                    "the Sturm count at {:.1} Hz found {} eigenvalues below, {} were computed: far more than an iteration skips (at most {} are solved for again), so these are not the lowest modes (a shift far from them); not solving again (a shift near the wanted modes, or without --keep-shift)",
                    st.shift_hz,
                    st.found,
                    st.expected,
                    recoverable(nev)
                );
                None
            }
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
    let (residuals, m_orthogonality) = certify::residuals_and_orthogonality(km, &modes, sigma);
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
                let (result, (tf, te)) = check_then_solve(&mass, llt, &settings, placement.floor)?;
                t_factor += tf;
                t_eigen += te;
                return Ok::<_, ModalError>(result);
            }
            let t = Instant::now();
            let ((result, spent), values) =
                watched_solve(&mass, llt, &settings, (watching, placement.floor), recycle)?;
            // a block check's seconds count with the factorisation's, as above
            t_eigen += t.elapsed().as_secs_f64() - spent.0;
            t_factor += spent.0;
            // (every move above leaves `spare` empty)
            spare = values;
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
    (watching, floor): (bool, f64),
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
    let product = Product::new(mass);
    let run = solve_modes_watched(n, settings, |x, y| product.apply(x, y), solve, watch)?;
    let Watched::Done(modes) = run else {
        // the first restart's bound leaves the shift in doubt: the block check decides
        let Some(llt) = factor.into_inner() else {
            unreachable!("a stopped iteration keeps its factor")
        };
        log::info!(
            "Lanczos stopped at its first restart (lambda_{nev} <= {bound:.4e}, shift {sigma:.4e})"
        );
        return Ok((check_then_solve(mass, llt, settings, floor)?, None));
    };
    log::info!("{}", modes.work_summary());
    // converged before its first restart: its own eigenvalues judge the shift
    let top = modes.eigenvalues.get(nev.saturating_sub(1)).copied();
    let result = match top
        .filter(|&t| watching && !watched && above_roundoff(t, -sigma))
        .and_then(|top| moved_shift(top, sigma, floor))
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
    floor: f64,
) -> Result<Checked, ModalError> {
    let (nev, sigma, n) = (settings.count, settings.sigma, mass.pattern.n);
    let t = Instant::now();
    let better = placed_shift(mass, &llt, nev, (sigma, floor));
    let t_check = t.elapsed().as_secs_f64();
    log::info!("shift check {t_check:.2} s");
    crate::machine::release_memory();
    if let Some(better) = better {
        return Ok((Err(better), (t_check, 0.0)));
    }
    let t = Instant::now();
    let solve = move |x: &mut [f64]| llt.solve_vec(x);
    let product = Product::new(mass);
    let modes = solve_modes(n, settings, |x, y| product.apply(x, y), solve)?;
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

/// The Sturm certificate of computed eigenvalues: the negative pivots of K - sigma_c M at a
/// shift in the first spectral gap at or above mode `count` and above the rigid-body cluster's
/// bound `zero` ([`certify::sturm_shift`]); None when the computed spectrum offers no gap.
fn sturm_check(
    km: &mut StiffnessMass,
    analysis: &Analysis,
    (modes, spare): (&mut Modes, Option<Vec<f64>>),
    (count, zero): (usize, f64),
) -> Result<Option<SturmCheck>, ModalError> {
    let Some((sigma_c, expected)) = certify::sturm_shift(&modes.eigenvalues, count, 1e-4, zero)
    else {
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
    use crate::eigen::placement::{checked_pass, mass_gram, SHIFT_CHECK_PASSES};
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

    /// Verification: the residuals and the M-orthonormality error of the certificate
    /// (computed on all cores, M Phi shared) equal their definitions evaluated one mode at a
    /// time with plain loops here, on modes disturbed so that neither is zero (mode 2 scaled
    /// by 1.001: its residual stays, its M-norm becomes 1.001^2; mode 4 given a part of mode
    /// 5). Both sides sum in the same order: equal to 1e-14 relative.
    #[test]
    fn verification_residuals_and_orthogonality_match_their_definitions() {
        let mut model = steel_block();
        let (km, an) = (&mut model.km, &model.analysis);
        let (sol, _) = certified_modes(km, an, 10, -1e4, 2, false, None).unwrap();
        let mut modes = sol.modes;
        let n = modes.n;
        modes.vectors[2 * n..3 * n]
            .iter_mut()
            .for_each(|v| *v *= 1.001);
        for i in 0..n {
            modes.vectors[4 * n + i] += 0.01 * modes.vectors[5 * n + i];
        }
        let (res, gram) = certify::residuals_and_orthogonality(km, &modes, -1e4);
        let k = crate::linalg::sparse::SymCsc {
            pattern: km.pattern.clone(),
            values: km.k.clone(),
        };
        let m = crate::linalg::sparse::SymCsc {
            pattern: km.pattern.clone(),
            values: km.m.clone(),
        };
        let mul = |a: &crate::linalg::sparse::SymCsc, x: &[f64]| {
            let mut y = vec![0.0; n];
            a.matvec(x, &mut y);
            y
        };
        let norm = |x: &[f64]| x.iter().map(|v| v * v).sum::<f64>().sqrt();
        // the residuals' scale s = min(|sigma|, max(lambda_top, f)) (`certify` module doc)
        let top = modes.eigenvalues.iter().fold(0.0f64, |t, &l| t.max(l));
        let scale = km.eigenvalue_scale();
        assert!(top > certify::RIGID_FRACTION * scale);
        let s = top.max(SHIFT_FLOOR * scale).min(1e4);
        let mut worst: f64 = 0.0;
        for i in 0..modes.count() {
            let (kx, mx) = (mul(&k, modes.vector(i)), mul(&m, modes.vector(i)));
            let lam = modes.eigenvalues[i];
            let r: Vec<f64> = kx.iter().zip(&mx).map(|(a, b)| a - lam * b).collect();
            let expected = norm(&r) / norm(&kx).max(s * norm(&mx)).max(f64::MIN_POSITIVE);
            assert!(
                (res[i] - expected).abs() <= 1e-14 * expected,
                "mode {i}: {} vs {expected}",
                res[i]
            );
            for j in 0..modes.count() {
                let dot: f64 = modes.vector(j).iter().zip(&mx).map(|(a, b)| a * b).sum();
                worst = worst.max((dot - if i == j { 1.0 } else { 0.0 }).abs());
            }
        }
        assert!((gram - worst).abs() <= 1e-14 * worst, "{gram} vs {worst}");
        assert!(gram > 1e-3, "the disturbance is seen: {gram}");
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
