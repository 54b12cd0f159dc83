//! Values that parse and pass their own range checks but are physically absurd together: the
//! worst are refused with the reason, the doubtful ones come back as warnings (logged when the
//! scene is loaded and carried in the JSON reports).

use super::spec::Elastic;
use super::{Scene, SceneError};
use crate::text::num;

/// Samples per period at the band's top below which the band is not represented at all
/// (Nyquist), and below which the average-acceleration rule's period error
/// (omega dt)^2 / 12 exceeds about 3 %.
const MIN_SAMPLES: f64 = 2.0;
const GOOD_SAMPLES: f64 = 10.0;
/// Samples per period beyond any convergence need: the step-converged reference of
/// `benches/convergence.sh` (1/64 of the default step) takes about 1,000.
const MAX_SAMPLES: f64 = 1e4;
/// Coolant gaps [m]: below 0.05 mm no passage can be cast and the cavitation number
/// Ca ~ 1 / h is singular; below 1 mm the squeeze-film picture of the criterion is doubtful.
const MIN_GAP: f64 = 0.05e-3;
const SMALL_GAP: f64 = 1e-3;
/// Shapes per cut between crankcase components below which the coupling error is percent-level
/// (`rom.cut_shapes`, measured in its doc).
const FEW_CUT_SHAPES: usize = 20;
/// Lowest useful response band [Hz]: the engine orders lie below, the structure's modes far
/// above.
const MIN_BAND_HZ: f64 = 100.0;
/// Cold diametral skirt clearances as fractions of the bore: running clearances of engine
/// pistons lie near 0.05-0.2 % (the study sweeps 40-120 um at 115 mm, 0.03-0.1 %); beyond 0.5 %
/// the piston is worn past any service limit, beyond 2 % its tilt (~ clearance / skirt length)
/// leaves the small-angle secondary-motion model and the skirt no longer guides it.
const WIDE_CLEARANCE: f64 = 0.005;
const MAX_CLEARANCE: f64 = 0.02;
/// Pin offsets as fractions of the bore: 0-2 % in engines (the study's +-1 mm at 115 mm is
/// 0.9 %); warned beyond 5 %. The pin axis and the centre of gravity lie inside the piston:
/// offsets of half the bore or more are refused.
const WIDE_PIN_OFFSET: f64 = 0.05;

/// Refuses the absurd and lists the doubtful.
pub fn review(scene: &Scene) -> Result<Vec<String>, SceneError> {
    let mut warnings = Vec::new();
    let err = |key: &str, msg: String| field_err(scene, key, msg);
    materials(scene, &mut warnings);
    if scene.rom.band_hz < MIN_BAND_HZ {
        return Err(err(
            "rom.band_hz",
            format!(
                "{} Hz: below {MIN_BAND_HZ} Hz no liner or crankcase mode lies in the band (piston slap rings them at 1-10 kHz)",
                num(scene.rom.band_hz)
            ),
        ));
    }
    let gap = scene.cavitation.gap;
    if gap < MIN_GAP {
        return Err(err(
            "cavitation.gap_mm",
            format!(
                "{} mm is no coolant gap (at least {} mm; the cavitation number ~ 1/h is singular as h -> 0)",
                num(gap * 1e3),
                num(MIN_GAP * 1e3)
            ),
        ));
    }
    if gap < SMALL_GAP {
        warnings.push(format!(
            "cavitation.gap_mm = {}: a coolant gap under 1 mm is outside the criterion's calibration",
            num(gap * 1e3)
        ));
    }
    let g = &scene.liner_geometry;
    if g.outer_diameter > g.pilot_diameter {
        warnings.push(format!(
            "liner.outer_diameter_mm = {} exceeds pilot_diameter_mm = {}: the wet wall is wider than the crankcase bore the liner passes through when fitted (modelled as a wall thickened into the coolant jacket)",
            num(g.outer_diameter * 1e3),
            num(g.pilot_diameter * 1e3)
        ));
    }
    if scene.rom.crankcase_components > 1 && scene.rom.cut_shapes < FEW_CUT_SHAPES {
        warnings.push(format!(
            "rom.cut_shapes = {}: fewer than {FEW_CUT_SHAPES} shapes per cut leave the system frequencies percent-level high (+17 to +67 % with 1 on the test engine, 7.4e-3 with 20, 3.3e-4 median with the default 200 on the default engine); rom's estimated error does not count the cuts'",
            scene.rom.cut_shapes
        ));
    }
    if scene.rom.cut_enrichment > 0 && scene.rom.crankcase_components == 1 {
        warnings.push(format!(
            "rom.cut_enrichment = {} has no effect: the crankcase is reduced in one piece (rom.crankcase_components = 1), so it has no cuts to enrich",
            scene.rom.cut_enrichment
        ));
    }
    if let Some(sim) = &scene.simulation {
        piston(scene, sim, &mut warnings)?;
        step(scene, &sim.transient, &mut warnings)?;
    }
    Ok(warnings)
}

/// A refusal of scene key `key`.
fn field_err(scene: &Scene, key: &str, msg: String) -> SceneError {
    SceneError::Field {
        path: scene.path.clone(),
        key: key.into(),
        msg,
    }
}

/// Greenwood-Tripp asperities touch where the gap is below about this many standard
/// deviations of their heights (F_5/2(4) is 4e-6 of F_5/2(0)): a roughness whose reach
/// exceeds the radial clearance holds the skirt off the liner everywhere it nears it.
const ROUGH_TO_CLEARANCE: f64 = 4.0;

/// The piston's skirt, clearance and offsets against the bore and the liner.
fn piston(
    scene: &Scene,
    sim: &super::Simulation,
    warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    let err = |key: &str, msg: String| field_err(scene, key, msg);
    let skirt = &sim.piston.skirt;
    if skirt.length >= scene.liner_geometry.length {
        return Err(err(
            "piston.skirt_length_mm",
            format!(
                "{} mm, longer than the {} mm liner",
                num(skirt.length * 1e3),
                num(scene.liner_geometry.length * 1e3)
            ),
        ));
    }
    let (clearance, bore) = (skirt.clearance, scene.engine.bore);
    let said = || {
        format!(
            "{} um is {} % of the {} mm bore",
            num(clearance * 1e6),
            num(100.0 * clearance / bore),
            num(bore * 1e3)
        )
    };
    if clearance > MAX_CLEARANCE * bore {
        return Err(err(
            "piston.clearance_um",
            format!(
                "{}: at most {} % (running clearances are 0.05-0.2 %; beyond, the skirt no longer guides the piston)",
                said(),
                num(100.0 * MAX_CLEARANCE)
            ),
        ));
    }
    if clearance > WIDE_CLEARANCE * bore {
        warnings.push(format!(
            "piston.clearance_um = {}: worn beyond any service limit (running clearances are 0.05-0.2 %)",
            said()
        ));
    }
    for (key, offset) in [
        ("piston.pin_offset_mm", sim.piston.pin_offset),
        ("piston.cg_offset_mm", sim.piston.cg_lateral),
    ] {
        if offset.abs() >= 0.5 * bore {
            return Err(err(
                key,
                format!(
                    "{} mm lies outside the piston (the bore's radius is {} mm)",
                    num(offset * 1e3),
                    num(0.5 * bore * 1e3)
                ),
            ));
        }
    }
    inertia(scene, &sim.piston, warnings)?;
    if sim.piston.pin_offset.abs() > WIDE_PIN_OFFSET * bore {
        warnings.push(format!(
            "piston.pin_offset_mm = {} is {} % of the bore (pin offsets are 0-2 %)",
            num(sim.piston.pin_offset * 1e3),
            num(100.0 * sim.piston.pin_offset.abs() / bore)
        ));
    }
    if let Some(oil) = &sim.piston.oil {
        warnings.push(format!(
            "piston.lubrication = \"{}\" is experimental: the film is verified against closed forms and the lubricated answer converges with the step on the test and the default engine, with the cylinders solved in one contact step, but a run costs about 10 times a dry one at the same step on the default engine; the dry skirt (the reference study's model) is the conservative answer on settled cycles at the default oil supply (docs/validation.md)",
            oil.model.name()
        ));
        if crate::scene::spec::starved(oil.supply) {
            warnings.push(format!(
                "piston.oil.supply_um = {}: a starved film (its wetted band lies near the film's 3 um gap floor); on the test engine supplies of 1, 1.5 and 2 um stop with \"contact iteration did not converge\" (exit 1) within two cycles, 2.5 um and more run (docs/validation.md, \"A starved film does not always run\")",
                num(oil.supply * 1e6)
            ));
        }
        if let Some(a) = oil
            .asperity
            .filter(|a| ROUGH_TO_CLEARANCE * a.sigma > 0.5 * clearance)
        {
            warnings.push(format!(
                "piston.oil.roughness_um = {}: {ROUGH_TO_CLEARANCE} standard deviations of the asperities ({} um) exceed the skirt's radial cold clearance ({} um), so the asperities carry the skirt wherever it nears the liner (on the test engine 30 um and more left no slap at all); composite roughnesses of skirts and liners are 0.1-5 um",
                num(a.sigma * 1e6),
                num(ROUGH_TO_CLEARANCE * a.sigma * 1e6),
                num(0.5 * clearance * 1e6)
            ));
        }
        if sim.transient.scheme == crate::scene::spec::SchemeChoice::AverageAcceleration {
            warnings.push("transient.scheme = \"newmark\" with a lubricated skirt: the squeeze film is a stiff damper on the liner's light modes, on which the average-acceleration rule rings and the default engine's run stopped in its sixth cycle; \"hht\" (the default for a lubricated skirt) damps it".to_string());
        }
    }
    Ok(())
}

/// A piston's mass over the bore cubed \[kg/m^3\]: 1,710 for the default engine's 2.6 kg at
/// 115 mm, about 600 for a light car piston, about 7,000 for a marine crosshead piston with its
/// crown. Outside the wide band the value is warned of; outside the outer one it is no piston
/// of that bore (a unit slip: grams as kilograms is 1,000 times) and is refused.
const MASS_DENSITY: (f64, f64) = (200.0, 1.0e4);
const MASS_DENSITY_LIMITS: (f64, f64) = (10.0, 1.0e5);
/// Tilt inertia about the pin over mass x bore^2: 0.116 for the default engine, 0.146 for a
/// solid cylinder as tall as its diameter about a transverse axis through its middle; warned
/// outside the wide band, refused outside the outer one (the helper of session 78 ran 4,000
/// kg m^2, a million times the default's, with exit 0).
const TILT_RATIO: (f64, f64) = (0.02, 1.0);
const TILT_RATIO_LIMITS: (f64, f64) = (1e-3, 100.0);
/// The contact dashpot's damping ratio on the piston's mass and a slice's stiffness,
/// c / (2 sqrt(k m)): 0.054 by default; above 10 the dashpot holds the skirt like glue (warned),
/// above 1,000 it is no contact model at all (refused: 1e308 N s/m ran with exit 0).
const DAMPING_RATIO_WIDE: f64 = 10.0;
const DAMPING_RATIO_MAX: f64 = 1000.0;

/// The piston's mass and tilt inertia against its bore, and the contact damper against the
/// slice's stiffness and the piston's mass.
fn inertia(
    scene: &Scene,
    p: &super::model::PistonSpec,
    warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    let bore = scene.engine.bore;
    let checks = [
        (
            "piston.mass_kg",
            p.mass / bore.powi(3),
            MASS_DENSITY,
            MASS_DENSITY_LIMITS,
            "kg/m^3 of bore cubed",
        ),
        (
            "piston.tilt_inertia_kg_m2",
            p.tilt_inertia / (p.mass * bore * bore),
            TILT_RATIO,
            TILT_RATIO_LIMITS,
            "times mass x bore^2",
        ),
    ];
    for (key, v, (lo, hi), (min, max), unit) in checks {
        let said = format!(
            "{} {unit} (pistons lie in [{}, {}])",
            num(v),
            num(lo),
            num(hi)
        );
        if !(min..=max).contains(&v) {
            return Err(field_err(
                scene,
                key,
                format!("{said}: no piston of a {} mm bore", num(bore * 1e3)),
            ));
        }
        if !(lo..=hi).contains(&v) {
            warnings.push(format!("{key}: {said}"));
        }
    }
    let ratio = p.contact_damping / (2.0 * (p.skirt.stiffness * p.mass).sqrt());
    let said = format!(
        "damping ratio {} on the piston's mass and a slice's stiffness (the default's is 0.054)",
        num(ratio)
    );
    if ratio > DAMPING_RATIO_MAX {
        return Err(field_err(
            scene,
            "piston.contact_damping_n_s_per_m",
            format!("{said}: at most {DAMPING_RATIO_MAX}"),
        ));
    }
    if ratio > DAMPING_RATIO_WIDE {
        warnings.push(format!(
            "piston.contact_damping_n_s_per_m: {said}: the dashpot holds the skirt on the liner"
        ));
    }
    Ok(())
}

/// The averaged cycles and the time step against the band's top.
fn step(
    scene: &Scene,
    t: &super::TransientSpec,
    warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    let err = |key: &str, msg: String| field_err(scene, key, msg);
    if t.cycles > 1 && t.averaged_cycles >= t.cycles {
        warnings.push(format!(
            "transient.averaged_cycles: all {} cycles are averaged, the first too, which starts from rest; average at most {} (transient.cycles - 1)",
            t.cycles,
            t.cycles - 1
        ));
    }
    let dt = t.step_deg / (6.0 * scene.engine.speed_rpm);
    let samples = 1.0 / (scene.rom.band_hz * dt);
    let what = format!(
        "{} deg ({} us at {} rpm) samples the band's top, {} Hz, {} times per period",
        num(t.step_deg),
        num(dt * 1e6),
        num(scene.engine.speed_rpm),
        num(scene.rom.band_hz),
        num(samples)
    );
    if samples < MIN_SAMPLES {
        return Err(err(
            "transient.step_deg",
            format!("{what}: at least {MIN_SAMPLES} are needed to represent it (10 for a few percent accuracy)"),
        ));
    }
    if samples > MAX_SAMPLES {
        return Err(err(
            "transient.step_deg",
            format!("{what}: more than {} is finer than any convergence study needs (the step-converged reference takes about 1000) and only costs time and memory", num(MAX_SAMPLES)),
        ));
    }
    if samples < GOOD_SAMPLES {
        warnings.push(format!(
            "transient.step_deg = {what}: fewer than {GOOD_SAMPLES}, the band's top is under-resolved"
        ));
    }
    Ok(())
}

fn materials(scene: &Scene, warnings: &mut Vec<String>) {
    let mut check = |what: &str, m: &Elastic| warnings.extend(m.structural_warning(what));
    if let Some(m) = &scene.liner.material {
        check("liner", m);
    }
    if let Some(c) = &scene.crankcase {
        if let Some(m) = &c.material {
            check("crankcase", m);
        }
    }
}
