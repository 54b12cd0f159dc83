//! Frequency response functions of the liner points from the modal model.

/// Inertance (acceleration over force) between two DOFs of a modal model with mass-normalised
/// shapes: A(w) = -w^2 sum_r phi_pr phi_qr / (w_r^2 - w^2 + 2 i zeta w_r w) [m/s^2/N],
/// evaluated at each frequency of `freqs_hz`. `phi_p`, `phi_q` are the two rows (one value per
/// mode), `modes_hz` the modal frequencies, `zeta` the modal damping ratio.
pub fn inertance(
    phi_p: &[f64],
    phi_q: &[f64],
    modes_hz: &[f64],
    zeta: f64,
    freqs_hz: &[f64],
) -> Vec<f64> {
    let tau = 2.0 * std::f64::consts::PI;
    freqs_hz
        .iter()
        .map(|&f| {
            let w = tau * f;
            let (mut h_re, mut h_im) = (0.0, 0.0);
            for ((a, b), fr) in phi_p.iter().zip(phi_q).zip(modes_hz) {
                let wr = tau * fr;
                let (re, im) = (wr * wr - w * w, 2.0 * zeta * wr * w);
                let d = re * re + im * im;
                let num = a * b;
                h_re += num * re / d;
                h_im -= num * im / d;
            }
            w * w * h_re.hypot(h_im)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One mode, mass-normalised (phi = 1/sqrt(m)): at resonance |A| = w^2 / (2 zeta w^2 m)
    /// = 1 / (2 zeta m); far above it |A| -> 1/m (mass line).
    #[test]
    fn single_mode_resonance_and_mass_line() {
        let m: f64 = 2.0;
        let phi = [1.0 / m.sqrt()];
        let a = inertance(&phi, &phi, &[1000.0], 0.02, &[1000.0, 1.0e6]);
        assert!((a[0] - 1.0 / (2.0 * 0.02 * m)).abs() < 1e-9);
        assert!((a[1] - 1.0 / m).abs() < 1e-5);
    }
}
