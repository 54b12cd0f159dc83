//! One piston slapping one liner over a short crank-angle window, on any structure that can
//! step itself: the ROM (modal coordinates) or the full-order FE model. The two share the
//! piston, the slices, the contact law and the step solver ([`super::contact::step`]), so the
//! difference of their results is the difference of the structural models.
//!
//! The window starts with the structure at rest in its preload state and the piston centred
//! with zero velocity (its acceleration from the loads at the start); the step is fixed. The
//! onset correction of the engine cycle ([`super::contact::onset_impulses`]) needs a structure
//! that takes impulses: the ROM does, the full-order model does not, so ROM-against-full
//! comparisons run both without it.

use super::contact::{self, dot, Body, Location, Structure};
use super::cycle::{push_slices, BoreLines, PistonInBore, TransientError};
use super::modal::ModalStructure;
use super::scheme::Scheme;
use crate::linalg::dense::{from_row_vecs, row, Dense};
use crate::piston::Piston;
use nalgebra::DMatrix;

/// A structure that integrates itself: the contact's view ([`Structure`]) plus the step.
pub trait Liner: Structure {
    /// Starts a step of `dt`: the predictor without new contact forces.
    fn predict(&mut self, dt: f64);
    /// Completes the step with the contact `forces` (outward radial on the liner, N) at `locs`.
    fn commit(&mut self, locs: &[Location], forces: &[f64]);
    /// Radial accelerations of the analysis points [m/s^2], + toward the coolant.
    fn point_accelerations(&self) -> Vec<f64>;
    /// Quasi-static point displacement of the contact forces not in
    /// [`Liner::point_accelerations`] (a ROM's residual flexibility R_pc F); its acceleration
    /// is added by differencing the series. Empty when the structure has none.
    fn point_residual(&self, _locs: &[Location], _forces: &[f64]) -> Vec<f64> {
        Vec::new()
    }
    /// Takes contact-onset impulses at `locs` over the next step
    /// ([`super::contact::onset_impulses`]); false when the structure cannot (then the window
    /// runs without the onset correction).
    fn impulse(&mut self, _locs: &[Location], _impulses: &[f64]) -> bool {
        false
    }
}

/// The crank-angle window and the piston's bore.
#[derive(Clone, Debug)]
pub struct Window {
    /// The cylinder's own crank angles [deg] (firing TDC at 360).
    pub start_deg: f64,
    pub end_deg: f64,
    pub step_deg: f64,
    /// Crank speed [rad/s].
    pub omega: f64,
    pub scheme: Scheme,
    pub liner_top: f64,
    /// Bore-line node heights (ascending); contact DOFs are the thrust nodes then the
    /// anti-thrust nodes, from 0.
    pub thrust_z: Vec<f64>,
    pub antithrust_z: Vec<f64>,
    pub max_newton: usize,
    pub max_penetration: f64,
    /// Restore the damper impulse missed at contact onsets, as the engine cycle does (only
    /// where the structure takes impulses: [`Liner::impulse`]).
    pub onset_correction: bool,
}

/// What the window produced, one entry per step.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct WindowResult {
    pub crank_angle_deg: Vec<f64>,
    /// Analysis-point accelerations (points x steps) [m/s^2].
    #[serde(serialize_with = "crate::linalg::dense::serialize_rows")]
    pub acceleration: Dense,
    pub lateral_m: Vec<f64>,
    pub tilt_rad: Vec<f64>,
    /// Net contact force toward thrust (thrust minus anti-thrust side) [N].
    pub contact_force_n: Vec<f64>,
    pub newton_iterations: usize,
    /// Wall time of the stepping [s].
    pub seconds: f64,
}

/// The piston at rest, centred, at its own crank angle `deg`: acceleration from the loads.
pub fn body_at_rest(piston: &Piston, deg: f64) -> Body {
    let mass = piston.mass_matrix();
    let f = piston.loads(deg).force;
    let det = mass[0][0] * mass[1][1] - mass[0][1] * mass[1][0];
    Body {
        mass,
        a: [
            (mass[1][1] * f[0] - mass[0][1] * f[1]) / det,
            (mass[0][0] * f[1] - mass[1][0] * f[0]) / det,
        ],
        applied: f,
        ..Body::default()
    }
}

/// Integrates the window with fixed steps.
pub fn run(
    window: &Window,
    piston: &Piston,
    liner: &mut dyn Liner,
) -> Result<WindowResult, TransientError> {
    let t0 = std::time::Instant::now();
    let steps = ((window.end_deg - window.start_deg) / window.step_deg).round() as usize;
    let dt = window.step_deg.to_radians() / window.omega;
    let ns = piston.skirt.heights.len();
    let mut body = body_at_rest(piston, window.start_deg);
    let mut prev = vec![contact::SliceState::APART; 2 * ns];
    let bore = BoreLines {
        thrust_z: &window.thrust_z,
        antithrust_z: &window.antithrust_z,
        first: 0,
    };
    let npoints = liner.point_accelerations().len();
    let mut out = WindowResult::default();
    let mut acceleration = vec![Vec::with_capacity(steps); npoints];
    let mut residual: Vec<Vec<f64>> = Vec::new();
    for s in 1..=steps {
        let deg = window.start_deg + s as f64 * window.step_deg;
        let time_s = (deg - window.start_deg).to_radians() / window.omega;
        liner.predict(dt);
        let loads = piston.loads(deg);
        body.force = loads.force;
        let mut slices = Vec::with_capacity(2 * ns);
        let mut meta = Vec::with_capacity(2 * ns);
        let pen_of = |side: bool, i: usize| prev[usize::from(!side) * ns + i].penetration;
        push_slices(
            &PistonInBore {
                piston,
                loads: &loads,
                liner_top: window.liner_top,
                bore: &bore,
                body: 0,
            },
            &pen_of,
            &mut slices,
            &mut meta,
        );
        let res = contact::step(
            &[body],
            &slices,
            liner,
            dt,
            window.scheme,
            window.max_newton,
        )
        .map_err(|f| step_failure(f, deg, time_s))?;
        let mut b = checked_body(window, &res, &meta, deg, time_s)?;
        let locs: Vec<Location> = slices.iter().map(|s| s.at).collect();
        liner.commit(&locs, &res.forces);
        for (p, r) in liner
            .point_residual(&locs, &res.forces)
            .into_iter()
            .enumerate()
        {
            residual.resize(npoints, Vec::new());
            residual[p].push(r);
        }
        // the damper impulse missed at onsets, as in the engine cycle
        let before: Vec<contact::SliceState> = meta
            .iter()
            .map(|&(_, side, i, _)| prev[usize::from(!side) * ns + i])
            .collect();
        let mut after = res.slice_states();
        let damping: Vec<f64> = slices.iter().map(|s| s.damping).collect();
        let impulses = contact::onset_impulses(&before, &mut after, &damping, dt, window.scheme);
        if window.onset_correction
            && impulses.iter().any(|&d| d != 0.0)
            && liner.impulse(&locs, &impulses)
        {
            let mut kicked = [b];
            contact::kick_bodies(&mut kicked, &slices, &impulses);
            b = kicked[0];
        }
        body = b;
        prev.fill(contact::SliceState::APART);
        let mut net = 0.0;
        for (k, &(_, side, i, _)) in meta.iter().enumerate() {
            prev[usize::from(!side) * ns + i] = after[k];
            net += if side { res.forces[k] } else { -res.forces[k] };
        }
        out.newton_iterations += res.iterations;
        out.crank_angle_deg.push(deg);
        for (p, a) in liner.point_accelerations().into_iter().enumerate() {
            acceleration[p].push(a);
        }
        out.lateral_m.push(b.q[0]);
        out.tilt_rad.push(b.q[1]);
        out.contact_force_n.push(net);
    }
    for (acc, r) in acceleration.iter_mut().zip(&residual) {
        for (a, d) in acc.iter_mut().zip(second_difference(r, dt, false)) {
            *a += d;
        }
    }
    out.acceleration = from_row_vecs(acceleration);
    out.seconds = t0.elapsed().as_secs_f64();
    Ok(out)
}

/// A failed contact step of the window as the transient's error, with its crank angle and
/// time (a fixed step: never halved).
fn step_failure(f: contact::StepFailure, deg: f64, time_s: f64) -> TransientError {
    match f {
        contact::StepFailure::NoConvergence { iterations } => TransientError::NoConvergence {
            crank_angle_deg: deg,
            time_s,
            iterations,
            halvings: 0,
        },
        contact::StepFailure::Singular => TransientError::Singular {
            crank_angle_deg: deg,
            time_s,
        },
    }
}

/// The window's piston after a step, checked: no slice deeper than the window's limit (named
/// with its side, slice and height), a finite state.
fn checked_body(
    window: &Window,
    res: &contact::StepResult,
    meta: &[(usize, bool, usize, f64)],
    deg: f64,
    time_s: f64,
) -> Result<Body, TransientError> {
    if let Some((k, &p)) = res
        .penetrations
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
    {
        if p > window.max_penetration {
            let (_, side, i, z) = meta[k];
            return Err(TransientError::DeepPenetration {
                cylinder: 0,
                side: if side { "thrust" } else { "anti-thrust" },
                slice: i + 1,
                height_mm: z * 1e3,
                penetration_um: p * 1e6,
                limit_um: window.max_penetration * 1e6,
                crank_angle_deg: deg,
                time_s,
            });
        }
    }
    let b = res.bodies[0];
    if !b.q.iter().chain(&b.v).chain(&b.a).all(|x| x.is_finite()) {
        return Err(TransientError::NonFinite {
            crank_angle_deg: deg,
            time_s,
            place: "the piston of the window's cylinder".into(),
        });
    }
    Ok(b)
}

/// The ROM as a [`Liner`]: a [`ModalStructure`], the mode rows of the analysis points and
/// their residual flexibility to the contact DOFs.
pub struct ModalLiner {
    pub structure: ModalStructure,
    /// Analysis points x modes.
    pub points: Dense,
    /// Analysis points x contact DOFs (None: modal outputs only).
    pub point_residual: Option<Dense>,
}

/// Residual point displacement R_pc F of `forces` at `locs` (contact DOFs interpolated).
pub fn residual_displacement(r: &Dense, locs: &[Location], forces: &[f64]) -> Vec<f64> {
    (0..r.nrows())
        .map(|p| {
            let row = row(r, p);
            locs.iter()
                .zip(forces)
                .filter(|(_, &f)| f != 0.0)
                .map(|(at, &f)| {
                    (at.weights[0] * row[at.dofs[0]] + at.weights[1] * row[at.dofs[1]]) * f
                })
                .sum()
        })
        .collect()
}

/// Second difference (r_{k+1} - 2 r_k + r_{k-1}) / dt^2 of a sampled series: the acceleration of
/// a quasi-static displacement. `cyclic`: the series is one period; otherwise it is extended
/// by its end values.
pub fn second_difference(r: &[f64], dt: f64, cyclic: bool) -> Vec<f64> {
    let n = r.len();
    if n < 3 {
        return vec![0.0; n];
    }
    let at = |k: isize| -> f64 {
        if cyclic {
            r[k.rem_euclid(n as isize) as usize]
        } else {
            r[k.clamp(0, n as isize - 1) as usize]
        }
    };
    (0..n as isize)
        .map(|k| (at(k + 1) - 2.0 * at(k) + at(k - 1)) / (dt * dt))
        .collect()
}

/// Fourth-order central second difference of a sampled series, the acceleration of a
/// displacement record:
///   a_k = (-r_{k+2} + 16 r_{k+1} - 30 r_k + 16 r_{k-1} - r_{k-2}) / (12 dt^2),
/// the series extended by its end values. For r = cos(omega t) it gives
/// -omega^2 cos(omega t) (1 - (omega dt)^4 / 90 + O((omega dt)^6)).
pub fn second_difference4(r: &[f64], dt: f64) -> Vec<f64> {
    let n = r.len() as isize;
    let at = |k: isize| r[k.clamp(0, n - 1) as usize];
    (0..n)
        .map(|k| {
            (-at(k + 2) + 16.0 * at(k + 1) - 30.0 * at(k) + 16.0 * at(k - 1) - at(k - 2))
                / (12.0 * dt * dt)
        })
        .collect()
}

impl Structure for ModalLiner {
    fn prepare(&mut self, locs: &[Location]) {
        self.structure.prepare(locs)
    }
    fn predicted(&self, i: usize) -> (f64, f64) {
        self.structure.predicted(i)
    }
    fn predicted_bound(&self, i: usize) -> Option<(f64, f64)> {
        self.structure.predicted_bound(i)
    }
    fn compliance(&mut self, active: &[usize]) -> (DMatrix<f64>, DMatrix<f64>) {
        self.structure.compliance(active)
    }
    fn response(&self, active: &[usize], forces: &[f64]) -> Vec<f64> {
        self.structure.response(active, forces)
    }
    fn velocity_response(&self, active: &[usize], forces: &[f64]) -> Vec<f64> {
        self.structure.velocity_response(active, forces)
    }
}

impl Liner for ModalLiner {
    fn predict(&mut self, dt: f64) {
        self.structure.integrator.predict(dt)
    }
    fn commit(&mut self, locs: &[Location], forces: &[f64]) {
        let f = self.structure.modal_force_at(locs, forces);
        self.structure.integrator.commit(&f)
    }
    fn point_accelerations(&self) -> Vec<f64> {
        let a = &self.structure.integrator.ddeta;
        let n = a.len().min(self.points.ncols());
        (0..self.points.nrows())
            .map(|p| dot(&row(&self.points, p)[..n], &a[..n]))
            .collect()
    }
    fn impulse(&mut self, locs: &[Location], impulses: &[f64]) -> bool {
        self.structure.impulse(locs, impulses);
        true
    }
    fn point_residual(&self, locs: &[Location], forces: &[f64]) -> Vec<f64> {
        match &self.point_residual {
            Some(r) => residual_displacement(r, locs, forces),
            None => Vec::new(),
        }
    }
}

/// Rayleigh damping C = a M + b K with damping ratio `zeta` at the angular frequencies `w1`
/// and `w2`: zeta(w) = a / (2 w) + b w / 2, so a = 2 zeta w1 w2 / (w1 + w2), b = 2 zeta / (w1 + w2).
pub fn rayleigh(zeta: f64, w1: f64, w2: f64) -> (f64, f64) {
    (2.0 * zeta * w1 * w2 / (w1 + w2), 2.0 * zeta / (w1 + w2))
}

/// Half length L/2 of the [`low_pass`] FIR at sampling step `dt` and band `band_hz`: the number
/// of samples on each side of an output sample that enter it.
pub fn fir_half_length(dt: f64, band_hz: f64) -> usize {
    ((5.5 / (0.5 * band_hz * dt)) / 2.0).ceil() as usize
}

/// Zero-phase low-pass: a symmetric windowed-sinc FIR (Blackman window), h_k =
/// w_k sin(2 pi f_c (k - L/2) T) / (pi (k - L/2)) normalised to unit DC gain, with the cut-off
/// f_c = 1.25 `band_hz` and L = 5.5 / (0.5 band T) + 1 taps (Blackman transition width 5.5/L
/// of the sampling rate): flat (< 0.1 % ripple) up to `band_hz`, > 70 dB down above 1.5
/// `band_hz`. `cyclic`: the series is one period (circular convolution, no ends); otherwise
/// samples beyond the ends count as zero. Returns the filtered series and how many samples at
/// each end the ends affect (L/2; 0 when cyclic).
pub fn low_pass(x: &[f64], dt: f64, band_hz: f64, cyclic: bool) -> (Vec<f64>, usize) {
    let half = fir_half_length(dt, band_hz);
    let fc = 1.25 * band_hz * dt; // cycles per sample
    let len = 2 * half + 1;
    let mut h: Vec<f64> = (0..len)
        .map(|k| {
            let m = k as f64 - half as f64;
            let sinc = if m == 0.0 {
                2.0 * fc
            } else {
                (2.0 * std::f64::consts::PI * fc * m).sin() / (std::f64::consts::PI * m)
            };
            let t = 2.0 * std::f64::consts::PI * k as f64 / (len - 1) as f64;
            let w = 0.42 - 0.5 * t.cos() + 0.08 * (2.0 * t).cos();
            sinc * w
        })
        .collect();
    let sum: f64 = h.iter().sum();
    h.iter_mut().for_each(|v| *v /= sum);
    // x extended by `half` samples each side (wrapped when cyclic, zeros otherwise), so
    // y_i = sum_k h_k x_ext[i + k] with no index arithmetic in the inner loop
    let n = x.len();
    let mut ext = vec![0.0; n + 2 * half];
    for (e, v) in ext.iter_mut().enumerate() {
        let j = e as isize - half as isize;
        if cyclic && n > 0 {
            *v = x[j.rem_euclid(n as isize) as usize];
        } else if j >= 0 && (j as usize) < n {
            *v = x[j as usize];
        }
    }
    let y = (0..n)
        .map(|i| super::contact::dot(&h, &ext[i..i + len]))
        .collect();
    (y, if cyclic { 0 } else { half })
}

/// Peak of `sign` y (sign +1: largest value, -1: most negative as a positive number) of a
/// band-limited sampled series over the samples `range`, located between the samples: the
/// largest g_k = sign y_k and, where it is a strict local maximum with both neighbours in the
/// series, the vertex of the parabola through g_{k-1}, g_k, g_{k+1},
///   delta = (g_{k-1} - g_{k+1}) / (2 (g_{k-1} - 2 g_k + g_{k+1})),
///   P = g_k - (g_{k-1} - g_{k+1}) delta / 4.
/// Returns (P, k + delta) (the position in samples), None for an empty range. For a sinusoid
/// of angular frequency omega sampled at h (x = omega h) the largest sample under-states the
/// peak by up to 1 - cos(x/2) (x^2/8: 0.8 % at 1.85 kHz, 2.1 % at the low-pass's 4.5 kHz stop
/// edge at the default 21.9 us step); the vertex by at most 9 x^4 / 384 (the peak midway
/// between two samples; 0.35 % at 4.5 kHz, 1e-4 at 1.85 kHz).
pub fn sampled_peak(y: &[f64], range: std::ops::Range<usize>, sign: f64) -> Option<(f64, f64)> {
    let range = range.start.min(y.len())..range.end.min(y.len());
    // the first of equal samples
    let k = range
        .clone()
        .reduce(|a, b| if sign * y[b] > sign * y[a] { b } else { a })?;
    let g = sign * y[k];
    if k == 0 || k + 1 >= y.len() {
        return Some((g, k as f64));
    }
    let (before, after) = (sign * y[k - 1], sign * y[k + 1]);
    let curvature = before - 2.0 * g + after;
    if curvature.is_nan() || curvature >= 0.0 || before > g || after > g {
        return Some((g, k as f64));
    }
    let delta = 0.5 * (before - after) / curvature;
    Some((g - 0.25 * (before - after) * delta, k as f64 + delta))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Verification against the analytical peak of a sampled cosine: the error bound of
    /// [`sampled_peak`]'s doc, 9 x^4 / 384, derived for the worst offset (midway), holds at
    /// every offset; and the largest sample alone is worse by the x^2/8 of the doc where the
    /// offset is midway (so the test can tell the vertex from the sample).
    /// The fourth-order difference of a sampled cosine against its analytical acceleration:
    /// D4 cos(omega t) = -omega^2 cos(omega t) g(x) / x^2 with x = omega h and
    /// g(x) = (32 (1 - cos x) - 2 (1 - cos 2x)) / 12 = x^2 - x^6 / 90 + ..., so the relative
    /// error at every interior sample is at most x^4 / 90 (the series alternates with
    /// decreasing terms for x < 1); the second-order difference's x^2 / 12 is far larger, so
    /// the test tells the two apart. At the default step and the band's 3 kHz: 3e-4.
    #[test]
    fn verification_fourth_order_difference_of_a_cosine() {
        let h = 21.9e-6;
        for f in [500.0, 1855.0, 3000.0, 4500.0] {
            let w = 2.0 * std::f64::consts::PI * f;
            let x = w * h;
            let u: Vec<f64> = (0..200).map(|k| (w * k as f64 * h + 0.3).cos()).collect();
            let a = second_difference4(&u, h);
            let a2 = second_difference(&u, h, false);
            let (mut worst, mut worst2) = (0.0f64, 0.0f64);
            for k in 2..198 {
                let exact = -w * w * u[k];
                worst = worst.max((a[k] - exact).abs() / (w * w));
                worst2 = worst2.max((a2[k] - exact).abs() / (w * w));
            }
            assert!(
                worst <= x.powi(4) / 90.0 * (1.0 + 1e-6) + 1e-9,
                "{f} Hz: {worst}"
            );
            assert!(worst2 > 0.5 * x * x / 12.0, "{f} Hz: {worst2}");
        }
    }

    #[test]
    fn verification_sampled_peak_of_a_cosine() {
        let h = 21.9e-6;
        for f in [500.0, 1855.0, 3000.0, 4500.0] {
            let x = 2.0 * std::f64::consts::PI * f * h;
            for i in 0..=20 {
                let offset = i as f64 / 20.0 - 0.5; // true peak at sample 50 + offset
                let y: Vec<f64> = (0..100)
                    .map(|k| -(x * (k as f64 - 50.0 - offset)).cos())
                    .collect();
                // one period of 4.5 kHz is 10 samples: the range holds one peak
                let (p, at) = sampled_peak(&y, 47..54, -1.0).expect("non-empty range");
                let bound = 9.0 * x.powi(4) / 384.0;
                assert!(
                    (p - 1.0).abs() <= bound * (1.0 + 1e-9) + 1e-15,
                    "{f} Hz, {offset}: {p}"
                );
                // position within a tenth of a sample at the band's frequencies
                assert!(
                    (at - 50.0 - offset).abs() < 0.1,
                    "{f} Hz, {offset}: at {at}"
                );
                if i == 0 {
                    let sample = y[47..54].iter().fold(0.0f64, |m, &v| m.max(-v));
                    assert!(1.0 - sample > 0.9 * x * x / 8.0 - x.powi(4) / 300.0);
                }
            }
        }
        // ends and flat tops fall back to the largest sample
        assert_eq!(sampled_peak(&[3.0, 1.0, 0.0], 0..3, 1.0), Some((3.0, 0.0)));
        assert_eq!(sampled_peak(&[1.0, 1.0, 1.0], 0..3, 1.0), Some((1.0, 0.0)));
        assert_eq!(sampled_peak(&[1.0], 1..1, 1.0), None);
    }

    #[test]
    fn rayleigh_hits_both_frequencies() {
        let (a, b) = rayleigh(0.02, 1000.0, 20000.0);
        for w in [1000.0, 20000.0] {
            assert!((a / (2.0 * w) + b * w / 2.0 - 0.02).abs() < 1e-12);
        }
    }

    #[test]
    fn low_pass_keeps_the_band_and_stops_above() {
        let dt = 2e-5;
        let n = 4000;
        let wave = |f: f64| -> Vec<f64> {
            (0..n)
                .map(|i| (2.0 * std::f64::consts::PI * f * i as f64 * dt).sin())
                .collect()
        };
        let amp = |y: &[f64], e: usize| y[e..n - e].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        // in band: gain 1 within the Blackman ripple (~2e-4) plus sampling of the peak
        let (y, e) = low_pass(&wave(1500.0), dt, 3000.0, false);
        assert!((amp(&y, e) - 1.0).abs() < 2e-3, "{}", amp(&y, e));
        // stop band (>= 1.5 band): Blackman side lobes are below -74 dB
        let (y, e) = low_pass(&wave(5000.0), dt, 3000.0, false);
        assert!(amp(&y, e) < 1e-3, "{}", amp(&y, e));
    }
}
