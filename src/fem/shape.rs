//! Reference elements: node ordering, shape functions N_a(xi) and their derivatives dN_a/dxi.
//!
//! Node ordering follows Gmsh (MSH 4.1), so imported meshes need no renumbering:
//! - `Tet4`: corners 0..3 at (0,0,0), (1,0,0), (0,1,0), (0,0,1); N = barycentric L_a.
//! - `Tet10`: corners, then mid-edge nodes on edges (0,1) (1,2) (2,0) (3,0) (3,2) (3,1);
//!   N_corner = L (2L - 1), N_mid = 4 L_a L_b.
//! - `Hex8`: corners (-1,-1,-1) (1,-1,-1) (1,1,-1) (-1,1,-1), then the same at zeta = +1;
//!   N = (1 + xi xi_a)(1 + eta eta_a)(1 + zeta zeta_a) / 8.
//! - `Hex20` (serendipity): corners, then mid-edge nodes on edges (0,1) (0,3) (0,4) (1,2)
//!   (1,5) (2,3) (2,6) (3,7) (4,5) (4,7) (5,6) (6,7);
//!   corner N = (1+xi xi_a)(1+eta eta_a)(1+zeta zeta_a)(xi xi_a + eta eta_a + zeta zeta_a - 2)/8,
//!   mid-edge (xi_a = 0) N = (1 - xi^2)(1 + eta eta_a)(1 + zeta zeta_a)/4, likewise per axis.

use crate::mesh::element::{HEX_CORNERS, TET10_EDGES};
use crate::scene::spec::ElementKind;

impl ElementKind {
    /// Shape functions `n[a]` and reference derivatives `dn[a][k] = dN_a / dxi_k` at `xi`.
    pub fn eval(self, xi: [f64; 3], n: &mut [f64], dn: &mut [[f64; 3]]) {
        let [x, y, z] = xi;
        match self {
            Self::Tet4 | Self::Tet10 => {
                let l = [1.0 - x - y - z, x, y, z];
                // dL_a / dxi_k
                let dl = [
                    [-1.0, -1.0, -1.0],
                    [1.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0],
                    [0.0, 0.0, 1.0],
                ];
                if self == Self::Tet4 {
                    n[..4].copy_from_slice(&l);
                    dn[..4].copy_from_slice(&dl);
                } else {
                    for a in 0..4 {
                        n[a] = l[a] * (2.0 * l[a] - 1.0);
                        for k in 0..3 {
                            dn[a][k] = (4.0 * l[a] - 1.0) * dl[a][k];
                        }
                    }
                    for (e, &(p, q)) in TET10_EDGES.iter().enumerate() {
                        n[4 + e] = 4.0 * l[p] * l[q];
                        for k in 0..3 {
                            dn[4 + e][k] = 4.0 * (dl[p][k] * l[q] + l[p] * dl[q][k]);
                        }
                    }
                }
            }
            Self::Hex8 => {
                for (a, c) in HEX_CORNERS.iter().enumerate() {
                    let (fx, fy, fz) = (1.0 + x * c[0], 1.0 + y * c[1], 1.0 + z * c[2]);
                    n[a] = 0.125 * fx * fy * fz;
                    dn[a] = [
                        0.125 * c[0] * fy * fz,
                        0.125 * fx * c[1] * fz,
                        0.125 * fx * fy * c[2],
                    ];
                }
            }
            Self::Hex20 => {
                for (a, c) in HEX_CORNERS.iter().enumerate() {
                    let (fx, fy, fz) = (1.0 + x * c[0], 1.0 + y * c[1], 1.0 + z * c[2]);
                    let s = x * c[0] + y * c[1] + z * c[2] - 2.0;
                    n[a] = 0.125 * fx * fy * fz * s;
                    dn[a] = [
                        0.125 * c[0] * fy * fz * (s + fx),
                        0.125 * fx * c[1] * fz * (s + fy),
                        0.125 * fx * fy * c[2] * (s + fz),
                    ];
                }
                for e in 0..12 {
                    let c = self.ref_node(8 + e);
                    // exactly one coordinate of a mid-edge node is zero: the bubble direction
                    let k0 = (0..3).find(|&k| c[k] == 0.0).expect("mid-edge node");
                    let (k1, k2) = ((k0 + 1) % 3, (k0 + 2) % 3);
                    let b = 1.0 - xi[k0] * xi[k0];
                    let f1 = 1.0 + xi[k1] * c[k1];
                    let f2 = 1.0 + xi[k2] * c[k2];
                    n[8 + e] = 0.25 * b * f1 * f2;
                    let mut d = [0.0; 3];
                    d[k0] = 0.25 * (-2.0 * xi[k0]) * f1 * f2;
                    d[k1] = 0.25 * b * c[k1] * f2;
                    d[k2] = 0.25 * b * f1 * c[k2];
                    dn[8 + e] = d;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    const ALL: [ElementKind; 4] = [
        ElementKind::Tet4,
        ElementKind::Tet10,
        ElementKind::Hex8,
        ElementKind::Hex20,
    ];

    /// Kronecker property N_a(xi_b) = delta_ab and partition of unity with zero derivative sum.
    #[test]
    fn kronecker_and_partition_of_unity() {
        for kind in ALL {
            let nn = kind.num_nodes();
            let mut n = vec![0.0; nn];
            let mut dn = vec![[0.0; 3]; nn];
            for b in 0..nn {
                kind.eval(kind.ref_node(b), &mut n, &mut dn);
                for a in 0..nn {
                    let e = if a == b { 1.0 } else { 0.0 };
                    assert!((n[a] - e).abs() < 1e-14, "{kind:?} N_{a}(x_{b})");
                }
            }
            let xi = if kind.is_tet() {
                [0.2, 0.3, 0.1]
            } else {
                [0.3, -0.4, 0.7]
            };
            kind.eval(xi, &mut n, &mut dn);
            assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-14);
            for k in 0..3 {
                assert!(dn.iter().map(|d| d[k]).sum::<f64>().abs() < 1e-13);
            }
        }
    }

    /// Derivatives against central finite differences (error O(h^2) ~ 1e-10).
    #[test]
    fn derivatives_match_finite_differences() {
        for kind in ALL {
            let nn = kind.num_nodes();
            let xi = if kind.is_tet() {
                [0.21, 0.17, 0.33]
            } else {
                [0.3, -0.45, 0.62]
            };
            let (mut n, mut dn) = (vec![0.0; nn], vec![[0.0; 3]; nn]);
            let (mut np, mut nm, mut scratch) = (vec![0.0; nn], vec![0.0; nn], vec![[0.0; 3]; nn]);
            kind.eval(xi, &mut n, &mut dn);
            let h = 1e-6;
            for k in 0..3 {
                let (mut xp, mut xm) = (xi, xi);
                xp[k] += h;
                xm[k] -= h;
                kind.eval(xp, &mut np, &mut scratch);
                kind.eval(xm, &mut nm, &mut scratch);
                for a in 0..nn {
                    let fd = (np[a] - nm[a]) / (2.0 * h);
                    assert!((fd - dn[a][k]).abs() < 1e-8, "{kind:?} a={a} k={k}");
                }
            }
        }
    }
}
