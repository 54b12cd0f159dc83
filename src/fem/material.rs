//! Isotropic linear-elastic material.
//!
//! Lame constants: lambda = E nu / ((1 + nu)(1 - 2 nu)), mu = E / (2 (1 + nu)).

use serde::{Deserialize, Serialize};

/// Isotropic elastic solid, SI units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Elastic {
    /// Young's modulus E [Pa], > 0.
    pub young: f64,
    /// Poisson's ratio nu [-], in (-1, 0.5).
    pub poisson: f64,
    /// Density rho [kg/m^3], > 0.
    pub density: f64,
}

impl Elastic {
    /// Checks the physical bounds; the message names the offending quantity and its bound.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.young.is_finite() && self.young > 0.0) {
            return Err(format!(
                "Young's modulus must be a positive number of Pa, got {}",
                self.young
            ));
        }
        if !(self.poisson.is_finite() && self.poisson > -1.0 && self.poisson < 0.5) {
            return Err(format!(
                "Poisson's ratio must lie in (-1, 0.5), got {}",
                self.poisson
            ));
        }
        if !(self.density.is_finite() && self.density > 0.0) {
            return Err(format!(
                "density must be a positive number of kg/m^3, got {}",
                self.density
            ));
        }
        Ok(())
    }
    /// First Lame constant lambda [Pa].
    pub fn lambda(&self) -> f64 {
        self.young * self.poisson / ((1.0 + self.poisson) * (1.0 - 2.0 * self.poisson))
    }
    /// Shear modulus mu [Pa].
    pub fn mu(&self) -> f64 {
        self.young / (2.0 * (1.0 + self.poisson))
    }
}
