//! The library's front door: load a scene, get or build its ROM, run the engine cycles and
//! evaluate the cavitation risk. The command layer (`src/app`, `src/main.rs`) and the tests go
//! through here; each item belongs to its pipeline stage (docs/physics.md):
//!
//! ```no_run
//! use linercav::api::*;
//! let scene = load_scene("models/engine.toml".as_ref(), &["piston.clearance_um=120".into()])?;
//! let rom = get_rom(&scene, &CacheOptions::default(), &|_| {})?.rom;
//! let piston = piston_of(&scene)?;
//! let settings = settings_of(simulation(&scene)?, scene.rom.band_hz);
//! let result = run_cycle(&scene, &rom, &piston, settings, |_, _| {})
//!     .map_err(|source| Error::Transient { path: scene.path.clone(), source })?;
//! let risk = evaluate_scene(&scene, &rom, &result)?;
//! # Ok::<(), linercav::api::Error>(())
//! ```

pub use crate::cavitation::evaluate::{evaluate, Evaluation};
pub use crate::error::{Error, Result};
pub use crate::piston::setup::{piston_of, simulation};
pub use crate::piston::Piston;
pub use crate::reduce::rom::EngineRom;
pub use crate::reduce::scene_rom::{build_rom, get_rom, CacheOptions, LoadedRom};
pub use crate::scene::Scene;
pub use crate::transient::cycle::{CycleResult, CycleSettings};
pub use crate::transient::engine::{run_cycle, settings_of};
use std::path::Path;

/// Loads and validates a scene with its `--set` overrides, and resolves its cavitation
/// thresholds, so that thresholds out of order are refused (exit 2, naming the file) before
/// any work starts.
pub fn load_scene(path: &Path, sets: &[String]) -> Result<Scene> {
    let scene = Scene::load(path, sets)?;
    crate::cavitation::Setup::new(&scene.cavitation).map_err(|e| {
        crate::scene::SceneError::Field {
            path: path.to_path_buf(),
            key: "cavitation".into(),
            msg: e.to_string(),
        }
    })?;
    Ok(scene)
}

/// The cavitation risk of a run of `scene` on `rom` ([`evaluate`] with the scene's coolant
/// state and thresholds, in the ROM's band).
pub fn evaluate_scene(scene: &Scene, rom: &EngineRom, result: &CycleResult) -> Result<Evaluation> {
    Ok(evaluate(
        result,
        rom,
        &crate::cavitation::Setup::new(&scene.cavitation)?,
        &scene.engine.firing_order,
        scene.rom.band_hz,
    ))
}
