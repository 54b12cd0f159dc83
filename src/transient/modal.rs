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
//! phi_d . eta'~ (each once per DOF, shared by the slices beside it).

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
    /// Per step size and static-correction flag (key: dt bits, flag): S = Phi D Phi^T over
    /// the contact DOFs and T = S + R (T = S without the static correction).
    step_compliance: Vec<(u64, bool, Dense, Dense)>,
    /// Index into `step_compliance` of the current step.
    current: usize,
    // per-step data: locations, predictor (u, u') per DOF (NaN: not yet formed)
    locs: Vec<Location>,
    dof_pred: std::cell::RefCell<Vec<(f64, f64)>>,
    touched: std::cell::RefCell<Vec<usize>>,
}

impl ModalStructure {
    /// `rows`: contact DOFs x modes; `rflex`: contact DOFs squared; `preload` per contact DOF.
    pub fn new(integrator: ModalIntegrator, rows: Dense, rflex: Dense, preload: Vec<f64>) -> Self {
        let ndof = rows.rows;
        Self {
            integrator,
            rows,
            rflex,
            preload,
            static_correction: true,
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
        if let Some(k) = self.step_compliance.iter().position(|(b, sc, _, _)| {
            *sc == self.static_correction && (f64::from_bits(*b) - dt).abs() <= 1e-9 * dt
        }) {
            self.current = k;
            return;
        }
        let n = self.integrator.len();
        let ndof = self.rows.rows;
        let d = &self.integrator.compliance;
        let nm = self.rows.cols;
        // Psi = Phi sqrt(D) (DOFs x modes), S = Psi Psi^T
        let psi =
            faer::Mat::<f64>::from_fn(ndof, n, |r, j| self.rows.data[r * nm + j] * d[j].sqrt());
        let mut s = faer::Mat::<f64>::zeros(ndof, ndof);
        faer::linalg::matmul::matmul(
            s.as_mut(),
            faer::Accum::Replace,
            psi.as_ref(),
            psi.transpose(),
            1.0,
            faer::Par::Seq,
        );
        // a handful of step sizes at most (the base step and its halvings)
        if self.step_compliance.len() >= 8 {
            self.step_compliance.remove(0);
        }
        let s = Dense::from_mat(&s);
        let mut t = s.clone();
        if self.static_correction {
            for (tv, rv) in t.data.iter_mut().zip(&self.rflex.data) {
                *tv += rv;
            }
        }
        self.step_compliance
            .push((key, self.static_correction, s, t));
        self.current = self.step_compliance.len() - 1;
    }

    /// A DOF-level matrix `s` (S or T) between two locations, sum_{d,e} w_d w_e s_de.
    fn interpolate(s: &Dense, a: &Location, b: &Location) -> f64 {
        let mut v = 0.0;
        for i in 0..2 {
            let row = s.row(a.dofs[i]);
            v += a.weights[i] * (b.weights[0] * row[b.dofs[0]] + b.weights[1] * row[b.dofs[1]]);
        }
        v
    }

    /// Predictor (phi_d . eta~, phi_d . eta'~) at contact DOF `d`, memoised per step.
    fn dof_predicted(&self, d: usize) -> (f64, f64) {
        let mut memo = self.dof_pred.borrow_mut();
        if memo[d].0.is_nan() {
            let it = &self.integrator;
            let n = it.len();
            memo[d] = dot4_pair(&self.rows.row(d)[..n], &it.pred, &it.dpred);
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
                s += a.weights[i] * b.weights[k] * self.rflex.at(a.dofs[i], b.dofs[k]);
            }
        }
        s
    }

    /// Number of contact DOFs (bore-line nodes of every modelled liner).
    pub fn contact_dofs(&self) -> usize {
        self.rows.rows
    }

    /// Residual-flexibility displacement at contact DOF `d` of DOF forces `loads` (DOF, force),
    /// sum_e R_de F_e [m] (0 without the static correction).
    pub fn rflex_dot(&self, d: usize, loads: &[(usize, f64)]) -> f64 {
        if !self.static_correction {
            return 0.0;
        }
        let row = self.rflex.row(d);
        loads.iter().map(|&(e, f)| row[e] * f).sum()
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
            for (fj, &r) in f.iter_mut().zip(&self.rows.row(e)[..n]) {
                *fj += r * fe;
            }
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
                at.weights[i] * (self.preload[d] + dot4(&self.rows.row(d)[..n], eta))
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

    /// G_AA = T_AA = S_AA + R_AA, G_v,AA = gamma / (beta dt) S_AA (interpolated from the DOFs).
    fn compliance(&mut self, active: &[usize]) -> (DMatrix<f64>, DMatrix<f64>) {
        let na = active.len();
        let kv = self.integrator.velocity_factor();
        let (_, _, s, t) = &self.step_compliance[self.current];
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
        let t = &self.step_compliance[self.current].3;
        let gathered = gather_on_dofs(
            active
                .iter()
                .map(|&k| &self.locs[k])
                .zip(forces.iter().copied()),
        );
        self.locs
            .iter()
            .map(|at| {
                let mut u = 0.0;
                for m in 0..2 {
                    let row = t.row(at.dofs[m]);
                    u += at.weights[m] * gathered.iter().map(|&(e, f)| row[e] * f).sum::<f64>();
                }
                u
            })
            .collect()
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

/// (a . b, a . c) in one pass with four partial sums each; the body compiled for AVX2 when the
/// CPU has it (same operations in the same order, so the same result bit for bit).
fn dot4_pair(a: &[f64], b: &[f64], c: &[f64]) -> (f64, f64) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above).
            return unsafe { dot4_pair_avx2(a, b, c) };
        }
    }
    dot4_pair_body(a, b, c)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn dot4_pair_avx2(a: &[f64], b: &[f64], c: &[f64]) -> (f64, f64) {
    use std::arch::x86_64::{
        _mm256_add_pd, _mm256_loadu_pd, _mm256_mul_pd, _mm256_setzero_pd, _mm256_storeu_pd,
    };
    let n = a.len().min(b.len()).min(c.len());
    let m = n - n % 4;
    // lane k holds the partial sum of the elements k mod 4, as in `dot4_pair_body`
    let (mut s, mut t) = (_mm256_setzero_pd(), _mm256_setzero_pd());
    let mut i = 0;
    while i < m {
        // SAFETY: i + 4 <= m <= the length of each slice
        let x = _mm256_loadu_pd(a.as_ptr().add(i));
        s = _mm256_add_pd(s, _mm256_mul_pd(x, _mm256_loadu_pd(b.as_ptr().add(i))));
        t = _mm256_add_pd(t, _mm256_mul_pd(x, _mm256_loadu_pd(c.as_ptr().add(i))));
        i += 4;
    }
    let (mut sv, mut tv) = ([0.0; 4], [0.0; 4]);
    _mm256_storeu_pd(sv.as_mut_ptr(), s);
    _mm256_storeu_pd(tv.as_mut_ptr(), t);
    let (mut ss, mut tt) = (0.0, 0.0);
    for k in m..n {
        ss += a[k] * b[k];
        tt += a[k] * c[k];
    }
    (
        (sv[0] + sv[1]) + (sv[2] + sv[3]) + ss,
        (tv[0] + tv[1]) + (tv[2] + tv[3]) + tt,
    )
}

#[inline(always)]
fn dot4_pair_body(a: &[f64], b: &[f64], c: &[f64]) -> (f64, f64) {
    let n = a.len().min(b.len()).min(c.len());
    let (a, b, c) = (&a[..n], &b[..n], &c[..n]);
    let mut s = [0.0; 4];
    let mut t = [0.0; 4];
    for ((x, y), z) in a
        .chunks_exact(4)
        .zip(b.chunks_exact(4))
        .zip(c.chunks_exact(4))
    {
        for k in 0..4 {
            s[k] += x[k] * y[k];
            t[k] += x[k] * z[k];
        }
    }
    let (mut ss, mut tt) = (0.0, 0.0);
    for k in n - n % 4..n {
        ss += a[k] * b[k];
        tt += a[k] * c[k];
    }
    (
        (s[0] + s[1]) + (s[2] + s[3]) + ss,
        (t[0] + t[1]) + (t[2] + t[3]) + tt,
    )
}
