//! The figure of a calibration of the acceleration criterion from rig data
//! (`calibrate --out`): the pressure against the acceleration with the fit, and Ca against
//! |a| with the thresholds.

use super::png::{write_png, Chart, Mark, Rule, Series};
use crate::cavitation::calibration::Calibration;
use crate::files::WriteError;
use std::path::Path;

/// Two panels: peak wall pressure against peak acceleration with the fitted line (positive
/// side linear, negative side saturating near p_v), and Ca against |a| with Ca = 1 and the
/// thresholds.
pub fn draw_calibration(path: &Path, cal: &Calibration) -> Result<(), WriteError> {
    let ps = cal.coolant.static_pa / 1e3;
    let pv = cal.coolant.vapour_pressure_pa / 1e3;
    let amax = cal
        .event_list
        .iter()
        .map(|e| e.peak_positive_m_s2.max(e.peak_negative_m_s2))
        .fold(0.0f64, f64::max);
    let k = cal.k_p_pa_per_m_s2 / 1e3;
    let pos: Vec<(f64, f64)> = cal
        .event_list
        .iter()
        .map(|e| (e.peak_positive_m_s2, e.peak_pressure_kpa))
        .collect();
    let neg: Vec<(f64, f64)> = cal
        .event_list
        .iter()
        .map(|e| (-e.peak_negative_m_s2, e.min_pressure_kpa))
        .collect();
    let left = Chart {
        title: "Peak wall pressure against peak liner acceleration",
        x_label: "peak acceleration [m/s^2] (+ toward the coolant)",
        y_label: "peak pressure [kPa]",
        series: vec![
            Series {
                name: "positive peaks".into(),
                points: pos,
                mark: Mark::Dots,
                color: 0,
            },
            Series {
                name: "negative peaks".into(),
                points: neg,
                mark: Mark::Dots,
                color: 1,
            },
            Series {
                name: format!("p_s + k_p a, k_p = {:.1} Pa/(m/s^2)", cal.k_p_pa_per_m_s2),
                points: vec![(-amax, ps - k * amax), (amax, ps + k * amax)],
                mark: Mark::Line,
                color: 7,
            },
        ],
        rules: vec![Rule {
            name: "vapour pressure".into(),
            value: pv,
            vertical: false,
            color: 2,
        }],
        x_range: None,
        y_range: None,
    };
    let ca: Vec<(f64, f64)> = cal
        .event_list
        .iter()
        .map(|e| (e.peak_negative_m_s2, e.ca))
        .collect();
    let ca_max = ca.iter().map(|p| p.1).fold(1.0f64, f64::max).min(10.0);
    let right = Chart {
        title: "Acceleration cavitation number per event",
        x_label: "peak negative acceleration |a| [m/s^2]",
        y_label: "Ca = (p_r - p_v) / (rho |a| h)",
        series: vec![Series {
            name: "events".into(),
            points: ca,
            mark: Mark::Dots,
            color: 0,
        }],
        rules: vec![
            Rule {
                name: "Ca = 1".into(),
                value: 1.0,
                vertical: false,
                color: 7,
            },
            Rule {
                name: format!("onset {:.0} m/s^2", cal.onset_m_s2),
                value: cal.onset_m_s2,
                vertical: true,
                color: 4,
            },
            Rule {
                name: format!("high risk {:.0} m/s^2", cal.high_risk_m_s2),
                value: cal.high_risk_m_s2,
                vertical: true,
                color: 1,
            },
        ],
        x_range: None,
        y_range: Some((-0.05 * ca_max, ca_max * 1.05)),
    };
    write_png(path, (1500, 620), |root| {
        let (a, b) = root.split_horizontally(750);
        left.draw(&a)?;
        right.draw(&b)
    })
}
