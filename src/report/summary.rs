//! The design-review report's record (`summary.json`) and its text (`summary.md`): the verdict
//! with the ranking and its uncertainty, why the cylinders differ, the what-if sweeps, the
//! speed against error of the fast path, the figures' list.

use crate::analysis::ranking::DecidedRanking;
use crate::analysis::refine::Maximum;
use crate::cavitation::evaluate::Evaluation;
use crate::report::figures::{SweepPoint, TradeoffPoint};
use crate::report::records::SimulateReport;
use std::collections::BTreeMap;
use std::path::Path;

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
    /// The scene and its sweeps under another skirt model (`report.compare_lubrication`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub skirt_comparison: Option<crate::report::comparison::SkirtComparison>,
    /// Where each sweep's largest engine-wide mean slap force (`peak_slap_force_n`) and peak
    /// negative acceleration (`peak_negative_m_s2`) lie: the run with the largest value, its
    /// mean and standard error, `at` +- `uncertainty` (half the larger spacing to the
    /// neighbouring runs).
    pub clearance_maximum: BTreeMap<&'static str, Maximum>,
    pub pin_offset_maximum: BTreeMap<&'static str, Maximum>,
    /// The ranges the sweeps' runs are placed in (the scene's own run, listed in the sweep,
    /// may lie outside and is then not among the runs the maxima are taken over).
    pub clearance_range_um: [f64; 2],
    pub pin_offset_range_mm: [f64; 2],
    pub tradeoff: Vec<TradeoffPoint>,
    /// The decided ranking: each cylinder's worst point from pooled realisations of the run
    /// and its half-step check, every neighbour pair separated, tied within the resolution or
    /// undecided, and where it stopped ([`DecidedRanking`]).
    pub ranking: DecidedRanking,
    /// Per cylinder, where the liner map's largest mean peak lies (`liner_maps.png`,
    /// `liner_maps.vtu`); empty when the liner mesh has no `coolant_wetted` set.
    pub liner_maps: Vec<crate::report::maps::MapSummary>,
    pub files: Vec<String>,
    pub seconds: f64,
}

/// The whole-run step check as a sentence, which covers that shift (empty without it).
fn step_check_sentence(simulate: &SimulateReport) -> String {
    let text = simulate.step_check_text();
    match text.strip_prefix("whole-run step check") {
        Some(rest) => format!("Whole-run step check{rest}."),
        None => "The whole-run step check was not run (`simulate --check-step`).".to_string(),
    }
}

/// The decided ranking as a sentence.
fn ranking_sentence(r: &Report) -> String {
    let d = &r.ranking;
    format!(
        "Decided ranking (each cylinder's worst point at half the step, pooled over {} realisation(s) of {} cycles; > separated, = tied within {:.0} m/s^2 = {:.0} % of the mean, ? undecided, at two combined standard uncertainties, the cycles' scatter and the step error from the whole-run check): {}. Where it stopped: {}.",
        d.realisations,
        d.cycles_averaged / d.realisations.max(1),
        d.resolution_m_s2,
        100.0 * d.resolution_fraction,
        d.pairs_text(),
        d.stopped
    )
}

/// Each cylinder's worst point and the slap event its peak follows (`peak_negative_event`),
/// with the event's means and standard errors, as a markdown section (empty without events).
fn slap_section(r: &Report) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let rows: Vec<String> = r
        .simulate
        .cylinders
        .iter()
        .filter_map(|c| {
            let w = c.worst_point()?;
            let e = c.slap_events.get(w.peak_negative_event?)?;
            Some(format!(
                "| {} | {} | {} | {:.1} | {:.2} ± {:.2} | {:.3} ± {:.3} | {:.1} ± {:.1} | {} of {} |",
                c.cylinder,
                w.point,
                e.side,
                e.crank_angle_deg,
                e.force_n.value / 1e3,
                e.force_n.se / 1e3,
                e.impact_velocity_m_s.value,
                e.impact_velocity_m_s.se,
                e.impact_energy_j.value * 1e3,
                e.impact_energy_j.se * 1e3,
                w.event_cycles,
                r.simulate.stats.cycles_averaged,
            ))
        })
        .collect();
    if rows.is_empty() {
        return s;
    }
    let _ = writeln!(s, "\n## The slaps behind the peaks\n\nEach cylinder's worst point and the slap event its peak negative acceleration follows (the event whose onset precedes the peak in most averaged cycles, and in how many), with the event's means ± standard errors over the cycles it occurs in; all events are in `simulate.json` (`slap_events`).\n\n| cylinder | worst point | side | onset [deg] | force [kN] | impact velocity [m/s] | impact energy [mJ] | peak follows it in |\n|---|---|---|---|---|---|---|---|");
    for row in rows {
        let _ = writeln!(s, "{row}");
    }
    s
}

/// The liner maps' section of summary.md: per cylinder where the largest mean peak lies.
fn maps_section(r: &Report) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    if r.liner_maps.is_empty() {
        return s;
    }
    let _ = writeln!(s, "\n## Where on the liner\n\nThe peak negative acceleration at every node of each liner's wet outer surface, mean over the averaged cycles (`liner_maps.png`: unrolled; `liner_maps.vtu`: for ParaView, with `ca` and `cavitating_fraction`, the share of the cycles with Ca < 1, and their standard errors). Per cylinder the node with the largest mean (angle from +x: thrust side 90 deg; depth below the liner top), its values ± standard errors, and the share of the wet surface whose mean peak is past Ca = 1.\n\n| cylinder | nodes | largest at [deg, mm] | peak negative [m/s^2] | Ca | cycles with Ca < 1 | surface past Ca = 1 |\n|---|---|---|---|---|---|---|");
    for m in &r.liner_maps {
        let _ = writeln!(
            s,
            "| {} | {} | {:.0}, {:.0} | {:.0} ± {:.0} | {:.2} ± {:.2} | {:.0} ± {:.0} % | {:.1} % |",
            m.cylinder,
            m.nodes,
            m.hottest_theta_deg,
            m.hottest_depth_mm,
            m.peak_negative_m_s2,
            m.peak_negative_se_m_s2,
            m.ca,
            m.ca_se,
            100.0 * m.cavitating_fraction,
            100.0 * m.cavitating_fraction_se,
            100.0 * m.share_ca_below_1
        );
    }
    s
}

/// `summary.md` of report `r` of `scene` written to `out`.
pub fn markdown(r: &Report, scene: &Path, out: &Path) -> String {
    use std::fmt::Write;
    let ev = &r.evaluation;
    let t = &ev.thresholds;
    let coolant = match r.coolant_layer_kg_m2 {
        None => "coolant around the liner not modelled (dry, as the study's model)".to_string(),
        Some(mu) => format!("coolant layer on the liner's wet zone: {mu:.2} kg/m^2"),
    };
    use crate::piston::lubrication::Lubrication;
    let skirt = match r.simulate.lubrication {
        Lubrication::Dry => "skirt dry (penalty contact, the study's model)".to_string(),
        l => format!(
            "skirt lubricated (oil film \"{}\", experimental: docs/validation.md)",
            l.name()
        ),
    };
    let mut s = format!("# linercav report: {}\n\n{} at {:.0} rpm; peak cylinder pressure {:.1} bar at {:.1} deg; hot clearance {:.1} um; {skirt}; {coolant}.\n\n", r.title, r.scene, r.speed_rpm, r.simulate.peak_pressure_bar, r.simulate.peak_pressure_deg, r.simulate.hot_clearance_um);
    let _ = writeln!(s, "## Verdict\n");
    let _ = writeln!(s, "Acceleration criterion ({}): onset {:.0} m/s^2, high risk {:.0} m/s^2 (k_p {:.1} Pa per m/s^2). Cylinders from the highest to the lowest peak negative acceleration: {}. The most active point along the liner: {} (of {}, top to bottom).\n", ev.threshold_source, t.onset_m_s2, t.high_risk_m_s2, t.k_p_pa_per_m_s2, crate::text::joined(&ev.ranking, ", "), ev.most_active_point, ev.cylinders.first().map(|c| c.points.len()).unwrap_or(0));
    let n_avg = r.simulate.stats.cycles_averaged;
    if n_avg > 1 {
        let st = &r.simulate.stats;
        let _ = writeln!(s, "Peaks are means over the last {n_avg} of {} cycles (slap on the ringing liner is not periodic), given as mean ± standard error (the cycles' correlation counted: autocorrelation time {:.2} cycles). Estimated step error of the mean peak: {:.1} % (tolerance {:.1} %, step {:.4} deg; from each cylinder's firing slap re-run at half the step, which does not hold the coarse step's shift of the cycles' statistics between the slaps; docs/verification.md). {} Risk and ranking use the means. {}\n", st.cycles_run, st.autocorrelation_cycles, 100.0 * st.step_error_estimate, 100.0 * r.simulate.tolerance, st.dt_s * r.speed_rpm * 6.0, step_check_sentence(&r.simulate), ranking_sentence(r));
    } else if r.simulate.step_check.is_some() {
        let _ = writeln!(s, "{}\n", step_check_sentence(&r.simulate));
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
    s.push_str(&slap_section(r));
    s.push_str(&maps_section(r));
    s.push_str(&why_section(r));
    s.push_str(&what_if_section(r));
    if let Some(c) = &r.skirt_comparison {
        s.push_str(&c.markdown((&r.clearance_sweep, &r.pin_offset_sweep)));
    }
    let _ = writeln!(s, "\n## Speed against error\n\nAgainst a converged reference (a step 64 times finer, uniform, all modes): the mode cut-off on one cylinder's window from rest (330-420 deg, largest error over its points), the step on the six firing slaps of cycle 3 from identical states (largest error over the cylinders' worst points).\n\n| setting | modes | error | wall time [ms] |\n|---|---|---|---|");
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

/// "Why the cylinders differ": the dominant response and the nearest system modes with their
/// cylinder coefficients and correlations.
fn why_section(r: &Report) -> String {
    use std::fmt::Write;
    let ev = &r.evaluation;
    let mut s = String::new();
    let _ = writeln!(s, "\n## Why the cylinders differ\n\nDominant response {:.0} Hz. Nearest system modes, with each cylinder's largest normalised radial coefficient at its analysis points and the correlation of those with the per-cylinder peak:\n", ev.dominant_hz);
    let _ = writeln!(
        s,
        "| mode [Hz] | coefficients (cylinders {}) | Pearson r | Spearman rho |\n|---|---|---|---|",
        crate::text::joined(
            &ev.cylinders.iter().map(|c| c.cylinder).collect::<Vec<_>>(),
            ", "
        )
    );
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
    s
}

/// "What-if": the clearance and pin-offset sweeps with their changes and located maxima.
fn what_if_section(r: &Report) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(s, "\n## What-if\n\nEach row's change of the engine's largest mean peak against the scene's own run, with the standard error of the difference (the two runs' cycle statistics combined); lower / higher when the change exceeds twice it, else not distinguishable.\n\n| clearance [um] | largest peak negative [m/s^2] | change against the scene [m/s^2] | largest slap force [kN] |\n|---|---|---|---|");
    for p in &r.clearance_sweep {
        let _ = writeln!(
            s,
            "| {:.1} | {:.0} ± {:.0} | {} | {:.2} |",
            p.value,
            p.largest_m_s2,
            p.largest_se_m_s2,
            change_text(p),
            p.peak_slap_force_n.iter().fold(0.0f64, |m, v| m.max(*v)) / 1e3
        );
    }
    maxima_text(
        &mut s,
        ("clearance", "um", 1),
        r.clearance_range_um,
        &r.clearance_maximum,
    );
    let _ = writeln!(s, "\n| pin offset [mm] | largest peak negative [m/s^2] | change against the scene [m/s^2] | largest slap force [kN] | side-force peak [kN] at [deg] |\n|---|---|---|---|---|");
    for p in &r.pin_offset_sweep {
        let _ = writeln!(
            s,
            "| {:+.3} | {:.0} ± {:.0} | {} | {:.2} | {:.1} at {:.1} |",
            p.value,
            p.largest_m_s2,
            p.largest_se_m_s2,
            change_text(p),
            p.peak_slap_force_n.iter().fold(0.0f64, |m, v| m.max(*v)) / 1e3,
            p.peak_side_force_n.first().copied().unwrap_or(0.0) / 1e3,
            p.side_force_crank_angle_deg.first().copied().unwrap_or(0.0)
        );
    }
    maxima_text(
        &mut s,
        ("pin offset", "mm", 3),
        r.pin_offset_range_mm,
        &r.pin_offset_maximum,
    );
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

/// A what-if row's change against the scene's run: "+123 ± 20 (higher)", or "the scene's".
fn change_text(p: &crate::report::figures::SweepPoint) -> String {
    p.change.as_ref().map_or(
        "the scene's".into(),
        crate::report::comparison::change_words,
    )
}

/// Where a sweep's maxima lie, in words: the run with the largest engine-wide mean slap force
/// and peak acceleration, each with its standard error, and the interval the response's
/// maximum lies in (half the larger spacing to the neighbouring runs).
fn maxima_text(
    s: &mut String,
    (key, unit, digits): (&str, &str, usize),
    ends: [f64; 2],
    maxima: &BTreeMap<&'static str, Maximum>,
) {
    use std::fmt::Write;
    let words = [
        ("peak_slap_force_n", "slap force", 1e-3, "kN", 2),
        (
            "peak_negative_m_s2",
            "peak negative acceleration",
            1.0,
            "m/s^2",
            0,
        ),
    ];
    for (name, what, scale, u, d) in words {
        if let Some(m) = maxima.get(name) {
            let (value, se) = (m.value * scale, m.value_se * scale);
            let _ = write!(
                s,
                "\nThe largest mean {what} over the {key} sweep ({:.digits$} to {:.digits$} {unit}): {value:.d$} ± {se:.d$} {u} at {:.digits$} {unit}",
                ends[0], ends[1], m.at
            );
            let _ = if m.at <= ends[0] || m.at >= ends[1] {
                writeln!(s, ", the end of the swept range: the response still rises there, so its maximum may lie beyond.")
            } else {
                writeln!(s, "; the maximum lies within ±{:.digits$} {unit} of it (runs placed where it can lie).", m.uncertainty)
            };
        }
    }
}
