//! The scene's description of each stage's input as plain data: materials, element kinds,
//! the generated parts' geometry and meshing, the skirt and the combustion model. The stages
//! that use them (`mesh`, `fem`, `piston`) add their behaviour; the scene only describes.

use serde::{Deserialize, Serialize};

/// Isotropic elastic solid, SI units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Elastic {
    /// Young's modulus E \[Pa\], > 0.
    pub young: f64,
    /// Poisson's ratio nu [-], in (-1, 0.5).
    pub poisson: f64,
    /// Density rho [kg/m^3], > 0.
    pub density: f64,
}

/// An elastic constant outside its physical bounds ([`Elastic::validate`]); the message names
/// the quantity, its bound and the value given.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ElasticError {
    #[error("Young's modulus must lie in [1e3, 1e14] Pa, got {}", crate::text::exact(*.0))]
    Young(f64),
    #[error("Poisson's ratio must lie in (-1, 0.5), got {}", crate::text::exact(*.0))]
    Poisson(f64),
    #[error("density must lie in [1, 1e5] kg/m^3, got {}", crate::text::exact(*.0))]
    Density(f64),
    #[error("E {} Pa and density {} kg/m^3 give a bar wave speed sqrt(E / rho) of {} m/s, above the {} m/s no solid reaches (diamond: 17,300 m/s): are E and the density in one unit system?", crate::text::num(*young), crate::text::num(*density), crate::text::num(*speed), crate::text::num(MAX_WAVE_SPEED))]
    WaveSpeed {
        young: f64,
        density: f64,
        speed: f64,
    },
}

/// The largest bar wave speed sqrt(E / rho) a material may have \[m/s\]: 2.9 times diamond's
/// (1.05e12 Pa, 3,515 kg/m^3: 17,300 m/s; steel 5,200). mm-t-s constants read as SI (E in
/// MPa, rho in t/mm^3) give 1e6 times too fast a wave; E in MPa beside rho in kg/m^3 gives
/// 1,000 times too slow a one, which [`Elastic::structural_warning`] warns of. At steel's
/// density this bound caps E near 2e13 Pa.
pub const MAX_WAVE_SPEED: f64 = 5e4;

/// Young's moduli of structural metals and composites \[Pa\] (outside: a warning).
pub const STRUCTURAL_YOUNG: (f64, f64) = (1e9, 1e12);

impl Elastic {
    /// Checks the physical bounds. Upper bounds: 100 times the stiffest (diamond, 1.2e12 Pa)
    /// and 4 times the densest (osmium, 22,600 kg/m^3) solid; beyond them the matrices
    /// overflow or are no solid's. Lower bounds: 1e3 Pa (below gels; elastomers 1e6) and 1
    /// kg/m^3 (aerogels): below them the constants are a unit mistake or roundoff (1e-300 gave
    /// a singular factorisation instead of this message). The bar wave speed sqrt(E / rho)
    /// at most [`MAX_WAVE_SPEED`].
    pub fn validate(&self) -> Result<(), ElasticError> {
        if !(self.young.is_finite() && (1e3..=1e14).contains(&self.young)) {
            return Err(ElasticError::Young(self.young));
        }
        if !(self.poisson.is_finite() && self.poisson > -1.0 && self.poisson < 0.5) {
            return Err(ElasticError::Poisson(self.poisson));
        }
        if !(self.density.is_finite() && (1.0..=1e5).contains(&self.density)) {
            return Err(ElasticError::Density(self.density));
        }
        let speed = (self.young / self.density).sqrt();
        if speed > MAX_WAVE_SPEED {
            return Err(ElasticError::WaveSpeed {
                young: self.young,
                density: self.density,
                speed,
            });
        }
        Ok(())
    }
    /// A warning when Young's modulus lies outside [`STRUCTURAL_YOUNG`] (valid, but no metal's
    /// or composite's: E given in MPa as Pa, say), naming the material as `what`.
    pub fn structural_warning(&self, what: &str) -> Option<String> {
        let (lo, hi) = STRUCTURAL_YOUNG;
        (!(lo..=hi).contains(&self.young)).then(|| {
            format!(
                "{what}: Young's modulus {} Pa is outside the range of structural materials ({}-{} Pa)",
                crate::text::num(self.young),
                crate::text::num(lo),
                crate::text::num(hi)
            )
        })
    }

    /// First Lame constant lambda \[Pa\].
    pub fn lambda(&self) -> f64 {
        self.young * self.poisson / ((1.0 + self.poisson) * (1.0 - 2.0 * self.poisson))
    }
    /// Shear modulus mu \[Pa\].
    pub fn mu(&self) -> f64 {
        self.young / (2.0 * (1.0 + self.poisson))
    }
}

/// Supported 3-D solid element kinds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, PartialOrd, Ord)]
#[serde(rename_all = "lowercase")]
pub enum ElementKind {
    Tet4,
    Tet10,
    Hex8,
    Hex20,
}

/// Liner geometry, SI units (metres).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct LinerGeometry {
    pub outer_diameter: f64,
    pub inner_diameter: f64,
    pub length: f64,
    pub flange_outer_diameter: f64,
    pub flange_height: f64,
    pub guide_height: f64,
    /// Height z of the guide band's lower edge above the liner bottom (0: the band ends the
    /// liner).
    pub guide_bottom: f64,
    /// Depths of the analysis points below the liner top, top to bottom.
    pub analysis_depths: Vec<f64>,
    /// Diameter of the pilot surfaces (the guide band, and the part above `deck_underside`),
    /// the crankcase's bore; equal to `outer_diameter` for a plain tube.
    pub pilot_diameter: f64,
    /// Height of the crankcase deck's underside above the liner bottom: from there up to the
    /// flange the liner sits in the deck bore at the pilot diameter (None: no crankcase).
    pub deck_underside: Option<f64>,
}

impl LinerGeometry {
    /// The upper pilot's lower edge: the deck's underside when the pilots differ from the wet
    /// wall and it lies between the guide band and the flange (a plane of the generated mesh).
    pub fn deck_plane(&self) -> Option<f64> {
        self.deck_in_wall()
            .filter(|_| self.pilot_diameter != self.outer_diameter)
    }

    /// The deck's underside when it lies between the guide band's top and the flange: the
    /// top of the coolant zone (where the liner enters the deck bore).
    pub fn deck_in_wall(&self) -> Option<f64> {
        let guide_top = self.guide_bottom + self.guide_height;
        let z_flange = self.length - self.flange_height;
        self.deck_underside
            .filter(|&z| z > guide_top && z < z_flange)
    }

    /// The axial planes every generated liner mesh has, ascending and distinct: its ends, the
    /// guide band's edges, the flange underside, the analysis points and [`Self::deck_plane`].
    pub fn axial_planes(&self) -> Vec<f64> {
        let guide_top = self.guide_bottom + self.guide_height;
        let z_flange = self.length - self.flange_height;
        let mut planes = vec![0.0, self.guide_bottom, guide_top, z_flange, self.length];
        planes.extend(self.deck_plane());
        planes.extend(self.analysis_depths.iter().map(|d| self.length - d));
        planes.sort_by(|a, b| a.partial_cmp(b).unwrap());
        planes.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
        planes
    }
}

/// Mesh density and element kind of the generated liner.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct LinerMeshing {
    pub kind: ElementKind,
    /// Elements around the circumference (multiple of 4).
    pub circumferential: usize,
    /// Elements through the wall.
    pub radial: usize,
    /// Elements across the flange overhang.
    pub radial_flange: usize,
    /// Target axial element size \[m\].
    pub axial_size: f64,
}

/// Crankcase geometry, SI (metres).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CrankcaseGeometry {
    pub cylinders: usize,
    pub pitch: f64,
    /// Bore radius r_b (the liner's pilot radius): bore of the deck ledge and of the lower
    /// support.
    pub bore_radius: f64,
    /// Flange radius r_f: outer edge of the seat annulus, inner face of the jacket wall.
    pub flange_radius: f64,
    /// Height of the flange seat (deck top face) above the liner bottom.
    pub seat_z: f64,
    pub guide_height: f64,
    /// Height of the guide band's lower edge above the liner bottom.
    pub guide_bottom: f64,
    pub deck_thickness: f64,
    /// Thrust/anti-thrust jacket wall thickness t_w at the cylinder centre line.
    pub jacket_wall: f64,
    /// Depth of the crank bay below the liner bottom (bottom face at z = -skirt_depth).
    pub skirt_depth: f64,
    pub front_wall: f64,
    pub rear_wall: f64,
    pub rail_width: f64,
    pub rail_height: f64,
    /// Heights of the analysis points (z), top to bottom.
    pub analysis_z: Vec<f64>,
}

/// Mesh density of the generated crankcase.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CrankcaseMeshing {
    pub kind: ElementKind,
    /// Elements per quarter sector of the circumference (even).
    pub per_sector: usize,
    /// Element rings through the jacket wall.
    pub wall_layers: usize,
    /// Target axial element size \[m\].
    pub axial_size: f64,
}

/// Skirt geometry and thermal state, SI.
#[derive(Clone, Debug, PartialEq)]
pub struct SkirtSpec {
    pub bore: f64,
    pub length: f64,
    /// Skirt top above the pin \[m\].
    pub top_above_pin: f64,
    pub slices: usize,
    /// Cold diametral clearance at the widest height \[m\].
    pub clearance: f64,
    /// Radial barrel drop at the farther skirt end \[m\] and the widest height below the pin \[m\].
    pub barrel: f64,
    pub barrel_max_below_pin: f64,
    /// Ovality (thrust-axis minus pin-axis diameter) \[m\].
    pub ovality: f64,
    /// Thermal expansion of piston and liner [1/K], temperatures [deg C].
    pub piston_expansion: f64,
    pub skirt_top_temp_c: f64,
    pub skirt_bottom_temp_c: f64,
    pub liner_expansion: f64,
    pub liner_temp_c: f64,
    pub reference_temp_c: f64,
    /// Contact stiffness per slice [N/m].
    pub stiffness: f64,
}

/// Which skirt film model runs (`piston.lubrication`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Lubrication {
    /// No film: the dry penalty contact only (the reference study's model).
    Dry,
    /// Hydrodynamic squeeze and sliding film.
    Squeeze,
    /// The film plus Greenwood-Tripp asperity contact.
    Mixed,
}

impl Lubrication {
    pub fn name(self) -> &'static str {
        match self {
            Lubrication::Dry => "dry",
            Lubrication::Squeeze => "squeeze",
            Lubrication::Mixed => "mixed",
        }
    }
}

/// Greenwood-Tripp's inputs, SI: composite roughness sigma \[m\], eta beta sigma, sigma / beta,
/// composite modulus E' \[Pa\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AsperitySpec {
    pub sigma: f64,
    pub eta_beta_sigma: f64,
    pub sigma_over_beta: f64,
    pub modulus: f64,
}

/// An oil supply below this \[um\] is a starved film, which may stop a lubricated run: the
/// film wets where the gap is below 1.5 times the supply, so below 3 um of supply its wetted
/// band lies within 1.5 um of the Reynolds term's gap floor
/// ([`crate::piston::lubrication::FILM_FLOOR`], 3 um), where the film is a damper of fixed
/// gap switched on and off by the wetting (docs/validation.md: on the test engine 1, 1.5 and
/// 2 um stop, 2.5 um and more run); the scene is warned of it and a stopped run's error says
/// so.
pub const STARVED_SUPPLY_UM: f64 = 3.0;

/// Whether an oil supply of `supply` \[m\] is starved ([`STARVED_SUPPLY_UM`]; compared in um
/// with a margin for the unit's rounding, so 3 um is not).
pub fn starved(supply: f64) -> bool {
    supply * 1e6 < STARVED_SUPPLY_UM - 1e-9
}

/// The skirt's oil film, SI (see [`crate::scene::raw::RawOil`]).
#[derive(Clone, Debug, PartialEq)]
pub struct OilSpec {
    pub model: Lubrication,
    /// Oil on the liner \[m\].
    pub supply: f64,
    /// Vogel's mu = a exp(b / (T + c)): a \[Pa s\], b and c \[deg C\].
    pub vogel: [f64; 3],
    /// Greenwood-Tripp asperity contact (`mixed`).
    pub asperity: Option<AsperitySpec>,
}

/// Parameters of the built-in Wiebe curve at full load (SI, angles in degrees).
#[derive(Clone, Debug, PartialEq)]
pub struct Wiebe {
    /// Geometric compression ratio eps.
    pub compression_ratio: f64,
    /// Intake (boost) pressure at full load, absolute \[Pa\]; falls linearly to 1 bar at no load.
    pub intake_pa: f64,
    /// Exhaust back-pressure above the intake pressure \[Pa\].
    pub exhaust_over_intake_pa: f64,
    /// Start of combustion \[deg\] and its duration \[deg\].
    pub start_deg: f64,
    pub duration_deg: f64,
    /// Wiebe efficiency and shape parameters a, m.
    pub a: f64,
    pub m: f64,
    /// Heat released per cycle at full load \[J\] (net of wall losses).
    pub heat_j: f64,
    /// Polytropic exponent n of the closed cycle.
    pub polytropic: f64,
    /// Exhaust valve opening \[deg\].
    pub evo_deg: f64,
    /// Load fraction in [0, 1].
    pub load: f64,
}

/// The time-integration rule of the transient (`transient.scheme`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum SchemeChoice {
    /// Newmark's average acceleration (beta 1/4, gamma 1/2): second order, no numerical
    /// damping.
    AverageAcceleration,
    /// Hilber-Hughes-Taylor alpha in [-1/3, 0]: damps the high modes.
    Hht { alpha: f64 },
}

/// Where the risk thresholds come from, as the scene states them; the cavitation stage
/// resolves them against the coolant ([`crate::cavitation::criteria::Thresholds::resolve`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ThresholdSpec {
    /// From a calibration file (`linercav calibrate --json`): all three given [m/s^2, Pa/(m/s^2)].
    Calibrated {
        onset_m_s2: f64,
        high_risk_m_s2: f64,
        k_p_pa_per_m_s2: f64,
    },
    /// From the scene's keys; each one left out is derived (k_p from the reference engine,
    /// the high-risk threshold from Ca = 1, the onset in the reference study's proportion).
    Scene {
        onset_m_s2: Option<f64>,
        high_risk_m_s2: Option<f64>,
        k_p_pa_per_m_s2: Option<f64>,
    },
}

/// The length unit of a mesh file's coordinates: metres (and SI constants), or millimetres
/// in the mm-t-s system (E in MPa, rho in t/mm^3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum MeshUnit {
    #[default]
    M,
    Mm,
}

impl MeshUnit {
    /// Parses `"m"` or `"mm"`.
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "m" => Some(Self::M),
            "mm" => Some(Self::Mm),
            _ => None,
        }
    }
    /// Metres per unit of length.
    pub fn metres(self) -> f64 {
        match self {
            Self::M => 1.0,
            Self::Mm => 1e-3,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            Self::M => "m",
            Self::Mm => "mm",
        }
    }
}

#[cfg(test)]
mod tests {
    /// Contract: the starved-film threshold is read in um as the scene gives it: 3 um (stored
    /// as 3 x 1e-6 m, a rounding off 3e-6) is not starved, 2.99 um is.
    #[test]
    fn contract_three_um_of_oil_is_not_starved() {
        assert!(!super::starved(3.0 * 1e-6));
        assert!(!super::starved(20.0 * 1e-6));
        assert!(super::starved(2.99 * 1e-6));
        assert!(super::starved(1.0 * 1e-6));
    }

    /// Regression: a refused material value was printed rounded, so a Poisson's ratio just
    /// above the bound read as the bound itself ("must lie in (-1, 0.5), got 0.5").
    #[test]
    fn regression_a_refused_poisson_ratio_is_printed_as_given() {
        let m = super::Elastic {
            young: 2.1e11,
            poisson: 0.500000001,
            density: 7850.0,
        };
        let msg = m.validate().unwrap_err().to_string();
        assert!(msg.contains("got 0.500000001"), "{msg}");
    }
}
