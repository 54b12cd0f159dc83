//! The full-order reference structure: Newmark/HHT-alpha on the full coupled FE model (no modal
//! truncation), condensed to the contact like the ROM.
//!
//! HHT-alpha (alpha = 0: average acceleration) enforces
//!   M a1 + (1 + alpha)(C v1 + K u1) - alpha (C v0 + K u0) = (1 + alpha) F1 - alpha F0
//! with the Newmark updates u1 = u^ + beta h^2 a1, v1 = v^ + gamma h a1, the predictors
//! u^ = u0 + h v0 + h^2 (1/2 - beta) a0, v^ = v0 + h (1 - gamma) a0, and Rayleigh damping
//! C = a M + b K. With kappa = gamma / (beta h) and w = kappa u^ - v^, the step's displacement
//! about the preload state solves
//!   K_eff u1 = (1 + alpha) F1 - alpha F0 + M (u^ / (beta h^2) + (1 + alpha) a w + alpha a v0)
//!              + K ((1 + alpha) b w + alpha (b v0 + u0)),
//!   K_eff = (1 + alpha)(1 + kappa b) K + (1 / (beta h^2) + (1 + alpha) kappa a) M,
//! then a1 = (u1 - u^) / (beta h^2), v1 = v^ + kappa (u1 - u^). K_eff is factorised once
//! (sparse Cholesky on the model's analysis). The contact forces act along the bore-line rows B
//! (outward radial), so u1 = u* + (1 + alpha) X F1 with u* the step without new contact force
//! (it holds the -alpha X F0 of the last step's forces) and X = K_eff^-1 B solved once for all
//! contact DOFs: the contact sees G = (1 + alpha) B^T X and G_v = kappa G exactly, and each step
//! costs one sparse solve.

use super::contact::{Location, Structure};
use super::scheme::Scheme;
use super::window::Liner;
use crate::linalg::factor::{FactorError, Llt};
use crate::reduce::full::FullSystem;
use faer::Mat;
use nalgebra::DMatrix;

/// A sparse row over the full model's unknowns.
pub type Row = Vec<(usize, f64)>;

fn dot(row: &Row, x: &[f64]) -> f64 {
    row.iter().map(|&(k, v)| v * x[k]).sum()
}

/// Full-order structure state of a window.
pub struct FullLiner<'a> {
    sys: &'a FullSystem,
    llt: Llt<'a>,
    beta: f64,
    gamma: f64,
    alpha: f64,
    dt: f64,
    rayleigh: (f64, f64),
    u: Vec<f64>,
    v: Vec<f64>,
    acc: Vec<f64>,
    u_hat: Vec<f64>,
    v_hat: Vec<f64>,
    u_star: Vec<f64>,
    contact: Vec<Row>,
    points: Vec<Row>,
    /// Preload displacement at the contact DOFs [m].
    preload: Vec<f64>,
    /// K_eff^-1 B (unknowns x contact DOFs) and G = B^T X (contact DOFs squared, row-major).
    x: Mat<f64>,
    g: Vec<f64>,
    uc: Vec<f64>,
    vc: Vec<f64>,
    locs: Vec<Location>,
    /// Contact forces of the last step at the contact DOFs (the -alpha F0 term).
    f_prev: Vec<f64>,
}

impl<'a> FullLiner<'a> {
    /// Factorises K_eff for the fixed step `dt` and solves the contact columns.
    /// `contact`: rows of the contact DOFs (thrust bore-line nodes, then anti-thrust), outward
    /// radial; `points`: rows of the analysis points; `preload` at the contact DOFs.
    pub fn new(
        sys: &'a FullSystem,
        contact: Vec<Row>,
        points: Vec<Row>,
        preload: Vec<f64>,
        scheme: Scheme,
        dt: f64,
        rayleigh: (f64, f64),
    ) -> Result<Self, FactorError> {
        let Scheme { beta, gamma, alpha } = scheme;
        let kappa = gamma / (beta * dt);
        let ck = (1.0 + alpha) * (1.0 + kappa * rayleigh.1);
        let cm = 1.0 / (beta * dt * dt) + (1.0 + alpha) * kappa * rayleigh.0;
        let values: Vec<f64> = sys
            .km
            .k
            .iter()
            .zip(&sys.km.m)
            .map(|(k, m)| ck * k + cm * m)
            .collect();
        let llt = sys.analysis.llt(&sys.km.pattern, &values)?;
        drop(values);
        let n = sys.dofs();
        let nc = contact.len();
        let mut x = Mat::<f64>::zeros(n, nc);
        for (j, row) in contact.iter().enumerate() {
            for &(k, v) in row {
                x[(k, j)] += v;
            }
        }
        {
            use rayon::prelude::*;
            // column blocks on both cores (each block's arithmetic independent of the split)
            x.as_mut()
                .par_col_chunks_mut(64)
                .for_each(|block| llt.solve_in_place(block));
        }
        let mut g = vec![0.0; nc * nc];
        for (i, row) in contact.iter().enumerate() {
            for j in 0..nc {
                g[i * nc + j] =
                    (1.0 + alpha) * row.iter().map(|&(k, v)| v * x[(k, j)]).sum::<f64>();
            }
        }
        Ok(Self {
            sys,
            llt,
            beta,
            gamma,
            alpha,
            dt,
            rayleigh,
            u: vec![0.0; n],
            v: vec![0.0; n],
            acc: vec![0.0; n],
            u_hat: vec![0.0; n],
            v_hat: vec![0.0; n],
            u_star: vec![0.0; n],
            contact,
            points,
            preload,
            x,
            g,
            uc: vec![0.0; nc],
            vc: vec![0.0; nc],
            locs: Vec::new(),
            f_prev: vec![0.0; nc],
        })
    }

    fn kappa(&self) -> f64 {
        self.gamma / (self.beta * self.dt)
    }

    /// G between two locations.
    fn g_at(&self, a: &Location, b: &Location) -> f64 {
        let nc = self.contact.len();
        let mut s = 0.0;
        for i in 0..2 {
            for k in 0..2 {
                s += a.weights[i] * b.weights[k] * self.g[a.dofs[i] * nc + b.dofs[k]];
            }
        }
        s
    }
}

impl Structure for FullLiner<'_> {
    fn prepare(&mut self, locs: &[Location]) {
        self.locs = locs.to_vec();
    }

    fn predicted(&self, i: usize) -> (f64, f64) {
        let at = &self.locs[i];
        let (mut u, mut v) = (0.0, 0.0);
        for k in 0..2 {
            let d = at.dofs[k];
            u += at.weights[k] * (self.preload[d] + self.uc[d]);
            v += at.weights[k] * self.vc[d];
        }
        (u, v)
    }

    fn compliance(&mut self, active: &[usize]) -> (DMatrix<f64>, DMatrix<f64>) {
        let g = DMatrix::from_fn(active.len(), active.len(), |a, b| {
            self.g_at(&self.locs[active[a]], &self.locs[active[b]])
        });
        let gv = &g * self.kappa();
        (g, gv)
    }

    /// G_v F = kappa G F (the full model's step compliance has no quasi-static part).
    fn velocity_response(&self, active: &[usize], forces: &[f64]) -> Vec<f64> {
        let k = self.kappa();
        let mut u = self.response(active, forces);
        u.iter_mut().for_each(|x| *x *= k);
        u
    }

    fn response(&self, active: &[usize], forces: &[f64]) -> Vec<f64> {
        self.locs
            .iter()
            .map(|at| {
                active
                    .iter()
                    .zip(forces)
                    .map(|(&k, &f)| self.g_at(at, &self.locs[k]) * f)
                    .sum()
            })
            .collect()
    }
}

impl Liner for FullLiner<'_> {
    fn predict(&mut self, dt: f64) {
        debug_assert!((dt - self.dt).abs() <= 1e-12 * self.dt, "fixed step");
        let (h, beta, gamma, alpha) = (self.dt, self.beta, self.gamma, self.alpha);
        let kappa = self.kappa();
        let (ra, rb) = self.rayleigh;
        let n = self.u.len();
        let mut ms = vec![0.0; n];
        let mut kw = vec![0.0; n];
        for i in 0..n {
            let uh = self.u[i] + h * self.v[i] + h * h * (0.5 - beta) * self.acc[i];
            let vh = self.v[i] + h * (1.0 - gamma) * self.acc[i];
            self.u_hat[i] = uh;
            self.v_hat[i] = vh;
            let w = kappa * uh - vh;
            ms[i] = uh / (beta * h * h) + (1.0 + alpha) * ra * w + alpha * ra * self.v[i];
            kw[i] = (1.0 + alpha) * rb * w + alpha * (rb * self.v[i] + self.u[i]);
        }
        let p = &self.sys.km.pattern;
        let mut rhs = vec![0.0; n];
        p.matvec(&self.sys.km.m, &ms, &mut rhs);
        p.matvec(&self.sys.km.k, &kw, &mut ms);
        for (r, k) in rhs.iter_mut().zip(&ms) {
            *r += k;
        }
        self.llt.solve_vec(&mut rhs);
        if alpha != 0.0 {
            // -alpha F0: the last step's contact forces through X = K_eff^-1 B
            for (j, &f) in self.f_prev.iter().enumerate() {
                if f != 0.0 {
                    let col = self.x.col(j);
                    for i in 0..n {
                        rhs[i] -= alpha * col[i] * f;
                    }
                }
            }
        }
        self.u_star = rhs;
        for (d, row) in self.contact.iter().enumerate() {
            let us = dot(row, &self.u_star);
            self.uc[d] = us;
            self.vc[d] = dot(row, &self.v_hat) + kappa * (us - dot(row, &self.u_hat));
        }
    }

    fn commit(&mut self, locs: &[Location], forces: &[f64]) {
        let nc = self.contact.len();
        let mut fd = vec![0.0; nc];
        for (at, &f) in locs.iter().zip(forces) {
            for k in 0..2 {
                fd[at.dofs[k]] += at.weights[k] * f;
            }
        }
        let (h, beta, gamma, alpha) = (self.dt, self.beta, self.gamma, self.alpha);
        let n = self.u.len();
        let mut u = std::mem::take(&mut self.u_star);
        for (j, &f) in fd.iter().enumerate() {
            if f != 0.0 {
                let col = self.x.col(j);
                for i in 0..n {
                    u[i] += (1.0 + alpha) * col[i] * f;
                }
            }
        }
        self.f_prev = fd;
        for i in 0..n {
            let a = (u[i] - self.u_hat[i]) / (beta * h * h);
            self.acc[i] = a;
            self.v[i] = self.v_hat[i] + gamma * h * a;
        }
        self.u = u;
    }

    fn point_accelerations(&self) -> Vec<f64> {
        self.points.iter().map(|r| dot(r, &self.acc)).collect()
    }
}
