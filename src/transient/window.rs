//! One piston slapping one liner over a short crank-angle window, on any structure that can
//! step itself: the ROM (modal coordinates) or the full-order FE model. The two share the
//! piston, the slices, the contact law and the step solver ([`super::contact::step`]), so the
//! difference of their results is the difference of the structural models.
//!
//! The window starts with the structure at rest in its preload state and the piston centred
//! with zero velocity (its acceleration from the loads at the start); the step is fixed. The
//! onset correction of the engine cycle ([`super::contact::onset_impulses`]) needs a structure
//! that takes impulses: the ROM does, the full-order model does not, so ROM-against-full
//! comparisons run both without it.

use super::bore::{
    body_at_rest, film_groups, push_slices, residual_displacement, BoreLines, PistonInBore,
};
use super::contact::{self, dot, Body, Location, Structure};
use super::error::TransientError;
use super::modal::ModalStructure;
use super::scheme::Scheme;
use super::signal::second_difference;
use crate::linalg::dense::{from_row_vecs, row, Dense};
use crate::piston::Piston;
use nalgebra::DMatrix;

/// A structure that integrates itself: the contact's view ([`Structure`]) plus the step.
pub trait Liner: Structure {
    /// Starts a step of `dt`: the predictor without new contact forces.
    fn predict(&mut self, dt: f64);
    /// Completes the step with the contact `forces` (outward radial on the liner, N) at `locs`.
    fn commit(&mut self, locs: &[Location], forces: &[f64]);
    /// Radial accelerations of the analysis points [m/s^2], + toward the coolant.
    fn point_accelerations(&self) -> Vec<f64>;
    /// Quasi-static point displacement of the contact forces not in
    /// [`Liner::point_accelerations`] (a ROM's residual flexibility R_pc F); its acceleration
    /// is added by differencing the series. Empty when the structure has none.
    fn point_residual(&self, _locs: &[Location], _forces: &[f64]) -> Vec<f64> {
        Vec::new()
    }
    /// Takes contact-onset impulses at `locs` over the next step
    /// ([`super::contact::onset_impulses`]); false when the structure cannot (then the window
    /// runs without the onset correction).
    fn impulse(&mut self, _locs: &[Location], _impulses: &[f64]) -> bool {
        false
    }
}

/// The crank-angle window and the piston's bore.
#[derive(Clone, Debug)]
pub struct Window {
    /// The cylinder's own crank angles \[deg\] (firing TDC at 360).
    pub start_deg: f64,
    pub end_deg: f64,
    pub step_deg: f64,
    /// Crank speed [rad/s].
    pub omega: f64,
    pub scheme: Scheme,
    pub liner_top: f64,
    /// Bore-line node heights (ascending); contact DOFs are the thrust nodes then the
    /// anti-thrust nodes, from 0.
    pub thrust_z: Vec<f64>,
    pub antithrust_z: Vec<f64>,
    pub max_newton: usize,
    pub max_penetration: f64,
    /// Restore the damper impulse missed at contact onsets, as the engine cycle does (only
    /// where the structure takes impulses: [`Liner::impulse`]).
    pub onset_correction: bool,
}

/// What the window produced, one entry per step.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct WindowResult {
    pub crank_angle_deg: Vec<f64>,
    /// Analysis-point accelerations (points x steps) [m/s^2].
    #[serde(serialize_with = "crate::linalg::dense::serialize_rows")]
    pub acceleration: Dense,
    pub lateral_m: Vec<f64>,
    pub tilt_rad: Vec<f64>,
    /// Net contact force toward thrust (thrust minus anti-thrust side) \[N\].
    pub contact_force_n: Vec<f64>,
    pub newton_iterations: usize,
    /// Wall time of the stepping \[s\].
    pub seconds: f64,
}

/// The damper impulses the step missed at contact onsets ([`contact::onset_impulses`];
/// marks the onsets in `after`), given to piston and liner as in the engine cycle when the
/// window corrects onsets and the liner takes them; returns the piston after them.
fn onset_kicks(
    window: &Window,
    liner: &mut dyn Liner,
    (slices, locs): (&[contact::Slice<'_>], &[Location]),
    (before, after): (&[contact::SliceState], &mut [contact::SliceState]),
    dt: f64,
    b: Body,
) -> Body {
    let damping: Vec<f64> = slices.iter().map(|s| s.damping).collect();
    let impulses = contact::onset_impulses(before, after, &damping, dt, window.scheme);
    if window.onset_correction
        && impulses.iter().any(|&d| d != 0.0)
        && liner.impulse(locs, &impulses)
    {
        let mut kicked = [b];
        contact::kick_bodies(&mut kicked, slices, &impulses);
        return kicked[0];
    }
    b
}

/// Integrates the window with fixed steps.
pub fn run(
    window: &Window,
    piston: &Piston,
    liner: &mut dyn Liner,
) -> Result<WindowResult, TransientError> {
    let t0 = std::time::Instant::now();
    let steps = ((window.end_deg - window.start_deg) / window.step_deg).round() as usize;
    let dt = window.step_deg.to_radians() / window.omega;
    let ns = piston.skirt.heights.len();
    let mut body = body_at_rest(piston, window.start_deg);
    let mut prev = vec![contact::SliceState::APART; 2 * ns];
    let bore = BoreLines {
        thrust_z: &window.thrust_z,
        antithrust_z: &window.antithrust_z,
        first: 0,
    };
    let npoints = liner.point_accelerations().len();
    let mut out = WindowResult::default();
    let mut acceleration = vec![Vec::with_capacity(steps); npoints];
    let mut residual: Vec<Vec<f64>> = Vec::new();
    for s in 1..=steps {
        let deg = window.start_deg + s as f64 * window.step_deg;
        let time_s = (deg - window.start_deg).to_radians() / window.omega;
        liner.predict(dt);
        let loads = piston.loads(deg);
        body.force = loads.force;
        body.tilt_friction = super::bore::tilt_friction(piston, &loads);
        let mut slices = Vec::with_capacity(2 * ns);
        let mut meta = Vec::with_capacity(2 * ns);
        let pen_of = |side: bool, i: usize| prev[usize::from(!side) * ns + i].prior();
        push_slices(
            &PistonInBore {
                piston,
                loads: &loads,
                liner_top: window.liner_top,
                bore: &bore,
                body: 0,
            },
            &pen_of,
            &mut slices,
            &mut meta,
        );
        let res = contact::step(
            &[body],
            &slices,
            &film_groups(piston, &meta, &|_| loads.axial_velocity),
            liner,
            dt,
            window.scheme,
            window.max_newton,
        )
        .map_err(|f| step_failure(f, deg, time_s, piston))?;
        let b = checked_body(window, &res, &meta, deg, time_s)?;
        let locs: Vec<Location> = slices.iter().map(|s| s.at).collect();
        liner.commit(&locs, &res.forces);
        let point_residual = liner.point_residual(&locs, &res.forces);
        residual.resize(point_residual.len().max(residual.len()), Vec::new());
        for (p, r) in point_residual.into_iter().enumerate() {
            residual[p].push(r);
        }
        // the damper impulse missed at onsets, as in the engine cycle
        let before: Vec<contact::SliceState> = meta
            .iter()
            .map(|&(_, side, i, _)| prev[usize::from(!side) * ns + i])
            .collect();
        let mut after = res.slice_states();
        let b = onset_kicks(
            window,
            liner,
            (&slices, &locs),
            (&before, &mut after),
            dt,
            b,
        );
        body = b;
        prev.fill(contact::SliceState::APART);
        let mut net = 0.0;
        for (k, &(_, side, i, _)) in meta.iter().enumerate() {
            prev[usize::from(!side) * ns + i] = after[k];
            net += if side { res.forces[k] } else { -res.forces[k] };
        }
        out.newton_iterations += res.iterations;
        out.crank_angle_deg.push(deg);
        for (p, a) in liner.point_accelerations().into_iter().enumerate() {
            acceleration[p].push(a);
        }
        out.lateral_m.push(b.q[0]);
        out.tilt_rad.push(b.q[1]);
        out.contact_force_n.push(net);
    }
    for (acc, r) in acceleration.iter_mut().zip(&residual) {
        for (a, d) in acc.iter_mut().zip(second_difference(r, dt, false)) {
            *a += d;
        }
    }
    out.acceleration = from_row_vecs(acceleration);
    out.seconds = t0.elapsed().as_secs_f64();
    Ok(out)
}

/// A failed contact step of the window as the transient's error, with its crank angle and
/// time (a fixed step: never halved) and the piston's oil supply.
fn step_failure(f: contact::StepFailure, deg: f64, time_s: f64, piston: &Piston) -> TransientError {
    match f {
        contact::StepFailure::NoConvergence { iterations } => TransientError::NoConvergence {
            crank_angle_deg: deg,
            time_s,
            iterations,
            halvings: 0,
            film: piston.film_summary(),
        },
        contact::StepFailure::Singular => TransientError::Singular {
            crank_angle_deg: deg,
            time_s,
        },
    }
}

/// The window's piston after a step, checked: no slice deeper than the window's limit (named
/// with its side, slice and height), a finite state.
fn checked_body(
    window: &Window,
    res: &contact::StepResult,
    meta: &[(usize, bool, usize, f64)],
    deg: f64,
    time_s: f64,
) -> Result<Body, TransientError> {
    if let Some((k, &p)) = res
        .penetrations
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
    {
        if p > window.max_penetration {
            let (_, side, i, z) = meta[k];
            return Err(TransientError::DeepPenetration {
                cylinder: 0,
                side: if side { "thrust" } else { "anti-thrust" },
                slice: i + 1,
                height_mm: z * 1e3,
                penetration_um: p * 1e6,
                limit_um: window.max_penetration * 1e6,
                crank_angle_deg: deg,
                time_s,
            });
        }
    }
    let b = res.bodies[0];
    if !b.q.iter().chain(&b.v).chain(&b.a).all(|x| x.is_finite()) {
        return Err(TransientError::NonFinite {
            crank_angle_deg: deg,
            time_s,
            place: "the piston of the window's cylinder".into(),
        });
    }
    Ok(b)
}

/// The ROM as a [`Liner`]: a [`ModalStructure`], the mode rows of the analysis points and
/// their residual flexibility to the contact DOFs.
pub struct ModalLiner {
    pub structure: ModalStructure,
    /// Analysis points x modes.
    pub points: Dense,
    /// Analysis points x contact DOFs (None: modal outputs only).
    pub point_residual: Option<Dense>,
}

impl Structure for ModalLiner {
    fn prepare(&mut self, locs: &[Location]) {
        self.structure.prepare(locs)
    }
    fn predicted(&self, i: usize) -> (f64, f64) {
        self.structure.predicted(i)
    }
    fn predicted_bound(&self, i: usize) -> Option<(f64, f64)> {
        self.structure.predicted_bound(i)
    }
    fn compliance(&mut self, active: &[usize]) -> (DMatrix<f64>, DMatrix<f64>) {
        self.structure.compliance(active)
    }
    fn response(&self, active: &[usize], forces: &[f64]) -> Vec<f64> {
        self.structure.response(active, forces)
    }
    fn velocity_response(&self, active: &[usize], forces: &[f64]) -> Vec<f64> {
        self.structure.velocity_response(active, forces)
    }
}

impl Liner for ModalLiner {
    fn predict(&mut self, dt: f64) {
        self.structure.integrator.predict(dt)
    }
    fn commit(&mut self, locs: &[Location], forces: &[f64]) {
        let f = self.structure.modal_force_at(locs, forces);
        self.structure.integrator.commit(&f)
    }
    fn point_accelerations(&self) -> Vec<f64> {
        let a = &self.structure.integrator.ddeta;
        let n = a.len().min(self.points.ncols());
        (0..self.points.nrows())
            .map(|p| dot(&row(&self.points, p)[..n], &a[..n]))
            .collect()
    }
    fn impulse(&mut self, locs: &[Location], impulses: &[f64]) -> bool {
        self.structure.impulse(locs, impulses);
        true
    }
    fn point_residual(&self, locs: &[Location], forces: &[f64]) -> Vec<f64> {
        match &self.point_residual {
            Some(r) => residual_displacement(r, locs, forces),
            None => Vec::new(),
        }
    }
}

/// Rayleigh damping C = a M + b K with damping ratio `zeta` at the angular frequencies `w1`
/// and `w2`: zeta(w) = a / (2 w) + b w / 2, so a = 2 zeta w1 w2 / (w1 + w2), b = 2 zeta / (w1 + w2).
pub fn rayleigh(zeta: f64, w1: f64, w2: f64) -> (f64, f64) {
    (2.0 * zeta * w1 * w2 / (w1 + w2), 2.0 * zeta / (w1 + w2))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rayleigh_hits_both_frequencies() {
        let (a, b) = rayleigh(0.02, 1000.0, 20000.0);
        for w in [1000.0, 20000.0] {
            assert!((a / (2.0 * w) + b * w / 2.0 - 0.02).abs() < 1e-12);
        }
    }
}
