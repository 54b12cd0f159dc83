//! Correlation between crankcase mode-shape coefficients and per-cylinder risk, and between
//! the modes of two models of one structure (MAC).

use crate::reduce::full::{recover_shapes, FullModes};
use crate::reduce::rom::RomBuild;

/// Pearson correlation coefficient r = sum (x - x_mean)(y - y_mean) /
/// sqrt(sum (x - x_mean)^2 sum (y - y_mean)^2); `None` when either series is constant.
pub fn pearson(x: &[f64], y: &[f64]) -> Option<f64> {
    let n = x.len().min(y.len());
    if n < 2 {
        return None;
    }
    let mx = x[..n].iter().sum::<f64>() / n as f64;
    let my = y[..n].iter().sum::<f64>() / n as f64;
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for i in 0..n {
        let (dx, dy) = (x[i] - mx, y[i] - my);
        sxy += dx * dy;
        sxx += dx * dx;
        syy += dy * dy;
    }
    (sxx > 0.0 && syy > 0.0).then(|| sxy / (sxx * syy).sqrt())
}

/// Spearman rank correlation (Pearson of the ranks; ties get their mean rank).
pub fn spearman(x: &[f64], y: &[f64]) -> Option<f64> {
    pearson(&ranks(x), &ranks(y))
}

fn ranks(v: &[f64]) -> Vec<f64> {
    let mut idx: Vec<usize> = (0..v.len()).collect();
    idx.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
    let mut r = vec![0.0; v.len()];
    let mut i = 0;
    while i < idx.len() {
        let mut j = i;
        while j + 1 < idx.len() && v[idx[j + 1]] == v[idx[i]] {
            j += 1;
        }
        let mean = (i + j) as f64 / 2.0 + 1.0;
        for k in i..=j {
            r[idx[k]] = mean;
        }
        i = j + 1;
    }
    r
}

/// MAC(a, b) = (a.b)^2 / ((a.a)(b.b)): 1 for parallel shapes, 0 for orthogonal ones.
pub fn mac(a: &[f64], b: &[f64]) -> f64 {
    let ab: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
    let aa: f64 = a.iter().map(|x| x * x).sum();
    let bb: f64 = b.iter().map(|x| x * x).sum();
    ab * ab / (aa * bb)
}

/// Modes of a model against a reference's, mode by mode.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ModeComparison {
    /// Number of compared modes (the reference's lowest).
    pub modes: usize,
    pub worst_frequency_error: f64,
    pub worst_mac: f64,
    /// Per compared mode: reference and model frequency \[Hz\], relative error, best MAC.
    pub rows: Vec<(f64, f64, f64, f64)>,
}

/// Compares every reference mode j (frequency `ref_hz[j]`, shape `ref_shapes[j]`) with the
/// model's: frequency error |f_j - F_j| / F_j in order, and the best MAC among the model's
/// modes within 1 % of F_j in frequency (close pairs may swap order). The model's lists may
/// be longer than the reference's.
pub fn compare_modes(
    ref_hz: &[f64],
    ref_shapes: &[Vec<f64>],
    model_hz: &[f64],
    model_shapes: &[Vec<f64>],
) -> ModeComparison {
    let n = ref_hz.len().min(model_hz.len());
    let mut rows = Vec::with_capacity(n);
    let (mut worst_f, mut worst_mac) = (0.0f64, 1.0f64);
    for j in 0..n {
        let (fr, ff) = (model_hz[j], ref_hz[j]);
        let rel = (fr - ff).abs() / ff;
        let best = (0..model_hz.len().min(model_shapes.len()))
            .filter(|&k| (model_hz[k] - ff).abs() / ff < 0.01)
            .map(|k| mac(&model_shapes[k], &ref_shapes[j]))
            .fold(0.0, f64::max);
        worst_f = worst_f.max(rel);
        worst_mac = worst_mac.min(best);
        rows.push((ff, fr, rel, best));
    }
    ModeComparison {
        modes: n,
        worst_frequency_error: worst_f,
        worst_mac,
        rows,
    }
}

/// Compares the lowest `n` modes of `reference` with the ROM of `b` (which must have kept its
/// bases) on all part DOFs ([`compare_modes`]); None when the build did not keep them.
pub fn compare_rom_with_full(
    b: &RomBuild,
    reference: &FullModes,
    n: usize,
) -> Option<ModeComparison> {
    let n = n
        .min(reference.frequencies_hz.len())
        .min(b.rom.frequencies_hz.len());
    let extra = (n + 2).min(b.rom.frequencies_hz.len());
    let rom_shapes: Vec<Vec<f64>> = recover_shapes(b, extra)?
        .iter()
        .map(|m| m.concat())
        .collect();
    let full_shapes: Vec<Vec<f64>> = reference.shapes[..n].iter().map(|m| m.concat()).collect();
    Some(compare_modes(
        &reference.frequencies_hz[..n],
        &full_shapes,
        &b.rom.frequencies_hz[..extra],
        &rom_shapes,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn by_hand() {
        // y = 2x + 1: r = 1; reversed: -1; x = [1,2,3], y = [1,3,2]: r = 0.5 by hand
        assert!((pearson(&[1.0, 2.0, 3.0], &[3.0, 5.0, 7.0]).unwrap() - 1.0).abs() < 1e-12);
        assert!((pearson(&[1.0, 2.0, 3.0], &[7.0, 5.0, 3.0]).unwrap() + 1.0).abs() < 1e-12);
        assert!((pearson(&[1.0, 2.0, 3.0], &[1.0, 3.0, 2.0]).unwrap() - 0.5).abs() < 1e-12);
        assert!(pearson(&[1.0, 1.0], &[1.0, 2.0]).is_none());
        assert!((spearman(&[1.0, 10.0, 100.0], &[2.0, 3.0, 4.0]).unwrap() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn mode_comparison_pairs_swapped_close_modes_by_shape() {
        // two close modes in swapped order: frequencies off by 0.5 %, shapes found by MAC
        let e = |i: usize| {
            (0..4)
                .map(|k| f64::from(u8::from(k == i)))
                .collect::<Vec<f64>>()
        };
        let c = compare_modes(
            &[100.0, 100.5],
            &[e(0), e(1)],
            &[100.5, 100.2, 300.0],
            &[e(1), e(0), e(2)],
        );
        assert_eq!(c.modes, 2);
        assert!((c.worst_mac - 1.0).abs() < 1e-12);
        assert!((c.worst_frequency_error - 0.005).abs() < 1e-12);
        assert!((mac(&[1.0, 1.0], &[1.0, 0.0]) - 0.5).abs() < 1e-12);
    }
}
