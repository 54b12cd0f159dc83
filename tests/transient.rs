//! Time integration and piston-slap transient: Newmark properties against formulas, penalty
//! impact against the spring-dashpot restitution, step convergence, and hard engine cases that
//! must run stably or stop with a clear message (two-cylinder coarse test engine).

use linercav::api::{
    get_rom, piston_of, run_cycle, run_half_step, settings_of, CacheOptions, CycleSettings,
    EngineRom, Scene, SimulateReport,
};
use linercav::piston::skirt::SliceLaw;
use linercav::transient::contact::{self, Body, Location, Slice, Structure};
use linercav::transient::scheme::{ModalIntegrator, Scheme};
use nalgebra::DMatrix;
use std::path::Path;
use std::sync::OnceLock;

const SMALL: &str = "tests/fixtures/engine_small.toml";

#[test]
fn verification_undamped_newmark_conserves_energy() {
    // Average acceleration on eta'' + omega^2 eta = 0 conserves 1/2 (eta'^2 + omega^2 eta^2)
    // exactly; over 10^4 steps only roundoff (~1e-13) may accumulate.
    let omega = [
        2.0 * std::f64::consts::PI * 1850.0,
        2.0 * std::f64::consts::PI * 7000.0,
    ];
    let mut m = ModalIntegrator::new(&omega, &[0.0, 0.0], Scheme::average_acceleration());
    m.eta = vec![1e-6, 2e-7];
    m.ddeta = vec![-omega[0].powi(2) * 1e-6, -omega[1].powi(2) * 2e-7];
    let e0 = m.energy();
    for _ in 0..10_000 {
        m.predict(20e-6);
        m.commit(&[0.0, 0.0]);
    }
    let drift = (m.energy() / e0 - 1.0).abs();
    assert!(drift < 1e-10, "energy drift {drift:e}");
    // HHT-alpha dissipates the high mode, never creates energy
    let mut h = ModalIntegrator::new(&omega, &[0.0, 0.0], Scheme::hht(-0.1));
    h.eta = vec![0.0, 2e-7];
    h.ddeta = vec![0.0, -omega[1].powi(2) * 2e-7];
    let e0 = h.energy();
    for _ in 0..1000 {
        h.predict(20e-6);
        h.commit(&[0.0, 0.0]);
    }
    assert!(h.energy() < 0.5 * e0);
}

#[test]
fn verification_newmark_period_error_matches_formula() {
    // Period measured from zero crossings over 200 periods vs
    // T_num / T = (omega dt / 2) / atan(omega dt / 2); the crossing interpolation error is
    // below 1e-6 of a period, so 1e-5 relative is a safe bound.
    let f = 1000.0;
    let omega = 2.0 * std::f64::consts::PI * f;
    for steps_per_period in [10.0, 20.0, 40.0] {
        let dt = 1.0 / (f * steps_per_period);
        let mut m = ModalIntegrator::new(&[omega], &[0.0], Scheme::average_acceleration());
        m.eta = vec![1.0];
        m.ddeta = vec![-omega * omega];
        let mut crossings = Vec::new();
        let mut t = 0.0;
        let mut prev = 1.0;
        while crossings.len() < 401 {
            m.predict(dt);
            m.commit(&[0.0]);
            t += dt;
            let x = m.eta[0];
            if prev > 0.0 && x <= 0.0 || prev < 0.0 && x >= 0.0 {
                crossings.push(t - dt * x / (x - prev));
            }
            prev = x;
        }
        let period = (crossings[400] - crossings[0]) / 200.0;
        let measured = period * f - 1.0;
        let formula = Scheme::average_acceleration_period_error(omega * dt);
        println!(
            "{steps_per_period} steps/period: period error {measured:.6e}, formula {formula:.6e}"
        );
        assert!((measured - formula).abs() < 1e-5, "{measured} vs {formula}");
    }
}

/// A rigid wall: no compliance, no motion.
struct Wall {
    n: usize,
}

impl Structure for Wall {
    fn prepare(&mut self, locs: &[Location]) {
        self.n = locs.len();
    }
    fn predicted(&self, _: usize) -> (f64, f64) {
        (0.0, 0.0)
    }
    fn compliance(&mut self, active: &[usize]) -> (DMatrix<f64>, DMatrix<f64>) {
        let n = active.len();
        (DMatrix::zeros(n, n), DMatrix::zeros(n, n))
    }
    fn response(&self, _: &[usize], _: &[f64]) -> Vec<f64> {
        vec![0.0; self.n]
    }
    fn velocity_response(&self, _: &[usize], _: &[f64]) -> Vec<f64> {
        vec![0.0; self.n]
    }
}

/// The one slice of a body moving along its first coordinate into structure location 0.
fn head_on(law: &SliceLaw, damping: f64, prev_penetration: f64) -> Slice<'_> {
    Slice {
        body: 0,
        row: [1.0, 0.0],
        force_row: [-1.0, 0.0],
        gap: 0.0,
        law,
        damping,
        at: Location {
            dofs: [0, 0],
            weights: [1.0, 0.0],
        },
        prev_penetration,
        prev_rate: 0.0,
    }
}

/// A free mass as the structure, integrated with the same scheme as the body (written here
/// from the HHT-alpha equations, independently of `ModalIntegrator`):
///   m_s b_{n+1} = (1 + alpha) P_{n+1} - alpha P_n,  P the slice force pushing it,
/// Newmark updates x_{n+1} = x^ + beta dt^2 b_{n+1}, w_{n+1} = w^ + gamma dt b_{n+1}. So the
/// prediction without new force is x^ - beta dt^2 alpha P_n / m_s and the compliance
/// (1 + alpha) beta dt^2 / m_s (velocity: gamma dt instead of beta dt^2).
struct FreeMass {
    m: f64,
    scheme: Scheme,
    dt: f64,
    x: f64,
    w: f64,
    b: f64,
    p_prev: f64,
    n: usize,
}

impl FreeMass {
    fn hats(&self) -> (f64, f64) {
        let (dt, beta, gamma) = (self.dt, self.scheme.beta, self.scheme.gamma);
        (
            self.x + dt * self.w + dt * dt * (0.5 - beta) * self.b,
            self.w + dt * (1.0 - gamma) * self.b,
        )
    }
    fn commit(&mut self, p: f64) {
        let (xh, wh) = self.hats();
        let Scheme { beta, gamma, alpha } = self.scheme;
        self.b = ((1.0 + alpha) * p - alpha * self.p_prev) / self.m;
        self.x = xh + beta * self.dt * self.dt * self.b;
        self.w = wh + gamma * self.dt * self.b;
        self.p_prev = p;
    }
}

impl Structure for FreeMass {
    fn prepare(&mut self, locs: &[Location]) {
        self.n = locs.len();
    }
    fn predicted(&self, _: usize) -> (f64, f64) {
        let (xh, wh) = self.hats();
        let Scheme { beta, gamma, alpha } = self.scheme;
        let shift = -alpha * self.p_prev / self.m;
        (
            xh + beta * self.dt * self.dt * shift,
            wh + gamma * self.dt * shift,
        )
    }
    fn compliance(&mut self, active: &[usize]) -> (DMatrix<f64>, DMatrix<f64>) {
        let Scheme { beta, gamma, alpha } = self.scheme;
        let g = (1.0 + alpha) * beta * self.dt * self.dt / self.m;
        let gv = (1.0 + alpha) * gamma * self.dt / self.m;
        let n = active.len();
        (
            DMatrix::from_element(n, n, g),
            DMatrix::from_element(n, n, gv),
        )
    }
    fn response(&self, _: &[usize], forces: &[f64]) -> Vec<f64> {
        let Scheme { beta, alpha, .. } = self.scheme;
        let g = (1.0 + alpha) * beta * self.dt * self.dt / self.m;
        vec![g * forces.iter().sum::<f64>(); self.n]
    }
    fn velocity_response(&self, _: &[usize], forces: &[f64]) -> Vec<f64> {
        let Scheme { gamma, alpha, .. } = self.scheme;
        let gv = (1.0 + alpha) * gamma * self.dt / self.m;
        vec![gv * forces.iter().sum::<f64>(); self.n]
    }
}

/// The pin's friction torque on a free tilt, I phi'' = T_m tanh((beta' - phi') / w_s) with
/// beta' constant, against its closed form: u = beta' - phi' obeys I u' = -T_m tanh(u / w_s),
/// so sinh(u / w_s) = sinh(u_0 / w_s) exp(-T_m t / (I w_s)).
/// - Smooth reversal (w_s = 20 rad/s): the step takes the torque implicitly, linearised at the
///   predictor's rate (an O(dt^2) force error per step), so u at the end converges at second
///   order like the trapezoidal rule (observed order >= 1.8 over dt, dt/2, dt/4) and the finest
///   run lies within 1e-4 of u_0 (the rule's error, about dt^2 / 12 times u's third
///   derivative summed over the run, is near 1e-6 of u_0 here).
/// - Stiff sticking (w_s = 0.01 rad/s, T_m dt / (I w_s) = 5 at the engine's step: an explicit
///   torque would diverge): the reversal time I u_0 / T_m is met within two steps, and from
///   two steps after it on the tilt follows the rod, |u| <= w_s.
#[test]
fn verification_pin_friction_torque_matches_its_closed_form() {
    use linercav::transient::contact::TiltFriction;
    let (inertia, tm, u0) = (4e-3, 10.0, 50.0);
    let run = |w: f64, dt: f64, t_end: f64| -> Vec<f64> {
        let mut body = Body {
            mass: [[3.5, 0.0], [0.0, inertia]],
            v: [0.0, -u0],
            tilt_friction: TiltFriction {
                max_torque: tm,
                rod_rate: 0.0,
                slip_rate: w,
            },
            ..Body::default()
        };
        // the start's acceleration from the torque (the equation at t = 0)
        body.a[1] = body.tilt_friction.torque(body.v[1]).0 / inertia;
        body.applied[1] = inertia * body.a[1];
        let mut wall = Wall { n: 0 };
        let steps = (t_end / dt).round() as usize;
        let mut u = Vec::with_capacity(steps);
        for _ in 0..steps {
            let res = contact::step(
                &[body],
                &[],
                &[],
                &mut wall,
                dt,
                Scheme::average_acceleration(),
                10,
            )
            .unwrap();
            body = res.bodies[0];
            u.push(-body.v[1]);
        }
        u
    };
    let exact = |w: f64, t: f64| w * ((u0 / w).sinh() * (-tm * t / (inertia * w)).exp()).asinh();
    // smooth: u from 50 to about 2 rad/s over 18 ms
    let (w, t_end) = (20.0, 0.018);
    let errs: Vec<f64> = [200, 400, 800]
        .iter()
        .map(|&n| {
            let dt = t_end / n as f64;
            let u = run(w, dt, t_end);
            (u.last().unwrap() - exact(w, t_end)).abs()
        })
        .collect();
    let orders: Vec<f64> = errs.windows(2).map(|e| (e[0] / e[1]).log2()).collect();
    println!("pin friction, smooth: errors {errs:?}, orders {orders:?}");
    assert!(orders.iter().all(|&o| o >= 1.8), "{orders:?}");
    assert!(errs[2] < 1e-4 * u0, "{errs:?}");
    // stiff: the rod's rate reached at I u0 / T_m = 20 ms, then held
    let (w, dt) = (0.01, 2.2e-5);
    let u = run(w, dt, 0.03);
    let reach = u.iter().position(|&x| x <= w).unwrap() as f64 * dt;
    println!(
        "pin friction, stiff: reached at {reach:.5} s, end u {:.2e}",
        u.last().unwrap()
    );
    assert!((reach - inertia * u0 / tm).abs() <= 2.0 * dt, "{reach}");
    let held = ((inertia * u0 / tm + 2.0 * dt) / dt).ceil() as usize;
    assert!(u[held..].iter().all(|x| x.abs() <= w), "sticking holds");
}

/// HHT-alpha: the piston and the structure take the slice forces at the same shifted time, so
/// the momentum they exchange balances every step: a body striking a free mass through the
/// penalty law with a dashpot keeps the total momentum m v + m_s w to roundoff (1e-12 of the
/// initial momentum) through the impact and after it, for alpha = 0 and -0.1 and -1/3. Body
/// forces taken unshifted while the structure's are shifted would break the balance by about
/// alpha times the impulse during contact.
#[test]
fn verification_hht_bodies_exchange_momentum_with_the_structure_exactly() {
    let (m, ms, k, c) = (2.0, 5.0, 1.0e8, 2.0e3);
    let law = SliceLaw::new(k, 0.0, 0.0);
    for alpha in [0.0, -0.1, -1.0 / 3.0] {
        let scheme = if alpha == 0.0 {
            Scheme::average_acceleration()
        } else {
            Scheme::hht(alpha)
        };
        let period = 2.0 * std::f64::consts::PI / (k / m).sqrt();
        let dt = period / 40.0;
        let v0 = 0.5;
        let mut body = Body {
            mass: [[m, 0.0], [0.0, 1.0]],
            q: [-2e-6, 0.0],
            v: [v0, 0.0],
            ..Body::default()
        };
        let mut wall = FreeMass {
            m: ms,
            scheme,
            dt,
            x: 0.0,
            w: 0.0,
            b: 0.0,
            p_prev: 0.0,
            n: 0,
        };
        let p0 = m * v0;
        let mut prev = -2e-6;
        let mut worst: f64 = 0.0;
        let mut touched = false;
        for _ in 0..400 {
            let slice = head_on(&law, c, prev);
            let r = contact::step(&[body], &[slice], &[], &mut wall, dt, scheme, 50).unwrap();
            body = r.bodies[0];
            prev = r.penetrations[0];
            touched |= r.forces[0] > 0.0;
            wall.commit(r.forces[0]);
            let p = m * body.v[0] + ms * wall.w;
            worst = worst.max((p - p0).abs() / p0);
        }
        println!(
            "alpha {alpha}: worst momentum error {worst:.2e}, body v {:.4}, mass w {:.4}",
            body.v[0], wall.w
        );
        assert!(touched, "the body must strike the mass");
        assert!(wall.w > 0.0, "the mass must be pushed");
        assert!(worst < 1e-12, "alpha {alpha}: momentum error {worst:e}");
    }
}

/// What one impact gives: the body's rebound velocity over its approach velocity (restitution)
/// and the largest acceleration of the struck side during the first contact (the body's for a
/// rigid wall, the structure's for a one-mode structure) [m/s^2].
#[derive(Clone, Copy, Debug)]
struct Impact {
    restitution: f64,
    peak_acc: f64,
}

/// A body of mass `m` at speed `v0` strikes, through one slice (stiffness `k`, damper `c`, the
/// law that never pulls), a rigid wall (`mode = None`) or a one-mode structure of mass and
/// stiffness `mode = Some((m_s, k_s))`, stepped with `dt` exactly as the engine cycle steps:
/// [`contact::step`], the structure's commit, then [`contact::onset_impulses`] on body and
/// structure. The body starts `gap_time * v0` away, so the onset falls inside a step.
fn impact(
    m: f64,
    k: f64,
    c: f64,
    v0: f64,
    gap_time: f64,
    mode: Option<(f64, f64)>,
    dt: f64,
) -> Impact {
    use linercav::transient::contact::SliceState;
    use linercav::transient::modal::ModalStructure;
    let law = SliceLaw::new(k, 0.0, 0.0);
    let scheme = Scheme::average_acceleration();
    let mut body = Body {
        mass: [[m, 0.0], [0.0, 1.0]],
        q: [-gap_time * v0, 0.0],
        v: [v0, 0.0],
        ..Body::default()
    };
    // the one-mode structure, mass-normalised: phi = 1 / sqrt(m_s), omega^2 = k_s / m_s
    let mut modal = mode.map(|(ms, ks)| {
        let integrator = ModalIntegrator::new(&[(ks / ms).sqrt()], &[0.0], scheme);
        let one = |v: f64| linercav::linalg::dense::from_rows(1, 1, vec![v]);
        let mut st = ModalStructure::new(integrator, one(1.0 / ms.sqrt()), one(0.0), vec![0.0]);
        st.bound_predictions = false;
        (st, 1.0 / ms.sqrt())
    });
    let mut wall = Wall { n: 0 };
    let mut prev = SliceState::APART;
    let (mut peak, mut touched) = (0.0f64, false);
    for _ in 0..10_000_000 {
        let slice = head_on(&law, c, prev.penetration);
        let r = match modal.as_mut() {
            Some((st, _)) => {
                st.integrator.predict(dt);
                contact::step(
                    &[body],
                    std::slice::from_ref(&slice),
                    &[],
                    st,
                    dt,
                    scheme,
                    50,
                )
            }
            None => contact::step(
                &[body],
                std::slice::from_ref(&slice),
                &[],
                &mut wall,
                dt,
                scheme,
                50,
            ),
        }
        .unwrap();
        let mut after = [SliceState {
            penetration: r.penetrations[0],
            rate: r.rates[0],
            damper: r.damper[0],
            clamped: r.clamped[0],
            onset: false,
            film: 0.0,
        }];
        let di = contact::onset_impulses(&[prev], &mut after, &[c], dt, scheme);
        let after = after[0];
        let mut bodies = r.bodies.clone();
        contact::kick_bodies(&mut bodies, std::slice::from_ref(&slice), &di);
        body = bodies[0];
        prev = after;
        match modal.as_mut() {
            Some((st, phi)) => {
                let f = st.modal_force_at(&[slice.at], &r.forces);
                st.integrator.commit(&f);
                st.impulse(&[slice.at], &di);
                if r.penetrations[0] > 0.0 {
                    peak = peak.max((*phi * st.integrator.ddeta[0]).abs());
                }
            }
            None => peak = peak.max(r.forces[0] / m),
        }
        touched |= r.penetrations[0] > 0.0;
        if touched && r.penetrations[0] < 0.0 && body.v[0] < 0.0 {
            return Impact {
                restitution: -body.v[0] / v0,
                peak_acc: peak,
            };
        }
    }
    panic!("no rebound");
}

/// Reference for [`impact`] that shares no code with the tool: the same body, slice law and
/// structure as ODEs (body mass, slice stiffness and damping (m, k, c); structure (m_s, k_s)), x_b'' = -F / m, x_s'' = (F - k_s x_s) / m_s, F = max(0, k p + c p') for
/// p = x_b - x_s > 0, from the same start (p = -gap_time v0), by classical Runge-Kutta on the
/// grid dt / `sub` (the onset, where the force jumps, located inside its step by bisection and
/// the step finished from there, so the grid stays on the coarse nodes). The peak is taken at
/// the coarse nodes t_k = k dt, as the tool samples it, so the comparison measures the
/// integration error, not where the samples fall.
fn impact_reference(
    (m, k, c): (f64, f64, f64),
    v0: f64,
    gap_time: f64,
    (ms, ks): (f64, f64),
    dt: f64,
    sub: usize,
) -> Impact {
    let force = |y: &[f64; 4]| {
        let p = y[0] - y[2];
        if p > 0.0 {
            (k * p + c * (y[1] - y[3])).max(0.0)
        } else {
            0.0
        }
    };
    let deriv = |y: &[f64; 4]| {
        let f = force(y);
        [y[1], -f / m, y[3], (f - ks * y[2]) / ms]
    };
    let rk4 = |y: &[f64; 4], h: f64| {
        let add = |a: &[f64; 4], b: &[f64; 4], s: f64| {
            [
                a[0] + s * b[0],
                a[1] + s * b[1],
                a[2] + s * b[2],
                a[3] + s * b[3],
            ]
        };
        let k1 = deriv(y);
        let k2 = deriv(&add(y, &k1, h / 2.0));
        let k3 = deriv(&add(y, &k2, h / 2.0));
        let k4 = deriv(&add(y, &k3, h));
        let mut out = *y;
        for i in 0..4 {
            out[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        out
    };
    let h = dt / sub as f64;
    let mut y = [-gap_time * v0, v0, 0.0, 0.0];
    let (mut peak, mut touched) = (0.0f64, false);
    for step in 1.. {
        let mut next = rk4(&y, h);
        if !touched && next[0] - next[2] > 0.0 {
            // the onset inside this step: bisection, then the rest of the step from there
            let (mut lo, mut hi) = (0.0, h);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                let t = rk4(&y, mid);
                if t[0] - t[2] > 0.0 {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            let mut at = rk4(&y, lo);
            at[0] = at[2]; // p = 0 to roundoff
            next = rk4(&at, h - lo);
            touched = true;
        }
        y = next;
        if touched && step % sub == 0 && y[0] - y[2] > 0.0 {
            let f = force(&y);
            peak = peak.max(((f - ks * y[2]) / ms).abs());
        }
        if touched && y[0] - y[2] < 0.0 && y[1] < 0.0 {
            return Impact {
                restitution: -y[1] / v0,
                peak_acc: peak,
            };
        }
    }
    unreachable!()
}

/// Where in its step the onset falls, as fractions of the step (the error of an event depends
/// on it; the order is measured on the largest error over these).
const PHASES: [f64; 7] = [0.03, 0.17, 0.31, 0.45, 0.59, 0.73, 0.87];

/// Observed orders log2(e_k / e_{k+1}) of the errors of successive halvings, and over all of
/// them, log2(e_0 / e_last) / halvings.
fn orders(errs: &[f64]) -> (Vec<f64>, f64) {
    let each = errs.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    let all = (errs[0] / errs[errs.len() - 1]).log2() / (errs.len() - 1) as f64;
    (each, all)
}

/// Observed orders over three halvings (50 to 400 steps per contact `period`) of the two
/// relative errors (restitution, peak) that `case(dt, gap_time)` returns, each the largest
/// over the onset [`PHASES`]; prints the errors and returns the orders over all halvings.
fn observed_orders(period: f64, case: impl Fn(f64, f64) -> (f64, f64)) -> (f64, f64) {
    let (mut de, mut dp) = (Vec::new(), Vec::new());
    for n in [50.0, 100.0, 200.0, 400.0] {
        let dt = period / n;
        let (mut we, mut wp) = (0.0f64, 0.0f64);
        for phase in PHASES {
            let (e, p) = case(dt, 0.37 * period + phase * dt);
            we = we.max(e);
            wp = wp.max(p);
        }
        println!("{n} steps per contact period: largest errors over onset phases: restitution {we:.2e}, peak {wp:.2e}");
        de.push(we);
        dp.push(wp);
    }
    let (oe, oe_all) = orders(&de);
    let (op, op_all) = orders(&dp);
    println!("restitution errors {de:?}, orders {oe:.2?}, over all {oe_all:.2}");
    println!("peak errors {dp:?}, orders {op:.2?}, over all {op_all:.2}");
    (oe_all, op_all)
}

/// Verification against the exact solution: a mass striking a rigid wall through a
/// Kelvin-Voigt slice that never pulls. Exact: x = v0 / w_d e^{-zeta w t} sin(w_d t) while
/// F = k x + c x' > 0; the contact ends at t_c where F = 0 (x still > 0), the restitution is
/// -x'(t_c) / v0 (no force after it) and the peak acceleration max F / m over the nodes in
/// [0, t_c], where the tool samples it. The
/// onset's damper jump (c v0) is integrated by the onset correction, so restitution and peak
/// converge at second order: the observed order over three halvings must be at least 1.8
/// (theory 2; the margin covers the pre-asymptotic range), chosen before the run.
#[test]
fn verification_wall_impact_converges_at_second_order() {
    let (m, k, v0): (f64, f64, f64) = (3.5, 3.6e9, 0.5);
    let zeta = 0.2;
    let c = zeta * 2.0 * (k * m).sqrt();
    let w = (k / m).sqrt();
    let wd = w * (1.0 - zeta * zeta).sqrt();
    let x = |t: f64| v0 / wd * (-zeta * w * t).exp() * (wd * t).sin();
    let xd =
        |t: f64| v0 * (-zeta * w * t).exp() * ((wd * t).cos() - zeta * w / wd * (wd * t).sin());
    let f = |t: f64| k * x(t) + c * xd(t);
    // t_c: F > 0 from t = 0 until it first crosses zero, after the half period pi / w_d
    let (mut lo, mut hi) = (
        0.5 * std::f64::consts::PI / wd,
        1.5 * std::f64::consts::PI / wd,
    );
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let tc = lo;
    let e_exact = -xd(tc) / v0;
    let period = 2.0 * std::f64::consts::PI / w;
    let (oe_all, op_all) = observed_orders(period, |dt, gap_time| {
        // the exact peak at the nodes t_k = k dt the tool samples (onset at t = gap_time)
        let peak_exact = (1..)
            .map(|i| i as f64 * dt - gap_time)
            .skip_while(|&t| t <= 0.0)
            .take_while(|&t| t < tc)
            .map(f)
            .fold(0.0f64, f64::max)
            / m;
        let r = impact(m, k, c, v0, gap_time, None, dt);
        (
            (r.restitution - e_exact).abs() / e_exact,
            (r.peak_acc - peak_exact).abs() / peak_exact,
        )
    });
    assert!(oe_all >= 1.8 && op_all >= 1.8, "{oe_all} {op_all}");
    // no damping: elastic rebound, e = 1 to the accuracy of the trapezoidal rule
    let r = impact(m, k, 0.0, v0, 0.371_830_2 * period, None, period / 200.0);
    assert!((r.restitution - 1.0).abs() < 1e-3, "{r:?}");
}

/// Verification against an independent reference: the same impact on a one-mode structure
/// (10 kg at 2 kHz, the liner-like side; undamped), through the production modal structure,
/// against a fine Runge-Kutta solution written in the test (step 1/40000 of the contact
/// period, onset located by bisection: its error is far below the coarse runs'). Restitution
/// and the structure's peak acceleration must converge at an observed order of at least 1.8
/// over three halvings (theory 2), chosen before the run.
#[test]
fn verification_one_mode_impact_converges_at_second_order() {
    let (m, k, v0): (f64, f64, f64) = (3.5, 3.6e9, 0.5);
    let c = 0.2 * 2.0 * (k * m).sqrt();
    let (ms, ks) = (
        10.0,
        10.0 * (2.0 * std::f64::consts::PI * 2000.0f64).powi(2),
    );
    let period = 2.0 * std::f64::consts::PI / (k / m).sqrt();
    let (oe_all, op_all) = observed_orders(period, |dt, gap_time| {
        let sub = (40_000.0 * dt / period).round() as usize;
        let reference = impact_reference((m, k, c), v0, gap_time, (ms, ks), dt, sub);
        let r = impact(m, k, c, v0, gap_time, Some((ms, ks)), dt);
        (
            (r.restitution - reference.restitution).abs() / reference.restitution,
            (r.peak_acc - reference.peak_acc).abs() / reference.peak_acc,
        )
    });
    assert!(oe_all >= 1.8 && op_all >= 1.8, "{oe_all} {op_all}");
}

fn small_rom() -> &'static EngineRom {
    static ROM: OnceLock<EngineRom> = OnceLock::new();
    ROM.get_or_init(|| {
        let scene = Scene::load(Path::new(SMALL), &[]).unwrap();
        get_rom(
            &scene,
            &CacheOptions {
                no_cache: true,
                dir: None,
            },
            &|_| {},
        )
        .unwrap()
        .rom
    })
}

fn simulation_of_small() -> linercav::scene::Simulation {
    Scene::load(Path::new(SMALL), &[])
        .unwrap()
        .simulation
        .unwrap()
}

fn simulate(
    sets: &[&str],
    tweak: impl Fn(&mut CycleSettings),
) -> Result<linercav::transient::cycle::CycleResult, String> {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let scene = Scene::load(Path::new(SMALL), &sets).map_err(|e| e.to_string())?;
    let piston = piston_of(&scene).map_err(|e| e.to_string())?;
    let mut settings = settings_of(scene.simulation.as_ref().unwrap(), scene.rom.band_hz);
    tweak(&mut settings);
    run_cycle(&scene, small_rom(), &piston, settings, |_, _| {}).map_err(|e| e.to_string())
}

#[test]
fn verification_engine_cycle_runs_with_bounded_energy_and_finite_peaks() {
    let r = simulate(&[], |s| s.tolerance = None).unwrap();
    assert_eq!(r.peaks.len(), 2);
    assert_eq!(r.peak_negative.nrows(), 2);
    for p in &r.peak_negative {
        assert!(p.value.is_finite() && p.value > 0.0);
    }
    for c in &r.peaks {
        // the quasi-static side force peaks in the expansion stroke, after firing TDC
        assert!(c.side_force.crank_angle_deg > 360.0 && c.side_force.crank_angle_deg < 420.0);
    }
    // average acceleration: the discrete energy balance holds to roundoff
    assert!(r.stats.energy_error.abs() < 1e-9, "{:?}", r.stats);
    // one cycle of 0.25 deg steps and the outputs' margin past its end, each base step around
    // a slap onset taken as `slap_substeps` committed sub-steps (no step rejected)
    let margin = linercav::transient::signal::fir_half_length(r.stats.dt_s, 2000.0)
        + linercav::transient::cycle::OUTPUT_DIFFERENCE_REACH;
    let m = simulation_of_small().transient.slap_substeps;
    assert_eq!(r.stats.rejected_steps, 0);
    assert!(r.stats.substepped_steps > 0 && r.stats.substepped_steps < 2880 / 4);
    assert_eq!(
        r.stats.steps,
        2880 + margin + (m - 1) * r.stats.substepped_steps
    );
}

/// The averaged peaks are the statistics of the per-cycle peaks (at a fixed step: the accuracy
/// control off, which could halve one run's step and not another's): a run is deterministic, so
/// the k-th cycle of a 3-cycle run is the last cycle of a k-cycle run. The mean, sample standard
/// deviation and largest value of the three single-cycle peaks must come back (to roundoff of
/// the summation: 1e-9 relative).
#[test]
fn verification_averaged_cycles_are_the_statistics_of_the_single_cycles() {
    let single: Vec<_> = (1..=3)
        .map(|k| simulate(&[&format!("transient.cycles={k}")], |s| s.tolerance = None).unwrap())
        .collect();
    let avg = simulate(
        &["transient.cycles=3", "transient.averaged_cycles=3"],
        |s| s.tolerance = None,
    )
    .unwrap();
    assert_eq!(avg.stats.cycles_averaged, 3);
    assert_eq!(single[2].stats.cycles_averaged, 1);
    for ((c, p), peak) in avg.peak_negative.indexed_iter() {
        let v: Vec<f64> = single
            .iter()
            .map(|r| r.peak_negative[[c, p]].value)
            .collect();
        let mean = v.iter().sum::<f64>() / 3.0;
        let std = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 2.0).sqrt();
        let max = v.iter().cloned().fold(f64::MIN, f64::max);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs().max(1.0);
        assert!(close(peak.value, mean), "{} vs {mean}", peak.value);
        assert!(close(peak.std, std), "{} vs {std}", peak.std);
        assert!(close(peak.max, max), "{} vs {max}", peak.max);
    }
    // the series are the last cycle's, as with one averaged cycle
    assert_eq!(
        avg.series.cylinders[0].acceleration.row(0),
        single[2].series.cylinders[0].acceleration.row(0)
    );
    // more averaged cycles than run: all of them; zero is refused with the key
    let all = simulate(
        &["transient.cycles=3", "transient.averaged_cycles=9"],
        |s| s.tolerance = None,
    )
    .unwrap();
    assert_eq!(all.stats.cycles_averaged, 3);
    let e = simulate(&["transient.averaged_cycles=0"], |s| s.tolerance = None).unwrap_err();
    assert!(e.contains("transient.averaged_cycles"), "{e}");
}

/// Verification against a converged run: the test engine at its default settings (the
/// accuracy control `transient.tolerance` = 5 % on, so the step may be halved) against the same
/// engine at a fixed step 64 times finer than the default 1/4 deg. The mean peak negative
/// acceleration must lie within 2 % of the converged one (issue 22's floor for the default;
/// one cycle from rest is deterministic, so no statistical margin is due). Measured with the
/// default 3 slap sub-steps: at 1/4 deg the estimate is 3.7 % against an error of 1.7 %, so the
/// control keeps the step. Before the sub-steps the estimate was 7.4 % against 6.0 % at 1/4 deg,
/// the control halved the step, and at 1/8 deg the error was 1.5 % while that run's own
/// estimate said 0.17 % (the estimate covers each cylinder's firing slap of the last cycle
/// only, and can under-state; it is printed, not asserted). The quasi-static side force is smooth and only sampled: its peak agrees to 1e-3.
#[test]
fn verification_accuracy_control_meets_its_tolerance_against_a_converged_run() {
    let controlled = simulate(&[], |_| {}).unwrap();
    let converged = converged_small();
    let mean = |r: &linercav::transient::cycle::CycleResult| {
        let v: Vec<f64> = r.peak_negative.iter().map(|p| p.value).collect();
        v.iter().sum::<f64>() / v.len() as f64
    };
    let err = (mean(&controlled) - mean(converged)).abs() / mean(converged);
    let est = controlled.stats.step_error_estimate;
    println!(
        "step {:.4} deg after {} halving(s): mean {:.1} against converged {:.1}: error {:.2} %, estimate {:.2} %",
        controlled.stats.dt_s * 1900.0 * 6.0,
        controlled.stats.step_refinements,
        mean(&controlled),
        mean(converged),
        100.0 * err,
        100.0 * est
    );
    assert!(err <= 0.02, "{err}");
    for (c, f) in controlled.peaks.iter().zip(&converged.peaks) {
        let d = (c.side_force.value - f.side_force.value).abs() / f.side_force.value;
        assert!(d < 1e-3, "{d}");
    }
}

/// The test engine's cycle at a fixed step 64 times finer than its default 1/4 deg, without
/// the accuracy control (shared by the tests that compare against it).
fn converged_small() -> &'static linercav::transient::cycle::CycleResult {
    static RUN: OnceLock<linercav::transient::cycle::CycleResult> = OnceLock::new();
    RUN.get_or_init(|| {
        simulate(&["transient.step_deg=0.00390625"], |s| s.tolerance = None).unwrap()
    })
}

/// Verification of the whole-run step check against a converged run: the test engine's cycle
/// from rest (deterministic: no statistical margin is due) at its default settings and
/// repeated at half the step ([`run_half_step`]), against a fixed step 64 times finer. The
/// check's numerical uncertainty of each cylinder's worst point, max(2 |P_h - P_{h/2}|, the
/// firing-slap estimate), must cover the actual error |P_h - P_converged| up to 1 % of the
/// converged peak (the claim the report's ranking rests on; the 1 % allows for what is left
/// of the reference's own step error and for the peaks' sampling). The records' fields must
/// carry the half-step run's values.
#[test]
fn verification_whole_run_step_check_covers_the_error_against_a_converged_run() {
    let scene = Scene::load(Path::new(SMALL), &[]).unwrap();
    let piston = piston_of(&scene).unwrap();
    let mut settings = settings_of(scene.simulation.as_ref().unwrap(), scene.rom.band_hz);
    settings.tolerance = None;
    let run = run_cycle(&scene, small_rom(), &piston, settings.clone(), |_, _| {}).unwrap();
    let half = run_half_step(
        &scene,
        small_rom(),
        &piston,
        settings.clone(),
        settings.step_deg,
        |_, _| {},
    )
    .unwrap();
    assert!((half.stats.dt_s - run.stats.dt_s / 2.0).abs() < 1e-15 * run.stats.dt_s);
    let mut report = SimulateReport::new(&scene, &piston, &run, "test", 0.0);
    report.add_step_check(&half, 0.0);
    let converged = converged_small();
    for (ci, c) in report.cylinders.iter().enumerate() {
        let (k, w) = c
            .points
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.peak_negative_m_s2.total_cmp(&b.1.peak_negative_m_s2))
            .unwrap();
        assert_eq!(
            w.peak_negative_half_step_m_s2,
            Some(half.peak_negative[[ci, k]].value)
        );
        let reference = converged.peak_negative[[ci, k]].value;
        let error = (w.peak_negative_m_s2 - reference).abs();
        let bound = w.numerical_uncertainty();
        println!(
            "cylinder {} point {}: P_h {:.1}, P_h/2 {:.1}, converged {:.1}: error {:.2} %, uncertainty {:.2} % (slap estimate {:.2} %)",
            c.cylinder,
            k + 1,
            w.peak_negative_m_s2,
            w.peak_negative_half_step_m_s2.unwrap(),
            reference,
            100.0 * error / reference,
            100.0 * bound / reference,
            100.0 * w.peak_negative_step_error_m_s2 / reference
        );
        assert!(error <= bound + 0.01 * reference, "cylinder {}", c.cylinder);
    }
    let check = report.step_check.as_ref().unwrap();
    assert_eq!(check.cycles_averaged, run.stats.cycles_averaged);
    assert!(check.mean_difference.is_finite() && check.mean_difference_se >= 0.0);
}

/// Verification of the report's speed-against-error curve against a converged reference: on
/// the test engine's firing slaps of the third cycle, run from identical states, the scene's
/// method (3 slap sub-steps) at its 1/4 deg step must lie within 4 % of a uniform step 64 times
/// finer at each cylinder's worst point (issue 22's floor for worst points; from identical
/// states there is no cycle-to-cycle scatter, only a single slap's sensitivity to its contact
/// history, 1.4 % rms over the default engine's firing slaps). The curve has its three kinds,
/// on the steps 4, 2, 1 and 1/2 times the scene's.
#[test]
fn verification_speed_error_curve_steps_against_a_converged_reference() {
    use linercav::transient::verify::{tradeoff, TradeoffKind, TRADEOFF_STEPS};
    let scene = Scene::load(Path::new(SMALL), &[]).unwrap();
    let piston = piston_of(&scene).unwrap();
    let settings = settings_of(scene.simulation.as_ref().unwrap(), scene.rom.band_hz);
    let curve = tradeoff(&scene, small_rom(), &piston, &settings).unwrap();
    for p in &curve {
        println!("{:45} error {:.4}", p.setting, p.error);
        assert!(p.error.is_finite() && p.seconds >= 0.0, "{p:?}");
    }
    for kind in [TradeoffKind::Step, TradeoffKind::UniformStep] {
        let steps: Vec<f64> = curve
            .iter()
            .filter(|p| p.kind == kind)
            .map(|p| p.step_deg)
            .collect();
        let expected: Vec<f64> = TRADEOFF_STEPS
            .iter()
            .map(|k| k * settings.step_deg)
            .collect();
        assert_eq!(steps, expected, "{kind:?}");
    }
    assert_eq!(
        curve
            .iter()
            .filter(|p| p.kind == TradeoffKind::ModeCutoff)
            .count(),
        3
    );
    let at_default = curve
        .iter()
        .find(|p| p.kind == TradeoffKind::Step && p.step_deg == settings.step_deg)
        .unwrap();
    assert!(at_default.error <= 0.04, "{at_default:?}");
}

#[test]
fn verification_per_cylinder_coupling_matches_the_monolithic_step() {
    // Lagging the other cylinder's within-step influence changes the contact by the measured
    // lag; on this engine that is below 1 % of the skirt penetration, and the peaks (which
    // follow the slap, itself sensitive to the contact history) agree to 2 %.
    let fast = simulate(&["transient.step_deg=0.5"], |s| s.tolerance = None).unwrap();
    let exact = simulate(&["transient.step_deg=0.5"], |s| {
        s.coupling = linercav::transient::cycle::Coupling::Monolithic;
        s.tolerance = None;
    })
    .unwrap();
    println!(
        "coupling lag {:.3e} m, max penetration {:.3e} m",
        fast.stats.coupling_lag_m, fast.stats.max_penetration_m
    );
    assert!(fast.stats.coupling_lag_m < 0.01 * fast.stats.max_penetration_m);
    for (x, y) in fast.peak_negative.iter().zip(&exact.peak_negative) {
        println!("{} vs {}", x.value, y.value);
        assert!(
            (x.value - y.value).abs() < 0.02 * y.value,
            "{} vs {}",
            x.value,
            y.value
        );
    }
}

#[test]
fn verification_bounded_predictions_change_nothing() {
    // The predictor's products are skipped only where the Cauchy-Schwarz bound proves a slice
    // apart, and such a slice's exact penetration would have been below the onset as well: every
    // peak, angle and counter of a run with the bound equals the run without it, bit for bit
    // (the HHT scheme too: its predictor differs).
    for scheme in [&[][..], &["transient.scheme=hht"][..]] {
        let with = simulate(scheme, |_| {}).unwrap();
        let without = simulate(scheme, |s| s.bound_predictions = false).unwrap();
        assert_eq!(with.stats.steps, without.stats.steps);
        assert_eq!(
            with.stats.newton_iterations,
            without.stats.newton_iterations
        );
        assert_eq!(
            with.stats.max_penetration_m.to_bits(),
            without.stats.max_penetration_m.to_bits()
        );
        for (x, y) in with.peak_negative.iter().zip(&without.peak_negative) {
            assert_eq!(x.value.to_bits(), y.value.to_bits(), "{x:?} vs {y:?}");
            assert_eq!(x.crank_angle_deg, y.crank_angle_deg);
        }
        for (a, b) in with.peaks.iter().zip(&without.peaks) {
            assert_eq!(a.slap_force.value.to_bits(), b.slap_force.value.to_bits());
        }
        for (a, b) in with.series.cylinders.iter().zip(&without.series.cylinders) {
            assert_eq!(a.lateral_m, b.lateral_m);
            assert_eq!(a.thrust_force_n, b.thrust_force_n);
        }
    }
}

#[test]
fn contract_hard_cases_run_stably_or_stop_clearly() {
    // very stiff contact: stable (average acceleration is unconditionally stable)
    let r = simulate(&["piston.contact_stiffness_n_per_m=1e10"], |_| {}).unwrap();
    assert!(r.stats.energy_error.abs() < 1e-9);
    // zero cold clearance: the hot skirt is pressed into the bore (a preloaded contact within
    // the penetration limit): runs
    let zero = simulate(&["piston.clearance_um=0"], |_| {}).expect("zero clearance runs");
    assert!(zero.stats.energy_error.abs() < 1e-9);
    // a hot interference beyond the penetration limit is refused before running
    let Err(e) = simulate(
        &[
            "piston.clearance_um=0",
            "piston.thermal.skirt_top_temp_c=300",
        ],
        |_| {},
    ) else {
        panic!("refused")
    };
    assert!(e.contains("clearance_um") && e.contains("seize"), "{e}");
    // 200 um: runs, slaps harder than at 80 um
    let wide = simulate(&["piston.clearance_um=200"], |_| {}).unwrap();
    assert!(wide.peak_negative.iter().all(|p| p.value.is_finite()));
    // 3000 rpm
    let fast = simulate(&["engine.speed_rpm=3000"], |_| {}).unwrap();
    assert!(fast.stats.energy_error.abs() < 1e-9);
    // a step ten times too large: runs (adaptive halving may reject steps) or stops clearly
    match simulate(&["transient.step_deg=2.5"], |_| {}) {
        Ok(r) => assert!(r.stats.steps >= 288 && r.stats.energy_error.abs() < 1e-9),
        Err(e) => assert!(e.contains("crank angle"), "{e}"),
    }
    // soft contact overloaded: deep penetration named with cylinder, side and crank angle
    let Err(e) = simulate(&["piston.contact_stiffness_n_per_m=1e6"], |s| {
        s.adaptive = false
    }) else {
        panic!("deep penetration stops the run")
    };
    assert!(
        e.contains("deep penetration") && e.contains("cylinder") && e.contains("crank angle"),
        "{e}"
    );
}

#[test]
fn contract_unstable_scheme_is_caught_as_energy_growth() {
    // gamma < 1/2 gives Newmark negative numerical damping: energy grows until the balance
    // check stops the run, naming the crank angle.
    let Err(e) = simulate(&["transient.damping_ratio=0"], |s| {
        s.scheme = Scheme {
            beta: 0.25,
            gamma: 0.3,
            alpha: 0.0,
        };
    }) else {
        panic!("energy growth stops the run")
    };
    assert!(
        e.contains("energy growth") && e.contains("crank angle"),
        "{e}"
    );
}

#[test]
fn contract_pressure_file_with_nan_is_refused_with_its_line() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("p.csv");
    std::fs::write(
        &csv,
        "crank_angle_deg,pressure_bar\n0,1.0\n360,150\n361,nan\n",
    )
    .unwrap();
    let set = format!("operating.pressure_file={:?}", csv.display().to_string());
    let Err(e) = simulate(&[set.as_str()], |_| {}) else {
        panic!("refused")
    };
    assert!(e.contains("line 4") && e.contains("not finite"), "{e}");
}

/// Slap events against a converged run on identical slaps: from the states where each
/// cylinder's firing-slap window begins (cycle 2 of the small engine), the window is run at the
/// scene's step (with its slap sub-steps) and at a sixteenth of it (the same sub-steps), and
/// the firing slap (the window's largest event) compared. Issue 38's floor, chosen before the
/// numbers were seen: within 1 % of the fine run's. The impact energy and velocity, located
/// at the onset within its step, the event's impulse and its force meet it at the scene's
/// settings (force -0.6 % and -0.2 %; it was 3.3-3.7 % low while the onset step credited the
/// damper impulse of slices whose dampers the next step then dropped, see
/// `contact::onset_impulses`); 16 sub-steps over 3 deg are checked as well.
#[test]
fn verification_slap_events_match_a_sixteenth_step_run() {
    use linercav::transient::cycle::{EngineRun, SlapEvent};
    use linercav::transient::engine::setup_of;
    let scene = Scene::load(Path::new(SMALL), &[]).unwrap();
    let piston = piston_of(&scene).unwrap();
    let mut settings = settings_of(scene.simulation.as_ref().unwrap(), scene.rom.band_hz);
    settings.tolerance = None;
    settings.step_error = false;
    let m = settings.slap_substeps;
    let setup = setup_of(&scene, small_rom(), &piston);
    let firing = |events: Vec<Vec<SlapEvent>>, c: usize| {
        events[c]
            .iter()
            .copied()
            .max_by(|a, b| a.force_n.total_cmp(&b.force_n))
            .unwrap()
    };
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
    for span in [settings.slap_span_deg, 3.0] {
        let run = EngineRun::new(
            &setup,
            linercav::api::CycleSettings {
                slap_span_deg: span,
                ..settings.clone()
            },
        );
        let h = run.base_dt();
        let (states, steps) = run.slap_window_states(2).unwrap();
        for (c, state) in states {
            let fine = firing(
                state.clone().window_events(16 * steps, h / 16.0).unwrap(),
                c,
            );
            if span == settings.slap_span_deg {
                let base = firing(state.window_events(steps, h).unwrap(), c);
                println!("cylinder {c}, {m} sub-steps: {base:?}\n  1/16 step: {fine:?}");
                assert!(base.thrust && fine.thrust);
                assert!((base.crank_angle_deg - fine.crank_angle_deg).abs() < 0.25);
                assert!(
                    rel(base.impact_energy_j, fine.impact_energy_j) <= 0.01,
                    "energy"
                );
                assert!(rel(base.impact_velocity_m_s, fine.impact_velocity_m_s) <= 0.01);
                // the impulse, from the sub-steps as the integrator delivers it (the momentum
                // the contact gave the piston)
                assert!(rel(base.impulse_n_s, fine.impulse_n_s) <= 0.01, "impulse");
                println!(
                    "  force {:+.2} %",
                    100.0 * (base.force_n / fine.force_n - 1.0)
                );
                assert!(rel(base.force_n, fine.force_n) <= 0.01, "force");
            } else {
                let sub = firing(
                    state
                        .with_slap_substeps(16)
                        .window_events(steps, h)
                        .unwrap(),
                    c,
                );
                println!(
                    "cylinder {c}, 16 sub-steps over {span} deg: force {:+.2} %",
                    100.0 * (sub.force_n / fine.force_n - 1.0)
                );
                assert!(rel(sub.force_n, fine.force_n) <= 0.01, "force");
            }
        }
    }
}

/// Verification (`transient.mode_cutoff_hz`): the modes a run does not integrate respond
/// quasi-statically at the analysis points of both the liner and the crankcase to every
/// cylinder's contact forces, not only the point's own cylinder's. With the top third of the
/// test ROM's modes dropped, every cylinder's points after each of the cycle's steps equal the
/// matrix form
///   u_p = sum_{j < nb} phi_pj eta_j + sum_b S_pb F_b + R_pc F_c,
///   S_pb = sum_{j >= nb} phi_pj c_bj^T / omega_j^2 (`CylinderRom::static_part` of cylinder b),
/// formed apart from the run's path (which sums the dropped modes' quasi-static coordinates
/// q_j = c_j^T F / omega_j^2): within 1e-9 of the points' largest displacement (roundoff of
/// sums over ~100 modes and ~50 loaded DOFs in another order). The other cylinders' part
/// must be seen at all (more than 1e-3 of it at some step), or the check could not tell.
#[test]
fn verification_points_carry_the_dropped_modes_static_part_of_every_cylinder() {
    let rom = small_rom();
    let scene = Scene::load(Path::new(SMALL), &[]).unwrap();
    let piston = piston_of(&scene).unwrap();
    let mut settings = settings_of(scene.simulation.as_ref().unwrap(), scene.rom.band_hz);
    let all = rom.frequencies_hz.len();
    settings.modes_below_hz = Some(rom.frequencies_hz[2 * all / 3]);
    let setup = linercav::transient::engine::setup_of(&scene, rom, &piston);
    let mut run = linercav::transient::cycle::EngineRun::new(&setup, settings);
    let dt = run.base_dt();
    let (mut checked, mut cross_seen) = (0, 0.0f64);
    for _ in 0..2880 {
        run.advance(dt).unwrap();
        if run.loaded().is_empty() {
            continue;
        }
        let eta = &run.structure.integrator.eta;
        let nb = eta.len();
        assert!(nb < all, "modes dropped");
        for (c, cyl) in rom.cylinders.iter().enumerate() {
            for crankcase in [false, true] {
                let rows = if crankcase {
                    &cyl.crankcase_point_modes
                } else {
                    &cyl.point_modes
                };
                let mut own = vec![0.0; rows.nrows()];
                let mut cross = vec![0.0; rows.nrows()];
                for (b, other) in rom.cylinders.iter().enumerate() {
                    let s = other.static_part(rows, &rom.frequencies_hz, nb);
                    let off = other.contact_offset;
                    let (locs, forces): (Vec<Location>, Vec<f64>) = run
                        .loaded()
                        .iter()
                        .filter(|(k, _, _)| *k == b)
                        .map(|(_, at, f)| {
                            let dofs = [at.dofs[0] - off, at.dofs[1] - off];
                            (
                                Location {
                                    dofs,
                                    weights: at.weights,
                                },
                                *f,
                            )
                        })
                        .unzip();
                    let target = if b == c { &mut own } else { &mut cross };
                    let u = linercav::transient::bore::residual_displacement(&s, &locs, &forces);
                    for (t, v) in target.iter_mut().zip(u) {
                        *t += v;
                    }
                    if b == c && !crankcase {
                        let r = linercav::transient::bore::residual_displacement(
                            &cyl.point_residual,
                            &locs,
                            &forces,
                        );
                        for (t, v) in own.iter_mut().zip(r) {
                            *t += v;
                        }
                    }
                }
                let got = run.point_displacements(c, crankcase);
                let expected: Vec<f64> = (0..rows.nrows())
                    .map(|p| {
                        (0..nb).map(|j| rows[[p, j]] * eta[j]).sum::<f64>() + own[p] + cross[p]
                    })
                    .collect();
                let scale = expected.iter().fold(1e-30f64, |m, v| m.max(v.abs()));
                for (p, (g, e)) in got.iter().zip(&expected).enumerate() {
                    assert!(
                        (g - e).abs() <= 1e-9 * scale,
                        "cylinder {c} point {p} (crankcase {crankcase}): {g:e} against {e:e}"
                    );
                }
                let cross_max = cross.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                cross_seen = cross_seen.max(cross_max / scale);
                checked += 1;
            }
        }
    }
    println!("{checked} checks, the other cylinders' part up to {cross_seen:.3e} of the points'");
    assert!(checked > 100, "{checked} checks");
    assert!(
        cross_seen > 1e-3,
        "the other cylinders' part {cross_seen:e}"
    );
}

/// Verification (liner maps): at the analysis points the surface map equals the point
/// outputs. The map's node rows are formed apart from the points' (another association of
/// the residual flexibility, the filter applied per coordinate by FFT instead of per point
/// directly, the minimum found through brackets), so agreement to roundoff checks the whole
/// chain: each point's node is the surface row equal to its point row (1e-9 of the row's
/// norm: roundoff of products over ~3,000 coordinates), and in every averaged cycle the peak
/// negative acceleration there equals the point's (mean and largest per-cycle peak within
/// 1e-9 relative, the same roundoff carried through a linear filter). Also with the modes
/// above two thirds of the ROM's integrated statically (`transient.mode_cutoff_hz`): their
/// quasi-static coordinates join the points' and the surface's modal sums apart.
#[test]
fn verification_liner_maps_equal_the_point_outputs_at_the_points() {
    let rom = small_rom();
    let cut = rom.frequencies_hz[2 * rom.frequencies_hz.len() / 3];
    for modes_below_hz in [None, Some(cut)] {
        println!("modes below {modes_below_hz:?} Hz");
        maps_equal_points(rom, modes_below_hz);
    }
}

fn maps_equal_points(rom: &EngineRom, modes_below_hz: Option<f64>) {
    let r = simulate(&[], |s| {
        s.tolerance = None;
        s.step_error = false;
        s.surface_maps = true;
        s.modes_below_hz = modes_below_hz;
    })
    .unwrap();
    assert_eq!(r.surface.len(), rom.cylinders.len());
    for (c, (cyl, map)) in rom.cylinders.iter().zip(&r.surface).enumerate() {
        let ns = cyl.surface.nodes.len();
        assert!(ns > 100, "cylinder {}: {ns} surface nodes", cyl.cylinder);
        assert_eq!(map.per_cycle.nrows(), ns);
        assert_eq!(map.per_cycle.ncols(), r.stats.cycles_averaged);
        let nm = cyl.point_modes.ncols();
        for p in 0..cyl.point_modes.nrows() {
            let dist = |n: usize| {
                (0..nm)
                    .map(|j| (cyl.surface.modes[[n, j]] - cyl.point_modes[[p, j]]).powi(2))
                    .sum::<f64>()
                    .sqrt()
            };
            let n = (0..ns)
                .min_by(|&a, &b| dist(a).total_cmp(&dist(b)))
                .unwrap();
            let norm = (0..nm)
                .map(|j| cyl.point_modes[[p, j]].powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(
                dist(n) <= 1e-9 * norm,
                "point {}: row {} of {norm}",
                p + 1,
                dist(n)
            );
            let res = (0..cyl.point_residual.ncols())
                .map(|j| (cyl.surface.residual[[n, j]] - cyl.point_residual[[p, j]]).abs())
                .fold(0.0, f64::max);
            let res_norm = cyl
                .point_residual
                .iter()
                .fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(
                res <= 1e-9 * res_norm,
                "point {}: residual {res} of {res_norm}",
                p + 1
            );
            let row = map.per_cycle.row(n);
            let mean = row.sum() / row.len() as f64;
            let largest = row.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let point = r.peak_negative[[c, p]];
            println!(
                "cylinder {} point {}: map {mean} / {largest}, point {} / {}",
                cyl.cylinder,
                p + 1,
                point.value,
                point.max
            );
            assert!((mean - point.value).abs() <= 1e-9 * point.value);
            assert!((largest - point.max).abs() <= 1e-9 * point.max);
        }
    }
}

/// Verification (issue 39: why a lubricated skirt integrates with HHT): a stiff damper,
/// v' = -c v with c dt = 1e4 (a squeeze film on a light mode), rings with the factor of the
/// scheme's recurrence in the limit c dt -> infinity. Average acceleration:
/// v_{n+1} / v_n = (1 - c dt / 2) / (1 + c dt / 2) -> -1 (no decay; a damping that falls
/// from step to step makes it grow). HHT-alpha, from (1 - gamma) [(1 + alpha) v_n - alpha
/// v_{n-1}] + gamma [(1 + alpha) v_{n+1} - alpha v_n] = 0: the larger root of
/// gamma (1 + alpha) r^2 + ((1 - gamma)(1 + alpha) - gamma alpha) r - (1 - gamma) alpha = 0,
/// -0.818 at alpha = -0.05. Tolerance 1e-3: the finite c dt moves the ratio by O(1 / (c dt)).
#[test]
fn verification_hht_damps_a_stiff_dampers_ringing() {
    let dt = 1e-5;
    let c = 1e4 / dt;
    let ratio = |scheme: Scheme| {
        // unit modal mass, omega 1 rad/s: 2 zeta omega = c
        let mut m = ModalIntegrator::new(&[1.0], &[0.5 * c], scheme);
        m.deta[0] = 1.0;
        m.ddeta[0] = -c;
        let mut v = Vec::new();
        for _ in 0..40 {
            m.predict(dt);
            m.commit(&[0.0]);
            v.push(m.deta[0]);
        }
        v[39] / v[38]
    };
    let newmark = ratio(Scheme::average_acceleration());
    let exact = (1.0 - 0.5 * c * dt) / (1.0 + 0.5 * c * dt);
    assert!((newmark - exact).abs() < 1e-9, "{newmark} against {exact}");
    assert!(newmark < -0.999);
    let alpha: f64 = -0.05;
    let g = 0.5 - alpha;
    let (a, b, q) = (
        g * (1.0 + alpha),
        (1.0 - g) * (1.0 + alpha) - g * alpha,
        -(1.0 - g) * alpha,
    );
    let root = (-b - (b * b - 4.0 * a * q).sqrt()) / (2.0 * a);
    let hht = ratio(Scheme::hht(alpha));
    println!("ringing per step: newmark {newmark:.5}, hht(-0.05) {hht:.5}, limit {root:.5}");
    assert!((hht - root).abs() < 1e-3, "{hht} against {root}");
    assert!((root + 0.818).abs() < 1e-3);
}
