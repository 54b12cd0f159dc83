//! The records of an engine run as the commands print and write them: per cylinder and
//! analysis point the mean peaks with their standard error and estimated step error, the
//! solver's statistics, warnings, and the last cycle's time series as CSV. `simulate` writes
//! them as `simulate.json` and `time_series.csv`; the report and the sweeps reuse the
//! per-cylinder records.

use crate::files::{write_atomic, WriteError};
use crate::piston::setup::simulation;
use crate::piston::Piston;
use crate::scene::Scene;
use crate::transient::cycle::{CycleResult, EventSummary, Stats};
use crate::transient::verify::FullOrderReport;
use std::path::Path;

/// One analysis point's peaks.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PointPeaks {
    pub point: usize,
    /// Largest negative acceleration (toward the crankcase... away from the coolant), as a
    /// positive magnitude [m/s^2], and the cylinder's crank angle of it \[deg\].
    pub peak_negative_m_s2: f64,
    pub crank_angle_deg: f64,
    pub peak_positive_m_s2: f64,
    pub positive_crank_angle_deg: f64,
    /// Over the averaged cycles (`stats.cycles_averaged`; the peaks above are their means):
    /// sample standard deviation and largest per-cycle value of the peak negative
    /// acceleration [m/s^2].
    pub peak_negative_std_m_s2: f64,
    pub peak_negative_max_m_s2: f64,
    /// Standard error of the mean peak negative acceleration, corrected for the correlation
    /// of consecutive cycles (`stats.autocorrelation_cycles`) [m/s^2].
    pub peak_negative_se_m_s2: f64,
    /// Estimated step error of the peak negative acceleration: the relative step error of
    /// the point's firing-slap peak (`transient::cycle::StepError`) times the mean [m/s^2].
    pub peak_negative_step_error_m_s2: f64,
    /// With the whole-run step check (`simulate --check-step`; always in the report): the
    /// mean peak negative acceleration of the run repeated at half the step, and its standard
    /// error [m/s^2] ([`StepCheck`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peak_negative_half_step_m_s2: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peak_negative_half_step_se_m_s2: Option<f64>,
    /// The numerical uncertainty of the mean peak [m/s^2] ([`PointPeaks::numerical_uncertainty`]):
    /// what `numerical_uncertainty_scope` of the report says it holds.
    pub peak_negative_numerical_uncertainty_m_s2: f64,
    /// The slap event (index into the cylinder's `slap_events`) whose onset the peak negative
    /// acceleration follows in most averaged cycles, and in how many (`event_cycles`).
    pub peak_negative_event: Option<usize>,
    pub event_cycles: usize,
}

impl PointPeaks {
    /// The whole-run estimate of the step error, E_run = 2 |P_h - P_{h/2}| [m/s^2] (None
    /// without the check). It holds the scatter of both means, standard error
    /// 2 sqrt(SE_h^2 + SE_{h/2}^2), so it leans to the safe side.
    pub fn run_step_error(&self) -> Option<f64> {
        self.peak_negative_half_step_m_s2
            .map(|half| 2.0 * (self.peak_negative_m_s2 - half).abs())
    }

    /// The peak's numerical uncertainty: the larger of the firing-slap estimate and, with the
    /// whole-run check, E_run [m/s^2].
    pub fn numerical_uncertainty(&self) -> f64 {
        self.run_step_error()
            .map_or(self.peak_negative_step_error_m_s2, |e| {
                e.max(self.peak_negative_step_error_m_s2)
            })
    }

    /// Stores [`PointPeaks::numerical_uncertainty`] in its serialised field.
    fn refresh_uncertainty(&mut self) {
        self.peak_negative_numerical_uncertainty_m_s2 = self.numerical_uncertainty();
    }

    /// The combined standard uncertainty of the mean, sqrt(SE^2 + E^2), E the numerical
    /// uncertainty [m/s^2].
    pub fn combined_uncertainty(&self) -> f64 {
        self.peak_negative_se_m_s2
            .hypot(self.numerical_uncertainty())
    }
}

/// The whole-run step check of a run: every cycle repeated at half the step
/// ([`crate::transient::engine::run_half_step`]); per point in [`PointPeaks`].
#[derive(Clone, Debug, serde::Serialize)]
pub struct StepCheck {
    /// Step of the repeated run \[deg\], its averaged cycles and wall time \[s\].
    pub step_deg: f64,
    pub cycles_averaged: usize,
    pub seconds: f64,
    /// Relative difference of the mean of all peak negative accelerations,
    /// (P_h - P_{h/2}) / P_{h/2}, and its standard error (the points' standard errors
    /// averaged, as if fully correlated, per run, combined in quadrature).
    pub mean_difference: f64,
    pub mean_difference_se: f64,
}

/// One cylinder's results.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CylinderReport {
    pub cylinder: usize,
    pub points: Vec<PointPeaks>,
    pub peak_slap_force_n: f64,
    pub slap_crank_angle_deg: f64,
    /// Sample standard deviation of the per-cycle slap-force peak \[N\].
    pub slap_force_std_n: f64,
    /// Standard error of the mean slap force (cycles' correlation respected; 0 for one cycle).
    pub slap_force_se_n: f64,
    pub peak_side_force_n: f64,
    pub side_force_crank_angle_deg: f64,
    /// The slap events over the averaged cycles, in onset order: side, onset crank angle,
    /// force, impact velocity and energy, each a mean with its standard error over the cycles
    /// it occurred in (`cycles`) (`transient::cycle::EventSummary`).
    pub slap_events: Vec<EventSummary>,
}

impl CylinderReport {
    /// The point with the largest mean peak negative acceleration.
    pub fn worst_point(&self) -> Option<&PointPeaks> {
        self.points
            .iter()
            .max_by(|a, b| a.peak_negative_m_s2.total_cmp(&b.peak_negative_m_s2))
    }
}

/// What `simulate` prints.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SimulateReport {
    pub scene: String,
    pub speed_rpm: f64,
    pub cylinders: Vec<CylinderReport>,
    pub seconds: f64,
    /// Wall time of the transient alone \[s\].
    pub transient_seconds: f64,
    pub stats: Stats,
    pub cache: &'static str,
    /// The scene's `transient.tolerance`.
    pub tolerance: f64,
    pub hot_clearance_um: f64,
    pub peak_pressure_bar: f64,
    pub peak_pressure_deg: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_series_csv: Option<String>,
    /// With `--full-order`: the comparison on the window, and its two headline figures.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub full_order: Option<FullOrderReport>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rom_error_peak_negative: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub speedup: Option<f64>,
    /// The whole-run step check, when run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub step_check: Option<StepCheck>,
    /// With `--maps`: per cylinder where the liner map's largest mean peak lies.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub liner_maps: Option<Vec<crate::report::maps::MapSummary>>,
    /// What each point's `peak_negative_numerical_uncertainty_m_s2` holds: `"firing_slaps"`,
    /// the step error of each cylinder's firing slap re-run at half the step (not the shift the
    /// coarse step makes in the cycles' statistics between the slaps: up to 2-3 % at single
    /// cylinders of the default engine, docs/verification.md), or, with the whole-run check
    /// (`--check-step`), `"whole_run"`: the larger of that and 2 |P_h - P_{h/2}|.
    pub numerical_uncertainty_scope: &'static str,
    /// With `--rank`: the decided ranking of pooled realisations
    /// ([`crate::analysis::ranking::DecidedRanking`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ranking: Option<crate::analysis::ranking::DecidedRanking>,
    /// Physically doubtful scene values (also printed on stderr).
    pub warnings: Vec<String>,
    /// The skirt's lubrication model that ran: "dry", "squeeze" or "mixed"
    /// (`piston.lubrication`).
    pub lubrication: crate::piston::lubrication::Lubrication,
    /// The pin journal's friction coefficient that ran (`piston.pin_friction`; 0: none).
    pub pin_friction: f64,
}

impl SimulateReport {
    /// The report of a cycle result (no full-order comparison, no files yet).
    pub fn new(
        scene: &Scene,
        piston: &Piston,
        res: &CycleResult,
        cache: &'static str,
        transient_seconds: f64,
    ) -> Self {
        let (pp, pdeg) = piston.pressure.peak();
        SimulateReport {
            scene: scene.path.display().to_string(),
            speed_rpm: scene.engine.speed_rpm,
            cylinders: Self::cylinders_of(res),
            seconds: 0.0,
            transient_seconds,
            stats: res.stats.clone(),
            cache,
            tolerance: simulation(scene).map_or(0.0, |s| s.transient.tolerance),
            warnings: scene
                .warnings
                .iter()
                .cloned()
                .chain(crate::piston::setup::interference_warning(
                    piston.skirt.hot_clearance(),
                    simulation(scene).map_or(0.0, |s| s.piston.skirt.clearance),
                ))
                .collect(),
            hot_clearance_um: piston.skirt.hot_clearance() * 1e6,
            lubrication: piston
                .film
                .as_ref()
                .map_or(crate::piston::lubrication::Lubrication::Dry, |f| f.model),
            pin_friction: piston.pin_friction,
            peak_pressure_bar: pp / 1e5,
            peak_pressure_deg: pdeg,
            time_series_csv: None,
            full_order: None,
            rom_error_peak_negative: None,
            speedup: None,
            step_check: None,
            liner_maps: None,
            numerical_uncertainty_scope: "firing_slaps",
            ranking: None,
        }
    }

    /// Adds the whole-run step check from `half`, the run repeated at half the step
    /// ([`crate::transient::engine::run_half_step`]), which took `seconds`.
    pub fn add_step_check(&mut self, half: &CycleResult, seconds: f64) {
        let (mut sum_h, mut sum_half, mut se_h, mut se_half) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for (c, row) in self.cylinders.iter_mut().zip(half.peak_negative.rows()) {
            for (p, q) in c.points.iter_mut().zip(row) {
                p.peak_negative_half_step_m_s2 = Some(q.value);
                p.peak_negative_half_step_se_m_s2 = Some(q.se);
                p.refresh_uncertainty();
                sum_h += p.peak_negative_m_s2;
                sum_half += q.value;
                se_h += p.peak_negative_se_m_s2;
                se_half += q.se;
            }
        }
        // the means' sums: the relative differences of the means are those of the sums
        let scale = sum_half.abs().max(1e-12);
        self.numerical_uncertainty_scope = "whole_run";
        self.step_check = Some(StepCheck {
            step_deg: half.stats.dt_s * self.speed_rpm * 6.0,
            cycles_averaged: half.stats.cycles_averaged,
            seconds,
            mean_difference: (sum_h - sum_half) / scale,
            mean_difference_se: se_h.hypot(se_half) / scale,
        });
    }

    /// Per-cylinder summary of a result.
    pub fn cylinders_of(res: &CycleResult) -> Vec<CylinderReport> {
        res.peaks
            .iter()
            .enumerate()
            .map(|(ci, c)| {
                let step = res.step_error.iter().find(|e| e.cylinder == c.cylinder);
                (ci, c, step)
            })
            .map(|(ci, c, step)| CylinderReport {
                cylinder: c.cylinder,
                points: res
                    .peak_negative
                    .row(ci)
                    .iter()
                    .zip(res.peak_positive.row(ci))
                    .enumerate()
                    .map(|(k, (n, p))| {
                        let mut point = PointPeaks {
                            point: k + 1,
                            peak_negative_m_s2: n.value,
                            crank_angle_deg: n.crank_angle_deg,
                            peak_positive_m_s2: p.value,
                            positive_crank_angle_deg: p.crank_angle_deg,
                            peak_negative_std_m_s2: n.std,
                            peak_negative_max_m_s2: n.max,
                            peak_negative_se_m_s2: n.se,
                            peak_negative_step_error_m_s2: step
                                .map_or(0.0, |e| e.relative(k) * n.value),
                            peak_negative_half_step_m_s2: None,
                            peak_negative_half_step_se_m_s2: None,
                            peak_negative_numerical_uncertainty_m_s2: 0.0,
                            peak_negative_event: c.negative_events.get(k).and_then(|e| e.0),
                            event_cycles: c.negative_events.get(k).map_or(0, |e| e.1),
                        };
                        point.refresh_uncertainty();
                        point
                    })
                    .collect(),
                peak_slap_force_n: c.slap_force.value,
                slap_crank_angle_deg: c.slap_force.crank_angle_deg,
                slap_force_std_n: c.slap_force.std,
                slap_force_se_n: c.slap_force.se,
                peak_side_force_n: c.side_force.value,
                side_force_crank_angle_deg: c.side_force.crank_angle_deg,
                slap_events: c.slap_events.clone(),
            })
            .collect()
    }

    /// With the whole-run check: each cylinder's worst point as (cylinder, relative difference
    /// (P_h - P_{h/2}) / P_{h/2}, its standard error sqrt(SE_h^2 + SE_{h/2}^2) / P_{h/2}).
    pub fn worst_point_step_checks(&self) -> Vec<(usize, f64, f64)> {
        self.cylinders
            .iter()
            .filter_map(|c| {
                let w = c.worst_point()?;
                let half = w.peak_negative_half_step_m_s2?;
                let se = w
                    .peak_negative_se_m_s2
                    .hypot(w.peak_negative_half_step_se_m_s2?);
                let scale = half.abs().max(1e-12);
                Some((
                    c.cylinder,
                    (w.peak_negative_m_s2 - half) / scale,
                    se / scale,
                ))
            })
            .collect()
    }

    /// The whole-run check as one line of text (empty without it).
    pub fn step_check_text(&self) -> String {
        let Some(c) = &self.step_check else {
            return String::new();
        };
        let per: Vec<String> = self
            .worst_point_step_checks()
            .iter()
            .map(|(cyl, d, se)| format!("{cyl}: {:+.1} ± {:.1} %", 100.0 * d, 100.0 * se))
            .collect();
        format!(
            "whole-run step check (every cycle repeated at {:.4} deg, {} averaged, {:.1} s): the mean peak differs by {:+.1} ± {:.1} %; each cylinder's worst point {}; the numerical uncertainty of a peak is the larger of 2 |difference| and the firing-slap estimate",
            c.step_deg,
            c.cycles_averaged,
            c.seconds,
            100.0 * c.mean_difference,
            100.0 * c.mean_difference_se,
            per.join(", ")
        )
    }

    pub fn to_text(&self) -> String {
        let mut s = format!(
            "{} at {:.0} rpm: peak pressure {:.1} bar at {:.1} deg, hot clearance {:.1} um, skirt {}{}\n",
            self.scene,
            self.speed_rpm,
            self.peak_pressure_bar,
            self.peak_pressure_deg,
            self.hot_clearance_um,
            self.lubrication.name(),
            if self.pin_friction > 0.0 {
                format!(", pin friction {}", self.pin_friction)
            } else {
                String::new()
            }
        );
        s += &self.peaks_text();
        let st = &self.stats;
        s += &format!(
            "solver: {} steps (dt {:.2} us), {} Newton iterations (max {} per step), {} rejected, {} modes, energy balance {:.1e}, max penetration {:.2} um, last-cycle change {:.1e}, coupling lag {:.3} um\n",
            st.steps, st.dt_s * 1e6, st.newton_iterations, st.max_newton_per_step, st.rejected_steps, st.modes, st.energy_error, st.max_penetration_m * 1e6, st.cycle_change, st.coupling_lag_m * 1e6
        );
        let wide: Vec<String> = self
            .cylinders
            .iter()
            .filter_map(|c| {
                let w = c.worst_point()?;
                let rel = w.peak_negative_se_m_s2 / w.peak_negative_m_s2.abs().max(1e-12);
                (rel > 0.02).then(|| format!("cylinder {} ({:.1} %)", c.cylinder, 100.0 * rel))
            })
            .collect();
        if !wide.is_empty() {
            s += &format!(
                "statistics: standard error of the worst point's mean above 2 % for {}: average more cycles (transient.cycles, transient.averaged_cycles)\n",
                wide.join(", ")
            );
        }
        s += &format!(
            "accuracy: estimated step error of the mean peak {:.1} % (tolerance {:.1} %{}), step {:.4} deg{}\n",
            100.0 * st.step_error_estimate,
            100.0 * self.tolerance,
            if st.step_error_estimate <= self.tolerance { ", met" } else { ", NOT met: refine transient.step_deg" },
            st.dt_s * self.speed_rpm * 6.0,
            if st.step_refinements > 0 { format!(" (halved {} time(s) to meet the tolerance)", st.step_refinements) } else { String::new() }
        );
        if self.step_check.is_some() {
            s += &self.step_check_text();
            s += "\n";
        } else {
            s += "  (from each cylinder's firing slap re-run at half the step; what the coarse step shifts between the slaps is not in it: --check-step measures it)\n";
        }
        if let Some(r) = &self.ranking {
            s += &format!(
                "decided ranking (worst points; > separated, = tied within {:.0} m/s^2 = {:.0} % of the mean, ? undecided; two combined standard uncertainties): {}\n  {}\n",
                r.resolution_m_s2,
                100.0 * r.resolution_fraction,
                r.pairs_text(),
                r.stopped
            );
        }
        s += &format!(
            "ROM cache: {}; {:.2} s (transient {:.3} s)\n",
            self.cache, self.seconds, self.transient_seconds
        );
        s += &self.full_order_text();
        s += &self.maps_text();
        if let Some(f) = &self.time_series_csv {
            s += &format!("time series: {f}\n");
        }
        s
    }

    /// The peak tables: per cylinder and point the peak negative and positive accelerations
    /// with their statistics; per cylinder the side and slap force peaks.
    fn peaks_text(&self) -> String {
        let mut s = String::new();
        let n = self.stats.cycles_averaged;
        s += &format!(
            "peaks: mean over the last {n} cycle(s); sample std; standard error of the mean (cycles correlated: tau {:.2}); estimated step error; largest\n",
            self.stats.autocorrelation_cycles
        );
        s += "cyl  point  peak neg [m/s^2]   std    SE  step    max @deg   peak pos [m/s^2] @deg\n";
        for c in &self.cylinders {
            for p in &c.points {
                s += &format!(
                    "{:>3}  {:>5}  {:>16.0} {:>5.0} {:>5.0} {:>5.0} {:>6.0} {:>6.1}   {:>16.0} {:>6.1}\n",
                    c.cylinder,
                    p.point,
                    p.peak_negative_m_s2,
                    p.peak_negative_std_m_s2,
                    p.peak_negative_se_m_s2,
                    p.peak_negative_step_error_m_s2,
                    p.peak_negative_max_m_s2,
                    p.crank_angle_deg,
                    p.peak_positive_m_s2,
                    p.positive_crank_angle_deg
                );
            }
        }
        s += "cyl  side force peak [N] @deg   dynamic slap force [N] @deg\n";
        for c in &self.cylinders {
            s += &format!(
                "{:>3}  {:>19.0} {:>6.1}   {:>22.0} {:>6.1}\n",
                c.cylinder,
                c.peak_side_force_n,
                c.side_force_crank_angle_deg,
                c.peak_slap_force_n,
                c.slap_crank_angle_deg
            );
        }
        s
    }

    /// The full-order window's comparison, when run.
    fn full_order_text(&self) -> String {
        let mut s = String::new();
        if let Some(c) = &self.full_order {
            s += &format!(
                "full-order check, cylinder {} from {:.0} to {:.0} deg ({} steps of {:.4} deg, both low-passed to {:.0} Hz): {} DOFs vs {} ROM modes\n",
                c.cylinder, c.window_start_deg, c.window_end_deg, c.steps, c.step_deg, c.filter_band_hz, c.full_dofs, c.rom_modes
            );
            s += "  point  peak neg full [m/s^2] @deg   ROM [m/s^2] @deg   error\n";
            for p in &c.points {
                s += &format!(
                    "  {:>5}  {:>20.1} {:>6.2}   {:>11.1} {:>6.2}   {:.2e}\n",
                    p.point,
                    p.peak_negative_full_m_s2,
                    p.crank_angle_full_deg,
                    p.peak_negative_rom_m_s2,
                    p.crank_angle_rom_deg,
                    p.relative_error
                );
            }
            s += &format!(
                "  ROM error (peak negative) {:.2e} (the ROM's peaks move {:.2e} at half the step), contact force {:.2e}, preload {:.2e}; speed-up {:.0}x ({:.1} s vs {:.4} s; stepping alone {:.0}x)\n",
                c.rom_error_peak_negative, c.rom_step_change, c.contact_force_error, c.preload_error, c.speedup, c.full_seconds, c.rom_seconds, c.speedup_stepping
            );
        }
        s
    }

    /// Where each liner map's largest mean peak lies, when mapped.
    fn maps_text(&self) -> String {
        let mut s = String::new();
        if let Some(maps) = &self.liner_maps {
            s += "liner maps (wet outer surface): cyl  nodes  largest mean peak negative [m/s^2] at [deg, mm]   Ca   surface past Ca = 1\n";
            for m in maps {
                s += &format!(
                    "  {:>3} {:>6}  {:>10.0} +- {:<5.0} at {:>3.0}, {:>3.0}   {:>5.2}   {:.1} %\n",
                    m.cylinder,
                    m.nodes,
                    m.peak_negative_m_s2,
                    m.peak_negative_se_m_s2,
                    m.hottest_theta_deg,
                    m.hottest_depth_mm,
                    m.ca,
                    100.0 * m.share_ca_below_1
                );
            }
        }
        s
    }
}

/// Writes the last cycle's time series (one row per step): per cylinder the liner points'
/// accelerations (+ toward the coolant), the crankcase jacket wall's at the facing points
/// (across the coolant gap, same sign convention), piston lateral motion and tilt, contact
/// forces, the quasi-static side force and the cylinder pressure.
pub fn write_series(path: &Path, res: &CycleResult) -> Result<(), WriteError> {
    let s = &res.series;
    write_atomic(path, |w| {
        write!(w, "crank_angle_deg,time_s")?;
        for c in &s.cylinders {
            let k = c.cylinder;
            for p in 0..c.acceleration.nrows() {
                write!(w, ",c{k}_p{}_acc_m_s2", p + 1)?;
            }
            for p in 0..c.crankcase_acceleration.nrows() {
                write!(w, ",c{k}_p{}_wall_acc_m_s2", p + 1)?;
            }
            write!(
                w,
                ",c{k}_lateral_um,c{k}_tilt_mrad,c{k}_thrust_force_n,c{k}_antithrust_force_n,c{k}_thrust_impulse_n_s,c{k}_antithrust_impulse_n_s,c{k}_side_force_n,c{k}_pressure_bar"
            )?;
        }
        writeln!(w)?;
        for i in 0..s.time_s.len() {
            write!(w, "{:.4},{:.8}", s.crank_angle_deg[i], s.time_s[i])?;
            for c in &s.cylinders {
                for a in c
                    .acceleration
                    .rows()
                    .into_iter()
                    .chain(c.crankcase_acceleration.rows())
                {
                    write!(w, ",{:.3}", a[i])?;
                }
                write!(
                    w,
                    ",{:.4},{:.5},{:.2},{:.2},{:.6e},{:.6e},{:.2},{:.3}",
                    c.lateral_m[i] * 1e6,
                    c.tilt_rad[i] * 1e3,
                    c.thrust_force_n[i],
                    c.antithrust_force_n[i],
                    c.thrust_impulse_n_s[i],
                    c.antithrust_impulse_n_s[i],
                    c.side_force_n[i],
                    c.pressure_pa[i] / 1e5
                )?;
            }
            writeln!(w)?;
        }
        Ok(())
    })
}
