//! A study's records and pictures (a sweep's grid or sample): each run's evaluated results
//! ([`SweepRun`]), its rows of `sweep.csv`, `probabilities.csv`, and the figures of the peaks
//! against each varied key, the risk-class probabilities and the rank sensitivities.

use super::png::{write_png, Chart, Mark, Series};
use super::records::{CylinderReport, SimulateReport};
use crate::analysis::study::{worst_peak, CylinderLine, ProbabilityRow, RunLine, Sensitivities};
use crate::cavitation::criteria::ThresholdError;
use crate::cavitation::evaluate::{evaluate, CylinderRisk};
use crate::files::WriteError;
use crate::reduce::rom::EngineRom;
use crate::scene::Scene;
use crate::transient::cycle::CycleResult;
use std::path::Path;

/// One run of the sweep: its full results (in `sweep.json`).
#[derive(Clone, Debug, serde::Serialize)]
pub struct SweepRun {
    /// Value of each varied key (same order as the sweep's keys).
    pub values: Vec<String>,
    pub cylinders: Vec<CylinderReport>,
    pub risk: Vec<CylinderRisk>,
    /// Largest |tilt| per cylinder over the cycle \[rad\].
    pub peak_tilt_rad: Vec<f64>,
    pub seconds: f64,
    /// Cycles the peaks are means over.
    pub cycles_averaged: usize,
    /// Per cylinder and point, the change of the mean peak negative acceleration against the
    /// base design (the scene without the design's values; [`Change::of`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub changes: Vec<Vec<Change>>,
}

/// Multiple of the standard error beyond which a change is called lower or higher (two-sided
/// 95 % for a normal difference).
pub const CHANGE_Z: f64 = 2.0;

/// The change of one point's mean peak negative acceleration P against the base design's:
/// delta = P - P_base with the standard error se = sqrt(se_P^2 + se_base^2) of the difference
/// of two means over their cycles (each se respects its cycles' correlation). Both runs start
/// from the same state at rest (paired), but the slap is chaotic and the two cycle sequences
/// decorrelate within a few cycles, so they are combined as independent (conservative if they
/// stay positively correlated). The verdict: `lower` / `higher` when |delta| > [`CHANGE_Z`] se,
/// else `not distinguishable`. The numerical (step) uncertainty of each value is reported
/// beside it and not folded in: both runs have the same step and scheme, so their step errors
/// are alike and largely cancel in the difference.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Change {
    pub delta_m_s2: f64,
    pub se_m_s2: f64,
    pub verdict: &'static str,
}

impl Change {
    /// The change of (mean, se) against the base's (mean, se); `statistics` false when either
    /// mean is of a single cycle (its standard error is unknown, not zero): the verdict is then
    /// `unknown (one cycle)` and the standard error NaN.
    pub fn of(value: (f64, f64), base: (f64, f64), statistics: bool) -> Self {
        let delta = value.0 - base.0;
        if !statistics {
            return Change {
                delta_m_s2: delta,
                se_m_s2: f64::NAN,
                verdict: "unknown (one cycle)",
            };
        }
        let se = value.1.hypot(base.1);
        let verdict = if delta < -CHANGE_Z * se {
            "lower"
        } else if delta > CHANGE_Z * se {
            "higher"
        } else {
            "not distinguishable"
        };
        Change {
            delta_m_s2: delta,
            se_m_s2: se,
            verdict,
        }
    }
}

impl SweepRun {
    /// Sets the changes of every cylinder and point against `base` (a run of the same engine),
    /// each cylinder against the base's cylinder of the same number (a run may model fewer
    /// cylinders, `rom.cylinders` varied: it was compared by position, its cylinder 2 with the
    /// base's cylinder 1); none for a cylinder the base does not model.
    pub fn set_changes(&mut self, base: &SweepRun) {
        self.changes = self
            .cylinders
            .iter()
            .map(|c| {
                let Some(b) = base.cylinders.iter().find(|b| b.cylinder == c.cylinder) else {
                    return Vec::new();
                };
                c.points
                    .iter()
                    .zip(&b.points)
                    .map(|(p, q)| {
                        Change::of(
                            (p.peak_negative_m_s2, p.peak_negative_se_m_s2),
                            (q.peak_negative_m_s2, q.peak_negative_se_m_s2),
                            self.cycles_averaged > 1 && base.cycles_averaged > 1,
                        )
                    })
                    .collect()
            })
            .collect();
    }
}

/// One run of the sweep, evaluated: values, per-cylinder peaks and risks, largest tilt.
pub fn sweep_run(
    sc: &Scene,
    rom: &EngineRom,
    values: &[String],
    res: &CycleResult,
    seconds: f64,
) -> Result<SweepRun, ThresholdError> {
    let ev = evaluate(
        res,
        rom,
        &crate::cavitation::Setup::new(&sc.cavitation)?,
        &sc.engine.firing_order,
        sc.rom.band_hz,
    );
    Ok(SweepRun {
        values: values.to_vec(),
        cylinders: SimulateReport::cylinders_of(res),
        risk: ev.cylinders,
        peak_tilt_rad: res
            .series
            .cylinders
            .iter()
            .map(|c| c.tilt_rad.iter().fold(0.0f64, |m, v| m.max(v.abs())))
            .collect(),
        seconds,
        cycles_averaged: res.stats.cycles_averaged,
        changes: Vec::new(),
    })
}

/// A run's label: `key=value` pairs.
pub fn label(keys: &[String], values: &[String]) -> String {
    keys.iter()
        .zip(values)
        .map(|(k, x)| format!("{k}={x}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// The header of `sweep.csv` for `keys`.
pub fn csv_header(keys: &[String]) -> String {
    let mut s: String = keys.iter().map(|k| format!("{k},")).collect();
    s.push_str("cylinder,point,peak_negative_m_s2,peak_slap_force_n,peak_positive_m_s2,crank_angle_deg,peak_side_force_n,side_force_crank_angle_deg,peak_tilt_mrad,ca,risk,peak_negative_std_m_s2,peak_negative_max_m_s2,peak_negative_se_m_s2,peak_negative_numerical_uncertainty_m_s2,change_m_s2,change_se_m_s2,change\n");
    s
}

/// The line of run `index`: its CSV rows (one per cylinder and point) and plotted values.
pub fn line_of(index: usize, r: &SweepRun) -> RunLine {
    use std::fmt::Write;
    let mut s = String::new();
    for (ci, c) in r.cylinders.iter().enumerate() {
        for (pi, p) in c.points.iter().enumerate() {
            for v in &r.values {
                let _ = write!(s, "{v},");
            }
            let risk = r.risk.get(ci).and_then(|x| x.points.get(pi));
            let change = r.changes.get(ci).and_then(|x| x.get(pi));
            let _ = writeln!(
                s,
                "{},{},{:.3},{:.2},{:.3},{:.3},{:.2},{:.3},{:.5},{:.4},{},{:.3},{:.3},{:.3},{:.3},{},{},{}",
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
                p.peak_negative_se_m_s2,
                p.peak_negative_numerical_uncertainty_m_s2,
                change.map_or(String::new(), |x| format!("{:.3}", x.delta_m_s2)),
                change
                    .filter(|x| x.se_m_s2.is_finite())
                    .map_or(String::new(), |x| format!("{:.3}", x.se_m_s2)),
                change.map_or("", |x| x.verdict),
            );
        }
    }
    RunLine {
        index,
        values: r.values.clone(),
        csv: s,
        cylinders: r
            .cylinders
            .iter()
            .enumerate()
            .map(|(ci, c)| CylinderLine {
                cylinder: c.cylinder,
                slap_force_n: c.peak_slap_force_n,
                tilt_rad: r.peak_tilt_rad.get(ci).copied().unwrap_or(0.0),
                peak_negative_m_s2: c.points.iter().map(|p| p.peak_negative_m_s2).collect(),
                risk: (0..c.points.len())
                    .map(|pi| {
                        r.risk
                            .get(ci)
                            .and_then(|x| x.points.get(pi))
                            .map_or("-", |x| x.risk.label())
                            .to_string()
                    })
                    .collect(),
            })
            .collect(),
    }
}

/// Tidy CSV text: one row per run, cylinder and point.
pub fn csv(keys: &[String], lines: &[RunLine]) -> String {
    let mut s = csv_header(keys);
    for l in lines {
        s.push_str(&l.csv);
    }
    s
}

/// `probabilities.csv`: cylinder,point,class,probability,ci_low,ci_high.
pub fn probabilities_csv(rows: &[ProbabilityRow]) -> String {
    let mut s = String::from("cylinder,point,class,probability,ci_low,ci_high\n");
    for r in rows {
        s.push_str(&format!(
            "{},{},{},{:.4},{:.4},{:.4}\n",
            r.cylinder, r.point, r.class, r.p.probability, r.p.ci_low, r.p.ci_high
        ));
    }
    s
}

/// Numeric value of a sweep value (TOML literal), for plotting.
pub fn numeric(v: &str) -> Option<f64> {
    v.parse::<f64>().ok()
}

/// The runs `draw_key` plots against key `key`, in sets of lines with their labels: a sample's
/// every run in one set; a grid's runs with the other numeric keys at their first value, one
/// set per combination of the other non-numeric keys' values ("piston.lubrication=squeeze"),
/// in the order they first appear.
pub fn key_groups<'a>(
    keys: &[String],
    lines: &'a [RunLine],
    sample: bool,
    key: usize,
) -> Vec<(String, Vec<&'a RunLine>)> {
    let categorical: Vec<usize> = (0..keys.len())
        .filter(|&j| j != key && lines.iter().any(|l| numeric(&l.values[j]).is_none()))
        .collect();
    let label = |r: &RunLine| -> String {
        match sample {
            true => String::new(),
            false => crate::text::joined(
                &categorical
                    .iter()
                    .map(|&j| format!("{}={}", keys[j], r.values[j]))
                    .collect::<Vec<_>>(),
                ", ",
            ),
        }
    };
    let mut groups: Vec<(String, Vec<&RunLine>)> = Vec::new();
    for r in lines {
        let held = r
            .values
            .iter()
            .enumerate()
            .all(|(j, v)| j == key || categorical.contains(&j) || *v == lines[0].values[j]);
        if !(sample || held) {
            continue;
        }
        let l = label(r);
        match groups.iter_mut().find(|g| g.0 == l) {
            Some(g) => g.1.push(r),
            None => groups.push((l, vec![r])),
        }
    }
    groups
}

/// The three-panel figure of one varied key: per cylinder, slap force, peak tilt and peak
/// negative acceleration (largest over the points) against the key; for a grid the other
/// numeric keys held at their first value and each combination of the other non-numeric keys
/// (such as `piston.lubrication`) its own set of lines (solid, dashed, dots only, in turn),
/// for a sample every run (dots).
pub fn draw_key(
    path: &Path,
    keys: &[String],
    lines: &[RunLine],
    sample: bool,
    key: usize,
) -> Result<(), WriteError> {
    let groups = key_groups(keys, lines, sample, key);
    // every cylinder of any run, by number: runs may model different cylinders
    // (`rom.cylinders` varied), so a run's c-th cylinder is found by its number
    let mut cylinders: Vec<usize> = groups
        .iter()
        .flat_map(|g| {
            g.1.iter()
                .flat_map(|r| r.cylinders.iter().map(|c| c.cylinder))
        })
        .collect();
    cylinders.sort_unstable();
    cylinders.dedup();
    let series = |f: &dyn Fn(&RunLine, usize) -> f64| -> Vec<Series> {
        let mut all = Vec::new();
        for (gi, (label, group)) in groups.iter().enumerate() {
            for (color, &cyl) in cylinders.iter().enumerate() {
                let points: Vec<(f64, f64)> = group
                    .iter()
                    .filter_map(|r| {
                        let c = r.cylinders.iter().position(|x| x.cylinder == cyl)?;
                        Some((numeric(&r.values[key])?, f(r, c)))
                    })
                    .collect();
                if points.is_empty() {
                    continue;
                }
                let mut name = format!("cylinder {cyl}");
                if groups.len() > 1 {
                    name = format!("{name}, {label}");
                }
                all.push(Series {
                    name,
                    points,
                    mark: match (sample, gi % 3) {
                        (true, _) | (false, 2) => Mark::Dots,
                        (false, 0) => Mark::LineDots,
                        (false, _) => Mark::DashedDots,
                    },
                    color,
                });
            }
        }
        all
    };
    let k = &keys[key];
    let chart = |title, y_label, series| Chart {
        title,
        x_label: k,
        y_label,
        series,
        rules: vec![],
        x_range: None,
        y_range: None,
    };
    let charts = [
        chart(
            "Dynamic slap force",
            "peak slap force [kN]",
            series(&|r, c| r.cylinders[c].slap_force_n / 1e3),
        ),
        chart(
            "Piston tilt",
            "peak |tilt| [mrad]",
            series(&|r, c| r.cylinders[c].tilt_rad * 1e3),
        ),
        chart(
            "Liner acceleration",
            "peak negative acceleration [m/s^2]",
            series(&|r, c| worst_peak(r, c)),
        ),
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

/// The sample's picture: per cylinder the probability of each risk class at its worst point
/// (the point most often high) with its 95 % interval, and the rank correlation of the
/// cylinder's peak with every varied key (x: key number, named in the title).
pub fn draw_statistics(
    path: &Path,
    rows: &[ProbabilityRow],
    sens: &Sensitivities,
) -> Result<(), WriteError> {
    let mut prob = Vec::new();
    for (ci, class) in ["safe", "transitional", "high"].iter().enumerate() {
        // per cylinder, the point with the largest probability of the high class
        let mut pts = Vec::new();
        for &cyl in &sens.cylinders {
            let of_cyl = |cl: &'static str| {
                rows.iter()
                    .filter(move |r| r.cylinder == cyl && r.class == cl)
            };
            let point = of_cyl("high")
                .max_by(|a, b| a.p.probability.total_cmp(&b.p.probability))
                .map_or(1, |r| r.point);
            if let Some(r) = of_cyl(class).find(|r| r.point == point) {
                // the classes side by side around the cylinder's number
                let x = cyl as f64 + 0.15 * (ci as f64 - 1.0);
                pts.push((x, r.p.probability));
                prob.push(Series {
                    name: String::new(),
                    points: vec![(x, r.p.ci_low), (x, r.p.ci_high)],
                    mark: Mark::Line,
                    color: ci + 3,
                });
            }
        }
        prob.push(Series {
            name: format!("{class} (95 % interval)"),
            points: pts,
            mark: Mark::Dots,
            color: ci + 3,
        });
    }
    let mut sensitivity = Vec::new();
    for (c, &cyl) in sens.cylinders.iter().enumerate() {
        sensitivity.push(Series {
            name: format!("cylinder {cyl}"),
            points: sens
                .spearman
                .iter()
                .enumerate()
                .filter_map(|(k, row)| Some((k as f64 + 1.0 + 0.08 * c as f64 - 0.2, row[c]?)))
                .collect(),
            mark: Mark::Dots,
            color: c,
        });
    }
    let names: Vec<String> = sens
        .keys
        .iter()
        .enumerate()
        // the key's last part: the full names are in the JSON and the CSV header
        .map(|(k, n)| format!("{} {}", k + 1, n.rsplit('.').next().unwrap_or(n)))
        .collect();
    let x_label = format!("varied key: {}", names.join(", "));
    let lo = sens.cylinders.iter().min().copied().unwrap_or(1) as f64 - 0.5;
    let hi = sens.cylinders.iter().max().copied().unwrap_or(1) as f64 + 0.5;
    let charts = [
        Chart {
            title: "Risk class probability at each cylinder's worst point",
            x_label: "cylinder",
            y_label: "probability over the sample",
            series: prob,
            rules: vec![],
            x_range: Some((lo, hi)),
            y_range: Some((0.0, 1.0)),
        },
        Chart {
            title: "Rank correlation of each cylinder's peak with the keys",
            x_label: &x_label,
            y_label: "Spearman rho",
            series: sensitivity,
            rules: vec![],
            x_range: Some((0.5, sens.keys.len() as f64 + 0.5)),
            y_range: Some((-1.0, 1.0)),
        },
    ];
    write_png(path, (1600, 600), |root| {
        let areas = root.split_evenly((1, 2));
        for (a, c) in areas.iter().zip(&charts) {
            c.draw(a)?;
        }
        Ok(())
    })?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::study::CylinderLine;

    fn run(index: usize, values: &[&str]) -> RunLine {
        RunLine {
            index,
            values: values.iter().map(|v| v.to_string()).collect(),
            csv: String::new(),
            cylinders: vec![CylinderLine {
                cylinder: 1,
                slap_force_n: 0.0,
                tilt_rad: 0.0,
                peak_negative_m_s2: vec![0.0],
                risk: vec!["safe".into()],
            }],
        }
    }

    /// Contract: a grid over a string key and a numeric one plots each string value's runs as
    /// its own set of lines against the numeric key (the pin-offset figure of a dry-against-
    /// lubricated sweep showed the dry runs only); another numeric key stays held at its first
    /// value; a sample keeps every run in one set.
    #[test]
    fn contract_a_string_key_splits_the_lines() {
        let keys: Vec<String> = ["piston.lubrication", "piston.pin_offset_mm", "x"]
            .map(String::from)
            .to_vec();
        let mut lines = Vec::new();
        for l in ["dry", "squeeze"] {
            for o in ["-1", "0", "1"] {
                for x in ["1", "2"] {
                    lines.push(run(lines.len(), &[l, o, x]));
                }
            }
        }
        let g = key_groups(&keys, &lines, false, 1);
        let labels: Vec<&str> = g.iter().map(|x| x.0.as_str()).collect();
        assert_eq!(
            labels,
            ["piston.lubrication=dry", "piston.lubrication=squeeze"]
        );
        for (label, runs) in &g {
            let offsets: Vec<&str> = runs.iter().map(|r| r.values[1].as_str()).collect();
            assert_eq!(offsets, ["-1", "0", "1"], "{label}");
            assert!(runs.iter().all(|r| r.values[2] == "1"), "{label}");
        }
        let s = key_groups(&keys, &lines, true, 1);
        assert_eq!(s.len(), 1);
        assert_eq!(s[0].1.len(), lines.len());
    }
}
