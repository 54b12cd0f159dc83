//! What the reduction costs in accuracy, and what it saves in time: the engine ROM against the
//! full coupled FE model (the reference: every part DOF plus the interface fields, no modal
//! truncation, certified ARPACK solve), over several cut-off factors.
//!
//! Per cut-off factor f (cut-off = f x band): the ROM is built from scratch (no cache) and its
//! system modes below the scene's band are paired with the full model's. Frequency error per
//! mode |f_rom - f_full| / f_full; shape error by the modal assurance criterion
//! MAC(a, b) = (a.b)^2 / ((a.a)(b.b)) on all part DOFs, pairing each full mode with the best MAC
//! among ROM modes within 1 % in frequency (close pairs may swap order). A Ritz reduction can
//! only raise frequencies, so a ROM mode below its full counterpart flags a bug.

use super::full_modes as full;
use super::rom::build_rom_with_progress;
use crate::error::{Error, Result};
use crate::files::write_all_atomic;
use crate::reduce::full::FullModes;
use crate::report::rom_tradeoff::draw_rom_tradeoff;
pub use crate::report::rom_tradeoff::{RomTradeoff, TradeoffRow};
use crate::scene::Scene;
use std::path::{Path, PathBuf};
use std::time::Instant;

pub use crate::analysis::correlation::{compare_rom_with_full as compare, mac, ModeComparison};

/// Builds the ROM at each cut-off factor and compares it with one full solve.
pub fn run(
    scene_path: &Path,
    sets: &[String],
    factors: &[f64],
    out: Option<&Path>,
) -> Result<RomTradeoff> {
    let max = crate::scene::CUTOFF_FACTOR_MAX;
    if factors.is_empty() || factors.iter().any(|f| !(1.0..=max).contains(f)) {
        return Err(Error::Argument {
            flag: format!("--factors {factors:?}"),
            msg: format!("cut-off factors must be numbers in [1, {max}]"),
        });
    }
    // the same factor twice builds the same ROM twice
    if let Some(f) =
        (1..factors.len()).find_map(|i| factors[..i].contains(&factors[i]).then_some(factors[i]))
    {
        return Err(Error::Argument {
            flag: format!("--factors {factors:?}"),
            msg: format!(
                "the factor {} is given twice: give each once",
                crate::text::num(f)
            ),
        });
    }
    // an output place that cannot be written stops the command before its solves
    if let Some(dir) = out {
        crate::files::check_output_names(dir, &OUTPUTS)?;
    }
    let base = super::load_scene(scene_path, sets)?;
    // the reference is the full model's modal solve
    let full = crate::scene::budget::full_model(&base, "the full engine's modal solve", false);
    if let Some(est) = full {
        crate::scene::budget::Limits::of(&base).check(&base, &est)?;
    }
    let band = base.rom.band_hz;
    // validate every factor's scene before the long solves
    let scenes: Vec<Scene> = factors
        .iter()
        .map(|f| {
            let mut s = sets.to_vec();
            s.push(format!("rom.cutoff_factor={f}"));
            super::load_scene(scene_path, &s)
        })
        .collect::<std::result::Result<_, _>>()?;
    let mut rows = Vec::new();
    let mut reference: Option<(FullModes, f64, usize)> = None;
    for (f, sc) in factors.iter().zip(&scenes) {
        let t0 = Instant::now();
        let (b, _, _) = build_rom_with_progress(sc, true)?;
        let build_seconds = t0.elapsed().as_secs_f64();
        if reference.is_none() {
            // one full solve, sized by the first ROM: its modes below the band (no rigid-body
            // modes, the engine is fixed) plus 4, so the full model's count below the band
            // (<= the ROM's: Ritz values lie above) is always covered
            let n = b.rom.frequencies_hz.iter().filter(|&&x| x < band).count() + 4;
            let t1 = Instant::now();
            let r = full::run(sc, n, None)?;
            if !r.sturm_ok {
                return Err(Error::ReferenceUncertified {
                    path: scene_path.to_path_buf(),
                });
            }
            let below = r.frequencies_hz.iter().filter(|&&x| x < band).count();
            reference = Some((r, t1.elapsed().as_secs_f64(), below));
        }
        let (r, _, below) = reference.as_ref().expect("set above");
        let c = compare(&b, r, *below).ok_or(Error::NoBases)?;
        rows.push(TradeoffRow {
            cutoff_factor: *f,
            cutoff_hz: f * band,
            reduced_dofs: b.rom.info.reduced_dofs,
            system_modes: b.rom.info.system_modes,
            build_seconds,
            worst_frequency_error: c.worst_frequency_error,
            worst_mac: c.worst_mac,
        });
    }
    let (r, full_seconds, below) = reference.expect("at least one factor");
    let mut report = RomTradeoff {
        scene: scene_path.display().to_string(),
        band_hz: band,
        full_dofs: r.dofs,
        full_seconds,
        modes_compared: below,
        rows,
        files: Vec::new(),
    };
    if let Some(dir) = out {
        report.files = write_files(&report, dir)?
            .iter()
            .map(|p| p.display().to_string())
            .collect();
    }
    Ok(report)
}

/// The files `--out` receives.
const OUTPUTS: [&str; 3] = ["rom_tradeoff.png", "rom_tradeoff.json", "rom_tradeoff.txt"];

fn write_files(t: &RomTradeoff, dir: &Path) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|e| {
        Error::Write(crate::files::WriteError {
            path: dir.to_path_buf(),
            source: e,
        })
    })?;
    let png = dir.join("rom_tradeoff.png");
    draw_rom_tradeoff(&png, t)?;
    let json = serde_json::to_string_pretty(t).expect("serialisable");
    let text = t.to_text();
    let (j, m) = (dir.join("rom_tradeoff.json"), dir.join("rom_tradeoff.txt"));
    write_all_atomic(vec![
        (
            j.clone(),
            Box::new(move |w: &mut dyn std::io::Write| w.write_all(json.as_bytes())),
        ),
        (
            m.clone(),
            Box::new(move |w: &mut dyn std::io::Write| w.write_all(text.as_bytes())),
        ),
    ])?;
    Ok(vec![png, j, m])
}
