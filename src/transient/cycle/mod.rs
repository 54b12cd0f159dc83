//! The engine cycle: six pistons slapping their liners on one shared crankcase, integrated in
//! the engine ROM's modal coordinates.
//!
//! Cylinder k of the firing order (k = 0 .. N-1) fires 720 k / N deg after cylinder
//! `firing_order[0]`; its own crank angle is theta_c = theta - 720 k / N (firing TDC at 360).
//! Each base step (the scene's crank-angle step) is one implicit step of all pistons and the
//! structure ([`super::contact::step`]); with `adaptive`, a step whose contact iteration fails
//! or whose penetration exceeds the limit is halved (up to `max_halvings` times) and counted as
//! rejected. Several cycles are run from rest (pistons centred, structure at the preload state).
//! Slap on a ringing liner is not periodic: which slice bounced how often decides the state the
//! next slap starts from, so consecutive cycles differ (the default engine's by 20-40 %) and
//! one cycle's peak is one draw. Each reported peak is therefore the mean over the last
//! `averaged_cycles` cycles of the per-cycle peak P_k, with the sample standard deviation
//! s = sqrt(sum (P_k - mean)^2 / (n - 1)) and the largest P_k; the series are the last cycle's
//! (with the averaged cycles' point accelerations, for averaged spectra).
//! The change between the last two cycles is reported as well.
//!
//! Energy balance of the structure (mass-normalised modes): E = 1/2 sum (eta'^2 + omega^2 eta^2);
//! per step dE = 1/2 (f_n + f_{n+1}) . (eta_{n+1} - eta_n) - dt sum c_j vbar_j^2, exactly for the
//! average-acceleration rule; the accumulated difference is reported, and growth beyond the
//! scheme's tolerance ([`Scheme::energy_tolerance`]: roundoff for average acceleration, a bounded
//! fraction of the scale for HHT-alpha, which balances a different energy) stops the run (a
//! numerical instability).

use super::bore::{
    body_at_rest, film_groups, push_slices, residual_displacement, BoreLines, PistonInBore,
};
use super::contact::{self, Body, Location, Slice, SliceState, StepFailure};
use super::error::TransientError;
use super::modal::ModalStructure;
use super::scheme::{ModalIntegrator, Scheme};
use super::signal::{fir_half_length, low_pass, sampled_peak, second_difference4};
use super::spectrum::{centred_spectrum, PowerSum, Spectrum};
use crate::linalg::dense::{from_row_vecs, row, values_mut, Dense};
use crate::piston::Piston;
use crate::reduce::rom::{CylinderRom, EngineRom};
use ndarray::Array2;
use rayon::prelude::*;

mod events;
mod record;
mod result;
mod settings;
pub mod statistics;
mod surface;
mod tolerance;

use events::{EventRecorder, SideSample};
pub use events::{EventSummary, Mean, SlapEvent, EVENT_CLUSTER_DEG, EVENT_SEPARATION_DEG};
pub use record::OUTPUT_DIFFERENCE_REACH;
use record::*;
pub use result::*;
pub use settings::*;
use statistics::*;
pub use surface::SurfacePeaks;
use surface::SurfaceRecord;
pub use tolerance::run_with_tolerance;

/// A step's slice as the records see it: cylinder index, thrust side, skirt slice, height.
type SliceMeta = (usize, bool, usize, f64);

/// A piston slice's fixed data: which side, and its bore line.
#[derive(Clone)]
struct Cyl<'a> {
    rom: &'a CylinderRom,
    /// Firing phase [deg].
    phase: f64,
    body: Body,
}

/// The running engine transient.
#[derive(Clone)]
pub struct EngineRun<'a> {
    setup: &'a EngineSetup<'a>,
    settings: CycleSettings,
    pub structure: ModalStructure,
    cyls: Vec<Cyl<'a>>,
    /// Point mode rows (stacked per cylinder) for outputs.
    pub time: f64,
    energy_work: f64,
    energy_damped: f64,
    /// Modal energy after the last committed step.
    energy_now: f64,
    energy_scale: f64,
    pub stats: Stats,
    /// Summed contact forces of the last step per cylinder (thrust, anti-thrust).
    pub last_forces: Vec<(f64, f64)>,
    /// State of every slice at the last step, (cylinder, side, slice) order.
    prev_state: Vec<SliceState>,
    /// Loaded locations of the last step (cylinder index, location, force).
    prev_loaded: Vec<(usize, Location, f64)>,
    /// Base steps still to be sub-stepped after the last contact onset, and the base step
    /// being advanced [s].
    substeps_left: usize,
    base_step: f64,
    /// The slap events of every committed step ([`events`]).
    events: EventRecorder,
    /// Per cylinder (thrust, anti-thrust): the weighted contact force C of the last committed
    /// step ([`EngineRun::contact_impulses`]) and the contact impulse since the last sample.
    applied_contact: Vec<(f64, f64)>,
    impulse_acc: Vec<(f64, f64)>,
}

/// One step's loads and skirt slices ([`EngineRun::step_loads`]).
struct StepLoads<'a> {
    /// The pistons with this step's gas and inertia forces.
    bodies: Vec<Body>,
    slices: Vec<Slice<'a>>,
    meta: Vec<SliceMeta>,
    /// Quasi-static side force [N] and axial velocity [m/s] per cylinder.
    side_forces: Vec<f64>,
    axial: Vec<f64>,
}

/// What [`EngineRun::run`] gathers over the averaged cycles: their peaks and cycle numbers,
/// the summed power spectra per cylinder and point, the last cycle's peaks (for the
/// cycle-to-cycle change) and its series.
struct Averaged {
    prev_peaks: Option<CyclePeaks>,
    kept: Vec<CyclePeaks>,
    kept_cycles: Vec<usize>,
    power: Vec<Vec<PowerSum>>,
    last_series: Option<Series>,
}

/// Modes kept and the contact-DOF rows/flexibility/preload of the ROM.
fn contact_data(rom: &EngineRom, nm: usize) -> (Dense, Vec<f64>) {
    let ndof = rom.residual_flexibility.nrows();
    let mut rows = Dense::zeros((ndof, nm));
    let mut pre = vec![0.0; ndof];
    for c in &rom.cylinders {
        let nt = c.thrust_z.len();
        for (k, (m, p)) in [
            (&c.thrust_modes, &c.preload_thrust),
            (&c.antithrust_modes, &c.preload_antithrust),
        ]
        .into_iter()
        .enumerate()
        {
            for i in 0..m.nrows() {
                let r = c.contact_offset + k * nt + i;
                values_mut(&mut rows)[r * nm..(r + 1) * nm].copy_from_slice(&row(m, i)[..nm]);
                pre[r] = p[i];
            }
        }
    }
    (rows, pre)
}

/// Residual flexibility when only the first `nm` system modes are integrated: the ROM's R
/// plus the static part of the ROM modes left out, sum_{j >= nm} phi_j phi_j^T / omega_j^2.
fn truncated_flexibility(rom: &EngineRom, nm: usize) -> Dense {
    let mut r = rom.residual_flexibility.clone();
    let n = r.nrows();
    let all = rom.frequencies_hz.len();
    if nm == all {
        return r;
    }
    let (rows, _) = contact_data(rom, all);
    for j in nm..all {
        let w2 = (2.0 * std::f64::consts::PI * rom.frequencies_hz[j]).powi(2);
        for a in 0..n {
            let pa = rows[[a, j]] / w2;
            if pa == 0.0 {
                continue;
            }
            for b in 0..n {
                r[[a, b]] += pa * rows[[b, j]];
            }
        }
    }
    r
}

impl<'a> EngineRun<'a> {
    /// A run at rest at global crank angle 0.
    pub fn new(setup: &'a EngineSetup<'a>, settings: CycleSettings) -> Self {
        let rom = setup.rom;
        let nm = match settings.modes_below_hz {
            Some(f) => rom.frequencies_hz.iter().take_while(|&&x| x <= f).count(),
            None => rom.frequencies_hz.len(),
        };
        let omega: Vec<f64> = rom.frequencies_hz[..nm]
            .iter()
            .map(|f| 2.0 * std::f64::consts::PI * f)
            .collect();
        let zeta = vec![settings.damping_ratio; nm];
        let mut integrator = ModalIntegrator::new(&omega, &zeta, settings.scheme);
        integrator.dynamic_modes = rom.info.system_modes.min(nm);
        let (rows, pre) = contact_data(rom, nm);
        let rflex = truncated_flexibility(rom, nm);
        let mut structure = ModalStructure::new(integrator, rows, rflex, pre);
        structure.static_correction = settings.static_correction;
        structure.bound_predictions = settings.bound_predictions;
        if settings.coupling == Coupling::PerCylinder {
            // each cylinder's contact step sees its own liner's DOFs only
            structure.blocks = Some(
                rom.cylinders
                    .iter()
                    .map(|c| {
                        c.contact_offset..c.contact_offset + c.thrust_z.len() + c.antithrust_z.len()
                    })
                    .collect(),
            );
        }
        let n = setup.firing_order.len();
        let cyls = rom
            .cylinders
            .iter()
            .map(|c| {
                let k = setup
                    .firing_order
                    .iter()
                    .position(|&f| f == c.cylinder)
                    .unwrap_or(0);
                let phase = 720.0 * k as f64 / n as f64;
                Cyl {
                    rom: c,
                    phase,
                    body: body_at_rest(setup.piston, -phase),
                }
            })
            .collect();
        let nslices = setup.piston.skirt.heights.len();
        let ncyl = rom.cylinders.len();
        let stats = Stats {
            modes: nm,
            min_slice_force_n: f64::INFINITY,
            ..Stats::default()
        };
        Self {
            setup,
            settings,
            structure,
            cyls,
            time: 0.0,
            energy_work: 0.0,
            energy_damped: 0.0,
            energy_now: 0.0,
            energy_scale: 0.0,
            stats,
            last_forces: Vec::new(),
            prev_state: vec![SliceState::APART; 2 * nslices * ncyl],
            prev_loaded: Vec::new(),
            substeps_left: 0,
            base_step: 0.0,
            events: EventRecorder::new(ncyl),
            applied_contact: vec![(0.0, 0.0); ncyl],
            impulse_acc: vec![(0.0, 0.0); ncyl],
        }
    }

    /// Global crank angle \[deg\] at time `t`.
    pub fn angle_at(&self, t: f64) -> f64 {
        t * self.setup.omega.to_degrees()
    }

    /// Base step \[s\].
    pub fn base_dt(&self) -> f64 {
        self.settings.step_deg.to_radians() / self.setup.omega
    }

    /// Advances one base step of `dt`, resolving slaps by sub-steps and halving failing
    /// steps when adaptive.
    ///
    /// With m = `slap_substeps` > 1, a step is first tried whole; if a cylinder side comes into
    /// contact within it (a slap begins), nothing is committed and the step is re-taken as m
    /// sub-steps of dt / m, as are the next ceil(`slap_span_deg` / `step_deg`) base steps (the
    /// span is renewed by every onset inside it). The average-acceleration rule's error in an
    /// impact grows with (omega_c dt)^2, omega_c the contact's frequency (a few steps per
    /// contact period at the default step): the sub-steps divide it by m^2 where it is made,
    /// at the cost of the few percent of the cycle that slaps occupy. A failing whole step is
    /// re-taken as sub-steps too when `adaptive` (counted as rejected), and stops the run
    /// otherwise.
    pub fn advance(&mut self, dt: f64) -> Result<(), TransientError> {
        let m = self.settings.slap_substeps.max(1);
        if m == 1 {
            return self.advance_depth(dt, 0);
        }
        self.base_step = dt;
        if self.substeps_left == 0 {
            match self.try_step(dt, true) {
                Ok(true) => return Ok(()),
                Ok(false) => {}
                Err(fail) if !self.settings.adaptive => return Err(fail.into_error(self, dt, 0)),
                Err(_) => self.stats.rejected_steps += 1,
            }
        }
        self.stats.substepped_steps += 1;
        let t0 = self.time;
        for k in 1..=m {
            let target = t0 + dt * k as f64 / m as f64;
            self.advance_depth(target - self.time, 0)?;
        }
        self.substeps_left = self.substeps_left.saturating_sub(1);
        Ok(())
    }

    /// Steps of `dt` sub-stepped after a contact onset: the onset's own step and those
    /// covering `slap_span_deg` after it (the same crank-angle span at every step size, the
    /// step-error windows' half step included).
    fn substep_span(&self, dt: f64) -> usize {
        let step_deg = self.angle_at(dt);
        1 + (self.settings.slap_span_deg / step_deg - 1e-9).ceil() as usize
    }

    fn advance_depth(&mut self, dt: f64, depth: usize) -> Result<(), TransientError> {
        match self.try_step(dt, false) {
            Ok(_) => Ok(()),
            Err(fail) => {
                if !self.settings.adaptive || depth >= self.settings.max_halvings {
                    return Err(fail.into_error(self, dt, depth));
                }
                self.stats.rejected_steps += 1;
                self.advance_depth(dt / 2.0, depth + 1)?;
                self.advance_depth(dt / 2.0, depth + 1)
            }
        }
    }

    /// One implicit step of `dt`. `stop_at_onset`: when a cylinder side comes into contact in
    /// the step, return `Ok(false)` before committing anything (the step is to be sub-stepped).
    fn try_step(&mut self, dt: f64, stop_at_onset: bool) -> Result<bool, Failure> {
        let t1 = self.time + dt;
        let theta = self.angle_at(t1);
        self.structure.integrator.predict(dt);
        let piston = self.setup.piston;
        let ns = piston.skirt.heights.len();
        let pen_index = |b: usize, side: bool, i: usize| (2 * b + usize::from(!side)) * ns + i;
        let StepLoads {
            bodies,
            slices,
            meta,
            side_forces,
            axial,
        } = self.step_loads(theta);
        let s = self.settings.scheme;
        let res = match self.settings.coupling {
            Coupling::Monolithic => contact::step(
                &bodies,
                &slices,
                &film_groups(piston, &meta, &|b| axial[b]),
                &mut self.structure,
                dt,
                s,
                self.settings.max_newton,
            )
            .map_err(Failure::Step)?,
            Coupling::PerCylinder => {
                self.contact_per_cylinder(&bodies, &slices, (&meta, &axial), dt)?
            }
        };
        self.check_step(&res, &meta)?;
        if self.settings.slap_substeps > 1 && self.side_onset(&meta, &res) {
            if stop_at_onset {
                return Ok(false);
            }
            self.substeps_left = self.substep_span(self.base_step);
        }
        // commit
        let fmin = res.forces.iter().copied().fold(f64::INFINITY, f64::min);
        self.stats.min_slice_force_n = self.stats.min_slice_force_n.min(fmin);
        let locs: Vec<Location> = slices.iter().map(|s| s.at).collect();
        let f = self.structure.modal_force_at(&locs, &res.forces);
        let step = self.structure.integrator.commit_with_energy(&f);
        self.energy_work += step.work;
        self.energy_damped += dt * step.damping_power;
        self.energy_now = step.energy;
        // a non-finite modal coordinate makes the energy non-finite
        if !step.energy.is_finite() {
            return Err(Failure::NonFinite(
                "the structure's modal coordinates (the ROM)".into(),
            ));
        }
        // the damper impulse the step missed at contact onsets, on pistons and structure
        let before: Vec<SliceState> = meta
            .iter()
            .map(|&(b, side, i, _)| self.prev_state[pen_index(b, side, i)])
            .collect();
        let mut after = res.slice_states();
        let damping: Vec<f64> = slices.iter().map(|s| s.damping).collect();
        let impulses = contact::onset_impulses(&before, &mut after, &damping, dt, s);
        let mut bodies_after = res.bodies.clone();
        if self.settings.onset_correction && impulses.iter().any(|&d| d != 0.0) {
            contact::kick_bodies(&mut bodies_after, &slices, &impulses);
            self.structure.impulse(&locs, &impulses);
        }
        for (cyl, b) in self.cyls.iter_mut().zip(&bodies_after) {
            cyl.body = *b;
        }
        let step_impulses = self.contact_impulses(dt, &res, &meta, &impulses);
        self.record_step(&res, &slices, &meta, &after);
        let view = StepView {
            res: &res,
            meta: &meta,
            slices: &slices,
            states: &before,
            before: &bodies,
            side_forces: &side_forces,
            impulses: &step_impulses,
        };
        self.observe_events(theta, dt, &view);
        self.time = t1;
        self.stats.steps += 1;
        self.stats.newton_iterations += res.iterations;
        self.stats.max_newton_per_step = self.stats.max_newton_per_step.max(res.iterations);
        Ok(true)
    }

    /// The pistons' loads at crank angle `theta` \[deg\] (each cylinder at its own phase) and
    /// the skirt slices they put on the bore lines ([`push_slices`]), with the slices' last
    /// penetrations (the damper's onset rule).
    fn step_loads(&self, theta: f64) -> StepLoads<'a> {
        let piston = self.setup.piston;
        let ns = piston.skirt.heights.len();
        let nc = self.cyls.len();
        let mut out = StepLoads {
            bodies: Vec::with_capacity(nc),
            slices: Vec::with_capacity(nc * 2 * ns),
            meta: Vec::new(),
            side_forces: Vec::with_capacity(nc),
            axial: Vec::with_capacity(nc),
        };
        for (b, cyl) in self.cyls.iter().enumerate() {
            let loads = piston.loads(theta - cyl.phase);
            let mut body = cyl.body;
            body.force = loads.force;
            out.bodies.push(body);
            out.side_forces.push(loads.side_force);
            out.axial.push(loads.axial_velocity);
            let bore = BoreLines {
                thrust_z: &cyl.rom.thrust_z,
                antithrust_z: &cyl.rom.antithrust_z,
                first: cyl.rom.contact_offset,
            };
            let prev = |side: bool, i: usize| {
                self.prev_state[(2 * b + usize::from(!side)) * ns + i].penetration
            };
            push_slices(
                &PistonInBore {
                    piston,
                    loads: &loads,
                    liner_top: self.setup.liner_top,
                    bore: &bore,
                    body: b,
                },
                &prev,
                &mut out.slices,
                &mut out.meta,
            );
        }
        out
    }

    /// The step's checks: no slice deeper than `max_penetration` (named with its cylinder,
    /// side, slice and height), finite piston states; records the deepest penetration.
    fn check_step(
        &mut self,
        res: &contact::StepResult,
        meta: &[(usize, bool, usize, f64)],
    ) -> Result<(), Failure> {
        // penetration limit
        if let Some((k, &p)) = res
            .penetrations
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
        {
            if p > self.settings.max_penetration {
                let (b, side, i, z) = meta[k];
                return Err(Failure::Deep {
                    cylinder: self.cyls[b].rom.cylinder,
                    side,
                    slice: i + 1,
                    height: z,
                    penetration: p,
                });
            }
            self.stats.max_penetration_m = self.stats.max_penetration_m.max(p);
        }
        if res
            .bodies
            .iter()
            .any(|b| !(b.q.iter().chain(&b.v).chain(&b.a).all(|x| x.is_finite())))
        {
            let b = res
                .bodies
                .iter()
                .position(|b| !b.q.iter().chain(&b.a).all(|x| x.is_finite()))
                .unwrap_or(0);
            return Err(Failure::NonFinite(format!(
                "the piston of cylinder {}",
                self.cyls[b].rom.cylinder
            )));
        }
        Ok(())
    }

    /// Keeps what the next step needs of this one: per cylinder the summed thrust and
    /// anti-thrust forces, the loaded locations with their forces (the lagged coupling), the
    /// slices' states; and the coupling-lag diagnostic.
    fn record_step(
        &mut self,
        res: &contact::StepResult,
        slices: &[Slice<'_>],
        meta: &[(usize, bool, usize, f64)],
        after: &[SliceState],
    ) {
        let ns = self.setup.piston.skirt.heights.len();
        let mut per = vec![(0.0, 0.0); self.cyls.len()];
        for (k, &(b, side, _, _)) in meta.iter().enumerate() {
            if side {
                per[b].0 += res.forces[k];
            } else {
                per[b].1 += res.forces[k];
            }
        }
        self.last_forces = per;
        let loaded: Vec<(usize, Location, f64)> = meta
            .iter()
            .zip(slices)
            .zip(&res.forces)
            .filter(|(_, &f)| f != 0.0)
            .map(|(((b, _, _, _), sl), &f)| (*b, sl.at, f))
            .collect();
        if self.settings.coupling == Coupling::PerCylinder && self.stats.steps % 16 == 0 {
            // displacement the slice used vs the completed step's, at the loaded slices
            // (sampled every 16th step, ~45 samples per slap: a diagnostic, not part of the
            // solution)
            let mut lag: f64 = 0.0;
            for (k, sl) in slices.iter().enumerate() {
                if res.forces[k] == 0.0 {
                    continue;
                }
                let u_now = self.structure.displacement(&sl.at)
                    + loaded
                        .iter()
                        .map(|(_, at, f)| self.structure.rflex_at(&sl.at, at) * f)
                        .sum::<f64>();
                let qb = res.bodies[sl.body].q;
                let u_used = sl.row[0] * qb[0] + sl.row[1] * qb[1] - sl.gap - res.penetrations[k];
                lag = lag.max((u_now - u_used).abs());
            }
            self.stats.coupling_lag_m = self.stats.coupling_lag_m.max(lag);
        }
        self.prev_loaded = loaded;
        self.prev_state.fill(SliceState::APART);
        for (k, &(b, side, i, _)) in meta.iter().enumerate() {
            self.prev_state[(2 * b + usize::from(!side)) * ns + i] = after[k];
        }
    }

    /// Each cylinder's contact impulse per side over the committed step of `dt`, as the
    /// integrator delivers it to the pistons, M (v_{n+1} - v_n) = dt ((1 - gamma) M a_n +
    /// gamma M a_{n+1}): dt ((1 - gamma) C_n + gamma C_{n+1}) with
    /// C_{n+1} = (1 + alpha) F_{n+1} - alpha F_n the side's summed slice force as HHT-alpha
    /// weights it (alpha = 0, gamma = 1/2: the trapezoid), plus the onset corrections'
    /// impulses when they are applied. Summed over
    /// steps it is the momentum the contact gave the piston; also added to the impulses since
    /// the last sample. Call before [`EngineRun::record_step`] (F_n is the last step's).
    fn contact_impulses(
        &mut self,
        dt: f64,
        res: &contact::StepResult,
        meta: &[(usize, bool, usize, f64)],
        kicks: &[f64],
    ) -> Vec<(f64, f64)> {
        let (alpha, gamma) = (self.settings.scheme.alpha, self.settings.scheme.gamma);
        let n = self.cyls.len();
        let (mut now, mut kick) = (vec![(0.0, 0.0); n], vec![(0.0, 0.0); n]);
        let corrected = self.settings.onset_correction;
        for (k, &(b, side, _, _)) in meta.iter().enumerate() {
            let (f, j) = if side {
                (&mut now[b].0, &mut kick[b].0)
            } else {
                (&mut now[b].1, &mut kick[b].1)
            };
            *f += res.forces[k];
            if corrected {
                *j += kicks[k];
            }
        }
        (0..n)
            .map(|b| {
                let old = self.last_forces.get(b).copied().unwrap_or((0.0, 0.0));
                let c = (
                    (1.0 + alpha) * now[b].0 - alpha * old.0,
                    (1.0 + alpha) * now[b].1 - alpha * old.1,
                );
                let prev = self.applied_contact[b];
                let imp = (
                    dt * ((1.0 - gamma) * prev.0 + gamma * c.0) + kick[b].0,
                    dt * ((1.0 - gamma) * prev.1 + gamma * c.1) + kick[b].1,
                );
                self.applied_contact[b] = c;
                self.impulse_acc[b].0 += imp.0;
                self.impulse_acc[b].1 += imp.1;
                imp
            })
            .collect()
    }

    /// Hands the committed step to the slap-event recorder: per cylinder the sides' summed
    /// forces (from [`EngineRun::record_step`]), the side force, and for each side in contact
    /// the piston's approach at the onset of its deepest slice: the step's fraction before
    /// contact tau = -p_0 / (p_1 - p_0) (penetrations at the step's ends), the piston's
    /// velocity then v = v_0 + tau dt a_0 (its motion before contact), the slice's velocity
    /// toward the wall row . v and the secondary kinetic energy 1/2 v^T M_b v.
    fn observe_events(&mut self, theta: f64, dt: f64, view: &StepView<'_, '_>) {
        let nc = self.cyls.len();
        // deepest slice of each (cylinder, side)
        let mut deepest: Vec<[Option<usize>; 2]> = vec![[None; 2]; nc];
        for (k, &(b, side, _, _)) in view.meta.iter().enumerate() {
            let slot = &mut deepest[b][usize::from(!side)];
            if slot.is_none_or(|j| view.res.penetrations[k] > view.res.penetrations[j]) {
                *slot = Some(k);
            }
        }
        for (b, cyl) in self.cyls.iter().enumerate() {
            let m = view.before[b].mass;
            let onset = |k: Option<usize>| -> (f64, f64) {
                let Some(k) = k else { return (0.0, 0.0) };
                let (p0, p1) = (view.states[k].penetration, view.res.penetrations[k]);
                let tau = if p0 < 0.0 && p1 > p0 {
                    (-p0 / (p1 - p0)).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let v: [f64; 2] =
                    std::array::from_fn(|i| view.before[b].v[i] + tau * dt * view.before[b].a[i]);
                let row = view.slices[k].row;
                let energy = 0.5
                    * (0..2)
                        .map(|i| v[i] * (0..2).map(|j| m[i][j] * v[j]).sum::<f64>())
                        .sum::<f64>();
                (row[0] * v[0] + row[1] * v[1], energy)
            };
            let (thrust, anti) = (onset(deepest[b][0]), onset(deepest[b][1]));
            let sample = SideSample {
                global_deg: theta,
                own_deg: (theta - cyl.phase).rem_euclid(720.0),
                forces: self.last_forces[b],
                side_force: view.side_forces[b],
                rates: (thrust.0, anti.0),
                kinetic_energy: (thrust.1, anti.1),
                impulses: view.impulses[b],
            };
            self.events.observe(b, &sample);
        }
    }

    /// The contact step of each cylinder on its own liner's DOFs: cylinder b's slices see the
    /// other cylinders' residual-flexibility displacement at their DOFs, lagged one step,
    /// u_d = sum_{loaded e, other cylinder} R_de F_e (the last step's forces gathered on the
    /// DOFs, F_e = sum_k w_ke F_k), as an offset of their gaps.
    fn contact_per_cylinder(
        &mut self,
        bodies: &[Body],
        slices: &[Slice<'_>],
        (meta, axial): (&[SliceMeta], &[f64]),
        dt: f64,
    ) -> Result<contact::StepResult, Failure> {
        let mut out = contact::StepResult {
            film: vec![0.0; slices.len()],
            bodies: bodies.to_vec(),
            forces: vec![0.0; slices.len()],
            penetrations: vec![0.0; slices.len()],
            rates: vec![0.0; slices.len()],
            damper: vec![0.0; slices.len()],
            clamped: vec![false; slices.len()],
            iterations: 0,
        };
        // other cylinders' residual-flexibility displacement at a contact DOF, lagged:
        // u_d = sum_{loaded e, other cylinder} R_de F_e with the last step's forces
        // gathered on the DOFs, F_e = sum_k w_ke F_k (each DOF belongs to one cylinder's
        // liner). R is symmetric, so u over a cylinder's slice DOFs is a sum of
        // contiguous pieces of the loaded DOFs' rows: u[lo..hi] += F_e R_e[lo..hi].
        let ndof = self.structure.contact_dofs();
        let mut f_dof = vec![0.0; ndof];
        let mut owner = vec![usize::MAX; ndof];
        let mut touched = Vec::new();
        for (c, at, f) in &self.prev_loaded {
            for k in 0..2 {
                let e = at.dofs[k];
                if owner[e] == usize::MAX {
                    owner[e] = *c;
                    touched.push(e);
                }
                f_dof[e] += at.weights[k] * f;
            }
        }
        let mut u_dof = vec![0.0; ndof];
        for b in 0..bodies.len() {
            let idx: Vec<usize> = (0..slices.len()).filter(|&k| slices[k].body == b).collect();
            // the slices' DOF span on each side (slices run along a bore line)
            let mut spans: Vec<(usize, usize)> = Vec::new();
            for side in [true, false] {
                let (lo, hi) = idx.iter().filter(|&&k| meta[k].1 == side).fold(
                    (usize::MAX, 0),
                    |(lo, hi), &k| {
                        (
                            lo.min(slices[k].at.dofs[0]),
                            hi.max(slices[k].at.dofs[1] + 1),
                        )
                    },
                );
                if lo < hi {
                    spans.push((lo, hi));
                }
            }
            for &e in touched.iter().filter(|&&e| owner[e] != b) {
                for &(lo, hi) in &spans {
                    self.structure
                        .rflex_axpy(&mut u_dof[lo..hi], f_dof[e], e, lo..hi);
                }
            }
            let sub: Vec<Slice<'_>> = idx
                .iter()
                .map(|&k| {
                    let mut sl = slices[k].clone();
                    sl.body = 0;
                    let [d0, d1] = sl.at.dofs;
                    sl.gap += sl.at.weights[0] * u_dof[d0] + sl.at.weights[1] * u_dof[d1];
                    sl
                })
                .collect();
            let sub_meta: Vec<_> = idx.iter().map(|&k| meta[k]).collect();
            let films = film_groups(self.setup.piston, &sub_meta, &|_| axial[b]);
            let r = contact::step(
                &bodies[b..b + 1],
                &sub,
                &films,
                &mut self.structure,
                dt,
                self.settings.scheme,
                self.settings.max_newton,
            )
            .map_err(Failure::Step)?;
            out.bodies[b] = r.bodies[0];
            for (j, &k) in idx.iter().enumerate() {
                out.forces[k] = r.forces[j];
                out.penetrations[k] = r.penetrations[j];
                out.rates[k] = r.rates[j];
                out.damper[k] = r.damper[j];
                out.clamped[k] = r.clamped[j];
                out.film[k] = r.film[j];
            }
            out.iterations = out.iterations.max(r.iterations);
        }
        Ok(out)
    }

    /// Whether a cylinder side touches the liner after the step (the step's slices per
    /// `meta`: cylinder index, thrust side, slice) with none of its slices touching before; a
    /// slice touches when it penetrates or its oil film is engaged.
    fn side_onset(&self, meta: &[(usize, bool, usize, f64)], res: &contact::StepResult) -> bool {
        let ns = self.setup.piston.skirt.heights.len();
        let mut before = vec![false; 2 * self.cyls.len()];
        let mut after = vec![false; 2 * self.cyls.len()];
        for (k_slice, &(b, side, i, _)) in meta.iter().enumerate() {
            let k = 2 * b + usize::from(!side);
            before[k] |= self.prev_state[k * ns + i].engaged();
            after[k] |= res.penetrations[k_slice] > 0.0 || res.film[k_slice] > 0.0;
        }
        before.iter().zip(&after).any(|(&b, &a)| a && !b)
    }

    /// Energy balance: (E - W + D) and the scale max(E, |W|, D).
    pub fn energy_balance(&mut self) -> (f64, f64) {
        let e = self.energy_now;
        self.energy_scale = self
            .energy_scale
            .max(e)
            .max(self.energy_work.abs())
            .max(self.energy_damped);
        (e - self.energy_work + self.energy_damped, self.energy_scale)
    }

    /// Piston states (lateral, tilt) per modelled cylinder.
    pub fn pistons(&self) -> Vec<[f64; 2]> {
        self.cyls.iter().map(|c| c.body.q).collect()
    }

    /// Displacements of cylinder index `c`'s analysis points (points), + toward the coolant:
    /// on the liner u_p = sum_j phi_pj eta_j + R_pc F (the integrated modes and the residual
    /// response to the last contact forces); at the crankcase's facing points the modal sum.
    pub fn point_displacements(&self, c: usize, crankcase: bool) -> Vec<f64> {
        let rom = self.cyls[c].rom;
        let m = if crankcase {
            &rom.crankcase_point_modes
        } else {
            &rom.point_modes
        };
        let eta = &self.structure.integrator.eta;
        let nb = eta.len();
        let modal = (0..m.nrows()).map(|p| contact::dot(&row(m, p)[..nb], &eta[..nb]));
        if crankcase {
            return modal.collect();
        }
        modal
            .zip(self.point_residual(c))
            .map(|(u, r)| u + r)
            .collect()
    }

    /// Residual (quasi-static) displacement of cylinder index `c`'s analysis points under its
    /// contact forces of the last step, R_pc F.
    fn point_residual(&self, c: usize) -> Vec<f64> {
        let rom = self.cyls[c].rom;
        let off = rom.contact_offset;
        let (locs, forces): (Vec<Location>, Vec<f64>) = self
            .prev_loaded
            .iter()
            .filter(|(b, _, _)| *b == c)
            .map(|(_, at, f)| {
                (
                    Location {
                        dofs: [at.dofs[0] - off, at.dofs[1] - off],
                        weights: at.weights,
                    },
                    *f,
                )
            })
            .unzip();
        residual_displacement(&rom.point_residual, &locs, &forces)
    }

    /// Runs `settings.cycles` cycles and returns the peaks averaged over the last
    /// `settings.averaged_cycles` ([`Peak::over_cycles`]) and the series of the last one.
    ///
    /// The point accelerations are filtered over the continuous record, never a cycle wrapped
    /// onto itself (cycles differ): cycle k's output is formed once the run has gone `margin`
    /// samples (the FIR's half length plus one) past its end, from the record
    /// [k N - margin, (k + 1) N + margin), N steps per cycle. Before t = 0 the engine is at
    /// rest (zero acceleration, no contact force), and the run goes on `margin` steps past its
    /// last cycle. Only that rolling segment of the record is kept.
    pub fn run(
        mut self,
        mut on_step: impl FnMut(usize, usize),
    ) -> Result<CycleResult, TransientError> {
        let spc = (720.0 / self.settings.step_deg).round() as usize;
        let dt = self.base_dt();
        self.stats.dt_s = dt;
        let cycles = self.settings.cycles.max(1);
        let averaged = self.settings.averaged_cycles.clamp(1, cycles);
        let margin = self.output_margin(dt);
        let total = cycles * spc + margin;
        let mut record = Record::new(&self, ((cycles - 1) * spc).saturating_sub(margin));
        let mut surface = match self.settings.surface_maps
            && self.cyls.iter().any(|c| !c.rom.surface.nodes.is_empty())
        {
            true => Some(SurfaceRecord::new(
                &self,
                ((cycles - averaged) * spc).saturating_sub(margin),
                (spc, margin, dt),
            )?),
            false => None,
        };
        let mut acc = Averaged {
            prev_peaks: None,
            kept: Vec::with_capacity(averaged),
            kept_cycles: Vec::with_capacity(averaged),
            power: vec![Vec::new(); self.cyls.len()],
            last_series: None,
        };
        let mut building: Option<Series> = None;
        let mut pending: Option<(usize, Series)> = None;
        let (starts, window_steps) = self.step_error_plan(cycles, spc, margin);
        let mut snapshots: Vec<(usize, EngineRun<'a>)> = Vec::new();
        for g in 0..total {
            for (c, &g0) in starts.iter().enumerate() {
                if g == g0 && self.settings.step_error {
                    snapshots.push((c, self.clone()));
                }
            }
            let cycle = g / spc;
            if g % spc == 0 && cycle < cycles {
                if let Some(done) = building.take() {
                    pending = Some((cycle - 1, done));
                }
                building = Some(self.empty_series(spc));
            }
            self.checked_step(((g + 1) as f64) * dt)?;
            record.push(&self, g);
            if let Some(s) = surface.as_mut() {
                s.push(&self, g);
            }
            if let Some(series) = building.as_mut().filter(|_| cycle < cycles) {
                self.sample(series, cycle);
            }
            self.impulse_acc.fill((0.0, 0.0));
            on_step(g + 1, total);
            if g + 1 == total {
                if let Some(done) = building.take() {
                    pending = Some((cycles - 1, done));
                }
            }
            // a cycle's output is complete `margin` samples past its end
            let ready = pending
                .as_ref()
                .is_some_and(|(k, _)| g + 1 >= (k + 1) * spc + margin);
            if !ready {
                continue;
            }
            let (k, mut series) = pending.take().expect("ready");
            record.outputs(&self, &mut series, k, k + 1 == cycles, (spc, margin, dt));
            let peaks = self.peaks(&series, k);
            if let Some(prev) = &acc.prev_peaks {
                self.stats.cycle_change = largest_change(&peaks, prev);
            }
            if k + averaged >= cycles {
                if let Some(s) = surface.as_mut() {
                    s.map_cycle(k, (spc, margin));
                }
                acc.kept.push(peaks.clone());
                acc.kept_cycles.push(k);
                self.add_spectra(&series, dt, &mut acc.power);
            }
            acc.prev_peaks = Some(peaks);
            acc.last_series = Some(series);
        }
        let step_error = self.step_errors(snapshots, window_steps, dt)?;
        self.conclude(acc, step_error, surface)
    }

    /// The run's result from the averaged cycles: energy balance, spectra, mean peaks with
    /// their standard errors ([`standard_errors`]), slap events and the half-step estimate.
    fn conclude(
        mut self,
        acc: Averaged,
        step_error: Vec<StepError>,
        surface: Option<SurfaceRecord>,
    ) -> Result<CycleResult, TransientError> {
        let (err, scale) = self.energy_balance();
        self.stats.energy_error = if scale > 0.0 { err / scale } else { 0.0 };
        self.stats.cycles_run = self.settings.cycles.max(1);
        self.stats.cycles_averaged = acc.kept.len();
        let mut series = acc.last_series.expect("at least one cycle");
        for (cs, sums) in series.cylinders.iter_mut().zip(&acc.power) {
            cs.spectra = sums.iter().filter_map(PowerSum::average).collect();
        }
        let mut peaks = average_peaks(&acc.kept);
        self.stats.autocorrelation_cycles = standard_errors(&acc.kept, &mut peaks);
        self.events.close();
        self.attach_events(&acc.kept, &acc.kept_cycles, &mut peaks);
        let CyclePeaks {
            cylinders: peaks,
            negative: peak_negative,
            positive: peak_positive,
        } = peaks;
        self.stats.step_error_estimate = mean_step_error(&step_error);
        let surface = match surface {
            Some(s) => s.finish(&self)?,
            None => Vec::new(),
        };
        Ok(CycleResult {
            peaks,
            peak_negative,
            peak_positive,
            series,
            stats: self.stats,
            step_error,
            surface,
        })
    }

    /// The half-step estimate's windows: each snapshot's window run at h and h/2
    /// ([`EngineRun::window_peaks`]). The windows are independent runs from their own states,
    /// so they run on every core; the first failing window in time order is reported, as a
    /// serial run would.
    fn step_errors(
        &self,
        snapshots: Vec<(usize, EngineRun<'a>)>,
        window_steps: usize,
        dt: f64,
    ) -> Result<Vec<StepError>, TransientError> {
        let ids: Vec<usize> = self.cyls.iter().map(|c| c.rom.cylinder).collect();
        snapshots
            .into_par_iter()
            .map(|(c, snap)| {
                let half = snap.clone();
                let (peak_h, peak_half_h) = rayon::join(
                    move || snap.window_peaks(c, window_steps, dt),
                    move || half.window_peaks(c, 2 * window_steps, 0.5 * dt),
                );
                Ok(StepError {
                    cylinder: ids[c],
                    peak_h: peak_h?,
                    peak_half_h: peak_half_h?,
                })
            })
            .collect::<Vec<Result<StepError, TransientError>>>()
            .into_iter()
            .collect()
    }

    /// Advances to time `target` and checks the energy balance (growth beyond the scheme's
    /// tolerance is a numerical failure, named with its crank angle).
    fn checked_step(&mut self, target: f64) -> Result<(), TransientError> {
        let h = target - self.time;
        self.advance(h)?;
        let (err, scale) = self.energy_balance();
        if scale > 1e-12 && err > self.structure.integrator.scheme.energy_tolerance() * scale {
            return Err(TransientError::EnergyGrowth {
                excess_j: err,
                scale_j: scale,
                crank_angle_deg: self.angle_at(self.time),
                time_s: self.time,
            });
        }
        Ok(())
    }

    /// Appends the current state to cycle `cycle`'s series: crank angle within the cycle,
    /// time, piston coordinates, slice forces, side force and cylinder pressure.
    fn sample(&self, series: &mut Series, cycle: usize) {
        let theta = self.angle_at(self.time);
        series.crank_angle_deg.push(theta - 720.0 * cycle as f64);
        series.time_s.push(self.time);
        for (c, cs) in series.cylinders.iter_mut().enumerate() {
            let q = self.cyls[c].body.q;
            cs.lateral_m.push(q[0]);
            cs.tilt_rad.push(q[1]);
            let (ft, fa) = self.last_forces.get(c).copied().unwrap_or((0.0, 0.0));
            cs.thrust_force_n.push(ft);
            cs.antithrust_force_n.push(fa);
            cs.thrust_impulse_n_s.push(self.impulse_acc[c].0);
            cs.antithrust_impulse_n_s.push(self.impulse_acc[c].1);
            let loads = self.setup.piston.loads(theta - self.cyls[c].phase);
            cs.side_force_n.push(loads.side_force);
            cs.pressure_pa.push(loads.pressure);
        }
    }

    /// Where each cylinder's step-error window starts in the last cycle (global step) and its
    /// length in steps. The peaks are compared away from the output filter's ends; where the
    /// filter spans more than the window's first and last 35 deg (high speed: at 3800 rpm a
    /// 110 deg window was shorter than the filter), the window is widened at both ends so the
    /// compared part still covers the slap at 355-395 deg.
    fn step_error_plan(
        &self,
        cycles: usize,
        spc: usize,
        filter_steps: usize,
    ) -> (Vec<usize>, usize) {
        let step_deg = self.settings.step_deg;
        let lead_steps = ((filter_steps as f64 * step_deg - SLAP_MARGIN_DEG).max(0.0) / step_deg)
            .ceil() as usize;
        let window_steps = ((STEP_ERROR_WINDOW_DEG.1 - STEP_ERROR_WINDOW_DEG.0) / step_deg).round()
            as usize
            + 2 * lead_steps;
        let lead_deg = lead_steps as f64 * step_deg;
        let starts = self
            .cyls
            .iter()
            .map(|c| {
                let own = (STEP_ERROR_WINDOW_DEG.0 - lead_deg + c.phase).rem_euclid(720.0);
                (cycles - 1) * spc + (own / step_deg).round() as usize % spc
            })
            .collect();
        (starts, window_steps)
    }

    /// Samples of the record an output at step size `dt` reaches on either side: the output
    /// filter's half length and the second difference's reach.
    fn output_margin(&self, dt: f64) -> usize {
        self.settings
            .output_band_hz
            .map_or(0, |band| fir_half_length(dt, band))
            + OUTPUT_DIFFERENCE_REACH
    }

    /// The run's states where each cylinder's firing-slap window starts in cycle `cycle`
    /// (0-based, from rest): the windows of the step-error estimate
    /// ([`STEP_ERROR_WINDOW_DEG`], widened by the output filter's reach), as (cylinder index,
    /// state) in time order, and the windows' length in base steps. Every state can be run on
    /// by [`EngineRun::window_peaks`] at any step, so that settings are compared on identical
    /// slaps.
    pub fn slap_window_states(
        mut self,
        cycle: usize,
    ) -> Result<(Vec<(usize, Self)>, usize), TransientError> {
        let spc = (720.0 / self.settings.step_deg).round() as usize;
        let dt = self.base_dt();
        let (starts, steps) = self.step_error_plan(cycle + 1, spc, self.output_margin(dt));
        let mut order: Vec<usize> = (0..starts.len()).collect();
        order.sort_by_key(|&c| starts[c]);
        let mut states = Vec::with_capacity(order.len());
        let mut g = 0;
        for c in order {
            while g < starts[c] {
                g += 1;
                self.checked_step(g as f64 * dt)?;
            }
            states.push((c, self.clone()));
        }
        Ok((states, steps))
    }

    /// This state with `slap_substeps` sub-steps per base step in slaps (1: a uniform step).
    pub fn with_slap_substeps(mut self, substeps: usize) -> Self {
        self.settings.slap_substeps = substeps.max(1);
        self
    }

    /// Runs `steps` steps of `h` from the current state and returns the peak negative
    /// acceleration of cylinder index `c`'s points over the window, filtered like the cycle's
    /// outputs and taken where the filter's ends do not reach.
    pub fn window_peaks(
        mut self,
        c: usize,
        steps: usize,
        h: f64,
    ) -> Result<Vec<f64>, TransientError> {
        let n = self.cyls[c].rom.point_modes.nrows();
        let mut disp = vec![Vec::with_capacity(steps); n];
        let t0 = self.time;
        for k in 1..=steps {
            let target = t0 + k as f64 * h;
            let dt = target - self.time;
            self.advance(dt)?;
            for (p, u) in self.point_displacements(c, false).into_iter().enumerate() {
                disp[p].push(u);
            }
        }
        let half = self.output_margin(h);
        Ok((0..n)
            .map(|p| {
                let acc = second_difference4(&disp[p], h);
                let y = match self.settings.output_band_hz {
                    Some(band) => low_pass(&acc, h, band, false).0,
                    None => acc,
                };
                let lo = half.min(y.len());
                sampled_peak(&y, lo..y.len().saturating_sub(half).max(lo), -1.0)
                    .map_or(0.0, |(p, _)| p.max(0.0))
            })
            .collect())
    }

    /// Runs `steps` steps of `h` from the current state and returns each cylinder's slap
    /// events with their onset in the window ([`SlapEvent`]; an event in contact at the start
    /// counts from there), so that settings can be compared on identical slaps.
    pub fn window_events(
        mut self,
        steps: usize,
        h: f64,
    ) -> Result<Vec<Vec<SlapEvent>>, TransientError> {
        self.events = EventRecorder::new(self.cyls.len());
        let t0 = self.time;
        for k in 1..=steps {
            let target = t0 + k as f64 * h;
            self.advance(target - self.time)?;
        }
        self.events.close();
        Ok(self.events.done)
    }

    /// Adds each cylinder's point spectra of the cycle in `series` to the power sums `power`
    /// (per cylinder, per point).
    fn add_spectra(&self, series: &Series, dt: f64, power: &mut [Vec<PowerSum>]) {
        for ((cs, cyl), sums) in series.cylinders.iter().zip(&self.cyls).zip(power) {
            let np = cs.acceleration.nrows();
            sums.resize(np, PowerSum::default());
            for (p, sum) in sums.iter_mut().enumerate() {
                let a = row(&cs.acceleration, p);
                sum.add(&centred_spectrum(a, &series.crank_angle_deg, cyl.phase, dt));
            }
        }
    }

    /// A cycle's series with room for `spc` steps (accelerations are set when it completes).
    fn empty_series(&self, spc: usize) -> Series {
        Series {
            crank_angle_deg: Vec::with_capacity(spc),
            time_s: Vec::with_capacity(spc),
            cylinders: self
                .cyls
                .iter()
                .map(|c| CylinderSeries {
                    cylinder: c.rom.cylinder,
                    acceleration: Dense::zeros((c.rom.point_modes.nrows(), 0)),
                    crankcase_acceleration: Dense::zeros((c.rom.crankcase_point_modes.nrows(), 0)),
                    ..CylinderSeries::default()
                })
                .collect(),
        }
    }

    /// The output band of a record segment with `margin` samples each side of the `spc`
    /// samples wanted: low-passed when the settings name a band, then cut to the cycle.
    fn output_filter(&self, seg: &[f64], dt: f64, margin: usize, spc: usize) -> Vec<f64> {
        match self.settings.output_band_hz {
            Some(band) => low_pass(seg, dt, band, false).0[margin..margin + spc].to_vec(),
            None => seg[margin..margin + spc].to_vec(),
        }
    }

    /// The averaged cycles' slap events per cylinder ([`events::summarise`]) and the event
    /// each point's peak negative acceleration follows: in each averaged cycle the latest
    /// onset at or before the peak's crank angle, the event most cycles name.
    fn attach_events(&self, kept: &[CyclePeaks], cycles: &[usize], peaks: &mut CyclePeaks) {
        for (c, cp) in peaks.cylinders.iter_mut().enumerate() {
            let per_cycle: Vec<Vec<SlapEvent>> =
                cycles.iter().map(|&k| self.events.in_cycle(c, k)).collect();
            let all: Vec<SlapEvent> = per_cycle.iter().flatten().copied().collect();
            let (summaries, group) = events::summarise(&all);
            let np = peaks.negative.ncols();
            cp.negative_events = (0..np)
                .map(|p| {
                    let mut votes = vec![0usize; summaries.len() + 1];
                    let mut offset = 0;
                    for (evs, cyc) in per_cycle.iter().zip(kept) {
                        let angle = cyc.negative[[c, p]].crank_angle_deg;
                        match events::event_before(evs, angle) {
                            Some(i) => votes[group[offset + i]] += 1,
                            None => votes[summaries.len()] += 1,
                        }
                        offset += evs.len();
                    }
                    let (best, &n) = votes
                        .iter()
                        .enumerate()
                        .max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(&a.0)))
                        .expect("at least the None slot");
                    ((best < summaries.len()).then_some(best), n)
                })
                .collect();
            cp.slap_events = summaries;
        }
    }

    /// A cycle's peaks from its series: the filtered point accelerations' peaks located
    /// between the samples ([`sampled_peak`]), the side force's largest sample, and the slap
    /// force of the cycle's largest slap event ([`events`], at the sub-step resolution).
    fn peaks(&self, series: &Series, cycle: usize) -> CyclePeaks {
        let nc = series.cylinders.len();
        let np = series
            .cylinders
            .first()
            .map_or(0, |c| c.acceleration.nrows());
        let mut out = CyclePeaks {
            cylinders: Vec::with_capacity(nc),
            negative: Array2::from_elem((nc, np), Peak::default()),
            positive: Array2::from_elem((nc, np), Peak::default()),
        };
        for (c, (cs, cyl)) in series.cylinders.iter().zip(&self.cyls).enumerate() {
            let local = |k: usize| (series.crank_angle_deg[k] - cyl.phase).rem_euclid(720.0);
            let arg = |v: &[f64], f: &dyn Fn(f64) -> f64| -> Peak {
                let mut best = Peak::single(f64::NEG_INFINITY, 0.0);
                for (k, &x) in v.iter().enumerate() {
                    if f(x) > best.value {
                        best = Peak::single(f(x), local(k));
                    }
                }
                best
            };
            let slap_force = self
                .events
                .in_cycle(c, cycle)
                .iter()
                .map(|e| Peak::single(e.force_n, e.force_crank_angle_deg))
                .max_by(|a, b| a.value.total_cmp(&b.value))
                .unwrap_or(Peak::single(0.0, 0.0));
            // the filtered accelerations are band-limited: their peaks lie between samples
            let band_peak = |v: &[f64], sign: f64| -> Peak {
                match sampled_peak(v, 0..v.len(), sign) {
                    Some((value, at)) => {
                        let k = at.floor() as usize;
                        let angle = local(k) + (at - k as f64) * self.settings.step_deg;
                        Peak::single(value, angle.rem_euclid(720.0))
                    }
                    None => Peak::single(f64::NEG_INFINITY, 0.0),
                }
            };
            for p in 0..np {
                out.negative[[c, p]] = band_peak(row(&cs.acceleration, p), -1.0);
                out.positive[[c, p]] = band_peak(row(&cs.acceleration, p), 1.0);
            }
            out.cylinders.push(CylinderPeaks {
                cylinder: cs.cylinder,
                slap_force,
                side_force: arg(&cs.side_force_n, &|x| x),
                ..Default::default()
            });
        }
        out
    }
}

/// What the slap-event recorder reads of a committed step: its result, the slices (with
/// their (cylinder, thrust side, slice, height)), the slices' states before it, the pistons
/// before it and the quasi-static side forces.
struct StepView<'r, 's> {
    res: &'r contact::StepResult,
    meta: &'r [(usize, bool, usize, f64)],
    slices: &'r [Slice<'s>],
    states: &'r [SliceState],
    before: &'r [Body],
    side_forces: &'r [f64],
    /// Per cylinder, the step's contact impulse of each side ([`EngineRun::contact_impulses`]).
    impulses: &'r [(f64, f64)],
}

/// A failed step attempt.
enum Failure {
    Step(StepFailure),
    Deep {
        cylinder: usize,
        side: bool,
        slice: usize,
        height: f64,
        penetration: f64,
    },
    NonFinite(String),
}

impl Failure {
    fn into_error(self, run: &EngineRun<'_>, dt: f64, halvings: usize) -> TransientError {
        let t = run.time + dt;
        let crank_angle_deg = run.angle_at(t);
        match self {
            Failure::Step(StepFailure::NoConvergence { iterations }) => {
                TransientError::NoConvergence {
                    crank_angle_deg,
                    time_s: t,
                    iterations,
                    halvings,
                }
            }
            Failure::Step(StepFailure::Singular) => TransientError::Singular {
                crank_angle_deg,
                time_s: t,
            },
            Failure::Deep {
                cylinder,
                side,
                slice,
                height,
                penetration,
            } => TransientError::DeepPenetration {
                cylinder,
                side: if side { "thrust" } else { "anti-thrust" },
                slice,
                height_mm: height * 1e3,
                penetration_um: penetration * 1e6,
                limit_um: run.settings.max_penetration * 1e6,
                crank_angle_deg,
                time_s: t,
            },
            Failure::NonFinite(place) => TransientError::NonFinite {
                crank_angle_deg,
                time_s: t,
                place,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Peak;

    #[test]
    fn peak_statistics_over_cycles() {
        // mean 2, sample std 1 (deviations -1, 0, 1 over n - 1 = 2), max 3; angles 719, 1 and
        // 3 deg lie around 1 deg on the 720 deg circle: summed distances 2 + 4, 2 + 2, 4 + 2,
        // so the medoid is 1 deg
        let p = Peak::over_cycles(&[
            Peak::single(1.0, 719.0),
            Peak::single(2.0, 1.0),
            Peak::single(3.0, 3.0),
        ]);
        assert!((p.value - 2.0).abs() < 1e-12);
        assert!((p.std - 1.0).abs() < 1e-12);
        assert_eq!(p.max, 3.0);
        assert_eq!(p.crank_angle_deg, 1.0);
        // peaks at two events (three cycles at 366.5-367.5 deg, two at 90 deg): the medoid is
        // an angle of the majority event (366.5: summed distances 554 against 554.5 for 367),
        // not their mean (~256 deg)
        let e = Peak::over_cycles(&[
            Peak::single(1.0, 367.0),
            Peak::single(1.0, 90.0),
            Peak::single(1.0, 367.5),
            Peak::single(1.0, 90.5),
            Peak::single(1.0, 366.5),
        ]);
        assert_eq!(e.crank_angle_deg, 366.5);
        // one cycle: itself, no spread
        let q = Peak::over_cycles(&[Peak::single(5.0, 367.0)]);
        assert_eq!(
            (q.value, q.std, q.max, q.crank_angle_deg),
            (5.0, 0.0, 5.0, 367.0)
        );
    }
}
