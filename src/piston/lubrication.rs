//! The oil film on the skirt: squeeze and sliding pressure from the Reynolds equation, viscosity
//! from the film temperature (Vogel), asperity contact (Greenwood-Tripp) where the film is thin.
//!
//! **Film thickness.** Skirt slice i (centre x_i below the skirt top, height dx) at angle psi_j
//! from the thrust line (the contact law's samples, [`SAMPLE_DEG`], each standing for an arc
//! R dpsi of the skirt) is apart from the liner by
//!
//!   h_ij = o_ij - cos(psi_j) p_i,   o_ij = g_i (1 - cos psi_j) + (w / 2) sin^2 psi_j,
//!
//! p_i the slice's penetration at the thrust line (negative while apart; the liner's
//! displacement included), g_i its hot gap, w the ovality (as in [`super::skirt`]).
//!
//! **Reynolds, short-bearing form.** Along each sample line the pressure obeys the axial
//! Reynolds equation (circumferential pressure flow neglected: the skirt's 65 mm against its
//! arc),
//!
//!   d/dx (h^3 / (12 mu) dp/dx) = dh/dt + (U / 2) dh/dx,   p = 0 at the skirt's top and bottom,
//!
//! x downward along the skirt, U = z' the liner's velocity relative to the skirt along x (z'
//! the piston's upward axial velocity), dh/dt = -cos(psi_j) p'_i the squeeze. Cavitation by
//! the Reynolds (Swift-Stieber) condition, a complementarity problem: p >= 0 everywhere, and
//! where the film is cavitated (p = 0) the flow into a node does not exceed what its source
//! takes (`reynolds_condition`, [`Line::reynolds_pressure`]); at a rupture p and dp/dx go to zero together. Partial
//! flooding: a point whose gap is larger than the oil supply on the liner (`supply`) is not
//! wetted, so the film engages as the skirt closes to within the supply: with w the wetted
//! fraction ([`Film::wetting`]) the source is w times the squeeze and sliding terms and the
//! film's pressure is w P (an unwetted point holds none, so a line's pressure rises from zero
//! as it wets). Gaps below [`FILM_FLOOR`] enter the Reynolds term as the
//! floor, through a smooth maximum ([`Film::floored`]).
//!
//! Discretisation: the slice centres are the nodes; the three-point form
//!   [G_r (P_r - P_i) - G_l (P_i - P_l)] = m_i S_i,  G = h_f^3 / (12 mu_f d),  m_i = (d_l + d_r) / 2,
//! (d the node distances, the skirt edges half a slice from the end nodes, h_f the mean of the
//! face's nodes) is exact for a quadratic pressure, and each slice integrates the local
//! quadratic through its node and neighbours (exact for a parabolic pressure too), so a uniform
//! strip's squeeze force -mu L^3 h' / h^3 per unit width is reproduced to roundoff. A slice's
//! force toward the liner's normal (the thrust line) is
//!
//!   F_i = R dpsi sum_j cos(psi_j) int_slice p_j(x) dx.
//!
//! **Viscosity (Vogel).** mu(T) = a exp(b / (T + c)), T in deg C, at the film temperature, the
//! mean of the skirt's temperature at the slice and the liner's bore temperature.
//!
//! **Asperity contact (Greenwood-Tripp, `mixed`).** Where the film is thin the roughness peaks
//! touch: p_c = K E' F_5/2(h / sigma), K = (16 sqrt(2) pi / 15) (eta beta sigma)^2 sqrt(sigma /
//! beta), with F_n(lambda) = 1 / sqrt(2 pi) int_lambda^inf (s - lambda)^n exp(-s^2 / 2) ds, sigma
//! the composite roughness, eta beta sigma the roughness parameter, sigma / beta the asperity
//! slope parameter and 1 / E' = (1 - nu_1^2) / E_1 + (1 - nu_2^2) / E_2. The skirt is rigid in the
//! film (no elastohydrodynamics): where the gap closes (p_i > 0) the dry penalty law acts as well.

use nalgebra::DMatrix;
use std::sync::OnceLock;

pub use super::skirt::PSI_DEG as SAMPLE_DEG;

pub use crate::scene::spec::{Lubrication, OilSpec};

/// Vogel viscosity mu(T) = a exp(b / (T + c)), T in deg C.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vogel {
    /// a \[Pa s\].
    pub a: f64,
    /// b and c \[deg C\].
    pub b: f64,
    pub c: f64,
}

impl Vogel {
    /// Dynamic viscosity \[Pa s\] at `t_c` \[deg C\].
    pub fn at(&self, t_c: f64) -> f64 {
        self.a * (self.b / (t_c + self.c)).exp()
    }
}

/// Greenwood-Tripp asperity contact: p_c = K E' F_5/2(h / sigma).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GreenwoodTripp {
    /// Composite roughness sigma \[m\].
    pub sigma: f64,
    /// K E' \[Pa\].
    pub k_e: f64,
}

impl GreenwoodTripp {
    /// From sigma \[m\], the roughness parameter eta beta sigma, the slope parameter sigma / beta
    /// and the composite modulus E' \[Pa\].
    pub fn new(sigma: f64, eta_beta_sigma: f64, sigma_over_beta: f64, modulus: f64) -> Self {
        let k = 16.0 * 2f64.sqrt() * std::f64::consts::PI / 15.0
            * eta_beta_sigma.powi(2)
            * sigma_over_beta.sqrt();
        Self {
            sigma,
            k_e: k * modulus,
        }
    }

    /// Asperity pressure p_c \[Pa\] and its derivative dp_c/dh [Pa/m] at gap `h` \[m\]:
    /// dF_5/2/dlambda = -(5/2) F_3/2.
    pub fn pressure(&self, h: f64) -> (f64, f64) {
        let l = h / self.sigma;
        let t = gt_table();
        (
            self.k_e * t.value(l, 2),
            -2.5 * self.k_e * t.value(l, 1) / self.sigma,
        )
    }
}

/// F_n(lambda) = 1 / sqrt(2 pi) int_lambda^inf (s - lambda)^n exp(-s^2 / 2) ds of order
/// n = k - 1/2 (k = 1, 2, 3: F_1/2, F_3/2, F_5/2), by quadrature: with s = lambda + t^2 the
/// integrand 2 t^(2k) exp(-(lambda + t^2)^2 / 2) is smooth; composite Simpson with 1000
/// intervals on t in [0, T], lambda + T^2 = 12 (the tail is below 1e-31).
pub fn gt_integral(k: usize, lambda: f64) -> f64 {
    let top = (12.0 - lambda).max(0.0).sqrt();
    if top == 0.0 {
        return 0.0;
    }
    let m = 1000;
    let dt = top / m as f64;
    let f = |t: f64| 2.0 * t.powi(2 * k as i32) * (-(lambda + t * t).powi(2) / 2.0).exp();
    let mut s = f(0.0) + f(top);
    for i in 1..m {
        let w = if i % 2 == 1 { 4.0 } else { 2.0 };
        s += w * f(i as f64 * dt);
    }
    s * dt / 3.0 / (2.0 * std::f64::consts::PI).sqrt()
}

/// F_n(lambda) below lambda = -4, where the asperities are pressed in by more than four
/// standard deviations of their heights: with a = -lambda,
///
///   F_n = 1 / sqrt(2 pi) int_-a^inf (a + s)^n exp(-s^2 / 2) ds
///       = a^n sum_j C(n, 2j) (2j - 1)!! a^(-2j)   (the Gaussian's even moments),
///
/// an asymptotic series, summed to j = [`GT_DEEP_TERMS`]: at a = 4 it is within 8e-7 of the
/// integral for n <= 5/2 (against quadrature) and the part of the Gaussian below s = -a, which the series
/// counts and the integral does not, is 3e-5 of the mass with (a + s)^n small there. Its
/// derivative in lambda is -n F_(n-1) term by term (n C(n-1, 2j) = (n - 2j) C(n, 2j)), as
/// the tabulated range's is, so the pressure's slope matches its value below the table.
fn gt_deep(n: f64, lambda: f64) -> f64 {
    let a = -lambda;
    let (mut sum, mut binom, mut moment, mut power) = (0.0, 1.0, 1.0, a.powf(n));
    for j in 0..=GT_DEEP_TERMS {
        if j > 0 {
            let m = 2.0 * j as f64;
            binom *= (n - m + 2.0) * (n - m + 1.0) / ((m - 1.0) * m);
            moment *= m - 1.0;
            power /= a * a;
        }
        sum += binom * moment * power;
    }
    sum
}

/// Terms of [`gt_deep`]'s series beyond the first.
const GT_DEEP_TERMS: usize = 6;

/// F_1/2, F_3/2, F_5/2 tabulated on lambda in [-4, 8] (step 0.01), interpolated by cubic
/// Hermite with the exact slopes dF_n/dlambda = -n F_(n-1) (F_3/2 and F_5/2 only are
/// interpolated; F_1/2 gives F_3/2's slope).
struct GtTable {
    lo: f64,
    step: f64,
    f: [Vec<f64>; 3],
}

fn gt_table() -> &'static GtTable {
    static TABLE: OnceLock<GtTable> = OnceLock::new();
    TABLE.get_or_init(|| {
        let (lo, hi, step): (f64, f64, f64) = (-4.0, 8.0, 0.01);
        let n = ((hi - lo) / step).round() as usize + 1;
        let f = [1, 2, 3].map(|k| {
            (0..n)
                .map(|i| gt_integral(k, lo + i as f64 * step))
                .collect::<Vec<f64>>()
        });
        GtTable { lo, step, f }
    })
}

impl GtTable {
    /// F_(k+1/2) for `k` = 1 (F_3/2) or 2 (F_5/2) at `l`: 0 beyond the table's top, the
    /// asymptotic series [`gt_deep`] below its bottom.
    fn value(&self, l: f64, k: usize) -> f64 {
        let y = &self.f[k];
        let n = y.len();
        let x = (l - self.lo) / self.step;
        if x >= (n - 1) as f64 {
            return 0.0;
        }
        if x < 0.0 {
            return gt_deep(k as f64 + 0.5, l);
        }
        let i = (x.floor() as usize).min(n - 2);
        let t = x - i as f64;
        // dF_n/dl = -n F_(n-1), in table units
        let order = k as f64 + 0.5;
        let slope = |j: usize| -order * self.f[k - 1][j] * self.step;
        let (y0, y1, m0, m1) = (y[i], y[i + 1], slope(i), slope(i + 1));
        let t2 = t * t;
        let t3 = t2 * t;
        (2.0 * t3 - 3.0 * t2 + 1.0) * y0
            + (t3 - 2.0 * t2 + t) * m0
            + (-2.0 * t3 + 3.0 * t2) * y1
            + (t3 - t2) * m1
    }
}

/// A rigid film along one line: nodes at `x` (ascending) between edges `left` and `right`
/// (p = 0 there), with gap `h` and viscosity `mu` per node; its pressure solves the three-point
/// Reynolds form of the module docs for the source S = dh/dt + (U/2) dh/dx (a partly wetted
/// film weights the source, [`Film::wetting`]).
pub struct Line<'a> {
    pub x: &'a [f64],
    pub left: f64,
    pub right: f64,
    pub h: &'a [f64],
    pub mu: &'a [f64],
}

/// The line's tridiagonal system: lower/diagonal/upper and the node weights m_i.
struct Tri {
    lower: Vec<f64>,
    diag: Vec<f64>,
    upper: Vec<f64>,
    m: Vec<f64>,
    /// Face conductances G (n + 1: left edge, between nodes, right edge) and their distances.
    g: Vec<f64>,
    d: Vec<f64>,
}

impl Tri {
    /// The system with the nodes not `free` decoupled from their neighbours (their row and
    /// column reduced to the diagonal), so that with a zero right-hand side there they solve to
    /// P = 0 and the free nodes see them as p = 0 edges.
    fn decoupled(&self, free: &[bool]) -> Tri {
        let mut t = Tri {
            lower: self.lower.clone(),
            diag: self.diag.clone(),
            upper: self.upper.clone(),
            m: self.m.clone(),
            g: self.g.clone(),
            d: self.d.clone(),
        };
        let n = free.len();
        for i in (0..n).filter(|&i| !free[i]) {
            t.lower[i] = 0.0;
            t.upper[i] = 0.0;
            if i > 0 {
                t.upper[i - 1] = 0.0;
            }
            if i + 1 < n {
                t.lower[i + 1] = 0.0;
            }
        }
        t
    }
}

impl Line<'_> {
    fn n(&self) -> usize {
        self.x.len()
    }

    /// Distance from node i to its left (k = i) or right (k = i + 1) face's other end.
    fn distances(&self) -> Vec<f64> {
        node_distances(self.x, self.left, self.right)
    }

    /// Face k's film thickness and viscosity: the mean of its nodes' (a face to an edge takes
    /// its node's).
    fn face(&self, k: usize) -> (f64, f64) {
        let n = self.n();
        match (k.checked_sub(1), (k < n).then_some(k)) {
            (Some(a), Some(b)) => (
                0.5 * (self.h[a] + self.h[b]),
                0.5 * (self.mu[a] + self.mu[b]),
            ),
            (Some(a), None) | (None, Some(a)) => (self.h[a], self.mu[a]),
            (None, None) => unreachable!("a line has a node"),
        }
    }

    fn system(&self) -> Tri {
        let n = self.n();
        let d = self.distances();
        let g: Vec<f64> = (0..=n)
            .map(|k| {
                let (h, mu) = self.face(k);
                h.powi(3) / (12.0 * mu * d[k])
            })
            .collect();
        let mut t = Tri {
            lower: vec![0.0; n],
            diag: vec![0.0; n],
            upper: vec![0.0; n],
            m: vec![0.0; n],
            g,
            d,
        };
        for i in 0..n {
            t.m[i] = 0.5 * (t.d[i] + t.d[i + 1]);
            t.diag[i] = -(t.g[i] + t.g[i + 1]);
            if i > 0 {
                t.lower[i] = t.g[i];
            }
            if i + 1 < n {
                t.upper[i] = t.g[i + 1];
            }
        }
        t
    }

    /// Axial slope dh/dx at every node by the three-point form (one-sided at the ends), as
    /// weights on the node gaps: slope_i = sum_k w_ik h_k (at most three k).
    pub fn slope_weights(x: &[f64]) -> Vec<[(usize, f64); 3]> {
        let n = x.len();
        (0..n)
            .map(|i| {
                if n < 2 {
                    return [(i, 0.0); 3];
                }
                if i == 0 || i == n - 1 {
                    let (a, b) = if i == 0 { (0, 1) } else { (n - 2, n - 1) };
                    let w = 1.0 / (x[b] - x[a]);
                    return [(a, -w), (b, w), (i, 0.0)];
                }
                let (dl, dr) = (x[i] - x[i - 1], x[i + 1] - x[i]);
                [
                    (i - 1, -dr / (dl * (dl + dr))),
                    (i, (dr - dl) / (dl * dr)),
                    (i + 1, dl / (dr * (dl + dr))),
                ]
            })
            .collect()
    }

    /// Pressure at the nodes for the source `s` (before the clip at zero).
    pub fn pressure(&self, s: &[f64]) -> Vec<f64> {
        let t = self.system();
        let rhs: Vec<f64> = (0..self.n()).map(|i| t.m[i] * s[i]).collect();
        Factored::new(&t).solve(&rhs)
    }

    /// Pressure at the nodes for the source `s` under the Reynolds condition: the linear
    /// complementarity problem P >= 0, lambda = -(A P - m S) >= 0, P_i lambda_i = 0 (the
    /// module docs; solved as the film solves it, a fully wetted line).
    pub fn reynolds_pressure(&self, s: &[f64]) -> Vec<f64> {
        let t = self.system();
        let rhs: Vec<f64> = (0..self.n()).map(|i| t.m[i] * s[i]).collect();
        reynolds_condition(&t, &rhs).1
    }

    /// The force on each node's slice of the clipped pressure `p`: the integral over the
    /// slice [e_i, e_(i+1)] (edges half-way between nodes, the line's ends outside) of the
    /// quadratic through the node and its neighbours (the edges at p = 0).
    pub fn integrate(&self, p: &[f64]) -> Vec<f64> {
        integrate_with(&self.integration_weights(), p).collect()
    }

    /// The weights of [`Line::integrate`]: slice i's force is
    /// q_i0 p_(i-1) + q_i1 p_i + q_i2 p_(i+1) (p = 0 beyond the ends).
    fn integration_weights(&self) -> Vec<[f64; 3]> {
        integration_weights(self.x, self.left, self.right)
    }
}

/// The distances between consecutive nodes `x`, the line's ends `left` and `right` counted as
/// the outer neighbours (n + 1 of them).
fn node_distances(x: &[f64], left: f64, right: f64) -> Vec<f64> {
    let n = x.len();
    (0..=n)
        .map(|k| {
            let a = if k == 0 { left } else { x[k - 1] };
            let b = if k == n { right } else { x[k] };
            b - a
        })
        .collect()
}

/// [`Line::integration_weights`] of the nodes `x` between `left` and `right` (they depend on
/// the nodes only, not on the film).
fn integration_weights(x: &[f64], left: f64, right: f64) -> Vec<[f64; 3]> {
    let n = x.len();
    let d = node_distances(x, left, right);
    (0..n)
        .map(|i| {
            let el = if i == 0 {
                left
            } else {
                0.5 * (x[i - 1] + x[i])
            };
            let er = if i == n - 1 {
                right
            } else {
                0.5 * (x[i] + x[i + 1])
            };
            let (dl, dr) = (d[i], d[i + 1]);
            let (a, b) = (el - x[i], er - x[i]);
            let f = |pl: f64, p: f64, pr: f64| {
                let q2 = 2.0 * ((pr - p) / dr - (p - pl) / dl) / (dl + dr);
                let q1 = (pr - p) / dr - 0.5 * q2 * dr;
                p * (b - a) + q1 * (b * b - a * a) / 2.0 + q2 * (b.powi(3) - a.powi(3)) / 6.0
            };
            [f(1.0, 0.0, 0.0), f(0.0, 1.0, 0.0), f(0.0, 0.0, 1.0)]
        })
        .collect()
}

/// Applies integration weights `q` to `v`.
fn integrate_with<'a>(q: &'a [[f64; 3]], v: &'a [f64]) -> impl Iterator<Item = f64> + 'a {
    let n = v.len();
    (0..n).map(move |i| {
        let l = if i > 0 { v[i - 1] } else { 0.0 };
        let r = if i + 1 < n { v[i + 1] } else { 0.0 };
        q[i][0] * l + q[i][1] * v[i] + q[i][2] * r
    })
}

/// v <- s Q v in place: the integration weights `q` ([`Line::integration_weights`]) applied to
/// `v` (p = 0 beyond the ends) and scaled by `s`.
fn integrate_in_place(q: &[[f64; 3]], v: &mut [f64], s: f64) {
    let n = v.len();
    let mut prev = 0.0;
    for i in 0..n {
        let (cur, next) = (v[i], if i + 1 < n { v[i + 1] } else { 0.0 });
        v[i] = s * (q[i][0] * prev + q[i][1] * cur + q[i][2] * next);
        prev = cur;
    }
}

/// y <- y + a x.
fn axpy(y: &mut [f64], a: f64, x: &[f64]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += a * xi;
    }
}

/// A tridiagonal system factored once (Thomas; the system is diagonally dominant), solved for
/// several right-hand sides.
struct Factored {
    lower: Vec<f64>,
    den: Vec<f64>,
    c: Vec<f64>,
}

impl Factored {
    fn new(t: &Tri) -> Self {
        let n = t.diag.len();
        let mut den = vec![0.0; n];
        let mut c = vec![0.0; n];
        let mut prev = 0.0;
        for i in 0..n {
            den[i] = t.diag[i] - t.lower[i] * prev;
            c[i] = t.upper[i] / den[i];
            prev = c[i];
        }
        Self {
            lower: t.lower.clone(),
            den,
            c,
        }
    }

    fn solve(&self, rhs: &[f64]) -> Vec<f64> {
        let mut y = rhs.to_vec();
        self.sweep(&mut y, 0);
        y
    }

    /// Solves in place for the right-hand side in `y`, which is zero above row `first` (the
    /// forward sweep starts there): y_i <- (y_i - l_i y_(i-1)) / den_i, then
    /// y_i <- y_i - c_i y_(i+1).
    fn sweep(&self, y: &mut [f64], first: usize) {
        let n = y.len();
        let mut prev = 0.0;
        for i in first..n {
            y[i] = (y[i] - self.lower[i] * prev) / self.den[i];
            prev = y[i];
        }
        for i in (0..n.saturating_sub(1)).rev() {
            y[i] -= self.c[i] * y[i + 1];
        }
    }

    /// A^-1, column-major (column j at `j n..(j + 1) n`; A is symmetric, so row-major too):
    /// the solves of all unit vectors at once, row by row, each row's update a vector
    /// operation over the n columns (the same operations per entry as [`Factored::sweep`],
    /// without its chain of dependent divisions).
    fn inverse(&self) -> Vec<f64> {
        let n = self.den.len();
        let mut inv = vec![0.0; n * n];
        // forward: row i of L^-1 (the rows of the identity eliminated in turn)
        for i in 0..n {
            let (done, rest) = inv.split_at_mut(i * n);
            let row = &mut rest[..n];
            row[i] = 1.0;
            let (l, d) = (self.lower[i], self.den[i]);
            if i == 0 {
                row.iter_mut().for_each(|y| *y /= d);
            } else {
                for (y, &p) in row.iter_mut().zip(&done[(i - 1) * n..]) {
                    *y = (*y - l * p) / d;
                }
            }
        }
        // backward: row i -= c_i row i+1
        for i in (0..n.saturating_sub(1)).rev() {
            let (head, tail) = inv.split_at_mut((i + 1) * n);
            let c = self.c[i];
            for (y, &next) in head[i * n..].iter_mut().zip(&tail[..n]) {
                *y -= c * next;
            }
        }
        inv
    }
}

/// The Reynolds (Swift-Stieber) cavitation condition on one line, a linear complementarity
/// problem: with K = -A (the three-point system of the module docs, an M-matrix) and b = -r
/// (r = m S the right-hand side),
///
///   P >= 0,   lambda = K P - b >= 0,   P_i lambda_i = 0,
///
/// so the film holds no suction, and where it is cavitated (P_i = 0) the flow the pressure
/// drives into the node does not exceed the flow the source takes out of it (lambda_i >= 0;
/// the cavitated zone's own flow and the film's reformation are not modelled: the condition
/// is not mass-conserving, unlike the JFO theory). The cavitated set is found by the primal-dual
/// active-set iteration (Hintermueller, Ito and Kunisch): a free node whose pressure is
/// negative is cavitated, a cavitated node whose multiplier is negative is freed, until no
/// node changes; for an M-matrix it converges in finitely many passes (capped here at
/// 2n + 3, after which the last set's negative nodes are cavitated). The
/// pressure is continuous in the sources and the gaps, and its derivative changes only where
/// a node changes its set, where the pressure and its slope are already near zero (the smooth
/// rupture of the Reynolds condition), not across a whole line's suction as when the
/// unconstrained pressure is clipped (half-Sommerfeld).
///
/// Returns the factored system with the cavitated nodes decoupled (identity-like rows:
/// P_i = 0), the pressure and which nodes are free.
fn reynolds_condition(t: &Tri, r: &[f64]) -> (Factored, Vec<f64>, Vec<bool>) {
    let n = r.len();
    let mut free = vec![true; n];
    for _ in 0..=2 * n + 2 {
        let (lu, p) = solve_free(t, r, &free);
        let next: Vec<bool> = (0..n)
            .map(|i| {
                if free[i] {
                    p[i] >= 0.0
                } else {
                    // lambda_i = (K P - b)_i = r_i - (A P)_i, P_i = 0
                    let left = if i > 0 { t.lower[i] * p[i - 1] } else { 0.0 };
                    let right = p.get(i + 1).map_or(0.0, |&pr| t.upper[i] * pr);
                    r[i] - left - right <= 0.0
                }
            })
            .collect();
        if next == free {
            return (lu, p.into_iter().map(|v| v.max(0.0)).collect(), free);
        }
        free = next;
    }
    // not reached for an M-matrix: the last set with its negative nodes cavitated, so that
    // the returned set is the one the pressure (and the tangent) is solved on
    let (_, p) = solve_free(t, r, &free);
    for (f, v) in free.iter_mut().zip(&p) {
        *f &= *v >= 0.0;
    }
    let (lu, p) = solve_free(t, r, &free);
    (lu, p.into_iter().map(|v| v.max(0.0)).collect(), free)
}

/// The system `t` with the nodes not `free` decoupled ([`Tri::decoupled`]), factored, and its
/// solution for the right-hand side `r` on the free nodes (zero on the others).
fn solve_free(t: &Tri, r: &[f64], free: &[bool]) -> (Factored, Vec<f64>) {
    let lu = Factored::new(&t.decoupled(free));
    let rc: Vec<f64> = r
        .iter()
        .zip(free)
        .map(|(&v, &f)| if f { v } else { 0.0 })
        .collect();
    let p = lu.solve(&rc);
    (lu, p)
}

/// One sample line's data for the pressure and its derivatives: cos psi, how many sample lines
/// it stands for (1 or 2, [`mirrored_samples`]), the unweighted source dh/dt + (U/2) dh/dx, the
/// wetted fraction and its slope (w, dw/dh), and dh/dp (0 where the gap is floored) per node.
#[derive(Clone, Copy)]
struct Sample<'a> {
    c: f64,
    count: f64,
    raw: &'a [f64],
    wt: &'a [(f64, f64)],
    dh: &'a [f64],
}

/// Per node, the three-point weights (node, weight) of the gap's slope dh/dx
/// ([`Line::slope_weights`]).
type Slopes = [[(usize, f64); 3]];

/// The distinct sample angles psi >= 0 of [`SAMPLE_DEG`] with the number of sample lines each
/// stands for: the lines at +psi and -psi have the same gap (h depends on cos psi and sin^2
/// psi), source and weight cos psi, hence the same pressure and force, so each pair is solved
/// once and counted twice.
fn mirrored_samples() -> impl Iterator<Item = (f64, f64)> {
    SAMPLE_DEG.iter().filter(|&&d| d >= 0.0).map(|&d| {
        let mirrored = d > 0.0 && SAMPLE_DEG.contains(&-d);
        (d, if mirrored { 2.0 } else { 1.0 })
    })
}

/// The film of one piston's skirt (built once), SI.
#[derive(Clone, Debug)]
pub struct Film {
    pub model: Lubrication,
    /// Slice centres below the skirt top \[m\] and the skirt length \[m\].
    pub x: Vec<f64>,
    pub length: f64,
    /// Per slice: hot gap \[m\] and film viscosity \[Pa s\].
    pub gaps: Vec<f64>,
    pub mu: Vec<f64>,
    /// Ovality \[m\], arc per sample R dpsi \[m\], oil supply on the liner \[m\].
    pub ovality: f64,
    pub arc: f64,
    pub supply: f64,
    /// Smallest gap the Reynolds term sees \[m\] (below it the penalty law carries the load).
    pub floor: f64,
    pub asperity: Option<GreenwoodTripp>,
}

/// The film forces of one skirt side and their derivatives (n x n, over the side's slices).
#[derive(Clone, Debug)]
pub struct SideFilm {
    pub force: Vec<f64>,
    /// dF_i / dp_k and dF_i / dp'_k.
    pub d_pen: DMatrix<f64>,
    pub d_rate: DMatrix<f64>,
    /// Whether any point of the side is wetted or touched by asperities.
    pub engaged: bool,
}

/// Gaps below this are held at it in the Reynolds term \[m\] (smoothly, [`Film::floored`]): the
/// film's squeeze damping stays finite when the surfaces meet, where the penalty law takes the
/// load.
pub const FILM_FLOOR: f64 = 3e-6;

/// The floor's smoothing width is the floor over this ([`Film::floored`]).
pub const FLOOR_SMOOTHING: f64 = 3.0;

impl Film {
    /// The film of `skirt` (built from `spec`) with the oil `oil`: slice positions, the Vogel
    /// viscosity at each slice's film temperature (the mean of the skirt's there and the
    /// liner's), the arc R dpsi of each contact sample.
    pub fn new(
        skirt: &super::skirt::Skirt,
        spec: &super::skirt::SkirtSpec,
        oil: &crate::scene::spec::OilSpec,
    ) -> Self {
        let x: Vec<f64> = skirt
            .heights
            .iter()
            .map(|h| spec.top_above_pin - h)
            .collect();
        let mu = x
            .iter()
            .map(|xi| {
                let frac = xi / spec.length;
                let t = spec.skirt_top_temp_c
                    + (spec.skirt_bottom_temp_c - spec.skirt_top_temp_c) * frac;
                let [a, b, c] = oil.vogel;
                Vogel { a, b, c }.at(0.5 * (t + spec.liner_temp_c))
            })
            .collect();
        let dpsi = (SAMPLE_DEG[1] - SAMPLE_DEG[0]).to_radians();
        Self {
            model: oil.model,
            x,
            length: spec.length,
            gaps: skirt.gaps.clone(),
            mu,
            ovality: spec.ovality,
            arc: 0.5 * spec.bore * dpsi,
            supply: oil.supply,
            floor: FILM_FLOOR,
            asperity: oil.asperity.map(|g| {
                GreenwoodTripp::new(g.sigma, g.eta_beta_sigma, g.sigma_over_beta, g.modulus)
            }),
        }
    }

    /// Film forces on the consecutive slices `first..first + pen.len()` of one side at
    /// penetrations `pen` \[m\] and rates `rate` [m/s], the piston's upward velocity `dz` [m/s].
    pub fn side(&self, first: usize, pen: &[f64], rate: &[f64], dz: f64) -> SideFilm {
        self.side_over(first, (pen, rate, dz), mirrored_samples())
    }

    /// The side's film summed over the sample `lines` (angle in degrees, how many lines it
    /// stands for).
    fn side_over(
        &self,
        first: usize,
        (pen, rate, dz): (&[f64], &[f64], f64),
        lines: impl Iterator<Item = (f64, f64)>,
    ) -> SideFilm {
        let n = pen.len();
        let x = &self.x[first..first + n];
        let dx = self.slice_height();
        let (left, right) = (x[0] - 0.5 * dx, x[n - 1] + 0.5 * dx);
        let slope = Line::slope_weights(x);
        // the slices' integration weights depend on the nodes only: once per side
        let q = integration_weights(x, left, right);
        let mut out = SideFilm {
            force: vec![0.0; n],
            d_pen: DMatrix::zeros(n, n),
            d_rate: DMatrix::zeros(n, n),
            engaged: false,
        };
        for (deg, count) in lines {
            let (s, c) = deg.to_radians().sin_cos();
            let geo: Vec<f64> = (0..n)
                .map(|i| self.gaps[first + i] * (1.0 - c) + 0.5 * self.ovality * s * s - c * pen[i])
                .collect();
            if let Some(gt) = &self.asperity {
                out.engaged |= self.asperity_sample(gt, (c, count, &geo), &mut out);
            }
            let wt: Vec<(f64, f64)> = geo.iter().map(|&h| self.wetting(h)).collect();
            if wt.iter().all(|w| w.0 == 0.0) {
                continue;
            }
            out.engaged = true;
            let (h, dh): (Vec<f64>, Vec<f64>) = geo
                .iter()
                .map(|&g| {
                    let (hf, slope) = self.floored(g);
                    (hf, -c * slope)
                })
                .unzip();
            let line = Line {
                x,
                left,
                right,
                h: &h,
                mu: &self.mu[first..first + n],
            };
            let raw: Vec<f64> = (0..n)
                .map(|i| {
                    let sl: f64 = slope[i].iter().map(|&(k, w)| w * h[k]).sum();
                    -c * rate[i] + 0.5 * dz * sl
                })
                .collect();
            let sample = Sample {
                c,
                count,
                raw: &raw,
                wt: &wt,
                dh: &dh,
            };
            self.add_sample(&line, &sample, (&slope, &q, dz), &mut out);
        }
        out
    }

    /// The gap the Reynolds term sees, a smooth maximum of `g` and the floor f,
    ///   h = f + d ln(1 + exp((g - f) / d)),  d = f / [`FLOOR_SMOOTHING`],
    /// and dh/dg: h = g to within d e^(-(g - f) / d) above the floor (1e-4 of it 3 um above
    /// a 3 um floor), h = f + d ln 2 at the floor, and no kink for the step's Newton iteration
    /// to cycle on.
    ///
    /// Above z = (g - f) / d = 15, ln(1 + e^z) = z + ln(1 + e^-z) is taken as z + e^-z (its
    /// error below e^-2z / 2 = 5e-14 of d) and dh/dg = 1 / (1 + e^-z) as 1 - e^-z: one
    /// exponential, no logarithm, for the gaps of a film well clear of the floor.
    pub fn floored(&self, g: f64) -> (f64, f64) {
        let d = self.floor / FLOOR_SMOOTHING;
        let z = (g - self.floor) / d;
        if z > 40.0 {
            return (g, 1.0);
        }
        if z > 15.0 {
            let e = (-z).exp();
            return (self.floor + d * (z + e), 1.0 - e);
        }
        let e = z.exp();
        (self.floor + d * e.ln_1p(), e / (1.0 + e))
    }

    /// The wetted fraction w of a point with gap `h` and dw/dh: 1 up to the oil supply, a C1
    /// ramp 1 - (3 t^2 - 2 t^3), t = (h - supply) / (supply / 2), down to 0 at 1.5 times the
    /// supply (the film force stays continuous as the skirt closes in, so the step's Newton
    /// iteration has a solution to find).
    pub fn wetting(&self, h: f64) -> (f64, f64) {
        let band = 0.5 * self.supply;
        let t = (h - self.supply) / band;
        if t <= 0.0 {
            (1.0, 0.0)
        } else if t >= 1.0 {
            (0.0, 0.0)
        } else {
            (1.0 - t * t * (3.0 - 2.0 * t), -6.0 * t * (1.0 - t) / band)
        }
    }

    /// Whether a slice at thrust-line penetration `pen` \[m\] is wetted there (its gap -pen is
    /// within the wetting ramp's end, [`Film::wetting`]).
    pub fn wets(&self, pen: f64) -> bool {
        self.wetting(-pen).0 > 0.0
    }

    /// Adds one sample line's cavitated pressure force and its derivatives to `out`: the
    /// source S_i = w_i raw_i (w the wetted fraction, raw = dh/dt + (U/2) dh/dx), the pressure A P = m S under the Reynolds condition
    /// ([`reynolds_condition`]: P >= 0, free nodes F and cavitated nodes at P = 0), the force
    /// F = a Q diag(w) P (a = R dpsi cos psi, Q the slices' integration weights), and for a
    /// change dr = m dS - dA P of the system's right-hand side by one penetration or rate (three
    /// nodes at most), with the cavitated set held,
    ///
    ///   dF = B dr,   B = a Q diag(w o 1_F) A_F^-1,
    ///
    /// (A_F the system with the cavitated nodes decoupled), B formed once per line, column j
    /// from A_F^-1's column j, so that each derivative is a sum of at most three of B's columns.
    fn add_sample(
        &self,
        line: &Line<'_>,
        sample: &Sample<'_>,
        (slope, q, dz): (&Slopes, &[[f64; 3]], f64),
        out: &mut SideFilm,
    ) {
        let Sample {
            c, count, raw, wt, ..
        } = *sample;
        let n = raw.len();
        let t = line.system();
        let rhs: Vec<f64> = (0..n).map(|i| t.m[i] * wt[i].0 * raw[i]).collect();
        let (lu, p, free) = reynolds_condition(&t, &rhs);
        // the film's pressure where the point is wetted: w_i P_i (an unwetted point holds
        // none, so a line's pressure rises from zero as the skirt closes in)
        let wetted: Vec<f64> = p.iter().zip(wt).map(|(v, w)| w.0 * v).collect();
        let w = self.arc * c * count;
        for (i, f) in integrate_with(q, &wetted).enumerate() {
            out.force[i] += w * f;
        }
        // B, column-major: column j = a Q (keep o A_F^-1 e_j), keep_i = w_i on the free nodes
        // (a cavitated node's pressure stays zero while the set holds)
        let mut b = lu.inverse();
        for col in b.chunks_exact_mut(n) {
            for ((v, &f), wt) in col.iter_mut().zip(&free).zip(wt) {
                *v *= if f { wt.0 } else { 0.0 };
            }
            integrate_in_place(q, col, w);
        }
        let column = |j: usize| &b[j * n..(j + 1) * n];
        for k in 0..n {
            if wt[k].0 > 0.0 {
                axpy(
                    out.d_rate.column_mut(k).as_mut_slice(),
                    t.m[k] * (-c) * wt[k].0,
                    column(k),
                );
            }
            let mut target = out.d_pen.column_mut(k);
            let target = target.as_mut_slice();
            for (j, rj) in self.pen_rhs(k, line, (&t, &p), sample, (slope, dz)) {
                if rj != 0.0 {
                    axpy(target, rj, column(j));
                }
            }
            // the wetted fraction's own change at node k: P_k dw_k/dh (-c), integrated by the
            // rows of Q that reach node k
            if wt[k].1 != 0.0 {
                let e = p[k] * wt[k].1 * (-c);
                for i in k.saturating_sub(1)..(k + 2).min(n) {
                    let weight = q[i][1 + k - i];
                    target[i] += w * (weight * e);
                }
            }
        }
    }

    /// m dS - dA P of penetration k (nodes k-1, k, k+1): p_k moves the wetted fraction at k
    /// (dgeo/dp = -c), the slopes of the neighbours and the conductances of k's faces
    /// (through the floored gap).
    fn pen_rhs(
        &self,
        k: usize,
        line: &Line<'_>,
        (t, p): (&Tri, &[f64]),
        sample: &Sample<'_>,
        (slope, dz): (&[[(usize, f64); 3]], f64),
    ) -> [(usize, f64); 3] {
        let Sample { c, raw, wt, dh, .. } = *sample;
        let n = raw.len();
        let lo = k.saturating_sub(1);
        let hi = (k + 1).min(n - 1);
        // nodes lo..=hi (the third entry stays zero at a line's end)
        let mut r = [(k, 0.0); 3];
        for (e, i) in r.iter_mut().zip(lo..=hi) {
            e.0 = i;
        }
        let at = |i: usize| i - lo;
        r[at(k)].1 += t.m[k] * wt[k].1 * (-c) * raw[k];
        if dh[k] == 0.0 {
            return r;
        }
        for i in lo..=hi {
            for &(kk, wgt) in &slope[i] {
                if kk == k {
                    r[at(i)].1 += t.m[i] * wt[i].0 * 0.5 * dz * wgt * dh[k];
                }
            }
        }
        for face in [k, k + 1] {
            let (hf, _) = line.face(face);
            let both = face > 0 && face < n;
            let dhf = if both { 0.5 } else { 1.0 } * dh[k];
            let dg = 3.0 * t.g[face] / hf * dhf;
            // rows: G_r (P_r - P_i) - G_l (P_i - P_l), P = 0 beyond the ends
            let pa = face.checked_sub(1).map_or(0.0, |i| p[i]);
            let pb = if face < n { p[face] } else { 0.0 };
            if face > 0 {
                r[at(face - 1)].1 -= dg * (pb - pa);
            }
            if face < n {
                r[at(face)].1 += dg * (pb - pa);
            }
        }
        r
    }

    /// Adds one sample line's asperity forces (midpoint per slice) and their derivatives;
    /// returns whether any asperity carries load.
    fn asperity_sample(
        &self,
        gt: &GreenwoodTripp,
        (c, count, geo): (f64, f64, &[f64]),
        out: &mut SideFilm,
    ) -> bool {
        let n = geo.len();
        let mut any = false;
        for i in 0..n {
            let (pc, dpc) = gt.pressure(geo[i]);
            if pc == 0.0 {
                continue;
            }
            any = true;
            let w = self.arc * c * count * self.slice_height();
            out.force[i] += w * pc;
            out.d_pen[(i, i)] += w * dpc * (-c);
        }
        any
    }

    /// Height of one slice \[m\].
    fn slice_height(&self) -> f64 {
        self.length / self.x.len() as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Verification: the floored gap and its slope against the softplus they stand for,
    /// f + d ln(1 + e^z) and 1 / (1 + e^-z) evaluated directly, across the switch to the
    /// one-exponential form at z = 15 and the plain gap above z = 40. Tolerance: that form's
    /// truncation, e^-2z / 2 <= 5e-14 of d, plus a few roundings of h (4 eps |h|).
    #[test]
    fn verification_floored_gap_is_the_softplus() {
        let f = 3e-6;
        let d = f / FLOOR_SMOOTHING;
        let film = Film {
            model: Lubrication::Squeeze,
            x: vec![0.0],
            length: 1.0,
            gaps: vec![0.0],
            mu: vec![1.0],
            ovality: 0.0,
            arc: 1.0,
            supply: 1.0,
            floor: f,
            asperity: None,
        };
        for i in 0..=600 {
            let z = -10.0 + 0.1 * i as f64;
            let g = f + d * z;
            let (h, dh) = film.floored(g);
            let (h_ref, dh_ref) = (f + d * z.exp().ln_1p(), 1.0 / (1.0 + (-z).exp()));
            let tol = 5e-14 * d + 4.0 * f64::EPSILON * h_ref;
            assert!((h - h_ref).abs() <= tol, "z {z}: h {h:e} against {h_ref:e}");
            assert!(
                (dh - dh_ref).abs() <= 1e-13,
                "z {z}: dh/dg {dh} against {dh_ref}"
            );
        }
    }

    /// Verification: the mirrored samples stand for every sample line once (the contact law's
    /// angles are symmetric about the thrust line).
    #[test]
    fn verification_mirrored_samples_cover_every_line() {
        let total: f64 = mirrored_samples().map(|(_, k)| k).sum();
        assert_eq!(total, SAMPLE_DEG.len() as f64);
        for d in SAMPLE_DEG {
            assert!(SAMPLE_DEG.contains(&-d), "{d} deg has no mirror");
        }
    }

    /// Verification: a side's film from the mirrored samples (each pair solved once, counted
    /// twice) against every sample line solved on its own, forces and both derivative
    /// matrices, on a partly wetted, loaded side with sliding and asperity contact. Tolerance:
    /// the sums differ only in their order, 1e-12 of the largest entry.
    #[test]
    fn verification_mirrored_samples_equal_every_line_solved() {
        let n = 12;
        let film = Film {
            model: Lubrication::Mixed,
            x: (0..n).map(|i| 0.0025 + 0.005 * i as f64).collect(),
            length: 0.06,
            gaps: (0..n).map(|i| 20e-6 + 2e-6 * i as f64).collect(),
            mu: vec![0.01; n],
            ovality: 30e-6,
            arc: 0.5 * 0.13 * 15f64.to_radians(),
            supply: 20e-6,
            floor: FILM_FLOOR,
            asperity: Some(GreenwoodTripp::new(0.5e-6, 0.05, 0.01, 110e9)),
        };
        // the top slices close to the liner (some within a few um), the lower ones apart
        let pen: Vec<f64> = (0..n).map(|i| -2e-6 - 4e-6 * i as f64).collect();
        let rate: Vec<f64> = (0..n).map(|i| 0.02 - 0.003 * i as f64).collect();
        let all = SAMPLE_DEG.iter().map(|&d| (d, 1.0));
        let each = film.side_over(0, (&pen, &rate, 3.0), all);
        let mirrored = film.side(0, &pen, &rate, 3.0);
        assert!(each.engaged && mirrored.engaged);
        let close = |a: &[f64], b: &[f64], what: &str| {
            let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(scale > 0.0, "{what}: all zero");
            for (x, y) in a.iter().zip(b) {
                assert!(
                    (x - y).abs() <= 1e-12 * scale,
                    "{what}: {x:e} against {y:e}"
                );
            }
        };
        close(&each.force, &mirrored.force, "force");
        close(each.d_pen.as_slice(), mirrored.d_pen.as_slice(), "dF/dp");
        close(each.d_rate.as_slice(), mirrored.d_rate.as_slice(), "dF/dp'");
    }

    #[test]
    fn verification_factored_thomas_solves_a_small_system() {
        let t = Tri {
            lower: vec![0.0, 1.0, 1.0],
            diag: vec![-2.0, -2.0, -2.0],
            upper: vec![1.0, 1.0, 0.0],
            m: vec![1.0; 3],
            g: vec![],
            d: vec![],
        };
        let x = Factored::new(&t).solve(&[-1.0, 0.0, -1.0]);
        for v in x {
            assert!((v - 1.0).abs() < 1e-14);
        }
    }
}
