//! `linercav report`: the design-review report of a scene. One slap transient of the engine,
//! its cavitation verdict and explanation, clearance and pin-offset sweeps, and the
//! speed-against-error curve of the fast path, as PNGs plus `summary.md` and `summary.json`.
//!
//! Figures: `pressure.png` (cylinder pressure, side force), `acceleration.png` (liner
//! acceleration per cylinder around firing, with the thresholds), `spectra.png`, `peaks.png`
//! (per cylinder and point, with the thresholds), `modes_risk.png` (coefficients of the
//! best-correlated of the modes nearest the dominant response beside the per-cylinder peaks), `sweep_clearance.png`,
//! `sweep_pin_offset.png`, `criteria.png` (CSF against Ca), `speed_error.png`, `frf.png`
//! (inertance from the slap location to each cylinder's worst point, from the modal model);
//! with `report.compare_lubrication`, `skirt_comparison.png` (the scene's skirt model against
//! the other over the sweeps: [`crate::report::comparison`]).

use super::rom::CacheOptions;
use crate::api::{report_runs, CLEARANCE_RANGE_UM, PIN_OFFSET_RANGE_MM, REPORT_SWEEP_RUNS};
use crate::error::Result;
use crate::files::write_all_atomic;
use crate::piston::setup::piston_of;
use crate::report::figures::Figures;
use crate::report::records::SimulateReport;
use crate::report::summary::markdown;
pub use crate::report::summary::Report;
use std::path::Path;
use std::time::Instant;

/// The files `report --out` writes (the figures all PNG).
pub const OUTPUTS: &[&str] = &["summary.md", "summary.json", "liner_maps.vtu", "*.png"];

/// The time of the comparison's runs with the other skirt model
/// (`report.compare_lubrication`) \[s\]: the scene's transient estimate under that model,
/// times the runs (the scene and both sweeps, two at a time); 0 without a comparison.
fn comparison_seconds(scene: &crate::scene::Scene) -> Result<f64> {
    let Some(other) = super::compare::checked_request(scene)? else {
        return Ok(0.0);
    };
    let lubricated = other != crate::scene::spec::Lubrication::Dry;
    let one = crate::scene::budget::transient_as(scene, lubricated).map_or(0.0, |e| e.seconds);
    Ok(one * (1 + 2 * REPORT_SWEEP_RUNS) as f64 / 2.0)
}

/// Writes the report of `scene` into `out`.
pub fn run(scene_path: &Path, sets: &[String], out: &Path, cache: &CacheOptions) -> Result<Report> {
    let started = Instant::now();
    let scene = super::load_scene(scene_path, sets)?;
    let piston = piston_of(&scene)?;
    // about twenty transients (the scene, its two sweeps, the step check, the ranking's
    // realisations): refused before any
    // work when beyond the limits, as is an output directory that cannot be written
    if let Some(mut est) = crate::scene::budget::transient(&scene) {
        est.what = "the report's transients";
        // two at a time (the sweeps' runs besides the scene's), then the whole-run step
        // check at half the step (about two transients)
        est.seconds *= (1 + 2 * REPORT_SWEEP_RUNS) as f64 / 2.0 + 2.0;
        // the comparison's runs with the other skirt model, two at a time
        let compared = comparison_seconds(&scene)?;
        if compared > 0.0 {
            est.seconds += compared;
            est.keys = "transient.step_deg, transient.cycles, piston.slices, piston.lubrication, report.compare_lubrication";
        }
        // and the decided ranking's realisations, within their budget
        est.seconds += crate::piston::setup::simulation(&scene)?
            .transient
            .max_seconds;
        crate::scene::budget::Limits::of(&scene).check(&scene, &est)?;
    }
    let stage = crate::files::OutputDir::create(out, OUTPUTS)?;
    let progress = super::progress::Progress::new();
    let runs = report_runs(scene_path, sets, &scene, cache, &|m| progress.phase(m))?;
    let mut simulate = SimulateReport::new(&scene, &piston, &runs.base, runs.rom.cache, 0.0);
    simulate.add_step_check(&runs.half_step, runs.half_step_seconds);
    simulate.seconds = started.elapsed().as_secs_f64();
    progress.phase("figures");
    let figs = Figures {
        out: stage.path(),
        scene: &scene,
        piston: &piston,
        base: &runs.base,
        simulate: &simulate,
        ev: &runs.evaluation,
        clearance: &runs.clearance,
        offset: &runs.pin_offset,
        trade: &runs.tradeoff,
        rom: &runs.rom.rom,
    }
    .draw()?;
    let (liner_maps, map_files) =
        super::maps::write_maps(&scene, &runs.maps, &runs.rom.rom, Some(stage.path()))?;
    let mut figs: Vec<std::path::PathBuf> = figs.into_iter().chain(map_files).collect();
    if let Some(c) = &runs.skirts {
        figs.push(c.draw(stage.path(), (&runs.clearance, &runs.pin_offset))?);
    }
    // the report's own run and check are the first realisation; the budget is for the others
    let ranking = super::rank::decided_ranking(
        &scene,
        &runs.rom.rom,
        &piston,
        (&runs.base, &runs.half_step),
        (0.0, runs.half_step_seconds),
        &|m| progress.phase(m),
    )?;
    let mut report = Report {
        scene: scene.path.display().to_string(),
        title: scene.title.clone(),
        speed_rpm: scene.engine.speed_rpm,
        coolant_layer_kg_m2: scene.cavitation.layer_mass_per_area,
        simulate,
        evaluation: runs.evaluation,
        clearance_sweep: runs.clearance,
        pin_offset_sweep: runs.pin_offset,
        skirt_comparison: runs.skirts,
        clearance_maximum: runs.clearance_maximum,
        pin_offset_maximum: runs.pin_offset_maximum,
        clearance_range_um: [CLEARANCE_RANGE_UM.0, CLEARANCE_RANGE_UM.1],
        pin_offset_range_mm: [PIN_OFFSET_RANGE_MM.0, PIN_OFFSET_RANGE_MM.1],
        tradeoff: runs.tradeoff,
        ranking,
        liner_maps,
        files: figs
            .iter()
            .map(|p| stage.final_path(p).display().to_string())
            .collect(),
        seconds: 0.0,
    };
    report.seconds = started.elapsed().as_secs_f64();
    let md = markdown(&report, scene_path, out);
    let json = serde_json::to_string_pretty(&report).expect("serialisable");
    write_all_atomic(vec![
        (
            stage.path().join("summary.json"),
            Box::new(move |w: &mut dyn std::io::Write| w.write_all(json.as_bytes())),
        ),
        (
            stage.path().join("summary.md"),
            Box::new(move |w: &mut dyn std::io::Write| w.write_all(md.as_bytes())),
        ),
    ])?;
    stage.commit()?;
    Ok(report)
}
