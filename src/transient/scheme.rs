//! Newmark and HHT-alpha time integration parameters.
//!
//! Newmark: u_{n+1} = u_n + dt v_n + dt^2 ((1/2 - beta) a_n + beta a_{n+1}),
//!          v_{n+1} = v_n + dt ((1 - gamma) a_n + gamma a_{n+1}).
//! Average acceleration: beta = 1/4, gamma = 1/2 (unconditionally stable, no numerical
//! damping, energy of a linear undamped system conserved exactly).
//! HHT-alpha (alpha in [-1/3, 0]): the equation of motion is enforced at the weighted time
//!   M a_{n+1} + (1 + alpha) (C v_{n+1} + K u_{n+1}) - alpha (C v_n + K u_n)
//!     = (1 + alpha) F_{n+1} - alpha F_n,
//! with beta = (1 - alpha)^2 / 4, gamma = 1/2 - alpha: second order, damps the highest
//! frequencies.

/// Integration parameters.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Scheme {
    pub beta: f64,
    pub gamma: f64,
    pub alpha: f64,
}

impl From<crate::scene::spec::SchemeChoice> for Scheme {
    fn from(c: crate::scene::spec::SchemeChoice) -> Self {
        use crate::scene::spec::SchemeChoice;
        match c {
            SchemeChoice::AverageAcceleration => Self::average_acceleration(),
            SchemeChoice::Hht { alpha } => Self::hht(alpha),
        }
    }
}

impl Scheme {
    /// Newmark average acceleration (trapezoidal rule).
    pub fn average_acceleration() -> Self {
        Self {
            beta: 0.25,
            gamma: 0.5,
            alpha: 0.0,
        }
    }

    /// HHT-alpha with `alpha` in [-1/3, 0].
    pub fn hht(alpha: f64) -> Self {
        Self {
            beta: (1.0 - alpha).powi(2) / 4.0,
            gamma: 0.5 - alpha,
            alpha,
        }
    }

    /// Largest energy-balance excess (E - W + D), relative to the energy scale, that a stable
    /// run of this scheme can show; beyond it a run is stopped as unstable.
    ///
    /// Average acceleration satisfies the balance with the trapezoidal work
    /// W = sum 1/2 (f_n + f_{n+1}) (eta_{n+1} - eta_n) exactly, so only roundoff remains
    /// (1e-4 leaves four orders of margin over the 1e-9 seen in the tests). HHT-alpha enforces
    /// the equation at the shifted time n + 1 + alpha: it dissipates a quadratic algorithmic
    /// energy, not E, so against the trapezoidal work E - W + D may rise by a bounded fraction
    /// of the scale while the run is stable (below 0.5 over random forcings, steps from 0.03
    /// to 100 per period and damping 0 to 0.2: `hht_energy_excess_is_bounded` below); an
    /// instability grows E without bound, so twice that bound still stops it within a few
    /// steps of growth.
    pub fn energy_tolerance(&self) -> f64 {
        if self.alpha == 0.0 && self.beta == 0.25 && self.gamma == 0.5 {
            1e-4
        } else {
            1.0
        }
    }

    /// Relative period elongation of the average-acceleration rule for a linear oscillator,
    /// T_num / T - 1 = (omega dt / 2) / atan(omega dt / 2) - 1  (~ (omega dt)^2 / 12).
    pub fn average_acceleration_period_error(omega_dt: f64) -> f64 {
        let x = omega_dt / 2.0;
        x / x.atan() - 1.0
    }
}

/// Energy quantities of one committed step ([`ModalIntegrator::commit_with_energy`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepEnergy {
    /// Work of the modal forces over the step \[J\].
    pub work: f64,
    /// Damping power at the step's mean velocity \[W\].
    pub damping_power: f64,
    /// Modal energy after the step \[J\].
    pub energy: f64,
}

/// Modal (diagonal) Newmark/HHT update of uncoupled modes
/// eta'' + 2 zeta omega eta' + omega^2 eta = f.
///
/// Per step: the predictor eta~ (displacement without the new force) and the compliance
/// D_j = beta dt^2 (1 + alpha) / m_j, m_j = 1 + (1 + alpha)(c_j gamma dt + k_j beta dt^2),
/// so that eta_{n+1} = eta~ + D f_{n+1} and eta'_{n+1} = eta'~ + gamma / (beta dt) D f_{n+1}.
#[derive(Clone, Debug)]
pub struct ModalIntegrator {
    pub scheme: Scheme,
    /// omega_j^2 and 2 zeta_j omega_j.
    k: Vec<f64>,
    c: Vec<f64>,
    pub eta: Vec<f64>,
    pub deta: Vec<f64>,
    pub ddeta: Vec<f64>,
    /// Modal force of the last committed step.
    pub force: Vec<f64>,
    // per-step scratch
    dt: f64,
    base_acc: Vec<f64>,
    inv_m: Vec<f64>,
    pub pred: Vec<f64>,
    pub dpred: Vec<f64>,
    /// D_j of the current step.
    pub compliance: Vec<f64>,
    /// Strain norm of the predictor, sqrt(sum_j omega_j^2 eta~_j^2).
    pub pred_strain_norm: f64,
    /// Modal impulses to deliver over the next step ([`ModalIntegrator::impulse_over_next_step`])
    /// and the force that delivers them in the current step (pending / dt).
    pending: Vec<f64>,
    held: Vec<f64>,
    /// Leading modes that are dynamic modes of the structure (the rest: residual vectors).
    pub dynamic_modes: usize,
}

impl ModalIntegrator {
    /// Modes of angular frequencies `omega` [rad/s] and damping ratios `zeta`, at rest.
    pub fn new(omega: &[f64], zeta: &[f64], scheme: Scheme) -> Self {
        let n = omega.len();
        Self {
            scheme,
            k: omega.iter().map(|w| w * w).collect(),
            c: omega.iter().zip(zeta).map(|(w, z)| 2.0 * z * w).collect(),
            eta: vec![0.0; n],
            deta: vec![0.0; n],
            ddeta: vec![0.0; n],
            force: vec![0.0; n],
            dt: 0.0,
            base_acc: vec![0.0; n],
            inv_m: vec![0.0; n],
            pred: vec![0.0; n],
            dpred: vec![0.0; n],
            compliance: vec![0.0; n],
            pred_strain_norm: 0.0,
            pending: vec![0.0; n],
            held: vec![0.0; n],
            dynamic_modes: n,
        }
    }

    pub fn len(&self) -> usize {
        self.k.len()
    }

    pub fn is_empty(&self) -> bool {
        self.k.is_empty()
    }

    /// omega_j^2 of every mode.
    pub fn stiffness(&self) -> &[f64] {
        &self.k
    }

    /// Prepares a step of size `dt`: predictor and compliance (the new force still unknown),
    /// and the predictor's strain norm sqrt(sum_j omega_j^2 eta~_j^2). A pending impulse d_j
    /// acts as the force h_j = d_j / dt held over the step: on the start acceleration (in the
    /// predictor) and on the end one (in a0).
    pub fn predict(&mut self, dt: f64) {
        let Scheme { beta, gamma, alpha } = self.scheme;
        self.dt = dt;
        let mut strain = 0.0;
        for j in 0..self.k.len() {
            let (k, c) = (self.k[j], self.c[j]);
            let h = self.pending[j] / dt;
            self.held[j] = h;
            let a_start = self.ddeta[j] + h;
            let uh = self.eta[j] + dt * self.deta[j] + dt * dt * (0.5 - beta) * a_start;
            let vh = self.deta[j] + dt * (1.0 - gamma) * a_start;
            let m = 1.0 + (1.0 + alpha) * (c * gamma * dt + k * beta * dt * dt);
            let a0 = (-alpha * self.force[j] + alpha * (c * self.deta[j] + k * self.eta[j])
                - (1.0 + alpha) * (c * vh + k * uh)
                + h)
                / m;
            self.inv_m[j] = (1.0 + alpha) / m;
            self.base_acc[j] = a0;
            self.pred[j] = uh + beta * dt * dt * a0;
            self.dpred[j] = vh + gamma * dt * a0;
            self.compliance[j] = beta * dt * dt * self.inv_m[j];
            strain += k * self.pred[j] * self.pred[j];
        }
        self.pred_strain_norm = strain.sqrt();
    }

    /// Size of the current step \[s\].
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// gamma / (beta dt) of the current step (velocity per displacement of the new force).
    pub fn velocity_factor(&self) -> f64 {
        self.scheme.gamma / (self.scheme.beta * self.dt)
    }

    /// Completes the step with the modal force `f` of the new time.
    pub fn commit(&mut self, f: &[f64]) {
        self.commit_with_energy(f);
    }

    /// Completes the step like [`ModalIntegrator::commit`] and returns, from the same pass over
    /// the modes, the step's work of the modal forces (trapezoidal),
    /// W = sum_j (f0_j + f_j) / 2 (eta1_j - eta0_j), the damping power at the mean velocity,
    /// P = sum_j c_j ((v0_j + v1_j) / 2)^2, and the new energy [`ModalIntegrator::energy`]
    /// (each summed over j in ascending order, as the separate functions do).
    pub fn commit_with_energy(&mut self, f: &[f64]) -> StepEnergy {
        let Scheme { beta, gamma, .. } = self.scheme;
        let dt = self.dt;
        let (mut work, mut power, mut energy) = (0.0, 0.0, 0.0);
        for j in 0..self.k.len() {
            let (eta0, v0, f0) = (self.eta[j], self.deta[j], self.force[j]);
            let a = self.base_acc[j] + self.inv_m[j] * f[j];
            self.eta[j] = self.pred[j] + beta * dt * dt * self.inv_m[j] * f[j];
            self.deta[j] = self.dpred[j] + gamma * dt * self.inv_m[j] * f[j];
            // the held force ends with the step: the stored acceleration is the equation's
            let h = self.held[j];
            self.ddeta[j] = a - h;
            self.force[j] = f[j];
            work += (0.5 * (f0 + f[j]) + h) * (self.eta[j] - eta0);
            let vbar = 0.5 * (v0 + self.deta[j]);
            power += self.c[j] * vbar * vbar;
            energy += self.deta[j].powi(2) + self.k[j] * self.eta[j].powi(2);
        }
        self.pending.iter_mut().for_each(|p| *p = 0.0);
        self.held.iter_mut().for_each(|h| *h = 0.0);
        StepEnergy {
            work,
            damping_power: power,
            energy: 0.5 * energy,
        }
    }

    /// Modal impulses d_j [sqrt(kg) m/s] to be delivered over the next step, as the constant
    /// modal force d_j / dt on both of its ends (added to what is already pending), to the
    /// modes the step resolves, omega_j dt <= 1/2 (at least 12 steps per period; every mode
    /// as dt -> 0). A resolved mode gains the impulse d_j (its timing moved by at most a step:
    /// O(dt^2) in where it is). An unresolved one (omega_j dt >> 1) would answer the short
    /// force the impulse stands for quasi-statically and only while it lasts; given to it, the
    /// average-acceleration rule, which never damps such a mode, keeps the response ringing at
    /// the Nyquist rate, and many onsets add up to a chattering wall (measured on the default
    /// engine: skirts through the liner within the first 12 deg). Only the first
    /// `dynamic_modes` modes take impulses: a ROM's residual vectors after its system modes
    /// are static Ritz vectors whose frequencies come from the reduction, not dynamic modes
    /// (measured: giving them the impulse where the step resolves part of them moved the
    /// edge cylinders' peaks by up to 20 % at 1/4 of the default step).
    pub fn impulse_over_next_step(&mut self, d: &[f64]) {
        let dt2 = self.dt * self.dt;
        let n = self.dynamic_modes.min(self.k.len());
        for ((p, dj), k) in self.pending.iter_mut().zip(d).zip(&self.k).take(n) {
            if k * dt2 <= 0.25 {
                *p += dj;
            }
        }
    }

    /// Modal energy 1/2 sum (eta'^2 + omega^2 eta^2) (mass-normalised modes).
    pub fn energy(&self) -> f64 {
        0.5 * (0..self.k.len())
            .map(|j| self.deta[j].powi(2) + self.k[j] * self.eta[j].powi(2))
            .sum::<f64>()
    }

    /// Damping power at velocity `v`: sum c_j v_j^2.
    pub fn damping_power(&self, v: &[f64]) -> f64 {
        (0..self.k.len()).map(|j| self.c[j] * v[j] * v[j]).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Energy excess of one forced mode: the cycle's balance E - W + D over the scale
    /// max(E, |W|, D), its largest value over the run.
    fn worst_excess(scheme: Scheme, w: f64, zeta: f64, dt: f64, f: &[f64]) -> f64 {
        let mut m = ModalIntegrator::new(&[w], &[zeta], scheme);
        let (mut work, mut damped, mut scale, mut worst) = (0.0, 0.0, 0.0f64, 0.0f64);
        for &fk in f {
            m.predict(dt);
            let (u0, v0, f0) = (m.eta[0], m.deta[0], m.force[0]);
            m.commit(&[fk]);
            work += 0.5 * (f0 + fk) * (m.eta[0] - u0);
            damped += dt * m.damping_power(&[0.5 * (v0 + m.deta[0])]);
            let e = m.energy();
            scale = scale.max(e).max(work.abs()).max(damped);
            if scale > 0.0 {
                worst = worst.max((e - work + damped) / scale);
            }
        }
        worst
    }

    #[test]
    fn hht_energy_excess_is_bounded() {
        // deterministic pseudo-random forcings (xorshift), the cases of the tolerance's doc
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut rnd = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut worst = [0.0f64; 2];
        for _ in 0..300 {
            let w = 10f64.powf(2.0 + 3.0 * rnd());
            let dt = 10f64.powf(-1.5 + 3.5 * rnd()) / w;
            let n = 20 + (580.0 * rnd()) as usize;
            let kind = (3.0 * rnd()) as usize;
            let ratio = 0.01 + 2.0 * rnd();
            let f: Vec<f64> = (0..n)
                .map(|k| match kind {
                    0 => rnd() - 0.5,
                    1 => (k as f64 * dt * w * ratio).sin(),
                    _ => {
                        if rnd() > 0.95 {
                            rnd() - 0.5
                        } else {
                            0.0
                        }
                    }
                })
                .collect();
            let zeta = [0.0, 0.02, 0.2][(3.0 * rnd()) as usize % 3];
            for alpha in [-0.05, -0.1, -0.2, -1.0 / 3.0] {
                let e = worst_excess(Scheme::hht(alpha), w, zeta, dt, &f);
                worst[0] = worst[0].max(e);
            }
            let e = worst_excess(Scheme::average_acceleration(), w, zeta, dt, &f);
            worst[1] = worst[1].max(e);
        }
        // HHT: bounded well inside its tolerance; average acceleration: roundoff
        assert!(
            worst[0] < 0.5 * Scheme::hht(-0.1).energy_tolerance(),
            "{worst:?}"
        );
        assert!(worst[0] > 1e-3, "the HHT excess is real: {worst:?}");
        assert!(
            worst[1] < 1e-6 * Scheme::average_acceleration().energy_tolerance(),
            "{worst:?}"
        );
        // an unstable update (negative damping) crosses the HHT tolerance
        let f = vec![0.0; 400];
        let mut m = ModalIntegrator::new(&[1000.0], &[-0.05], Scheme::hht(-0.1));
        m.eta[0] = 1e-3;
        let e0 = m.energy();
        for _ in 0..400 {
            m.predict(1e-4);
            m.commit(&f[..1]);
        }
        assert!(m.energy() > (1.0 + Scheme::hht(-0.1).energy_tolerance()) * e0);
    }

    #[test]
    fn period_error_formula_is_second_order() {
        let e1 = Scheme::average_acceleration_period_error(0.1);
        let e2 = Scheme::average_acceleration_period_error(0.05);
        assert!((e1 / e2 - 4.0).abs() < 0.01);
        assert!((e1 - 0.01 / 12.0).abs() < 1e-5);
    }
}
