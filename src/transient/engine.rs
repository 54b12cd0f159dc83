//! The engine transient of a scene: its numerical settings and one run on the engine ROM.

use super::cycle::{run_with_tolerance, Coupling, CycleResult, CycleSettings, EngineSetup};
use super::error::TransientError;
use crate::piston::Piston;
use crate::reduce::rom::EngineRom;
use crate::scene::{Scene, SceneError, Simulation};

/// How often the tolerance control may halve the step ([`run_with_tolerance`]).
pub const MAX_REFINEMENTS: usize = 2;

/// The transient settings of a scene's `[transient]` section; accelerations reported in the
/// ROM's band `band_hz`. Fixed choices (not scene keys): contact coupled per cylinder (one
/// step for a lubricated skirt, [`coupling_of`]), the residual flexibility at the contact, the
/// onset correction, the step-error windows, and up to 6 halvings of a failing step with at
/// most 50 contact iterations each.
pub fn settings_of(sim: &Simulation, band_hz: f64) -> CycleSettings {
    let t = &sim.transient;
    CycleSettings {
        scheme: t.scheme.into(),
        step_deg: t.step_deg,
        cycles: t.cycles,
        averaged_cycles: t.averaged_cycles,
        adaptive: t.adaptive,
        max_halvings: 6,
        damping_ratio: t.damping_ratio,
        max_penetration: t.max_penetration,
        max_newton: 50,
        modes_below_hz: t.mode_cutoff_hz,
        static_correction: true,
        coupling: coupling_of(sim),
        output_band_hz: Some(band_hz),
        bound_predictions: true,
        step_error: true,
        onset_correction: true,
        tolerance: Some(t.tolerance),
        slap_substeps: t.slap_substeps,
        slap_span_deg: t.slap_span_deg,
        surface_maps: false,
    }
}

/// How the cylinders' contacts are solved within a step: per cylinder for a dry skirt,
/// monolithically for a lubricated one.
///
/// Per cylinder, what the other cylinders' new forces do to a liner within the step comes
/// from the previous step; a dry contact tolerates that lag (`stats.coupling_lag_m`), an oil
/// film does not: its force follows the squeeze rate, which the lagged give falsifies. On the
/// default engine (squeeze, 4 cycles) the per-cylinder answer did not converge with the step
/// (cylinder 2's slap force 4.30, 3.58, 2.89, 2.57, 1.39 kN at 1/8, 1/10, 1/12, 1/16 and
/// 1/32 deg, smooth in the step and the same with the damping moved by 1 %, HHT alpha -0.3,
/// Rayleigh damping on the residual vectors, uniform steps); solved monolithically it
/// converges (3.92, 3.86, 3.82 kN at 1/4, 1/8, 1/16 deg; every cylinder's worst point within
/// 1 %), at about twice the per-cylinder cost (docs/validation.md).
pub fn coupling_of(sim: &Simulation) -> Coupling {
    if sim.piston.oil.is_some() {
        Coupling::Monolithic
    } else {
        Coupling::PerCylinder
    }
}

/// Runs the engine cycles of `scene` on `rom` with `settings` (the tolerance control halving
/// the step at most [`MAX_REFINEMENTS`] times); `on_step(k, n)` is called after step k of n.
pub fn run_cycle(
    scene: &Scene,
    rom: &EngineRom,
    piston: &Piston,
    settings: CycleSettings,
    on_step: impl FnMut(usize, usize) + Send,
) -> Result<CycleResult, TransientError> {
    run_with_tolerance(
        &setup_of(scene, rom, piston),
        settings,
        MAX_REFINEMENTS,
        on_step,
    )
}

/// Refuses a `transient.mode_cutoff_hz` below the ROM's lowest system mode: the run would
/// integrate no mode at all (the structure reduced to its static flexibility) and report
/// quasi-static accelerations as if they were the ringing liner's; warns when it lies in the
/// output band (some of the band's modes then respond only statically).
pub fn check_mode_cutoff(
    scene: &Scene,
    sim: &Simulation,
    rom: &EngineRom,
) -> Result<(), SceneError> {
    let (Some(cut), Some(&lowest)) = (sim.transient.mode_cutoff_hz, rom.frequencies_hz.first())
    else {
        return Ok(());
    };
    if cut < lowest {
        return Err(SceneError::Field {
            path: scene.path.clone(),
            key: "transient.mode_cutoff_hz".into(),
            msg: format!(
                "{} Hz keeps no system mode (the ROM's lowest is {} Hz): the transient would integrate no mode; remove the key (all modes) or set it above the band ({} Hz)",
                crate::text::num(cut),
                crate::text::num(lowest),
                crate::text::num(scene.rom.band_hz)
            ),
        });
    }
    // legal but doubtful: modes in the output band respond only statically (600 Hz on the
    // test engine kept one mode and the peaks dropped 2-3x without a word)
    let band = scene.rom.band_hz;
    if cut < band {
        let kept = rom.frequencies_hz.iter().filter(|&&f| f <= cut).count();
        let in_band = rom.frequencies_hz.iter().filter(|&&f| f <= band).count();
        log::warn!(
            "transient.mode_cutoff_hz = {} Hz keeps {kept} of the {in_band} system modes in the output band (up to {} Hz): the others respond only statically, so the peaks are not the ringing liner's; set it above the band for results",
            crate::text::num(cut),
            crate::text::num(band)
        );
    }
    Ok(())
}

/// The whole-run step check of a run made at `step_deg` \[deg\]: the same cycles at `step_deg` / 2
/// (no accuracy control, no firing-slap windows). Its mean peaks P_{h/2} differ from the run's
/// P_h by the whole step error, the slaps' own and the shift of the cycles' statistics that the
/// coarser step makes between the slaps (which the firing-slap windows of [`StepError`] do not
/// see); |P_h - P_converged| ~ 2 |P_h - P_{h/2}| for any order of convergence >= 1.
///
/// [`StepError`]: super::cycle::StepError
pub fn run_half_step(
    scene: &Scene,
    rom: &EngineRom,
    piston: &Piston,
    mut settings: CycleSettings,
    step_deg: f64,
    on_step: impl FnMut(usize, usize) + Send,
) -> Result<CycleResult, TransientError> {
    settings.step_deg = step_deg / 2.0;
    settings.tolerance = None;
    settings.step_error = false;
    run_cycle(scene, rom, piston, settings, on_step)
}

/// The engine of `scene` on `rom` with `piston`: its firing order, crank speed and liner top.
pub fn setup_of<'a>(scene: &'a Scene, rom: &'a EngineRom, piston: &'a Piston) -> EngineSetup<'a> {
    EngineSetup {
        rom,
        piston,
        firing_order: &scene.engine.firing_order,
        omega: piston.kinematics.omega,
        liner_top: scene.liner_geometry.length,
    }
}
