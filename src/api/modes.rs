//! `linercav modes`: the lowest modes of one part, certified.

use super::progress::Progress;
use super::{load_part, ModelInput};
use crate::error::Result;
use crate::fem::model::{FeModel, Timings};
use crate::report::vtu;
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

/// What to compute.
#[derive(Clone, Debug)]
pub struct ModesRequest {
    pub input: ModelInput,
    pub count: usize,
    pub extra_fix: Vec<String>,
    pub vtu: Option<PathBuf>,
    /// Overrides the scene's shift frequency \[Hz\].
    pub shift_hz: Option<f64>,
    /// Solve at the shift as given (neither the smooth trial fields nor
    /// `eigen::placement::placed_shift` asked).
    pub keep_shift: bool,
}

/// The result as printed (JSON with `--json`).
#[derive(Clone, Debug, Serialize)]
pub struct ModesReport {
    pub frequencies_hz: Vec<f64>,
    pub residuals: Vec<f64>,
    pub dofs: usize,
    pub sturm_count_ok: bool,
    pub seconds: f64,
    pub model: String,
    pub nodes: usize,
    pub elements: usize,
    pub fixed_sets: Vec<String>,
    pub max_residual: f64,
    pub m_orthogonality_error: f64,
    pub sturm: Option<crate::eigen::certify::SturmCheck>,
    /// Modes the first Lanczos solve missed (found by the Sturm count) and a second solve
    /// recovered; 0 when none was missed.
    pub recovered_modes: usize,
    /// The shift frequency the modes were solved at \[Hz\]: the one asked for, or where the
    /// solver moved a shift far below the wanted modes (the smooth trial fields or
    /// `eigen::placement::placed_shift`; a warning says so).
    pub shift_hz: f64,
    pub factor_nnz: usize,
    /// The solve's memory as estimated before it started, from the factor's size
    /// (`scene::budget::modal_solve`) \[GB\].
    pub estimated_memory_gb: f64,
    pub solves: usize,
    pub mass_products: usize,
    pub ncv: usize,
    pub timings: Timings,
    pub warnings: Vec<String>,
    /// Where the material came from: "given" (scene key or flags) or "deck" (per element).
    pub material: String,
}

/// The shift of the request (`--shift-hz`, else the scene's `solver.shift_hz`) and its count,
/// checked: above 1e9 Hz sigma = -(2 pi f)^2 swamps K, no structural spectrum lies there.
fn checked_shift(req: &ModesRequest, part: &super::LoadedPart) -> Result<f64> {
    let shift_hz = req.shift_hz.unwrap_or(part.shift_hz);
    if !(shift_hz.is_finite() && shift_hz > 0.0 && shift_hz <= 1e9) {
        let flag = match req.shift_hz {
            Some(_) => format!("--shift-hz {}", crate::text::num(shift_hz)),
            None => format!("solver.shift_hz = {}", crate::text::num(shift_hz)),
        };
        return Err(crate::error::Error::Argument {
            flag,
            msg: "must be a positive number up to 1e9".into(),
        });
    }
    if req.count == 0 {
        return Err(crate::error::Error::Argument {
            flag: "--count".into(),
            msg: "must be at least 1".into(),
        });
    }
    Ok(shift_hz)
}

/// Runs the modal analysis; `started` is the process start so `seconds` covers everything.
pub fn run(req: &ModesRequest, started: Instant) -> Result<ModesReport> {
    // directories made for the VTU are removed again if the run fails
    let vtu_dirs = match &req.vtu {
        Some(path) => {
            crate::files::check_not_an_input(path, &[req.input.path()])?;
            Some(crate::files::check_output_file(path)?)
        }
        None => None,
    };
    let progress = Progress::new();
    progress.phase("reading mesh");
    let part = load_part(&req.input, &req.extra_fix)?;
    let shift_hz = checked_shift(req, &part)?;
    let (nodes, elements) = (part.mesh.nodes.len(), part.mesh.num_elements());
    let material = match part.material_source {
        crate::mesh::import::MaterialSource::Given => "given".to_string(),
        crate::mesh::import::MaterialSource::Deck => format!(
            "deck: {}",
            part.mesh
                .materials
                .iter()
                .map(|m| format!(
                    "{} (E {} Pa, nu {}, rho {} kg/m^3)",
                    m.name,
                    crate::text::num(m.elastic.young),
                    crate::text::num(m.elastic.poisson),
                    crate::text::num(m.elastic.density)
                ))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    progress.phase("assembling K and M");
    let mut model = FeModel::build(part.mesh, &part.material, &part.fix)?;
    if req.count >= model.n_free() {
        return Err(crate::error::Error::Argument {
            flag: format!("--count {}", req.count),
            msg: format!(
                "must be smaller than the number of free DOFs ({})",
                model.n_free()
            ),
        });
    }
    let estimate =
        crate::scene::budget::modal_solve(&model.modal_solve_sizes(req.count, part.guard_modes));
    part.limits.check_at(&part.limits_file, &estimate)?;
    progress.phase("factorising and solving (ARPACK shift-invert)");
    let sigma = -(2.0 * std::f64::consts::PI * shift_hz).powi(2);
    let sol = model.modes_at(req.count, sigma, part.guard_modes, !req.keep_shift)?;
    if let Some(path) = &req.vtu {
        progress.phase("writing VTU");
        let n = sol.modes.count();
        let shapes: Vec<&[f64]> = (0..n).map(|j| sol.modes.vector(j)).collect();
        let freqs: Vec<f64> = (0..n).map(|j| sol.modes.frequency_hz(j)).collect();
        vtu::write_part_modes(path, &model.mesh, &model.dofs, &shapes, &freqs)?;
    }
    if let Some(d) = vtu_dirs {
        d.keep();
    }
    let max_residual = crate::eigen::certify::worst(sol.residuals.iter().copied());
    let mut warnings = part.checks.warnings;
    warnings.extend(moved_shift_warning(shift_hz, sigma, sol.sigma, req.count));
    let used_hz = (-sol.sigma).max(0.0).sqrt() / (2.0 * std::f64::consts::PI);
    Ok(ModesReport {
        frequencies_hz: (0..sol.modes.count())
            .map(|j| sol.modes.frequency_hz(j))
            .collect(),
        residuals: sol.residuals.clone(),
        dofs: model.n_free(),
        sturm_count_ok: sol.sturm.as_ref().is_some_and(|s| s.ok),
        seconds: started.elapsed().as_secs_f64(),
        model: part.label,
        nodes,
        elements,
        fixed_sets: part.fix,
        max_residual,
        m_orthogonality_error: sol.m_orthogonality,
        sturm: sol.sturm,
        recovered_modes: sol.recovered,
        shift_hz: used_hz,
        factor_nnz: model.analysis.factor_nnz(),
        estimated_memory_gb: estimate.memory / 1e9,
        solves: sol.modes.solves,
        mass_products: sol.modes.mass_products,
        ncv: sol.modes.ncv,
        timings: model.timings.clone(),
        warnings,
        material,
    })
}

/// The warning for a shift the solve moved: away from zero (`eigen::modal::SHIFT_FLOOR`) or
/// up toward the `count` wanted modes from far below them; None when it solved at `sigma`.
fn moved_shift_warning(shift_hz: f64, sigma: f64, used: f64, count: usize) -> Option<String> {
    let used_hz = crate::text::num((-used).max(0.0).sqrt() / (2.0 * std::f64::consts::PI));
    let shift_hz = crate::text::num(shift_hz);
    if used < sigma {
        Some(format!(
            "the shift {shift_hz} Hz lay so close to zero that rigid-body modes' residuals are round-off against it: the modes were solved at {used_hz} Hz (--keep-shift solves at the shift as given)"
        ))
    } else if used != sigma {
        Some(format!(
            "the shift {shift_hz} Hz lay far below the lowest {count} modes: they were solved at {used_hz} Hz (--shift-hz near the lowest modes saves the extra factorisation)"
        ))
    } else {
        None
    }
}

impl ModesReport {
    /// Human-readable table.
    pub fn to_text(&self) -> String {
        let mut s = format!(
            "model      {}\nmesh       {} nodes, {} elements, {} free DOFs{}\n",
            self.model,
            self.nodes,
            self.elements,
            self.dofs,
            if self.fixed_sets.is_empty() {
                " (free-free)".to_string()
            } else {
                format!(", fixed: {}", self.fixed_sets.join(", "))
            }
        );
        s += "\n mode   frequency [Hz]   rel. residual\n";
        for (j, (f, r)) in self.frequencies_hz.iter().zip(&self.residuals).enumerate() {
            s += &format!(" {:>4}   {:>14.3}   {:>13.2e}\n", j + 1, f, r);
        }
        s += &format!(
            "\nM-orthonormality error {:.1e}; largest residual {:.1e}\n",
            self.m_orthogonality_error, self.max_residual
        );
        s += &match &self.sturm {
            Some(st) => format!(
                "Sturm check at {:.1} Hz: {} eigenvalues below, {} computed -> {}\n",
                st.shift_hz,
                st.found,
                st.expected,
                if st.ok {
                    "no mode missed"
                } else {
                    "MISMATCH: a mode was missed"
                }
            ),
            None => "Sturm check: no spectral gap among the computed modes, not certified\n".into(),
        };
        if self.recovered_modes > 0 {
            s += &format!(
                "recovered: the first Lanczos solve missed {} mode(s) the Sturm count found; solved again\n",
                self.recovered_modes
            );
        }
        s += &format!(
            "work: {} solves, {} M-products, ncv {}, factor nnz {} (memory estimated {:.2} GB)\ntime: {:.2} s (assembly {:.2}, ordering {:.2}, factorisation {:.2}, eigen {:.2}, certification {:.2})\n",
            self.solves, self.mass_products, self.ncv, self.factor_nnz, self.estimated_memory_gb, self.seconds,
            self.timings.assembly, self.timings.ordering, self.timings.factorisation, self.timings.eigen, self.timings.certification
        );
        s
    }
}

/// Coupled engine modes (`modes --assembly`).
#[derive(Clone, Debug, Serialize)]
pub struct AssemblyReport {
    pub frequencies_hz: Vec<f64>,
    pub dofs: usize,
    pub seconds: f64,
    /// "rom" or "full".
    pub source: &'static str,
    /// ROM: cache hit, miss or bypassed; full: "none".
    pub cache: &'static str,
    /// Full model only: relative residuals and the Sturm certificate.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residuals: Option<Vec<f64>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sturm_count_ok: Option<bool>,
    /// ROM only: DOFs of the full model it stands for.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub full_dofs: Option<usize>,
}

impl AssemblyReport {
    pub fn to_text(&self) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "coupled engine modes from the {} ({} DOFs, {:.2} s{})",
            if self.source == "rom" {
                "ROM"
            } else {
                "full FE model"
            },
            self.dofs,
            self.seconds,
            if self.source == "rom" {
                format!(", cache {}", self.cache)
            } else {
                String::new()
            }
        );
        for (i, f) in self.frequencies_hz.iter().enumerate() {
            let r = self
                .residuals
                .as_ref()
                .map(|r| format!("   residual {:.1e}", r[i]))
                .unwrap_or_default();
            let _ = writeln!(s, "  {:3}  {:10.2} Hz{r}", i + 1, f);
        }
        if let Some(ok) = self.sturm_count_ok {
            let _ = writeln!(
                s,
                "  Sturm count: {}",
                if ok {
                    "ok (no mode missed)"
                } else {
                    "MISMATCH"
                }
            );
        }
        s
    }
}

/// Coupled engine modes from the ROM or the full FE model.
pub fn run_assembly(
    scene: &crate::scene::Scene,
    count: usize,
    full: bool,
    vtu_path: Option<&std::path::Path>,
    cache: &super::rom::CacheOptions,
    started: Instant,
) -> Result<AssemblyReport> {
    use crate::error::Error;
    if count == 0 {
        return Err(Error::Argument {
            flag: "--count".into(),
            msg: "must be at least 1".into(),
        });
    }
    let vtu_dirs = match vtu_path {
        Some(path) => {
            crate::files::check_not_an_input(path, &[&scene.path])?;
            Some(crate::files::check_output_file(path)?)
        }
        None => None,
    };
    if full {
        // the whole engine's FE model is sized before it is made (per_sector = 2000 aborted in
        // an allocation after 22 s under a 6 GB cap)
        let full = crate::scene::budget::full_model(scene, "the full engine's modal solve", false);
        if let Some(est) = full {
            crate::scene::budget::Limits::of(scene).check(scene, &est)?;
        }
        let r = super::full_modes::run(scene, count, vtu_path)?;
        if let Some(d) = vtu_dirs {
            d.keep();
        }
        return Ok(AssemblyReport {
            frequencies_hz: r.frequencies_hz,
            dofs: r.dofs,
            seconds: started.elapsed().as_secs_f64(),
            source: "full",
            cache: "none",
            residuals: Some(r.residuals),
            sturm_count_ok: Some(r.sturm_ok),
            full_dofs: None,
        });
    }
    let (rom, cache_state) = if let Some(path) = vtu_path {
        // mode shapes on the meshes need the full bases: build in this run
        let (b, lm, cm) = super::rom::build_rom_with_progress(scene, true)?;
        enough_system_modes(&b.rom, count)?;
        super::full_modes::write_vtu(path, scene, &lm, &cm, &b, count)?;
        if let Some(d) = vtu_dirs {
            d.keep();
        }
        (b.rom, "bypassed")
    } else {
        let l = super::rom::get_rom_with_progress(scene, cache)?;
        (l.rom, l.cache)
    };
    enough_system_modes(&rom, count)?;
    Ok(AssemblyReport {
        frequencies_hz: rom.frequencies_hz[..count].to_vec(),
        dofs: rom.info.reduced_dofs,
        seconds: started.elapsed().as_secs_f64(),
        source: "rom",
        cache: cache_state,
        residuals: None,
        sturm_count_ok: None,
        full_dofs: Some(rom.info.full_dofs),
    })
}

/// Refuses `--count` beyond the system modes `rom` holds below its cut-off (checked before a
/// VTU of them is written).
fn enough_system_modes(rom: &crate::reduce::rom::EngineRom, count: usize) -> Result<()> {
    if rom.frequencies_hz.len() < count {
        return Err(crate::error::Error::Argument {
            flag: format!("--count {count}"),
            msg: format!(
                "the ROM holds {} system modes below its cut-off {:.0} Hz; ask for fewer or raise rom.band_hz",
                rom.frequencies_hz.len(),
                rom.info.cutoff_hz
            ),
        });
    }
    Ok(())
}
