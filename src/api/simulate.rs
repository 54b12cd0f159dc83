//! `simulate`: the piston-slap transient of the whole engine on the cached ROM; peaks per
//! cylinder and analysis point, time series CSV, solver statistics.

use super::full_order::compare;
use super::progress::Progress;
use super::rom::{get_rom_with_progress, CacheOptions};
use crate::error::{Error, Result};
use crate::files::{write_atomic, OutputDir};
use crate::piston::Piston;
use crate::reduce::rom::EngineRom;
use crate::report::records::{write_series, SimulateReport};
use crate::scene::Scene;
use crate::transient::cycle::{CycleResult, CycleSettings};
use std::path::PathBuf;
use std::time::Instant;

use crate::piston::setup::{piston_of, simulation};
use crate::transient::engine::settings_of;

/// Runs the engine cycle of `scene` on `rom` ([`crate::transient::engine::run_cycle`]) with a
/// progress bar on a terminal.
pub fn run_cycle_with_progress(
    scene: &Scene,
    rom: &EngineRom,
    piston: &Piston,
    settings: CycleSettings,
    progress: Option<&Progress>,
) -> Result<CycleResult> {
    crate::transient::engine::run_cycle(scene, rom, piston, settings, |k, n| {
        if let Some(p) = progress {
            if k % 200 == 0 {
                p.phase(&format!("transient: step {k} of {n}"));
            }
        }
    })
    .map_err(|source| Error::Transient {
        path: scene.path.clone(),
        source,
    })
}

/// The files `simulate --out` writes.
pub const OUTPUTS: &[&str] = &[
    "simulate.json",
    "time_series.csv",
    "full_order_window.csv",
    "liner_maps.png",
    "liner_maps.vtu",
];

/// Request of `simulate`.
pub struct SimulateRequest {
    pub scene: PathBuf,
    pub sets: Vec<String>,
    pub out: Option<PathBuf>,
    pub cache: CacheOptions,
    /// Compare with the full-order model on a window ([`super::full_order`]).
    pub full_order: bool,
    /// Repeat every cycle at half the step ([`crate::transient::engine::run_half_step`]).
    pub check_step: bool,
    /// Map the liners' wet surfaces ([`super::maps`]).
    pub maps: bool,
    /// Decide the cylinder ranking: the step check and pooled realisations within the
    /// scene's `transient.max_seconds` ([`super::rank`]; implies `check_step`).
    pub rank: bool,
}

/// Refuses a run its scene's limits do not allow: the transient (three times with the step
/// check, plus the ranking's time) and the full-order window (its model and its stepping).
fn check_limits(
    req: &SimulateRequest,
    scene: &crate::scene::Scene,
    sim: &crate::scene::Simulation,
) -> Result<()> {
    let limits = crate::scene::budget::Limits::of(scene);
    if let Some(mut est) = crate::scene::budget::transient(scene) {
        if req.check_step || req.rank {
            // the repeated run at half the step costs about twice the run
            est.seconds *= 3.0;
        }
        if req.rank {
            est.seconds += sim.transient.max_seconds;
        }
        limits.check(scene, &est)?;
    }
    let window = crate::scene::budget::full_model(scene, "the full-order window", true);
    if let Some(mut est) = window.filter(|_| req.full_order) {
        // the window steps at the slap sub-step: its stepping, one factor solve a step
        let t = &sim.transient;
        let step = crate::transient::verify::window_step_deg(t.step_deg, t.slap_substeps);
        let dofs = crate::scene::budget::engine_dofs(scene).unwrap_or(0.0);
        est.seconds += crate::transient::verify::window_stepping_seconds(dofs, step);
        est.keys = "liner.mesh.* / crankcase.mesh.*, transient.step_deg, transient.slap_substeps";
        limits.check(scene, &est)?;
    }
    Ok(())
}

/// Runs `simulate`.
pub fn run(req: &SimulateRequest, started: Instant) -> Result<SimulateReport> {
    let scene = super::load_scene(&req.scene, &req.sets)?;
    let sim = simulation(&scene)?;
    let piston = piston_of(&scene)?;
    // refused before any work: a transient beyond the limits, an output that cannot be written
    check_limits(req, &scene, sim)?;
    let stage = req
        .out
        .as_deref()
        .map(|o| OutputDir::create(o, OUTPUTS))
        .transpose()?;
    let progress = Progress::new();
    progress.phase("engine ROM");
    let loaded = get_rom_with_progress(&scene, &req.cache)?;
    crate::transient::engine::check_mode_cutoff(&scene, sim, &loaded.rom)?;
    if req.maps {
        super::maps::check_maps(&scene, &loaded.rom)?;
    }
    progress.phase("transient");
    let t = Instant::now();
    let mut settings = settings_of(sim, scene.rom.band_hz);
    settings.surface_maps = req.maps;
    let res = run_cycle_with_progress(
        &scene,
        &loaded.rom,
        &piston,
        settings.clone(),
        Some(&progress),
    )?;
    settings.surface_maps = false;
    let transient_seconds = t.elapsed().as_secs_f64();
    let mut report = SimulateReport::new(&scene, &piston, &res, loaded.cache, transient_seconds);
    report
        .warnings
        .extend(film_warning(res.stats.film_mismatch));
    // the ROM build's warnings (decks against the scene): said again for a cached ROM
    for w in &loaded.rom.info.warnings {
        if loaded.cache == "hit" {
            log::warn!("{w} (said when the cached ROM was built)");
        }
        if !report.warnings.contains(w) {
            report.warnings.push(w.clone());
        }
    }
    let maps = if req.maps {
        super::maps::maps_of(&scene, &res)?
    } else {
        Vec::new()
    };
    if req.check_step || req.rank {
        check_and_rank(
            &scene,
            &loaded.rom,
            &piston,
            &res,
            req.rank,
            &progress,
            &mut report,
        )?;
    }
    if req.full_order {
        let cmp = compare(&scene, &loaded.rom, &piston, &settings, &|m| {
            progress.phase(m)
        })?;
        report.rom_error_peak_negative = Some(cmp.rom_error_peak_negative);
        report.speedup = Some(cmp.speedup);
        report.full_order = Some(cmp);
    }
    if let Some(stage) = stage {
        let dir = stage.path().to_path_buf();
        let path = dir.join("time_series.csv");
        write_series(&path, &res)?;
        report.time_series_csv = Some(stage.final_path(&path).display().to_string());
        if let Some(cmp) = &report.full_order {
            super::full_order::write_window_series(&dir.join("full_order_window.csv"), cmp)?;
        }
        if req.maps {
            let (summaries, _) = super::maps::write_maps(&scene, &maps, &loaded.rom, Some(&dir))?;
            report.liner_maps = Some(summaries);
        }
        let json = dir.join("simulate.json");
        report.seconds = started.elapsed().as_secs_f64();
        let text = serde_json::to_string_pretty(&report).expect("serialisable");
        write_atomic(&json, |w| w.write_all(text.as_bytes()))?;
        stage.commit()?;
    }
    if req.maps && maps.iter().all(|m| m.nodes.is_empty()) {
        report.warnings.push(
            "--maps: the liner mesh has no 'coolant_wetted' node set (the wet outer surface), so there is no map".into(),
        );
    }
    if req.maps && report.liner_maps.is_none() {
        report.liner_maps = Some(super::maps::write_maps(&scene, &maps, &loaded.rom, None)?.0);
    }
    report.seconds = started.elapsed().as_secs_f64();
    Ok(report)
}

/// The warning of a lubricated run whose film the steps did not resolve: its
/// `stats.film_mismatch` above [`crate::transient::cycle::FILM_RESOLVED`].
fn film_warning(mismatch: f64) -> Option<String> {
    let bound = crate::transient::cycle::FILM_RESOLVED;
    (mismatch > bound).then(|| format!(
        "the oil film is not resolved: at some step the film force the step linearised differed from the film at the step's end by {:.0} % of the side's film force (stats.film_mismatch; resolved: up to {:.0} %): the lubricated slap forces and peaks are not trustworthy (docs/validation.md)",
        100.0 * mismatch,
        100.0 * bound
    ))
}

/// The whole-run step check of the run `res` into `report`, and with `rank` the decided
/// ranking ([`super::rank`]).
fn check_and_rank(
    scene: &Scene,
    rom: &EngineRom,
    piston: &Piston,
    res: &CycleResult,
    rank: bool,
    progress: &Progress,
    report: &mut SimulateReport,
) -> Result<()> {
    progress.phase("whole-run step check");
    let (half, seconds) = crate::api::half_step_check(scene, rom, piston, res, |k, n| {
        if k % 200 == 0 {
            progress.phase(&format!("whole-run step check: step {k} of {n}"));
        }
    })?;
    report.add_step_check(&half, seconds);
    if rank {
        // the run and its check are the first realisation (as in the report); another
        // runs the two side by side, about as long as the check
        report.ranking = Some(super::rank::decided_ranking(
            scene,
            rom,
            piston,
            (res, &half),
            (0.0, seconds),
            &|m| progress.phase(m),
        )?);
    }
    Ok(())
}
