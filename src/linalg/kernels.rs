//! Dense vector kernels of the modal transient's inner loop: dot products and axpy over the
//! mode count (about a thousand on the default engine), called a few hundred times per step.
//!
//! Each kernel has a plain body with four partial sums (lane k sums the elements k mod 4) and,
//! chosen at run time when the CPU has AVX2, a version that keeps the four sums in one AVX
//! register. Both do the same operations in the same order (no fused multiply-add), so the
//! result is the same bit for bit on every x86-64 machine. The dot products are written with
//! intrinsics: the compiler's own vectorisation of the body interleaves the two sums of
//! `dot4_pair` through 128-bit shuffles and ran 3x slower.

/// a . b with four partial sums: (s_0 + s_1) + (s_2 + s_3) + tail, s_k = sum_{i = k mod 4} a_i b_i.
pub fn dot4(a: &[f64], b: &[f64]) -> f64 {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above).
            return unsafe { avx2::dot4(a, b) };
        }
    }
    dot4_body(a, b)
}

/// (a . b, a . c) in one pass over `a`, each summed as in [`dot4`].
pub fn dot4_pair(a: &[f64], b: &[f64], c: &[f64]) -> (f64, f64) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above).
            return unsafe { avx2::dot4_pair(a, b, c) };
        }
    }
    dot4_pair_body(a, b, c)
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

    /// (s_0 + s_1) + (s_2 + s_3) of a register of four partial sums.
    #[target_feature(enable = "avx2")]
    unsafe fn reduce(s: __m256d) -> f64 {
        let mut v = [0.0; 4];
        _mm256_storeu_pd(v.as_mut_ptr(), s);
        (v[0] + v[1]) + (v[2] + v[3])
    }

    #[target_feature(enable = "avx2")]
    pub unsafe fn dot4(a: &[f64], b: &[f64]) -> f64 {
        let n = a.len().min(b.len());
        let m = n - n % 4;
        let mut s = _mm256_setzero_pd();
        let mut i = 0;
        while i < m {
            // SAFETY: i + 4 <= m <= the length of each slice
            let x = _mm256_loadu_pd(a.as_ptr().add(i));
            s = _mm256_add_pd(s, _mm256_mul_pd(x, _mm256_loadu_pd(b.as_ptr().add(i))));
            i += 4;
        }
        let mut t = 0.0;
        for k in m..n {
            t += a[k] * b[k];
        }
        reduce(s) + t
    }

    #[target_feature(enable = "avx2")]
    pub unsafe fn dot4_pair(a: &[f64], b: &[f64], c: &[f64]) -> (f64, f64) {
        let n = a.len().min(b.len()).min(c.len());
        let m = n - n % 4;
        let (mut s, mut t) = (_mm256_setzero_pd(), _mm256_setzero_pd());
        let mut i = 0;
        while i < m {
            // SAFETY: i + 4 <= m <= the length of each slice
            let x = _mm256_loadu_pd(a.as_ptr().add(i));
            s = _mm256_add_pd(s, _mm256_mul_pd(x, _mm256_loadu_pd(b.as_ptr().add(i))));
            t = _mm256_add_pd(t, _mm256_mul_pd(x, _mm256_loadu_pd(c.as_ptr().add(i))));
            i += 4;
        }
        let (mut ss, mut tt) = (0.0, 0.0);
        for k in m..n {
            ss += a[k] * b[k];
            tt += a[k] * c[k];
        }
        (reduce(s) + ss, reduce(t) + tt)
    }
}

#[inline(always)]
fn dot4_body(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut s = [0.0; 4];
    for (x, y) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
        for k in 0..4 {
            s[k] += x[k] * y[k];
        }
    }
    let mut t = 0.0;
    for k in n - n % 4..n {
        t += a[k] * b[k];
    }
    (s[0] + s[1]) + (s[2] + s[3]) + t
}

#[inline(always)]
fn dot4_pair_body(a: &[f64], b: &[f64], c: &[f64]) -> (f64, f64) {
    let n = a.len().min(b.len()).min(c.len());
    let (a, b, c) = (&a[..n], &b[..n], &c[..n]);
    let mut s = [0.0; 4];
    let mut t = [0.0; 4];
    for ((x, y), z) in a
        .chunks_exact(4)
        .zip(b.chunks_exact(4))
        .zip(c.chunks_exact(4))
    {
        for k in 0..4 {
            s[k] += x[k] * y[k];
            t[k] += x[k] * z[k];
        }
    }
    let (mut ss, mut tt) = (0.0, 0.0);
    for k in n - n % 4..n {
        ss += a[k] * b[k];
        tt += a[k] * c[k];
    }
    (
        (s[0] + s[1]) + (s[2] + s[3]) + ss,
        (t[0] + t[1]) + (t[2] + t[3]) + tt,
    )
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
    /// the same operations in the same order), over lengths with every tail 0-3.
    #[test]
    fn kernels_match_the_documented_summation_order() {
        for n in [0usize, 1, 3, 4, 7, 8, 947, 1001] {
            let a: Vec<f64> = (0..n)
                .map(|i| ((i * 37 % 101) as f64 - 50.0) / 7.0)
                .collect();
            let b: Vec<f64> = (0..n)
                .map(|i| ((i * 53 % 89) as f64 - 44.0) / 3.0)
                .collect();
            let c: Vec<f64> = (0..n).map(|i| 1.0 / (1.0 + i as f64)).collect();
            let reference = |x: &[f64], y: &[f64]| {
                let mut s = [0.0; 4];
                for i in 0..n - n % 4 {
                    s[i % 4] += x[i] * y[i];
                }
                let mut t = 0.0;
                for i in n - n % 4..n {
                    t += x[i] * y[i];
                }
                (s[0] + s[1]) + (s[2] + s[3]) + t
            };
            assert_eq!(dot4(&a, &b).to_bits(), reference(&a, &b).to_bits());
            assert_eq!(dot4_body(&a, &b).to_bits(), reference(&a, &b).to_bits());
            let (p, q) = dot4_pair(&a, &b, &c);
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
