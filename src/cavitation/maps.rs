//! Liner maps: the cavitation criteria over every node of each liner's wet outer surface, from
//! the transient's per-cycle surface peaks ([`SurfacePeaks`]).
//!
//! Per node, from the peak negative accelerations a_k of the n averaged cycles:
//! - the mean peak a = sum a_k / n with its standard error s sqrt(tau / n) (s the sample
//!   deviation, tau the run's autocorrelation time in cycles, as the analysis points' peaks);
//! - the acceleration cavitation number on the mean peak, Ca(a) ([`criteria::acceleration_number`],
//!   as the points' `ca`), its standard error |dCa/da| SE(a) (central difference);
//! - the fraction f of the averaged cycles with Ca(a_k) < 1 (|a_k| beyond the threshold),
//!   its standard error sqrt(n f (1 - f) / (n - 1)) sqrt(tau / n) (the same estimator on the
//!   0/1 series).

use super::criteria;
use super::Setup;
use crate::transient::cycle::{statistics, SurfacePeaks};

/// The largest Ca a map holds (a node at rest has Ca = inf; far beyond any threshold).
pub const CA_CAP: f64 = 1e6;

/// One liner's map: per node of its wet outer surface (rows of `nodes`).
#[derive(Clone, Debug, serde::Serialize)]
pub struct LinerMap {
    /// 1-based cylinder number.
    pub cylinder: usize,
    /// Liner mesh node of each value.
    pub nodes: Vec<usize>,
    /// Mean peak negative acceleration (a positive magnitude) [m/s^2] and its standard error.
    pub peak_negative_m_s2: Vec<f64>,
    pub peak_negative_se_m_s2: Vec<f64>,
    /// Acceleration cavitation number on the mean peak and its standard error.
    pub ca: Vec<f64>,
    pub ca_se: Vec<f64>,
    /// Fraction of the averaged cycles with Ca < 1 and its standard error.
    pub cavitating_fraction: Vec<f64>,
    pub cavitating_fraction_se: Vec<f64>,
    /// Averaged cycles behind each value.
    pub cycles: usize,
}

/// Mean and standard error s sqrt(tau / n) of a series (0 for one value), by the transient's
/// own statistics ([`statistics::mean_std`], [`statistics::se_factor`]).
fn mean_se(v: &[f64], tau: f64) -> (f64, f64) {
    let (mean, s) = statistics::mean_std(v);
    (mean, s * statistics::se_factor(tau, v.len()))
}

/// The maps of every cylinder's surface peaks, `tau` the run's autocorrelation time.
pub fn liner_maps(surface: &[SurfacePeaks], cav: &Setup, tau: f64) -> Vec<LinerMap> {
    let (c, k_p, gap) = (&cav.coolant, cav.thresholds.k_p_pa_per_m_s2, cav.gap);
    let ca_of = |a: f64| criteria::acceleration_number(c, k_p, gap, a);
    surface
        .iter()
        .map(|s| {
            let mut m = LinerMap {
                cylinder: s.cylinder,
                nodes: s.nodes.clone(),
                peak_negative_m_s2: Vec::new(),
                peak_negative_se_m_s2: Vec::new(),
                ca: Vec::new(),
                ca_se: Vec::new(),
                cavitating_fraction: Vec::new(),
                cavitating_fraction_se: Vec::new(),
                cycles: s.per_cycle.ncols(),
            };
            for row in s.per_cycle.rows() {
                let v = row.to_vec();
                let (a, se) = mean_se(&v, tau);
                let da = 1e-6 * a.max(1e-3);
                let slope =
                    (ca_of(a + da) - ca_of((a - da).max(0.0))) / (a + da - (a - da).max(0.0));
                let hits: Vec<f64> = v
                    .iter()
                    .map(|&x| if ca_of(x) < 1.0 { 1.0 } else { 0.0 })
                    .collect();
                let (f, f_se) = mean_se(&hits, tau);
                m.peak_negative_m_s2.push(a);
                m.peak_negative_se_m_s2.push(se);
                // a node that never moves has Ca = inf: capped, so that every file can hold it
                m.ca.push(ca_of(a).min(CA_CAP));
                let ca_se = slope.abs() * se;
                m.ca_se.push(if ca_se.is_finite() { ca_se } else { 0.0 });
                m.cavitating_fraction.push(f);
                m.cavitating_fraction_se.push(f_se);
            }
            m
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Verification: the standard error of the 0/1 series is the binomial one for
    /// independent cycles (tau = 1): sqrt(f (1 - f) / (n - 1)).
    #[test]
    fn verification_fraction_standard_error_is_binomial_for_independent_cycles() {
        let v = [1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        let (f, se) = mean_se(&v, 1.0);
        assert!((f - 0.3).abs() < 1e-15);
        assert!((se - (0.3f64 * 0.7 / 9.0).sqrt()).abs() < 1e-15);
    }
}
