//! The engine ROM as the contact sees it: system modes integrated by [`ModalIntegrator`], mode
//! rows at the contact DOFs (bore-line nodes of every modelled liner, outward radial), their
//! residual flexibility R and the head-bolt preload displacement u0.
//!
//! At a location x (two bore-line DOFs with weights w), phi_x = sum w phi_dof, and
//!   u(x) = u0(x) + phi_x . eta + sum_k R(x, x_k) F_k,
//!   G(x, y) = sum_j phi_xj D_j phi_yj + R(x, y),  G_v(x, y) = gamma / (beta dt) sum_j phi_xj D_j phi_yj.
//! The residual flexibility responds quasi-statically (no velocity). Per step the rows of the
//! step's locations are formed once; G of an active set is one matrix product.

use super::contact::{dot4, Location, Structure};
use super::scheme::ModalIntegrator;
use crate::reduce::engine::Dense;
use nalgebra::DMatrix;

/// ROM structure state of a transient.
pub struct ModalStructure {
    pub integrator: ModalIntegrator,
    /// Contact DOF rows (contact DOFs x modes), row-major.
    rows: Dense,
    rflex: Dense,
    preload: Vec<f64>,
    /// Whether the residual flexibility is used.
    pub static_correction: bool,
    // per-step data: locations, their mode rows, sqrt(D)
    locs: Vec<Location>,
    phi: Vec<f64>,
    sqrt_d: Vec<f64>,
    /// R between the step's locations, filled when first needed (NaN: not yet).
    rmemo: std::cell::RefCell<Vec<f64>>,
}

impl ModalStructure {
    /// `rows`: contact DOFs x modes; `rflex`: contact DOFs squared; `preload` per contact DOF.
    pub fn new(integrator: ModalIntegrator, rows: Dense, rflex: Dense, preload: Vec<f64>) -> Self {
        Self {
            integrator,
            rows,
            rflex,
            preload,
            static_correction: true,
            locs: Vec::new(),
            phi: Vec::new(),
            sqrt_d: Vec::new(),
            rmemo: std::cell::RefCell::new(Vec::new()),
        }
    }

    /// phi_x (modes) into `out`.
    fn row_into(&self, at: &Location, out: &mut [f64]) {
        let n = self.integrator.len();
        let r0 = self.rows.row(at.dofs[0]);
        let r1 = self.rows.row(at.dofs[1]);
        let (w0, w1) = (at.weights[0], at.weights[1]);
        for j in 0..n {
            out[j] = w0 * r0[j] + w1 * r1[j];
        }
    }

    /// Residual flexibility R(a, b) between two locations [m/N].
    pub fn rflex_at(&self, a: &Location, b: &Location) -> f64 {
        if !self.static_correction {
            return 0.0;
        }
        let mut s = 0.0;
        for i in 0..2 {
            for k in 0..2 {
                s += a.weights[i] * b.weights[k] * self.rflex.at(a.dofs[i], b.dofs[k]);
            }
        }
        s
    }

    /// R between prepared locations `i` and `k` (memoised per step).
    fn r_of(&self, i: usize, k: usize) -> f64 {
        if !self.static_correction {
            return 0.0;
        }
        let m = self.locs.len();
        let mut memo = self.rmemo.borrow_mut();
        let v = memo[i * m + k];
        if !v.is_nan() {
            return v;
        }
        let r = self.rflex_at(&self.locs[i], &self.locs[k]);
        memo[i * m + k] = r;
        memo[k * m + i] = r;
        r
    }

    fn phi_of(&self, i: usize) -> &[f64] {
        let n = self.integrator.len();
        &self.phi[i * n..(i + 1) * n]
    }

    /// Modal force sum_k phi_k F_k of forces at the prepared locations `idx`.
    pub fn modal_force(&self, idx: &[usize], forces: &[f64]) -> Vec<f64> {
        let n = self.integrator.len();
        let mut f = vec![0.0; n];
        for (&i, &fk) in idx.iter().zip(forces) {
            if fk == 0.0 {
                continue;
            }
            for (fj, pj) in f.iter_mut().zip(self.phi_of(i)) {
                *fj += pj * fk;
            }
        }
        f
    }

    /// Modal force sum_k phi_k F_k of forces at arbitrary locations.
    pub fn modal_force_at(&self, locs: &[Location], forces: &[f64]) -> Vec<f64> {
        let n = self.integrator.len();
        let mut f = vec![0.0; n];
        for (at, &fk) in locs.iter().zip(forces) {
            if fk == 0.0 {
                continue;
            }
            let r0 = self.rows.row(at.dofs[0]);
            let r1 = self.rows.row(at.dofs[1]);
            for j in 0..n {
                f[j] += (at.weights[0] * r0[j] + at.weights[1] * r1[j]) * fk;
            }
        }
        f
    }

    /// Mode rows of the point outputs times accelerations etc. use the rows directly; this is
    /// the preload plus modal displacement (no residual part) at a location.
    pub fn displacement(&self, at: &Location) -> f64 {
        let n = self.integrator.len();
        let mut row = vec![0.0; n];
        self.row_into(at, &mut row);
        let pre: f64 = (0..2)
            .map(|i| at.weights[i] * self.preload[at.dofs[i]])
            .sum();
        pre + dot4(&row, &self.integrator.eta)
    }
}

impl Structure for ModalStructure {
    fn prepare(&mut self, locs: &[Location]) {
        let n = self.integrator.len();
        let m = locs.len();
        self.locs = locs.to_vec();
        {
            let mut memo = self.rmemo.borrow_mut();
            memo.clear();
            memo.resize(m * m, f64::NAN);
        }
        self.phi.resize(m * n, 0.0);
        let mut phi = std::mem::take(&mut self.phi);
        for (i, at) in locs.iter().enumerate() {
            self.row_into(at, &mut phi[i * n..(i + 1) * n]);
        }
        self.phi = phi;
        self.sqrt_d.clear();
        self.sqrt_d
            .extend(self.integrator.compliance.iter().map(|d| d.sqrt()));
    }

    fn predicted(&self, i: usize) -> (f64, f64) {
        let at = &self.locs[i];
        let it = &self.integrator;
        let phi = self.phi_of(i);
        let pre =
            at.weights[0] * self.preload[at.dofs[0]] + at.weights[1] * self.preload[at.dofs[1]];
        (pre + dot4(phi, &it.pred), dot4(phi, &it.dpred))
    }

    fn compliance(&mut self, active: &[usize]) -> (DMatrix<f64>, DMatrix<f64>) {
        let n = self.integrator.len();
        let na = active.len();
        let kv = self.integrator.velocity_factor();
        // Psi_A (modes x active, one column per slice), S = Psi_A^T Psi_A (faer gemm)
        let psi =
            faer::Mat::<f64>::from_fn(n, na, |j, a| self.phi[active[a] * n + j] * self.sqrt_d[j]);
        let mut prod = faer::Mat::<f64>::zeros(na, na);
        faer::linalg::matmul::matmul(
            prod.as_mut(),
            faer::Accum::Replace,
            psi.transpose(),
            psi.as_ref(),
            1.0,
            faer::Par::Seq,
        );
        let s = DMatrix::<f64>::from_fn(na, na, |a, b| prod[(a, b)]);
        let gv = &s * kv;
        let mut g = s;
        if self.static_correction {
            for (a, &i) in active.iter().enumerate() {
                for (b, &k) in active.iter().enumerate() {
                    g[(a, b)] += self.r_of(i, k);
                }
            }
        }
        (g, gv)
    }

    fn response(&self, active: &[usize], forces: &[f64]) -> Vec<f64> {
        let mut f = self.modal_force(active, forces);
        for (fj, d) in f.iter_mut().zip(&self.integrator.compliance) {
            *fj *= d;
        }
        (0..self.locs.len())
            .map(|i| {
                let r: f64 = active
                    .iter()
                    .zip(forces)
                    .map(|(&k, &fk)| self.r_of(i, k) * fk)
                    .sum();
                dot4(self.phi_of(i), &f) + r
            })
            .collect()
    }
}
