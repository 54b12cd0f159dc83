//! `linercav report`: the design-review report of a scene. One slap transient of the engine,
//! its cavitation verdict and explanation, clearance and pin-offset sweeps, and the
//! speed-against-error curve of the fast path, as PNGs plus `summary.md` and `summary.json`.
//!
//! Figures: `pressure.png` (cylinder pressure, side force), `acceleration.png` (liner
//! acceleration per cylinder around firing, with the thresholds), `spectra.png`, `peaks.png`
//! (per cylinder and point, with the thresholds), `modes_risk.png` (coefficients of the
//! best-correlated of the modes nearest the dominant response beside the per-cylinder peaks), `sweep_clearance.png`,
//! `sweep_pin_offset.png`, `criteria.png` (CSF against Ca), `speed_error.png`, `frf.png`
//! (inertance from the slap location to each cylinder's worst point, from the modal model).

use super::rom::CacheOptions;
use super::simulate::SimulateReport;
use super::sweep::Variants;
use crate::analysis::spectrum::{rms_average, Spectrum};
use crate::cavitation::evaluate::{evaluate, spectra, Evaluation};
use crate::error::Result;
use crate::files::write_all_atomic;
use crate::piston::setup::{piston_of, simulation};
use crate::piston::Piston;
use crate::reduce::rom::EngineRom;
use crate::report::png::{bars, write_png, BarData, Chart, Mark, Rule, Series};
use crate::scene::Scene;
use crate::transient::cycle::CycleResult;
use crate::transient::engine::settings_of;
use crate::transient::verify::{peak_negative, rom_window};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Values of the report's sweeps (the scene's own value is added when missing).
pub const CLEARANCES_UM: [f64; 3] = [40.0, 80.0, 120.0];
pub const PIN_OFFSETS_MM: [f64; 3] = [-1.0, 0.0, 1.0];

/// One point of the speed-against-error curve.
#[derive(Clone, Debug, serde::Serialize)]
pub struct TradeoffPoint {
    pub setting: String,
    pub modes: usize,
    pub step_deg: f64,
    /// Largest relative error of the window's peak negative accelerations against the finest
    /// setting (all modes, smallest step).
    pub error: f64,
    pub seconds: f64,
}

/// What the report holds (summary.json).
#[derive(Clone, Debug, serde::Serialize)]
pub struct Report {
    pub scene: String,
    pub title: String,
    pub speed_rpm: f64,
    /// The coolant layer's normal mass on the liner's wet zone [kg/m^2]; null: dry model.
    pub coolant_layer_kg_m2: Option<f64>,
    pub simulate: SimulateReport,
    pub evaluation: Evaluation,
    pub clearance_sweep: Vec<SweepPoint>,
    pub pin_offset_sweep: Vec<SweepPoint>,
    pub tradeoff: Vec<TradeoffPoint>,
    pub files: Vec<String>,
    pub seconds: f64,
}

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
    /// Per cylinder and point.
    pub points_m_s2: Vec<Vec<f64>>,
}

fn condense(value: f64, r: &CycleResult) -> SweepPoint {
    let cyl = SimulateReport::cylinders_of(r);
    SweepPoint {
        value,
        peak_negative_m_s2: cyl
            .iter()
            .map(|c| {
                c.points
                    .iter()
                    .fold(0.0f64, |m, p| m.max(p.peak_negative_m_s2))
            })
            .collect(),
        peak_slap_force_n: cyl.iter().map(|c| c.peak_slap_force_n).collect(),
        peak_side_force_n: cyl.iter().map(|c| c.peak_side_force_n).collect(),
        side_force_crank_angle_deg: cyl.iter().map(|c| c.side_force_crank_angle_deg).collect(),
        peak_tilt_rad: r
            .series
            .cylinders
            .iter()
            .map(|c| c.tilt_rad.iter().fold(0.0f64, |m, v| m.max(v.abs())))
            .collect(),
        points_m_s2: cyl
            .iter()
            .map(|c| c.points.iter().map(|p| p.peak_negative_m_s2).collect())
            .collect(),
    }
}

/// What a report run varies.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Swept {
    Scene,
    Clearance,
    PinOffset,
}

impl Swept {
    /// The `--set` overrides of a run at `value` (the clearance in um, the pin offset in mm).
    fn sets(self, value: f64) -> Vec<String> {
        match self {
            Swept::Scene => Vec::new(),
            Swept::Clearance => vec![format!("piston.clearance_um={value}")],
            Swept::PinOffset => vec![format!("piston.pin_offset_mm={value}")],
        }
    }
}

/// Speed against error on the reference window: mode cut-off and step, each against the
/// finest setting.
pub fn tradeoff(scene: &Scene, rom: &EngineRom, piston: &Piston) -> Result<Vec<TradeoffPoint>> {
    let sim = simulation(scene)?;
    let settings = settings_of(sim, scene.rom.band_hz);
    let base = settings.step_deg;
    let run = |keep: Option<f64>, step: f64| -> Result<(Vec<f64>, usize, f64)> {
        let rw = rom_window(scene, rom, piston, &settings, keep, Some(step))?;
        let peaks = (0..rw.res.acceleration.len())
            .map(|p| peak_negative(&rw.res, p, rw.dt, rw.band).0)
            .collect();
        Ok((peaks, rw.modes, rw.res.seconds))
    };
    // the converged reference: all modes at a step 64 times finer (the window is one piston
    // from rest, deterministic); the truncated-mode rows at 1/8 of the step
    let (reference, _, _) = run(None, base / 64.0)?;
    let fine = base / 8.0;
    let err = |p: &[f64]| {
        p.iter()
            .zip(&reference)
            .map(|(a, b)| (a - b).abs() / b.abs().max(1e-30))
            .fold(0.0, f64::max)
    };
    let mut out = Vec::new();
    let band = scene.rom.band_hz;
    for f in [band, 1.5 * band, 2.0 * band] {
        let (p, m, s) = run(Some(f), fine)?;
        out.push(TradeoffPoint {
            setting: format!("modes <= {f:.0} Hz, step {fine} deg"),
            modes: m,
            step_deg: fine,
            error: err(&p),
            seconds: s,
        });
    }
    for k in [4.0, 2.0, 1.0, 0.5] {
        let step = base * k;
        let (p, m, s) = run(None, step)?;
        out.push(TradeoffPoint {
            setting: format!("all modes, step {step} deg"),
            modes: m,
            step_deg: step,
            error: err(&p),
            seconds: s,
        });
    }
    Ok(out)
}

/// Writes the report of `scene` into `out`.
pub fn run(scene_path: &Path, sets: &[String], out: &Path, cache: &CacheOptions) -> Result<Report> {
    let started = Instant::now();
    let scene = super::load_scene(scene_path, sets)?;
    let sim = simulation(&scene)?;
    let piston = piston_of(&scene)?;
    // about ten transients (the scene and its two sweeps): refused before any work when beyond
    // the limits, as is an output directory that cannot be written
    if let Some(mut est) = crate::scene::budget::transient(&scene) {
        est.what = "the report's transients";
        est.seconds *= (1 + CLEARANCES_UM.len() + PIN_OFFSETS_MM.len()) as f64 / 2.0;
        crate::scene::budget::Limits::of(&scene).check(&scene, &est)?;
    }
    let stage = crate::files::OutputDir::create(out)?;
    let target = out;
    let out = stage.path();
    let progress = super::progress::Progress::new();
    // the scene itself, then the clearance and pin-offset sweeps (their scene values skipped)
    let cur_c = sim.piston.skirt.clearance * 1e6;
    let cur_o = sim.piston.pin_offset * 1e3;
    let mut jobs: Vec<(Swept, f64)> = vec![(Swept::Scene, 0.0)];
    jobs.extend(
        CLEARANCES_UM
            .iter()
            .filter(|&&c| (c - cur_c).abs() > 1e-9)
            .map(|&c| (Swept::Clearance, c)),
    );
    jobs.extend(
        PIN_OFFSETS_MM
            .iter()
            .filter(|&&o| (o - cur_o).abs() > 1e-9)
            .map(|&o| (Swept::PinOffset, o)),
    );
    let extra: Vec<Vec<String>> = jobs.iter().map(|(k, v)| k.sets(*v)).collect();
    let labels: Vec<String> = extra
        .iter()
        .map(|e| {
            if e.is_empty() {
                scene.path.display().to_string()
            } else {
                e.join(" ")
            }
        })
        .collect();
    progress.phase("engine ROM");
    let variants = Variants::prepare(scene_path, sets, &extra, cache)?;
    progress.phase("transients: the scene, clearance and pin-offset sweeps");
    let results = variants.run(&labels, || {})?;
    let loaded = &variants.roms[variants.rom_of[0]];
    let rom = &loaded.rom;
    let base = &results[0].0;
    let mut clearance: Vec<SweepPoint> = vec![condense(cur_c, base)];
    let mut offset: Vec<SweepPoint> = vec![condense(cur_o, base)];
    for ((kind, v), (r, _)) in jobs.iter().zip(&results).skip(1) {
        match kind {
            Swept::Clearance => clearance.push(condense(*v, r)),
            Swept::PinOffset => offset.push(condense(*v, r)),
            Swept::Scene => {}
        }
    }
    clearance.sort_by(|a, b| a.value.total_cmp(&b.value));
    offset.sort_by(|a, b| a.value.total_cmp(&b.value));
    progress.phase("speed against error (window runs)");
    let trade = tradeoff(&scene, rom, &piston)?;
    let ev = evaluate(
        base,
        rom,
        &crate::cavitation::Setup::new(&scene.cavitation)?,
        &scene.engine.firing_order,
        scene.rom.band_hz,
    );
    let mut simulate = SimulateReport::new(&scene, &piston, base, loaded.cache, 0.0);
    simulate.seconds = started.elapsed().as_secs_f64();
    progress.phase("figures");
    let figs = Figures {
        out,
        scene: &scene,
        piston: &piston,
        base,
        ev: &ev,
        clearance: &clearance,
        offset: &offset,
        trade: &trade,
        rom,
    }
    .draw()?;
    let mut report = Report {
        scene: scene.path.display().to_string(),
        title: scene.title.clone(),
        speed_rpm: scene.engine.speed_rpm,
        coolant_layer_kg_m2: scene.cavitation.layer_mass_per_area,
        simulate,
        evaluation: ev,
        clearance_sweep: clearance,
        pin_offset_sweep: offset,
        tradeoff: trade,
        files: figs
            .iter()
            .map(|p| stage.final_path(p).display().to_string())
            .collect(),
        seconds: 0.0,
    };
    report.seconds = started.elapsed().as_secs_f64();
    let md = markdown(&report, scene_path, target);
    let json = serde_json::to_string_pretty(&report).expect("serialisable");
    write_all_atomic(vec![
        (
            out.join("summary.json"),
            Box::new(move |w: &mut dyn std::io::Write| w.write_all(json.as_bytes())),
        ),
        (
            out.join("summary.md"),
            Box::new(move |w: &mut dyn std::io::Write| w.write_all(md.as_bytes())),
        ),
    ])?;
    stage.commit()?;
    Ok(report)
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
struct Figures<'a> {
    out: &'a Path,
    scene: &'a Scene,
    piston: &'a Piston,
    base: &'a CycleResult,
    ev: &'a Evaluation,
    clearance: &'a [SweepPoint],
    offset: &'a [SweepPoint],
    trade: &'a [crate::app::summary::TradeoffPoint],
    rom: &'a EngineRom,
}

impl Figures<'_> {
    /// Draws every figure; returns the files written.
    fn draw(&self) -> Result<Vec<PathBuf>> {
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
    fn pressure(&self) -> Result<Vec<PathBuf>> {
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
    fn acceleration(&self) -> Result<Vec<PathBuf>> {
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
                    rules: vec![
                        Rule {
                            name: "-onset".into(),
                            value: -t.onset_m_s2,
                            vertical: false,
                            color: 4,
                        },
                        Rule {
                            name: "-high risk".into(),
                            value: -t.high_risk_m_s2,
                            vertical: false,
                            color: 1,
                        },
                    ],
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

    /// `spectra.png`: the spectrum of each cylinder's worst point.
    fn spectra(&self) -> Result<Vec<PathBuf>> {
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
                "Amplitude spectra (Hann, window centred on firing); dominant {:.0} Hz (peak of the RMS average)",
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
    fn frf(&self) -> Result<Vec<PathBuf>> {
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
    fn peaks(&self) -> Result<Vec<PathBuf>> {
        let Self { out, base, ev, .. } = *self;
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
        // standard error (cycles correlated) and E its estimated step error
        let errors: Vec<Vec<f64>> = ev
            .cylinders
            .iter()
            .map(|c| {
                let step = base.step_error.iter().find(|e| e.cylinder == c.cylinder);
                base.peaks
                    .iter()
                    .find(|b| b.cylinder == c.cylinder)
                    .map(|b| {
                        b.peak_negative
                            .iter()
                            .enumerate()
                            .map(|(k, p)| {
                                let e = step.map_or(0.0, |s| s.relative(k) * p.value);
                                p.se.hypot(e)
                            })
                            .collect()
                    })
                    .unwrap_or_default()
            })
            .collect();
        let n_avg = base.stats.cycles_averaged;
        let peaks_title = if n_avg > 1 {
            format!("Peak negative liner acceleration per cylinder and point (top to bottom): mean of {n_avg} cycles +- uncertainty (standard error and step error)")
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
                &[
                    Rule {
                        name: format!("onset {:.0}", t.onset_m_s2),
                        value: t.onset_m_s2,
                        vertical: false,
                        color: 4,
                    },
                    Rule {
                        name: format!("high risk {:.0}", t.high_risk_m_s2),
                        value: t.high_risk_m_s2,
                        vertical: false,
                        color: 1,
                    },
                ],
            )
        })?;
        files.push(p);
        Ok(files)
    }

    /// `modes_risk.png`: mode-shape coefficients of the modes near the response beside risk.
    fn modes_risk(&self) -> Result<Vec<PathBuf>> {
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
                &[Rule {
                    name: "high risk".into(),
                    value: t.high_risk_m_s2,
                    vertical: false,
                    color: 1,
                }],
            )
        })?;
        files.push(p);
        Ok(files)
    }

    /// `sweep_clearance.png`, `sweep_pin_offset.png`: the report's two sweeps.
    fn sweeps(&self) -> Result<Vec<PathBuf>> {
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
                    rules: vec![
                        Rule {
                            name: "onset".into(),
                            value: t.onset_m_s2,
                            vertical: false,
                            color: 4,
                        },
                        Rule {
                            name: "high risk".into(),
                            value: t.high_risk_m_s2,
                            vertical: false,
                            color: 7,
                        },
                    ],
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
    fn criteria(&self) -> Result<Vec<PathBuf>> {
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

    /// `speed_error.png`: wall time against error on the reference window.
    fn speed_error(&self) -> Result<Vec<PathBuf>> {
        let Self { out, trade, .. } = *self;
        let mut files = Vec::new();
        // speed against error
        let p = out.join("speed_error.png");
        write_png(&p, (1100, 650), |root| {
            let modes: Vec<(f64, f64)> = trade
                .iter()
                .filter(|x| x.setting.starts_with("modes"))
                .map(|x| (x.seconds * 1e3, x.error.max(1e-6)))
                .collect();
            let steps: Vec<(f64, f64)> = trade
                .iter()
                .filter(|x| x.setting.starts_with("all"))
                .map(|x| (x.seconds * 1e3, x.error.max(1e-6)))
                .collect();
            Chart {
                title: "Fast path: error against wall time (window 330-420 deg, one cylinder)",
                x_label: "wall time of the window [ms]",
                y_label: "error of peak negative acceleration (relative)",
                series: vec![
                    Series {
                        name: "mode cut-off (band, 1.5x, 2x band)".into(),
                        points: modes,
                        mark: Mark::LineDots,
                        color: 0,
                    },
                    Series {
                        name: "step (4x, 2x, 1x, 0.5x the scene's)".into(),
                        points: steps,
                        mark: Mark::LineDots,
                        color: 1,
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

/// Which neighbours of the cylinder ranking are separated beyond the uncertainty: each
/// cylinder's largest mean peak m carries u = sqrt(SE^2 + E^2), SE its standard error (cycles
/// correlated) and E its estimated step error; neighbours m1 > m2 count as separated when
/// m1 - m2 > 2 sqrt(u1^2 + u2^2), and as tied otherwise.
fn ranking_resolution(r: &Report) -> String {
    let worst = |cyl: usize| -> Option<(f64, f64)> {
        let c = r.simulate.cylinders.iter().find(|c| c.cylinder == cyl)?;
        c.points
            .iter()
            .max_by(|a, b| a.peak_negative_m_s2.total_cmp(&b.peak_negative_m_s2))
            .map(|p| {
                let u = p
                    .peak_negative_se_m_s2
                    .hypot(p.peak_negative_step_error_m_s2);
                (p.peak_negative_m_s2, u)
            })
    };
    let pairs: Vec<String> = r
        .evaluation
        .ranking
        .windows(2)
        .filter_map(|w| {
            let ((m1, u1), (m2, u2)) = (worst(w[0])?, worst(w[1])?);
            let separated = m1 - m2 > 2.0 * u1.hypot(u2);
            Some(format!(
                "{} {} {}",
                w[0],
                if separated { ">" } else { "~" },
                w[1]
            ))
        })
        .collect();
    format!(
        "Ranking with its uncertainty (each cylinder's worst point; > separated by more than two combined standard uncertainties, standard error and step error; ~ tied): {}.",
        pairs.join(", ")
    )
}

fn markdown(r: &Report, scene: &Path, out: &Path) -> String {
    use std::fmt::Write;
    let ev = &r.evaluation;
    let t = &ev.thresholds;
    let coolant = match r.coolant_layer_kg_m2 {
        None => "coolant around the liner not modelled (dry, as the study's model)".to_string(),
        Some(mu) => format!("coolant layer on the liner's wet zone: {mu:.2} kg/m^2"),
    };
    let mut s = format!("# linercav report: {}\n\n{} at {:.0} rpm; peak cylinder pressure {:.1} bar at {:.1} deg; hot clearance {:.1} um; {coolant}.\n\n", r.title, r.scene, r.speed_rpm, r.simulate.peak_pressure_bar, r.simulate.peak_pressure_deg, r.simulate.hot_clearance_um);
    let _ = writeln!(s, "## Verdict\n");
    let _ = writeln!(s, "Acceleration criterion ({}): onset {:.0} m/s^2, high risk {:.0} m/s^2 (k_p {:.1} Pa per m/s^2). Cylinders from the highest to the lowest peak negative acceleration: {:?}. The most active point along the liner: {} (of {}, top to bottom).\n", ev.threshold_source, t.onset_m_s2, t.high_risk_m_s2, t.k_p_pa_per_m_s2, ev.ranking, ev.most_active_point, ev.cylinders.first().map(|c| c.points.len()).unwrap_or(0));
    let n_avg = r.simulate.stats.cycles_averaged;
    if n_avg > 1 {
        let st = &r.simulate.stats;
        let _ = writeln!(s, "Peaks are means over the last {n_avg} of {} cycles (slap on the ringing liner is not periodic), given as mean ± standard error (the cycles' correlation counted: autocorrelation time {:.2} cycles). Estimated step error of the mean peak: {:.1} % (tolerance {:.1} %, step {:.4} deg). Risk and ranking use the means. {}\n", st.cycles_run, st.autocorrelation_cycles, 100.0 * st.step_error_estimate, 100.0 * r.simulate.tolerance, st.dt_s * r.speed_rpm * 6.0, ranking_resolution(r));
    }
    let _ = writeln!(s, "| cylinder | risk | peak negative per point [m/s^2] | Ca per point | CSF per point | slap force [kN] | side force [kN] at [deg] |\n|---|---|---|---|---|---|---|");
    for (c, cr) in ev.cylinders.iter().zip(&r.simulate.cylinders) {
        let f = |v: Vec<String>| v.join(" / ");
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {:.2} | {:.1} at {:.1} |",
            c.cylinder,
            c.worst.label(),
            f(c.points
                .iter()
                .zip(&cr.points)
                .map(|(p, q)| if n_avg > 1 {
                    format!(
                        "{:.0} ± {:.0}",
                        p.peak_negative_m_s2, q.peak_negative_se_m_s2
                    )
                } else {
                    format!("{:.0}", p.peak_negative_m_s2)
                })
                .collect()),
            f(c.points.iter().map(|p| format!("{:.2}", p.ca)).collect()),
            f(c.points.iter().map(|p| format!("{:.2}", p.csf)).collect()),
            cr.peak_slap_force_n / 1e3,
            cr.peak_side_force_n / 1e3,
            cr.side_force_crank_angle_deg
        );
    }
    let _ = writeln!(s, "\n## Why the cylinders differ\n\nDominant response {:.0} Hz. Nearest system modes, with each cylinder's largest normalised radial coefficient at its analysis points and the correlation of those with the per-cylinder peak:\n", ev.dominant_hz);
    let _ = writeln!(s, "| mode [Hz] | coefficients (cylinders {:?}) | Pearson r | Spearman rho |\n|---|---|---|---|", ev.cylinders.iter().map(|c| c.cylinder).collect::<Vec<_>>());
    for m in &ev.nearest_modes {
        let _ = writeln!(
            s,
            "| {:.0} | {} | {} | {} |",
            m.frequency_hz,
            m.cylinder_coefficients
                .iter()
                .map(|v| format!("{v:.2}"))
                .collect::<Vec<_>>()
                .join(", "),
            m.pearson.map(|v| format!("{v:.2}")).unwrap_or("-".into()),
            m.spearman.map(|v| format!("{v:.2}")).unwrap_or("-".into())
        );
    }
    let _ = writeln!(s, "\n## What-if\n\n| clearance [um] | largest peak negative [m/s^2] | largest slap force [kN] |\n|---|---|---|");
    for p in &r.clearance_sweep {
        let _ = writeln!(
            s,
            "| {:.0} | {:.0} | {:.2} |",
            p.value,
            p.peak_negative_m_s2.iter().fold(0.0f64, |m, v| m.max(*v)),
            p.peak_slap_force_n.iter().fold(0.0f64, |m, v| m.max(*v)) / 1e3
        );
    }
    let _ = writeln!(s, "\n| pin offset [mm] | largest peak negative [m/s^2] | largest slap force [kN] | side-force peak [kN] at [deg] |\n|---|---|---|---|");
    for p in &r.pin_offset_sweep {
        let _ = writeln!(
            s,
            "| {:+.1} | {:.0} | {:.2} | {:.1} at {:.1} |",
            p.value,
            p.peak_negative_m_s2.iter().fold(0.0f64, |m, v| m.max(*v)),
            p.peak_slap_force_n.iter().fold(0.0f64, |m, v| m.max(*v)) / 1e3,
            p.peak_side_force_n.first().copied().unwrap_or(0.0) / 1e3,
            p.side_force_crank_angle_deg.first().copied().unwrap_or(0.0)
        );
    }
    let _ = writeln!(s, "\n## Speed against error (fast path, window 330-420 deg)\n\n| setting | modes | error | wall time [ms] |\n|---|---|---|---|");
    for x in &r.tradeoff {
        let _ = writeln!(
            s,
            "| {} | {} | {:.2e} | {:.1} |",
            x.setting,
            x.modes,
            x.error,
            x.seconds * 1e3
        );
    }
    let _ = writeln!(s, "\n## Figures\n");
    for f in &r.files {
        let name = Path::new(f)
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let _ = writeln!(s, "![{name}]({name})");
    }
    let _ = writeln!(s, "\nReproduce: `linercav report {} --out {}` (solver: {} steps, {} Newton iterations, {} rejected, energy balance {:.1e}, cycle change {:.1e}).", scene.display(), out.display(), r.simulate.stats.steps, r.simulate.stats.newton_iterations, r.simulate.stats.rejected_steps, r.simulate.stats.energy_error, r.simulate.stats.cycle_change);
    s
}

impl Report {
    pub fn to_text(&self) -> String {
        let mut s = self.evaluation.to_text();
        s += &format!(
            "report written: {} files in {:.1} s\n",
            self.files.len() + 2,
            self.seconds
        );
        s
    }
}
