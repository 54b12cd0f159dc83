//! Certification of computed eigenpairs.
//!
//! - Residual of mode i: r_i = ||K phi_i - lambda_i M phi_i|| / max(||K phi_i||, s ||M phi_i||),
//!   s = min(|sigma|, max(lambda_top, f)), lambda_top the largest computed eigenvalue and f the
//!   shift floor's distance from zero ([`SHIFT_FLOOR`] times the model's
//!   eigenvalue scale; s = |sigma| when every computed mode is a rigid-body mode). For
//!   elastic modes (lambda >> s) this is
//!   ||K phi - lambda M phi|| / ||K phi||; for rigid-body modes, where K phi ~ 0, the shift
//!   sets the scale instead of round-off noise. A shift far from the wanted modes (|sigma| far
//!   beyond them) sets it no higher than they reach: its eigenvalues lambda = sigma + 1 / theta
//!   carry an error of eps |sigma|, which against |sigma| would pass as round-off (`--shift-hz 1e9 --keep-shift` on
//!   a block gave its rigid-body modes at 14-38 Hz, certified).
//! - M-orthonormality: max_ij |phi_i^T M phi_j - delta_ij|.
//! - Sturm count: with sigma_c inside a spectral gap just above the wanted modes, the number of
//!   negative pivots of L D L^T = K - sigma_c M equals the number of eigenvalues below sigma_c
//!   (Sylvester's law of inertia). If it equals the number of computed eigenvalues below
//!   sigma_c, no mode below sigma_c was missed.

use super::shift_invert::Modes;
use crate::linalg::sparse::StiffnessMass;
use serde::Serialize;

fn norm(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// Relative residual of every mode and the M-orthonormality error of the set (see module
/// docs): K Phi and M Phi each in one blocked pass over the matrix ([`crate::linalg::sparse::Pattern::mul_dense`],
/// 16 modes at a time, every entry's sum in the order of a single product), M Phi kept for
/// Phi^T M Phi, the modes' norms and dot products on all cores.
pub fn residuals_and_orthogonality(
    km: &StiffnessMass,
    modes: &Modes,
    sigma: f64,
) -> (Vec<f64>, f64) {
    use rayon::prelude::*;
    let (n, c) = (modes.n, modes.count());
    let phi = faer::MatRef::from_column_major_slice(&modes.vectors[..n * c], n, c);
    let product = |pattern: &crate::linalg::sparse::Pattern, values: &[f64]| {
        let mut y = vec![0.0; n * c];
        let out = faer::MatMut::from_column_major_slice_mut(&mut y, n, c);
        pattern.mul_dense(values, phi, out);
        y
    };
    // M couples like directions only: its products skip the pattern's zeros (the same sums)
    let mass = km.pattern.compress(&km.m);
    let s = residual_scale(&modes.eigenvalues[..c], sigma, km.eigenvalue_scale());
    let (kphi, mphi) = (
        product(&km.pattern, &km.k),
        product(&mass.pattern, &mass.values),
    );
    let residuals = (0..c)
        .into_par_iter()
        .map(|j| {
            let (kx, mx) = (&kphi[j * n..(j + 1) * n], &mphi[j * n..(j + 1) * n]);
            let lam = modes.eigenvalues[j];
            let r = kx
                .iter()
                .zip(mx)
                .map(|(k, m)| (k - lam * m).powi(2))
                .sum::<f64>();
            r.sqrt() / norm(kx).max(s * norm(mx)).max(f64::MIN_POSITIVE)
        })
        .collect();
    (residuals, gram_error(modes, &mphi))
}

/// The residuals' scale s of the module doc: min(|sigma|, max(lambda_top, f)), or |sigma| when
/// the largest computed eigenvalue lambda_top is a rigid-body mode's round-off (below
/// [`RIGID_FRACTION`] of the model's eigenvalue scale `scale`). Never below the floor's f:
/// there a rigid-body mode's round-off would fail the bound however well it is solved (a
/// slender body's wanted modes may all lie below the floor, as its shift does not).
fn residual_scale(eigenvalues: &[f64], sigma: f64, scale: f64) -> f64 {
    let top = eigenvalues.iter().fold(0.0f64, |t, &l| t.max(l));
    if top > RIGID_FRACTION * scale {
        sigma.abs().min(top.max(SHIFT_FLOOR * scale))
    } else {
        sigma.abs()
    }
}

/// max_ij |phi_i^T (M phi_j) - delta_ij| with M Phi given (column-major, as the modes).
fn gram_error(modes: &Modes, mphi: &[f64]) -> f64 {
    use rayon::prelude::*;
    let (n, c) = (modes.n, modes.count());
    (0..c)
        .into_par_iter()
        .map(|i| {
            let phi = modes.vector(i);
            worst((0..c).map(|j| {
                let dot: f64 = phi
                    .iter()
                    .zip(&mphi[j * n..(j + 1) * n])
                    .map(|(a, b)| a * b)
                    .sum();
                let e = if i == j { 1.0 } else { 0.0 };
                (dot - e).abs()
            }))
        })
        .reduce(|| 0.0, |a, b| worst([a, b]))
}

/// The largest of `values` (0 for none), NaN when any is NaN: a certificate's worst figure,
/// where `f64::max` would pass over a NaN and let a failed product certify.
pub fn worst(values: impl IntoIterator<Item = f64>) -> f64 {
    values.into_iter().fold(0.0, |w: f64, v| {
        if w.is_nan() || v.is_nan() {
            f64::NAN
        } else {
            w.max(v)
        }
    })
}

/// Where to place the Sturm shift: the middle of the first gap at or after index `count`
/// whose width exceeds `rel_gap` times max(|lambda_hi|, 1e-6 scale), scale the largest
/// |lambda| computed. Eigenvalues below max(1e-6 scale, `zero`) (rigid-body modes: round-off
/// around zero; `zero` from the model, [`RIGID_FRACTION`]) count as one cluster, and the
/// shift lies above `zero`, so it never falls inside it (where the inertia count is decided
/// by round-off: `modes --count 5` on a free body reported a false mismatch). Returns
/// (sigma_c, number of computed eigenvalues below it) or None when the computed spectrum
/// offers no such gap.
pub fn sturm_shift(
    eigenvalues: &[f64],
    count: usize,
    rel_gap: f64,
    zero: f64,
) -> Option<(f64, usize)> {
    let scale = eigenvalues.iter().fold(0.0f64, |a, &l| a.max(l.abs()));
    let floor = (1e-6 * scale).max(zero);
    (count.max(1)..eigenvalues.len()).find_map(|i| {
        let (lo, hi) = (eigenvalues[i - 1], eigenvalues[i]);
        (hi > zero && hi - lo > rel_gap * hi.abs().max(floor)).then_some((0.5 * (lo + hi), i))
    })
}

/// Eigenvalues below this fraction of the model's scale trace(K) / trace(M)
/// ([`crate::linalg::sparse::StiffnessMass::eigenvalue_scale`]) are rigid-body modes: their
/// computed values are round-off, about 1e-16 of the largest eigenvalues (which a mesh of
/// poorly shaped elements may put 1e4 times above the scale: 1e-12 of it), while a mesh's
/// lowest elastic eigenvalue lies near (h / L)^2 of the scale (h the element size, L the
/// body's), 1e-8 for 1e4 elements along a body: a factor 100 either side.
pub const RIGID_FRACTION: f64 = 1e-10;

/// A negative shift is kept at least this fraction of the eigenvalue scale trace(K) / trace(M)
/// below zero (`floored_shift`, in [`super::modal::certified_modes`]). Closer to zero a free body's
/// rigid-body modes, whose residuals the certificate measures against |sigma| ||M phi|| (this
/// module; never against less than this floor's distance), fail it on round-off alone: K phi of a rigid mode is a sum of terms of the
/// order of the largest eigenvalues that cancel, leaving about 7e-4 ||M phi|| on the default
/// liner (scale 3.6e12; relative residuals 1.7e-5 at 1 Hz, 1.7e-3 at 0.1 Hz, certified from
/// 5 Hz, 2.2e-10 of the scale, 1.7e-9 at the default 100 Hz). At 1e-8 of the scale (30 Hz
/// there) that round-off is 40-50 times below the certificate's bound (2.6e-8 on a free
/// test block); the shift is below zero, hence below every eigenvalue, whatever the model.
pub const SHIFT_FLOOR: f64 = 1e-8;

/// Outcome of the Sturm check, as reported.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct SturmCheck {
    /// Shift of the check \[Hz\] (sqrt(sigma_c) / 2 pi).
    pub shift_hz: f64,
    /// Computed eigenvalues below the shift.
    pub expected: usize,
    /// Negative pivots of K - sigma_c M.
    pub found: usize,
    pub ok: bool,
}

/// Largest relative residual and M-orthonormality error a certified set of modes may have:
/// ARPACK converges the Ritz pairs to machine precision (relative residuals 1e-15..1e-9
/// measured on the test meshes); above 1e-6 the pairs are not eigenpairs to the accuracy a
/// user reads.
pub const RESIDUAL_BOUND: f64 = 1e-6;

/// Why a set of computed modes is not certified (exit 1: the computation failed, not the input).
#[derive(Debug, thiserror::Error)]
pub enum CertificationError {
    #[error("certification failed: the Sturm count at {shift_hz:.1} Hz found {found} eigenvalues below, {expected} were computed (a mode was missed; raise --count or lower --shift-hz)")]
    Missed {
        shift_hz: f64,
        found: usize,
        expected: usize,
    },
    #[error("certification failed: the Sturm count found more eigenvalues below the check's shift than were computed (a mode was missed)")]
    MissedSystemModes,
    #[error("certification failed: largest relative residual {residual:.1e}, M-orthonormality error {orthogonality:.1e} (bound {RESIDUAL_BOUND:.0e})")]
    Residual { residual: f64, orthogonality: f64 },
}

/// The verdict on a part's modes: the Sturm check passed (when one was made), and the largest
/// relative residual ||K x - lambda M x|| / ||K x|| and the M-orthonormality error max
/// |X^T M X - I| are within [`RESIDUAL_BOUND`] (a NaN fails).
pub fn verdict(
    sturm: Option<&SturmCheck>,
    max_residual: f64,
    m_orthogonality_error: f64,
) -> Result<(), CertificationError> {
    if let Some(st) = sturm.filter(|st| !st.ok) {
        return Err(CertificationError::Missed {
            shift_hz: st.shift_hz,
            found: st.found,
            expected: st.expected,
        });
    }
    if !(max_residual <= RESIDUAL_BOUND && m_orthogonality_error <= RESIDUAL_BOUND) {
        return Err(CertificationError::Residual {
            residual: max_residual,
            orthogonality: m_orthogonality_error,
        });
    }
    Ok(())
}

/// The verdict on the coupled engine's modes: `sturm_count_ok` false (more eigenvalues below
/// the check's shift than computed) fails; None (no check made) passes.
pub fn system_verdict(sturm_count_ok: Option<bool>) -> Result<(), CertificationError> {
    match sturm_count_ok {
        Some(false) => Err(CertificationError::MissedSystemModes),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod verdict_tests {
    use super::*;

    /// Regression: the worst figure of a certificate is NaN when any is (`f64::max` passed
    /// over a NaN residual, so a mode with a failed product reported its neighbours' worst and
    /// certified); otherwise the largest, 0 for none.
    #[test]
    fn regression_a_nan_is_the_worst_figure() {
        assert!(worst([1e-12, f64::NAN, 1e-9]).is_nan());
        assert!(worst([f64::NAN]).is_nan());
        assert_eq!(worst([1e-12, 3e-9, 1e-10]), 3e-9);
        assert_eq!(worst(std::iter::empty()), 0.0);
        assert!(verdict(None, worst([1e-12, f64::NAN]), 0.0).is_err());
    }

    /// Verification: each failure is named, a NaN residual fails, a clean set passes.
    #[test]
    fn verification_the_verdict_names_each_failure() {
        let ok = SturmCheck {
            shift_hz: 10.0,
            expected: 20,
            found: 20,
            ok: true,
        };
        assert!(verdict(Some(&ok), 1e-12, 1e-13).is_ok());
        let missed = SturmCheck {
            found: 22,
            ok: false,
            ..ok.clone()
        };
        let e = verdict(Some(&missed), 1e-12, 1e-13)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("found 22") && e.contains("20 were computed"),
            "{e}"
        );
        assert!(matches!(
            verdict(None, f64::NAN, 0.0),
            Err(CertificationError::Residual { .. })
        ));
        assert!(verdict(None, 1e-12, 2e-6).is_err());
        assert!(system_verdict(Some(false)).is_err());
        assert!(system_verdict(None).is_ok() && system_verdict(Some(true)).is_ok());
    }
}
