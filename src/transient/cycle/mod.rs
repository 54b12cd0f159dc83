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
    body_at_rest, film_groups, push_slices, residual_displacement, tilt_friction, BoreLines,
    PistonInBore,
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

mod events;
mod record;
mod result;
mod settings;
pub mod statistics;
mod step;
mod surface;
mod tolerance;
mod windows;

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
use windows::StepErrorRuns;

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
    /// The modes the run does not integrate (`transient.mode_cutoff_hz`), quasi-static: their
    /// contact rows over omega_j^2 (contact DOFs x dropped modes, [`dropped_rows`]) and their
    /// coordinates under the last step's contact forces ([`EngineRun::set_loaded`]).
    dropped_rows: Dense,
    pub(super) dropped_static: Vec<f64>,
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

/// The contact rows of the modes from `nm` on over their omega_j^2, c_j / omega_j^2 (contact
/// DOFs x the modes not integrated; no columns when every mode is): with them the quasi-static
/// coordinates of those modes under contact forces F are q_j = c_j^T F / omega_j^2.
fn dropped_rows(rom: &EngineRom, nm: usize) -> Dense {
    let all = rom.frequencies_hz.len();
    if nm == all {
        return Dense::zeros((rom.residual_flexibility.nrows(), 0));
    }
    let (rows, _) = contact_data(rom, all);
    Dense::from_shape_fn((rows.nrows(), all - nm), |(r, k)| {
        let w = 2.0 * std::f64::consts::PI * rom.frequencies_hz[nm + k];
        rows[[r, nm + k]] / (w * w)
    })
}

/// How many of the ROM's modes (ascending) the transient integrates: those up to
/// `modes_below_hz` (all when None); the rest respond statically ([`truncated_flexibility`]).
pub(crate) fn integrated_modes(rom: &EngineRom, settings: &CycleSettings) -> usize {
    match settings.modes_below_hz {
        Some(f) => rom.frequencies_hz.iter().take_while(|&&x| x <= f).count(),
        None => rom.frequencies_hz.len(),
    }
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
        let nm = integrated_modes(rom, &settings);
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
            dropped_static: vec![0.0; rom.frequencies_hz.len() - nm],
            dropped_rows: dropped_rows(rom, nm),
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
    /// on the liner
    ///
    ///   u_p = sum_{j < nb} phi_pj eta_j + sum_{j >= nb} phi_pj q_j + R_pc F_c,
    ///
    /// the integrated modes, the quasi-static coordinates q_j of the modes not integrated
    /// under every cylinder's last contact forces (`EngineRun::loaded`) and the residual
    /// response to this cylinder's; at the crankcase's facing points the two modal sums.
    pub fn point_displacements(&self, c: usize, crankcase: bool) -> Vec<f64> {
        let rom = self.cyls[c].rom;
        let m = if crankcase {
            &rom.crankcase_point_modes
        } else {
            &rom.point_modes
        };
        let eta = &self.structure.integrator.eta;
        let (nb, q) = (eta.len(), &self.dropped_static);
        let modal = (0..m.nrows()).map(|p| {
            let r = row(m, p);
            contact::dot(&r[..nb], &eta[..nb]) + contact::dot(&r[nb..nb + q.len()], q)
        });
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

    /// The last step's contact forces: (cylinder index, location on the contact DOFs of the
    /// ROM's residual flexibility, force \[N\]).
    pub fn loaded(&self) -> &[(usize, Location, f64)] {
        &self.prev_loaded
    }

    /// Makes `loaded` (cylinder index, location, force) the last step's contact forces and
    /// sets the quasi-static coordinates of the modes not integrated under them,
    /// q_j = sum_e (c_j)_e F_e / omega_j^2 over the loaded contact DOFs e of every cylinder
    /// (nothing to do when every mode is integrated).
    pub(super) fn set_loaded(&mut self, loaded: Vec<(usize, Location, f64)>) {
        self.prev_loaded = loaded;
        if self.dropped_static.is_empty() {
            return;
        }
        self.dropped_static.fill(0.0);
        for (_, at, f) in &self.prev_loaded {
            for k in 0..2 {
                let w = at.weights[k] * f;
                if w != 0.0 {
                    let r = row(&self.dropped_rows, at.dofs[k]);
                    for (q, c) in self.dropped_static.iter_mut().zip(r) {
                        *q += w * c;
                    }
                }
            }
        }
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
        on_step: impl FnMut(usize, usize) + Send,
    ) -> Result<CycleResult, TransientError> {
        let spc = (720.0 / self.settings.step_deg).round() as usize;
        let dt = self.base_dt();
        self.stats.dt_s = dt;
        let cycles = self.settings.cycles.max(1);
        let margin = self.output_margin(dt);
        let (starts, window_steps) = self.step_error_plan(cycles, spc, margin);
        let windows = StepErrorRuns::new(window_steps, dt);
        // the step-error windows run on the other core while the cycles go on
        let (acc, surface) = rayon::scope(|scope| {
            let starts: &[usize] = match self.settings.step_error {
                true => &starts,
                false => &[],
            };
            let out = self.cycles_loop((spc, margin, dt), starts, on_step, |c, snap| {
                windows.start(scope, c, snap)
            });
            if out.is_err() {
                windows.cancel();
            }
            out
        })?;
        let step_error = windows.results()?;
        self.conclude(acc, step_error, surface)
    }

    /// The cycles of [`EngineRun::run`] at `dt` (`spc` steps a cycle, the output filter's
    /// reach `margin`): every step recorded, each cycle's outputs and peaks formed once the
    /// run is `margin` past its end, the averaged cycles' peaks, spectra and surface maps
    /// kept. At global step `starts[c]` the state is handed to `on_window(c, state)` (cylinder
    /// c's step-error window starts there).
    fn cycles_loop(
        &mut self,
        (spc, margin, dt): (usize, usize, f64),
        starts: &[usize],
        mut on_step: impl FnMut(usize, usize),
        mut on_window: impl FnMut(usize, Self),
    ) -> Result<(Averaged, Option<SurfaceRecord>), TransientError> {
        let cycles = self.settings.cycles.max(1);
        let averaged = self.settings.averaged_cycles.clamp(1, cycles);
        let total = cycles * spc + margin;
        let mut record = Record::new(self, ((cycles - 1) * spc).saturating_sub(margin));
        let mut surface = match self.settings.surface_maps
            && self.cyls.iter().any(|c| !c.rom.surface.nodes.is_empty())
        {
            true => Some(SurfaceRecord::new(
                self,
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
        for g in 0..total {
            for (c, _) in starts.iter().enumerate().filter(|&(_, &g0)| g == g0) {
                on_window(c, self.clone());
            }
            let cycle = g / spc;
            if g % spc == 0 && cycle < cycles {
                if let Some(done) = building.take() {
                    pending = Some((cycle - 1, done));
                }
                building = Some(self.empty_series(spc));
            }
            self.checked_step(((g + 1) as f64) * dt)?;
            record.push(self, g);
            if let Some(s) = surface.as_mut() {
                s.push(self, g);
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
            record.outputs(self, &mut series, k, k + 1 == cycles, (spc, margin, dt));
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
        Ok((acc, surface))
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
    /// force of the cycle's largest slap event ([`events`], interpolated between the sub-steps).
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
