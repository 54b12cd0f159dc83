//! Statistics of a sampled study: how likely each risk class is, and which varied key the
//! peaks follow.

/// A proportion k / n with its 95 % Wilson score interval,
///   (p + z^2 / 2n -+ z sqrt(p (1 - p) / n + z^2 / 4n^2)) / (1 + z^2 / n),  z = 1.959964,
/// which stays inside [0, 1] and keeps its coverage near 95 % also for p near 0 or 1 and small
/// n, where the normal interval p -+ z sqrt(p (1 - p) / n) fails (Brown, Cai and DasGupta 2001).
/// For a Latin hypercube it is conservative (stratification lowers the variance of p).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Proportion {
    pub probability: f64,
    pub ci_low: f64,
    pub ci_high: f64,
}

impl Proportion {
    pub fn wilson(k: usize, n: usize) -> Self {
        if n == 0 {
            return Self {
                probability: f64::NAN,
                ci_low: 0.0,
                ci_high: 1.0,
            };
        }
        let z = 1.959_963_984_540_054;
        let (nf, p) = (n as f64, k as f64 / n as f64);
        let d = 1.0 + z * z / nf;
        let centre = (p + z * z / (2.0 * nf)) / d;
        let half = z * (p * (1.0 - p) / nf + z * z / (4.0 * nf * nf)).sqrt() / d;
        Self {
            probability: p,
            ci_low: (centre - half).max(0.0),
            ci_high: (centre + half).min(1.0),
        }
    }
}

/// Spearman rank correlation of every varied key (`x[key][run]`) with every response
/// (`y[response][run]`): `rho[key][response]`, None where either is constant.
pub fn rank_sensitivities(x: &[Vec<f64>], y: &[Vec<f64>]) -> Vec<Vec<Option<f64>>> {
    x.iter()
        .map(|xk| {
            y.iter()
                .map(|yr| super::correlation::spearman(xk, yr))
                .collect()
        })
        .collect()
}

/// What the tables and pictures need of one run (kept in shard parts).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct RunLine {
    /// Index of the run in the design (0-based).
    pub index: usize,
    pub values: Vec<String>,
    /// The run's rows of `sweep.csv` (no header).
    pub csv: String,
    pub cylinders: Vec<CylinderLine>,
}

/// One cylinder of a [`RunLine`].
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct CylinderLine {
    pub cylinder: usize,
    pub slap_force_n: f64,
    pub tilt_rad: f64,
    /// Per analysis point: mean peak negative acceleration [m/s^2] and risk class.
    pub peak_negative_m_s2: Vec<f64>,
    pub risk: Vec<String>,
}

/// One row of `probabilities.csv`: the probability of a risk class at a point over the runs.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ProbabilityRow {
    pub cylinder: usize,
    pub point: usize,
    pub class: &'static str,
    #[serde(flatten)]
    pub p: Proportion,
}

/// Spearman rank correlation of each cylinder's worst-point peak negative acceleration (and
/// the engine's largest) with each varied key over the runs of a sample.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Sensitivities {
    pub keys: Vec<String>,
    pub cylinders: Vec<usize>,
    /// rho\[key\]\[cylinder\] (None: constant), then the engine's largest peak as the last column.
    pub spearman: Vec<Vec<Option<f64>>>,
}

/// For a sampled design: the probability of every risk class at every point
/// ([`Proportion::wilson`]) and the rank sensitivities of the peaks to the keys.
/// `keys` are the varied keys, `lines` the runs (at least one; their values parse as numbers
/// where the key is numeric, NaN otherwise).
pub fn statistics(keys: &[String], lines: &[RunLine]) -> (Vec<ProbabilityRow>, Sensitivities) {
    let n = lines.len();
    let first = &lines[0];
    let mut rows = Vec::new();
    for (ci, c) in first.cylinders.iter().enumerate() {
        for pi in 0..c.risk.len() {
            for class in ["safe", "transitional", "high"] {
                let k = lines
                    .iter()
                    .filter(|l| l.cylinders[ci].risk[pi] == class)
                    .count();
                rows.push(ProbabilityRow {
                    cylinder: c.cylinder,
                    point: pi + 1,
                    class,
                    p: Proportion::wilson(k, n),
                });
            }
        }
    }
    let x: Vec<Vec<f64>> = (0..keys.len())
        .map(|j| {
            lines
                .iter()
                .map(|l| l.values[j].parse::<f64>().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    let mut y: Vec<Vec<f64>> = (0..first.cylinders.len())
        .map(|ci| lines.iter().map(|l| worst_peak(l, ci)).collect())
        .collect();
    y.push(
        lines
            .iter()
            .map(|l| {
                (0..l.cylinders.len())
                    .map(|ci| worst_peak(l, ci))
                    .fold(0.0, f64::max)
            })
            .collect(),
    );
    let sensitivities = Sensitivities {
        keys: keys.to_vec(),
        cylinders: first.cylinders.iter().map(|c| c.cylinder).collect(),
        spearman: rank_sensitivities(&x, &y),
    };
    (rows, sensitivities)
}

/// Largest mean peak negative acceleration over cylinder `ci`'s points in run `l`.
pub fn worst_peak(l: &RunLine, ci: usize) -> f64 {
    l.cylinders[ci]
        .peak_negative_m_s2
        .iter()
        .fold(0.0, |m: f64, &v| m.max(v))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn verification_wilson_interval_against_tabulated_values() {
        // Brown, Cai and DasGupta (2001) / standard tables: k = 0, n = 10 -> [0, 0.2775];
        // k = 5, n = 10 -> [0.2366, 0.7634]; 4 decimals as tabulated
        let a = Proportion::wilson(0, 10);
        assert!(
            a.ci_low == 0.0 && (a.ci_high - 0.2775).abs() < 1e-4,
            "{a:?}"
        );
        let b = Proportion::wilson(5, 10);
        assert!(
            (b.ci_low - 0.2366).abs() < 1e-4 && (b.ci_high - 0.7634).abs() < 1e-4,
            "{b:?}"
        );
        // the interval narrows like 1 / sqrt(n)
        let c = Proportion::wilson(500, 1000);
        assert!(((c.ci_high - c.ci_low) / 2.0 - 1.96 * (0.25f64 / 1000.0).sqrt()).abs() < 1e-3);
    }

    #[test]
    fn rank_sensitivity_follows_a_monotone_response() {
        let x1: Vec<f64> = (0..20).map(|i| i as f64).collect();
        let x2: Vec<f64> = (0..20).map(|i| ((i * 7) % 20) as f64).collect();
        let y: Vec<f64> = x1.iter().map(|v| v.powi(3)).collect();
        let s = rank_sensitivities(&[x1, x2], &[y]);
        assert!((s[0][0].unwrap() - 1.0).abs() < 1e-12);
        assert!(s[1][0].unwrap().abs() < 0.5);
    }
}
