//! `linercav export-matrices`: K.mtx and M.mtx of one part (constrained DOFs removed) so any
//! other tool can check our modal results; `linercav export-mesh`: the part's mesh as MSH 4.1.

use super::{load_part, ModelInput};
use crate::error::{Error, Result};
use crate::fem::model::FeModel;
use crate::files as atomic;
use crate::mesh::gmsh;
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

fn ensure_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| {
        Error::Write(crate::files::WriteError {
            path: dir.to_path_buf(),
            source: e,
        })
    })
}

/// Writes `DIR/K.mtx` and `DIR/M.mtx` (both or neither).
pub fn export_matrices(
    input: &ModelInput,
    extra_fix: &[String],
    out: &Path,
) -> Result<ExportReport> {
    let part = load_part(input, extra_fix)?;
    let model = FeModel::build(part.mesh, &part.material, &part.fix)?;
    ensure_dir(out)?;
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
    Ok(ExportReport {
        dofs: model.n_free(),
        nnz_lower: km.pattern.lower_entries(&km.k).count(),
        files: vec![kp, mp],
    })
}

/// Writes the part's (checked) mesh as MSH 4.1 ASCII with its node sets as physical groups.
pub fn export_mesh(input: &ModelInput, out: &Path) -> Result<usize> {
    let part = load_part(input, &[])?;
    atomic::write_atomic(out, |w| gmsh::write(&part.mesh, &mut { w }))?;
    Ok(part.mesh.nodes.len())
}
