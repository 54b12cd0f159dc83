//! One implicit step of rigid bodies (pistons, 2 DOF each) in penalty contact with a linear
//! structure, the structure condensed to the contact slices.
//!
//! Unknowns of the step: the body coordinates q (Newmark, average acceleration or the
//! scheme's beta, gamma) and the slice forces F. With the structure condensed,
//!   u = u~ + G F,   u' = u'~ + G_v F
//! (u~ the structure's predictor at the slices, G its compliance for this step), and a slice in
//! a fixed linear piece of its law, F = a + k_t p + c_d p' with p = s . q - g - u, the forces
//! of the active slices A solve
//!   W F_A = r0 + (K_t + kappa C_d) S q,   W = I + K_t G_AA + C_d G_v,AA,
//!   r0 = a - K_t (g + u~) + C_d (S v^ - kappa S q^ - u'~),  kappa = gamma / (beta dt),
//! and the bodies
//!   [M / (beta dt^2) - B^T W^-1 (K_t + kappa C_d) S] q = f_ext + M q^ / (beta dt^2) + B^T W^-1 r0.
//! Newton on the piecewise-linear contact: solve for the assumed pieces, recompute every
//! slice's penetration, repeat until no slice changes its piece (the exact solution of the
//! step). Only contact-sized systems are solved.
//!
//! HHT-alpha: the bodies' equation is taken at the same shifted time as the structure's,
//!   M a_{n+1} = (1 + alpha) (f_{n+1} + B^T F_{n+1}) - alpha (f_n + B^T F_n),
//! so the slice forces act on body and structure with the same weights (the momentum they
//! exchange balances step by step). The body's M / (beta dt^2) row then carries
//! (1 + alpha) B^T on the slice forces and -alpha times the total force of the last step
//! ([`Body::applied`]) on its right-hand side; alpha = 0 is Newmark exactly.

use super::scheme::Scheme;
use nalgebra::{DMatrix, DVector};

/// Where a slice touches the structure: up to two structure contact DOFs with weights
/// (linear interpolation along a bore line).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Location {
    pub dofs: [usize; 2],
    pub weights: [f64; 2],
}

/// The linear structure as the contact sees it during one step. [`Structure::prepare`] gets
/// the step's slice locations (after the structure's own predictor); the other methods refer
/// to them by index.
pub trait Structure {
    /// Sets the locations of this step.
    fn prepare(&mut self, locs: &[Location]);
    /// Predicted displacement and velocity at location `i` (no new contact force).
    fn predicted(&self, i: usize) -> (f64, f64);
    /// An interval (centre, radius) that holds the predicted displacement at location `i`,
    /// cheaper than [`Structure::predicted`]; `None` when the structure has no such bound.
    /// A slice whose penetration stays below its law's onset over the whole interval is apart
    /// without its exact prediction.
    fn predicted_bound(&self, _i: usize) -> Option<(f64, f64)> {
        None
    }
    /// Compliances G (displacement per force) and G_v (velocity per force) among `active`.
    fn compliance(&mut self, active: &[usize]) -> (DMatrix<f64>, DMatrix<f64>);
    /// Displacement at every location caused by the forces `forces` at `active`: G F.
    fn response(&self, active: &[usize], forces: &[f64]) -> Vec<f64>;
}

pub use crate::linalg::kernels::dot;

/// A slice that may touch during the step.
#[derive(Clone, Debug)]
pub struct Slice<'a> {
    pub body: usize,
    /// d p / d q of the body, and the generalised force per unit contact force.
    pub row: [f64; 2],
    pub force_row: [f64; 2],
    /// Penetration offset: p = row . q - gap - u.
    pub gap: f64,
    pub law: &'a crate::piston::skirt::SliceLaw,
    pub damping: f64,
    pub at: Location,
    /// Penetration at the previous step: the damper acts during this step when it was > 0
    /// (keeps the law continuous within the step, so the implicit step always has a solution;
    /// the damper engages at most one step late).
    pub prev_penetration: f64,
}

/// A body's Newmark state and this step's loads.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Body {
    pub mass: [[f64; 2]; 2],
    pub q: [f64; 2],
    pub v: [f64; 2],
    pub a: [f64; 2],
    /// External generalised force at the new time.
    pub force: [f64; 2],
    /// Total generalised force (external and contact) at the body's current time: the
    /// -alpha f_n term of HHT-alpha. Set it to the external force when starting from rest.
    pub applied: [f64; 2],
}

/// Result of one step.
#[derive(Clone, Debug)]
pub struct StepResult {
    pub bodies: Vec<Body>,
    /// Force of every slice (0 when apart) and its penetration.
    pub forces: Vec<f64>,
    pub penetrations: Vec<f64>,
    pub iterations: usize,
}

/// Why a step failed (the caller retries with a smaller step or reports).
#[derive(Clone, Debug, PartialEq)]
pub enum StepFailure {
    NoConvergence { iterations: usize },
    Singular,
}

/// Solves one step of size `dt` with the structure's `scheme` (Newmark beta, gamma; HHT alpha).
pub fn step(
    bodies: &[Body],
    slices: &[Slice<'_>],
    structure: &mut dyn Structure,
    dt: f64,
    scheme: Scheme,
    max_iterations: usize,
) -> Result<StepResult, StepFailure> {
    let Scheme { beta, gamma, alpha } = scheme;
    let nb = bodies.len();
    let nq = 2 * nb;
    let kappa = gamma / (beta * dt);
    let c_acc = 1.0 / (beta * dt * dt);
    // Newmark predictors of the bodies
    let qh: Vec<[f64; 2]> = bodies
        .iter()
        .map(|b| {
            let f = |k: usize| b.q[k] + dt * b.v[k] + dt * dt * (0.5 - beta) * b.a[k];
            [f(0), f(1)]
        })
        .collect();
    let vh: Vec<[f64; 2]> = bodies
        .iter()
        .map(|b| {
            let f = |k: usize| b.v[k] + dt * (1.0 - gamma) * b.a[k];
            [f(0), f(1)]
        })
        .collect();
    let locs: Vec<Location> = slices.iter().map(|s| s.at).collect();
    structure.prepare(&locs);
    // exact predictions where a slice may touch: at slices in contact or damped at the last
    // step, and wherever the penetration's upper bound (the structure's interval) reaches the
    // law's onset; the others are apart and keep that bound as their penetration
    let mut pred: Vec<Option<(f64, f64)>> = vec![None; slices.len()];
    let bounds: Vec<Option<(f64, f64)>> = slices
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let touching = s.prev_penetration > 0.0 || s.law.piece(s.prev_penetration).mask != 0;
            if touching {
                None
            } else {
                structure.predicted_bound(i)
            }
        })
        .collect();
    let threshold: Vec<f64> = slices.iter().map(|s| s.law.onset().min(0.0)).collect();
    // penetration of slice i at body coordinates qb and extra structure displacement `extra`
    let penetration = |i: usize,
                       qb: [f64; 2],
                       extra: f64,
                       pred: &mut [Option<(f64, f64)>],
                       structure: &dyn Structure| {
        let s = &slices[i];
        let base = s.row[0] * qb[0] + s.row[1] * qb[1] - s.gap;
        if pred[i].is_none() {
            if let Some((centre, radius)) = bounds[i] {
                let upper = base - (centre - radius) - extra;
                if upper <= threshold[i] {
                    return upper;
                }
            }
            pred[i] = Some(structure.predicted(i));
        }
        base - pred[i].expect("set above").0 - extra
    };
    // penetration of each slice without new contact forces: first guess of the pieces
    let dot = |r: [f64; 2], q: [f64; 2]| r[0] * q[0] + r[1] * q[1];
    let mut pen: Vec<f64> = (0..slices.len())
        .map(|i| penetration(i, qh[slices[i].body], 0.0, &mut pred, &*structure))
        .collect();
    let mut pieces: Vec<(u8, bool)> = slices
        .iter()
        .zip(&pen)
        .map(|(s, &p)| {
            // start from the previous step's piece (usually still right in sustained
            // contact); a slice the predictor finds penetrating starts in contact
            let prev = s.law.piece(s.prev_penetration).mask;
            let mask = if prev != 0 { prev } else { s.law.piece(p).mask };
            (mask, s.prev_penetration > 0.0)
        })
        .collect();
    let mut g_cache: Option<(Vec<usize>, DMatrix<f64>, DMatrix<f64>)> = None;
    for it in 1..=max_iterations {
        let active: Vec<usize> = (0..slices.len())
            .filter(|&i| pieces[i].0 != 0 || pieces[i].1)
            .collect();
        // (a slice with only its damper active carries F = c_d p' this step)
        let na = active.len();
        // compliance of the active set (reused while the set is unchanged)
        if g_cache.as_ref().is_none_or(|(a, _, _)| *a != active) {
            let (g, gv) = structure.compliance(&active);
            g_cache = Some((active.clone(), g, gv));
        }
        let (_, g, gv) = g_cache.as_ref().expect("set above");
        // linear pieces
        let mut kt = vec![0.0; na];
        let mut av = vec![0.0; na];
        let mut cd = vec![0.0; na];
        for (r, &i) in active.iter().enumerate() {
            let s = &slices[i];
            let piece = s.law.piece_of(pieces[i].0);
            kt[r] = piece.kt;
            av[r] = piece.a;
            cd[r] = if pieces[i].1 { s.damping } else { 0.0 };
        }
        // W and right-hand sides [r0 | (Kt + kappa Cd) S]
        let mut w = DMatrix::<f64>::identity(na, na);
        let mut rhs = DMatrix::<f64>::zeros(na, 1 + nq);
        for (r, &i) in active.iter().enumerate() {
            let s = &slices[i];
            for (c2, _) in active.iter().enumerate() {
                w[(r, c2)] += kt[r] * g[(r, c2)] + cd[r] * gv[(r, c2)];
            }
            let (u, du) = pred[i].expect("active slices have their prediction");
            let b = s.body;
            rhs[(r, 0)] = av[r] - kt[r] * (s.gap + u)
                + cd[r] * (dot(s.row, vh[b]) - kappa * dot(s.row, qh[b]) - du);
            let f = kt[r] + kappa * cd[r];
            rhs[(r, 1 + 2 * b)] = f * s.row[0];
            rhs[(r, 2 + 2 * b)] = f * s.row[1];
        }
        let sol = if na > 0 {
            w.lu().solve(&rhs).ok_or(StepFailure::Singular)?
        } else {
            rhs.clone()
        };
        // body system
        let mut a = DMatrix::<f64>::zeros(nq, nq);
        let mut bvec = DVector::<f64>::zeros(nq);
        for (k, body) in bodies.iter().enumerate() {
            for i in 0..2 {
                for j in 0..2 {
                    a[(2 * k + i, 2 * k + j)] = body.mass[i][j] * c_acc;
                    bvec[2 * k + i] += body.mass[i][j] * c_acc * qh[k][j];
                }
                bvec[2 * k + i] += (1.0 + alpha) * body.force[i] - alpha * body.applied[i];
            }
        }
        for (r, &i) in active.iter().enumerate() {
            let s = &slices[i];
            let row = 2 * s.body;
            for d in 0..2 {
                let fr = (1.0 + alpha) * s.force_row[d];
                bvec[row + d] += fr * sol[(r, 0)];
                for col in 0..nq {
                    a[(row + d, col)] -= fr * sol[(r, 1 + col)];
                }
            }
        }
        let q = a.lu().solve(&bvec).ok_or(StepFailure::Singular)?;
        // forces of the active slices, new displacements and penetrations
        let mut fa = vec![0.0; na];
        for r in 0..na {
            fa[r] = sol[(r, 0)] + (0..nq).map(|c| sol[(r, 1 + c)] * q[c]).sum::<f64>();
        }
        let mut forces = vec![0.0; slices.len()];
        for (r, &i) in active.iter().enumerate() {
            forces[i] = fa[r];
        }
        // displacement at every slice includes the compliance to the active forces
        let extra = if na > 0 {
            structure.response(&active, &fa)
        } else {
            vec![0.0; slices.len()]
        };
        // new pieces; after many iterations change only the most violated slice per
        // iteration (guards against cycling of the piecewise-linear Newton)
        let mut worst: Option<(usize, f64)> = None;
        let mut changes = Vec::new();
        for i in 0..slices.len() {
            let s = &slices[i];
            let qb = [q[2 * s.body], q[2 * s.body + 1]];
            pen[i] = penetration(i, qb, extra[i], &mut pred, &*structure);
            let mask = s.law.piece(pen[i]).mask;
            if mask != pieces[i].0 {
                let v = pen[i].abs();
                changes.push((i, mask));
                if worst.is_none_or(|(_, w)| v > w) {
                    worst = Some((i, v));
                }
            }
        }
        let changed = !changes.is_empty();
        if it <= max_iterations / 3 {
            for (i, mask) in changes {
                pieces[i].0 = mask;
            }
        } else if let Some((i, _)) = worst {
            pieces[i].0 = slices[i].law.piece(pen[i]).mask;
        }
        if !changed {
            let mut out = Vec::with_capacity(nb);
            for (k, body) in bodies.iter().enumerate() {
                let mut b = *body;
                for d in 0..2 {
                    let qn = q[2 * k + d];
                    let an = (qn - qh[k][d]) * c_acc;
                    b.q[d] = qn;
                    b.a[d] = an;
                    b.v[d] = vh[k][d] + gamma * dt * an;
                }
                b.applied = body.force;
                out.push(b);
            }
            for (r, &i) in active.iter().enumerate() {
                let s = &slices[i];
                for d in 0..2 {
                    out[s.body].applied[d] += s.force_row[d] * fa[r];
                }
            }
            return Ok(StepResult {
                bodies: out,
                forces,
                penetrations: pen,
                iterations: it,
            });
        }
    }
    Err(StepFailure::NoConvergence {
        iterations: max_iterations,
    })
}
