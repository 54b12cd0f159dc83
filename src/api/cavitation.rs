//! `coolant` and `calibrate`: coolant properties with the critical velocity and thresholds, and
//! the calibration of the acceleration criterion from rig data.

use crate::cavitation::calibration::{self, Calibration, RigData};
use crate::cavitation::criteria;
use crate::coolant::Coolant;
use crate::error::{Error, Result};
use crate::report::calibration::draw_calibration;
use crate::text::num;
use std::path::PathBuf;

/// What `coolant` prints.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CoolantReport {
    pub temp_c: f64,
    pub static_kpa: f64,
    pub glycol: f64,
    pub vapour_pressure_kpa: f64,
    pub density_kg_m3: f64,
    pub speed_of_sound_m_s: f64,
    /// Critical velocity of the cavitation safety factor, (p_s - p_v) / (rho c).
    pub vccv_m_s: f64,
    /// With a gap: the static threshold (p_s - p_v)/(rho h) (no wall-pressure swing) and the
    /// threshold with the reference k_p, (p_s - p_v)/(k_p + rho h).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gap_mm: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub static_threshold_m_s2: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub threshold_m_s2: Option<f64>,
    /// With a gap: the coolant layer's mass per unit wall area rho h [kg/m^2], what
    /// `cavitation.coolant_mass = "layer"` puts on the liner's wet zone.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub layer_mass_kg_m2: Option<f64>,
    pub k_p_pa_per_m_s2: f64,
}

/// Coolant state from command-line values, errors naming the option; the static pressure
/// within the scene's bound for `cavitation.static_pressure_kpa` (a 1e9 kPa rig pressure was
/// taken).
pub fn coolant_of(temp_c: f64, static_kpa: f64, glycol: f64) -> Result<Coolant> {
    let most = crate::scene::MAX_STATIC_KPA;
    if static_kpa > most {
        return Err(Error::Argument {
            flag: format!("--static-kpa {}", num(static_kpa)),
            msg: format!(
                "must be at most {} kPa (as cavitation.static_pressure_kpa)",
                num(most)
            ),
        });
    }
    Coolant::new(temp_c, glycol, static_kpa * 1e3).map_err(|e| Error::Argument {
        flag: format!(
            "--temp-c {} --static-kpa {} --glycol {}",
            num(temp_c),
            num(static_kpa),
            num(glycol)
        ),
        msg: e.to_string(),
    })
}

/// `--gap-mm` in metres, within the scene's bounds for `cavitation.gap_mm` (0.05-100 mm: a
/// 1e308 mm gap printed 300-digit layer masses).
fn gap_of(gap_mm: f64) -> Result<f64> {
    if gap_mm.is_finite() && (0.05..=100.0).contains(&gap_mm) {
        Ok(gap_mm * 1e-3)
    } else {
        Err(Error::Argument {
            flag: format!("--gap-mm {}", num(gap_mm)),
            msg: "must lie in [0.05, 100] mm (as cavitation.gap_mm)".into(),
        })
    }
}

/// Runs `coolant`.
pub fn coolant(
    temp_c: f64,
    static_kpa: f64,
    glycol: f64,
    gap_mm: Option<f64>,
) -> Result<CoolantReport> {
    let c = coolant_of(temp_c, static_kpa, glycol)?;
    let k_p = criteria::reference_k_p().expect("reference state valid");
    let gap = gap_mm.map(gap_of).transpose()?;
    Ok(CoolantReport {
        temp_c,
        static_kpa,
        glycol,
        vapour_pressure_kpa: c.vapour_pressure_pa / 1e3,
        density_kg_m3: c.density_kg_m3,
        speed_of_sound_m_s: c.speed_of_sound_m_s,
        vccv_m_s: c.vccv(),
        gap_mm,
        static_threshold_m_s2: gap.map(|h| c.static_threshold(h)),
        threshold_m_s2: gap.map(|h| criteria::threshold(&c, k_p, h)),
        layer_mass_kg_m2: gap.map(|h| c.density_kg_m3 * h),
        k_p_pa_per_m_s2: k_p,
    })
}

impl CoolantReport {
    pub fn to_text(&self) -> String {
        let mut s = format!(
            "coolant at {:.1} C, {:.1} kPa, glycol mass fraction {:.2}\n  vapour pressure   {:.3} kPa\n  density           {:.2} kg/m^3\n  speed of sound    {:.1} m/s\n  Vccv              {:.4} m/s   (p_s - p_v = rho c Vccv)\n",
            self.temp_c,
            self.static_kpa,
            self.glycol,
            self.vapour_pressure_kpa,
            self.density_kg_m3,
            self.speed_of_sound_m_s,
            self.vccv_m_s
        );
        if let (Some(h), Some(st), Some(t), Some(mu)) = (
            self.gap_mm,
            self.static_threshold_m_s2,
            self.threshold_m_s2,
            self.layer_mass_kg_m2,
        ) {
            s += &format!(
                "  gap {h} mm: static threshold (p_s - p_v)/(rho h) = {st:.0} m/s^2\n  with the wall-pressure swing k_p = {:.1} Pa/(m/s^2): Ca = 1 at {t:.0} m/s^2\n  coolant layer rho h = {mu:.2} kg/m^2 (cavitation.coolant_mass = \"layer\")\n",
                self.k_p_pa_per_m_s2
            );
        }
        s
    }
}

/// `calibrate` options.
pub struct CalibrateRequest {
    pub data: PathBuf,
    pub gap_mm: f64,
    pub static_kpa: f64,
    pub temp_c: f64,
    pub glycol: f64,
    pub quiet_ms: f64,
    pub png: Option<PathBuf>,
}

/// Runs `calibrate`; bad data is an input error (exit 2) and nothing is written.
pub fn calibrate(req: &CalibrateRequest) -> Result<Calibration> {
    let coolant = coolant_of(req.temp_c, req.static_kpa, req.glycol)?;
    let gap = gap_of(req.gap_mm)?;
    if !(req.quiet_ms.is_finite() && req.quiet_ms > 0.0) {
        return Err(Error::Argument {
            flag: format!("--quiet-ms {}", req.quiet_ms),
            msg: "must be positive".into(),
        });
    }
    // the plot's directories are removed again if the run fails
    let png_dirs = match &req.png {
        Some(png) => {
            crate::files::check_not_an_input(png, &[&req.data])?;
            Some(crate::files::check_output_file(png)?)
        }
        None => None,
    };
    let d = RigData::read(&req.data)?;
    let file = req.data.display().to_string();
    let cal = calibration::calibrate(
        &file,
        &d,
        &calibration::Settings {
            coolant,
            gap,
            quiet: req.quiet_ms * 1e-3,
        },
    )?;
    if let Some(png) = &req.png {
        draw_calibration(png, &cal)?;
    }
    if let Some(d) = png_dirs {
        d.keep();
    }
    Ok(cal)
}

/// Text summary of a calibration.
pub fn calibration_text(c: &Calibration) -> String {
    format!(
        "{} events ({} cavitating, Ca < 1); noise {:.3} m/s^2, detection level {:.3} m/s^2\n  k_p = {:.2} Pa/(m/s^2) (positive-peak fit, R^2 = {:.4})\n  onset threshold      {:.1} m/s^2 (below it every event has Ca >= 1)\n  high-risk threshold  {:.1} m/s^2 (above it every event has Ca < 1){}\n  model threshold with the fitted k_p: {:.1} m/s^2\n",
        c.events,
        c.cavitating_events,
        c.noise_m_s2,
        c.detection_m_s2,
        c.k_p_pa_per_m_s2,
        c.fit_r2,
        c.onset_m_s2,
        c.high_risk_m_s2,
        if c.transition_band_observed { "" } else { "\n  (no overlap of safe and cavitating events: the thresholds bracket the gap between them)" },
        c.model_threshold_m_s2
    )
}
