//! Output signals of the transients: second differences of sampled displacements (the
//! acceleration of a displacement record), the zero-phase low-pass to the ROM's band, and peaks
//! located between the samples. Shared by the engine cycle and the windows.

/// Second difference (r_{k+1} - 2 r_k + r_{k-1}) / dt^2 of a sampled series: the acceleration of
/// a quasi-static displacement. `cyclic`: the series is one period; otherwise it is extended
/// by its end values.
pub fn second_difference(r: &[f64], dt: f64, cyclic: bool) -> Vec<f64> {
    let n = r.len();
    if n < 3 {
        return vec![0.0; n];
    }
    let at = |k: isize| -> f64 {
        if cyclic {
            r[k.rem_euclid(n as isize) as usize]
        } else {
            r[k.clamp(0, n as isize - 1) as usize]
        }
    };
    (0..n as isize)
        .map(|k| (at(k + 1) - 2.0 * at(k) + at(k - 1)) / (dt * dt))
        .collect()
}

/// Fourth-order central second difference of a sampled series, the acceleration of a
/// displacement record:
///   a_k = (-r_{k+2} + 16 r_{k+1} - 30 r_k + 16 r_{k-1} - r_{k-2}) / (12 dt^2),
/// the series extended by its end values. For r = cos(omega t) it gives
/// -omega^2 cos(omega t) (1 - (omega dt)^4 / 90 + O((omega dt)^6)).
pub fn second_difference4(r: &[f64], dt: f64) -> Vec<f64> {
    let n = r.len() as isize;
    let at = |k: isize| r[k.clamp(0, n - 1) as usize];
    (0..n)
        .map(|k| {
            (-at(k + 2) + 16.0 * at(k + 1) - 30.0 * at(k) + 16.0 * at(k - 1) - at(k - 2))
                / (12.0 * dt * dt)
        })
        .collect()
}

/// Half length L/2 of the [`low_pass`] FIR at sampling step `dt` and band `band_hz`: the number
/// of samples on each side of an output sample that enter it.
pub fn fir_half_length(dt: f64, band_hz: f64) -> usize {
    ((5.5 / (0.5 * band_hz * dt)) / 2.0).ceil() as usize
}

/// The taps of the [`low_pass`] FIR (2 [`fir_half_length`] + 1 of them, unit DC gain).
pub fn fir_taps(dt: f64, band_hz: f64) -> Vec<f64> {
    let half = fir_half_length(dt, band_hz);
    let fc = 1.25 * band_hz * dt; // cycles per sample
    let len = 2 * half + 1;
    let mut h: Vec<f64> = (0..len)
        .map(|k| {
            let m = k as f64 - half as f64;
            let sinc = if m == 0.0 {
                2.0 * fc
            } else {
                (2.0 * std::f64::consts::PI * fc * m).sin() / (std::f64::consts::PI * m)
            };
            let t = 2.0 * std::f64::consts::PI * k as f64 / (len - 1) as f64;
            let w = 0.42 - 0.5 * t.cos() + 0.08 * (2.0 * t).cos();
            sinc * w
        })
        .collect();
    let sum: f64 = h.iter().sum();
    h.iter_mut().for_each(|v| *v /= sum);
    h
}

/// The [`low_pass`] FIR (not cyclic) applied to many series of one length by FFT with the
/// filter's transform computed once: y_i = sum_k h_k x_ext[i + k], x_ext the series with
/// `half` zeros each side, as `correlate_fft`. Two real series go through one complex
/// transform (x_a + i x_b: the real taps keep the parts apart). Equal to [`low_pass`] to
/// roundoff (relative 1e-15 of the largest |x| sum |h|).
pub struct BatchLowPass {
    n: usize,
    half: usize,
    taps: usize,
    size: usize,
    kernel: Vec<rustfft::num_complex::Complex<f64>>,
    forward: std::sync::Arc<dyn rustfft::Fft<f64>>,
    inverse: std::sync::Arc<dyn rustfft::Fft<f64>>,
}

impl BatchLowPass {
    /// The filter for series of `n` samples at step `dt`, band `band_hz`.
    pub fn new(n: usize, dt: f64, band_hz: f64) -> Self {
        use rustfft::{num_complex::Complex, FftPlanner};
        let h = fir_taps(dt, band_hz);
        let (half, taps) = (h.len() / 2, h.len());
        let size = (n + 2 * half + taps).next_power_of_two();
        let mut planner = FftPlanner::new();
        let (forward, inverse) = (
            planner.plan_fft_forward(size),
            planner.plan_fft_inverse(size),
        );
        let mut kernel = vec![Complex::new(0.0, 0.0); size];
        for (v, &hk) in kernel.iter_mut().zip(h.iter().rev()) {
            v.re = hk / size as f64;
        }
        forward.process(&mut kernel);
        BatchLowPass {
            n,
            half,
            taps,
            size,
            kernel,
            forward,
            inverse,
        }
    }

    /// Filters `a` and `b` (each `n` samples) in place.
    pub fn apply_pair(&self, a: &mut [f64], b: &mut [f64]) {
        use rustfft::num_complex::Complex;
        let mut z = vec![Complex::new(0.0, 0.0); self.size];
        for (i, (&x, &y)) in a.iter().zip(b.iter()).enumerate() {
            z[self.half + i] = Complex::new(x, y);
        }
        self.forward.process(&mut z);
        for (u, v) in z.iter_mut().zip(&self.kernel) {
            *u *= v;
        }
        self.inverse.process(&mut z);
        let first = self.taps - 1;
        for i in 0..self.n {
            a[i] = z[first + i].re;
            b[i] = z[first + i].im;
        }
    }
}

/// Zero-phase low-pass: a symmetric windowed-sinc FIR (Blackman window), h_k =
/// w_k sin(2 pi f_c (k - L/2) T) / (pi (k - L/2)) normalised to unit DC gain, with the cut-off
/// f_c = 1.25 `band_hz` and L = 5.5 / (0.5 band T) + 1 taps (Blackman transition width 5.5/L
/// of the sampling rate): flat (< 0.1 % ripple) up to `band_hz`, > 70 dB down above 1.5
/// `band_hz`. `cyclic`: the series is one period (circular convolution, no ends); otherwise
/// samples beyond the ends count as zero. Returns the filtered series and how many samples at
/// each end the ends affect (L/2; 0 when cyclic).
pub fn low_pass(x: &[f64], dt: f64, band_hz: f64, cyclic: bool) -> (Vec<f64>, usize) {
    let h = fir_taps(dt, band_hz);
    let (half, len) = (h.len() / 2, h.len());
    // x extended by `half` samples each side (wrapped when cyclic, zeros otherwise), so
    // y_i = sum_k h_k x_ext[i + k] with no index arithmetic in the inner loop
    let n = x.len();
    let mut ext = vec![0.0; n + 2 * half];
    for (e, v) in ext.iter_mut().enumerate() {
        let j = e as isize - half as isize;
        if cyclic && n > 0 {
            *v = x[j.rem_euclid(n as isize) as usize];
        } else if j >= 0 && (j as usize) < n {
            *v = x[j as usize];
        }
    }
    let y = if len <= DIRECT_TAPS {
        (0..n)
            .map(|i| super::contact::dot(&h, &ext[i..i + len]))
            .collect()
    } else {
        correlate_fft(&h, &ext, n)
    };
    (y, if cyclic { 0 } else { half })
}

/// Longest filter applied directly (n L multiply-adds); longer ones, which a fine step makes
/// (L grows as 1 / dt, the direct cost as 1 / dt^2: 0.001 deg made 41,800 taps), go through
/// the FFT ([`correlate_fft`], O(n log n)). The default step's filter (167 taps) is direct.
const DIRECT_TAPS: usize = 1024;

/// y_i = sum_k h_k x[i + k] for i < n (x holds n + len(h) - 1 samples) by FFT: the cyclic
/// convolution of x with h reversed on a grid of size N >= len(x) + len(h), whose samples
/// len(h) - 1 .. len(h) - 1 + n are the wanted ones (no wrap-around reaches them). Equal to
/// the direct sum to roundoff (relative 1e-15 of the largest |x| sum |h|).
fn correlate_fft(h: &[f64], x: &[f64], n: usize) -> Vec<f64> {
    use rustfft::{num_complex::Complex, FftPlanner};
    let size = (x.len() + h.len()).next_power_of_two();
    let mut a: Vec<Complex<f64>> = vec![Complex::new(0.0, 0.0); size];
    let mut b = a.clone();
    for (v, &xi) in a.iter_mut().zip(x) {
        v.re = xi;
    }
    for (v, &hk) in b.iter_mut().zip(h.iter().rev()) {
        v.re = hk;
    }
    let mut planner = FftPlanner::new();
    planner.plan_fft_forward(size).process(&mut a);
    planner.plan_fft_forward(size).process(&mut b);
    for (u, v) in a.iter_mut().zip(&b) {
        *u *= v;
    }
    planner.plan_fft_inverse(size).process(&mut a);
    let scale = 1.0 / size as f64;
    (0..n).map(|i| a[h.len() - 1 + i].re * scale).collect()
}

/// Peak of `sign` y (sign +1: largest value, -1: most negative as a positive number) of a
/// band-limited sampled series over the samples `range`, located between the samples: the
/// largest g_k = sign y_k and, where it is a strict local maximum with both neighbours in the
/// series, the vertex of the parabola through g_{k-1}, g_k, g_{k+1},
///   delta = (g_{k-1} - g_{k+1}) / (2 (g_{k-1} - 2 g_k + g_{k+1})),
///   P = g_k - (g_{k-1} - g_{k+1}) delta / 4.
/// Returns (P, k + delta) (the position in samples), None for an empty range. For a sinusoid
/// of angular frequency omega sampled at h (x = omega h) the largest sample under-states the
/// peak by up to 1 - cos(x/2) (x^2/8: 0.8 % at 1.85 kHz, 2.1 % at the low-pass's 4.5 kHz stop
/// edge at the default 21.9 us step); the vertex by at most 9 x^4 / 384 (the peak midway
/// between two samples; 0.35 % at 4.5 kHz, 1e-4 at 1.85 kHz).
pub fn sampled_peak(y: &[f64], range: std::ops::Range<usize>, sign: f64) -> Option<(f64, f64)> {
    let range = range.start.min(y.len())..range.end.min(y.len());
    // the first of equal samples
    let k = range
        .clone()
        .reduce(|a, b| if sign * y[b] > sign * y[a] { b } else { a })?;
    // + 0.0: a flat record's peak is 0, not -0 (sign * 0.0 is -0.0 for sign = -1)
    let g = sign * y[k] + 0.0;
    if k == 0 || k + 1 >= y.len() {
        return Some((g, k as f64));
    }
    let (before, after) = (sign * y[k - 1], sign * y[k + 1]);
    let curvature = before - 2.0 * g + after;
    if curvature.is_nan() || curvature >= 0.0 || before > g || after > g {
        return Some((g, k as f64));
    }
    let delta = 0.5 * (before - after) / curvature;
    Some((g - 0.25 * (before - after) * delta, k as f64 + delta))
}

/// The vertex of the parabola p through three samples (x0, f0), (x1, f1), (x2, f2) whose
/// middle one is the largest (f1 >= f0, f1 >= f2, x0 < x1 < x2), as (x*, p(x*)).
///
/// A parabola's secant slopes d0 = (f1 - f0) / (x1 - x0) and d1 = (f2 - f1) / (x2 - x1) are
/// its slopes at the midpoints m0 = (x0 + x1) / 2 and m1 = (x1 + x2) / 2, so with
/// a = (d1 - d0) / (2 (m1 - m0)) < 0 (half its curvature)
///   p(x) = f1 + p'(x1) (x - x1) + a (x - x1)^2,   p'(x1) = d0 + 2 a (x1 - m0),
///   p'(x*) = 0 at x* = m0 + d0 (m1 - m0) / (d0 - d1).
/// x* lies in \[x0, x2\] (p is concave and p(x1) the largest of the three), so the peak is
/// interpolated, never extrapolated; a flat triple (d0 = d1) returns the middle sample.
/// For a smooth peak sampled at spacing h the error falls from O(h^2) to O(h^3); on even
/// spacing it is [`sampled_peak`]'s vertex.
pub fn parabola_peak(p0: (f64, f64), p1: (f64, f64), p2: (f64, f64)) -> (f64, f64) {
    let (d0, d1) = ((p1.1 - p0.1) / (p1.0 - p0.0), (p2.1 - p1.1) / (p2.0 - p1.0));
    let (m0, m1) = (0.5 * (p0.0 + p1.0), 0.5 * (p1.0 + p2.0));
    if d0 <= d1 {
        return p1;
    }
    let a = 0.5 * (d1 - d0) / (m1 - m0);
    let slope = d0 + 2.0 * a * (p1.0 - m0);
    let x = (m0 + d0 * (m1 - m0) / (d0 - d1)).clamp(p0.0, p2.0);
    let dx = x - p1.0;
    (x, p1.1 + slope * dx + a * dx * dx)
}

#[cfg(test)]
pub(crate) mod tests {

    /// A deterministic pseudo-random sequence in [-0.5, 0.5) (a 64-bit LCG's top 53 bits), for
    /// the unit tests' records.
    pub(crate) fn noise(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }

    /// Verification (peak interpolation): a parabola is its own interpolant, so its vertex
    /// comes back to roundoff (1e-12) from unevenly spaced samples; for cos(x - phi) sampled
    /// at spacing h the interpolated peak is within the interpolation error bound
    /// max|f'''| max|(x - x0)(x - x1)(x - x2)| / 6 = h^3 / (9 sqrt 3) of the true peak 1 at
    /// every phase, where the largest sample alone misses it by up to 1 - cos(h / 2) ~ h^2 / 8.
    #[test]
    fn verification_parabola_peak_recovers_smooth_peaks() {
        let p = |x: f64| 3.0 - 2.0 * (x - 1.3) * (x - 1.3);
        let (xs, f) = parabola_peak((1.0, p(1.0)), (1.25, p(1.25)), (1.9, p(1.9)));
        assert!(
            (xs - 1.3).abs() < 1e-12 && (f - 3.0).abs() < 1e-12,
            "{xs} {f}"
        );
        let h = 0.2f64;
        let bound = h.powi(3) / (9.0 * 3f64.sqrt());
        let mut worst_sample = 0.0f64;
        for k in 0..50 {
            let phi = h * (k as f64 / 50.0 - 0.5);
            let g = |x: f64| (x - phi).cos();
            let (x, f) = parabola_peak((-h, g(-h)), (0.0, g(0.0)), (h, g(h)));
            assert!((f - 1.0).abs() <= bound, "phase {phi}: {f}");
            assert!((x - phi).abs() <= h / 2.0, "phase {phi}: at {x}");
            worst_sample = worst_sample.max(1.0 - g(0.0));
        }
        assert!(worst_sample > 5.0 * bound, "the interpolation matters here");
        // a flat triple gives its middle sample
        assert_eq!(
            parabola_peak((0.0, 1.0), (1.0, 1.0), (2.0, 1.0)),
            (1.0, 1.0)
        );
    }

    /// Verification: the batch filter (one transform of the taps, two real series per
    /// complex transform) equals [`super::low_pass`] (not cyclic) to roundoff: 1e-12 of the
    /// record's scale, as the FFT path's own check; at the default step's 167 taps (the direct
    /// sum in `low_pass`) and at a step that takes 1,469 (its FFT path).
    #[test]
    fn verification_batch_low_pass_equals_the_low_pass() {
        let mut seed = 3u64;
        let mut rnd = || noise(&mut seed);
        for (dt, n) in [(21.93e-6, 3054), (2.5e-6, 4000)] {
            let batch = super::BatchLowPass::new(n, dt, 3000.0);
            let mut a: Vec<f64> = (0..n).map(|_| rnd()).collect();
            let mut b: Vec<f64> = (0..n).map(|_| 1e3 * rnd()).collect();
            let (want_a, _) = super::low_pass(&a, dt, 3000.0, false);
            let (want_b, _) = super::low_pass(&b, dt, 3000.0, false);
            batch.apply_pair(&mut a, &mut b);
            for (got, want, scale) in [(&a, &want_a, 1.0), (&b, &want_b, 1e3)] {
                for (g, w) in got.iter().zip(want) {
                    assert!((g - w).abs() <= 1e-12 * scale, "{g} against {w}");
                }
            }
        }
    }

    /// Verification: the FFT path of the low-pass equals the direct sum to roundoff (the same
    /// taps, a random record; bound 1e-12 of the record's scale: a few ulps per product over
    /// 2,000 taps), cyclic and not.
    #[test]
    fn verification_fft_correlation_equals_the_direct_sum() {
        let mut seed = 7u64;
        let mut rnd = || noise(&mut seed);
        let h: Vec<f64> = (0..2001).map(|_| rnd()).collect();
        let x: Vec<f64> = (0..5000 + 2000).map(|_| rnd()).collect();
        let fast = super::correlate_fft(&h, &x, 5000);
        let scale: f64 = h.iter().map(|v| v.abs()).sum::<f64>() * 0.5;
        for (i, f) in fast.iter().enumerate() {
            let direct: f64 = h.iter().zip(&x[i..]).map(|(a, b)| a * b).sum();
            assert!((f - direct).abs() < 1e-12 * scale, "{i}: {f} {direct}");
        }
    }

    use super::*;

    /// The fourth-order difference of a sampled cosine against its analytical acceleration:
    /// D4 cos(omega t) = -omega^2 cos(omega t) g(x) / x^2 with x = omega h and
    /// g(x) = (32 (1 - cos x) - 2 (1 - cos 2x)) / 12 = x^2 - x^6 / 90 + ..., so the relative
    /// error at every interior sample is at most x^4 / 90 (the series alternates with
    /// decreasing terms for x < 1); the second-order difference's x^2 / 12 is far larger, so
    /// the test tells the two apart. At the default step and the band's 3 kHz: 3e-4.
    #[test]
    fn verification_fourth_order_difference_of_a_cosine() {
        let h = 21.9e-6;
        for f in [500.0, 1855.0, 3000.0, 4500.0] {
            let w = 2.0 * std::f64::consts::PI * f;
            let x = w * h;
            let u: Vec<f64> = (0..200).map(|k| (w * k as f64 * h + 0.3).cos()).collect();
            let a = second_difference4(&u, h);
            let a2 = second_difference(&u, h, false);
            let (mut worst, mut worst2) = (0.0f64, 0.0f64);
            for k in 2..198 {
                let exact = -w * w * u[k];
                worst = worst.max((a[k] - exact).abs() / (w * w));
                worst2 = worst2.max((a2[k] - exact).abs() / (w * w));
            }
            assert!(
                worst <= x.powi(4) / 90.0 * (1.0 + 1e-6) + 1e-9,
                "{f} Hz: {worst}"
            );
            assert!(worst2 > 0.5 * x * x / 12.0, "{f} Hz: {worst2}");
        }
    }

    /// Verification against the analytical peak of a sampled cosine: the error bound of
    /// [`sampled_peak`]'s doc, 9 x^4 / 384, derived for the worst offset (midway), holds at
    /// every offset; and the largest sample alone is worse by the x^2/8 of the doc where the
    /// offset is midway (so the test can tell the vertex from the sample).
    #[test]
    fn verification_sampled_peak_of_a_cosine() {
        let h = 21.9e-6;
        for f in [500.0, 1855.0, 3000.0, 4500.0] {
            let x = 2.0 * std::f64::consts::PI * f * h;
            for i in 0..=20 {
                let offset = i as f64 / 20.0 - 0.5; // true peak at sample 50 + offset
                let y: Vec<f64> = (0..100)
                    .map(|k| -(x * (k as f64 - 50.0 - offset)).cos())
                    .collect();
                // one period of 4.5 kHz is 10 samples: the range holds one peak
                let (p, at) = sampled_peak(&y, 47..54, -1.0).expect("non-empty range");
                let bound = 9.0 * x.powi(4) / 384.0;
                assert!(
                    (p - 1.0).abs() <= bound * (1.0 + 1e-9) + 1e-15,
                    "{f} Hz, {offset}: {p}"
                );
                // position within a tenth of a sample at the band's frequencies
                assert!(
                    (at - 50.0 - offset).abs() < 0.1,
                    "{f} Hz, {offset}: at {at}"
                );
                if i == 0 {
                    let sample = y[47..54].iter().fold(0.0f64, |m, &v| m.max(-v));
                    assert!(1.0 - sample > 0.9 * x * x / 8.0 - x.powi(4) / 300.0);
                }
            }
        }
        // ends and flat tops fall back to the largest sample
        assert_eq!(sampled_peak(&[3.0, 1.0, 0.0], 0..3, 1.0), Some((3.0, 0.0)));
        assert_eq!(sampled_peak(&[1.0, 1.0, 1.0], 0..3, 1.0), Some((1.0, 0.0)));
        assert_eq!(sampled_peak(&[1.0], 1..1, 1.0), None);
    }

    /// Regression: a record that never moves (a piston that never touched) gave the negative
    /// peak -0.0, printed "-0".
    #[test]
    fn regression_a_flat_record_peaks_at_plus_zero() {
        let (p, _) = sampled_peak(&[0.0; 5], 0..5, -1.0).expect("non-empty range");
        assert!(p == 0.0 && p.is_sign_positive(), "{p:?}");
    }

    #[test]
    fn low_pass_keeps_the_band_and_stops_above() {
        let dt = 2e-5;
        let n = 4000;
        let wave = |f: f64| -> Vec<f64> {
            (0..n)
                .map(|i| (2.0 * std::f64::consts::PI * f * i as f64 * dt).sin())
                .collect()
        };
        let amp = |y: &[f64], e: usize| y[e..n - e].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        // in band: gain 1 within the Blackman ripple (~2e-4) plus sampling of the peak
        let (y, e) = low_pass(&wave(1500.0), dt, 3000.0, false);
        assert!((amp(&y, e) - 1.0).abs() < 2e-3, "{}", amp(&y, e));
        // stop band (>= 1.5 band): Blackman side lobes are below -74 dB
        let (y, e) = low_pass(&wave(5000.0), dt, 3000.0, false);
        assert!(amp(&y, e) < 1e-3, "{}", amp(&y, e));
    }
}
