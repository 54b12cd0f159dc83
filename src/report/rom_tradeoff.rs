//! The ROM's accuracy against the full coupled FE model over cut-off factors
//! (`rom-tradeoff`): its record, text and figure.

use super::png::{write_png, Chart, Mark, Rule, Series};
use crate::files::WriteError;
use std::path::Path;

/// One cut-off factor's ROM.
#[derive(Clone, Debug, serde::Serialize)]
pub struct TradeoffRow {
    pub cutoff_factor: f64,
    pub cutoff_hz: f64,
    pub reduced_dofs: usize,
    pub system_modes: usize,
    /// Build from scratch (parts, assembly, system modes, residual vectors) \[s\].
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
    /// Full coupled eigen-solve of the compared modes \[s\].
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

/// `rom_tradeoff.png`: the worst relative frequency error and 1 - the worst MAC (log10)
/// against the cut-off factor, with the floors.
pub fn draw_rom_tradeoff(path: &Path, t: &RomTradeoff) -> Result<(), WriteError> {
    write_png(path, (1100, 650), |root| {
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
    })
}
