//! Crank-slider kinematics with pin and crank offsets.
//!
//! Frame: z up along the bore axis from the crankshaft axis, y toward the thrust side. The crank
//! turns so that the crank pin is on the anti-thrust side during the expansion stroke:
//! crank pin at (y, z) = (-r sin theta, r cos theta), theta = 0 at top dead centre. The piston pin
//! sits at the lateral offset e = pin offset - crank offset (+ toward thrust). The rod of length
//! l joins them:
//!
//!   s(theta) = e + r sin theta,  sin beta = s / l,
//!   z(theta) = r cos theta + sqrt(l^2 - s^2).
//!
//! A compressive rod force C pushes the pin along the rod, (sin beta, cos beta) C, so during
//! the expansion stroke (sin theta > 0) the piston is pressed against the thrust side.
//! Derivatives at constant speed omega (g = sqrt(l^2 - s^2)):
//!   s' = r omega cos theta, s'' = -r omega^2 sin theta,
//!   g' = -s s' / g,  g'' = -(s'^2 + s s'') / g - s^2 s'^2 / g^3,
//!   z' = -r omega sin theta + g',  z'' = -r omega^2 cos theta + g''.
//! The rod's angular velocity, in the sense in which its top moves toward thrust:
//!   beta' = d/dt asin(s / l) = s' / (l cos beta) = s' / g.

/// Crank radius, rod length, lateral offset and speed, SI.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CrankSlider {
    /// Crank radius r = stroke / 2 \[m\].
    pub radius: f64,
    /// Connecting-rod length l \[m\].
    pub rod: f64,
    /// Lateral pin offset relative to the crank axis e \[m\], + toward the thrust side.
    pub offset: f64,
    /// Crank speed omega [rad/s].
    pub omega: f64,
}

/// Piston pin motion at one crank angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PinMotion {
    /// Height above the crank axis \[m\], its velocity and acceleration.
    pub z: f64,
    pub dz: f64,
    pub ddz: f64,
    /// tan of the rod angle: lateral / axial share of the rod force.
    pub tan_beta: f64,
    /// The rod's angular velocity beta' = s' / g [rad/s] (+: its top turns toward thrust).
    pub rod_rate: f64,
}

impl CrankSlider {
    /// Pin motion at crank angle `theta` \[rad\] (0 = top dead centre).
    pub fn at(&self, theta: f64) -> PinMotion {
        let (r, l, w) = (self.radius, self.rod, self.omega);
        let (st, ct) = theta.sin_cos();
        let s = self.offset + r * st;
        let s1 = r * w * ct;
        let s2 = -r * w * w * st;
        let g = (l * l - s * s).sqrt();
        let g1 = -s * s1 / g;
        let g2 = -(s1 * s1 + s * s2) / g - s * s * s1 * s1 / (g * g * g);
        PinMotion {
            z: r * ct + g,
            dz: -r * w * st + g1,
            ddz: -r * w * w * ct + g2,
            tan_beta: s / g,
            rod_rate: s1 / g,
        }
    }

    /// Highest pin position sqrt((l + r)^2 - e^2) (rod and crank in line).
    pub fn z_top(&self) -> f64 {
        ((self.rod + self.radius).powi(2) - self.offset.powi(2)).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_match_finite_differences() {
        // Central differences: error O(h^2 z''') ~ 1e-9 relative at h = 1e-5 rad.
        let k = CrankSlider {
            radius: 0.0705,
            rod: 0.219,
            offset: 0.001,
            omega: 199.0,
        };
        let h = 1e-5;
        for i in 0..36 {
            let th = i as f64 * 0.17 + 0.05;
            let (a, b, c) = (k.at(th - h), k.at(th), k.at(th + h));
            let dz = (c.z - a.z) / (2.0 * h) * k.omega;
            let ddz = (c.z - 2.0 * b.z + a.z) / (h * h) * k.omega * k.omega;
            assert!((dz - b.dz).abs() < 1e-6 * k.radius * k.omega);
            assert!((ddz - b.ddz).abs() < 1e-4 * k.radius * k.omega * k.omega);
            // beta' against the difference of beta = atan(tan beta)
            let rate = (c.tan_beta.atan() - a.tan_beta.atan()) / (2.0 * h) * k.omega;
            assert!((rate - b.rod_rate).abs() < 1e-6 * k.radius / k.rod * k.omega);
        }
        // No offset: top and bottom dead centres at 0 and pi with stroke 2r.
        let k0 = CrankSlider { offset: 0.0, ..k };
        assert!((k0.at(0.0).z - k0.z_top()).abs() < 1e-15);
        assert!((k0.at(0.0).z - k0.at(std::f64::consts::PI).z - 2.0 * k0.radius).abs() < 1e-12);
    }
}
