//! The full coupled engine model's modes of a scene (the reference of `modes --assembly
//! --full` and `rom-tradeoff`), and engine mode shapes written as VTU for ParaView.

use crate::error::{Error, Result};
use crate::fem::dofs::DofMap;
use crate::mesh::Mesh;
pub use crate::reduce::full::recover_shapes;
use crate::reduce::full::FullModes;
use crate::reduce::rom::RomBuild;
use crate::reduce::scene_rom::full_modes;
use crate::report::vtu::{write_engine_modes, EngineShapes};
use crate::scene::Scene;
use std::path::Path;

/// Builds and solves the full coupled model of a scene for `count` modes
/// ([`full_modes`]); with `vtu_path`, writes their shapes on the placed meshes.
pub fn run(scene: &Scene, count: usize, vtu_path: Option<&Path>) -> Result<FullModes> {
    let full = full_modes(scene, count)?;
    if let Some(path) = vtu_path {
        write_engine_modes(
            path,
            &EngineShapes {
                cylinders: &full.system.cylinders,
                axis_x: &full.axis_x,
                liner: &full.liner_mesh,
                crankcase: &full.crankcase_mesh,
                dofs: &full.system.dof_maps(),
                shapes: &full.modes.shapes,
                freqs: &full.modes.frequencies_hz,
            },
        )?;
    }
    Ok(full.modes)
}

/// Writes the first `count` ROM system modes recovered on the meshes.
pub fn write_vtu(
    path: &Path,
    scene: &Scene,
    lm: &Mesh,
    cm: &Mesh,
    b: &RomBuild,
    count: usize,
) -> Result<()> {
    let axis_x = crate::reduce::scene_rom::axis_x(scene);
    let shapes = recover_shapes(b, count).ok_or(Error::NoBases)?;
    let dofs: Vec<&DofMap> = b
        .liner_maps
        .iter()
        .map(|_| &b.liner.dofs)
        .chain(std::iter::once(&b.crankcase.dofs))
        .collect();
    let cyls: Vec<usize> = b.rom.cylinders.iter().map(|c| c.cylinder).collect();
    Ok(write_engine_modes(
        path,
        &EngineShapes {
            cylinders: &cyls,
            axis_x: &axis_x,
            liner: lm,
            crankcase: cm,
            dofs: &dofs,
            shapes: &shapes,
            freqs: &b.rom.frequencies_hz[..count],
        },
    )?)
}
