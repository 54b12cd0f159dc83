//! Where to run next in a one-key sweep that looks for the response's maximum
//! (`sweep --refine KEY=LO:HI --runs N`): a sharp feature, such as the slap force's knife-edge
//! about 0.1 mm wide in pin offset, falls between the points of any affordable uniform grid, so
//! the runs are placed where the maximum can lie and where the response changes faster than its
//! uncertainty.
//!
//! Rule. Start with a uniform grid of n_0 = clamp(N / 3, 3, N) points over [LO, HI]. Each next
//! point serves one quantity q in turn (the engine's largest mean slap force, then the largest
//! mean peak acceleration): with k the sampled argmax of q, the maximum of a response that is
//! not sampled finely enough lies between x_k and one of its neighbours, more likely the higher
//! one; the point is the midpoint of that interval (of the wider one when the higher side is
//! less than half as wide). Every third point instead bisects the interval where q changes
//! most against its uncertainty, w_i |y_{i+1} - y_i| / (se_i^2 + se_{i+1}^2)^(1/2) (a feature
//! away from the current maximum). Intervals narrower than (HI - LO) / 1000 are not split.

/// A sampled point: the key's value and, per quantity, the mean and its standard error.
#[derive(Clone, Debug)]
pub struct Sample {
    pub x: f64,
    pub y: Vec<(f64, f64)>,
}

/// The first `n_0` points of a refinement with `runs` runs over [lo, hi].
pub fn initial(lo: f64, hi: f64, runs: usize) -> Vec<f64> {
    let n0 = (runs / 3).clamp(3, runs.max(3)).min(runs);
    if n0 <= 1 {
        return vec![0.5 * (lo + hi)];
    }
    (0..n0)
        .map(|i| lo + (hi - lo) * i as f64 / (n0 - 1) as f64)
        .collect()
}

/// The next point for round `round` (0-based, counted after the initial grid) given the
/// samples so far (any order), or None when every useful interval is narrower than the
/// resolution.
pub fn next(samples: &[Sample], round: usize, lo: f64, hi: f64) -> Option<f64> {
    let mut s: Vec<&Sample> = samples.iter().collect();
    s.sort_by(|a, b| a.x.total_cmp(&b.x));
    let nq = s.first().map_or(0, |x| x.y.len());
    if s.len() < 2 || nq == 0 {
        return None;
    }
    // rounds 0, 1 (mod 3) serve the quantities in turn beside their maxima, round 2 (mod 3)
    // explores, for each quantity in turn
    let q = if round % 3 == 2 {
        (round / 3) % nq
    } else {
        (round % 3) % nq
    };
    let min_width = (hi - lo).abs() / 1000.0;
    let mid = |i: usize| 0.5 * (s[i].x + s[i + 1].x);
    let width = |i: usize| s[i + 1].x - s[i].x;
    if round % 3 != 2 {
        if let Some(i) = beside_maximum(&s, q).filter(|&i| width(i) >= min_width) {
            return Some(mid(i));
        }
    }
    // the interval where q changes most against its uncertainty
    (0..s.len() - 1)
        .filter(|&i| width(i) >= min_width)
        .max_by(|&i, &j| steepness(&s, q, i).total_cmp(&steepness(&s, q, j)))
        .map(mid)
}

/// The interval (its left index) beside the sampled maximum of quantity `q` where the
/// maximum most likely lies: toward the higher neighbour, unless that side is less than half
/// as wide as the other.
fn beside_maximum(s: &[&Sample], q: usize) -> Option<usize> {
    let k = (0..s.len()).max_by(|&a, &b| s[a].y[q].0.total_cmp(&s[b].y[q].0))?;
    let left = (k > 0).then(|| k - 1);
    let right = (k + 1 < s.len()).then_some(k);
    match (left, right) {
        (Some(l), Some(r)) => {
            let (wl, wr) = (s[k].x - s[l].x, s[r + 1].x - s[k].x);
            let higher_left = s[l].y[q].0 >= s[r + 1].y[q].0;
            Some(match (higher_left, wl < 0.5 * wr, wr < 0.5 * wl) {
                (true, false, _) => l,
                (true, true, _) => r,
                (false, _, false) => r,
                (false, _, true) => l,
            })
        }
        (l, r) => l.or(r),
    }
}

/// w |y_{i+1} - y_i| / sqrt(se_i^2 + se_{i+1}^2) (the standard errors floored at 1e-9 of the
/// values' scale, so that one-cycle runs, whose se is 0, compare by the change itself).
fn steepness(s: &[&Sample], q: usize, i: usize) -> f64 {
    let (a, b) = (s[i].y[q], s[i + 1].y[q]);
    let floor = 1e-9 * a.0.abs().max(b.0.abs()).max(1e-300);
    (s[i + 1].x - s[i].x) * (b.0 - a.0).abs() / a.1.hypot(b.1).max(floor)
}

/// The sampled maximum of quantity `q`: (x, mean, se, location uncertainty), the location
/// uncertainty being half the larger spacing to the neighbours (the maximum of the response
/// lies between them).
pub fn maximum(samples: &[Sample], q: usize) -> Option<(f64, f64, f64, f64)> {
    let mut s: Vec<&Sample> = samples.iter().collect();
    s.sort_by(|a, b| a.x.total_cmp(&b.x));
    let k = (0..s.len()).max_by(|&a, &b| s[a].y[q].0.total_cmp(&s[b].y[q].0))?;
    let left = if k > 0 { s[k].x - s[k - 1].x } else { 0.0 };
    let right = if k + 1 < s.len() {
        s[k + 1].x - s[k].x
    } else {
        0.0
    };
    Some((s[k].x, s[k].y[q].0, s[k].y[q].1, 0.5 * left.max(right)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A broad response with a knife-edge 0.12 wide at x = -0.06 (the slap force's shape in
    /// pin offset) and a second, broad quantity peaking at -0.25.
    fn response(x: f64) -> Vec<(f64, f64)> {
        let sharp = 4.2 + 2.0 * (1.0 - x * x) + 1.8 * (1.0 - (x + 0.06).abs() / 0.06).max(0.0);
        let broad = 1700.0 - 800.0 * (x + 0.25).powi(2);
        vec![(sharp, 0.01), (broad, 5.0)]
    }

    fn refine(runs: usize) -> Vec<Sample> {
        let (lo, hi) = (-1.0, 1.0);
        let mut s: Vec<Sample> = initial(lo, hi, runs)
            .into_iter()
            .map(|x| Sample { x, y: response(x) })
            .collect();
        let mut round = 0;
        while s.len() < runs {
            let Some(x) = next(&s, round, lo, hi) else {
                break;
            };
            s.push(Sample { x, y: response(x) });
            round += 1;
        }
        s
    }

    /// Verification: with 15 runs over [-1, 1], both maxima are located within 0.05 of the
    /// true ones (the knife-edge at -0.06, 0.12 wide, and the broad maximum at -0.25), which a
    /// uniform 15-point grid (spacing 0.14) misses for the knife-edge; the located maximum's
    /// reported location uncertainty covers the true one.
    #[test]
    fn verification_refinement_finds_a_knife_edge() {
        let s = refine(15);
        assert_eq!(s.len(), 15);
        let (at, _, _, u) = maximum(&s, 0).unwrap();
        assert!((at + 0.06).abs() < 0.05, "sharp maximum at {at}");
        assert!((at + 0.06).abs() <= u + 1e-12, "{at} +- {u}");
        let (at_b, ..) = maximum(&s, 1).unwrap();
        assert!((at_b + 0.25).abs() < 0.05, "broad maximum at {at_b}");
        // the uniform grid of the same size
        let grid: Vec<Sample> = (0..15)
            .map(|i| -1.0 + 2.0 * i as f64 / 14.0)
            .map(|x| Sample { x, y: response(x) })
            .collect();
        let (g, ..) = maximum(&grid, 0).unwrap();
        assert!((g + 0.06).abs() >= 0.05, "the grid found it too ({g})");
    }

    /// The first points are a uniform grid over the whole range; nothing below the resolution
    /// is split.
    #[test]
    fn verification_initial_grid_and_resolution() {
        assert_eq!(initial(-1.0, 1.0, 15), vec![-1.0, -0.5, 0.0, 0.5, 1.0]);
        assert_eq!(initial(0.0, 1.0, 3), vec![0.0, 0.5, 1.0]);
        let close = vec![
            Sample {
                x: 0.0,
                y: vec![(1.0, 0.0)],
            },
            Sample {
                x: 1e-4,
                y: vec![(2.0, 0.0)],
            },
        ];
        assert_eq!(next(&close, 0, 0.0, 1.0), None);
    }
}

/// The located maximum of one quantity over a refined key: the run with the largest value,
/// its mean and standard error, and where the maximum lies: `at` +- `uncertainty` (half the
/// larger spacing to the neighbouring runs: the response's maximum lies between them).
#[derive(Clone, Debug, serde::Serialize)]
pub struct Maximum {
    pub at: f64,
    pub uncertainty: f64,
    pub value: f64,
    pub value_se: f64,
}

/// [`maximum`] of quantity `q` as a [`Maximum`].
pub fn located(samples: &[Sample], q: usize) -> Option<Maximum> {
    maximum(samples, q).map(|(at, value, value_se, uncertainty)| Maximum {
        at,
        uncertainty,
        value,
        value_se,
    })
}

/// The next point of a refinement ([`next`]) that is neither sampled nor `pending` (not
/// within 1e-12 of the interval of either), advancing `round`; None when no useful interval
/// is left, or at a repeat once `round` exceeds 4 x `runs`.
pub fn next_unsampled(
    samples: &[Sample],
    pending: &[f64],
    round: &mut usize,
    (lo, hi): (f64, f64),
    runs: usize,
) -> Option<f64> {
    loop {
        let x = next(samples, *round, lo, hi)?;
        *round += 1;
        let repeat = pending
            .iter()
            .chain(samples.iter().map(|s| &s.x))
            .any(|b| (b - x).abs() < 1e-12 * (hi - lo));
        if !repeat {
            return Some(x);
        }
        if *round > 4 * runs {
            return None;
        }
    }
}
