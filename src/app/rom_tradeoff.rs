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
use super::rom::build_rom;
use crate::error::{Error, Result};
use crate::files::write_all_atomic;
use crate::reduce::full::FullModes;
use crate::report::png::{write_png, Chart, Mark, Rule, Series};
use crate::scene::Scene;
use std::path::{Path, PathBuf};
use std::time::Instant;

pub use crate::analysis::correlation::{compare_rom_with_full as compare, mac, ModeComparison};

/// One cut-off factor's ROM.
#[derive(Clone, Debug, serde::Serialize)]
pub struct TradeoffRow {
    pub cutoff_factor: f64,
    pub cutoff_hz: f64,
    pub reduced_dofs: usize,
    pub system_modes: usize,
    /// Build from scratch (parts, assembly, system modes, residual vectors) [s].
    pub build_seconds: f64,
    pub worst_frequency_error: f64,
    pub worst_mac: f64,
}

/// What `rom-tradeoff` prints and writes.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RomTradeoff {
    pub scene: String,
    pub band_hz: f64,
    pub full_dofs: usize,
    /// Full coupled eigen-solve of the compared modes [s].
    pub full_seconds: f64,
    /// Modes compared: the full model's below the band.
    pub modes_compared: usize,
    pub rows: Vec<TradeoffRow>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub files: Vec<String>,
}

impl RomTradeoff {
    pub fn to_text(&self) -> String {
        let mut s = format!(
            "{}: ROM against the full coupled FE model ({} DOFs, {} modes below the {:.0} Hz band, full solve {:.1} s)\n",
            self.scene, self.full_dofs, self.modes_compared, self.band_hz, self.full_seconds
        );
        s += "cut-off factor  cut-off [Hz]  reduced DOFs  system modes  worst freq. error  worst MAC  build [s]  full/ROM time\n";
        for r in &self.rows {
            s += &format!(
                "{:>14.2} {:>13.0} {:>13} {:>13} {:>18.2e} {:>10.5} {:>10.1} {:>14.1}\n",
                r.cutoff_factor,
                r.cutoff_hz,
                r.reduced_dofs,
                r.system_modes,
                r.worst_frequency_error,
                r.worst_mac,
                r.build_seconds,
                self.full_seconds / r.build_seconds.max(1e-9)
            );
        }
        s
    }
}

/// Builds the ROM at each cut-off factor and compares it with one full solve.
pub fn run(
    scene_path: &Path,
    sets: &[String],
    factors: &[f64],
    out: Option<&Path>,
) -> Result<RomTradeoff> {
    if factors.is_empty() || factors.iter().any(|f| !(f.is_finite() && *f >= 1.0)) {
        return Err(Error::Argument {
            flag: format!("--factors {factors:?}"),
            msg: "cut-off factors must be numbers >= 1".into(),
        });
    }
    let base = super::load_scene(scene_path, sets)?;
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
        let (b, _, _) = build_rom(sc, true)?;
        let build_seconds = t0.elapsed().as_secs_f64();
        if reference.is_none() {
            // one full solve, sized by the first ROM: its modes below the band (no rigid-body
            // modes, the engine is fixed) plus 4, so the full model's count below the band
            // (<= the ROM's: Ritz values lie above) is always covered
            let n = b.rom.frequencies_hz.iter().filter(|&&x| x < band).count() + 4;
            let t1 = Instant::now();
            let r = full::run(sc, n, None)?;
            if !r.sturm_ok {
                return Err(Error::Failure(format!(
                    "{}: the full model's Sturm check failed (a mode may be missing)",
                    scene_path.display()
                )));
            }
            let below = r.frequencies_hz.iter().filter(|&&x| x < band).count();
            reference = Some((r, t1.elapsed().as_secs_f64(), below));
        }
        let (r, _, below) = reference.as_ref().expect("set above");
        let c = compare(&b, r, *below)
            .ok_or_else(|| Error::Failure("the ROM build did not keep its bases".into()))?;
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

fn write_files(t: &RomTradeoff, dir: &Path) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|e| {
        Error::Write(crate::files::WriteError {
            path: dir.to_path_buf(),
            source: e,
        })
    })?;
    let png = dir.join("rom_tradeoff.png");
    write_png(&png, (1100, 650), |root| {
        let freq: Vec<(f64, f64)> = t
            .rows
            .iter()
            .map(|r| (r.cutoff_factor, r.worst_frequency_error.max(1e-9).log10()))
            .collect();
        let shape: Vec<(f64, f64)> = t
            .rows
            .iter()
            .map(|r| (r.cutoff_factor, (1.0 - r.worst_mac).max(1e-9).log10()))
            .collect();
        let title = format!(
            "ROM against the full FE model ({} modes below {:.0} Hz); builds {} s, full solve {:.0} s",
            t.modes_compared,
            t.band_hz,
            t.rows
                .iter()
                .map(|r| format!("{:.0}", r.build_seconds))
                .collect::<Vec<_>>()
                .join(" / "),
            t.full_seconds
        );
        Chart {
            title: &title,
            x_label: "cut-off factor (cut-off = factor x band)",
            y_label: "log10: worst relative frequency error; 1 - worst MAC",
            series: vec![
                Series {
                    name: "worst relative frequency error".into(),
                    points: freq,
                    mark: Mark::LineDots,
                    color: 0,
                },
                Series {
                    name: "1 - worst MAC".into(),
                    points: shape,
                    mark: Mark::LineDots,
                    color: 1,
                },
            ],
            rules: vec![
                Rule {
                    name: "0.5 % frequency floor".into(),
                    value: 5e-3f64.log10(),
                    vertical: false,
                    color: 6,
                },
                Rule {
                    name: "MAC 0.98 floor".into(),
                    value: 0.02f64.log10(),
                    vertical: false,
                    color: 7,
                },
            ],
            x_range: None,
            y_range: None,
        }
        .draw(root)
    })?;
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
