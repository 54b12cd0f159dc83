//! Cavitation criteria and risk classes.
//!
//! Symbols: p_s static coolant pressure, p_v vapour pressure, rho density, c speed of sound,
//! h coolant gap (liner to crankcase wall), a liner wall acceleration (+ toward the coolant),
//! v liner wall velocity.
//!
//! The acceleration-based number: an inviscid, incompressible layer between the liner and
//! the crankcase wall obeys rho dv/dt = -dp/dx; across the gap h this gives
//! p_r - p_l = rho a h (p_r at the crankcase wall, p_l at the liner). When the liner pulls
//! away from the coolant (a < 0), p_l = p_r - rho |a| h, and vapour forms at the liner where
//! p_l < p_v, i.e. where Ca = (p_r - p_v) / (rho |a| h) < 1. The wall pressure itself swings
//! with the liner motion; a linear transfer p_r = p_s + k_p a closes the model, so on a
//! negative peak Ca(|a|) = (p_s - k_p |a| - p_v) / (rho |a| h), which is 1 at
//! |a|* = (p_s - p_v) / (k_p + rho h).
//!
//! Default k_p: the reference engine (p_s = 240 kPa, water at 90 C, h = 4.7 mm) showed high
//! risk from 1189 m/s^2; solving |a|* = 1189 for k_p gives
//! k_p = (p_s - p_v)/1189 - rho h = (240000 - 70182)/1189 - 965.3 x 0.0047 = 138.3 Pa/(m/s^2).
//! k_p is a property of the liner/jacket/coolant transfer, so it is derived once at the
//! reference state and kept when a scene changes the coolant state: a lower static pressure
//! or a hotter coolant then lowers the threshold, as it should.

use crate::coolant::{Coolant, CoolantError};
use crate::scene::ThresholdSpec;
use crate::text::num;

/// Reference study's coolant state and thresholds.
pub const REFERENCE_STATIC_PA: f64 = 240e3;
pub const REFERENCE_TEMP_C: f64 = 90.0;
pub const REFERENCE_GAP_M: f64 = 4.7e-3;
/// Peak negative acceleration above which every measured event cavitated [m/s^2].
pub const REFERENCE_HIGH_RISK: f64 = 1189.0;
/// Peak negative acceleration below which no event cavitated [m/s^2].
pub const REFERENCE_ONSET: f64 = 917.0;

/// Classic cavitation number Ca = (p_r - p_v) / (rho v^2 / 2).
pub fn classic_number(p_r: f64, coolant: &Coolant, v: f64) -> f64 {
    (p_r - coolant.vapour_pressure_pa) / (0.5 * coolant.density_kg_m3 * v * v)
}

/// Cavitation safety factor CSF = Vccv / Vmax; risk where CSF < 1.
pub fn safety_factor(coolant: &Coolant, v_max: f64) -> f64 {
    coolant.vccv() / v_max.abs()
}

/// Acceleration-based cavitation number on a negative peak of magnitude `a_neg`:
/// Ca = (p_r - p_v) / (rho |a| h) with p_r = max(p_s - k_p |a|, p_v): the wall pressure
/// cannot fall below the vapour pressure (it saturates there, as measured), so Ca >= 0.
pub fn acceleration_number(coolant: &Coolant, k_p: f64, gap: f64, a_neg: f64) -> f64 {
    let a = a_neg.abs();
    let p_r = (coolant.static_pa - k_p * a).max(coolant.vapour_pressure_pa);
    (p_r - coolant.vapour_pressure_pa) / (coolant.density_kg_m3 * a * gap)
}

/// |a|* where the acceleration number is 1: (p_s - p_v) / (k_p + rho h) [m/s^2].
pub fn threshold(coolant: &Coolant, k_p: f64, gap: f64) -> f64 {
    (coolant.static_pa - coolant.vapour_pressure_pa) / (k_p + coolant.density_kg_m3 * gap)
}

/// k_p that puts the Ca = 1 threshold at `a_star`: k_p = (p_s - p_v)/a* - rho h.
pub fn k_p_for_threshold(coolant: &Coolant, gap: f64, a_star: f64) -> f64 {
    (coolant.static_pa - coolant.vapour_pressure_pa) / a_star - coolant.density_kg_m3 * gap
}

/// The default k_p, derived from the reference engine (module doc) [Pa/(m/s^2)].
pub fn reference_k_p() -> Result<f64, CoolantError> {
    let c = Coolant::new(REFERENCE_TEMP_C, 0.0, REFERENCE_STATIC_PA)?;
    Ok(k_p_for_threshold(&c, REFERENCE_GAP_M, REFERENCE_HIGH_RISK))
}

/// Risk class of a peak negative acceleration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Risk {
    Safe,
    Transitional,
    High,
}

impl Risk {
    pub fn label(self) -> &'static str {
        match self {
            Risk::Safe => "safe",
            Risk::Transitional => "transitional",
            Risk::High => "high",
        }
    }
}

/// Thresholds of the risk classes [m/s^2]: safe below `onset`, high from `high_risk`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Thresholds {
    pub onset_m_s2: f64,
    pub high_risk_m_s2: f64,
    pub k_p_pa_per_m_s2: f64,
    /// Where they come from ("scene", "calibration FILE", "derived ...").
    #[serde(skip)]
    pub source: &'static str,
}

/// Resolved thresholds out of order.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("need 0 < onset ({}) <= high risk ({}) m/s^2", num(*.onset), num(*.high))]
pub struct ThresholdError {
    pub onset: f64,
    pub high: f64,
}

impl Thresholds {
    /// The scene's thresholds with the missing ones derived: k_p = [`reference_k_p`], the
    /// high-risk threshold |a|* = (p_s - p_v) / (k_p + rho h) ([`threshold`]), the onset
    /// |a|* 917 / 1189 (the reference study's proportion).
    pub fn resolve(
        spec: &ThresholdSpec,
        coolant: &Coolant,
        gap: f64,
    ) -> Result<Self, ThresholdError> {
        let t = match *spec {
            ThresholdSpec::Calibrated {
                onset_m_s2,
                high_risk_m_s2,
                k_p_pa_per_m_s2,
            } => Thresholds {
                onset_m_s2,
                high_risk_m_s2,
                k_p_pa_per_m_s2,
                source: "calibration file",
            },
            ThresholdSpec::Scene {
                onset_m_s2,
                high_risk_m_s2,
                k_p_pa_per_m_s2,
            } => {
                let k_p = k_p_pa_per_m_s2
                    .unwrap_or_else(|| reference_k_p().expect("reference coolant state is valid"));
                let high = high_risk_m_s2.unwrap_or_else(|| threshold(coolant, k_p, gap));
                let onset = onset_m_s2.unwrap_or(high * REFERENCE_ONSET / REFERENCE_HIGH_RISK);
                Thresholds {
                    onset_m_s2: onset,
                    high_risk_m_s2: high,
                    k_p_pa_per_m_s2: k_p,
                    source: "scene",
                }
            }
        };
        if !(t.onset_m_s2.is_finite() && t.high_risk_m_s2.is_finite())
            || t.onset_m_s2 <= 0.0
            || t.onset_m_s2 > t.high_risk_m_s2
        {
            return Err(ThresholdError {
                onset: t.onset_m_s2,
                high: t.high_risk_m_s2,
            });
        }
        Ok(t)
    }

    pub fn classify(&self, a_neg: f64) -> Risk {
        let a = a_neg.abs();
        if a >= self.high_risk_m_s2 {
            Risk::High
        } else if a >= self.onset_m_s2 {
            Risk::Transitional
        } else {
            Risk::Safe
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reference() -> Coolant {
        Coolant::new(90.0, 0.0, 240e3).unwrap()
    }

    /// Hand computation (module doc): k_p = 169818/1189 - 965.3 x 0.0047 = 138.3.
    #[test]
    fn reference_k_p_is_about_138() {
        let k = reference_k_p().unwrap();
        assert!((k - 138.3).abs() < 0.2, "{k}");
        // and it reproduces the 1189 threshold exactly
        let c = reference();
        assert!((threshold(&c, k, REFERENCE_GAP_M) - 1189.0).abs() < 1e-9);
        assert!((acceleration_number(&c, k, REFERENCE_GAP_M, 1189.0) - 1.0).abs() < 1e-12);
    }

    /// Hand values: Ca at 600 m/s^2 with k_p = 138.3: (240000 - 82980 - 70182)/(965.3 x 600 x
    /// 0.0047) = 86838 / 2722.1 = 31.9; without the swing (k_p = 0) the static threshold is
    /// 169818 / (965.3 x 0.0047) = 37430 m/s^2 (the swing is what makes thin layers risky).
    #[test]
    fn acceleration_number_by_hand() {
        let c = reference();
        let ca = acceleration_number(&c, 138.3, 4.7e-3, -600.0);
        assert!((ca - 31.9).abs() < 0.05, "{ca}");
        assert!((c.static_threshold(4.7e-3) - 37_430.0).abs() < 20.0);
        // beyond p_s - k_p |a| = p_v the wall pressure saturates: Ca = 0
        assert_eq!(acceleration_number(&c, 138.3, 4.7e-3, 2000.0), 0.0);
    }

    /// Classic number and CSF by hand: v = 0.2 m/s: Ca = 169818 / (0.5 x 965.3 x 0.04) = 8796;
    /// CSF = 0.1135 / 0.2 = 0.567.
    #[test]
    fn classic_criteria_by_hand() {
        let c = reference();
        assert!((classic_number(240e3, &c, 0.2) - 8796.0).abs() < 3.0);
        assert!((safety_factor(&c, -0.2) - 0.5675).abs() < 1e-3);
    }

    #[test]
    fn classes() {
        let t = Thresholds {
            onset_m_s2: 917.0,
            high_risk_m_s2: 1189.0,
            k_p_pa_per_m_s2: 138.3,
            source: "test",
        };
        assert_eq!(t.classify(900.0), Risk::Safe);
        assert_eq!(t.classify(917.0), Risk::Transitional);
        assert_eq!(t.classify(-1200.0), Risk::High);
    }
}
