//! The liner maps of a run as files and summaries (`report`, `simulate --maps`).

use crate::cavitation::maps::LinerMap;
use crate::error::Result;
use crate::reduce::rom::EngineRom;
use crate::report::maps::{write_maps_png, write_maps_vtu, MapSummary, SurfaceGeometry};
use crate::scene::Scene;
use std::path::{Path, PathBuf};

/// The maps of a run of `scene` on `rom`: `liner_maps.png` and `liner_maps.vtu` written into
/// `dir` (when given) and each map's summary; nothing when there is no map (no
/// `coolant_wetted` set on the liner mesh).
pub fn write_maps(
    scene: &Scene,
    maps: &[LinerMap],
    rom: &EngineRom,
    dir: Option<&Path>,
) -> Result<(Vec<MapSummary>, Vec<PathBuf>)> {
    if maps.iter().all(|m| m.nodes.is_empty()) {
        return Ok((Vec::new(), Vec::new()));
    }
    let meshes = crate::reduce::scene_rom::load_meshes(scene)?;
    let points = scene.liner_geometry.analysis_depths.len();
    let geometry: Vec<SurfaceGeometry> = maps
        .iter()
        .map(|m| SurfaceGeometry::new(&meshes.liner, &m.nodes, points))
        .collect();
    let summaries = maps
        .iter()
        .zip(&geometry)
        .filter_map(|(m, g)| MapSummary::of(m, g))
        .collect();
    let Some(dir) = dir else {
        return Ok((summaries, Vec::new()));
    };
    let axis_x: Vec<f64> = maps
        .iter()
        .map(|m| {
            rom.cylinders
                .iter()
                .find(|c| c.cylinder == m.cylinder)
                .map_or(0.0, |c| c.axis_x)
        })
        .collect();
    let cav = crate::cavitation::Setup::new(&scene.cavitation)?;
    let ca_one = crate::cavitation::criteria::threshold(
        &cav.coolant,
        cav.thresholds.k_p_pa_per_m_s2,
        cav.gap,
    );
    let (png, vtu) = (dir.join("liner_maps.png"), dir.join("liner_maps.vtu"));
    write_maps_png(&png, maps, &geometry, ca_one)?;
    write_maps_vtu(&vtu, maps, &geometry, &axis_x)?;
    Ok((summaries, vec![png, vtu]))
}

/// The maps of `result` (a run of `scene` with `surface_maps`): the per-node criteria
/// ([`crate::cavitation::maps::liner_maps`]).
pub fn maps_of(
    scene: &Scene,
    result: &crate::transient::cycle::CycleResult,
) -> Result<Vec<LinerMap>> {
    Ok(crate::cavitation::maps::liner_maps(
        &result.surface,
        &crate::cavitation::Setup::new(&scene.cavitation)?,
        result.stats.autocorrelation_cycles,
    ))
}

/// Refuses the liner maps of a run of `scene` on `rom` beyond the limits
/// ([`crate::scene::budget::maps`]), before the run starts.
pub fn check_maps(scene: &Scene, rom: &EngineRom) -> Result<()> {
    let nodes: Vec<usize> = rom
        .cylinders
        .iter()
        .map(|c| c.surface.nodes.len())
        .collect();
    let contact = rom
        .cylinders
        .iter()
        .map(|c| c.thrust_z.len() + c.antithrust_z.len())
        .max()
        .unwrap_or(0);
    if let Some(est) = crate::scene::budget::maps(scene, &nodes, rom.frequencies_hz.len() + contact)
    {
        crate::scene::budget::Limits::of(scene).check(scene, &est)?;
    }
    Ok(())
}
