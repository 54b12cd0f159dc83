//! The piston: crank-slider kinematics, cylinder pressure, skirt profile and contact law, and
//! its secondary-motion equations.
//!
//! Secondary motion of one piston, q = (y, phi): y the lateral displacement of the piston axis
//! from the bore axis (+ toward thrust), phi the tilt about the pin (+ when the crown moves
//! toward thrust). The piston (mass m_p, centre of gravity a above and b beside the pin, tilt
//! inertia I_pin about the pin) and the pin (mass m_pin) move vertically with the pin motion
//! z(theta) of [`kinematics`]; the rod is a massless link (its small-end share is part of the
//! pin mass). With the gas force F_g = (p - p_cc) A on the crown (on the piston axis, the pin
//! offset e_p beside the pin):
//!
//!   [m_p + m_pin   m_p a ] [y'' ]   [ C_z tan(beta)           ]
//!   [m_p a         I_pin ] [phi''] = [ -e_p F_g + b m_p z''    ] + sum_i F_i b_i,
//!   C_z = F_g + (m_p + m_pin) z''   (vertical balance: the rod's axial push),
//!
//! F_i >= 0 the contact force of skirt slice i (height h_i above the pin) with the penetration
//! p_i = s_i . q - g_i - u_i: s_i = (1, h_i) on the thrust side, (-1, -h_i) on the anti-thrust
//! side. Its generalised force is b_i = -s_i + mu sgn(z') (tan(beta), +-R) with friction
//! coefficient mu: the friction force -mu F sgn(z') acts on the skirt surface (lever +-R about
//! the pin) and adds to the rod force.
//! The quasi-static side force pressing the liner toward thrust is C_z tan(beta).
//!
//! Pin friction (optional, `piston.pin_friction`): the pin journal turns in the piston's bosses
//! and the rod's small end; when the rod turns against the piston (beta' - phi' != 0) the
//! slipping joint transmits the friction torque
//!   T = mu_pin r_pin F_pin tanh((beta' - phi') / w_s)
//! on the tilt (it drags the piston toward the rod's rotation). F_pin is the load of the joint
//! that slips first: a floating pin (its own inertia negligible) carries the same torque
//! through both joints, so the smaller capacity decides,
//!   F_pin = min(|F_boss|, |F_rod|),  F_boss = |(F_g + m_p z'', C_z tan(beta))|,
//!   F_rod = |C_z| / cos(beta) = |C_z| sqrt(1 + tan^2(beta)),
//! (the boss carries the gas force and the piston's inertia, the small end also the pin's;
//! the lateral share is the quasi-static side force). tanh regularises Coulomb's sign over the
//! slip rate w_s (the journal's boundary-to-hydrodynamic transition); beta' = s' / g from
//! [`kinematics`].

pub mod kinematics;
pub mod lubrication;
pub mod pressure;
pub mod setup;
pub mod skirt;

use kinematics::CrankSlider;
use pressure::PressureCurve;
use skirt::Skirt;

/// One piston with its cylinder pressure, SI.
#[derive(Clone, Debug)]
pub struct Piston {
    pub kinematics: CrankSlider,
    pub pressure: PressureCurve,
    /// Crankcase (back-side) pressure \[Pa\].
    pub crankcase_pa: f64,
    /// Bore area A [m^2].
    pub area: f64,
    pub mass: f64,
    pub pin_mass: f64,
    /// Tilt inertia about the pin axis [kg m^2].
    pub tilt_inertia: f64,
    /// Centre of gravity above the pin \[m\] and beside it toward thrust \[m\].
    pub cg_above_pin: f64,
    pub cg_lateral: f64,
    /// Pin offset from the piston axis toward thrust \[m\].
    pub pin_offset: f64,
    /// Pin height below the liner top at top dead centre \[m\].
    pub pin_depth_at_tdc: f64,
    pub skirt: Skirt,
    /// Contact damping per slice [N s/m].
    pub contact_damping: f64,
    /// Coulomb friction coefficient of the skirt.
    pub friction: f64,
    /// The skirt's oil film (`None`: dry).
    pub film: Option<lubrication::Film>,
    /// Pin friction coefficient mu_pin (0: none), pin radius r_pin \[m\] and the slip rate w_s
    /// over which the pin's torque reverses [rad/s].
    pub pin_friction: f64,
    pub pin_radius: f64,
    pub pin_slip_rate: f64,
}

/// Loads on the secondary motion at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PistonLoads {
    /// Generalised force on (y, phi) without contact [N, N m].
    pub force: [f64; 2],
    /// Quasi-static side force C_z tan(beta) \[N\] (+: presses the thrust side).
    pub side_force: f64,
    /// Pin height below the liner top \[m\].
    pub pin_depth: f64,
    /// tan(beta) and the sign of the piston's axial velocity.
    pub tan_beta: f64,
    pub axial_sign: f64,
    /// The piston's axial velocity z' [m/s] (+ up, toward the liner's top).
    pub axial_velocity: f64,
    /// Gas pressure \[Pa\].
    pub pressure: f64,
    /// The pin's Coulomb torque mu_pin r_pin F_pin \[N m\] (0 without pin friction) and the
    /// rod's angular velocity beta' [rad/s] (see the module docs).
    pub pin_torque: f64,
    pub rod_rate: f64,
}

/// A lubricated skirt's film as a stopped run's error names it: the model, the oil supply
/// \[um\], the composite roughness \[um\] (`mixed`) and the film's viscosity over the skirt
/// (lowest, highest) \[mPa s\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilmSummary {
    pub model: &'static str,
    pub supply_um: f64,
    pub roughness_um: Option<f64>,
    pub viscosity_mpa_s: (f64, f64),
}

impl Piston {
    /// What a stopped run's error says of a lubricated skirt's film (None: dry).
    pub fn film_summary(&self) -> Option<FilmSummary> {
        self.film.as_ref().map(|f| {
            let (lo, hi) = f.mu.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &m| {
                (lo.min(m), hi.max(m))
            });
            FilmSummary {
                model: f.model.name(),
                supply_um: f.supply * 1e6,
                roughness_um: f.asperity.as_ref().map(|g| g.sigma * 1e6),
                viscosity_mpa_s: (lo * 1e3, hi * 1e3),
            }
        })
    }

    /// The 2 x 2 mass matrix of (y, phi), row-major.
    pub fn mass_matrix(&self) -> [[f64; 2]; 2] {
        let ma = self.mass * self.cg_above_pin;
        [[self.mass + self.pin_mass, ma], [ma, self.tilt_inertia]]
    }

    /// Loads at the cylinder's own crank angle `deg` (firing TDC at 360).
    pub fn loads(&self, deg: f64) -> PistonLoads {
        let k = self.kinematics.at(deg.to_radians());
        let p = self.pressure.at(deg);
        let fg = (p - self.crankcase_pa) * self.area;
        let cz = fg + (self.mass + self.pin_mass) * k.ddz;
        let side = cz * k.tan_beta;
        PistonLoads {
            force: [
                side,
                -self.pin_offset * fg + self.cg_lateral * self.mass * k.ddz,
            ],
            side_force: side,
            pin_depth: self.pin_depth_at_tdc + (self.kinematics.z_top() - k.z),
            tan_beta: k.tan_beta,
            axial_sign: if k.dz >= 0.0 { 1.0 } else { -1.0 },
            axial_velocity: k.dz,
            pressure: p,
            pin_torque: self.pin_coulomb_torque(fg, cz, &k),
            rod_rate: k.rod_rate,
        }
    }

    /// The pin's Coulomb torque mu_pin r_pin min(|F_boss|, |F_rod|) \[N m\] at gas force `fg`
    /// and rod push `cz` (module docs).
    fn pin_coulomb_torque(&self, fg: f64, cz: f64, k: &kinematics::PinMotion) -> f64 {
        if self.pin_friction == 0.0 {
            return 0.0;
        }
        let boss = (fg + self.mass * k.ddz).hypot(cz * k.tan_beta);
        let rod = cz.abs() * (1.0 + k.tan_beta * k.tan_beta).sqrt();
        self.pin_friction * self.pin_radius * boss.min(rod)
    }

    /// Kinematic row s_i (d p_i / d q) of slice `i` on the thrust (`thrust`) or anti-thrust side.
    pub fn slice_row(&self, i: usize, thrust: bool) -> [f64; 2] {
        let h = self.skirt.heights[i];
        if thrust {
            [1.0, h]
        } else {
            [-1.0, -h]
        }
    }

    /// Generalised force per unit contact force b_i of slice `i`.
    pub fn slice_force_row(&self, i: usize, thrust: bool, l: &PistonLoads) -> [f64; 2] {
        let s = self.slice_row(i, thrust);
        let r = self.area_radius();
        let side = if thrust { 1.0 } else { -1.0 };
        let mu = self.friction * l.axial_sign;
        [-s[0] + mu * l.tan_beta, -s[1] + mu * side * r]
    }

    fn area_radius(&self) -> f64 {
        (self.area / std::f64::consts::PI).sqrt()
    }
}
