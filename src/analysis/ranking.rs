//! Which cylinders a ranking separates beyond the uncertainty of their peaks, which are tied
//! within a resolution and which are still open: the decided ranking of pooled realisations
//! (`simulate --rank`, `report`).

use crate::transient::cycle::CycleResult;

/// One analysis point's mean peak from a run or pooled over realisations, with what its
/// uncertainty is made of.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct PeakEstimate {
    /// Mean over the averaged cycles of the per-cycle peak.
    pub mean: f64,
    /// Its standard error (cycles correlated).
    pub se: f64,
    /// The whole-run step check: the same run at half the step, (mean, standard error).
    pub half: Option<(f64, f64)>,
    /// The firing slap's step-error estimate (absolute), the numerical uncertainty without the
    /// whole-run check.
    pub slap_error: f64,
}

impl PeakEstimate {
    /// Pooled over R realisations of equal length (independent: perturbed histories): the
    /// mean of the means, SE = sqrt(sum SE_r^2) / R, the half-step run's likewise (kept only
    /// when every realisation has one), the mean firing-slap estimate.
    pub fn pooled(runs: &[PeakEstimate]) -> PeakEstimate {
        let r = runs.len().max(1) as f64;
        let mean_se = |v: &mut dyn Iterator<Item = (f64, f64)>| {
            let (m, s2) = v.fold((0.0, 0.0), |(m, s2), (x, se)| (m + x, s2 + se * se));
            (m / r, s2.sqrt() / r)
        };
        let half = runs
            .iter()
            .map(|p| p.half)
            .collect::<Option<Vec<_>>>()
            .filter(|h| !h.is_empty())
            .map(|h| mean_se(&mut h.into_iter()));
        let (mean, se) = mean_se(&mut runs.iter().map(|p| (p.mean, p.se)));
        PeakEstimate {
            mean,
            se,
            half,
            slap_error: runs.iter().map(|p| p.slap_error).sum::<f64>() / r,
        }
    }
}

/// A neighbour pair's verdict at a resolution.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// The upper cylinder's peak is higher beyond two standard uncertainties.
    Separated,
    /// The difference is within the resolution beyond two standard uncertainties.
    Tied,
    /// Neither yet.
    Undecided,
}

/// One neighbour pair of a ranking with its difference, uncertainty and verdict.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Decision {
    pub upper: usize,
    pub lower: usize,
    /// D = m_upper - m_lower of the best estimates ([`PeakEstimate::best`]) \[m/s^2\].
    pub difference: f64,
    /// Its combined standard uncertainty u_D = sqrt(s^2 + e^2) \[m/s^2\] ([`pair_terms`]).
    pub uncertainty: f64,
    /// The statistical part s (cycles' scatter, and the scatter of the step check).
    pub scatter: f64,
    /// The step-error part e.
    pub step_error: f64,
    /// The scatter of e's estimate, u(e) (part of `scatter`; 0 without the check).
    pub step_error_scatter: f64,
    pub verdict: Verdict,
}

impl Decision {
    /// Could the pair still be decided when the scatter shrinks by `shrink` (pooling more
    /// realisations)? The step error's own estimate then sheds its noise too: e^2 is
    /// predicted as max(e^2 - u(e)^2, 0) (its unbiased estimate), the scatter as
    /// shrink x s.
    pub fn decidable_with(&self, shrink: f64, resolution: f64) -> bool {
        let e2 = self.step_error.powi(2) - self.step_error_scatter.powi(2);
        let e = e2.max(0.0).sqrt();
        verdict(self.difference, shrink * self.scatter, e, resolution) != Verdict::Undecided
    }
}

impl PeakEstimate {
    /// The best estimate of the mean peak and its standard error: the half-step run's when the
    /// whole-run check was made (twice as accurate), else the run's.
    pub fn best(&self) -> (f64, f64) {
        self.half.unwrap_or((self.mean, self.se))
    }
}

/// The terms of D = m_a - m_b's uncertainty, (s, e, u(e)), u_D^2 = s^2 + e^2. With the whole-run
/// check D is taken at half the step, its step error there e = dD = (m_a - h_a) - (m_b - h_b)
/// (first-order convergence: the error at h/2 equals the change from h to h/2; a step error
/// common to both cylinders cancels), and s^2 = SEh_a^2 + SEh_b^2 + u(e)^2 with u(e)^2 =
/// SE_a^2 + SEh_a^2 + SE_b^2 + SEh_b^2 the scatter of that estimate (the uncorrected bias and
/// its uncertainty root-sum-squared). Without the check: the run's D, s^2 = SE_a^2 + SE_b^2,
/// e^2 = E_a^2 + E_b^2 of the firing-slap estimates and u(e) = 0. Pooling realisations
/// shrinks s, not e.
pub fn pair_terms(a: &PeakEstimate, b: &PeakEstimate) -> (f64, f64, f64) {
    match (a.half, b.half) {
        (Some((ha, sa)), Some((hb, sb))) => {
            let e = (a.mean - ha) - (b.mean - hb);
            let ue2 = a.se * a.se + sa * sa + b.se * b.se + sb * sb;
            ((sa * sa + sb * sb + ue2).sqrt(), e.abs(), ue2.sqrt())
        }
        _ => (a.se.hypot(b.se), a.slap_error.hypot(b.slap_error), 0.0),
    }
}

/// The verdict on a difference `d` with terms (s, e) at `resolution`: separated when
/// d > 2 u, tied when |d| + 2 u <= resolution, undecided otherwise (u = sqrt(s^2 + e^2)).
pub fn verdict(d: f64, s: f64, e: f64, resolution: f64) -> Verdict {
    let u = s.hypot(e);
    if d > 2.0 * u {
        Verdict::Separated
    } else if d.abs() + 2.0 * u <= resolution {
        Verdict::Tied
    } else {
        Verdict::Undecided
    }
}

/// The neighbour pairs of `ranked` (cylinder, estimate), ordered from the highest best
/// estimate, each with its [`verdict`] at `resolution`.
pub fn decide(ranked: &[(usize, PeakEstimate)], resolution: f64) -> Vec<Decision> {
    ranked
        .windows(2)
        .map(|w| {
            let ((ca, a), (cb, b)) = (&w[0], &w[1]);
            let d = a.best().0 - b.best().0;
            let (s, e, ue) = pair_terms(a, b);
            Decision {
                upper: *ca,
                lower: *cb,
                difference: d,
                uncertainty: s.hypot(e),
                scatter: s,
                step_error: e,
                step_error_scatter: ue,
                verdict: verdict(d, s, e, resolution),
            }
        })
        .collect()
}

/// The ranking's resolution: a fraction of the cylinders' mean worst-point peak (issue 38:
/// 2 %).
pub const RESOLUTION: f64 = 0.02;

/// Relative perturbation of the damping ratio per realisation.
pub const PERTURBATION: f64 = 1e-6;

/// One cylinder's worst point, pooled over the realisations.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct WorstPoint {
    pub cylinder: usize,
    /// 1-based analysis point.
    pub point: usize,
    pub peak_negative: PeakEstimate,
}

/// A decided ranking and where it stopped.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct DecidedRanking {
    /// Cylinders from the highest pooled worst-point peak, with those peaks.
    pub order: Vec<WorstPoint>,
    /// Neighbour pairs, higher first, each separated, tied or undecided.
    pub pairs: Vec<Decision>,
    pub resolution_fraction: f64,
    /// The resolution in m/s^2: the fraction of the mean worst-point peak.
    pub resolution_m_s2: f64,
    /// Realisations pooled (each a run and its half-step check) and their averaged cycles.
    pub realisations: usize,
    pub cycles_averaged: usize,
    /// Wall time of all realisations \[s\] and the budget.
    pub seconds: f64,
    pub max_seconds: f64,
    /// Every pair decided, or the budget reached.
    pub decided: bool,
    /// Where it stopped and why, in words.
    pub stopped: String,
}

impl DecidedRanking {
    /// "2 > 5 (+12 +- 5 m/s^2), 5 ~ 4 (...), ..." with ">" separated, "=" tied within the
    /// resolution and "?" undecided.
    pub fn pairs_text(&self) -> String {
        self.pairs
            .iter()
            .map(|d| {
                let sign = match d.verdict {
                    Verdict::Separated => ">",
                    Verdict::Tied => "=",
                    Verdict::Undecided => "?",
                };
                format!(
                    "{} {sign} {} ({:+.0} +- {:.0} m/s^2)",
                    d.upper, d.lower, d.difference, d.uncertainty
                )
            })
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// Every cylinder's and point's estimate of one realisation: the run `base`, its half-step
/// check `half` (same cylinders and points), the firing slap's step-error estimate.
pub fn estimates(base: &CycleResult, half: &CycleResult) -> Vec<Vec<PeakEstimate>> {
    base.peaks
        .iter()
        .enumerate()
        .map(|(ci, c)| {
            let step = base.step_error.iter().find(|e| e.cylinder == c.cylinder);
            base.peak_negative
                .row(ci)
                .iter()
                .zip(half.peak_negative.row(ci))
                .enumerate()
                .map(|(k, (n, h))| PeakEstimate {
                    mean: n.value,
                    se: n.se,
                    half: Some((h.value, h.se)),
                    slap_error: step.map_or(0.0, |e| e.relative(k) * n.value),
                })
                .collect()
        })
        .collect()
}

/// The ranking of pooled realisations (`runs[r][cylinder][point]`, cylinders numbered by
/// `cylinders`): each cylinder's worst point (the largest pooled mean), ordered, and the
/// neighbour pairs decided at [`RESOLUTION`] of the mean worst-point peak.
pub fn rank_of(runs: &[Vec<Vec<PeakEstimate>>], cylinders: &[usize]) -> (Vec<WorstPoint>, f64) {
    let mut order: Vec<WorstPoint> = cylinders
        .iter()
        .enumerate()
        .filter_map(|(ci, &cylinder)| {
            let points = runs.first()?.get(ci)?.len();
            (0..points)
                .map(|k| {
                    let per_run: Vec<PeakEstimate> = runs.iter().map(|r| r[ci][k]).collect();
                    WorstPoint {
                        cylinder,
                        point: k + 1,
                        peak_negative: PeakEstimate::pooled(&per_run),
                    }
                })
                .max_by(|a, b| {
                    a.peak_negative
                        .best()
                        .0
                        .total_cmp(&b.peak_negative.best().0)
                })
        })
        .collect();
    order.sort_by(|a, b| {
        b.peak_negative
            .best()
            .0
            .total_cmp(&a.peak_negative.best().0)
    });
    let mean =
        order.iter().map(|w| w.peak_negative.best().0).sum::<f64>() / order.len().max(1) as f64;
    (order, RESOLUTION * mean)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Verification of the pair rule on hand-computed cases. Without the check: s =
    /// sqrt(3^2 + 4^2) = 5, e = 0, D = 11 > 10 separated. With it (SE 3 and 4, half-step 99
    /// +- 1 and 90 +- 2): D = 99 - 90 = 9, e = (100 - 99) - (90 - 90) = 1, u(e)^2 = 9 + 1 +
    /// 16 + 4 = 30, s = sqrt(1 + 4 + 30) = 5.92, u = 6.0: 9 < 12 undecided.
    #[test]
    fn verification_pair_uncertainty_and_verdicts() {
        let est = |mean, se, half, slap_error| PeakEstimate {
            mean,
            se,
            half,
            slap_error,
        };
        let (a, b) = (est(100.0, 3.0, None, 0.0), est(89.0, 4.0, None, 0.0));
        assert_eq!(pair_terms(&a, &b), (5.0, 0.0, 0.0));
        let d = decide(&[(2, a), (5, b)], 1.0);
        assert_eq!(
            (d[0].upper, d[0].lower, d[0].verdict),
            (2, 5, Verdict::Separated)
        );
        let (a, b) = (
            est(100.0, 3.0, Some((99.0, 1.0)), 7.0),
            est(90.0, 4.0, Some((90.0, 2.0)), 7.0),
        );
        let (s, e, _) = pair_terms(&a, &b);
        assert!((s - 35.0f64.sqrt()).abs() < 1e-12 && (e - 1.0).abs() < 1e-12);
        let d = decide(&[(1, a), (3, b)], 1.0)[0];
        assert_eq!((d.difference, d.verdict), (9.0, Verdict::Undecided));
        // a tie: D = 1, u = 1 (no check, SE 0.6 and 0.8): 1 + 2 <= 3.5
        let (a, b) = (est(100.0, 0.6, None, 0.0), est(99.0, 0.8, None, 0.0));
        assert_eq!(decide(&[(1, a), (3, b)], 3.5)[0].verdict, Verdict::Tied);
        assert_eq!(
            decide(&[(1, a), (3, b)], 2.9)[0].verdict,
            Verdict::Undecided
        );
    }

    /// Verification of pooling: R equal realisations keep the mean and divide the standard
    /// errors by sqrt(R); a realisation without the half-step run drops the pooled one.
    #[test]
    fn verification_pooling_divides_the_standard_error_by_root_r() {
        let p = PeakEstimate {
            mean: 10.0,
            se: 2.0,
            half: Some((9.0, 4.0)),
            slap_error: 1.0,
        };
        let q = PeakEstimate::pooled(&[p; 4]);
        assert!((q.mean - 10.0).abs() < 1e-12 && (q.se - 1.0).abs() < 1e-12);
        assert_eq!(q.half, Some((9.0, 2.0)));
        let r = PeakEstimate::pooled(&[p, PeakEstimate { half: None, ..p }]);
        assert_eq!(r.half, None);
    }
}
