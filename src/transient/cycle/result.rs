//! What an engine run returns: peaks (means over the averaged cycles with their spread and
//! standard error), forces, the last cycle's series with the averaged spectra, work counters and
//! the firing slaps' step-error estimates.

#[allow(unused_imports)]
use super::*;

/// Work counters and checks of a run.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Stats {
    pub steps: usize,
    pub newton_iterations: usize,
    pub max_newton_per_step: usize,
    pub rejected_steps: usize,
    pub modes: usize,
    /// Accumulated energy-balance error relative to the energy scale (E - W_contact + W_damping).
    pub energy_error: f64,
    /// Largest penetration \[m\].
    pub max_penetration_m: f64,
    /// Smallest force of any slice at any committed step \[N\] (the law never pulls: >= 0).
    pub min_slice_force_n: f64,
    /// Base steps taken as sub-steps around slap onsets ([`CycleSettings::slap_substeps`]).
    pub substepped_steps: usize,
    /// Largest relative change of a peak negative acceleration between the last two cycles.
    pub cycle_change: f64,
    /// Cycles run, and the last ones whose peaks are averaged.
    pub cycles_run: usize,
    pub cycles_averaged: usize,
    /// Estimated relative step error of the mean peak negative acceleration
    /// ([`mean_step_error`]; 0 when not estimated), and how often the step was halved to
    /// bring it within the tolerance.
    pub step_error_estimate: f64,
    pub step_refinements: usize,
    /// Integrated autocorrelation time of the per-cycle peaks (1: independent cycles), pooled
    /// over every peak series of the run (`standard_errors`).
    pub autocorrelation_cycles: f64,
    pub dt_s: f64,
    /// Per-cylinder coupling: largest difference between the liner displacement a contact
    /// slice used and the one of the completed step \[m\].
    pub coupling_lag_m: f64,
    /// Lubricated skirt: the largest difference, over the committed steps, between an engaged
    /// film side's force as the step linearised it and the film evaluated at the step's end,
    /// relative to the side's film force (`film_mismatch`; 0 for a dry skirt). Above
    /// [`FILM_RESOLVED`] the run did not resolve its film.
    pub film_mismatch: f64,
}

/// The film mismatch (`Stats::film_mismatch`) up to which a lubricated run's film counts as
/// resolved: a fifth of a side's film force, chosen before any run.
pub const FILM_RESOLVED: f64 = 0.2;

/// Time series of the last cycle, one row per base step.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Series {
    /// Global crank angle \[deg\] (cylinder `firing_order[0]`'s own angle) and time \[s\].
    pub crank_angle_deg: Vec<f64>,
    pub time_s: Vec<f64>,
    /// Per modelled cylinder.
    pub cylinders: Vec<CylinderSeries>,
}

/// One cylinder's series.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct CylinderSeries {
    pub cylinder: usize,
    /// Liner point accelerations [m/s^2] (points x steps), + toward the coolant.
    pub acceleration: Dense,
    /// Per point, the amplitude spectrum of `acceleration` averaged over the averaged cycles:
    /// each cycle's record centred on the cylinder's firing TDC
    /// ([`crate::transient::spectrum::centred_spectrum`]), RMS-averaged ([`crate::transient::spectrum::PowerSum`];
    /// one cycle's spectrum of a non-periodic slap is one draw). Not serialised.
    #[serde(skip)]
    pub spectra: Vec<Spectrum>,
    /// Crankcase jacket-wall accelerations at the facing points [m/s^2] (points x steps; the
    /// last cycle's only, 0 steps in the others).
    pub crankcase_acceleration: Dense,
    pub lateral_m: Vec<f64>,
    pub tilt_rad: Vec<f64>,
    /// Summed contact force on the thrust and anti-thrust side \[N\].
    pub thrust_force_n: Vec<f64>,
    pub antithrust_force_n: Vec<f64>,
    /// Contact impulse of each side over the base step ending at the sample, its sub-steps
    /// included \[N s\]: summed over a slap it is the momentum the contact gave the piston (the
    /// force samples above are the base steps' ends and miss a slap shorter than a step).
    pub thrust_impulse_n_s: Vec<f64>,
    pub antithrust_impulse_n_s: Vec<f64>,
    /// Quasi-static side force \[N\] and cylinder pressure \[Pa\].
    pub side_force_n: Vec<f64>,
    pub pressure_pa: Vec<f64>,
}

/// A peak value and the cylinder's own crank angle where it occurs; over several cycles the
/// mean of the per-cycle peaks, the medoid of their crank angles (on the 720 deg circle), the
/// sample standard deviation and the largest per-cycle peak.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Peak {
    pub value: f64,
    pub crank_angle_deg: f64,
    /// Sample standard deviation of the per-cycle peaks (0 for one cycle).
    pub std: f64,
    /// Standard error of the mean, corrected for the correlation of consecutive cycles
    /// (`standard_errors`; 0 for one cycle).
    pub se: f64,
    /// Largest per-cycle peak.
    pub max: f64,
}

impl Peak {
    /// One cycle's peak.
    pub fn single(value: f64, crank_angle_deg: f64) -> Self {
        Peak {
            value,
            crank_angle_deg,
            std: 0.0,
            se: 0.0,
            max: value,
        }
    }

    /// Statistics of per-cycle peaks P_k at angles a_k (k = 1..n): mean, the medoid angle (the
    /// a_k with the least summed distance to the others on the 720 deg circle; the first such
    /// one on ties), s = sqrt(sum (P_k - mean)^2 / (n - 1)), max P_k. The medoid is an angle
    /// where a peak occurred: when cycles peak at different events (a non-periodic slap), a
    /// mean angle would fall between them, where nothing happens.
    pub fn over_cycles(per_cycle: &[Peak]) -> Self {
        let n = per_cycle.len();
        if n == 0 {
            return Peak::default();
        }
        let values: Vec<f64> = per_cycle.iter().map(|p| p.value).collect();
        let (mean, std) = super::statistics::mean_std(&values);
        // circular distance on the 720 deg cycle
        let dist = |a: f64, b: f64| {
            let d = (a - b).rem_euclid(720.0);
            d.min(720.0 - d)
        };
        let medoid = per_cycle
            .iter()
            .map(|p| p.crank_angle_deg)
            .min_by(|&a, &b| {
                let spread = |x: f64| {
                    per_cycle
                        .iter()
                        .map(|q| dist(x, q.crank_angle_deg))
                        .sum::<f64>()
                };
                spread(a).total_cmp(&spread(b))
            })
            .expect("n > 0");
        Peak {
            value: mean,
            crank_angle_deg: medoid,
            std,
            se: if n > 1 { std / (n as f64).sqrt() } else { 0.0 },
            max: per_cycle
                .iter()
                .map(|p| p.value)
                .fold(f64::NEG_INFINITY, f64::max),
        }
    }
}

/// The force peaks of one cylinder over the reported cycles.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct CylinderPeaks {
    pub cylinder: usize,
    /// The largest slap event's force (the dynamic slap, the contact force beyond the
    /// quasi-static side force, interpolated between the sub-steps: [`SlapEvent`]) \[N\], at the
    /// crank angle of its largest force.
    pub slap_force: Peak,
    /// Largest quasi-static side force toward thrust \[N\].
    pub side_force: Peak,
    /// The slap events over the averaged cycles, in onset order ([`EventSummary`]).
    pub slap_events: Vec<EventSummary>,
    /// Per analysis point, the event (index into `slap_events`) whose onset its peak negative
    /// acceleration follows in most averaged cycles (None: before every onset), and in how
    /// many of them.
    pub negative_events: Vec<(Option<usize>, usize)>,
}

/// A cycle's (or the averaged cycles') peaks: per cylinder the forces, and per cylinder
/// (rows, in the order of `cylinders`) and analysis point (columns) the largest negative
/// acceleration as a positive magnitude and the largest positive acceleration.
#[derive(Clone, Debug, Default)]
pub(super) struct CyclePeaks {
    pub(super) cylinders: Vec<CylinderPeaks>,
    pub(super) negative: Array2<Peak>,
    pub(super) positive: Array2<Peak>,
}

/// Result of a run.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CycleResult {
    /// Per cylinder: its number and force peaks.
    pub peaks: Vec<CylinderPeaks>,
    /// Per cylinder (rows, as `peaks`) and analysis point (columns, top to bottom): the peak
    /// negative acceleration as a positive magnitude, and the peak positive acceleration
    /// [m/s^2].
    pub peak_negative: Array2<Peak>,
    pub peak_positive: Array2<Peak>,
    pub series: Series,
    pub stats: Stats,
    /// Step-error estimate of each cylinder's firing slap ([`StepError`]).
    pub step_error: Vec<StepError>,
    /// Per cylinder, the wet surface's peak negative accelerations in each averaged cycle
    /// (empty unless `surface_maps`).
    #[serde(skip)]
    pub surface: Vec<SurfacePeaks>,
}

/// The step error of one cylinder's peak negative accelerations, measured on its firing
/// slap in the last cycle: from the state at the start of the window (its own crank angle
/// [`STEP_ERROR_WINDOW_DEG`]), the engine is run over the window at the base step h and at
/// h/2 and the filtered peaks of the cylinder's points compared away from the filter's ends.
/// The estimate of |P_h - P_converged| is 2 |P_h - P_{h/2}|, which holds for any order of
/// convergence >= 1 (4/3 of it for second order).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct StepError {
    pub cylinder: usize,
    /// Window peaks at h and at h/2 per point [m/s^2].
    pub peak_h: Vec<f64>,
    pub peak_half_h: Vec<f64>,
}

impl StepError {
    /// Estimated relative error of point `p`'s peak, 2 |P_h - P_{h/2}| / P_h.
    pub fn relative(&self, p: usize) -> f64 {
        2.0 * (self.peak_h[p] - self.peak_half_h[p]).abs() / self.peak_h[p].abs().max(1e-12)
    }
}

/// The firing-slap window of the step-error estimate, in the cylinder's own crank angle \[deg\].
pub const STEP_ERROR_WINDOW_DEG: (f64, f64) = (320.0, 430.0);
/// How much of each end of the window the output filter may take before the window is
/// widened (the compared part keeps covering 355-395 deg, the firing slap) \[deg\].
pub(super) const SLAP_MARGIN_DEG: f64 = 35.0;

/// Estimated relative step error of the mean of all peaks: 2 |sum (P_h - P_{h/2})| / sum P_h
/// over every cylinder and point.
pub fn mean_step_error(errors: &[StepError]) -> f64 {
    let (mut d, mut s) = (0.0, 0.0);
    for e in errors {
        for (a, b) in e.peak_h.iter().zip(&e.peak_half_h) {
            d += a - b;
            s += a;
        }
    }
    if s > 0.0 {
        2.0 * d.abs() / s
    } else {
        0.0
    }
}
