//! Stepping the engine: one base step of every piston and the structure, its slap sub-steps
//! and halvings, the contact step of the monolithic or per-cylinder coupling, its checks, and
//! what a committed step records (the series, the contact impulses and the slap events).

use super::*;

/// One step's loads and skirt slices ([`EngineRun::step_loads`]).
pub(super) struct StepLoads<'a> {
    /// The pistons with this step's gas and inertia forces.
    bodies: Vec<Body>,
    slices: Vec<Slice<'a>>,
    meta: Vec<SliceMeta>,
    /// Quasi-static side force [N] and axial velocity [m/s] per cylinder.
    side_forces: Vec<f64>,
    axial: Vec<f64>,
}

impl<'a> EngineRun<'a> {
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
    pub(super) fn substep_span(&self, dt: f64) -> usize {
        let step_deg = self.angle_at(dt);
        1 + (self.settings.slap_span_deg / step_deg - 1e-9).ceil() as usize
    }

    pub(super) fn advance_depth(&mut self, dt: f64, depth: usize) -> Result<(), TransientError> {
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
    pub(super) fn try_step(&mut self, dt: f64, stop_at_onset: bool) -> Result<bool, Failure> {
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
        let films = film_groups(piston, &meta, &|b| axial[b]);
        let res = match self.settings.coupling {
            Coupling::Monolithic => contact::step(
                &bodies,
                &slices,
                &films,
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
        self.stats.film_mismatch = self.stats.film_mismatch.max(film_mismatch(&films, &res));
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
    pub(super) fn step_loads(&self, theta: f64) -> StepLoads<'a> {
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
            body.tilt_friction = tilt_friction(piston, &loads);
            out.bodies.push(body);
            out.side_forces.push(loads.side_force);
            out.axial.push(loads.axial_velocity);
            let bore = BoreLines {
                thrust_z: &cyl.rom.thrust_z,
                antithrust_z: &cyl.rom.antithrust_z,
                first: cyl.rom.contact_offset,
            };
            let prev = |side: bool, i: usize| {
                self.prev_state[(2 * b + usize::from(!side)) * ns + i].prior()
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
    pub(super) fn check_step(
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
    pub(super) fn record_step(
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
        self.set_loaded(loaded);
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
    pub(super) fn contact_impulses(
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
    pub(super) fn observe_events(&mut self, theta: f64, dt: f64, view: &StepView<'_, '_>) {
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
    pub(super) fn contact_per_cylinder(
        &mut self,
        bodies: &[Body],
        slices: &[Slice<'_>],
        (meta, axial): (&[SliceMeta], &[f64]),
        dt: f64,
    ) -> Result<contact::StepResult, Failure> {
        let mut out = contact::StepResult {
            film: vec![0.0; slices.len()],
            film_end: vec![0.0; slices.len()],
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
                out.film_end[k] = r.film_end[j];
            }
            out.iterations = out.iterations.max(r.iterations);
        }
        Ok(out)
    }

    /// Whether a cylinder side touches the liner after the step (the step's slices per
    /// `meta`: cylinder index, thrust side, slice) with none of its slices touching before; a
    /// slice touches when it penetrates or, on a lubricated skirt, when its thrust line is
    /// wetted ([`crate::piston::lubrication::Film::wets`]): a lubricated slap begins where the skirt closes
    /// in to the oil, not where the film's pressure first rises from zero (under the Reynolds
    /// condition it is zero again wherever the skirt draws back, so it would start a slap's
    /// sub-steps at every turn of the skirt within the oil).
    pub(super) fn side_onset(
        &self,
        meta: &[(usize, bool, usize, f64)],
        res: &contact::StepResult,
    ) -> bool {
        let ns = self.setup.piston.skirt.heights.len();
        let film = self.setup.piston.film.as_ref();
        let touches = |pen: f64| {
            pen > 0.0 || film.is_some_and(|f: &crate::piston::lubrication::Film| f.wets(pen))
        };
        let mut before = vec![false; 2 * self.cyls.len()];
        let mut after = vec![false; 2 * self.cyls.len()];
        for (k_slice, &(b, side, i, _)) in meta.iter().enumerate() {
            let k = 2 * b + usize::from(!side);
            before[k] |= touches(self.prev_state[k * ns + i].penetration);
            after[k] |= touches(res.penetrations[k_slice]);
        }
        before.iter().zip(&after).any(|(&b, &a)| a && !b)
    }
}

/// What the slap-event recorder reads of a committed step: its result, the slices (with
/// their (cylinder, thrust side, slice, height)), the slices' states before it, the pistons
/// before it and the quasi-static side forces.
pub(super) struct StepView<'r, 's> {
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
pub(super) enum Failure {
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
    pub(super) fn into_error(
        self,
        run: &EngineRun<'_>,
        dt: f64,
        halvings: usize,
    ) -> TransientError {
        let t = run.time + dt;
        let crank_angle_deg = run.angle_at(t);
        match self {
            Failure::Step(StepFailure::NoConvergence { iterations }) => {
                TransientError::NoConvergence {
                    crank_angle_deg,
                    time_s: t,
                    iterations,
                    halvings,
                    film: run.setup.piston.film_summary(),
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

/// Film forces of a side below this are not compared \[N\] (the cavitation's smoothing keeps
/// about 34 N on a side at rest).
const FILM_CHECK_FLOOR_N: f64 = 200.0;

/// How well a step resolved the oil film: each engaged side's film F_end at the step's end
/// (`res.film_end`, the film evaluated at the converged state, where the Newton iteration
/// linearised it last) against the forces F_used the step carries (`res.film`),
///   m = max over sides of max_i |F_end,i - F_used,i| / max(sum_i F_end,i, sum_i F_used,i),
/// sides whose film force is below [`FILM_CHECK_FLOOR_N`] left out (0 without a film).
pub(super) fn film_mismatch(films: &[contact::FilmGroup<'_>], res: &contact::StepResult) -> f64 {
    let mut worst_side = 0.0f64;
    for g in films {
        let end: Vec<f64> = g.slices.iter().map(|&i| res.film_end[i]).collect();
        let used: Vec<f64> = g.slices.iter().map(|&i| res.film[i]).collect();
        let total = end.iter().sum::<f64>().max(used.iter().sum::<f64>());
        if total < FILM_CHECK_FLOOR_N {
            continue;
        }
        let worst = end
            .iter()
            .zip(&used)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        worst_side = worst_side.max(worst / total);
    }
    worst_side
}
