//! Statistics over the averaged cycles: means, sample deviations, and standard errors that
//! respect the cycles' correlation.

#[allow(unused_imports)]
use super::*;

/// Largest relative change of any point's peak negative acceleration from `prev` to `peaks`.
pub(super) fn largest_change(peaks: &CyclePeaks, prev: &CyclePeaks) -> f64 {
    let mut change: f64 = 0.0;
    for (x, y) in peaks.negative.iter().zip(&prev.negative) {
        change = change.max((x.value - y.value).abs() / x.value.abs().max(1e-9));
    }
    change
}

/// Per cylinder and point, the statistics of each peak over the cycles in `per_cycle` (all
/// with the same cylinders and points, as one run gives them).
pub(super) fn average_peaks(per_cycle: &[CyclePeaks]) -> CyclePeaks {
    let first = &per_cycle[0];
    let over = |pick: &dyn Fn(&CyclePeaks) -> Peak| -> Peak {
        let v: Vec<Peak> = per_cycle.iter().map(pick).collect();
        Peak::over_cycles(&v)
    };
    CyclePeaks {
        cylinders: first
            .cylinders
            .iter()
            .enumerate()
            .map(|(c, cp)| CylinderPeaks {
                cylinder: cp.cylinder,
                slap_force: over(&|x| x.cylinders[c].slap_force),
                side_force: over(&|x| x.cylinders[c].side_force),
                ..Default::default()
            })
            .collect(),
        negative: Array2::from_shape_fn(first.negative.dim(), |i| over(&|x| x.negative[i])),
        positive: Array2::from_shape_fn(first.positive.dim(), |i| over(&|x| x.positive[i])),
    }
}

/// Standard errors of the cycle means that account for the correlation of consecutive cycles
/// (which slice bounced how often carries over from one slap to the next); sets `se` of every
/// peak in `peaks` (the means of `per_cycle`) and returns the autocorrelation time used.
///
/// For n cycle values P_k of one series with mean m and deviations d_k = P_k - m, the lag-k
/// autocorrelation is pooled over all S series of the run (every cylinder, point and peak
/// kind: one dynamics; 20 cycles are too few to estimate it per series):
///   rho_k = sum_s sum_i d_i d_{i+k} / sum_s sum_i d_i^2,
/// the integrated autocorrelation time tau = 1 + 2 sum_{k=1}^{K} rho_k over the initial run of
/// positive rho_k (Geyer's initial positive sequence; K <= n / 3), clamped to [1, n], and
///   SE = s sqrt(tau / n),  s the sample standard deviation
/// (for independent cycles tau = 1 and SE = s / sqrt(n)). Fewer than 4 cycles: tau = 1.
pub(super) fn standard_errors(per_cycle: &[CyclePeaks], peaks: &mut CyclePeaks) -> f64 {
    let n = per_cycle.len();
    if n < 2 {
        return 1.0;
    }
    // every series of per-cycle values, in a fixed order, with a setter for its peak
    let series = |c: usize, kind: usize, p: usize| -> Vec<f64> {
        per_cycle
            .iter()
            .map(|cyc| match kind {
                0 => cyc.negative[[c, p]].value,
                1 => cyc.positive[[c, p]].value,
                _ => cyc.cylinders[c].slap_force.value,
            })
            .collect()
    };
    let mut all: Vec<(usize, usize, usize, Vec<f64>)> = Vec::new();
    let np = peaks.negative.ncols();
    for c in 0..peaks.cylinders.len() {
        for p in 0..np {
            all.push((c, 0, p, series(c, 0, p)));
            all.push((c, 1, p, series(c, 1, p)));
        }
        all.push((c, 2, 0, series(c, 2, 0)));
    }
    let dev: Vec<Vec<f64>> = all
        .iter()
        .map(|(_, _, _, v)| {
            let m = v.iter().sum::<f64>() / n as f64;
            v.iter().map(|x| x - m).collect()
        })
        .collect();
    let var: f64 = dev.iter().flatten().map(|d| d * d).sum();
    let mut tau = 1.0;
    if n >= 4 && var > 0.0 {
        for k in 1..=n / 3 {
            let cov: f64 = dev
                .iter()
                .map(|d| (0..n - k).map(|i| d[i] * d[i + k]).sum::<f64>())
                .sum();
            let rho = cov / var;
            if rho <= 0.0 {
                break;
            }
            tau += 2.0 * rho;
        }
    }
    let tau = tau.clamp(1.0, n as f64);
    let factor = se_factor(tau, n);
    for (c, kind, p, _) in &all {
        let peak = match kind {
            0 => &mut peaks.negative[[*c, *p]],
            1 => &mut peaks.positive[[*c, *p]],
            _ => &mut peaks.cylinders[*c].slap_force,
        };
        peak.se = peak.std * factor;
    }
    tau
}

/// Mean and sample standard deviation s = sqrt(sum (v_k - mean)^2 / (n - 1)) of a series
/// (0, 0 when empty; s = 0 for one value).
pub fn mean_std(v: &[f64]) -> (f64, f64) {
    let n = v.len();
    if n == 0 {
        return (0.0, 0.0);
    }
    let mean = v.iter().sum::<f64>() / n as f64;
    if n < 2 {
        return (mean, 0.0);
    }
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    (mean, var.sqrt())
}

/// The standard error's factor over the sample deviation for n correlated cycles with
/// autocorrelation time tau: SE = s sqrt(tau / n), tau clamped to [1, n].
pub fn se_factor(tau: f64, n: usize) -> f64 {
    if n == 0 {
        return 0.0;
    }
    (tau.clamp(1.0, n as f64) / n as f64).sqrt()
}
