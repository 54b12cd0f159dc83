//! `simulate --full-order`: the comparison of [`crate::transient::verify`] and its window
//! series as CSV.

use crate::error::Result;
use crate::linalg::dense::row;
use crate::transient::signal::low_pass;
pub use crate::transient::verify::{compare, FullOrderReport, PointComparison};

/// Writes both runs of the window, one row per step: crank angle, then for the full model and
/// the ROM the piston's lateral displacement \[um\] and tilt \[mrad\], the net contact force toward
/// thrust \[N\], and each analysis point's acceleration raw and low-passed to the band [m/s^2].
pub fn write_window_series(path: &std::path::Path, report: &FullOrderReport) -> Result<()> {
    let runs = [("full", &report.full_series), ("rom", &report.rom_series)];
    let filtered: Vec<Vec<Vec<f64>>> = runs
        .iter()
        .map(|(_, r)| {
            (0..r.acceleration.nrows())
                .map(|p| {
                    low_pass(
                        row(&r.acceleration, p),
                        report.dt,
                        report.filter_band_hz,
                        false,
                    )
                    .0
                })
                .collect()
        })
        .collect();
    crate::files::write_atomic(path, |w| {
        write!(w, "crank_angle_deg")?;
        for (name, r) in &runs {
            write!(
                w,
                ",{name}_lateral_um,{name}_tilt_mrad,{name}_contact_force_n"
            )?;
            for p in 1..=r.acceleration.nrows() {
                write!(w, ",{name}_p{p}_acc_m_s2,{name}_p{p}_acc_band_m_s2")?;
            }
        }
        writeln!(w)?;
        let n = report.full_series.crank_angle_deg.len();
        for i in 0..n {
            write!(w, "{:.4}", report.full_series.crank_angle_deg[i])?;
            for ((_, r), f) in runs.iter().zip(&filtered) {
                write!(
                    w,
                    ",{:.4},{:.5},{:.3}",
                    r.lateral_m[i] * 1e6,
                    r.tilt_rad[i] * 1e3,
                    r.contact_force_n[i]
                )?;
                for (p, af) in f.iter().enumerate() {
                    write!(w, ",{:.3},{:.3}", r.acceleration[[p, i]], af[i])?;
                }
            }
            writeln!(w)?;
        }
        Ok(())
    })?;
    Ok(())
}
