//! Dense vector kernels of the modal transient's inner loop: dot products and axpy over the
//! mode count (about a thousand on the default engine), called a few hundred times per step.
//!
//! Each kernel has a plain body with eight partial sums (lane k sums the elements k mod 8) and,
//! chosen at run time when the CPU has AVX2, a version that keeps the eight sums in two AVX
//! registers (two independent addition chains, so the loop is not bound by the addition's
//! latency). Both do the same operations in the same order (no fused multiply-add), so the
//! result is the same bit for bit on every x86-64 machine. The dot products are written with
//! intrinsics: the compiler's own vectorisation of the body interleaves the two sums of
//! `dot_pair` through 128-bit shuffles and ran 3x slower.

/// a . b with eight partial sums s_k = sum_{i = k mod 8} a_i b_i over the first 8 floor(n / 8)
/// elements: ((s_0 + s_4) + (s_1 + s_5)) + ((s_2 + s_6) + (s_3 + s_7)) + tail (summed in order).
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above).
            return unsafe { avx2::dot(a, b) };
        }
    }
    dot_body(a, b)
}

/// (a . b, a . c) in one pass over `a`, each summed as in [`dot`].
pub fn dot_pair(a: &[f64], b: &[f64], c: &[f64]) -> (f64, f64) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above).
            return unsafe { avx2::dot_pair(a, b, c) };
        }
    }
    dot_pair_body(a, b, c)
}

/// y <- y + s x over the common length.
pub fn axpy(y: &mut [f64], s: f64, x: &[f64]) {
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn avx(y: &mut [f64], s: f64, x: &[f64]) {
        axpy_body(y, s, x)
    }
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above).
            return unsafe { avx(y, s, x) };
        }
    }
    axpy_body(y, s, x)
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use std::arch::x86_64::{
        __m256d, _mm256_add_pd, _mm256_loadu_pd, _mm256_mul_pd, _mm256_setzero_pd, _mm256_storeu_pd,
    };

    /// ((s_0 + s_4) + (s_1 + s_5)) + ((s_2 + s_6) + (s_3 + s_7)) of the partial sums s_0..3 in
    /// `lo` and s_4..7 in `hi`.
    #[target_feature(enable = "avx2")]
    unsafe fn reduce(lo: __m256d, hi: __m256d) -> f64 {
        let mut v = [0.0; 4];
        _mm256_storeu_pd(v.as_mut_ptr(), _mm256_add_pd(lo, hi));
        (v[0] + v[1]) + (v[2] + v[3])
    }

    #[target_feature(enable = "avx2")]
    pub unsafe fn dot(a: &[f64], b: &[f64]) -> f64 {
        let n = a.len().min(b.len());
        let m = n - n % 8;
        let (mut lo, mut hi) = (_mm256_setzero_pd(), _mm256_setzero_pd());
        let mut i = 0;
        while i < m {
            // SAFETY: i + 8 <= m <= the length of each slice
            let (pa, pb) = (a.as_ptr().add(i), b.as_ptr().add(i));
            lo = _mm256_add_pd(lo, _mm256_mul_pd(_mm256_loadu_pd(pa), _mm256_loadu_pd(pb)));
            hi = _mm256_add_pd(
                hi,
                _mm256_mul_pd(_mm256_loadu_pd(pa.add(4)), _mm256_loadu_pd(pb.add(4))),
            );
            i += 8;
        }
        let mut t = 0.0;
        for k in m..n {
            t += a[k] * b[k];
        }
        reduce(lo, hi) + t
    }

    #[target_feature(enable = "avx2")]
    pub unsafe fn dot_pair(a: &[f64], b: &[f64], c: &[f64]) -> (f64, f64) {
        let n = a.len().min(b.len()).min(c.len());
        let m = n - n % 8;
        let (mut s_lo, mut s_hi) = (_mm256_setzero_pd(), _mm256_setzero_pd());
        let (mut t_lo, mut t_hi) = (_mm256_setzero_pd(), _mm256_setzero_pd());
        let mut i = 0;
        while i < m {
            // SAFETY: i + 8 <= m <= the length of each slice
            let (pa, pb, pc) = (a.as_ptr().add(i), b.as_ptr().add(i), c.as_ptr().add(i));
            let (x0, x1) = (_mm256_loadu_pd(pa), _mm256_loadu_pd(pa.add(4)));
            s_lo = _mm256_add_pd(s_lo, _mm256_mul_pd(x0, _mm256_loadu_pd(pb)));
            s_hi = _mm256_add_pd(s_hi, _mm256_mul_pd(x1, _mm256_loadu_pd(pb.add(4))));
            t_lo = _mm256_add_pd(t_lo, _mm256_mul_pd(x0, _mm256_loadu_pd(pc)));
            t_hi = _mm256_add_pd(t_hi, _mm256_mul_pd(x1, _mm256_loadu_pd(pc.add(4))));
            i += 8;
        }
        let (mut ss, mut tt) = (0.0, 0.0);
        for k in m..n {
            ss += a[k] * b[k];
            tt += a[k] * c[k];
        }
        (reduce(s_lo, s_hi) + ss, reduce(t_lo, t_hi) + tt)
    }
}

#[inline(always)]
fn dot_body(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut s = [0.0; 8];
    for (x, y) in a.chunks_exact(8).zip(b.chunks_exact(8)) {
        for k in 0..8 {
            s[k] += x[k] * y[k];
        }
    }
    let mut t = 0.0;
    for k in n - n % 8..n {
        t += a[k] * b[k];
    }
    reduce8(&s) + t
}

#[inline(always)]
fn dot_pair_body(a: &[f64], b: &[f64], c: &[f64]) -> (f64, f64) {
    let n = a.len().min(b.len()).min(c.len());
    let (a, b, c) = (&a[..n], &b[..n], &c[..n]);
    let mut s = [0.0; 8];
    let mut t = [0.0; 8];
    for ((x, y), z) in a
        .chunks_exact(8)
        .zip(b.chunks_exact(8))
        .zip(c.chunks_exact(8))
    {
        for k in 0..8 {
            s[k] += x[k] * y[k];
            t[k] += x[k] * z[k];
        }
    }
    let (mut ss, mut tt) = (0.0, 0.0);
    for k in n - n % 8..n {
        ss += a[k] * b[k];
        tt += a[k] * c[k];
    }
    (reduce8(&s) + ss, reduce8(&t) + tt)
}

/// ((s_0 + s_4) + (s_1 + s_5)) + ((s_2 + s_6) + (s_3 + s_7)).
#[inline(always)]
fn reduce8(s: &[f64; 8]) -> f64 {
    ((s[0] + s[4]) + (s[1] + s[5])) + ((s[2] + s[6]) + (s[3] + s[7]))
}

#[inline(always)]
fn axpy_body(y: &mut [f64], s: f64, x: &[f64]) {
    for (yi, &xi) in y.iter_mut().zip(x) {
        *yi += s * xi;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both compilations against a plain loop summed in the documented order (exact equality:
    /// the same operations in the same order), over lengths with tails 0-7.
    #[test]
    fn kernels_match_the_documented_summation_order() {
        for n in [0usize, 1, 3, 7, 8, 9, 15, 16, 947, 1001] {
            let a: Vec<f64> = (0..n)
                .map(|i| ((i * 37 % 101) as f64 - 50.0) / 7.0)
                .collect();
            let b: Vec<f64> = (0..n)
                .map(|i| ((i * 53 % 89) as f64 - 44.0) / 3.0)
                .collect();
            let c: Vec<f64> = (0..n).map(|i| 1.0 / (1.0 + i as f64)).collect();
            let reference = |x: &[f64], y: &[f64]| {
                let mut s = [0.0; 8];
                for i in 0..n - n % 8 {
                    s[i % 8] += x[i] * y[i];
                }
                let mut t = 0.0;
                for i in n - n % 8..n {
                    t += x[i] * y[i];
                }
                ((s[0] + s[4]) + (s[1] + s[5])) + ((s[2] + s[6]) + (s[3] + s[7])) + t
            };
            assert_eq!(dot(&a, &b).to_bits(), reference(&a, &b).to_bits());
            assert_eq!(dot_body(&a, &b).to_bits(), reference(&a, &b).to_bits());
            let (p, q) = dot_pair(&a, &b, &c);
            assert_eq!(p.to_bits(), reference(&a, &b).to_bits());
            assert_eq!(q.to_bits(), reference(&a, &c).to_bits());
            let mut y = c.clone();
            axpy(&mut y, 0.5, &a);
            for i in 0..n {
                assert_eq!(y[i].to_bits(), (c[i] + 0.5 * a[i]).to_bits());
            }
        }
    }
}
