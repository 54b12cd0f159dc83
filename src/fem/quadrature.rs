//! Quadrature rules on the reference hexahedron [-1, 1]^3 and the reference tetrahedron
//! {xi, eta, zeta >= 0, xi + eta + zeta <= 1}.
//!
//! Hexahedra use tensor Gauss–Legendre rules. Tetrahedra use the collapsed (Duffy) product rule
//! xi = u, eta = (1 - u) v, zeta = (1 - u)(1 - v) w with u, v, w in [0, 1] and Jacobian
//! (1 - u)^2 (1 - v): an integrand of total degree p on the tetrahedron becomes a polynomial of
//! degree p + 2 in u, p + 1 in v and p in w, so `n` Gauss points per direction (exact to degree
//! 2n - 1) integrate degree p exactly when 2n - 1 >= p + 2.

/// A quadrature point: reference coordinates and weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadPoint {
    pub xi: [f64; 3],
    pub weight: f64,
}

/// Gauss–Legendre nodes and weights on [-1, 1] for n = 1..=4.
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    match n {
        1 => vec![(0.0, 2.0)],
        2 => {
            let a = 1.0 / 3f64.sqrt();
            vec![(-a, 1.0), (a, 1.0)]
        }
        3 => {
            let a = (3.0f64 / 5.0).sqrt();
            vec![(-a, 5.0 / 9.0), (0.0, 8.0 / 9.0), (a, 5.0 / 9.0)]
        }
        4 => {
            let s = (6.0f64 / 5.0).sqrt();
            let a = ((3.0 - 2.0 * s) / 7.0).sqrt();
            let b = ((3.0 + 2.0 * s) / 7.0).sqrt();
            let wa = (18.0 + 30f64.sqrt()) / 36.0;
            let wb = (18.0 - 30f64.sqrt()) / 36.0;
            vec![(-b, wb), (-a, wa), (a, wa), (b, wb)]
        }
        _ => panic!("gauss_legendre: n = {n} not tabulated (1..=4)"),
    }
}

/// Tensor Gauss rule with `n` points per direction on [-1, 1]^3 (exact to degree 2n-1 per axis).
pub fn hex_rule(n: usize) -> Vec<QuadPoint> {
    let g = gauss_legendre(n);
    let mut out = Vec::with_capacity(n * n * n);
    for &(z, wz) in &g {
        for &(y, wy) in &g {
            for &(x, wx) in &g {
                out.push(QuadPoint {
                    xi: [x, y, z],
                    weight: wx * wy * wz,
                });
            }
        }
    }
    out
}

/// Classic 4-point rule on the unit tetrahedron, exact to degree 2 (weights 1/24).
pub fn tet_rule4() -> Vec<QuadPoint> {
    let a = 0.585_410_196_624_968_5;
    let b = 0.138_196_601_125_010_5;
    [[b, b, b], [a, b, b], [b, a, b], [b, b, a]]
        .into_iter()
        .map(|xi| QuadPoint {
            xi,
            weight: 1.0 / 24.0,
        })
        .collect()
}

/// Collapsed Gauss rule on the unit tetrahedron, `n` points per direction; weights sum to 1/6.
pub fn tet_rule(n: usize) -> Vec<QuadPoint> {
    let g: Vec<(f64, f64)> = gauss_legendre(n)
        .into_iter()
        .map(|(x, w)| ((x + 1.0) / 2.0, w / 2.0))
        .collect();
    let mut out = Vec::with_capacity(n * n * n);
    for &(u, wu) in &g {
        for &(v, wv) in &g {
            for &(w, ww) in &g {
                let xi = u;
                let eta = (1.0 - u) * v;
                let zeta = (1.0 - u) * (1.0 - v) * w;
                let jac = (1.0 - u) * (1.0 - u) * (1.0 - v);
                out.push(QuadPoint {
                    xi: [xi, eta, zeta],
                    weight: wu * wv * ww * jac,
                });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn factorial(n: u32) -> f64 {
        (1..=n).map(f64::from).product()
    }

    /// The integral of xi^a eta^b zeta^c over the unit tetrahedron is a! b! c! / (a+b+c+3)!.
    #[test]
    fn tet_rule_integrates_monomials_exactly() {
        for n in 2..=4usize {
            let rule = tet_rule(n);
            let max_deg = 2 * n as u32 - 3; // 2n - 1 >= p + 2
            for a in 0..=max_deg {
                for b in 0..=(max_deg - a) {
                    for c in 0..=(max_deg - a - b) {
                        let exact =
                            factorial(a) * factorial(b) * factorial(c) / factorial(a + b + c + 3);
                        let q: f64 = rule
                            .iter()
                            .map(|p| {
                                p.weight
                                    * p.xi[0].powi(a as i32)
                                    * p.xi[1].powi(b as i32)
                                    * p.xi[2].powi(c as i32)
                            })
                            .sum();
                        assert!((q - exact).abs() < 1e-14, "n={n} a={a} b={b} c={c}");
                    }
                }
            }
        }
    }

    #[test]
    fn tet_rule4_exact_to_degree_2() {
        let rule = tet_rule4();
        for (a, b, c) in [
            (0, 0, 0),
            (1, 0, 0),
            (0, 1, 1),
            (2, 0, 0),
            (0, 0, 2),
            (1, 1, 0),
        ] {
            let exact = factorial(a) * factorial(b) * factorial(c) / factorial(a + b + c + 3);
            let q: f64 = rule
                .iter()
                .map(|p| {
                    p.weight
                        * p.xi[0].powi(a as i32)
                        * p.xi[1].powi(b as i32)
                        * p.xi[2].powi(c as i32)
                })
                .sum();
            assert!((q - exact).abs() < 1e-15);
        }
    }

    /// Gauss-Legendre with n points integrates x^k on [-1,1] exactly for k <= 2n-1.
    #[test]
    fn gauss_legendre_exact_to_degree_2n_minus_1() {
        for n in 1..=4usize {
            for k in 0..(2 * n) {
                let exact = if k % 2 == 1 {
                    0.0
                } else {
                    2.0 / (k as f64 + 1.0)
                };
                let q: f64 = gauss_legendre(n)
                    .iter()
                    .map(|(x, w)| w * x.powi(k as i32))
                    .sum();
                assert!((q - exact).abs() < 1e-14, "n={n} k={k}");
            }
        }
    }
}
