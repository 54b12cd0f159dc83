//! `sweep`: what-if runs over the Cartesian product of varied scene keys, in parallel on the
//! cached ROM; a tidy CSV (one row per run, cylinder and analysis point) and PNGs of every
//! varied key (slap force, piston tilt, peak negative acceleration per cylinder).

use super::rom::{get_rom, key_description, CacheOptions, LoadedRom};
use super::simulate::{
    piston_of, run_cycle, settings_of, simulation, CylinderReport, SimulateReport,
};
use crate::cavitation::evaluate::{evaluate, CylinderRisk};
use crate::error::{Error, Result};
use crate::files::{write_all_atomic, Filler, OutputDir};
use crate::report::png::{write_png, Chart, Mark, Series};
use crate::scene::Scene;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// One varied key and its values (as written, TOML literals).
#[derive(Clone, Debug, serde::Serialize)]
pub struct Vary {
    pub key: String,
    pub values: Vec<String>,
}

/// Parses `KEY=V1,V2,...`.
pub fn parse_vary(arg: &str) -> Result<Vary> {
    let bad = |msg: &str| Error::Input(format!("--vary '{arg}': {msg} (expected KEY=V1,V2,...)"));
    let (k, v) = arg.split_once('=').ok_or_else(|| bad("no '='"))?;
    let key = k.trim();
    if key.is_empty() {
        return Err(bad("empty key"));
    }
    let values: Vec<String> = v.split(',').map(|s| s.trim().to_string()).collect();
    if values.iter().any(|s| s.is_empty()) {
        return Err(bad("empty value"));
    }
    Ok(Vary {
        key: key.to_string(),
        values,
    })
}

/// One run of the sweep.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SweepRun {
    /// Value of each varied key (same order as the sweep's keys).
    pub values: Vec<String>,
    pub cylinders: Vec<CylinderReport>,
    pub risk: Vec<CylinderRisk>,
    /// Largest |tilt| per cylinder over the cycle [rad].
    pub peak_tilt_rad: Vec<f64>,
    pub seconds: f64,
}

/// What `sweep` returns.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SweepReport {
    pub scene: String,
    pub keys: Vec<String>,
    pub runs: Vec<SweepRun>,
    /// ROMs used (distinct reduction inputs) and whether each was a cache hit.
    pub roms: Vec<&'static str>,
    pub seconds: f64,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub files: Vec<String>,
}

pub struct SweepRequest {
    pub scene: PathBuf,
    pub sets: Vec<String>,
    pub vary: Vec<String>,
    pub out: Option<PathBuf>,
    pub cache: CacheOptions,
}

/// Runs the sweep.
pub fn run(req: &SweepRequest, started: Instant) -> Result<SweepReport> {
    let vary: Vec<Vary> = req
        .vary
        .iter()
        .map(|v| parse_vary(v))
        .collect::<Result<_>>()?;
    if vary.is_empty() {
        return Err(Error::Input(
            "sweep: give at least one --vary KEY=V1,V2,...".into(),
        ));
    }
    let mut seen = std::collections::HashSet::new();
    if let Some(d) = vary.iter().find(|v| !seen.insert(v.key.clone())) {
        return Err(Error::Input(format!("--vary: key '{}' given twice", d.key)));
    }
    check_size(req, &vary)?;
    let stage = req.out.as_deref().map(OutputDir::create).transpose()?;
    // the Cartesian product, last key fastest
    let mut combos: Vec<Vec<String>> = vec![vec![]];
    for v in &vary {
        combos = combos
            .into_iter()
            .flat_map(|c| {
                v.values.iter().map(move |x| {
                    let mut c = c.clone();
                    c.push(x.clone());
                    c
                })
            })
            .collect();
    }
    // load and validate every scene first: a bad value stops the sweep before any run
    let scenes: Vec<Scene> = combos
        .iter()
        .map(|c| {
            let mut sets = req.sets.clone();
            sets.extend(vary.iter().zip(c).map(|(v, x)| format!("{}={x}", v.key)));
            let sc = super::load_scene(&req.scene, &sets)?;
            simulation(&sc)?;
            Ok(sc)
        })
        .collect::<Result<_>>()?;
    // one ROM per distinct reduction input, loaded or built one after the other
    let mut roms: Vec<LoadedRom> = Vec::new();
    let mut keys: BTreeMap<String, usize> = BTreeMap::new();
    let mut which = Vec::with_capacity(scenes.len());
    for sc in &scenes {
        let k = key_description(sc)?;
        let idx = match keys.get(&k) {
            Some(&i) => i,
            None => {
                roms.push(get_rom(sc, &req.cache)?);
                keys.insert(k, roms.len() - 1);
                roms.len() - 1
            }
        };
        which.push(idx);
    }
    let bar = std::io::stderr().is_terminal().then(|| {
        let b = indicatif::ProgressBar::new(scenes.len() as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{bar:30} {pos}/{len} runs, {elapsed} (eta {eta})",
            )
            .expect("valid template"),
        );
        b
    });
    let runs: Vec<SweepRun> = scenes
        .par_iter()
        .zip(combos.par_iter())
        .zip(which.par_iter())
        .map(|((sc, values), &ri)| {
            let t = Instant::now();
            let sim = simulation(sc)?;
            let piston = piston_of(sc)?;
            let rom = &roms[ri].rom;
            let res = run_cycle(sc, rom, &piston, settings_of(sim, sc.rom.band_hz), None)
                .map_err(|e| Error::Failure(format!("run {}: {e}", label(&vary, values))))?;
            let ev = evaluate(
                &res,
                rom,
                &crate::cavitation::Setup::new(&sc.cavitation)?,
                &sc.engine.firing_order,
                sc.rom.band_hz,
            );
            if let Some(b) = &bar {
                b.inc(1);
            }
            Ok(SweepRun {
                values: values.clone(),
                cylinders: SimulateReport::cylinders_of(&res),
                risk: ev.cylinders,
                peak_tilt_rad: res
                    .series
                    .cylinders
                    .iter()
                    .map(|c| c.tilt_rad.iter().fold(0.0f64, |m, v| m.max(v.abs())))
                    .collect(),
                seconds: t.elapsed().as_secs_f64(),
            })
        })
        .collect::<Result<_>>()?;
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    let mut report = SweepReport {
        scene: req.scene.display().to_string(),
        keys: vary.iter().map(|v| v.key.clone()).collect(),
        runs,
        roms: roms.iter().map(|r| r.cache).collect(),
        seconds: 0.0,
        files: vec![],
    };
    if let Some(stage) = stage {
        let files = write_outputs(stage.path(), &vary, &report)?;
        report.files = files
            .iter()
            .map(|f| stage.final_path(Path::new(f)).display().to_string())
            .collect();
        stage.commit()?;
    }
    report.seconds = started.elapsed().as_secs_f64();
    Ok(report)
}

/// Refuses, before any scene is loaded for each run, a sweep whose runs would take longer
/// than `limits.max_hours` on this machine: runs x the base scene's transient estimate /
/// cores.
fn check_size(req: &SweepRequest, vary: &[Vary]) -> Result<()> {
    let runs = vary
        .iter()
        .try_fold(1usize, |n, v| n.checked_mul(v.values.len()))
        .unwrap_or(usize::MAX);
    let base = super::load_scene(&req.scene, &req.sets)?;
    let Some(one) = crate::scene::budget::transient(&base) else {
        return Ok(());
    };
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as f64;
    let est = crate::scene::budget::Estimate {
        what: "the sweep",
        // runs in parallel, plus each run's scene and results held until the end (~50 kB)
        memory: one.memory * cores + runs as f64 * 50e3,
        seconds: runs as f64 * one.seconds / cores,
        keys: "the --vary lists (fewer values), transient.step_deg or transient.cycles",
        detail: format!("{runs} runs of {}", one.detail),
    };
    crate::scene::budget::Limits::of(&base).check(&base, &est)?;
    Ok(())
}

fn label(vary: &[Vary], values: &[String]) -> String {
    vary.iter()
        .zip(values)
        .map(|(v, x)| format!("{}={x}", v.key))
        .collect::<Vec<_>>()
        .join(" ")
}

/// Tidy CSV text: one row per run, cylinder and point.
pub fn csv(report: &SweepReport) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    for k in &report.keys {
        let _ = write!(s, "{k},");
    }
    let _ = writeln!(
        s,
        "cylinder,point,peak_negative_m_s2,peak_slap_force_n,peak_positive_m_s2,crank_angle_deg,peak_side_force_n,side_force_crank_angle_deg,peak_tilt_mrad,ca,risk,peak_negative_std_m_s2,peak_negative_max_m_s2"
    );
    for r in &report.runs {
        for (ci, c) in r.cylinders.iter().enumerate() {
            for (pi, p) in c.points.iter().enumerate() {
                for v in &r.values {
                    let _ = write!(s, "{v},");
                }
                let risk = r.risk.get(ci).and_then(|x| x.points.get(pi));
                let _ = writeln!(
                    s,
                    "{},{},{:.3},{:.2},{:.3},{:.3},{:.2},{:.3},{:.5},{:.4},{},{:.3},{:.3}",
                    c.cylinder,
                    p.point,
                    p.peak_negative_m_s2,
                    c.peak_slap_force_n,
                    p.peak_positive_m_s2,
                    p.crank_angle_deg,
                    c.peak_side_force_n,
                    c.side_force_crank_angle_deg,
                    r.peak_tilt_rad.get(ci).copied().unwrap_or(0.0) * 1e3,
                    risk.map(|x| x.ca).unwrap_or(f64::NAN),
                    risk.map(|x| x.risk.label()).unwrap_or("-"),
                    p.peak_negative_std_m_s2,
                    p.peak_negative_max_m_s2,
                );
            }
        }
    }
    s
}

/// Numeric value of a sweep value (TOML literal), for plotting.
fn numeric(v: &str) -> Option<f64> {
    v.parse::<f64>().ok()
}

/// The three-panel figure of one varied key: per cylinder, slap force, peak tilt and peak
/// negative acceleration (largest over the points) against the key, the other keys held at
/// their first value.
pub fn draw_key(path: &Path, report: &SweepReport, key: usize) -> Result<()> {
    let runs: Vec<&SweepRun> = report
        .runs
        .iter()
        .filter(|r| {
            r.values
                .iter()
                .enumerate()
                .all(|(j, v)| j == key || *v == report.runs[0].values[j])
        })
        .collect();
    let ncyl = runs.first().map(|r| r.cylinders.len()).unwrap_or(0);
    let series = |f: &dyn Fn(&SweepRun, usize) -> f64| -> Vec<Series> {
        (0..ncyl)
            .map(|c| Series {
                name: format!("cylinder {}", runs[0].cylinders[c].cylinder),
                points: runs
                    .iter()
                    .filter_map(|r| Some((numeric(&r.values[key])?, f(r, c))))
                    .collect(),
                mark: Mark::LineDots,
                color: c,
            })
            .collect()
    };
    let k = &report.keys[key];
    let slap = series(&|r, c| r.cylinders[c].peak_slap_force_n / 1e3);
    let tilt = series(&|r, c| r.peak_tilt_rad[c] * 1e3);
    let acc = series(&|r, c| {
        r.cylinders[c]
            .points
            .iter()
            .fold(0.0f64, |m, p| m.max(p.peak_negative_m_s2))
    });
    let charts = [
        Chart {
            title: "Dynamic slap force",
            x_label: k,
            y_label: "peak slap force [kN]",
            series: slap,
            rules: vec![],
            x_range: None,
            y_range: None,
        },
        Chart {
            title: "Piston tilt",
            x_label: k,
            y_label: "peak |tilt| [mrad]",
            series: tilt,
            rules: vec![],
            x_range: None,
            y_range: None,
        },
        Chart {
            title: "Liner acceleration",
            x_label: k,
            y_label: "peak negative acceleration [m/s^2]",
            series: acc,
            rules: vec![],
            x_range: None,
            y_range: None,
        },
    ];
    write_png(path, (1800, 560), |root| {
        let areas = root.split_evenly((1, 3));
        for (a, c) in areas.iter().zip(&charts) {
            c.draw(a)?;
        }
        Ok(())
    })?;
    Ok(())
}

fn write_outputs(dir: &Path, vary: &[Vary], report: &SweepReport) -> Result<Vec<String>> {
    let csv_text = csv(report);
    let json = serde_json::to_string_pretty(report).expect("serialisable");
    let mut files: Vec<(PathBuf, Filler<'_>)> = vec![
        (
            dir.join("sweep.csv"),
            Box::new(move |w| w.write_all(csv_text.as_bytes())),
        ),
        (
            dir.join("sweep.json"),
            Box::new(move |w| w.write_all(json.as_bytes())),
        ),
    ];
    let mut names: Vec<String> = files.iter().map(|f| f.0.display().to_string()).collect();
    // PNGs first (each atomic), then the tables: a failure leaves no table behind
    let mut pngs = Vec::new();
    for (j, v) in vary.iter().enumerate() {
        if v.values.len() < 2 || v.values.iter().any(|x| numeric(x).is_none()) {
            continue;
        }
        let p = dir.join(format!("sweep_{}.png", v.key.replace('.', "_")));
        draw_key(&p, report, j)?;
        pngs.push(p.display().to_string());
    }
    write_all_atomic(std::mem::take(&mut files))?;
    names.extend(pngs);
    Ok(names)
}

impl SweepReport {
    pub fn to_text(&self) -> String {
        use std::fmt::Write;
        let mut s = format!(
            "{} runs of {} in {:.1} s (ROM: {:?})\n",
            self.runs.len(),
            self.scene,
            self.seconds,
            self.roms
        );
        for r in &self.runs {
            let _ = write!(
                s,
                "  {:<40}",
                self.keys
                    .iter()
                    .zip(&r.values)
                    .map(|(k, v)| format!("{k}={v}"))
                    .collect::<Vec<_>>()
                    .join(" ")
            );
            for c in &r.cylinders {
                let a = c
                    .points
                    .iter()
                    .fold(0.0f64, |m, p| m.max(p.peak_negative_m_s2));
                let _ = write!(
                    s,
                    " c{} {:>5.0}/{:>5.1}kN",
                    c.cylinder,
                    a,
                    c.peak_slap_force_n / 1e3
                );
            }
            let _ = writeln!(s);
        }
        for f in &self.files {
            let _ = writeln!(s, "wrote {f}");
        }
        s
    }
}
