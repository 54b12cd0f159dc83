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
