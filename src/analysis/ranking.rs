//! Which cylinders a ranking separates beyond the uncertainty of their peaks, and which are
//! tied.

/// One neighbour pair of a ranking, from the higher to the lower.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct RankStep {
    pub upper: usize,
    pub lower: usize,
    /// The two are separated beyond their combined uncertainty (else tied).
    pub separated: bool,
}

/// The neighbour pairs of `ranked` = (cylinder, mean peak m, standard uncertainty u), ordered
/// from the highest m: a pair counts as separated when m1 - m2 > 2 sqrt(u1^2 + u2^2) (two
/// combined standard uncertainties), and as tied otherwise. u combines the statistical and
/// the numerical uncertainty of a mean peak, u = sqrt(SE^2 + E^2) (standard error, cycles
/// correlated, and estimated step error).
pub fn separations(ranked: &[(usize, f64, f64)]) -> Vec<RankStep> {
    ranked
        .windows(2)
        .map(|w| {
            let ((c1, m1, u1), (c2, m2, u2)) = (w[0], w[1]);
            RankStep {
                upper: c1,
                lower: c2,
                separated: m1 - m2 > 2.0 * u1.hypot(u2),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Verification of the rule on hand-computed cases: 2 sqrt(3^2 + 4^2) = 10.
    #[test]
    fn verification_separation_at_two_combined_uncertainties() {
        let s = separations(&[(2, 120.0, 3.0), (5, 109.0, 4.0), (1, 100.0, 4.0)]);
        assert_eq!(s.len(), 2);
        assert!(s[0].separated, "11 > 10");
        assert_eq!((s[0].upper, s[0].lower), (2, 5));
        // 9 < 2 sqrt(32) = 11.3
        assert!(!s[1].separated);
        assert!(separations(&[(1, 1.0, 0.0)]).is_empty());
    }
}
