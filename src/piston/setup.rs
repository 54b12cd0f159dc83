//! The piston model of a scene: crank-slider kinematics from the engine, the cylinder pressure
//! (a measured curve or the scene's Wiebe heat release), the skirt and its contact laws.

use super::kinematics::CrankSlider;
use super::lubrication;
use super::pressure::{PressureCurve, PressureError};
use super::skirt::Skirt;
use super::Piston;
use crate::scene::{PressureSource, Scene, Simulation};
use std::path::PathBuf;

/// Why a scene gives no piston model (all the user's to fix: exit 2).
#[derive(Debug, thiserror::Error)]
pub enum PistonSetupError {
    #[error("{}: simulate needs the [piston], [operating] and [transient] sections (see models/engine.toml)", path.display())]
    NoSimulation { path: PathBuf },
    #[error("{}: {source}", path.display())]
    Pressure {
        path: PathBuf,
        #[source]
        source: PressureError,
    },
    #[error("{}: the built-in pressure curve ([operating.combustion]) peaks at {} bar, beyond the {} bar a cylinder pressure may reach: check compression_ratio, intake_bar, exhaust_over_intake_bar and heat_release_j", path.display(), crate::text::num(*peak_bar), crate::text::num(super::pressure::MAX_BAR))]
    Curve { path: PathBuf, peak_bar: f64 },
    #[error("{}: the hot skirt is {hot_um:.1} um (diametral) larger than the bore: piston.clearance_um is too small for the temperatures in [piston.thermal] (the piston would seize)", path.display())]
    Seizure { path: PathBuf, hot_um: f64 },
}

/// The scene's simulation sections, or an error naming what is missing.
pub fn simulation(scene: &Scene) -> Result<&Simulation, PistonSetupError> {
    scene
        .simulation
        .as_ref()
        .ok_or_else(|| PistonSetupError::NoSimulation {
            path: scene.path.clone(),
        })
}

/// The warning for a hot skirt larger than the bore (`hot` <= 0, the hot diametral clearance;
/// `cold` the scene's cold clearance) \[m\].
pub fn interference_warning(hot: f64, cold: f64) -> Option<String> {
    (hot <= 0.0).then(|| {
        format!(
            "the hot skirt is {} um (diametral) larger than the bore at piston.clearance_um = {}: an interference fit, the piston runs in permanent contact",
            crate::text::num(-hot * 1e6),
            crate::text::num(cold * 1e6)
        )
    })
}

/// The piston model of a scene (reads the pressure file when one is given). The crank-slider
/// has radius S/2, rod l, offset e = e_pin - e_crank and omega = n pi / 30; the crown area is
/// A = pi B^2 / 4. A hot skirt larger than the bore by more than the penetration limit is
/// refused (it would seize); one larger by less is logged as an interference fit.
pub fn piston_of(scene: &Scene) -> Result<Piston, PistonSetupError> {
    let sim = simulation(scene)?;
    let p = &sim.piston;
    let e = &scene.engine;
    let kinematics = CrankSlider {
        radius: e.stroke / 2.0,
        rod: e.rod_length,
        offset: p.pin_offset - p.crank_offset,
        omega: e.speed_rpm * std::f64::consts::PI / 30.0,
    };
    let area = std::f64::consts::PI * e.bore * e.bore / 4.0;
    let pressure = match &sim.operating.pressure {
        PressureSource::File(f) => {
            PressureCurve::from_csv(f).map_err(|source| PistonSetupError::Pressure {
                path: scene.path.clone(),
                source,
            })?
        }
        PressureSource::Wiebe(w) => {
            let curve = PressureCurve::wiebe(w, &kinematics, area);
            // the bound of a pressure table's values holds for the built-in curve too (a
            // compression ratio of 1e9 ran into a deep penetration, exit 1)
            let peak_bar = curve.peak().0 / 1e5;
            if !(peak_bar.is_finite() && peak_bar <= super::pressure::MAX_BAR) {
                return Err(PistonSetupError::Curve {
                    path: scene.path.clone(),
                    peak_bar,
                });
            }
            curve
        }
    };
    let skirt = Skirt::new(&p.skirt);
    let hot = skirt.hot_clearance();
    if let Some(w) = interference_warning(hot, p.skirt.clearance) {
        log::warn!("{}: {w}", scene.path.display());
    }
    if hot < -sim.transient.max_penetration {
        return Err(PistonSetupError::Seizure {
            path: scene.path.clone(),
            hot_um: -hot * 1e6,
        });
    }
    Ok(Piston {
        kinematics,
        pressure,
        crankcase_pa: sim.operating.crankcase_pa,
        area,
        mass: p.mass,
        pin_mass: p.pin_mass,
        tilt_inertia: p.tilt_inertia,
        cg_above_pin: p.cg_above_pin,
        cg_lateral: p.cg_lateral,
        pin_offset: p.pin_offset,
        pin_depth_at_tdc: p.crown_depth_at_tdc + p.compression_height,
        film: p
            .oil
            .as_ref()
            .map(|oil| lubrication::Film::new(&skirt, &p.skirt, oil)),
        skirt,
        contact_damping: p.contact_damping,
        friction: p.friction,
        pin_friction: p.pin_friction,
        pin_radius: p.pin_radius,
        pin_slip_rate: p.pin_slip_rate,
    })
}
