//! Turns a cycle result into a risk verdict with its explanation: per cylinder and analysis
//! point the acceleration cavitation number and risk class, the velocity-based criteria
//! (cavitation safety factor, classic number) beside it, the spectra and their dominant peak,
//! the system modes nearest to it with each cylinder's mode-shape coefficient, and the
//! correlation of those coefficients with the per-cylinder peak negative acceleration.

use super::criteria::{self, Risk, Thresholds};
use super::Setup;
use crate::analysis::correlation::{pearson, spearman};
use crate::analysis::spectrum::{centred_spectrum, rms_average, Spectrum};
use crate::linalg::dense::row;
use crate::reduce::rom::EngineRom;
use crate::transient::cycle::{CycleResult, Series};

/// Lowest frequency searched for the dominant response \[Hz\] (below it: the quasi-static
/// piston motion, not the ring).
pub const SPECTRUM_FLOOR_HZ: f64 = 500.0;

/// One analysis point's verdict.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PointRisk {
    pub point: usize,
    pub peak_negative_m_s2: f64,
    /// Acceleration cavitation number on the negative peak (< 1: cavitation likely).
    pub ca: f64,
    pub risk: Risk,
    /// Peak wall velocity over the cycle [m/s], the cavitation safety factor Vccv / Vmax and
    /// the classic number (p_s - p_v) / (rho v^2 / 2) at that velocity.
    pub peak_velocity_m_s: f64,
    pub csf: f64,
    pub classic_number: f64,
    /// Dominant frequency of the point's spectrum above the floor \[Hz\] and its amplitude.
    pub dominant_hz: f64,
    pub dominant_amplitude_m_s2: f64,
}

/// One cylinder's verdict.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CylinderRisk {
    pub cylinder: usize,
    pub points: Vec<PointRisk>,
    pub worst: Risk,
    pub peak_negative_m_s2: f64,
    /// Point (1-based) with the largest peak negative acceleration.
    pub worst_point: usize,
}

/// A system mode near the dominant response and how its shape matches the risk ranking.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ModeLink {
    pub frequency_hz: f64,
    /// Per cylinder: largest |normalised radial coefficient| over the analysis points.
    pub cylinder_coefficients: Vec<f64>,
    /// Correlation of those with the per-cylinder peak negative acceleration (None when
    /// either is constant or one cylinder is modelled).
    pub pearson: Option<f64>,
    pub spearman: Option<f64>,
}

/// The whole evaluation.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Evaluation {
    pub thresholds: Thresholds,
    pub threshold_source: &'static str,
    pub vccv_m_s: f64,
    pub cylinders: Vec<CylinderRisk>,
    /// Cylinders ordered from the highest to the lowest peak negative acceleration.
    pub ranking: Vec<usize>,
    /// Engine-wide dominant response frequency \[Hz\]: the peak of the RMS average of all the
    /// points' spectra, each itself averaged over the averaged cycles ([`spectra`]). The
    /// spectrum of one cycle scatters bin to bin (the slap is not periodic), so its largest
    /// peak jumps between neighbouring peaks of similar height from one realisation to the next.
    pub dominant_hz: f64,
    /// The system modes nearest to it (closest first).
    pub nearest_modes: Vec<ModeLink>,
    /// Point (1-based) most often the worst over the cylinders.
    pub most_active_point: usize,
}

/// Per cylinder and point, the spectrum averaged over the averaged cycles, as the run made it
/// (`CylinderSeries::spectra`: each cycle's record centred on the cylinder's firing TDC, RMS
/// average over the cycles; one cycle's spectrum of a non-periodic slap is one draw, whose
/// largest peak jumps between neighbouring modes). A series without them gives the last
/// cycle's spectrum, centred the same way.
pub fn spectra(series: &Series, firing_order: &[usize]) -> Vec<Vec<Spectrum>> {
    let n = series.time_s.len();
    if n < 4 {
        return vec![];
    }
    let dt = (series.time_s[n - 1] - series.time_s[0]) / (n - 1) as f64;
    let cyls = firing_order.len();
    series
        .cylinders
        .iter()
        .map(|c| {
            if c.spectra.len() == c.acceleration.nrows() {
                return c.spectra.clone();
            }
            let k = firing_order
                .iter()
                .position(|&x| x == c.cylinder)
                .unwrap_or(0);
            let phase = 720.0 * k as f64 / cyls as f64;
            (0..c.acceleration.nrows())
                .map(|p| {
                    centred_spectrum(row(&c.acceleration, p), &series.crank_angle_deg, phase, dt)
                })
                .collect()
        })
        .collect()
}

/// Peak |v| of a periodic acceleration record: v = cumulative trapezoid integral, mean
/// removed (the cycle is periodic, so the mean velocity is zero).
pub fn peak_velocity(a: &[f64], dt: f64) -> f64 {
    let mut v = Vec::with_capacity(a.len());
    let mut s = 0.0;
    v.push(0.0);
    for k in 1..a.len() {
        s += 0.5 * (a[k - 1] + a[k]) * dt;
        v.push(s);
    }
    let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
    v.iter().fold(0.0f64, |m, x| m.max((x - mean).abs()))
}

/// The three system modes up to 1.5 x `band_hz` nearest in frequency to `dominant_hz`, each
/// with its per-cylinder coefficient (the largest |phi| over the cylinder's points) and the
/// Pearson and Spearman correlations of those coefficients with the cylinders' peaks `per_cyl`.
fn modes_near(rom: &EngineRom, dominant_hz: f64, band_hz: f64, per_cyl: &[f64]) -> Vec<ModeLink> {
    let modes = rom.shapes();
    let mut order: Vec<usize> = (0..modes.len())
        .filter(|&j| rom.frequencies_hz[j] <= band_hz * 1.5)
        .collect();
    order.sort_by(|&a, &b| {
        (modes[a].frequency_hz - dominant_hz)
            .abs()
            .total_cmp(&(modes[b].frequency_hz - dominant_hz).abs())
    });
    order
        .iter()
        .take(3)
        .map(|&j| {
            let coef: Vec<f64> = modes[j]
                .coefficients
                .iter()
                .map(|row| row.iter().fold(0.0f64, |m, v| m.max(v.abs())))
                .collect();
            ModeLink {
                frequency_hz: modes[j].frequency_hz,
                pearson: pearson(&coef, per_cyl),
                spearman: spearman(&coef, per_cyl),
                cylinder_coefficients: coef,
            }
        })
        .collect()
}

/// Evaluates `res` (from `rom`) with the scene's cavitation data.
pub fn evaluate(
    res: &CycleResult,
    rom: &EngineRom,
    cav: &Setup,
    firing_order: &[usize],
    band_hz: f64,
) -> Evaluation {
    let t = cav.thresholds;
    let c = &cav.coolant;
    let s = &res.series;
    let n = s.time_s.len();
    let dt = if n > 1 {
        (s.time_s[n - 1] - s.time_s[0]) / (n - 1) as f64
    } else {
        1.0
    };
    let sp = spectra(s, firing_order);
    let mut cylinders = Vec::new();
    let mut best = (0.0f64, 0.0f64);
    for (ci, peaks) in res.peaks.iter().enumerate() {
        let mut pts = Vec::new();
        for (p, neg) in res.peak_negative.row(ci).iter().enumerate() {
            let a = neg.value;
            let v = s
                .cylinders
                .get(ci)
                .map(|cs| peak_velocity(row(&cs.acceleration, p), dt))
                .unwrap_or(0.0);
            let (fd, amp) = sp
                .get(ci)
                .and_then(|x| x.get(p))
                .and_then(|x| x.dominant(SPECTRUM_FLOOR_HZ, band_hz))
                .unwrap_or((0.0, 0.0));
            if amp > best.1 {
                best = (fd, amp);
            }
            pts.push(PointRisk {
                point: p + 1,
                peak_negative_m_s2: a,
                ca: criteria::acceleration_number(c, t.k_p_pa_per_m_s2, cav.gap, a),
                risk: t.classify(a),
                peak_velocity_m_s: v,
                csf: criteria::safety_factor(c, v),
                classic_number: criteria::classic_number(c.static_pa, c, v),
                dominant_hz: fd,
                dominant_amplitude_m_s2: amp,
            });
        }
        let (wp, wa) = pts
            .iter()
            .map(|p| (p.point, p.peak_negative_m_s2))
            .fold((0, f64::MIN), |m, x| if x.1 > m.1 { x } else { m });
        cylinders.push(CylinderRisk {
            cylinder: peaks.cylinder,
            worst: pts.iter().map(|p| p.risk).max().unwrap_or(Risk::Safe),
            peak_negative_m_s2: wa,
            worst_point: wp,
            points: pts,
        });
    }
    let all: Vec<&Spectrum> = sp.iter().flatten().collect();
    if let Some((f, _)) = rms_average(&all).and_then(|m| m.dominant(SPECTRUM_FLOOR_HZ, band_hz)) {
        best.0 = f;
    }
    let mut ranking: Vec<&CylinderRisk> = cylinders.iter().collect();
    ranking.sort_by(|a, b| b.peak_negative_m_s2.total_cmp(&a.peak_negative_m_s2));
    let ranking: Vec<usize> = ranking.iter().map(|c| c.cylinder).collect();
    let per_cyl: Vec<f64> = cylinders.iter().map(|c| c.peak_negative_m_s2).collect();
    let nearest_modes = modes_near(rom, best.0, band_hz, &per_cyl);
    let np = cylinders.first().map(|c| c.points.len()).unwrap_or(0);
    let mut count = vec![0usize; np];
    for c in &cylinders {
        if c.worst_point >= 1 {
            count[c.worst_point - 1] += 1;
        }
    }
    let most_active_point = (0..np)
        .max_by_key(|&k| (count[k], std::cmp::Reverse(k)))
        .map(|k| k + 1)
        .unwrap_or(0);
    Evaluation {
        thresholds: t,
        threshold_source: t.source,
        vccv_m_s: c.vccv(),
        cylinders,
        ranking,
        dominant_hz: best.0,
        nearest_modes,
        most_active_point,
    }
}

impl Evaluation {
    pub fn to_text(&self) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        let t = &self.thresholds;
        let _ = writeln!(
            s,
            "cavitation risk (acceleration criterion; {}): onset {:.0} m/s^2, high risk {:.0} m/s^2, k_p {:.1} Pa/(m/s^2); Vccv {:.4} m/s",
            self.threshold_source, t.onset_m_s2, t.high_risk_m_s2, t.k_p_pa_per_m_s2, self.vccv_m_s
        );
        for c in &self.cylinders {
            let _ = write!(s, "  cylinder {}: {:<12}", c.cylinder, c.worst.label());
            for p in &c.points {
                let _ = write!(
                    s,
                    " p{} {:>6.0} (Ca {:>5.2}, CSF {:>5.2})",
                    p.point, p.peak_negative_m_s2, p.ca, p.csf
                );
            }
            let _ = writeln!(s);
        }
        let _ = writeln!(
            s,
            "  ranking (peak negative): {}; most active point: {}; dominant response {:.0} Hz",
            crate::text::joined(&self.ranking, " > "),
            self.most_active_point,
            self.dominant_hz
        );
        for m in &self.nearest_modes {
            let _ = writeln!(
                s,
                "  mode {:.0} Hz: cylinder coefficients {}, correlation with the per-cylinder peak: pearson {}, spearman {}",
                m.frequency_hz,
                crate::text::joined(
                    &m.cylinder_coefficients
                        .iter()
                        .map(|v| format!("{v:.2}"))
                        .collect::<Vec<_>>(),
                    ", "
                ),
                m.pearson.map(|v| format!("{v:.2}")).unwrap_or("-".into()),
                m.spearman.map(|v| format!("{v:.2}")).unwrap_or("-".into()),
            );
        }
        s
    }
}
