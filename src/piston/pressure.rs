//! Cylinder pressure over the 720 deg four-stroke cycle: a measured table from CSV, or the
//! built-in single-zone Wiebe curve.
//!
//! Crank angles are the cylinder's own, firing top dead centre at 360 deg, gas-exchange TDC at
//! 0/720. Pressures are absolute \[Pa\]; the table is periodic over 720 deg and interpolated
//! linearly.
//!
//! Built-in curve (closed cycle from bottom dead centre, 180 deg, to exhaust valve opening):
//!   dp/dtheta = -n p / V dV/dtheta + (n - 1) / V dQ/dtheta,
//!   Q(theta) = Q_tot (1 - exp(-a x^(m+1))),  x = (theta - theta_soc) / dtheta_comb in [0, 1]
//! (Wiebe), V = V_c + A (z_top - z(theta)), V_c = A 2r / (eps - 1), integrated by RK4 in
//! 0.1 deg steps. Intake stroke at the intake pressure, exhaust stroke at the exhaust pressure,
//! a blowdown p = p_exh + (p_evo - p_exh) exp(-(theta - theta_evo) / 15 deg) after exhaust
//! valve opening. Heat released and intake pressure scale with the load fraction.

use super::kinematics::CrankSlider;
use std::path::{Path, PathBuf};

pub use crate::scene::spec::Wiebe;

/// A pressure curve that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum PressureError {
    #[error("{}: cannot read the pressure file: {source}", path.display())]
    Io {
        path: PathBuf,
        source: crate::files::ReadError,
    },
    #[error("{}: line {line}: {msg}", path.display())]
    Line {
        path: PathBuf,
        line: usize,
        msg: String,
    },
    #[error("{}: {msg}", path.display())]
    Table { path: PathBuf, msg: String },
}

/// Absolute cylinder pressure over the cycle, periodic in 720 deg.
#[derive(Clone, Debug, PartialEq)]
pub struct PressureCurve {
    angles_deg: Vec<f64>,
    pa: Vec<f64>,
}

/// Largest relative difference between a table's first row and a closing row 720 deg later
/// that is taken as the same point of the periodic cycle (a measured cycle's ends differ by
/// the cycle-to-cycle scatter, well under this).
const CLOSING_ROW_TOLERANCE: f64 = 0.01;

/// Drops a closing row: a table whose last row lies 720 deg after its first gives one crank
/// angle of the periodic cycle twice. Within [`CLOSING_ROW_TOLERANCE`] of the first row's
/// pressure it is dropped; otherwise the table is refused, naming both pressures.
fn close_cycle(path: &Path, angles: &mut Vec<f64>, pa: &mut Vec<f64>) -> Result<(), PressureError> {
    let n = angles.len();
    if n < 3 || angles[n - 1] - angles[0] != 720.0 {
        return Ok(());
    }
    let (p0, p1) = (pa[0], pa[n - 1]);
    if (p1 - p0).abs() > CLOSING_ROW_TOLERANCE * p0 {
        return Err(PressureError::Table {
            path: path.into(),
            msg: format!(
                "the rows at {} and {} deg are the same point of the periodic cycle but give {} and {} bar: drop the last row, or make them agree",
                crate::text::num(angles[0]),
                crate::text::num(angles[n - 1]),
                crate::text::num(p0 / 1e5),
                crate::text::num(p1 / 1e5)
            ),
        });
    }
    angles.pop();
    pa.pop();
    Ok(())
}

impl PressureCurve {
    /// Reads `crank_angle_deg,pressure_bar` (header line required; angles strictly increasing
    /// within [0, 720], spanning less than 720 deg; pressures finite and positive).
    pub fn from_csv(path: &Path) -> Result<Self, PressureError> {
        let text = crate::files::read_text(path, crate::files::LIMIT_TEXT).map_err(|source| {
            PressureError::Io {
                path: path.into(),
                source,
            }
        })?;
        Self::parse(path, &text)
    }

    /// Parses CSV text; `path` names the source in errors.
    pub fn parse(path: &Path, text: &str) -> Result<Self, PressureError> {
        let line_err = |line: usize, msg: String| PressureError::Line {
            path: path.into(),
            line,
            msg,
        };
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty());
        let (hl, header) = lines.next().ok_or_else(|| PressureError::Table {
            path: path.into(),
            msg: "is empty; expected the header 'crank_angle_deg,pressure_bar'".into(),
        })?;
        let cols: Vec<&str> = header.split(',').map(str::trim).collect();
        let wanted = ["crank_angle_deg", "pressure_bar"];
        if let Some(c) = crate::text::repeated_column(&cols, &wanted) {
            let msg = format!("the header names column '{c}' twice: give each column once");
            return Err(line_err(hl + 1, msg));
        }
        let ia = cols.iter().position(|c| *c == "crank_angle_deg");
        let ip = cols.iter().position(|c| *c == "pressure_bar");
        let (Some(ia), Some(ip)) = (ia, ip) else {
            return Err(line_err(hl + 1, missing_columns(header)));
        };
        let (mut angles_deg, mut pa) = (Vec::new(), Vec::new());
        for (i, l) in lines {
            let f: Vec<&str> = l.split(',').map(str::trim).collect();
            if f.len() != cols.len() {
                return Err(line_err(
                    i + 1,
                    crate::text::field_count_message(f.len(), cols.len()),
                ));
            }
            let get = |k: usize, name: &str| -> Result<f64, PressureError> {
                let s = f
                    .get(k)
                    .ok_or_else(|| line_err(i + 1, format!("missing column '{name}'")))?;
                let v: f64 = s
                    .parse()
                    .map_err(|_| line_err(i + 1, format!("'{name}' is not a number: '{s}'")))?;
                if !v.is_finite() {
                    return Err(line_err(i + 1, format!("'{name}' is not finite: '{s}'")));
                }
                Ok(v)
            };
            let a = get(ia, "crank_angle_deg")?;
            let p = get(ip, "pressure_bar")?;
            if !(0.0..=720.0).contains(&a) {
                return Err(line_err(
                    i + 1,
                    format!("crank angle {} deg outside [0, 720]", crate::text::exact(a)),
                ));
            }
            if angles_deg.last().is_some_and(|&last| a <= last) {
                return Err(line_err(
                    i + 1,
                    format!(
                        "crank angle {} deg does not increase",
                        crate::text::exact(a)
                    ),
                ));
            }
            if p <= 0.0 {
                return Err(line_err(
                    i + 1,
                    format!(
                        "pressure {} bar must be positive (absolute)",
                        crate::text::exact(p)
                    ),
                ));
            }
            if p > MAX_BAR {
                return Err(line_err(
                    i + 1,
                    format!("pressure {} bar is beyond any engine's ({MAX_BAR} bar at most; is the column in Pa or kPa?)", crate::text::num(p)),
                ));
            }
            angles_deg.push(a);
            pa.push(p * 1e5);
        }
        close_cycle(path, &mut angles_deg, &mut pa)?;
        if angles_deg.len() < 2 || angles_deg[angles_deg.len() - 1] - angles_deg[0] >= 720.0 {
            return Err(PressureError::Table {
                path: path.into(),
                msg: "needs at least two rows spanning less than 720 deg (the curve is periodic)"
                    .into(),
            });
        }
        if let Some(msg) = coverage_gap(&angles_deg) {
            return Err(PressureError::Table {
                path: path.into(),
                msg,
            });
        }
        Ok(Self { angles_deg, pa })
    }

    /// The built-in curve of `w` for the cylinder geometry (bore area `area` [m^2]).
    pub fn wiebe(w: &Wiebe, kin: &CrankSlider, area: f64) -> Self {
        let load = w.load;
        let p_int = 1e5 + (w.intake_pa - 1e5) * load;
        let p_exh = p_int + w.exhaust_over_intake_pa;
        let q_tot = w.heat_j * load;
        let vc = area * 2.0 * kin.radius / (w.compression_ratio - 1.0);
        let ztop = kin.z_top();
        let rad = std::f64::consts::PI / 180.0;
        let vol = |deg: f64| vc + area * (ztop - kin.at(deg * rad).z);
        let dq = |deg: f64| {
            let x = (deg - w.start_deg) / w.duration_deg;
            if !(0.0..=1.0).contains(&x) || q_tot == 0.0 {
                return 0.0;
            }
            q_tot * w.a * (w.m + 1.0) / w.duration_deg
                * x.powf(w.m)
                * (-w.a * x.powf(w.m + 1.0)).exp()
        };
        let n = w.polytropic;
        let h = 0.1;
        let rhs = |deg: f64, p: f64| {
            let v = vol(deg);
            let dv = (vol(deg + 1e-4) - vol(deg - 1e-4)) / 2e-4;
            -n * p / v * dv + (n - 1.0) / v * dq(deg)
        };
        let steps = 7200;
        let mut angles_deg = Vec::with_capacity(steps);
        let mut pa = Vec::with_capacity(steps);
        let mut p = p_int;
        let mut p_evo = p_int;
        for i in 0..steps {
            let deg = i as f64 * h;
            let value = if deg <= 180.0 {
                p_int
            } else if deg <= w.evo_deg {
                p
            } else {
                p_exh + (p_evo - p_exh) * (-(deg - w.evo_deg) / 15.0).exp()
            };
            angles_deg.push(deg);
            pa.push(value);
            if deg >= 180.0 && deg < w.evo_deg {
                let k1 = rhs(deg, p);
                let k2 = rhs(deg + h / 2.0, p + h / 2.0 * k1);
                let k3 = rhs(deg + h / 2.0, p + h / 2.0 * k2);
                let k4 = rhs(deg + h, p + h * k3);
                p += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
                p_evo = p;
            }
        }
        Self { angles_deg, pa }
    }

    /// Pressure \[Pa\] at crank angle `deg` (any value; periodic in 720 deg).
    pub fn at(&self, deg: f64) -> f64 {
        let a0 = self.angles_deg[0];
        let x = a0 + (deg - a0).rem_euclid(720.0);
        let n = self.angles_deg.len();
        let i = self.angles_deg.partition_point(|&a| a <= x);
        let (a, pa_a, b, pb) = if i == 0 || i == n {
            // between the last sample and the first one + 720
            let (a, b) = (self.angles_deg[n - 1], self.angles_deg[0] + 720.0);
            let xx = if x < a { x + 720.0 } else { x };
            return self.pa[n - 1] + (self.pa[0] - self.pa[n - 1]) * (xx - a) / (b - a);
        } else {
            (
                self.angles_deg[i - 1],
                self.pa[i - 1],
                self.angles_deg[i],
                self.pa[i],
            )
        };
        pa_a + (pb - pa_a) * (x - a) / (b - a)
    }

    /// Peak pressure \[Pa\] and its crank angle \[deg\].
    pub fn peak(&self) -> (f64, f64) {
        let (i, p) = self
            .pa
            .iter()
            .enumerate()
            .fold((0, f64::MIN), |b, (i, &p)| if p > b.1 { (i, p) } else { b });
        (p, self.angles_deg[i])
    }

    /// The samples (angle \[deg\], pressure \[Pa\]) as stored.
    pub fn samples(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.angles_deg.iter().copied().zip(self.pa.iter().copied())
    }
}

/// Largest cylinder pressure a table may hold \[bar\]: peak firing pressures of heavy-duty
/// diesels are 200-300 bar; a larger value is a unit mistake (Pa or kPa), and 1e308 bar would
/// overflow to infinity in Pa.
pub const MAX_BAR: f64 = 1000.0;

/// Largest gap allowed between consecutive table angles, the wrap from the last to the first
/// through 720/0 deg included \[deg\]: a four-stroke table must cover the whole cycle (a trace of
/// one revolution, or of the firing part only, would otherwise be read as a periodic 720 deg
/// curve and interpolated across the missing strokes without a word).
pub const MAX_GAP_DEG: f64 = 45.0;

/// Why the table's angles do not cover the cycle, or None: the largest gap
/// max(theta_{i+1} - theta_i, theta_0 + 720 - theta_last) must not exceed [`MAX_GAP_DEG`].
fn coverage_gap(angles: &[f64]) -> Option<String> {
    let n = angles.len();
    let wrap = angles[0] + 720.0 - angles[n - 1];
    let (gap, from, to) = angles.windows(2).map(|w| (w[1] - w[0], w[0], w[1])).fold(
        (wrap, angles[n - 1], angles[0]),
        |m, x| if x.0 > m.0 { x } else { m },
    );
    (gap > MAX_GAP_DEG).then(|| {
        format!(
            "covers {}-{} deg with a gap of {} deg from {} to {} deg (through 720/0 when the second is smaller); a four-stroke pressure table needs samples over the whole 0-720 deg cycle, at most {} deg apart (firing TDC at 360 deg)",
            crate::text::num(angles[0]),
            crate::text::num(angles[n - 1]),
            crate::text::num(gap),
            crate::text::num(from),
            crate::text::num(to),
            MAX_GAP_DEG
        )
    })
}

/// The message for a header without the two columns (quoted at most 200 characters: a file
/// without a line end it knows is one header line).
fn missing_columns(header: &str) -> String {
    format!(
        "header must name the columns 'crank_angle_deg' and 'pressure_bar', got '{}'",
        crate::text::clipped(header, 200)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kin() -> CrankSlider {
        CrankSlider {
            radius: 0.0705,
            rod: 0.219,
            offset: 0.0,
            omega: 199.0,
        }
    }

    fn wiebe(load: f64, heat_j: f64) -> Wiebe {
        Wiebe {
            compression_ratio: 17.0,
            intake_pa: 2.6e5,
            exhaust_over_intake_pa: 0.3e5,
            start_deg: 356.0,
            duration_deg: 55.0,
            a: 6.9,
            m: 1.0,
            heat_j,
            polytropic: 1.35,
            evo_deg: 500.0,
            load,
        }
    }

    #[test]
    fn motored_curve_is_polytropic() {
        // No heat release: p V^n constant on the closed cycle, so TDC pressure is
        // p_int eps^n (the offset-free slider reaches V_c exactly at 360 deg). RK4 at
        // 0.1 deg: relative error well below 1e-6.
        let k = kin();
        let area = std::f64::consts::PI * 0.115f64.powi(2) / 4.0;
        let c = PressureCurve::wiebe(&wiebe(1.0, 0.0), &k, area);
        let expect = 2.6e5 * 17f64.powf(1.35);
        assert!(
            (c.at(360.0) / expect - 1.0).abs() < 1e-6,
            "{} vs {expect}",
            c.at(360.0)
        );
        // symmetric about TDC on the closed part
        assert!((c.at(300.0) / c.at(420.0) - 1.0).abs() < 1e-6);
    }

    /// p = 1 + 100 max(0, 1 - |theta - 360| / 180) bar.
    fn triangle(t: f64) -> f64 {
        1.0 + 100.0 * (1.0 - (t - 360.0).abs() / 180.0).max(0.0)
    }

    /// [`triangle`] every 30 deg over 0-690 deg as CSV rows, linear between samples (its kinks
    /// at 180, 360 and 540 are samples), so the interpolation is exact.
    fn triangle_rows() -> String {
        (0..24)
            .map(|k| format!("{},{}\n", 30 * k, triangle(30.0 * k as f64)))
            .collect()
    }

    #[test]
    fn csv_table_interpolates_periodically_and_names_bad_lines() {
        let p = Path::new("p.csv");
        let (f, table) = (triangle, triangle_rows());
        let c = PressureCurve::parse(p, &format!("crank_angle_deg,pressure_bar\n{table}")).unwrap();
        for t in [100.0, 275.0, 372.5, 705.0] {
            assert!((c.at(t) - f(t) * 1e5).abs() < 1e-6, "{t}");
        }
        assert!((c.at(1080.0) - 101e5).abs() < 1e-6);
        // a partial trace (firing part only) and one revolution of a four-stroke cycle
        for rows in [
            "0,1\n50,2\n99,80\n",
            "0,1\n120,2\n240,20\n300,60\n360,150\n",
        ] {
            let e = PressureCurve::parse(p, &format!("crank_angle_deg,pressure_bar\n{rows}"))
                .unwrap_err()
                .to_string();
            assert!(e.contains("p.csv") && e.contains("whole 0-720 deg"), "{e}");
        }
        let e = PressureCurve::parse(p, "crank_angle_deg,pressure_bar,pressure_bar\n0,1,2\n")
            .unwrap_err();
        assert!(e.to_string().contains("'pressure_bar' twice"), "{e}");
        let e = PressureCurve::parse(p, "crank_angle_deg,pressure_bar\n0,1\n10,NaN\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 3") && e.contains("not finite"), "{e}");
        let e = PressureCurve::parse(p, "crank_angle_deg,pressure_bar\n10,1\n5,2\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("line 3") && e.contains("does not increase"),
            "{e}"
        );
        let e = PressureCurve::parse(p, "angle,p\n0,1\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 1"), "{e}");
    }

    /// Regression (issue 40): a closed-cycle table, its 720 deg row repeating the 0 deg one, was
    /// refused ("needs at least two rows spanning less than 720 deg") though it is legal; it
    /// now reads as the same table without the closing row, and closing rows that disagree
    /// are refused with both pressures named.
    #[test]
    fn regression_a_closing_row_at_720_deg_is_the_first_row_again() {
        let p = Path::new("p.csv");
        let (f, open) = (triangle, triangle_rows());
        let parse =
            |rows: &str| PressureCurve::parse(p, &format!("crank_angle_deg,pressure_bar\n{rows}"));
        let closed = parse(&format!("{open}720,{}\n", f(0.0))).unwrap();
        assert_eq!(closed, parse(&open).unwrap());
        let e = parse(&format!("{open}720,5\n")).unwrap_err().to_string();
        assert!(e.contains("0 and 720 deg") && e.contains("5 bar"), "{e}");
    }
}
