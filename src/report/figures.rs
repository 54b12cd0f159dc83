//! The design-review report's figures: `pressure.png` (cylinder pressure, side force),
//! `acceleration.png` (liner acceleration per cylinder around firing, with the thresholds),
//! `spectra.png`, `frf.png` (inertance from the slap location to each cylinder's worst point,
//! from the modal model), `peaks.png` (per cylinder and point, with the thresholds),
//! `modes_risk.png` (coefficients of the best-correlated of the modes nearest the dominant
//! response beside the per-cylinder peaks), `sweep_clearance.png`, `sweep_pin_offset.png`,
//! `criteria.png` (CSF against Ca) and `speed_error.png`.

use super::png::{bars, write_png, BarData, Chart, Mark, Rule, Series};
use super::records::SimulateReport;
use super::study::Change;
use crate::analysis::spectrum::{rms_average, Spectrum};
use crate::cavitation::criteria::Thresholds;
use crate::cavitation::evaluate::{spectra, Evaluation};
use crate::files::WriteError;
use crate::linalg::dense::Dense;
use crate::piston::Piston;
use crate::reduce::rom::EngineRom;
use crate::scene::Scene;
use crate::transient::cycle::CycleResult;
pub use crate::transient::verify::{TradeoffKind, TradeoffPoint};
use std::path::{Path, PathBuf};

/// One run of a report sweep, condensed.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SweepPoint {
    pub value: f64,
    /// Per cylinder: largest peak negative acceleration over the points, slap force, side
    /// force and its crank angle, peak |tilt|.
    pub peak_negative_m_s2: Vec<f64>,
    pub peak_slap_force_n: Vec<f64>,
    pub peak_side_force_n: Vec<f64>,
    pub side_force_crank_angle_deg: Vec<f64>,
    pub peak_tilt_rad: Vec<f64>,
    /// Per cylinder (rows) and point (columns).
    #[serde(serialize_with = "crate::linalg::dense::serialize_rows")]
    pub points_m_s2: Dense,
    /// The engine's largest mean peak negative acceleration and the standard error of the point
    /// that holds it.
    pub largest_m_s2: f64,
    pub largest_se_m_s2: f64,
    /// Cycles the peaks are means over.
    pub cycles_averaged: usize,
    /// Its change against the scene's own design ([`Change::of`]); None for the scene's run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub change: Option<Change>,
}

impl SweepPoint {
    /// The sweep's summary of the run `r` at the swept `value`: per cylinder the largest mean
    /// peak negative acceleration over the points, the slap and side-force peaks, the
    /// side-force angle and the last cycle's largest |tilt|; per cylinder and point the peaks.
    pub fn of(value: f64, r: &CycleResult) -> Self {
        let points = r.peak_negative.map(|p| p.value);
        let largest =
            r.peak_negative
                .iter()
                .fold(None::<&crate::transient::cycle::Peak>, |m, p| match m {
                    Some(q) if q.value >= p.value => Some(q),
                    _ => Some(p),
                });
        SweepPoint {
            value,
            peak_negative_m_s2: points
                .rows()
                .into_iter()
                .map(|p| p.iter().fold(0.0f64, |m, &v| m.max(v)))
                .collect(),
            peak_slap_force_n: r.peaks.iter().map(|c| c.slap_force.value).collect(),
            peak_side_force_n: r.peaks.iter().map(|c| c.side_force.value).collect(),
            side_force_crank_angle_deg: r
                .peaks
                .iter()
                .map(|c| c.side_force.crank_angle_deg)
                .collect(),
            peak_tilt_rad: r
                .series
                .cylinders
                .iter()
                .map(|c| c.tilt_rad.iter().fold(0.0f64, |m, v| m.max(v.abs())))
                .collect(),
            points_m_s2: points,
            largest_m_s2: largest.map_or(0.0, |p| p.value),
            largest_se_m_s2: largest.map_or(0.0, |p| p.se),
            cycles_averaged: r.stats.cycles_averaged,
            change: None,
        }
    }

    /// Sets the change of the largest peak against `base` (the scene's own run).
    pub fn set_change(&mut self, base: &SweepPoint) {
        self.change = Some(Change::of(
            (self.largest_m_s2, self.largest_se_m_s2),
            (base.largest_m_s2, base.largest_se_m_s2),
            self.cycles_averaged > 1 && base.cycles_averaged > 1,
        ));
    }
}

/// Horizontal rules at the acceleration criterion's onset and high-risk thresholds at
/// `sign` x their values (-1 on a signed acceleration axis), named with the values when
/// `with_values`; grey and black, apart from the six cylinders' colours.
fn threshold_rules(t: &Thresholds, sign: f64, with_values: bool) -> Vec<Rule> {
    let prefix = if sign < 0.0 { "-" } else { "" };
    [
        ("onset", t.onset_m_s2, 6),
        ("high risk", t.high_risk_m_s2, 7),
    ]
    .into_iter()
    .map(|(name, v, color)| Rule {
        name: match with_values {
            true => format!("{prefix}{name} {v:.0}"),
            false => format!("{prefix}{name}"),
        },
        value: sign * v,
        vertical: false,
        color,
    })
    .collect()
}

/// Vertical rules at the two system modes nearest the dominant response.
fn mode_rules(ev: &Evaluation) -> Vec<Rule> {
    ev.nearest_modes
        .iter()
        .take(2)
        .enumerate()
        .map(|(k, m)| Rule {
            name: format!("system mode {:.0} Hz", m.frequency_hz),
            value: m.frequency_hz,
            vertical: true,
            color: 6 + k,
        })
        .collect()
}

/// Everything the report's figures are drawn from.
#[derive(Clone, Copy)]
pub struct Figures<'a> {
    pub out: &'a Path,
    pub scene: &'a Scene,
    pub piston: &'a Piston,
    pub base: &'a CycleResult,
    /// The run's records: each peak's combined uncertainty.
    pub simulate: &'a SimulateReport,
    pub ev: &'a Evaluation,
    pub clearance: &'a [SweepPoint],
    pub offset: &'a [SweepPoint],
    pub trade: &'a [TradeoffPoint],
    pub rom: &'a EngineRom,
}

impl Figures<'_> {
    /// Draws every figure; returns the files written.
    pub fn draw(&self) -> Result<Vec<PathBuf>, WriteError> {
        let mut files = Vec::new();
        for figure in [
            Self::pressure,
            Self::acceleration,
            Self::spectra,
            Self::frf,
            Self::peaks,
            Self::modes_risk,
            Self::sweeps,
            Self::criteria,
            Self::speed_error,
        ] {
            files.extend(figure(self)?);
        }
        Ok(files)
    }

    /// Crank angle of each step of the last cycle in cylinder `ci`'s own frame (0 at its
    /// firing-cycle start).
    fn own(&self, ci: usize) -> Vec<f64> {
        let s = &self.base.series;
        let fo = &self.scene.engine.firing_order;
        let cyl = s.cylinders[ci].cylinder;
        let k = fo.iter().position(|&x| x == cyl).unwrap_or(0);
        let phase = 720.0 * k as f64 / fo.len() as f64;
        s.crank_angle_deg
            .iter()
            .map(|a| (a - phase).rem_euclid(720.0))
            .collect()
    }

    /// `pressure.png`: cylinder pressure and side force over the cycle.
    fn pressure(&self) -> Result<Vec<PathBuf>, WriteError> {
        let Self { out, piston, .. } = *self;
        let mut files = Vec::new();
        // pressure and side force
        let p = out.join("pressure.png");
        let pressure: Vec<(f64, f64)> = (0..=1440)
            .map(|k| {
                let d = k as f64 * 0.5;
                (d, piston.pressure.at(d) / 1e5)
            })
            .collect();
        let side: Vec<(f64, f64)> = (0..=1440)
            .map(|k| {
                let d = k as f64 * 0.5;
                (d, piston.loads(d).side_force / 1e3)
            })
            .collect();
        write_png(&p, (1500, 560), |root| {
            let (a, b) = root.split_horizontally(750);
            Chart {
                title: "Cylinder pressure",
                x_label: "crank angle [deg] (firing TDC 360)",
                y_label: "pressure [bar]",
                series: vec![Series {
                    name: String::new(),
                    points: pressure.clone(),
                    mark: Mark::Line,
                    color: 0,
                }],
                rules: vec![Rule {
                    name: "firing TDC".into(),
                    value: 360.0,
                    vertical: true,
                    color: 6,
                }],
                x_range: None,
                y_range: None,
            }
            .draw(&a)?;
            Chart {
                title: "Quasi-static side force (+ toward thrust)",
                x_label: "crank angle [deg]",
                y_label: "side force [kN]",
                series: vec![Series {
                    name: String::new(),
                    points: side.clone(),
                    mark: Mark::Line,
                    color: 1,
                }],
                rules: vec![Rule {
                    name: "firing TDC".into(),
                    value: 360.0,
                    vertical: true,
                    color: 6,
                }],
                x_range: None,
                y_range: None,
            }
            .draw(&b)
        })?;
        files.push(p);
        Ok(files)
    }

    /// `acceleration.png`: each cylinder's point accelerations around its firing.
    fn acceleration(&self) -> Result<Vec<PathBuf>, WriteError> {
        let Self { out, base, ev, .. } = *self;
        let t = ev.thresholds;
        let s = &base.series;
        let own = |ci: usize| self.own(ci);
        let n = base.series.time_s.len();
        let mut files = Vec::new();
        // acceleration time series per cylinder, around firing
        let p = out.join("acceleration.png");
        let nc = s.cylinders.len();
        write_png(&p, (1500, 340 * nc.div_ceil(2).max(1) as u32), |root| {
            let areas = root.split_evenly((nc.div_ceil(2).max(1), 2));
            for (ci, area) in areas.iter().enumerate().take(nc) {
                let ang = own(ci);
                let c = &s.cylinders[ci];
                let series = c
                    .acceleration
                    .rows()
                    .into_iter()
                    .enumerate()
                    .map(|(pi, a)| {
                        let mut pts: Vec<(f64, f64)> = (0..n)
                            .filter(|&k| ang[k] >= 330.0 && ang[k] <= 450.0)
                            .map(|k| (ang[k], a[k]))
                            .collect();
                        pts.sort_by(|x, y| x.0.total_cmp(&y.0));
                        Series {
                            name: format!("point {}", pi + 1),
                            points: pts,
                            mark: Mark::Line,
                            color: pi,
                        }
                    })
                    .collect();
                let title = format!(
                    "Cylinder {}: liner acceleration (+ toward the coolant)",
                    c.cylinder
                );
                Chart {
                    title: &title,
                    x_label: "crank angle of the cylinder [deg]",
                    y_label: "acceleration [m/s^2]",
                    series,
                    rules: threshold_rules(&t, -1.0, false),
                    x_range: Some((330.0, 450.0)),
                    y_range: None,
                }
                .draw(area)?;
            }
            Ok(())
        })?;
        files.push(p);
        Ok(files)
    }

    /// `spectra.png`: the spectrum of each cylinder's worst point, averaged over the cycles.
    fn spectra(&self) -> Result<Vec<PathBuf>, WriteError> {
        let Self {
            out,
            scene,
            base,
            ev,
            ..
        } = *self;
        let s = &base.series;
        let fo = &scene.engine.firing_order;
        let mut files = Vec::new();
        // spectra of each cylinder's worst point
        let p = out.join("spectra.png");
        let sp = spectra(s, fo);
        let band = scene.rom.band_hz;
        // (frequency, amplitude) pairs within the band
        let curve = |x: &Spectrum| -> Vec<(f64, f64)> {
            x.frequency_hz
                .iter()
                .zip(&x.amplitude)
                .filter(|(f, _)| **f <= band)
                .map(|(f, a)| (*f, *a))
                .collect()
        };
        write_png(&p, (1500, 600), |root| {
            let mut series: Vec<Series> = ev
                .cylinders
                .iter()
                .enumerate()
                .filter_map(|(ci, c)| {
                    let spc = sp.get(ci)?.get(c.worst_point.checked_sub(1)?)?;
                    Some(Series {
                        name: format!("cylinder {} point {}", c.cylinder, c.worst_point),
                        points: curve(spc),
                        mark: Mark::Line,
                        color: ci,
                    })
                })
                .collect();
            // the engine-wide dominant response is the peak of this average (cavitation::evaluate::evaluate)
            let all: Vec<&Spectrum> = sp.iter().flatten().collect();
            if let Some(avg) = rms_average(&all) {
                series.push(Series {
                    name: format!("RMS average of all {} points", all.len()),
                    points: curve(&avg),
                    mark: Mark::Line,
                    color: 7,
                });
            }
            let rules = mode_rules(ev);
            let title = format!(
                "Amplitude spectra (Hann, window centred on firing, RMS over {} cycles); dominant {:.0} Hz (peak of the RMS average)",
                base.stats.cycles_averaged,
                ev.dominant_hz
            );
            Chart {
                title: &title,
                x_label: "frequency [Hz]",
                y_label: "amplitude [m/s^2]",
                series,
                rules,
                x_range: Some((0.0, band)),
                y_range: None,
            }
            .draw(root)
        })?;
        files.push(p);
        Ok(files)
    }

    /// `frf.png`: inertance of each cylinder's worst point from the modal model.
    fn frf(&self) -> Result<Vec<PathBuf>, WriteError> {
        let Self {
            out,
            scene,
            piston,
            ev,
            rom,
            ..
        } = *self;
        let band = scene.rom.band_hz;
        let mut files = Vec::new();
        // FRFs of the liner points from the modal model: inertance from the thrust bore line at
        // the skirt centre at firing TDC (where the slap lands) to each cylinder's worst point
        let p = out.join("frf.png");
        let zeta = scene
            .simulation
            .as_ref()
            .map_or(0.02, |sim| sim.transient.damping_ratio);
        let skirt = &piston.skirt.heights;
        let skirt_mid = skirt.iter().sum::<f64>() / skirt.len().max(1) as f64;
        let z_slap = scene.liner_geometry.length - piston.loads(360.0).pin_depth + skirt_mid;
        let freqs: Vec<f64> = (1..=600).map(|k| band * k as f64 / 600.0).collect();
        let frf_series: Vec<Series> = ev
            .cylinders
            .iter()
            .enumerate()
            .filter_map(|(ci, c)| {
                let cr = rom.cylinders.iter().find(|r| r.cylinder == c.cylinder)?;
                let node = (0..cr.thrust_z.len()).min_by(|&a, &b| {
                    (cr.thrust_z[a] - z_slap)
                        .abs()
                        .total_cmp(&(cr.thrust_z[b] - z_slap).abs())
                })?;
                let point = c.worst_point.checked_sub(1)?;
                let a = crate::analysis::frf::inertance(
                    crate::linalg::dense::row(&cr.thrust_modes, node),
                    crate::linalg::dense::row(&cr.point_modes, point),
                    &rom.frequencies_hz,
                    zeta,
                    &freqs,
                );
                Some(Series {
                    name: format!("cylinder {} point {}", c.cylinder, c.worst_point),
                    points: freqs.iter().copied().zip(a).collect(),
                    mark: Mark::Line,
                    color: ci,
                })
            })
            .collect();
        if !frf_series.is_empty() {
            write_png(&p, (1500, 600), |root| {
                let title = format!(
                    "Liner FRF: inertance from the thrust contact at {:.0} mm (skirt centre at firing TDC) to the worst point, modal damping {:.1} %",
                    z_slap * 1e3,
                    zeta * 100.0
                );
                let rules = mode_rules(ev);
                Chart {
                    title: &title,
                    x_label: "frequency [Hz]",
                    y_label: "inertance [m/s^2/N]",
                    series: frf_series,
                    rules,
                    x_range: Some((0.0, band)),
                    y_range: None,
                }
                .draw(root)
            })?;
            files.push(p);
        }
        Ok(files)
    }

    /// `peaks.png`: mean peaks per cylinder and point with their uncertainty and thresholds.
    fn peaks(&self) -> Result<Vec<PathBuf>, WriteError> {
        let Self {
            out,
            base,
            ev,
            simulate,
            ..
        } = *self;
        let t = ev.thresholds;
        let mut files = Vec::new();
        // peaks per cylinder and point with thresholds
        let p = out.join("peaks.png");
        let names: Vec<String> = ev
            .cylinders
            .iter()
            .map(|c| format!("cyl {} ({})", c.cylinder, c.worst.label()))
            .collect();
        let np = ev.cylinders.first().map(|c| c.points.len()).unwrap_or(0);
        let bar_names: Vec<String> = (1..=np).map(|k| format!("point {k}")).collect();
        let groups: Vec<Vec<f64>> = ev
            .cylinders
            .iter()
            .map(|c| c.points.iter().map(|p| p.peak_negative_m_s2).collect())
            .collect();
        // whiskers: the combined standard uncertainty of each mean, sqrt(SE^2 + E^2), SE its
        // standard error (cycles correlated) and E its numerical uncertainty
        let errors: Vec<Vec<f64>> = ev
            .cylinders
            .iter()
            .map(|c| {
                simulate
                    .cylinders
                    .iter()
                    .find(|s| s.cylinder == c.cylinder)
                    .map(|s| s.points.iter().map(|p| p.combined_uncertainty()).collect())
                    .unwrap_or_default()
            })
            .collect();
        let n_avg = base.stats.cycles_averaged;
        let peaks_title = if n_avg > 1 {
            format!("Peak negative liner acceleration per cylinder and point (top to bottom): mean of {n_avg} cycles +- uncertainty (standard error and numerical uncertainty)")
        } else {
            "Peak negative liner acceleration per cylinder and point (top to bottom)".to_string()
        };
        write_png(&p, (1500, 620), |root| {
            bars(
                root,
                &peaks_title,
                "peak negative acceleration [m/s^2]",
                &names,
                &bar_names,
                BarData {
                    groups: &groups,
                    errors: &errors,
                },
                &threshold_rules(&t, 1.0, true),
            )
        })?;
        files.push(p);
        Ok(files)
    }

    /// `modes_risk.png`: mode-shape coefficients of the modes near the response beside risk.
    fn modes_risk(&self) -> Result<Vec<PathBuf>, WriteError> {
        let Self { out, ev, rom, .. } = *self;
        let t = ev.thresholds;
        let np = ev.cylinders.first().map(|c| c.points.len()).unwrap_or(0);
        let bar_names: Vec<String> = (1..=np).map(|k| format!("point {k}")).collect();
        let mut files = Vec::new();
        // mode-shape coefficients beside risk
        let p = out.join("modes_risk.png");
        let cyl_names: Vec<String> = ev
            .cylinders
            .iter()
            .map(|c| format!("cyl {}", c.cylinder))
            .collect();
        let shapes = rom.shapes();
        write_png(&p, (1500, 600), |root| {
            let (a, b) = root.split_horizontally(750);
            // of the modes nearest the dominant response, the one whose coefficients follow the
            // per-cylinder peaks best (highest Pearson r): the picture answers "why do they differ"
            let best = ev.nearest_modes.iter().max_by(|p, q| {
                let (rp, rq) = (p.pearson.unwrap_or(-2.0), q.pearson.unwrap_or(-2.0));
                rp.total_cmp(&rq)
            });
            if let Some(m) = best {
                let j = shapes
                    .iter()
                    .position(|s| s.frequency_hz == m.frequency_hz)
                    .unwrap_or(0);
                let g: Vec<Vec<f64>> = shapes[j]
                    .coefficients
                    .iter()
                    .map(|r| r.iter().map(|v| v.abs()).collect())
                    .collect();
                let title = format!(
                    "|Mode-shape coefficient|, system mode {:.0} Hz (best r of the nearest: {})",
                    m.frequency_hz,
                    m.pearson.map(|v| format!("{v:.2}")).unwrap_or("-".into())
                );
                bars(
                    &a,
                    &title,
                    "normalised radial amplitude",
                    &cyl_names,
                    &bar_names,
                    BarData {
                        groups: &g,
                        errors: &[],
                    },
                    &[],
                )?;
            }
            let g: Vec<Vec<f64>> = ev
                .cylinders
                .iter()
                .map(|c| vec![c.peak_negative_m_s2])
                .collect();
            bars(
                &b,
                "Per-cylinder peak negative acceleration",
                "m/s^2",
                &cyl_names,
                &["largest over the points".to_string()],
                BarData {
                    groups: &g,
                    errors: &[],
                },
                &threshold_rules(&t, 1.0, false)[1..],
            )
        })?;
        files.push(p);
        Ok(files)
    }

    /// `sweep_clearance.png`, `sweep_pin_offset.png`: the report's two sweeps.
    fn sweeps(&self) -> Result<Vec<PathBuf>, WriteError> {
        let Self {
            out,
            ev,
            clearance,
            offset,
            ..
        } = *self;
        let t = ev.thresholds;
        let mut files = Vec::new();
        // sweeps
        for (name, key, pts, unit) in [
            (
                "sweep_clearance.png",
                "cold clearance [um]",
                clearance,
                "clearance",
            ),
            (
                "sweep_pin_offset.png",
                "pin offset [mm] (+ toward thrust)",
                offset,
                "pin offset",
            ),
        ] {
            let p = out.join(name);
            let per_cyl = |f: &dyn Fn(&SweepPoint, usize) -> f64| -> Vec<Series> {
                (0..ev.cylinders.len())
                    .map(|c| Series {
                        name: format!("cylinder {}", ev.cylinders[c].cylinder),
                        points: pts.iter().map(|s| (s.value, f(s, c))).collect(),
                        mark: Mark::LineDots,
                        color: c,
                    })
                    .collect()
            };
            let t1 = format!("Slap force against {unit}");
            let t2 = format!("Piston tilt against {unit}");
            let t3 = format!("Liner acceleration against {unit}");
            write_png(&p, (1800, 560), |root| {
                let areas = root.split_evenly((1, 3));
                Chart {
                    title: &t1,
                    x_label: key,
                    y_label: "peak slap force [kN]",
                    series: per_cyl(&|s, c| s.peak_slap_force_n[c] / 1e3),
                    rules: vec![],
                    x_range: None,
                    y_range: None,
                }
                .draw(&areas[0])?;
                Chart {
                    title: &t2,
                    x_label: key,
                    y_label: "peak |tilt| [mrad]",
                    series: per_cyl(&|s, c| s.peak_tilt_rad[c] * 1e3),
                    rules: vec![],
                    x_range: None,
                    y_range: None,
                }
                .draw(&areas[1])?;
                Chart {
                    title: &t3,
                    x_label: key,
                    y_label: "peak negative acceleration [m/s^2]",
                    series: per_cyl(&|s, c| s.peak_negative_m_s2[c]),
                    rules: threshold_rules(&t, 1.0, false),
                    x_range: None,
                    y_range: None,
                }
                .draw(&areas[2])
            })?;
            files.push(p);
        }
        Ok(files)
    }

    /// `criteria.png`: the cavitation safety factor against the acceleration number.
    fn criteria(&self) -> Result<Vec<PathBuf>, WriteError> {
        let Self { out, ev, .. } = *self;
        let mut files = Vec::new();
        // CSF against Ca
        let p = out.join("criteria.png");
        let pts: Vec<(f64, f64)> = ev
            .cylinders
            .iter()
            .flat_map(|c| c.points.iter().map(|p| (p.ca, p.csf)))
            .collect();
        write_png(&p, (900, 700), |root| {
            Chart {
                title: "Velocity criterion (CSF) against acceleration criterion (Ca)",
                x_label: "Ca = (p_r - p_v)/(rho |a| h)  (< 1: cavitation)",
                y_label: "CSF = Vccv / Vmax  (< 1: cavitation)",
                series: vec![Series {
                    name: "analysis points".into(),
                    points: pts.clone(),
                    mark: Mark::Dots,
                    color: 0,
                }],
                rules: vec![
                    Rule {
                        name: "Ca = 1".into(),
                        value: 1.0,
                        vertical: true,
                        color: 1,
                    },
                    Rule {
                        name: "CSF = 1".into(),
                        value: 1.0,
                        vertical: false,
                        color: 2,
                    },
                ],
                x_range: None,
                y_range: None,
            }
            .draw(root)
        })?;
        files.push(p);
        Ok(files)
    }

    /// `speed_error.png`: wall time against error of the mode cut-off and the step
    /// ([`crate::transient::verify::tradeoff`]).
    fn speed_error(&self) -> Result<Vec<PathBuf>, WriteError> {
        let Self { out, trade, .. } = *self;
        let mut files = Vec::new();
        // speed against error
        let p = out.join("speed_error.png");
        write_png(&p, (1100, 650), |root| {
            let of = |kind: TradeoffKind| -> Vec<(f64, f64)> {
                trade
                    .iter()
                    .filter(|x| x.kind == kind)
                    .map(|x| (x.seconds * 1e3, x.error.max(1e-6)))
                    .collect()
            };
            Chart {
                title: "Fast path: error against wall time (converged reference: step / 64)",
                x_label: "wall time [ms]",
                y_label: "error of peak negative acceleration (relative, largest)",
                series: vec![
                    Series {
                        name: "mode cut-off (band, 1.5x, 2x band), one cylinder's window".into(),
                        points: of(TradeoffKind::ModeCutoff),
                        mark: Mark::LineDots,
                        color: 0,
                    },
                    Series {
                        name: "step with slap sub-steps (4x, 2x, 1x, 0.5x), six firing slaps"
                            .into(),
                        points: of(TradeoffKind::Step),
                        mark: Mark::LineDots,
                        color: 1,
                    },
                    Series {
                        name: "uniform step (4x, 2x, 1x, 0.5x), six firing slaps".into(),
                        points: of(TradeoffKind::UniformStep),
                        mark: Mark::LineDots,
                        color: 2,
                    },
                ],
                rules: vec![Rule {
                    name: "2 %".into(),
                    value: 0.02,
                    vertical: false,
                    color: 6,
                }],
                x_range: None,
                y_range: None,
            }
            .draw(root)
        })?;
        files.push(p);
        Ok(files)
    }
}
