//! Calibration of the acceleration criterion from rig data: events, peaks, the positive-peak
//! pressure transfer k_p, the acceleration number of every event, and the onset and high-risk
//! thresholds.
//!
//! Data: `time_s`, `acceleration_m_s2` (liner, + toward the coolant) and `pressure_kpa`
//! (absolute, at the crankcase wall), many pulse events separated by quiet time.
//!
//! Method:
//! 1. noise level sigma = 1.4826 MAD(a) (robust standard deviation; quiet time dominates the
//!    median); samples with |a| > max(6 sigma, 2 % of max |a|) are active;
//! 2. active samples closer than the quiet time (default 2 ms, several periods of a kHz ring)
//!    belong to one event; each event's window reaches half-way to its neighbours, at most
//!    one quiet time beyond its active samples;
//! 3. per event: largest positive and negative acceleration and pressure;
//! 4. k_p by least squares through the static point: p_max - p_s = k_p a_max,
//!    k_p = sum a_i (p_i - p_s) / sum a_i^2 (the positive side stays linear: no cavitation);
//! 5. per event Ca = (p_min - p_v) / (rho |a_min| h), with the measured wall pressure at the
//!    negative peak (it saturates near p_v once vapour forms);
//! 6. onset = the smallest |a_min| of the events with Ca < 1 (below it every event has
//!    Ca >= 1); high risk = the largest |a_min| of the events with Ca >= 1 (above it every
//!    event has Ca < 1). When the two classes do not overlap (no transition band seen),
//!    the thresholds bracket the gap: onset = the largest safe event, high = the smallest
//!    cavitating one.

use crate::coolant::Coolant;
use std::path::Path;

/// Rig data: time \[s\], acceleration [m/s^2], pressure \[Pa\].
#[derive(Clone, Debug, Default)]
pub struct RigData {
    pub time: Vec<f64>,
    pub acceleration: Vec<f64>,
    pub pressure: Vec<f64>,
}

/// Bad rig data or a calibration that cannot be made, naming file and line.
#[derive(Debug, thiserror::Error)]
pub enum CalibrationError {
    #[error("{file}: cannot read: {msg}")]
    Io { file: String, msg: String },
    #[error("{file}: missing column '{column}' in the header (need time_s, acceleration_m_s2, pressure_kpa; found: {found})")]
    Column {
        file: String,
        column: &'static str,
        found: String,
    },
    #[error("{file}:{line}: {msg}")]
    Line {
        file: String,
        line: usize,
        msg: String,
    },
    #[error("{file}: {msg}")]
    Data { file: String, msg: String },
}

const COLUMNS: [&str; 3] = ["time_s", "acceleration_m_s2", "pressure_kpa"];

impl RigData {
    /// Reads the CSV at `path` (header with the three columns in any order; other columns are
    /// ignored; `#` lines and blank lines skipped).
    pub fn read(path: &Path) -> Result<Self, CalibrationError> {
        let file = path.display().to_string();
        let text = crate::files::read_text(path, crate::files::LIMIT_DATA).map_err(|e| {
            CalibrationError::Io {
                file: file.clone(),
                msg: e.to_string(),
            }
        })?;
        Self::parse(&file, &text)
    }

    /// Parses CSV text; `file` names it in errors.
    pub fn parse(file: &str, text: &str) -> Result<Self, CalibrationError> {
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
        let Some((_, header)) = lines.next() else {
            return Err(CalibrationError::Data {
                file: file.into(),
                msg: "empty file".into(),
            });
        };
        let names: Vec<&str> = header.split(',').map(|s| s.trim()).collect();
        if let Some(c) = crate::text::repeated_column(&names, &COLUMNS) {
            return Err(CalibrationError::Data {
                file: file.into(),
                msg: format!("the header names column '{c}' twice: give each column once"),
            });
        }
        let mut idx = [0usize; 3];
        for (k, col) in COLUMNS.iter().enumerate() {
            idx[k] =
                names
                    .iter()
                    .position(|n| n == col)
                    .ok_or_else(|| CalibrationError::Column {
                        file: file.into(),
                        column: col,
                        found: crate::text::clipped(&names.join(", "), 200),
                    })?;
        }
        let mut d = RigData::default();
        for (ln, line) in lines {
            let fields: Vec<&str> = line.split(',').map(|s| s.trim()).collect();
            if fields.len() != names.len() {
                return Err(CalibrationError::Line {
                    file: file.into(),
                    line: ln + 1,
                    msg: crate::text::field_count_message(fields.len(), names.len()),
                });
            }
            let v = row_values(file, ln + 1, &fields, &idx)?;
            if let Some(&last) = d.time.last() {
                if v[0] <= last {
                    return Err(CalibrationError::Line {
                        file: file.into(),
                        line: ln + 1,
                        msg: format!("time {} s does not increase (previous {} s)", v[0], last),
                    });
                }
            }
            d.time.push(v[0]);
            d.acceleration.push(v[1]);
            d.pressure.push(v[2] * 1e3);
        }
        if d.time.len() < 16 {
            return Err(CalibrationError::Data {
                file: file.into(),
                msg: format!(
                    "{} data rows; need a record with events (at least 16 rows)",
                    d.time.len()
                ),
            });
        }
        Ok(d)
    }
}

/// One pulse event.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Event {
    pub start_s: f64,
    pub end_s: f64,
    pub peak_positive_m_s2: f64,
    /// Magnitude.
    pub peak_negative_m_s2: f64,
    pub peak_pressure_kpa: f64,
    pub min_pressure_kpa: f64,
    /// Acceleration-based cavitation number with the measured wall pressure.
    pub ca: f64,
}

/// Calibration settings.
#[derive(Clone, Copy, Debug)]
pub struct Settings {
    pub coolant: Coolant,
    /// Coolant gap \[m\].
    pub gap: f64,
    /// Quiet time that separates events \[s\].
    pub quiet: f64,
}

/// The calibration result.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Calibration {
    pub onset_m_s2: f64,
    pub high_risk_m_s2: f64,
    pub k_p_pa_per_m_s2: f64,
    pub events: usize,
    pub cavitating_events: usize,
    /// Coefficient of determination of the positive-peak fit.
    pub fit_r2: f64,
    /// Robust noise level of the acceleration [m/s^2] and the detection level.
    pub noise_m_s2: f64,
    pub detection_m_s2: f64,
    /// Whether safe and cavitating events overlap (a transition band was observed).
    pub transition_band_observed: bool,
    /// The model threshold |a|* = (p_s - p_v)/(k_p + rho h) with the fitted k_p.
    pub model_threshold_m_s2: f64,
    pub coolant: Coolant,
    pub gap_mm: f64,
    pub event_list: Vec<Event>,
}

/// The three values (time, acceleration, pressure) of rig-data line `line` (`fields`, the
/// columns at `idx`): numbers, finite, the absolute pressure not negative.
fn row_values(
    file: &str,
    line: usize,
    fields: &[&str],
    idx: &[usize; 3],
) -> Result<[f64; 3], CalibrationError> {
    let mut v = [0.0; 3];
    for k in 0..3 {
        let s = fields.get(idx[k]).ok_or_else(|| CalibrationError::Line {
            file: file.into(),
            line,
            msg: format!(
                "{} fields, column '{}' is field {}",
                fields.len(),
                COLUMNS[k],
                idx[k] + 1
            ),
        })?;
        v[k] = s.parse::<f64>().map_err(|_| CalibrationError::Line {
            file: file.into(),
            line,
            msg: format!("'{s}' in column '{}' is not a number", COLUMNS[k]),
        })?;
        if !v[k].is_finite() {
            return Err(CalibrationError::Line {
                file: file.into(),
                line,
                msg: format!("{} in column '{}' (need finite values)", v[k], COLUMNS[k]),
            });
        }
    }
    // the wall pressure is absolute (a negative one is a gauge reading or a sign
    // slip: every event read as cavitating)
    if v[2] < 0.0 {
        return Err(CalibrationError::Line {
            file: file.into(),
            line,
            msg: format!(
                "pressure_kpa {} is negative: the column holds the absolute wall pressure",
                crate::text::num(v[2])
            ),
        });
    }
    Ok(v)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Finds the events of `d` (method steps 1-3): index ranges and the noise/detection levels.
pub fn find_events(d: &RigData, quiet: f64) -> (Vec<(usize, usize)>, f64, f64) {
    let a = &d.acceleration;
    let m = median(a.clone());
    let sigma = 1.4826 * median(a.iter().map(|x| (x - m).abs()).collect());
    let amax = a.iter().fold(0.0f64, |s, x| s.max(x.abs()));
    let level = (6.0 * sigma).max(0.02 * amax);
    let active: Vec<usize> = (0..a.len()).filter(|&i| a[i].abs() > level).collect();
    let mut groups: Vec<(usize, usize)> = Vec::new();
    for &i in &active {
        match groups.last_mut() {
            Some(g) if d.time[i] - d.time[g.1] <= quiet => g.1 = i,
            _ => groups.push((i, i)),
        }
    }
    // widen each group half-way to its neighbours, at most one quiet time
    let n = a.len();
    let mut out = Vec::with_capacity(groups.len());
    for (k, &(s, e)) in groups.iter().enumerate() {
        let lo_lim = if k > 0 { (groups[k - 1].1 + s) / 2 } else { 0 };
        let hi_lim = if k + 1 < groups.len() {
            (e + groups[k + 1].0) / 2
        } else {
            n - 1
        };
        let mut lo = s;
        while lo > lo_lim && d.time[s] - d.time[lo - 1] <= quiet {
            lo -= 1;
        }
        let mut hi = e;
        while hi < hi_lim && d.time[hi + 1] - d.time[e] <= quiet {
            hi += 1;
        }
        out.push((lo, hi));
    }
    (out, sigma, level)
}

/// One event's peaks over samples `lo..=hi`: the largest positive and negative acceleration
/// and pressure, and its cavitation number Ca = (p_min - p_v) / (rho a_neg gap).
fn measure_event(d: &RigData, (lo, hi): (usize, usize), c: &Coolant, gap: f64) -> Event {
    let w = lo..=hi;
    let amax = d.acceleration[w.clone()]
        .iter()
        .fold(f64::MIN, |m, &x| m.max(x));
    let amin = d.acceleration[w.clone()]
        .iter()
        .fold(f64::MAX, |m, &x| m.min(x));
    let pmax = d.pressure[w.clone()]
        .iter()
        .fold(f64::MIN, |m, &x| m.max(x));
    let pmin = d.pressure[w].iter().fold(f64::MAX, |m, &x| m.min(x));
    let aneg = (-amin).max(0.0);
    Event {
        start_s: d.time[lo],
        end_s: d.time[hi],
        peak_positive_m_s2: amax.max(0.0),
        peak_negative_m_s2: aneg,
        peak_pressure_kpa: pmax / 1e3,
        min_pressure_kpa: pmin / 1e3,
        ca: (pmin - c.vapour_pressure_pa) / (c.density_kg_m3 * aneg * gap),
    }
}

/// The least-squares slope through the origin of the pressure rise against the positive
/// acceleration peak, k_p = sum x y / sum x^2 (y = p_max - p_static), and its R^2
/// (1 when the rises do not vary); None without a positive peak.
fn fit_k_p(events: &[Event], static_pa: f64) -> Option<(f64, f64)> {
    let y = |e: &Event| e.peak_pressure_kpa * 1e3 - static_pa;
    let sxy: f64 = events.iter().map(|e| e.peak_positive_m_s2 * y(e)).sum();
    let sxx: f64 = events.iter().map(|e| e.peak_positive_m_s2.powi(2)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let k_p = sxy / sxx;
    let mean_y = events.iter().map(y).sum::<f64>() / events.len() as f64;
    let ss_res: f64 = events
        .iter()
        .map(|e| (y(e) - k_p * e.peak_positive_m_s2).powi(2))
        .sum();
    let ss_tot: f64 = events.iter().map(|e| (y(e) - mean_y).powi(2)).sum();
    let r2 = if ss_tot > 0.0 {
        1.0 - ss_res / ss_tot
    } else {
        1.0
    };
    Some((k_p, r2))
}

/// Runs the calibration (module doc) on `d`; `file` names the data in errors.
pub fn calibrate(file: &str, d: &RigData, s: &Settings) -> Result<Calibration, CalibrationError> {
    let err = |msg: String| CalibrationError::Data {
        file: file.into(),
        msg,
    };
    let (ranges, sigma, level) = find_events(d, s.quiet);
    if ranges.is_empty() {
        return Err(err(format!(
            "no events found (no acceleration above the detection level {level:.4e} m/s^2)"
        )));
    }
    let c = &s.coolant;
    let mut events: Vec<Event> = ranges
        .iter()
        .map(|&r| measure_event(d, r, c, s.gap))
        .collect();
    // drop events without a negative swing (a one-sided spike has no Ca)
    events.retain(|e| e.peak_negative_m_s2 > level);
    if events.len() < 3 {
        return Err(err(format!(
            "{} event(s) with a negative peak above the detection level {level:.4e} m/s^2; need at least 3",
            events.len()
        )));
    }
    let Some((k_p, fit_r2)) = fit_k_p(&events, c.static_pa) else {
        return Err(err("no positive acceleration peaks to fit k_p".into()));
    };
    // the wall pressure rises with the positive acceleration: a fit below zero says the
    // record's pressures lie below the static pressure given (wrong --static-kpa, or a
    // pressure channel in other units); its thresholds would be nonsense
    if k_p.is_nan() || k_p < 0.0 {
        return Err(err(format!(
            "the pressure peaks fall below the static pressure {:.1} kPa as the acceleration grows (k_p = {k_p:.4e} Pa/(m/s^2), R^2 = {fit_r2:.3}): is --static-kpa the rig's static pressure, and the pressure column in kPa?",
            c.static_pa / 1e3
        )));
    }
    let cav: Vec<f64> = events
        .iter()
        .filter(|e| e.ca < 1.0)
        .map(|e| e.peak_negative_m_s2)
        .collect();
    let safe: Vec<f64> = events
        .iter()
        .filter(|e| e.ca >= 1.0)
        .map(|e| e.peak_negative_m_s2)
        .collect();
    if safe.is_empty() {
        return Err(err(format!(
            "all {} events cavitate (Ca < 1): the onset cannot be bracketed; record weaker events too",
            events.len()
        )));
    }
    if cav.is_empty() {
        return Err(err(format!(
            "no event cavitates (all {} have Ca >= 1, strongest {:.0} m/s^2): the thresholds cannot be bracketed; record stronger events",
            events.len(),
            safe.iter().fold(0.0f64, |m, &x| m.max(x))
        )));
    }
    let min_cav = cav.iter().fold(f64::MAX, |m, &x| m.min(x));
    let max_safe = safe.iter().fold(0.0f64, |m, &x| m.max(x));
    let overlap = min_cav <= max_safe;
    let (onset, high) = if overlap {
        (min_cav, max_safe)
    } else {
        (max_safe, min_cav)
    };
    Ok(Calibration {
        onset_m_s2: onset,
        high_risk_m_s2: high,
        k_p_pa_per_m_s2: k_p,
        events: events.len(),
        cavitating_events: cav.len(),
        fit_r2,
        noise_m_s2: sigma,
        detection_m_s2: level,
        transition_band_observed: overlap,
        model_threshold_m_s2: super::criteria::threshold(c, k_p, s.gap),
        coolant: *c,
        gap_mm: s.gap * 1e3,
        event_list: events,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_csv_is_named() {
        let e = RigData::parse(
            "r.csv",
            "time_s,time_s,acceleration_m_s2,pressure_kpa\n0,1,2,3\n",
        )
        .unwrap_err();
        assert!(e.to_string().contains("'time_s' twice"), "{e}");
        let e =
            RigData::parse("r.csv", "time_s,acceleration_m_s2,pressure_kpa\n0,1,-2\n").unwrap_err();
        assert!(e.to_string().contains("is negative"), "{e}");
        let e = RigData::parse("r.csv", "time_s,acceleration_m_s2\n0,1\n").unwrap_err();
        assert!(
            e.to_string().contains("missing column 'pressure_kpa'"),
            "{e}"
        );
        let e = RigData::parse(
            "r.csv",
            "time_s,acceleration_m_s2,pressure_kpa\n0,1,2\n1,x,2\n",
        )
        .unwrap_err();
        assert!(e.to_string().starts_with("r.csv:3:"), "{e}");
        let e = RigData::parse(
            "r.csv",
            "time_s,acceleration_m_s2,pressure_kpa\n0,1,2\n0,1,2\n",
        )
        .unwrap_err();
        assert!(e.to_string().contains("does not increase"), "{e}");
        let e = RigData::parse("r.csv", "time_s,acceleration_m_s2,pressure_kpa\n0,NaN,2\n")
            .unwrap_err();
        assert!(e.to_string().contains("finite"), "{e}");
    }

    #[test]
    fn events_are_separated_by_quiet_time() {
        let dt = 1e-5;
        let mut d = RigData::default();
        for i in 0..10_000 {
            let t = i as f64 * dt;
            let local = t % 0.02; // an event every 20 ms
            let a = if local < 0.004 {
                1000.0
                    * (-local / 0.001).exp()
                    * (2.0 * std::f64::consts::PI * 1850.0 * local).sin()
            } else {
                0.0
            };
            d.time.push(t);
            d.acceleration.push(a);
            d.pressure.push(240e3);
        }
        let (ev, _, _) = find_events(&d, 2e-3);
        assert_eq!(ev.len(), 5);
    }
}
