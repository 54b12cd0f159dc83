//! The engine ROM as the contact sees it: system modes integrated by [`ModalIntegrator`], mode
//! rows at the contact DOFs (bore-line nodes of every modelled liner, outward radial), their
//! residual flexibility R and the head-bolt preload displacement u0.
//!
//! At a location x (two bore-line DOFs with weights w), phi_x = sum w phi_dof, and
//!   u(x) = u0(x) + phi_x . eta + sum_k R(x, x_k) F_k,
//!   G(x, y) = sum_j phi_xj D_j phi_yj + R(x, y),  G_v(x, y) = gamma / (beta dt) sum_j phi_xj D_j phi_yj.
//! The residual flexibility responds quasi-statically (no velocity).

use super::contact::{Location, Structure};
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
}

impl ModalStructure {
    /// `rows`: contact DOFs x modes; `rflex`: contact DOFs squared; `preload` per contact DOF.
    pub fn new(
        integrator: ModalIntegrator,
        rows: Dense,
        rflex: Dense,
        preload: Vec<f64>,
    ) -> Self {
        Self {
            integrator,
            rows,
            rflex,
            preload,
            static_correction: true,
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

    fn rflex_at(&self, a: &Location, b: &Location) -> f64 {
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

    /// Modal force sum_k phi_k F_k of forces at locations.
    pub fn modal_force(&self, locs: &[Location], forces: &[f64]) -> Vec<f64> {
        let n = self.integrator.len();
        let mut f = vec![0.0; n];
        let mut row = vec![0.0; n];
        for (at, &fk) in locs.iter().zip(forces) {
            if fk == 0.0 {
                continue;
            }
            self.row_into(at, &mut row);
            for j in 0..n {
                f[j] += row[j] * fk;
            }
        }
        f
    }

    /// Preload plus modal displacement (no residual part) at a location.
    pub fn displacement(&self, at: &Location) -> f64 {
        let mut u = 0.0;
        for i in 0..2 {
            u += at.weights[i] * self.preload[at.dofs[i]];
        }
        let r0 = self.rows.row(at.dofs[0]);
        let r1 = self.rows.row(at.dofs[1]);
        let eta = &self.integrator.eta;
        for j in 0..eta.len() {
            u += (at.weights[0] * r0[j] + at.weights[1] * r1[j]) * eta[j];
        }
        u
    }
}

impl Structure for ModalStructure {
    fn predicted(&self, at: &Location) -> (f64, f64) {
        let it = &self.integrator;
        let r0 = self.rows.row(at.dofs[0]);
        let r1 = self.rows.row(at.dofs[1]);
        let (w0, w1) = (at.weights[0], at.weights[1]);
        let mut u = w0 * self.preload[at.dofs[0]] + w1 * self.preload[at.dofs[1]];
        let mut v = 0.0;
        for j in 0..it.len() {
            let p = w0 * r0[j] + w1 * r1[j];
            u += p * it.pred[j];
            v += p * it.dpred[j];
        }
        (u, v)
    }

    fn compliance(&self, locs: &[Location]) -> (DMatrix<f64>, DMatrix<f64>) {
        let n = self.integrator.len();
        let na = locs.len();
        let d = &self.integrator.compliance;
        // scaled rows psi = phi sqrt(D)
        let mut psi = vec![0.0; na * n];
        for (r, at) in locs.iter().enumerate() {
            let out = &mut psi[r * n..(r + 1) * n];
            self.row_into(at, out);
            for j in 0..n {
                out[j] *= d[j].sqrt();
            }
        }
        let kv = self.integrator.velocity_factor();
        let mut g = DMatrix::zeros(na, na);
        let mut gv = DMatrix::zeros(na, na);
        for a in 0..na {
            let pa = &psi[a * n..(a + 1) * n];
            for b in a..na {
                let pb = &psi[b * n..(b + 1) * n];
                let s: f64 = pa.iter().zip(pb).map(|(x, y)| x * y).sum();
                let r = self.rflex_at(&locs[a], &locs[b]);
                g[(a, b)] = s + r;
                g[(b, a)] = s + r;
                gv[(a, b)] = kv * s;
                gv[(b, a)] = kv * s;
            }
        }
        (g, gv)
    }

    fn response(&self, loaded: &[Location], forces: &[f64], at: &[Location]) -> Vec<f64> {
        let n = self.integrator.len();
        let mut f = self.modal_force(loaded, forces);
        for j in 0..n {
            f[j] *= self.integrator.compliance[j];
        }
        let mut row = vec![0.0; n];
        at.iter()
            .map(|x| {
                self.row_into(x, &mut row);
                let m: f64 = row.iter().zip(&f).map(|(a, b)| a * b).sum();
                let r: f64 = loaded
                    .iter()
                    .zip(forces)
                    .map(|(y, &fk)| self.rflex_at(x, y) * fk)
                    .sum();
                m + r
            })
            .collect()
    }
}
