//! Coolant properties against temperature: water and ethylene-glycol/water mixtures.
//!
//! Sources (each function names its own):
//! - vapour pressure of water: IAPWS-IF97, region 4 saturation-pressure equation
//!   (IAPWS, "Revised Release on the IAPWS Industrial Formulation 1997", 2007, eq. 30);
//! - density of water: Kell (1975), J. Chem. Eng. Data 20, 97, air-free water at 1 atm,
//!   0-150 C (the pressure effect at a few bar is < 0.02 % and is neglected);
//! - speed of sound in water: Marczak (1997), J. Acoust. Soc. Am. 102, 2776, 0-95 C at 1 atm;
//! - mixtures: Raoult's law for the vapour pressure (ethylene glycol's own vapour pressure,
//!   about 1 kPa at 90 C, and the activity coefficient of water, 0.95-1 in these mixtures,
//!   are neglected), ideal mixing of specific volumes for the density (real 50 % mixtures
//!   are about 1.5-2 % denser), Wood's equation (volume-weighted compressibility) for the
//!   speed of sound, with pure ethylene glycol taken as rho = 1127 - 0.70 t kg/m^3 and
//!   c = 1658 - 2.1 (t - 25) m/s (t in C; handbook values, 20-100 C).

use crate::text::num;

/// Molar masses of water and ethylene glycol [kg/mol].
const M_WATER: f64 = 0.018_015;
const M_GLYCOL: f64 = 0.062_068;

/// Coolant state: what the criteria need.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Coolant {
    pub temp_c: f64,
    /// Ethylene glycol mass fraction in [0, 1).
    pub glycol: f64,
    /// Static pressure at the liner \[Pa\].
    pub static_pa: f64,
    pub vapour_pressure_pa: f64,
    pub density_kg_m3: f64,
    pub speed_of_sound_m_s: f64,
}

/// Why a coolant state cannot be evaluated.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum CoolantError {
    #[error("temperature {} C is outside 0-150 C (range of the water correlations)", num(*.0))]
    Temperature(f64),
    #[error("glycol mass fraction {} is outside [0, 0.8]", num(*.0))]
    Glycol(f64),
    #[error("static pressure {} kPa must be positive", num(*.0))]
    Pressure(f64),
    #[error("static pressure {} kPa is not above the vapour pressure {vapour_kpa:.2} kPa: the coolant boils", num(*static_kpa))]
    Boiling { static_kpa: f64, vapour_kpa: f64 },
}

impl Coolant {
    /// Properties at `temp_c` \[C\], glycol mass fraction `glycol`, static pressure `static_pa`.
    pub fn new(temp_c: f64, glycol: f64, static_pa: f64) -> Result<Self, CoolantError> {
        if !(0.0..=150.0).contains(&temp_c) {
            return Err(CoolantError::Temperature(temp_c));
        }
        if !(0.0..=0.8).contains(&glycol) {
            return Err(CoolantError::Glycol(glycol));
        }
        if !(static_pa.is_finite() && static_pa > 0.0) {
            return Err(CoolantError::Pressure(static_pa / 1e3));
        }
        let c = Coolant {
            temp_c,
            glycol,
            static_pa,
            vapour_pressure_pa: mixture_vapour_pressure(temp_c, glycol),
            density_kg_m3: mixture_density(temp_c, glycol),
            speed_of_sound_m_s: mixture_speed_of_sound(temp_c, glycol),
        };
        if c.static_pa <= c.vapour_pressure_pa {
            return Err(CoolantError::Boiling {
                static_kpa: static_pa / 1e3,
                vapour_kpa: c.vapour_pressure_pa / 1e3,
            });
        }
        Ok(c)
    }

    /// Critical velocity of the cavitation safety factor, from p_s - p_v = rho c Vccv:
    /// Vccv = (p_s - p_v) / (rho c) [m/s].
    pub fn vccv(&self) -> f64 {
        (self.static_pa - self.vapour_pressure_pa) / (self.density_kg_m3 * self.speed_of_sound_m_s)
    }

    /// Static acceleration threshold of a layer of thickness `gap` \[m\] with a rigid far wall
    /// (no pressure swing at the crankcase wall, k_p = 0): Ca = 1 at
    /// |a| = (p_s - p_v) / (rho h) [m/s^2].
    pub fn static_threshold(&self, gap: f64) -> f64 {
        (self.static_pa - self.vapour_pressure_pa) / (self.density_kg_m3 * gap)
    }
}

/// Saturation pressure of water \[Pa\] at `temp_c`, IAPWS-IF97 region 4 (eq. 30):
/// theta = T + n9 / (T - n10), A = theta^2 + n1 theta + n2, B = n3 theta^2 + n4 theta + n5,
/// C = n6 theta^2 + n7 theta + n8, p_s = [2C / (-B + sqrt(B^2 - 4AC))]^4 MPa.
/// Valid 273.15-647.096 K.
pub fn water_vapour_pressure(temp_c: f64) -> f64 {
    const N: [f64; 10] = [
        0.116_705_214_527_67e4,
        -0.724_213_167_032_06e6,
        -0.170_738_469_400_92e2,
        0.120_208_247_024_70e5,
        -0.323_255_503_223_33e7,
        0.149_151_086_135_30e2,
        -0.482_326_573_615_91e4,
        0.405_113_405_420_57e6,
        -0.238_555_575_678_49,
        0.650_175_348_447_98e3,
    ];
    let t = temp_c + 273.15;
    let th = t + N[8] / (t - N[9]);
    let a = th * th + N[0] * th + N[1];
    let b = N[2] * th * th + N[3] * th + N[4];
    let c = N[5] * th * th + N[6] * th + N[7];
    let x = 2.0 * c / (-b + (b * b - 4.0 * a * c).sqrt());
    x.powi(4) * 1e6
}

/// Density of air-free water at 1 atm [kg/m^3], Kell (1975):
/// rho = (999.83952 + 16.945176 t - 7.9870401e-3 t^2 - 46.170461e-6 t^3 + 105.56302e-9 t^4
/// - 280.54253e-12 t^5) / (1 + 16.879850e-3 t), t in C.
pub fn water_density(temp_c: f64) -> f64 {
    let t = temp_c;
    let num = 999.839_52
        + t * (16.945_176
            + t * (-7.987_040_1e-3
                + t * (-46.170_461e-6 + t * (105.563_02e-9 - t * 280.542_53e-12))));
    num / (1.0 + 16.879_850e-3 * t)
}

/// Speed of sound in water at 1 atm [m/s], Marczak (1997):
/// c = 1402.385 + 5.038813 t - 5.799136e-2 t^2 + 3.287156e-4 t^3 - 1.398845e-6 t^4
/// + 2.787860e-9 t^5, t in C (fitted 0-95 C; used up to 150 C with a growing error).
pub fn water_speed_of_sound(temp_c: f64) -> f64 {
    let t = temp_c;
    1402.385
        + t * (5.038_813
            + t * (-5.799_136e-2 + t * (3.287_156e-4 + t * (-1.398_845e-6 + t * 2.787_860e-9))))
}

/// Density of pure ethylene glycol [kg/m^3] (handbook values 20-100 C, linear).
fn glycol_density(temp_c: f64) -> f64 {
    1127.0 - 0.70 * temp_c
}

/// Speed of sound in pure ethylene glycol [m/s] (handbook values, linear).
fn glycol_speed_of_sound(temp_c: f64) -> f64 {
    1658.0 - 2.1 * (temp_c - 25.0)
}

/// Mole fraction of water for glycol mass fraction `w`: x = (1-w)/M_w / ((1-w)/M_w + w/M_g).
pub fn water_mole_fraction(glycol: f64) -> f64 {
    let nw = (1.0 - glycol) / M_WATER;
    let ng = glycol / M_GLYCOL;
    nw / (nw + ng)
}

/// Vapour pressure of the mixture \[Pa\], Raoult's law: p_v = x_w p_sat,water(T).
pub fn mixture_vapour_pressure(temp_c: f64, glycol: f64) -> f64 {
    water_mole_fraction(glycol) * water_vapour_pressure(temp_c)
}

/// Density of the mixture [kg/m^3], ideal mixing of specific volumes:
/// 1/rho = (1-w)/rho_w + w/rho_g.
pub fn mixture_density(temp_c: f64, glycol: f64) -> f64 {
    1.0 / ((1.0 - glycol) / water_density(temp_c) + glycol / glycol_density(temp_c))
}

/// Speed of sound of the mixture [m/s], Wood's equation:
/// 1/(rho c^2) = phi_w/(rho_w c_w^2) + phi_g/(rho_g c_g^2), phi the volume fractions.
pub fn mixture_speed_of_sound(temp_c: f64, glycol: f64) -> f64 {
    let (rw, rg) = (water_density(temp_c), glycol_density(temp_c));
    let (cw, cg) = (water_speed_of_sound(temp_c), glycol_speed_of_sound(temp_c));
    let rho = mixture_density(temp_c, glycol);
    let phi_g = glycol * rho / rg;
    let phi_w = 1.0 - phi_g;
    let compressibility = phi_w / (rw * cw * cw) + phi_g / (rg * cg * cg);
    (1.0 / (rho * compressibility)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// IAPWS-IF97 verification values of the saturation-pressure equation (Table 35 of the
    /// release: 300, 500, 600 K); the release states them to 9 significant digits.
    #[test]
    fn if97_saturation_pressure_matches_the_release_table() {
        for (t, p_mpa) in [
            (300.0, 0.353_658_941e-2),
            (500.0, 0.263_889_776e1),
            (600.0, 0.123_443_146e2),
        ] {
            let p = water_vapour_pressure(t - 273.15) / 1e6;
            assert!((p / p_mpa - 1.0).abs() < 1e-8, "{t} K: {p} vs {p_mpa}");
        }
        // boiling point at 1 atm: 99.97 C (IAPWS-95 / ITS-90)
        let p = water_vapour_pressure(99.974);
        assert!((p / 101_325.0 - 1.0).abs() < 1e-4, "{p}");
    }

    /// Kell's density at 4 C (maximum, 999.97) and at 90 C (965.3, steam tables), speed of
    /// sound at 20 C (1482.3) and 90 C (1550.4): tabulated values, four digits.
    #[test]
    fn water_density_and_sound_speed_match_tables() {
        assert!((water_density(4.0) - 999.97).abs() < 0.02);
        assert!((water_density(90.0) - 965.3).abs() < 0.1);
        assert!((water_speed_of_sound(20.0) - 1482.3).abs() < 0.2);
        assert!((water_speed_of_sound(90.0) - 1550.4).abs() < 0.5);
    }

    /// Vccv for the reference coolant (240 kPa, 90 C water): by hand,
    /// (240 - 70.18) kPa / (965.3 kg/m^3 x 1550.4 m/s) = 0.1135 m/s.
    #[test]
    fn vccv_of_the_reference_coolant() {
        let c = Coolant::new(90.0, 0.0, 240e3).unwrap();
        assert!(
            (c.vapour_pressure_pa - 70_182.0).abs() < 5.0,
            "{}",
            c.vapour_pressure_pa
        );
        assert!((c.vccv() - 0.1135).abs() < 2e-4, "{}", c.vccv());
    }

    /// A 50 % mixture: x_w = 0.775 by hand ((0.5/18.015)/(0.5/18.015 + 0.5/62.068));
    /// density between the components; sound speed between them.
    #[test]
    fn mixture_rules() {
        assert!((water_mole_fraction(0.5) - 0.7751).abs() < 1e-3);
        let p = mixture_vapour_pressure(90.0, 0.5);
        assert!((p / water_vapour_pressure(90.0) - 0.7751).abs() < 1e-3);
        let r = mixture_density(90.0, 0.5);
        assert!(r > water_density(90.0) && r < glycol_density(90.0));
        let c = mixture_speed_of_sound(90.0, 0.5);
        assert!(c > 1400.0 && c < 1700.0, "{c}");
        assert_eq!(mixture_density(90.0, 0.0), water_density(90.0));
        assert!((mixture_speed_of_sound(90.0, 0.0) - water_speed_of_sound(90.0)).abs() < 1e-9);
    }

    #[test]
    fn bad_states_are_refused() {
        assert!(matches!(
            Coolant::new(200.0, 0.0, 1e5),
            Err(CoolantError::Temperature(_))
        ));
        assert!(matches!(
            Coolant::new(90.0, 0.9, 1e5),
            Err(CoolantError::Glycol(_))
        ));
        assert!(matches!(
            Coolant::new(120.0, 0.0, 1e5),
            Err(CoolantError::Boiling { .. })
        ));
        assert!(matches!(
            Coolant::new(90.0, 0.0, f64::NAN),
            Err(CoolantError::Pressure(_))
        ));
    }
}
