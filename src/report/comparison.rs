//! The report's comparison of two skirt models (`report.compare_lubrication`): the scene's run
//! and its what-if sweeps repeated with another skirt (dry against an oil film) on the same
//! ROM and settings, as `skirt_comparison` in summary.json, a section of summary.md and
//! `skirt_comparison.png`.

use super::figures::SweepPoint;
use super::png::{write_png, Chart, Mark, Series};
use super::study::Change;
use crate::cavitation::evaluate::Evaluation;
use crate::files::WriteError;
use crate::scene::spec::Lubrication;
use crate::transient::cycle::CycleResult;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// One cylinder under both skirt models: `[scene's model, other model]` each, means and
/// standard errors over the averaged cycles.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CylinderPair {
    pub cylinder: usize,
    pub risk: [&'static str; 2],
    /// The worst point's (largest mean) peak negative acceleration, and which point it is.
    pub worst_point: [usize; 2],
    pub worst_m_s2: [f64; 2],
    pub worst_se_m_s2: [f64; 2],
    pub slap_force_n: [f64; 2],
    pub slap_force_se_n: [f64; 2],
    /// The other model's worst point against the scene's ([`Change::of`]).
    pub change: Change,
}

/// The comparison as summary.json holds it.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SkirtComparison {
    /// `[scene's model, other model]`.
    pub models: [Lubrication; 2],
    pub cylinders: Vec<CylinderPair>,
    /// Each run's estimated step error of the mean peaks (the firing slaps at half the step).
    pub step_error_estimate: [f64; 2],
    /// The cycles each run's means are over (standard errors need two or more).
    pub cycles_averaged: [usize; 2],
    /// The sweeps' values run with the other model, in the scene's sweeps' order; `change`
    /// of each: its engine-wide largest peak against the scene model's at the same value.
    pub clearance_sweep: Vec<SweepPoint>,
    pub pin_offset_sweep: Vec<SweepPoint>,
}

/// The worst point of cylinder row `c` of a run (its evaluation's): (1-based point, mean, se).
fn worst_point(r: &CycleResult, ev: &Evaluation, c: usize) -> (usize, f64, f64) {
    let cr = &ev.cylinders[c];
    let se = cr
        .worst_point
        .checked_sub(1)
        .and_then(|j| r.peak_negative.get((c, j)))
        .map_or(0.0, |p| p.se);
    (cr.worst_point, cr.peak_negative_m_s2, se)
}

/// b / a, or None when it is not a finite number (a cylinder without a slap has force 0).
fn ratio(b: f64, a: f64) -> Option<f64> {
    Some(b / a).filter(|x| x.is_finite())
}

/// A ratio with two decimals, or "-" without one.
fn ratio_text(b: f64, a: f64) -> String {
    ratio(b, a).map_or("-".into(), |x| format!("{x:.2}"))
}

impl SkirtComparison {
    /// The comparison of `runs[0]` (the scene's model, its evaluation `evs[0]`) with
    /// `runs[1]` (the other model); `sweeps`: the other model's clearance and pin-offset
    /// points, their changes set against the scene model's points at the same values.
    pub fn new(
        models: [Lubrication; 2],
        runs: [&CycleResult; 2],
        evs: [&Evaluation; 2],
        sweeps: (Vec<SweepPoint>, Vec<SweepPoint>),
    ) -> Self {
        let statistics = runs.iter().all(|r| r.stats.cycles_averaged > 1);
        let cylinders = (0..evs[0].cylinders.len())
            .map(|c| {
                let w = [
                    worst_point(runs[0], evs[0], c),
                    worst_point(runs[1], evs[1], c),
                ];
                let slap = runs.map(|r| &r.peaks[c].slap_force);
                CylinderPair {
                    cylinder: evs[0].cylinders[c].cylinder,
                    risk: evs.map(|e| e.cylinders[c].worst.label()),
                    worst_point: w.map(|x| x.0),
                    worst_m_s2: w.map(|x| x.1),
                    worst_se_m_s2: w.map(|x| x.2),
                    slap_force_n: slap.map(|s| s.value),
                    slap_force_se_n: slap.map(|s| s.se),
                    change: Change::of((w[1].1, w[1].2), (w[0].1, w[0].2), statistics),
                }
            })
            .collect();
        SkirtComparison {
            models,
            cylinders,
            step_error_estimate: runs.map(|r| r.stats.step_error_estimate),
            cycles_averaged: runs.map(|r| r.stats.cycles_averaged),
            clearance_sweep: sweeps.0,
            pin_offset_sweep: sweeps.1,
        }
    }

    /// The section "Skirt models compared" of summary.md; `scene_sweeps`: the scene model's
    /// clearance and pin-offset points.
    pub fn markdown(&self, scene_sweeps: (&[SweepPoint], &[SweepPoint])) -> String {
        let [a, b] = self.models.map(|m| m.name());
        let mut s = String::new();
        let _ = writeln!(s, "\n## Skirt models compared\n\nThe scene's skirt ({a}) against {b} (`report.compare_lubrication`): the same ROM, settings and operating point, the sweeps at the same values; `skirt_comparison.png`. Means ± standard errors over the averaged cycles; change = {b} - {a} of the worst point with the standard error of the difference (lower / higher beyond twice it). Estimated step error of the mean peaks, each from its firing slaps re-run at half the step: {:.1} % ({a}), {:.1} % ({b}) (for an oil film this estimate has come out below the error measured against finer steps: docs/validation.md).\n\n| cylinder | risk {a} / {b} | worst point {a} [m/s^2] | worst point {b} [m/s^2] | change [m/s^2] | ratio | slap force {a} [kN] | slap force {b} [kN] | ratio |\n|---|---|---|---|---|---|---|---|---|", 100.0 * self.step_error_estimate[0], 100.0 * self.step_error_estimate[1]);
        // a mean with its standard error, or alone when it is of one cycle
        let stats = self.cycles_averaged.iter().all(|&n| n > 1);
        let pm = |v: f64, se: f64, scale: f64, d: usize| match stats {
            true => format!("{:.d$} ± {:.d$}", v / scale, se / scale),
            false => format!("{:.d$}", v / scale),
        };
        for c in &self.cylinders {
            let _ = writeln!(
                s,
                "| {} | {} / {} | {} (point {}) | {} (point {}) | {} | {} | {} | {} | {} |",
                c.cylinder,
                c.risk[0],
                c.risk[1],
                pm(c.worst_m_s2[0], c.worst_se_m_s2[0], 1.0, 0),
                c.worst_point[0],
                pm(c.worst_m_s2[1], c.worst_se_m_s2[1], 1.0, 0),
                c.worst_point[1],
                change_words(&c.change),
                ratio_text(c.worst_m_s2[1], c.worst_m_s2[0]),
                pm(c.slap_force_n[0], c.slap_force_se_n[0], 1e3, 2),
                pm(c.slap_force_n[1], c.slap_force_se_n[1], 1e3, 2),
                ratio_text(c.slap_force_n[1], c.slap_force_n[0]),
            );
        }
        for (key, digits, own, other) in [
            ("clearance [um]", 1, scene_sweeps.0, &self.clearance_sweep),
            ("pin offset [mm]", 3, scene_sweeps.1, &self.pin_offset_sweep),
        ] {
            let _ = writeln!(s, "\n| {key} | largest peak negative {a} [m/s^2] | {b} [m/s^2] | change [m/s^2] | ratio | largest slap force {a} / {b} [kN] |\n|---|---|---|---|---|---|");
            for (p, q) in own.iter().zip(other) {
                let _ = writeln!(
                    s,
                    "| {:.digits$} | {} | {} | {} | {} | {:.2} / {:.2} |",
                    p.value,
                    pm(p.largest_m_s2, p.largest_se_m_s2, 1.0, 0),
                    pm(q.largest_m_s2, q.largest_se_m_s2, 1.0, 0),
                    q.change.as_ref().map_or("-".into(), change_words),
                    ratio_text(q.largest_m_s2, p.largest_m_s2),
                    largest_slap(p) / 1e3,
                    largest_slap(q) / 1e3,
                );
            }
        }
        s
    }

    /// `skirt_comparison.png` in `out`: the engine's largest mean slap force and peak negative
    /// acceleration against clearance and pin offset, one series per skirt model.
    pub fn draw(
        &self,
        out: &Path,
        scene_sweeps: (&[SweepPoint], &[SweepPoint]),
    ) -> Result<PathBuf, WriteError> {
        let p = out.join("skirt_comparison.png");
        let names = self.models.map(|m| m.name());
        let panels = [
            (
                "clearance",
                "cold clearance [um]",
                scene_sweeps.0,
                &self.clearance_sweep,
            ),
            (
                "pin offset",
                "pin offset [mm] (+ toward thrust)",
                scene_sweeps.1,
                &self.pin_offset_sweep,
            ),
        ];
        let series = |pts: [&[SweepPoint]; 2], f: &dyn Fn(&SweepPoint) -> f64| -> Vec<Series> {
            (0..2)
                .map(|m| Series {
                    name: format!("skirt {}", names[m]),
                    points: pts[m].iter().map(|q| (q.value, f(q))).collect(),
                    mark: Mark::LineDots,
                    color: m,
                })
                .collect()
        };
        write_png(&p, (1200, 900), |root| {
            let areas = root.split_evenly((2, 2));
            for (i, (what, key, own, other)) in panels.iter().enumerate() {
                let pts = [*own, other.as_slice()];
                let titles = [
                    format!("Largest slap force against {what}"),
                    format!("Largest peak negative acceleration against {what}"),
                ];
                Chart {
                    title: &titles[0],
                    x_label: key,
                    y_label: "slap force [kN]",
                    series: series(pts, &|q| largest_slap(q) / 1e3),
                    rules: vec![],
                    x_range: None,
                    y_range: None,
                }
                .draw(&areas[i])?;
                Chart {
                    title: &titles[1],
                    x_label: key,
                    y_label: "peak negative acceleration [m/s^2]",
                    series: series(pts, &|q| q.largest_m_s2),
                    rules: vec![],
                    x_range: None,
                    y_range: None,
                }
                .draw(&areas[2 + i])?;
            }
            Ok(())
        })?;
        Ok(p)
    }
}

/// The largest mean slap force over the cylinders of a sweep point \[N\].
fn largest_slap(p: &SweepPoint) -> f64 {
    p.peak_slap_force_n.iter().fold(0.0f64, |m, v| m.max(*v))
}

/// "-123 ± 20 (lower)", or without the standard error when it is unknown.
pub(crate) fn change_words(c: &Change) -> String {
    match c.se_m_s2.is_finite() {
        true => format!("{:+.0} ± {:.0} ({})", c.delta_m_s2, c.se_m_s2, c.verdict),
        false => format!("{:+.0} ({})", c.delta_m_s2, c.verdict),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Contract: with cycle statistics the table gives means ± standard errors and the change's
    /// verdict; a cylinder without a slap (force 0) gets no ratio ("-", not inf or NaN).
    #[test]
    fn contract_the_comparison_table_states_uncertainty_and_no_infinite_ratio() {
        let pair = CylinderPair {
            cylinder: 3,
            risk: ["high", "transitional"],
            worst_point: [2, 2],
            worst_m_s2: [1500.0, 900.0],
            worst_se_m_s2: [40.0, 30.0],
            slap_force_n: [0.0, 2500.0],
            slap_force_se_n: [0.0, 60.0],
            change: Change::of((900.0, 30.0), (1500.0, 40.0), true),
        };
        let c = SkirtComparison {
            models: [Lubrication::Dry, Lubrication::Squeeze],
            cylinders: vec![pair],
            step_error_estimate: [0.01, 0.02],
            cycles_averaged: [20, 20],
            clearance_sweep: vec![],
            pin_offset_sweep: vec![],
        };
        let md = c.markdown((&[], &[]));
        let row = md.lines().find(|l| l.starts_with("| 3 |")).unwrap();
        assert!(row.contains("1500 ± 40 (point 2)"), "{row}");
        assert!(row.contains("-600 ± 50 (lower)"), "{row}");
        assert!(row.contains("| 0.60 |"), "{row}");
        assert!(row.ends_with("| 2.50 ± 0.06 | - |"), "{row}");
        assert!(!md.contains("inf") && !md.contains("NaN"), "{md}");
    }
}
