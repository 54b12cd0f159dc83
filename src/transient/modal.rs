//! The engine ROM as the contact sees it: system modes integrated by [`ModalIntegrator`], mode
//! rows at the contact DOFs (bore-line nodes of every modelled liner, outward radial), their
//! residual flexibility R and the head-bolt preload displacement u0.
//!
//! At a location x (two bore-line DOFs d with weights w), phi_x = sum_d w_d phi_d, and
//!   u(x) = u0(x) + phi_x . eta + sum_k R(x, x_k) F_k,
//!   G(x, y) = sum_j phi_xj D_j phi_yj + R(x, y),  G_v(x, y) = gamma / (beta dt) sum_j phi_xj D_j phi_yj.
//! The residual flexibility responds quasi-statically (no velocity).
//!
//! D depends on the step size only, so the DOF-level step compliance S_de = phi_d D phi_e is
//! formed once per step size (one matrix product over all contact DOFs) and every per-step
//! quantity is an interpolation of it: G(x, y) = sum_{d,e} w_d w_e S_de + R(x, y). The only
//! per-step products over the modes are the predictor at the touched DOFs, phi_d . eta~ and
//! phi_d . eta'~ (each once per DOF, shared by the slices beside it), and only at the slices
//! that may touch: with mass-normalised modes, Cauchy-Schwarz on (phi_dj / omega_j)(omega_j eta_j)
//! bounds the modal displacement by the static modal flexibility and the strain norm,
//!   |phi_d . eta~| <= sqrt(sum_j phi_dj^2 / omega_j^2) sqrt(sum_j omega_j^2 eta~_j^2),
//! so a slice whose penetration stays below its law's onset over that interval is apart
//! without its dot products (the result is the same bit for bit).

use super::contact::{Location, Structure};
use super::scheme::ModalIntegrator;
use crate::linalg::dense::{from_faer, row, values, values_mut, Dense};
use crate::linalg::kernels::{axpy, dot, dot_pair};
use nalgebra::DMatrix;
use std::sync::Arc;

/// The DOF-level step matrices of one step size, (S, T), shared between clones.
type StepMatrices = Arc<(Dense, Dense)>;

/// ROM structure state of a transient. What does not change during a run (the mode rows,
/// residual flexibility, preload, the step matrices once formed) is shared between clones: the
/// step-error windows clone the running engine 18 times a run (six snapshots, two runs each).
#[derive(Clone)]
pub struct ModalStructure {
    pub integrator: ModalIntegrator,
    /// Contact DOF rows (contact DOFs x modes), row-major.
    rows: Arc<Dense>,
    rflex: Arc<Dense>,
    preload: Arc<[f64]>,
    /// sqrt(sum_j phi_dj^2 / omega_j^2) per contact DOF (+inf with a mode at omega = 0).
    static_norm: Arc<[f64]>,
    /// Whether the residual flexibility is used.
    pub static_correction: bool,
    /// Whether [`Structure::predicted_bound`] offers its bound (false: every prediction exact).
    pub bound_predictions: bool,
    /// Contact-DOF blocks that exchange force within one step (`None`: all of them). With
    /// blocks, S and T are formed on the diagonal blocks only (zero elsewhere).
    pub blocks: Option<Vec<std::ops::Range<usize>>>,
    /// Per step size and static-correction flag (key: dt bits, flag): S = Phi D Phi^T over
    /// the contact DOFs and T = S + R (T = S without the static correction), each stored
    /// transposed (row e holds column e), so that a response G F is a sum of contiguous row
    /// pieces ([`ModalStructure::apply_step_matrix`]).
    step_compliance: Vec<(u64, bool, StepMatrices)>,
    /// Index into `step_compliance` of the current step.
    current: usize,
    // per-step data: locations, predictor (u, u') per DOF (NaN: not yet formed)
    locs: Vec<Location>,
    dof_pred: std::cell::RefCell<Vec<(f64, f64)>>,
    touched: std::cell::RefCell<Vec<usize>>,
}

impl ModalStructure {
    /// `rows`: contact DOFs x modes; `rflex`: contact DOFs squared; `preload` per contact DOF.
    /// `rflex` is made exactly symmetric, (R + R^T) / 2 (its products leave roundoff
    /// asymmetry; the per-cylinder coupling reads its rows as columns).
    pub fn new(
        integrator: ModalIntegrator,
        rows: Dense,
        mut rflex: Dense,
        preload: Vec<f64>,
    ) -> Self {
        let ndof = rows.nrows();
        let nr = rflex.nrows();
        for a in 0..nr {
            for b in a + 1..nr {
                let v = 0.5 * (rflex[[a, b]] + rflex[[b, a]]);
                rflex[[a, b]] = v;
                rflex[[b, a]] = v;
            }
        }
        let k = integrator.stiffness();
        let rigid = k.iter().any(|&w2| w2 <= 0.0);
        let static_norm: Arc<[f64]> = (0..ndof)
            .map(|d| {
                if rigid {
                    return f64::INFINITY;
                }
                let row = &row(&rows, d)[..k.len()];
                row.iter()
                    .zip(k)
                    .map(|(p, w2)| p * p / w2)
                    .sum::<f64>()
                    .sqrt()
            })
            .collect();
        Self {
            integrator,
            rows: Arc::new(rows),
            rflex: Arc::new(rflex),
            preload: preload.into(),
            static_norm,
            static_correction: true,
            bound_predictions: true,
            blocks: None,
            step_compliance: Vec::new(),
            current: 0,
            locs: Vec::new(),
            dof_pred: std::cell::RefCell::new(vec![(f64::NAN, f64::NAN); ndof]),
            touched: std::cell::RefCell::new(Vec::new()),
        }
    }

    /// Selects (forming on first use) S = Phi D Phi^T for the integrator's current step size.
    fn select_step_compliance(&mut self) {
        // steps of one size differ by roundoff (t_{n+1} - t_n); a relative 1e-9 difference in
        // dt changes S by the same relative amount, far below every tolerance of the run
        let dt = self.integrator.dt();
        let key = dt.to_bits();
        if let Some(k) = self.step_compliance.iter().position(|(b, sc, _)| {
            *sc == self.static_correction && (f64::from_bits(*b) - dt).abs() <= 1e-9 * dt
        }) {
            self.current = k;
            return;
        }
        let n = self.integrator.len();
        let ndof = self.rows.nrows();
        let d = &self.integrator.compliance;
        // Psi = Phi sqrt(D) (DOFs x modes), S = Psi Psi^T
        let psi = faer::Mat::<f64>::from_fn(ndof, n, |r, j| self.rows[[r, j]] * d[j].sqrt());
        let mut s = faer::Mat::<f64>::zeros(ndof, ndof);
        let whole = 0..ndof;
        let blocks = self
            .blocks
            .as_deref()
            .unwrap_or(std::slice::from_ref(&whole));
        for r in blocks {
            let p = psi.as_ref().subrows(r.start, r.len());
            faer::linalg::matmul::matmul(
                s.as_mut().submatrix_mut(r.start, r.start, r.len(), r.len()),
                faer::Accum::Replace,
                p,
                p.transpose(),
                1.0,
                faer::Par::Seq,
            );
        }
        // a handful of step sizes at most (the base step and its halvings)
        if self.step_compliance.len() >= 8 {
            self.step_compliance.remove(0);
        }
        // transposed (R is exactly symmetric, so S^T + R is T^T to the bit)
        let s = from_faer(&s.transpose().to_owned());
        let mut t = s.clone();
        if self.static_correction {
            for (tv, rv) in values_mut(&mut t).iter_mut().zip(values(&self.rflex)) {
                *tv += rv;
            }
        }
        self.step_compliance
            .push((key, self.static_correction, Arc::new((s, t))));
        self.current = self.step_compliance.len() - 1;
    }

    /// A DOF-level matrix X (S or T) between two locations, sum_{d,e} w_d w_e X_de, from its
    /// transpose `xt` (X_de = xt_ed).
    fn interpolate(xt: &Dense, a: &Location, b: &Location) -> f64 {
        let mut v = 0.0;
        for i in 0..2 {
            let d = a.dofs[i];
            let (x0, x1) = (xt[[b.dofs[0], d]], xt[[b.dofs[1], d]]);
            v += a.weights[i] * (b.weights[0] * x0 + b.weights[1] * x1);
        }
        v
    }

    /// Predictor (phi_d . eta~, phi_d . eta'~) at contact DOF `d`, memoised per step.
    fn dof_predicted(&self, d: usize) -> (f64, f64) {
        let mut memo = self.dof_pred.borrow_mut();
        if memo[d].0.is_nan() {
            let it = &self.integrator;
            let n = it.len();
            memo[d] = dot_pair(&row(&self.rows, d)[..n], &it.pred, &it.dpred);
            self.touched.borrow_mut().push(d);
        }
        memo[d]
    }

    /// Residual flexibility R(a, b) between two locations [m/N].
    pub fn rflex_at(&self, a: &Location, b: &Location) -> f64 {
        if !self.static_correction {
            return 0.0;
        }
        let mut s = 0.0;
        for i in 0..2 {
            for k in 0..2 {
                s += a.weights[i] * b.weights[k] * self.rflex[[a.dofs[i], b.dofs[k]]];
            }
        }
        s
    }

    /// Number of contact DOFs (bore-line nodes of every modelled liner).
    pub fn contact_dofs(&self) -> usize {
        self.rows.nrows()
    }

    /// u += f R_e\[range\] (row `e` of the residual flexibility, which is symmetric: the column
    /// too); nothing without the static correction.
    pub fn rflex_axpy(&self, u: &mut [f64], f: f64, e: usize, range: std::ops::Range<usize>) {
        if self.static_correction {
            axpy(u, f, &row(&self.rflex, e)[range]);
        }
    }

    /// Modal force sum_k phi_k F_k of forces at arbitrary locations.
    pub fn modal_force_at(&self, locs: &[Location], forces: &[f64]) -> Vec<f64> {
        let n = self.integrator.len();
        // neighbouring slices share bore-line nodes: gather on the DOFs first
        let gathered = gather_on_dofs(locs.iter().zip(forces.iter().copied()));
        let mut f = vec![0.0; n];
        for &(e, fe) in &gathered {
            if fe == 0.0 {
                continue;
            }
            axpy(&mut f, fe, &row(&self.rows, e)[..n]);
        }
        f
    }

    /// Preload plus modal displacement (no residual part) at a location,
    /// u0(x) + sum_d w_d phi_d . eta.
    pub fn displacement(&self, at: &Location) -> f64 {
        let n = self.integrator.len();
        let eta = &self.integrator.eta;
        (0..2)
            .map(|i| {
                let d = at.dofs[i];
                at.weights[i] * (self.preload[d] + dot(&row(&self.rows, d)[..n], eta))
            })
            .sum()
    }
}

impl Structure for ModalStructure {
    fn prepare(&mut self, locs: &[Location]) {
        self.select_step_compliance();
        self.locs.clear();
        self.locs.extend_from_slice(locs);
        let mut memo = self.dof_pred.borrow_mut();
        for d in self.touched.borrow_mut().drain(..) {
            memo[d] = (f64::NAN, f64::NAN);
        }
    }

    /// u~(x) = u0(x) + sum_d w_d phi_d . eta~, u~'(x) = sum_d w_d phi_d . eta'~.
    fn predicted(&self, i: usize) -> (f64, f64) {
        let at = &self.locs[i];
        let (mut u, mut v) = (0.0, 0.0);
        for k in 0..2 {
            let (ud, vd) = self.dof_predicted(at.dofs[k]);
            u += at.weights[k] * (self.preload[at.dofs[k]] + ud);
            v += at.weights[k] * vd;
        }
        (u, v)
    }

    /// Centre u0(x) and radius sum_d w_d sqrt(sum_j phi_dj^2 / omega_j^2) * |eta~|_K, widened
    /// by 1e-9 relative (the dot product's roundoff is below n eps ~ 1e-13 of the radius).
    fn predicted_bound(&self, i: usize) -> Option<(f64, f64)> {
        if !self.bound_predictions {
            return None;
        }
        let at = &self.locs[i];
        let e = self.integrator.pred_strain_norm;
        let (mut centre, mut radius) = (0.0, 0.0);
        for k in 0..2 {
            let d = at.dofs[k];
            centre += at.weights[k] * self.preload[d];
            radius += at.weights[k].abs() * self.static_norm[d] * e;
        }
        radius
            .is_finite()
            .then_some((centre, radius * (1.0 + 1e-9)))
    }

    /// G_AA = T_AA = S_AA + R_AA, G_v,AA = gamma / (beta dt) S_AA (interpolated from the DOFs).
    fn compliance(&mut self, active: &[usize]) -> (DMatrix<f64>, DMatrix<f64>) {
        let na = active.len();
        let kv = self.integrator.velocity_factor();
        let (s, t) = &*self.step_compliance[self.current].2;
        let mut g = DMatrix::<f64>::zeros(na, na);
        let mut gv = DMatrix::<f64>::zeros(na, na);
        for a in 0..na {
            let la = &self.locs[active[a]];
            for b in a..na {
                let lb = &self.locs[active[b]];
                let sv = kv * Self::interpolate(s, la, lb);
                gv[(a, b)] = sv;
                gv[(b, a)] = sv;
                let tv = Self::interpolate(t, la, lb);
                g[(a, b)] = tv;
                g[(b, a)] = tv;
            }
        }
        (g, gv)
    }

    /// (G F)_i = sum_d w_id sum_e T_de F_e with the forces gathered on the DOFs,
    /// F_e = sum_k w_ke F_k.
    fn response(&self, active: &[usize], forces: &[f64]) -> Vec<f64> {
        self.apply_step_matrix(
            &self.step_compliance[self.current].2 .1,
            1.0,
            active,
            forces,
        )
    }

    /// (G_v F)_i = gamma / (beta dt) sum_d w_id sum_e S_de F_e (the residual flexibility
    /// responds quasi-statically: no velocity).
    fn velocity_response(&self, active: &[usize], forces: &[f64]) -> Vec<f64> {
        let kv = self.integrator.velocity_factor();
        self.apply_step_matrix(&self.step_compliance[self.current].2 .0, kv, active, forces)
    }
}

impl ModalStructure {
    /// scale * sum_d w_id sum_e X_de F_e at every location of this step, X a DOF-level step
    /// matrix (S or T, given transposed as `xt`) and the forces at `active` gathered on the
    /// DOFs. The sums over e are formed for the span of DOFs the locations use at once, as
    /// the sum over e of F_e times row e of `xt` (contiguous pieces of rows, vector
    /// operations; each DOF's terms added in the order of the gathered DOFs, from -0.0 as a
    /// float sum starts), and shared by the locations beside each DOF.
    fn apply_step_matrix(
        &self,
        xt: &Dense,
        scale: f64,
        active: &[usize],
        forces: &[f64],
    ) -> Vec<f64> {
        let gathered = gather_on_dofs(
            active
                .iter()
                .map(|&k| &self.locs[k])
                .zip(forces.iter().copied()),
        );
        // only the span of DOFs the locations use (one cylinder's, for a per-cylinder step)
        let (lo, hi) = self.locs.iter().fold((usize::MAX, 0), |(lo, hi), at| {
            (
                lo.min(at.dofs[0].min(at.dofs[1])),
                hi.max(at.dofs[0].max(at.dofs[1]) + 1),
            )
        });
        let mut at_dof = vec![-0.0; xt.nrows()];
        if lo < hi {
            for &(e, f) in &gathered {
                axpy(&mut at_dof[lo..hi], f, &row(xt, e)[lo..hi]);
            }
        }
        self.locs
            .iter()
            .map(|at| {
                let mut u = 0.0;
                for m in 0..2 {
                    u += at.weights[m] * at_dof[at.dofs[m]];
                }
                scale * u
            })
            .collect()
    }

    /// Impulses `impulses` [N s] at `locs` (outward on the liner, like contact forces),
    /// delivered over the next step ([`ModalIntegrator::impulse_over_next_step`]) as the modal
    /// impulses d_j = sum_k phi_kj dI_k.
    pub fn impulse(&mut self, locs: &[Location], impulses: &[f64]) {
        let d = self.modal_force_at(locs, impulses);
        self.integrator.impulse_over_next_step(&d);
    }
}

/// Forces at locations gathered on the contact DOFs, F_e = sum_k w_ke F_k (first-seen DOF
/// order; zero forces skipped).
fn gather_on_dofs<'a>(loads: impl Iterator<Item = (&'a Location, f64)>) -> Vec<(usize, f64)> {
    let mut gathered: Vec<(usize, f64)> = Vec::new();
    for (at, fk) in loads {
        if fk == 0.0 {
            continue;
        }
        for m in 0..2 {
            let e = at.dofs[m];
            match gathered.iter_mut().find(|(ee, _)| *ee == e) {
                Some(g) => g.1 += at.weights[m] * fk,
                None => gathered.push((e, at.weights[m] * fk)),
            }
        }
    }
    gathered
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::lu::tests::lcg;
    use crate::transient::scheme::Scheme;

    /// The interval of `predicted_bound` holds the exact prediction at every location, for
    /// modal states from rest to strongly excited, and is tight for a single mode (Cauchy-
    /// Schwarz is an equality when phi_d / omega is parallel to omega eta).
    #[test]
    fn predicted_bound_holds_the_exact_prediction() {
        let (ndof, n) = (9, 37);
        let mut st = 7u64;
        let omega: Vec<f64> = (0..n).map(|j| 2e3 + 1e3 * j as f64).collect();
        let mut integrator =
            ModalIntegrator::new(&omega, &vec![0.02; n], Scheme::average_acceleration());
        let rows =
            crate::linalg::dense::from_rows(ndof, n, (0..ndof * n).map(|_| lcg(&mut st)).collect());
        let preload: Vec<f64> = (0..ndof).map(|_| 1e-5 * lcg(&mut st)).collect();
        for j in 0..n {
            integrator.eta[j] = 1e-6 * lcg(&mut st);
            integrator.deta[j] = 1e-3 * lcg(&mut st);
        }
        let rflex = crate::linalg::dense::from_rows(ndof, ndof, vec![0.0; ndof * ndof]);
        let mut s = ModalStructure::new(integrator, rows, rflex, preload);
        let locs: Vec<Location> = (0..ndof - 1)
            .map(|d| {
                let t = 0.5 + 0.5 * lcg(&mut st);
                Location {
                    dofs: [d, d + 1],
                    weights: [1.0 - t, t],
                }
            })
            .collect();
        for dt in [1e-6, 2e-5, 1e-4] {
            s.integrator.predict(dt);
            s.prepare(&locs);
            for i in 0..locs.len() {
                let (u, _) = s.predicted(i);
                let (c, r) = s.predicted_bound(i).expect("all modes have omega > 0");
                assert!((u - c).abs() <= r, "location {i}: |{u} - {c}| > {r}");
                // not vacuous: the radius is within the modal displacement's order
                assert!(r < 1e3 * (u - c).abs().max(1e-12), "radius {r} at {i}");
            }
        }
        // one mode: the bound is attained
        let mut one = ModalIntegrator::new(&[3e3], &[0.0], Scheme::average_acceleration());
        one.eta[0] = 2e-6;
        let rows1 = crate::linalg::dense::from_rows(2, 1, vec![0.7, -0.3]);
        let zero = crate::linalg::dense::from_rows(2, 2, vec![0.0; 4]);
        let mut s1 = ModalStructure::new(one, rows1, zero, vec![0.0; 2]);
        s1.integrator.predict(1e-9);
        let at = [Location {
            dofs: [0, 1],
            weights: [1.0, 0.0],
        }];
        s1.prepare(&at);
        let (u, _) = s1.predicted(0);
        let (_, r) = s1.predicted_bound(0).expect("omega > 0");
        assert!((r - u.abs()).abs() <= 1e-8 * r, "{r} vs {u}");
    }
}
