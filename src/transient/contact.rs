//! One implicit step of rigid bodies (pistons, 2 DOF each) in penalty contact with a linear
//! structure, the structure condensed to the contact slices.
//!
//! Unknowns of the step: the body coordinates q (Newmark, average acceleration or the
//! scheme's beta, gamma) and the slice forces F. With the structure condensed,
//!   u = u~ + G F,   u' = u'~ + G_v F
//! (u~ the structure's predictor at the slices, G its compliance for this step), and a slice in
//! a fixed linear piece of its law, F = a + k_t p + c_d p' with p = s . q - g - u, the forces
//! of the active slices A solve
//!   W F_A = r0 + (K_t + kappa C_d) S q,   W = I + K_t G_AA + C_d G_v,AA,
//!   r0 = a - K_t (g + u~) + C_d (S v^ - kappa S q^ - u'~),  kappa = gamma / (beta dt),
//! and the bodies
//!   [M / (beta dt^2) - B^T W^-1 (K_t + kappa C_d) S] q = f_ext + M q^ / (beta dt^2) + B^T W^-1 r0.
//! Newton on the piecewise-linear contact: solve for the assumed pieces, recompute every
//! slice's penetration, repeat until no slice changes its piece (the exact solution of the
//! step). Only contact-sized systems are solved.
//!
//! Contact law of a slice (Kelvin-Voigt that never pulls):
//!   F = max(0, F_e(p) + c_d p')  for p > 0,   F = 0  for p <= 0,
//! F_e the slice's elastic law. The clamp makes the release continuous in time: the force
//! reaches zero while the slice still penetrates (F_e(p) = -c_d p' > 0) and stays zero until
//! the surfaces part. The one jump of the law is at the onset, where the damper force c_d p'
//! appears at once. Within the implicit step the damper acts only on slices that penetrated
//! at the previous step (so the step's law is continuous in the unknowns and the step always
//! has a solution); the impulse the damper should have delivered from the onset on is added
//! afterwards as an impulsive correction ([`onset_impulses`]), which makes the error of an
//! impact second order in the step instead of first (c_d v dt per impact).
//!
//! HHT-alpha: the bodies' equation is taken at the same shifted time as the structure's,
//!   M a_{n+1} = (1 + alpha) (f_{n+1} + B^T F_{n+1}) - alpha (f_n + B^T F_n),
//! so the slice forces act on body and structure with the same weights (the momentum they
//! exchange balances step by step). The body's M / (beta dt^2) row then carries
//! (1 + alpha) B^T on the slice forces and -alpha times the total force of the last step
//! ([`Body::applied`]) on its right-hand side; alpha = 0 is Newmark exactly.

use super::scheme::Scheme;
use crate::linalg::lu::Lu;
use crate::piston::lubrication::Film;
use nalgebra::{DMatrix, DVector};

/// Where a slice touches the structure: up to two structure contact DOFs with weights
/// (linear interpolation along a bore line).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Location {
    pub dofs: [usize; 2],
    pub weights: [f64; 2],
}

/// The linear structure as the contact sees it during one step. [`Structure::prepare`] gets
/// the step's slice locations (after the structure's own predictor); the other methods refer
/// to them by index.
pub trait Structure {
    /// Sets the locations of this step.
    fn prepare(&mut self, locs: &[Location]);
    /// Predicted displacement and velocity at location `i` (no new contact force).
    fn predicted(&self, i: usize) -> (f64, f64);
    /// An interval (centre, radius) that holds the predicted displacement at location `i`,
    /// cheaper than [`Structure::predicted`]; `None` when the structure has no such bound.
    /// A slice whose penetration stays below its law's onset over the whole interval is apart
    /// without its exact prediction.
    fn predicted_bound(&self, _i: usize) -> Option<(f64, f64)> {
        None
    }
    /// Compliances G (displacement per force) and G_v (velocity per force) among `active`.
    fn compliance(&mut self, active: &[usize]) -> (DMatrix<f64>, DMatrix<f64>);
    /// Displacement at every location caused by the forces `forces` at `active`: G F.
    fn response(&self, active: &[usize], forces: &[f64]) -> Vec<f64>;
    /// Velocity at every location caused by the forces `forces` at `active`: G_v F.
    fn velocity_response(&self, active: &[usize], forces: &[f64]) -> Vec<f64>;
}

pub use crate::linalg::kernels::dot;

/// A slice that may touch during the step.
#[derive(Clone, Debug)]
pub struct Slice<'a> {
    pub body: usize,
    /// d p / d q of the body, and the generalised force per unit contact force.
    pub row: [f64; 2],
    pub force_row: [f64; 2],
    /// Penetration offset: p = row . q - gap - u.
    pub gap: f64,
    pub law: &'a crate::piston::skirt::SliceLaw,
    pub damping: f64,
    pub at: Location,
    /// Penetration at the previous step: the damper acts during this step when it was > 0
    /// (keeps the law continuous within the step, so the implicit step always has a solution;
    /// the impulse it misses from the onset on is restored by [`onset_impulses`]).
    pub prev_penetration: f64,
    /// Penetration rate at the previous step [m/s] (where a film or contact had it): with
    /// `prev_penetration` the first linearisation point of a film.
    pub prev_rate: f64,
}

/// One skirt side's oil film in a step ([`crate::piston::lubrication`]): its slices (indices
/// into the step's slices, consecutive skirt slices from skirt slice `first`, top to bottom),
/// the film and the piston's axial velocity z' [m/s] (+ up).
#[derive(Clone, Debug)]
pub struct FilmGroup<'a> {
    pub slices: Vec<usize>,
    pub first: usize,
    pub film: &'a Film,
    pub axial_velocity: f64,
}

/// One engaged film side during a step: the film evaluated at a linearisation point (p0, p0')
/// (the previous step's state, then each Newton iterate) and linearised there,
///   F_f,i = F0_i + sum_k D_ik (p_k - p0_k) + sum_k C_ik (p'_k - p0'_k),
/// D = dF/dp the side's gap tangent (Reynolds and asperity terms), C = dF/dp' its squeeze
/// matrix.
struct FilmBlock {
    slices: Vec<usize>,
    f0: Vec<f64>,
    p0: Vec<f64>,
    r0: Vec<f64>,
    c: DMatrix<f64>,
    d: DMatrix<f64>,
}

impl FilmBlock {
    /// The engaged films of `films` at penetrations `pen` and rates `rates`.
    fn at(films: &[FilmGroup<'_>], (pen, rates): (&[f64], &[f64])) -> Vec<Self> {
        films
            .iter()
            .filter_map(|g| {
                let p0: Vec<f64> = g.slices.iter().map(|&i| pen[i]).collect();
                let r0: Vec<f64> = g.slices.iter().map(|&i| rates[i]).collect();
                let side = g.film.side(g.first, &p0, &r0, g.axial_velocity);
                side.engaged.then(|| FilmBlock {
                    slices: g.slices.clone(),
                    f0: side.force.clone(),
                    p0,
                    r0,
                    c: side.d_rate,
                    d: side.d_pen,
                })
            })
            .collect()
    }

    /// The film force of the block's slice `a` at penetrations `pen` and rates `rates`.
    fn force(&self, a: usize, pen: &[f64], rates: &[f64]) -> f64 {
        let mut f = self.f0[a];
        for (k, &j) in self.slices.iter().enumerate() {
            f += self.d[(a, k)] * (pen[j] - self.p0[k]) + self.c[(a, k)] * (rates[j] - self.r0[k]);
        }
        f
    }
}

/// A body's Newmark state and this step's loads.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Body {
    pub mass: [[f64; 2]; 2],
    pub q: [f64; 2],
    pub v: [f64; 2],
    pub a: [f64; 2],
    /// External generalised force at the new time.
    pub force: [f64; 2],
    /// Total generalised force (external and contact) at the body's current time: the
    /// -alpha f_n term of HHT-alpha. Set it to the external force when starting from rest.
    pub applied: [f64; 2],
    /// The pin's friction torque on the tilt at the new time (none by default).
    pub tilt_friction: TiltFriction,
}

/// The pin journal's friction torque on the piston's tilt over one step,
///   T(phi') = T_m tanh((beta' - phi') / w_s),
/// T_m = mu_pin r_pin F_pin the Coulomb torque, beta' the rod's angular velocity and w_s the
/// slip rate over which the torque reverses (the [`crate::piston`] module docs).
/// The step takes it implicitly, linearised at the predictor's tilt rate phi'~:
///   T = T(phi'~) + T'(phi'~) (phi'_{n+1} - phi'~),  phi'_{n+1} = phi'~ + kappa (phi - phi~),
/// so a steep reversal (T_m / w_s large against the tilt inertia / dt) stays stable; the
/// linearisation's error is O((phi'_{n+1} - phi'~)^2 T'').
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TiltFriction {
    /// T_m [N m], beta' [rad/s], w_s [rad/s] (> 0 when T_m > 0).
    pub max_torque: f64,
    pub rod_rate: f64,
    pub slip_rate: f64,
}

impl TiltFriction {
    /// The torque [N m] at tilt rate `phi_rate` and its derivative dT / d phi' [N m s].
    pub fn torque(&self, phi_rate: f64) -> (f64, f64) {
        if self.max_torque == 0.0 {
            return (0.0, 0.0);
        }
        let th = ((self.rod_rate - phi_rate) / self.slip_rate).tanh();
        (
            self.max_torque * th,
            -self.max_torque * (1.0 - th * th) / self.slip_rate,
        )
    }
}

/// Result of one step.
#[derive(Clone, Debug)]
pub struct StepResult {
    pub bodies: Vec<Body>,
    /// Force of every slice (0 when apart or clamped, never negative) and its penetration.
    pub forces: Vec<f64>,
    pub penetrations: Vec<f64>,
    /// Penetration rate p' at the new time of every penetrating slice (0 elsewhere) [m/s].
    pub rates: Vec<f64>,
    /// Damper part c_d p' of every slice force (0 where the damper did not act) \[N\].
    pub damper: Vec<f64>,
    /// Slices whose damped force was clamped at zero (it would have pulled).
    pub clamped: Vec<bool>,
    /// The oil film's part of every slice force \[N\] (0 for a dry skirt).
    pub film: Vec<f64>,
    /// The film evaluated at the step's end state, F_end (each engaged side's force at the
    /// converged iterate, where the Newton iteration last linearised it; 0 off an engaged
    /// side): `film` differs from it by the iteration's residual.
    pub film_end: Vec<f64>,
    pub iterations: usize,
}

impl StepResult {
    /// Every slice's state at the end of the step, for [`onset_impulses`] (onsets unmarked).
    pub fn slice_states(&self) -> Vec<SliceState> {
        (0..self.forces.len())
            .map(|k| SliceState {
                penetration: self.penetrations[k],
                rate: self.rates[k],
                damper: self.damper[k],
                clamped: self.clamped[k],
                onset: false,
                film: self.film[k],
            })
            .collect()
    }
}

/// One slice at one end of a step, as [`onset_impulses`] needs it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SliceState {
    /// Penetration \[m\] (negative: apart), its rate [m/s], and the damper part of the slice's
    /// nodal force \[N\].
    pub penetration: f64,
    pub rate: f64,
    pub damper: f64,
    pub clamped: bool,
    /// The contact began in the step that ended here (the damper was lagged).
    pub onset: bool,
    /// The oil film's part of the slice force \[N\].
    pub film: f64,
}

impl SliceState {
    /// A slice not on the liner (or apart with no history).
    pub const APART: SliceState = SliceState {
        penetration: -1.0,
        rate: 0.0,
        damper: 0.0,
        clamped: false,
        onset: false,
        film: 0.0,
    };

    /// Penetration and its rate: where a slice of the next step starts ([`Slice`]).
    pub fn prior(&self) -> (f64, f64) {
        (self.penetration, self.rate)
    }
}

/// Damper impulses that the average-acceleration steps miss at a contact onset, one per
/// slice [N s]; marks the onsets in `after` (the next call needs them).
///
/// The steps integrate a slice force by the trapezoidal rule, dt/2 (F_n + F_{n+1}). In
/// sustained contact the damper's impulse c_d int p' dt is then dt/2 c_d (p'_n + p'_{n+1}),
/// exact for the trapezoidal kinematics. At an onset (p_n <= 0 < p_{n+1}) the damper is
/// lagged, so two steps miss part of it:
/// - the onset step carries none; the damper's impulse from the onset t* on is
///   c_d p'_{n+1} (t_{n+1} - t*), with t_{n+1} - t* = min(dt, p_{n+1} / p'_{n+1}) (linear in
///   time: second order; the start's penetration may be only a bound, see
///   [`Structure::predicted_bound`], so it is not used);
/// - the next step starts from a node without damper force; if the slice still penetrates
///   and is damped at its end, it misses dt/2 c_d p'_{n+1}.
///
/// Both are restored at the end of the step after the onset, and only when the damper acts
/// in that step (the slice penetrates, is damped and not clamped at its end). Whether the
/// damper can act at all is decided by that step: where the damper's force would push the
/// slice out within the step (the liner's quasi-static compliance gives way by more than the
/// penetration, R c_d p' > p), the Newton iteration parts it and it loses its damper for the
/// step ([`step`]), so a shallow slice runs undamped until it is deep enough to hold it. The
/// onset step cannot know this; giving its impulse at the onset
/// would credit a damper that the law, as stepped, does not carry (measured on the small
/// engine's rolling slap: the slices engaging one by one got c_d p_{n+1} each at 0.083 deg
/// while their dampers stayed off for 0.2 deg at 1/48 of it, and the slap force came out
/// 3.3-3.7 % low at the scene's step). Kicking one step later moves the impulse by a step:
/// O(dt^2) in where the body is, like the second part.
///
/// A grazing onset, already receding at t_{n+1} (p'_{n+1} <= 0), gets none: its damper would
/// pull and is clamped. The impulses act on body and structure like slice forces (equal and
/// opposite). Average acceleration only (HHT-alpha weights the nodal forces differently):
/// other schemes get none. `dt` is the step just taken (the onset step's size is taken equal
/// to it in the bound t_{n+1} - t* <= dt).
pub fn onset_impulses(
    before: &[SliceState],
    after: &mut [SliceState],
    damping: &[f64],
    dt: f64,
    scheme: Scheme,
) -> Vec<f64> {
    if scheme != Scheme::average_acceleration() {
        return vec![0.0; after.len()];
    }
    before
        .iter()
        .zip(after.iter_mut())
        .zip(damping)
        .map(|((b, a), &c)| {
            if c == 0.0 || a.penetration <= 0.0 {
                return 0.0;
            }
            if b.penetration <= 0.0 {
                if a.rate <= 0.0 {
                    return 0.0;
                }
                a.onset = true;
                return 0.0;
            }
            if b.onset && a.damper != 0.0 && !a.clamped {
                // from the onset to t_n, then the start node's missing half
                let since_onset = (b.penetration / b.rate).min(dt);
                return c * b.rate * since_onset + 0.5 * dt * c * b.rate;
            }
            0.0
        })
        .collect()
}

/// Applies slice impulses `impulses` to the bodies: v += M^-1 b_i dI_i (the structure takes
/// the opposite impulse through [`Structure`]'s owner).
pub fn kick_bodies(bodies: &mut [Body], slices: &[Slice<'_>], impulses: &[f64]) {
    for (s, &di) in slices.iter().zip(impulses) {
        if di == 0.0 {
            continue;
        }
        let b = &mut bodies[s.body];
        let m = b.mass;
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        let g = [s.force_row[0] * di, s.force_row[1] * di];
        b.v[0] += (m[1][1] * g[0] - m[0][1] * g[1]) / det;
        b.v[1] += (m[0][0] * g[1] - m[1][0] * g[0]) / det;
    }
}

/// Why a step failed (the caller retries with a smaller step or reports).
#[derive(Clone, Debug, PartialEq)]
pub enum StepFailure {
    NoConvergence { iterations: usize },
    Singular,
}

/// Marks the slices of the film groups `films` among `n` slices.
fn film_slices(films: &[FilmGroup<'_>], n: usize) -> Vec<bool> {
    let mut in_film = vec![false; n];
    for g in films {
        for &i in &g.slices {
            in_film[i] = true;
        }
    }
    in_film
}

/// Linearises every engaged film side at penetrations `pen` and rates `rates` into the step's
/// [`FilmBlock`]s and marks their slices.
fn link_films(st: &mut Step<'_, '_>, films: &[FilmGroup<'_>], pen: &[f64], rates: &[f64]) {
    set_films(st, FilmBlock::at(films, (pen, rates)));
}

/// Makes `blocks` the step's film linearisation and marks their slices.
fn set_films(st: &mut Step<'_, '_>, blocks: Vec<FilmBlock>) {
    st.blocks = blocks;
    st.in_film.iter_mut().for_each(|v| *v = false);
    for b in &st.blocks {
        for &i in &b.slices {
            st.in_film[i] = true;
        }
    }
}

/// Relative agreement of a film's force with the film at the state that carries it at which
/// a step's Newton iteration has converged: per side, the largest slice difference against
/// the side's force (1e-4: a hundredth of the step's own error, about 1 %).
pub const FILM_NEWTON_TOL: f64 = 1e-4;
/// The absolute part of that agreement \[N\].
pub const FILM_NEWTON_FLOOR_N: f64 = 1e-3;

/// A lubricated step may take this many times the dry step's Newton iterations (its line
/// search shortens the steps where the film's force turns steeply).
pub const FILM_ITERATIONS: usize = 4;

/// A line search's state: body coordinates, slice forces, and the films evaluated there with
/// the film part of the forces (none without a search).
type SearchedState = (DVector<f64>, Vec<f64>, Option<(Vec<FilmBlock>, Vec<f64>)>);

/// A state of a lubricated step's Newton iteration: body coordinates, every slice's force and
/// its film part, and the largest slice difference between that film part and the film at
/// the state \[N\] (the residual the line search lowers).
struct Accepted {
    q: DVector<f64>,
    forces: Vec<f64>,
    film: Vec<f64>,
    resid: f64,
}

/// The residual of the film forces `used` (every slice) against the films `blocks` evaluated
/// at the same state (their F0; a group slice in no engaged block has none): the largest
/// slice difference \[N\], and whether every side agrees to [`FILM_NEWTON_TOL`] of its force.
fn film_agreement(blocks: &[FilmBlock], in_group: &[bool], used: &[f64]) -> (f64, bool) {
    let mut exact = vec![0.0; used.len()];
    let mut covered = vec![false; used.len()];
    for b in blocks {
        for (a, &i) in b.slices.iter().enumerate() {
            exact[i] = b.f0[a];
            covered[i] = true;
        }
    }
    let resid = (0..used.len())
        .filter(|&i| in_group[i])
        .map(|i| (used[i] - exact[i]).abs())
        .fold(0.0, f64::max);
    let sides = blocks.iter().all(|b| {
        let total: f64 = b
            .slices
            .iter()
            .map(|&i| exact[i].abs().max(used[i].abs()))
            .sum();
        b.slices
            .iter()
            .all(|&i| (used[i] - exact[i]).abs() <= FILM_NEWTON_TOL * total + FILM_NEWTON_FLOOR_N)
    });
    // a film force on a slice whose side has no film at this state
    let stray =
        (0..used.len()).any(|i| in_group[i] && !covered[i] && used[i].abs() > FILM_NEWTON_FLOOR_N);
    (resid, sides && !stray)
}

/// The Newton iteration's first pieces: the previous step's piece of each slice (usually
/// still right in sustained contact), or for a slice apart before, the piece of its
/// predicted penetration `pen`; the damper acts where the slice penetrated before.
fn initial_pieces(slices: &[Slice<'_>], pen: &[f64]) -> Vec<Piece> {
    slices
        .iter()
        .zip(pen)
        .map(|(s, &p)| {
            let prev = s.law.piece(s.prev_penetration).mask;
            let mask = if prev != 0 { prev } else { s.law.piece(p).mask };
            Piece {
                mask,
                damped: s.prev_penetration > 0.0 && s.damping != 0.0,
                clamped: false,
            }
        })
        .collect()
}

/// Solves one step of size `dt` with the structure's `scheme` (Newmark beta, gamma; HHT alpha).
///
/// A piecewise-linear Newton on the slices' law pieces: each iteration solves the step's
/// linear problem for the active set (`Step::solve_active`), then moves every slice to the
/// piece its new penetration lies on (`Step::next_pieces`); it has converged when no slice
/// changes. After a third of `max_iterations` only the most violated slice changes per
/// iteration (guards against cycling).
///
/// The oil films (`films`, empty for a dry skirt) add their forces to their slices, fully
/// implicit: each side's film is linearised (`FilmBlock`) at the state of the last iterate,
///   F_f,i = F0_i + sum_k D_ik (p_k - p0_k) + sum_k C_ik (p'_k - p0'_k),
/// D = dF/dp (Reynolds and asperity terms), C = dF/dp' (the squeeze matrix), first at the
/// previous step's state. The iteration is a damped Newton method: each solution is reached
/// along a line search (`Step::film_search`) that lowers the films' residual (the film part
/// of the forces against the film at the state), and the step has converged when no slice
/// changes its piece and every side's film agrees with its force to [`FILM_NEWTON_TOL`].
/// Without the line search the iteration cycled where a squeeze film met the liner's light
/// bore-line modes (the default engine: the residual vectors); without the previous state as
/// the first point it started from the predictor, which lacks the static part of the
/// structure's give under the film's force.
pub fn step(
    bodies: &[Body],
    slices: &[Slice<'_>],
    films: &[FilmGroup<'_>],
    structure: &mut dyn Structure,
    dt: f64,
    scheme: Scheme,
    max_iterations: usize,
) -> Result<StepResult, StepFailure> {
    let mut st = Step::new(bodies, slices, dt, scheme);
    let locs: Vec<Location> = slices.iter().map(|s| s.at).collect();
    structure.prepare(&locs);
    st.in_group = film_slices(films, slices.len());
    if !films.is_empty() {
        st.last_response = Some(std::cell::RefCell::new(None));
    }
    let mut pred = Predictions::new(slices, &*structure, &st.in_group);
    // penetration of each slice without new contact forces: first guess of the pieces
    let mut pen: Vec<f64> = (0..slices.len())
        .map(|i| pred.penetration(i, st.qh[slices[i].body], 0.0, &*structure))
        .collect();
    if !films.is_empty() {
        // the films' first linearisation point: the previous step's state (the predictor
        // lacks the static part of the structure's response to the film's force, and would
        // start the iteration far from the solution)
        let p0: Vec<f64> = slices.iter().map(|s| s.prev_penetration).collect();
        let r0: Vec<f64> = slices.iter().map(|s| s.prev_rate).collect();
        link_films(&mut st, films, &p0, &r0);
    }
    let mut pieces = initial_pieces(slices, &pen);
    let mut g_cache: Option<(Vec<usize>, DMatrix<f64>, DMatrix<f64>)> = None;
    let mut acc: Option<Accepted> = None;
    // a lubricated step's damped Newton iteration may take short steps for a while
    let max_iterations = if films.is_empty() {
        max_iterations
    } else {
        FILM_ITERATIONS * max_iterations
    };
    for it in 1..=max_iterations {
        // a slice carries force when it penetrates or has a film, and its damped force is not
        // clamped
        let active: Vec<usize> = (0..slices.len())
            .filter(|&i| (pieces[i].mask != 0 && !pieces[i].clamped) || st.in_film[i])
            .collect();
        // compliance of the active set (reused while the set is unchanged)
        if g_cache.as_ref().is_none_or(|(a, _, _)| *a != active) {
            let (g, gv) = structure.compliance(&active);
            g_cache = Some((active.clone(), g, gv));
        }
        let (_, g, gv) = g_cache.as_ref().expect("set above");
        let (q, fa) = st.solve_active(&active, &pieces, g, gv, &pred)?;
        let mut forces = vec![0.0; slices.len()];
        for (r, &i) in active.iter().enumerate() {
            forces[i] = fa[r];
        }
        // with films: a damped Newton step, the point on the way from the last state to this
        // solution where the films' residual falls (a line search)
        let (q, forces, searched) = match acc.as_ref() {
            Some(last) if !films.is_empty() => {
                st.film_search(last, (&q, &forces), &mut pred, &*structure, films)
            }
            _ => (q, forces, None),
        };
        let active: Vec<usize> = if films.is_empty() {
            active
        } else {
            (0..slices.len()).filter(|&i| forces[i] != 0.0).collect()
        };
        let fa: Vec<f64> = active.iter().map(|&i| forces[i]).collect();
        let (extra, vel) = st.responses(&*structure, &active, &fa);
        let mut rates = vec![0.0; slices.len()];
        let (changes, worst) = st.next_pieces(
            &q,
            (&extra, &vel),
            &pieces,
            &mut pred,
            &*structure,
            (&mut pen, &mut rates),
        );
        let film_done = films.is_empty()
            || st.settle_films(&mut acc, films, searched, (&q, &forces, &pen, &rates));
        // with films, the mixed forces must also be the laws' plus the films' (checked last)
        if changes.is_empty()
            && film_done
            && (films.is_empty() || st.laws_agree(&pieces, (&forces, acc.as_ref()), (&pen, &rates)))
        {
            let mut res = st.result(&q, &active, &fa, &pieces, (forces, pen, rates), it);
            // the film part of the forces the step carries (the film at its end, `film_end`,
            // differs by the Newton residual: stats.film_mismatch)
            if let Some(last) = acc {
                res.film = last.film;
            }
            return Ok(res);
        }
        apply_changes(&mut pieces, (changes, worst), it > max_iterations / 3);
    }
    Err(StepFailure::NoConvergence {
        iterations: max_iterations,
    })
}

/// w_j += k g_j + c v_j for every j: a row of the step matrix W (stored as a column of its
/// transpose) gains a slice's stiffness and damping times a row of G and G_v.
fn add_row(w: &mut [f64], (k, g): (f64, &[f64]), (c, v): (f64, &[f64])) {
    for ((wj, gj), vj) in w.iter_mut().zip(g).zip(v) {
        *wj += k * gj + c * vj;
    }
}

/// Moves the slices to their next pieces: all that changed, or `late` in the iteration only
/// the most violated (guards against cycling).
fn apply_changes(pieces: &mut [Piece], (changes, worst): PieceChanges, late: bool) {
    if !late {
        for (i, next) in changes {
            pieces[i] = next;
        }
    } else if let Some((i, _)) = worst {
        let next = changes
            .iter()
            .find(|(k, _)| *k == i)
            .expect("the worst is a change")
            .1;
        pieces[i] = next;
    }
}

/// A slice's place on its law during the Newton iterations: the elastic piece (mask), whether
/// the damper acts this step (penetrating at the last step), whether the damped force is
/// clamped at zero.
#[derive(Clone, Copy)]
struct Piece {
    mask: u8,
    damped: bool,
    clamped: bool,
}

/// The slices whose piece changes in an iteration, with their next piece, and the most
/// violated of them (slice, violation as a penetration [m]).
type PieceChanges = (Vec<(usize, Piece)>, Option<(usize, f64)>);

/// The structure's predicted displacement and velocity at the slices, formed only where a
/// slice may touch: at slices in contact or damped at the last step, and wherever the
/// penetration's upper bound (the structure's interval) reaches the law's onset; the others
/// are apart and keep that bound as their penetration.
struct Predictions<'s, 'a> {
    slices: &'s [Slice<'a>],
    bounds: Vec<Option<(f64, f64)>>,
    threshold: Vec<f64>,
    exact: Vec<Option<(f64, f64)>>,
}

impl<'s, 'a> Predictions<'s, 'a> {
    /// `exact`: slices that need their exact prediction whatever their bound (a film's).
    fn new(slices: &'s [Slice<'a>], structure: &dyn Structure, exact: &[bool]) -> Self {
        let bounds = slices
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let touching =
                    s.prev_penetration > 0.0 || s.law.piece(s.prev_penetration).mask != 0;
                if touching || exact[i] {
                    None
                } else {
                    structure.predicted_bound(i)
                }
            })
            .collect();
        Self {
            slices,
            bounds,
            threshold: slices.iter().map(|s| s.law.onset().min(0.0)).collect(),
            exact: vec![None; slices.len()],
        }
    }

    /// Penetration of slice `i` at body coordinates `qb` with the extra structure
    /// displacement `extra`, p = s . q - gap - u~ - extra (the bound's upper end where that
    /// keeps it apart).
    fn penetration(
        &mut self,
        i: usize,
        qb: [f64; 2],
        extra: f64,
        structure: &dyn Structure,
    ) -> f64 {
        let s = &self.slices[i];
        let base = s.row[0] * qb[0] + s.row[1] * qb[1] - s.gap;
        if self.exact[i].is_none() {
            if let Some((centre, radius)) = self.bounds[i] {
                let upper = base - (centre - radius) - extra;
                if upper <= self.threshold[i] {
                    return upper;
                }
            }
            self.exact[i] = Some(structure.predicted(i));
        }
        base - self.exact[i].expect("set above").0 - extra
    }

    /// The exact prediction (u~, u~') of a slice that has one (every penetrating slice).
    fn exact(&self, i: usize) -> (f64, f64) {
        self.exact[i].expect("a penetrating slice has its prediction")
    }
}

/// The step's fixed data: bodies, slices, their Newmark predictors and the scheme's factors.
struct Step<'s, 'a> {
    bodies: &'s [Body],
    slices: &'s [Slice<'a>],
    dt: f64,
    scheme: Scheme,
    /// Newmark predictors q~ = q + dt v + dt^2 (1/2 - beta) a and v~ = v + dt (1 - gamma) a.
    qh: Vec<[f64; 2]>,
    vh: Vec<[f64; 2]>,
    /// kappa = gamma / (beta dt) (velocity per displacement), 1 / (beta dt^2).
    kappa: f64,
    c_acc: f64,
    /// The engaged films of this step and whether each slice belongs to one; whether each
    /// slice belongs to a film group (engaged or not).
    blocks: Vec<FilmBlock>,
    in_film: Vec<bool>,
    in_group: Vec<bool>,
    /// The last structure response asked for: active slices, their forces, G F and G_v F
    /// ([`Step::responses`]); kept for a lubricated step only (`None`: not kept).
    last_response: Option<std::cell::RefCell<Option<Response>>>,
}

/// A structure response: active slices, their forces, the displacement and velocity at every
/// slice.
type Response = (Vec<usize>, Vec<f64>, Vec<f64>, Vec<f64>);

fn dot2(r: [f64; 2], q: [f64; 2]) -> f64 {
    r[0] * q[0] + r[1] * q[1]
}

impl<'s, 'a> Step<'s, 'a> {
    fn new(bodies: &'s [Body], slices: &'s [Slice<'a>], dt: f64, scheme: Scheme) -> Self {
        let Scheme { beta, gamma, .. } = scheme;
        let qh = bodies
            .iter()
            .map(|b| {
                let f = |k: usize| b.q[k] + dt * b.v[k] + dt * dt * (0.5 - beta) * b.a[k];
                [f(0), f(1)]
            })
            .collect();
        let vh = bodies
            .iter()
            .map(|b| {
                let f = |k: usize| b.v[k] + dt * (1.0 - gamma) * b.a[k];
                [f(0), f(1)]
            })
            .collect();
        Self {
            bodies,
            slices,
            dt,
            scheme,
            qh,
            vh,
            kappa: gamma / (beta * dt),
            c_acc: 1.0 / (beta * dt * dt),
            blocks: Vec::new(),
            in_film: vec![false; slices.len()],
            in_group: vec![false; slices.len()],
            last_response: None,
        }
    }

    /// The linear step on the active set A with its pieces F_i = a_i + kt_i p_i (+ c_d p'_i
    /// where damped): the slice forces as affine functions of the body coordinates,
    /// W F_A = r0 + (Kt + kappa Cd) S q with W = I + Kt G + Cd G_v, then the bodies'
    /// M / (beta dt^2) (q - q~) = (1 + alpha) (f + B^T F_A) - alpha f_n; returns (q, F_A).
    fn solve_active(
        &self,
        active: &[usize],
        pieces: &[Piece],
        g: &DMatrix<f64>,
        gv: &DMatrix<f64>,
        pred: &Predictions<'_, '_>,
    ) -> Result<(DVector<f64>, Vec<f64>), StepFailure> {
        let (slices, kappa) = (self.slices, self.kappa);
        let na = active.len();
        let nq = 2 * self.bodies.len();
        // linear pieces
        let mut kt = vec![0.0; na];
        let mut av = vec![0.0; na];
        let mut cd = vec![0.0; na];
        for (r, &i) in active.iter().enumerate() {
            let s = &slices[i];
            if pieces[i].mask != 0 && !pieces[i].clamped {
                let piece = s.law.piece_of(pieces[i].mask);
                kt[r] = piece.kt;
                av[r] = piece.a;
                cd[r] = if pieces[i].damped { s.damping } else { 0.0 };
            }
        }
        // W built as its transpose from the transposes of G and G_v: row r of each is the
        // contiguous column r (the same sums in the same order as row by row) and right-hand
        // sides [r0 | (Kt + kappa Cd) S]
        let (g, gv) = (&g.transpose(), &gv.transpose());
        let mut wt = DMatrix::<f64>::identity(na, na);
        let mut rhs = DMatrix::<f64>::zeros(na, 1 + nq);
        for (r, &i) in active.iter().enumerate() {
            let s = &slices[i];
            add_row(
                wt.column_mut(r).as_mut_slice(),
                (kt[r], g.column(r).as_slice()),
                (cd[r], gv.column(r).as_slice()),
            );
            let (u, du) = pred.exact(i);
            let b = s.body;
            rhs[(r, 0)] = av[r] - kt[r] * (s.gap + u)
                + cd[r] * (dot2(s.row, self.vh[b]) - kappa * dot2(s.row, self.qh[b]) - du);
            let f = kt[r] + kappa * cd[r];
            rhs[(r, 1 + 2 * b)] = f * s.row[0];
            rhs[(r, 2 + 2 * b)] = f * s.row[1];
        }
        if !self.blocks.is_empty() {
            self.add_films(active, (g, gv), pred, (&mut wt, &mut rhs));
        }
        let sol = if na > 0 {
            let lu = Lu::new(wt.transpose().data.into(), na);
            let mut sol = rhs;
            lu.solve(sol.as_mut_slice(), 1 + nq)
                .ok_or(StepFailure::Singular)?;
            sol
        } else {
            rhs
        };
        let q = self.solve_bodies(active, &sol)?;
        // forces of the active slices
        let fa = (0..na)
            .map(|r| sol[(r, 0)] + (0..nq).map(|c| sol[(r, 1 + c)] * q[c]).sum::<f64>())
            .collect();
        Ok((q, fa))
    }

    /// Adds the engaged films' linearised forces to the rows of their slices (`g`, `gv`: G and
    /// G_v transposed, so that their rows are contiguous): for slice i of a block and every
    /// slice k of it, with p_k = s_k . q - g_k - u~_k - (G F)_k and
    /// p'_k = s_k . (v~ + kappa (q - q~)) - u'~_k - (G_v F)_k,
    ///   W_i. += D_ik G_k. + C_ik G_v,k. (W stored as its transpose `wt`),
    ///   r0_i += F0_i - D_ik p0_k - C_ik p0'_k - D_ik (g_k + u~_k) + C_ik (s_k . v~ - kappa s_k . q~ - u'~_k),
    ///   (rhs_q)_i += (D_ik + kappa C_ik) s_k.
    fn add_films(
        &self,
        active: &[usize],
        (g, gv): (&DMatrix<f64>, &DMatrix<f64>),
        pred: &Predictions<'_, '_>,
        (wt, rhs): (&mut DMatrix<f64>, &mut DMatrix<f64>),
    ) {
        let kappa = self.kappa;
        let pos = |i: usize| {
            active
                .binary_search(&i)
                .expect("a film's slices are active")
        };
        for blk in &self.blocks {
            // a side's slices are consecutive (`bore::film_groups`) and all active, so they sit
            // side by side in the active set: its rows of W gain D G_b + C G_v,b in two
            // matrix products
            let (n, r0) = (blk.slices.len(), pos(blk.slices[0]));
            debug_assert!(blk
                .slices
                .iter()
                .enumerate()
                .all(|(a, &i)| pos(i) == r0 + a));
            let mut rows = wt.columns_mut(r0, n);
            rows.gemm(1.0, &g.columns(r0, n), &blk.d.transpose(), 1.0);
            rows.gemm(1.0, &gv.columns(r0, n), &blk.c.transpose(), 1.0);
            for a in 0..n {
                let r = r0 + a;
                rhs[(r, 0)] += blk.f0[a];
                let mut term = |c: usize, kk: f64, cc: f64, shift: f64| {
                    let s = &self.slices[c];
                    let b = s.body;
                    let (u, du) = pred.exact(c);
                    rhs[(r, 0)] += -kk * (s.gap + u) - shift
                        + cc * (dot2(s.row, self.vh[b]) - kappa * dot2(s.row, self.qh[b]) - du);
                    let f = kk + kappa * cc;
                    rhs[(r, 1 + 2 * b)] += f * s.row[0];
                    rhs[(r, 2 + 2 * b)] += f * s.row[1];
                };
                for (k, &c) in blk.slices.iter().enumerate() {
                    let (dd, cc) = (blk.d[(a, k)], blk.c[(a, k)]);
                    if dd != 0.0 || cc != 0.0 {
                        term(c, dd, cc, dd * blk.p0[k] + cc * blk.r0[k]);
                    }
                }
            }
        }
    }

    /// The displacement and velocity at every slice caused by the forces `fa` at `active`:
    /// G F and G_v F (zero without forces). The last call's are kept and returned again for
    /// the same forces (a lubricated iteration asks for its accepted state's twice: in the
    /// line search and for the slices' next pieces).
    fn responses(
        &self,
        structure: &dyn Structure,
        active: &[usize],
        fa: &[f64],
    ) -> (Vec<f64>, Vec<f64>) {
        if active.is_empty() {
            let n = self.slices.len();
            return (vec![0.0; n], vec![0.0; n]);
        }
        let respond = || {
            (
                structure.response(active, fa),
                structure.velocity_response(active, fa),
            )
        };
        // only a lubricated step asks twice (a dry one would pay the copies for nothing)
        let Some(memo) = &self.last_response else {
            return respond();
        };
        let mut last = memo.borrow_mut();
        if let Some((a, f, u, v)) = last.as_ref() {
            if a == active && f == fa {
                return (u.clone(), v.clone());
            }
        }
        let (u, v) = respond();
        *last = Some((active.to_vec(), fa.to_vec(), u.clone(), v.clone()));
        (u, v)
    }

    /// The film groups' penetrations and rates (0 elsewhere) at body coordinates `q` with
    /// slice forces `forces`.
    fn film_state(
        &self,
        (q, forces): (&DVector<f64>, &[f64]),
        pred: &mut Predictions<'_, '_>,
        structure: &dyn Structure,
    ) -> (Vec<f64>, Vec<f64>) {
        let n = self.slices.len();
        let active: Vec<usize> = (0..n).filter(|&i| forces[i] != 0.0).collect();
        let fa: Vec<f64> = active.iter().map(|&i| forces[i]).collect();
        let (extra, vel) = self.responses(structure, &active, &fa);
        let (mut pen, mut rates) = (vec![0.0; n], vec![0.0; n]);
        for (i, s) in self.slices.iter().enumerate() {
            if self.in_group[i] {
                let qb = [q[2 * s.body], q[2 * s.body + 1]];
                pen[i] = pred.penetration(i, qb, extra[i], structure);
                let du = pred.exact(i).1 + vel[i];
                rates[i] = dot2(s.row, self.body_velocity(q, s.body)) - du;
            }
        }
        (pen, rates)
    }

    /// A damped Newton step of a lubricated step (a line search): from the last state `last`
    /// toward the new solution (`q1`, `f1`), solved with the films linearised at `last`, the
    /// state at the first of omega = 1, 1/2, ..., 1/64 where the films' residual (the film
    /// part of the forces against the film there, [`film_agreement`]) is below
    /// (1 - 1e-4 omega) of the last one or within the tolerance; at 1/64 when none is. The
    /// bodies' and the structure's equations are linear, so every such state satisfies them;
    /// the film part of the forces moves from `last`'s to the linearisation's at (`q1`, `f1`).
    /// Returns the state's coordinates and forces, and the films evaluated there with the film
    /// part of the forces.
    fn film_search(
        &self,
        last: &Accepted,
        (q1, f1): (&DVector<f64>, &[f64]),
        pred: &mut Predictions<'_, '_>,
        structure: &dyn Structure,
        films: &[FilmGroup<'_>],
    ) -> SearchedState {
        let (pen1, rates1) = self.film_state((q1, f1), pred, structure);
        let film1 = self.film_forces(&pen1, &rates1);
        let mix = |a: &[f64], b: &[f64], w: f64| -> Vec<f64> {
            a.iter().zip(b).map(|(x, y)| x + w * (y - x)).collect()
        };
        let mut omega = 1.0;
        loop {
            let qz = &last.q + (q1 - &last.q) * omega;
            let fz = mix(&last.forces, f1, omega);
            let filmz = mix(&last.film, &film1, omega);
            let (pz, rz) = if omega == 1.0 {
                (pen1.clone(), rates1.clone())
            } else {
                self.film_state((&qz, &fz), pred, structure)
            };
            let blocks = FilmBlock::at(films, (&pz, &rz));
            let (resid, ok) = film_agreement(&blocks, &self.in_group, &filmz);
            if ok || resid <= (1.0 - 1e-4 * omega) * last.resid || omega <= 1.0 / 64.0 {
                return (qz, fz, Some((blocks, filmz)));
            }
            omega *= 0.5;
        }
    }

    /// Relinearises the films at the iteration's new state (`q`, `forces`, with penetrations
    /// `pen` and rates `rates`; `searched`: the films already evaluated there by the line
    /// search, with the film part of the forces) and makes it the last state `acc`; returns
    /// whether the film part of the forces agrees with the films there ([`film_agreement`]).
    /// Without a search (the first iteration) the film part is the linearisation's at the
    /// state.
    fn settle_films(
        &mut self,
        acc: &mut Option<Accepted>,
        films: &[FilmGroup<'_>],
        searched: Option<(Vec<FilmBlock>, Vec<f64>)>,
        (q, forces, pen, rates): (&DVector<f64>, &[f64], &[f64], &[f64]),
    ) -> bool {
        let film = match searched {
            Some((blocks, film)) => {
                set_films(self, blocks);
                film
            }
            None => {
                let film = self.film_forces(pen, rates);
                link_films(self, films, pen, rates);
                film
            }
        };
        let (resid, done) = film_agreement(&self.blocks, &self.in_group, &film);
        *acc = Some(Accepted {
            q: q.clone(),
            forces: forces.to_vec(),
            film,
            resid,
        });
        done
    }

    /// Whether every slice's force `forces` is its contact law's on its piece at the state,
    /// plus the film part of the `accepted` state (none: false) (a lubricated step's line search mixes the last state's forces
    /// with the new ones, and a slice whose piece changed in between carries the old piece's
    /// force in the mix until a full step replaces it):
    ///   |F_i - (a_i + kt_i p_i + c_d p'_i) - F_film,i| <= [`FILM_NEWTON_TOL`] F_side + [`FILM_NEWTON_FLOOR_N`],
    /// the law's part 0 for a slice apart or clamped, F_side the body's summed |F| over both
    /// sides ([`film_agreement`] sums each side).
    fn laws_agree(
        &self,
        pieces: &[Piece],
        (forces, accepted): (&[f64], Option<&Accepted>),
        (pen, rates): (&[f64], &[f64]),
    ) -> bool {
        let Some(film) = accepted.map(|a| &a.film) else {
            return false;
        };
        let mut scale = vec![0.0; self.bodies.len()];
        for (s, f) in self.slices.iter().zip(forces) {
            scale[s.body] += f.abs();
        }
        self.slices.iter().enumerate().all(|(i, s)| {
            let p = pieces[i];
            let law = if p.mask != 0 && !p.clamped {
                let piece = s.law.piece_of(p.mask);
                let damper = if p.damped { s.damping * rates[i] } else { 0.0 };
                piece.a + piece.kt * pen[i] + damper
            } else {
                0.0
            };
            (forces[i] - law - film[i]).abs()
                <= FILM_NEWTON_TOL * scale[s.body] + FILM_NEWTON_FLOOR_N
        })
    }

    /// The film force of every slice at the films' linearisation point, F0 (0 off an engaged
    /// side).
    fn film_at_linearisation(&self) -> Vec<f64> {
        let mut out = vec![0.0; self.slices.len()];
        for blk in &self.blocks {
            for (&i, &f) in blk.slices.iter().zip(&blk.f0) {
                out[i] = f;
            }
        }
        out
    }

    /// The film force of every slice at penetrations `pen` and rates `rates` (0 off a film).
    fn film_forces(&self, pen: &[f64], rates: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.slices.len()];
        for blk in &self.blocks {
            for (a, &i) in blk.slices.iter().enumerate() {
                out[i] = blk.force(a, pen, rates);
            }
        }
        out
    }

    /// The bodies' coordinates with the active slice forces F_A = sol0 + sol_q q eliminated.
    fn solve_bodies(
        &self,
        active: &[usize],
        sol: &DMatrix<f64>,
    ) -> Result<DVector<f64>, StepFailure> {
        let alpha = self.scheme.alpha;
        let nq = 2 * self.bodies.len();
        let c_acc = self.c_acc;
        let mut a = DMatrix::<f64>::zeros(nq, nq);
        let mut bvec = DVector::<f64>::zeros(nq);
        for (k, body) in self.bodies.iter().enumerate() {
            for i in 0..2 {
                for j in 0..2 {
                    a[(2 * k + i, 2 * k + j)] = body.mass[i][j] * c_acc;
                    bvec[2 * k + i] += body.mass[i][j] * c_acc * self.qh[k][j];
                }
                bvec[2 * k + i] += (1.0 + alpha) * body.force[i] - alpha * body.applied[i];
            }
            // the pin's torque, linear in the new tilt: T0 + T' kappa (phi - phi~)
            let (t0, dt0) = body.tilt_friction.torque(self.vh[k][1]);
            let r = 2 * k + 1;
            bvec[r] += (1.0 + alpha) * (t0 - dt0 * self.kappa * self.qh[k][1]);
            a[(r, r)] -= (1.0 + alpha) * dt0 * self.kappa;
        }
        for (r, &i) in active.iter().enumerate() {
            let s = &self.slices[i];
            let row = 2 * s.body;
            for d in 0..2 {
                let fr = (1.0 + alpha) * s.force_row[d];
                bvec[row + d] += fr * sol[(r, 0)];
                for col in 0..nq {
                    a[(row + d, col)] -= fr * sol[(r, 1 + col)];
                }
            }
        }
        a.lu().solve(&bvec).ok_or(StepFailure::Singular)
    }

    /// Body `b`'s velocity at the new time, v~ + kappa (q - q~).
    fn body_velocity(&self, q: &DVector<f64>, b: usize) -> [f64; 2] {
        let (vh, qh) = (self.vh[b], self.qh[b]);
        [
            vh[0] + self.kappa * (q[2 * b] - qh[0]),
            vh[1] + self.kappa * (q[2 * b + 1] - qh[1]),
        ]
    }

    /// Every slice's new penetration and (where penetrating) rate p' = s . q' - u', u' =
    /// u'~ + G_v F, written into `pen` and `rates`; returns the slices whose piece changes
    /// with their next piece, and the most violated one (violation as a penetration).
    fn next_pieces(
        &self,
        q: &DVector<f64>,
        (extra, vel): (&[f64], &[f64]),
        pieces: &[Piece],
        pred: &mut Predictions<'_, '_>,
        structure: &dyn Structure,
        (pen, rates): (&mut [f64], &mut [f64]),
    ) -> PieceChanges {
        let mut next: Vec<Piece> = pieces.to_vec();
        for (i, s) in self.slices.iter().enumerate() {
            let qb = [q[2 * s.body], q[2 * s.body + 1]];
            pen[i] = pred.penetration(i, qb, extra[i], structure);
            let mask = s.law.piece(pen[i]).mask;
            next[i].mask = mask;
            if mask != 0 || self.in_group[i] {
                let du = pred.exact(i).1 + vel[i];
                rates[i] = dot2(s.row, self.body_velocity(q, s.body)) - du;
            }
            if mask == 0 {
                // a slice that parts loses its damper for the rest of the step: the law
                // jumps at p = 0 when the damper pushes (F(0+) = c_d p' > 0), and the step must
                // stay solvable; what the damper misses is restored by [`onset_impulses`]
                next[i].clamped = false;
                next[i].damped = false;
            } else if pieces[i].damped {
                // the damped force F_e(p) + c_d p' decides the clamp
                let f = s.law.force(pen[i]) + s.damping * rates[i];
                next[i].clamped = f < 0.0;
            }
        }
        let mut worst: Option<(usize, f64)> = None;
        let mut changes: Vec<(usize, Piece)> = Vec::new();
        for (i, s) in self.slices.iter().enumerate() {
            let (a, b) = (pieces[i], next[i]);
            if a.mask == b.mask && a.clamped == b.clamped && a.damped == b.damped {
                continue;
            }
            // violation as a penetration: the clamp's force over the piece's stiffness
            let v = if b.clamped != a.clamped {
                let f = s.law.force(pen[i]) + s.damping * rates[i];
                f.abs() / s.law.piece(pen[i]).kt.max(1.0)
            } else {
                pen[i].abs()
            };
            changes.push((i, b));
            if worst.is_none_or(|(_, w)| v > w) {
                worst = Some((i, v));
            }
        }
        (changes, worst)
    }

    /// The converged step: bodies at the new time (a = (q - q~) / (beta dt^2), v = v~ + gamma
    /// dt a, the total generalised force for HHT's next step), and every slice's force,
    /// penetration, rate, damper part F - F_e(p) and clamp.
    fn result(
        &self,
        q: &DVector<f64>,
        active: &[usize],
        fa: &[f64],
        pieces: &[Piece],
        (forces, pen, rates): (Vec<f64>, Vec<f64>, Vec<f64>),
        iterations: usize,
    ) -> StepResult {
        let gamma = self.scheme.gamma;
        let mut out = Vec::with_capacity(self.bodies.len());
        for (k, body) in self.bodies.iter().enumerate() {
            let mut b = *body;
            for d in 0..2 {
                let qn = q[2 * k + d];
                let an = (qn - self.qh[k][d]) * self.c_acc;
                b.q[d] = qn;
                b.a[d] = an;
                b.v[d] = self.vh[k][d] + gamma * self.dt * an;
            }
            b.applied = body.force;
            let (t0, dt0) = body.tilt_friction.torque(self.vh[k][1]);
            b.applied[1] += t0 + dt0 * (b.v[1] - self.vh[k][1]);
            out.push(b);
        }
        for (r, &i) in active.iter().enumerate() {
            let s = &self.slices[i];
            for d in 0..2 {
                out[s.body].applied[d] += s.force_row[d] * fa[r];
            }
        }
        let damper = (0..self.slices.len())
            .map(|i| {
                let st = pieces[i];
                if st.mask != 0 && st.damped && !st.clamped {
                    self.slices[i].damping * rates[i]
                } else {
                    0.0
                }
            })
            .collect();
        let film = self.film_forces(&pen, &rates);
        StepResult {
            bodies: out,
            forces,
            penetrations: pen,
            rates,
            damper,
            clamped: pieces.iter().map(|st| st.clamped).collect(),
            film,
            film_end: self.film_at_linearisation(),
            iterations,
        }
    }
}
