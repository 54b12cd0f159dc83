//! `linercav export-matrices`: K.mtx and M.mtx of one part (constrained DOFs removed) so any
//! other tool can check our modal results; `linercav export-mesh`: the part's mesh as MSH 4.1.

use super::{load_part, ModelInput};
use crate::error::{Error, Result};
use crate::fem::model::FeModel;
use crate::files as atomic;
use crate::mesh::import::MaterialSource;
use crate::mesh::write::{write_mesh, DeckFormat, WriteOptions};
use crate::mesh::MeshUnit;
use crate::report::mtx;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Summary of what was written.
#[derive(Clone, Debug, Serialize)]
pub struct ExportReport {
    pub dofs: usize,
    pub nnz_lower: usize,
    pub files: Vec<PathBuf>,
}

/// Writes `DIR/K.mtx` and `DIR/M.mtx` (both or neither).
pub fn export_matrices(
    input: &ModelInput,
    extra_fix: &[String],
    out: &Path,
) -> Result<ExportReport> {
    // an output place that cannot be written stops the command before the assembly
    crate::files::check_output_names(out, &["K.mtx", "M.mtx"])?;
    let dirs = crate::files::NewDirs::create(out)?;
    crate::files::check_writable(out)?;
    let part = load_part(input, extra_fix)?;
    let model = FeModel::build(part.mesh, &part.material, &part.fix)?;
    let (kp, mp) = (out.join("K.mtx"), out.join("M.mtx"));
    let km = &model.km;
    let comment = format!(
        "linercav {}: {} (free DOFs {})",
        env!("CARGO_PKG_VERSION"),
        part.label,
        model.n_free()
    );
    atomic::write_all_atomic(vec![
        (
            kp.clone(),
            Box::new(|w: &mut dyn std::io::Write| {
                mtx::write_symmetric(
                    &km.pattern,
                    &km.k,
                    &format!("stiffness K [N/m], {comment}"),
                    w,
                )
            }),
        ),
        (
            mp.clone(),
            Box::new(|w: &mut dyn std::io::Write| {
                mtx::write_symmetric(
                    &km.pattern,
                    &km.m,
                    &format!("consistent mass M [kg], {comment}"),
                    w,
                )
            }),
        ),
    ])?;
    dirs.keep();
    Ok(ExportReport {
        dofs: model.n_free(),
        nnz_lower: km.pattern.lower_entries(&km.k).count(),
        files: vec![kp, mp],
    })
}

/// Writes a part's mesh by the output's extension (`.msh` Gmsh MSH 4.1, `.bdf`/`.nas` Nastran
/// bulk data, `.inp` Abaqus input) in `unit`, with its node sets (generated, named in a deck,
/// or found from the geometry) unless `sets` is false, and its material(s). A scene part comes
/// from the engine model when the scene has a crankcase (both parts placed, every set found);
/// the liner alone otherwise. Returns the number of nodes written.
pub fn export_mesh(input: &ModelInput, out: &Path, unit: MeshUnit, sets: bool) -> Result<usize> {
    if DeckFormat::of_path(out).is_none() {
        return Err(Error::Argument {
            flag: format!("--out {}", out.display()),
            msg: "unknown format: expected .msh (Gmsh MSH 4.1), .bdf or .nas (Nastran bulk data) or .inp (Abaqus input)".into(),
        });
    }
    crate::files::check_not_an_input(out, &[input.path()])?;
    // directories made for the file are removed again if the run fails
    let dirs = crate::files::check_output_file(out)?;
    let (mesh, material) = match input {
        ModelInput::Scene { scene, part, sets }
            if part == "crankcase" || has_crankcase(scene, sets)? =>
        {
            let sc = crate::api::load_scene(scene, sets)?;
            let em = crate::reduce::scene_rom::load_meshes(&sc)?;
            let given = |m: Option<_>, e| m.map(|_| e);
            match part.as_str() {
                "liner" => (em.liner, given(sc.liner.material, em.liner_material)),
                "crankcase" => (
                    em.crankcase,
                    given(
                        sc.crankcase.as_ref().and_then(|c| c.material),
                        em.crankcase_material,
                    ),
                ),
                other => {
                    return Err(Error::Argument {
                        flag: format!("--part {other}"),
                        msg: "expected liner or crankcase".into(),
                    })
                }
            }
        }
        _ => {
            let part = load_part(input, &[])?;
            let given = (part.material_source == MaterialSource::Given).then_some(part.material);
            (part.mesh, given)
        }
    };
    let opts = WriteOptions {
        unit,
        sets,
        material,
    };
    write_mesh(out, &mesh, &opts)?;
    dirs.keep();
    Ok(mesh.nodes.len())
}

/// Whether the scene at `path` has a crankcase (its parts are then exported from the engine).
fn has_crankcase(path: &Path, sets: &[String]) -> Result<bool> {
    Ok(crate::api::load_scene(path, sets)?.crankcase.is_some())
}
