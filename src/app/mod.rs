//! Commands of the command-line tool as library functions: each takes a request, returns a
//! serialisable report, and writes its files atomically.

pub mod cavitation;

pub mod export;
pub mod full_modes;
pub mod full_order;
pub mod modes;
pub mod progress;
pub mod rom;
pub mod rom_tradeoff;
pub mod simulate;
pub mod summary;
pub mod sweep;

use crate::error::{Error, Result};
use crate::fem::element::check_mesh as check_and_compact;
use crate::fem::material::Elastic;
use crate::mesh::checks::CheckReport;
use crate::mesh::{liner, Mesh};
use crate::scene::{MeshSource, PARTS};
use std::path::PathBuf;

/// Where the model of a command comes from: a scene part, or a bare mesh file with a material.
#[derive(Clone, Debug)]
pub enum ModelInput {
    Scene {
        scene: PathBuf,
        part: String,
        sets: Vec<String>,
    },
    Mesh {
        mesh: PathBuf,
        material: Elastic,
        fix: Vec<String>,
    },
}

/// A checked mesh with its material, the sets to fix, and the mesh-check findings.
pub struct LoadedPart {
    pub mesh: Mesh,
    pub material: Elastic,
    pub fix: Vec<String>,
    pub checks: CheckReport,
    pub label: String,
    /// Shift frequency of the modal solve [Hz].
    pub shift_hz: f64,
    pub guard_modes: usize,
}

pub use crate::api::load_scene;

fn read_mesh(source: &MeshSource) -> Result<(Mesh, Option<String>)> {
    Ok(match source {
        MeshSource::Liner { geometry, meshing } => (liner::generate(geometry, meshing), None),
        MeshSource::File(p) => (crate::mesh::read(p)?, Some(p.display().to_string())),
    })
}

/// Resolves a [`ModelInput`] to a checked mesh and material. `extra_fix` adds sets to fix.
pub fn load_part(input: &ModelInput, extra_fix: &[String]) -> Result<LoadedPart> {
    let (mesh, file, material, mut fix, label, shift_hz, guard_modes) = match input {
        ModelInput::Scene { scene, part, sets } => {
            let sc = load_scene(scene, sets)?;
            let p = sc.part(part).ok_or_else(|| Error::Argument {
                flag: format!("{}: part '{part}'", scene.display()),
                msg: format!("unknown; the scene has: {}", PARTS.join(", ")),
            })?;
            let (mesh, file) = read_mesh(&p.source)?;
            (
                mesh,
                file,
                p.material,
                p.fix.clone(),
                format!("{} / {part}", scene.display()),
                sc.solver.shift_hz,
                sc.solver.guard_modes,
            )
        }
        ModelInput::Mesh {
            mesh,
            material,
            fix,
        } => {
            material.validate().map_err(|m| Error::Argument {
                flag: "material".into(),
                msg: m.to_string(),
            })?;
            let m = crate::mesh::read(mesh)?;
            (
                m,
                Some(mesh.display().to_string()),
                *material,
                fix.clone(),
                mesh.display().to_string(),
                100.0,
                4,
            )
        }
    };
    fix.extend_from_slice(extra_fix);
    let mut mesh = mesh;
    if let Some(f) = &file {
        let est = crate::scene::budget::fe_model(3 * mesh.nodes.len(), "the modal solve");
        crate::scene::budget::Limits::machine().check_at(std::path::Path::new(f), &est)?;
    }
    let checks = check_and_compact(&mut mesh).map_err(|source| Error::Mesh { file, source })?;
    for name in &fix {
        if mesh.node_set(name).is_none() {
            return Err(Error::Argument {
                flag: format!("{label}: group '{name}' to fix"),
                msg: format!("unknown; the mesh has: {}", mesh.set_names().join(", ")),
            });
        }
    }
    Ok(LoadedPart {
        mesh,
        material,
        fix,
        checks,
        label,
        shift_hz,
        guard_modes,
    })
}
