//! Pictures of a study (a sweep's grid or sample): the peaks against each varied key, the
//! risk-class probabilities and the rank sensitivities.

use super::png::{write_png, Chart, Mark, Series};
use crate::analysis::study::{worst_peak, ProbabilityRow, RunLine, Sensitivities};
use crate::files::WriteError;
use std::path::Path;

/// Numeric value of a sweep value (TOML literal), for plotting.
pub fn numeric(v: &str) -> Option<f64> {
    v.parse::<f64>().ok()
}

/// The three-panel figure of one varied key: per cylinder, slap force, peak tilt and peak
/// negative acceleration (largest over the points) against the key; for a grid the other
/// keys held at their first value (lines), for a sample every run (dots).
pub fn draw_key(
    path: &Path,
    keys: &[String],
    lines: &[RunLine],
    sample: bool,
    key: usize,
) -> Result<(), WriteError> {
    let runs: Vec<&RunLine> = lines
        .iter()
        .filter(|r| {
            sample
                || r.values
                    .iter()
                    .enumerate()
                    .all(|(j, v)| j == key || *v == lines[0].values[j])
        })
        .collect();
    let ncyl = runs.first().map(|r| r.cylinders.len()).unwrap_or(0);
    let series = |f: &dyn Fn(&RunLine, usize) -> f64| -> Vec<Series> {
        (0..ncyl)
            .map(|c| Series {
                name: format!("cylinder {}", runs[0].cylinders[c].cylinder),
                points: runs
                    .iter()
                    .filter_map(|r| Some((numeric(&r.values[key])?, f(r, c))))
                    .collect(),
                mark: if sample { Mark::Dots } else { Mark::LineDots },
                color: c,
            })
            .collect()
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
