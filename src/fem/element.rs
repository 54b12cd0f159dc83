//! Element stiffness and consistent mass matrices of isotropic 3-D solids.
//!
//! For nodes a, b with physical shape-function gradients g_a = J^{-T} dN_a/dxi the 3x3 stiffness
//! block is
//!   K_ab,ij = int( lambda g_a,i g_b,j + mu g_a,j g_b,i + mu delta_ij g_a . g_b ) dV,
//! which is B_a^T D B_b written out for isotropic D, and the consistent mass block is
//!   M_ab,ij = int( rho N_a N_b ) dV delta_ij.
//! DOFs are node-major: dof = 3 a + i. Matrices are dense row-major (3n x 3n).
//!
//! `Hex8` uses Wilson's incompatible modes with Taylor's correction (QM6): three bubble modes
//! P_k = 1 - xi_k^2 per displacement component, their gradients taken with the centre Jacobian
//! J0 and scaled by det J0 / det J so the patch test is passed, condensed statically:
//!   K = K_uu - K_ua K_aa^{-1} K_au.
//! That removes the shear locking of the plain trilinear brick in bending.

use super::quadrature::{hex_rule, tet_rule, tet_rule4, QuadPoint};
use crate::scene::spec::Elastic;
use crate::scene::spec::ElementKind;
use nalgebra::{DMatrix, Matrix3, Vector3};
use std::sync::OnceLock;

/// A geometric failure of one element, reported with the quadrature point where it occurred.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ElementError {
    #[error("non-positive Jacobian determinant {det:.3e} at reference point {xi:?} (inverted or degenerate element)")]
    BadJacobian { det: f64, xi: [f64; 3] },
}

/// Shape data of one element kind at one quadrature rule, tabulated once.
pub struct Tabulated {
    pub points: Vec<QuadPoint>,
    pub n: Vec<Vec<f64>>,
    pub dn: Vec<Vec<[f64; 3]>>,
}

fn tabulate(kind: ElementKind, points: Vec<QuadPoint>) -> Tabulated {
    let nn = kind.num_nodes();
    let mut n = Vec::new();
    let mut dn = Vec::new();
    for p in &points {
        let mut nv = vec![0.0; nn];
        let mut dv = vec![[0.0; 3]; nn];
        kind.eval(p.xi, &mut nv, &mut dv);
        n.push(nv);
        dn.push(dv);
    }
    Tabulated { points, n, dn }
}

/// Quadrature for stiffness (index 0) and mass (index 1).
/// Tet4: the 4-point rule (degree 2) is exact for both; Tet10: K integrand of degree 2 and M of
/// degree 4 on straight-sided tetrahedra (curved ones use [`curved_tet10_stiffness_rule`]);
/// hexahedra: 2x2x2 (Hex8) and 3x3x3 (Hex20) full integration.
pub fn rules(kind: ElementKind) -> &'static [Tabulated; 2] {
    static T4: OnceLock<[Tabulated; 2]> = OnceLock::new();
    static T10: OnceLock<[Tabulated; 2]> = OnceLock::new();
    static H8: OnceLock<[Tabulated; 2]> = OnceLock::new();
    static H20: OnceLock<[Tabulated; 2]> = OnceLock::new();
    match kind {
        ElementKind::Tet4 => {
            T4.get_or_init(|| [tabulate(kind, tet_rule4()), tabulate(kind, tet_rule4())])
        }
        ElementKind::Tet10 => {
            T10.get_or_init(|| [tabulate(kind, tet_rule4()), tabulate(kind, tet_rule(4))])
        }
        ElementKind::Hex8 => {
            H8.get_or_init(|| [tabulate(kind, hex_rule(2)), tabulate(kind, hex_rule(2))])
        }
        ElementKind::Hex20 => {
            H20.get_or_init(|| [tabulate(kind, hex_rule(3)), tabulate(kind, hex_rule(3))])
        }
    }
}

/// Stiffness rule of curved 10-node tetrahedra: with a quadratic geometry map,
/// det(J) dN/dx = adj(J)^T dN/dxi is a cubic polynomial, so a degree-3-exact rule (collapsed
/// Gauss, 3 points per direction) integrates int dN_a/dx dV exactly and the patch test holds.
pub fn curved_tet10_stiffness_rule() -> &'static Tabulated {
    static R: OnceLock<Tabulated> = OnceLock::new();
    R.get_or_init(|| tabulate(ElementKind::Tet10, tet_rule(3)))
}

/// True when every mid-edge node sits at its edge midpoint (to 1e-9 of the edge length).
fn straight_sided(kind: ElementKind, coords: &[[f64; 3]]) -> bool {
    let nc = kind.num_corners();
    kind.mid_edges().iter().enumerate().all(|(m, &(a, b))| {
        let len2: f64 = (0..3).map(|i| (coords[a][i] - coords[b][i]).powi(2)).sum();
        let off2: f64 = (0..3)
            .map(|i| (coords[nc + m][i] - 0.5 * (coords[a][i] + coords[b][i])).powi(2))
            .sum();
        off2 <= 1e-18 * len2
    })
}

/// Jacobian J_ij = sum_a x_a,i dN_a/dxi_j.
fn jacobian(coords: &[[f64; 3]], dn: &[[f64; 3]]) -> Matrix3<f64> {
    let mut j = Matrix3::zeros();
    for (x, d) in coords.iter().zip(dn) {
        for r in 0..3 {
            for c in 0..3 {
                j[(r, c)] += x[r] * d[c];
            }
        }
    }
    j
}

/// Physical gradients g_a = J^{-T} dN_a/dxi into `g`; returns det J.
fn gradients(
    coords: &[[f64; 3]],
    dn: &[[f64; 3]],
    xi: [f64; 3],
    g: &mut [[f64; 3]],
) -> Result<f64, ElementError> {
    let j = jacobian(coords, dn);
    let det = j.determinant();
    if det.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(ElementError::BadJacobian { det, xi });
    }
    let jit = j
        .try_inverse()
        .ok_or(ElementError::BadJacobian { det, xi })?
        .transpose();
    for (ga, d) in g.iter_mut().zip(dn) {
        let v = jit * Vector3::new(d[0], d[1], d[2]);
        *ga = [v[0], v[1], v[2]];
    }
    Ok(det)
}

/// Adds w * K_ab(g_a, g_b) for all node pairs to the dense `k` (size nd x nd, nd = 3 n).
fn add_isotropic_stiffness(
    k: &mut [f64],
    nd: usize,
    ga: &[[f64; 3]],
    gb: &[[f64; 3]],
    lam: f64,
    mu: f64,
    w: f64,
) {
    for (a, p) in ga.iter().enumerate() {
        for (b, q) in gb.iter().enumerate() {
            let dot = p[0] * q[0] + p[1] * q[1] + p[2] * q[2];
            for i in 0..3 {
                let row = (3 * a + i) * nd + 3 * b;
                for j in 0..3 {
                    let mut v = lam * p[i] * q[j] + mu * p[j] * q[i];
                    if i == j {
                        v += mu * dot;
                    }
                    k[row + j] += w * v;
                }
            }
        }
    }
}

/// Element stiffness K and consistent mass M (dense, row-major, 3n x 3n).
pub fn stiffness_mass(
    kind: ElementKind,
    coords: &[[f64; 3]],
    mat: &Elastic,
) -> Result<(Vec<f64>, Vec<f64>), ElementError> {
    let nn = kind.num_nodes();
    let nd = 3 * nn;
    let (lam, mu) = (mat.lambda(), mat.mu());
    let [kr, mr] = rules(kind);
    let kr = if kind == ElementKind::Tet10 && !straight_sided(kind, coords) {
        curved_tet10_stiffness_rule()
    } else {
        kr
    };
    let mut k = vec![0.0; nd * nd];
    let mut m = vec![0.0; nd * nd];
    let mut g = vec![[0.0; 3]; nn];
    for (q, p) in kr.points.iter().enumerate() {
        let det = gradients(coords, &kr.dn[q], p.xi, &mut g)?;
        add_isotropic_stiffness(&mut k, nd, &g, &g, lam, mu, p.weight * det);
    }
    for (q, p) in mr.points.iter().enumerate() {
        let det = jacobian(coords, &mr.dn[q]).determinant();
        if det.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(ElementError::BadJacobian { det, xi: p.xi });
        }
        let w = p.weight * det * mat.density;
        let n = &mr.n[q];
        for a in 0..nn {
            for b in 0..nn {
                let v = w * n[a] * n[b];
                for i in 0..3 {
                    m[(3 * a + i) * nd + 3 * b + i] += v;
                }
            }
        }
    }
    if kind == ElementKind::Hex8 {
        condense_incompatible_modes(coords, lam, mu, &mut k)?;
    }
    Ok((k, m))
}

/// Adds the Wilson–Taylor incompatible modes to a Hex8 stiffness and condenses them out.
fn condense_incompatible_modes(
    coords: &[[f64; 3]],
    lam: f64,
    mu: f64,
    k: &mut [f64],
) -> Result<(), ElementError> {
    let [kr, _] = rules(ElementKind::Hex8);
    let mut dn0 = vec![[0.0; 3]; 8];
    let mut n0 = vec![0.0; 8];
    ElementKind::Hex8.eval([0.0; 3], &mut n0, &mut dn0);
    let j0 = jacobian(coords, &dn0);
    let det0 = j0.determinant();
    if det0.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(ElementError::BadJacobian {
            det: det0,
            xi: [0.0; 3],
        });
    }
    let j0it = j0
        .try_inverse()
        .ok_or(ElementError::BadJacobian {
            det: det0,
            xi: [0.0; 3],
        })?
        .transpose();
    // Combined matrix over 8 nodes + 3 bubble "nodes" (33 x 33): [K_uu K_ua; K_au K_aa].
    let nt = 33;
    let mut kt = vec![0.0; nt * nt];
    let mut g = vec![[0.0; 3]; 11];
    for (q, p) in kr.points.iter().enumerate() {
        let det = gradients(coords, &kr.dn[q], p.xi, &mut g[..8])?;
        let scale = det0 / det;
        for kk in 0..3 {
            let mut d = Vector3::zeros();
            d[kk] = -2.0 * p.xi[kk];
            let v = j0it * d * scale;
            g[8 + kk] = [v[0], v[1], v[2]];
        }
        add_isotropic_stiffness(&mut kt, nt, &g, &g, lam, mu, p.weight * det);
    }
    let kaa = DMatrix::from_fn(9, 9, |r, c| kt[(24 + r) * nt + 24 + c]);
    let kau = DMatrix::from_fn(9, 24, |r, c| kt[(24 + r) * nt + c]);
    let chol = kaa.cholesky().ok_or(ElementError::BadJacobian {
        det: det0,
        xi: [0.0; 3],
    })?;
    let x = chol.solve(&kau); // K_aa^{-1} K_au
    for r in 0..24 {
        for c in 0..24 {
            let mut corr = 0.0;
            for s in 0..9 {
                corr += kau[(s, r)] * x[(s, c)];
            }
            k[r * 24 + c] = kt[r * nt + c] - corr;
        }
    }
    Ok(())
}

/// Volume of an element by quadrature of det J (the stiffness rule).
pub fn volume(kind: ElementKind, coords: &[[f64; 3]]) -> f64 {
    let [kr, _] = rules(kind);
    kr.points
        .iter()
        .enumerate()
        .map(|(q, p)| p.weight * jacobian(coords, &kr.dn[q]).determinant())
        .sum()
}

/// Checks a mesh (inverted elements by [`min_jacobian_ratio`], displaced mid-edge nodes,
/// duplicate and unused nodes) and compacts away unused nodes.
pub fn check_mesh(
    mesh: &mut crate::mesh::Mesh,
) -> Result<crate::mesh::checks::CheckReport, crate::mesh::checks::MeshError> {
    crate::mesh::checks::check_and_compact(mesh, min_jacobian_ratio)
}

/// Smallest det J over the stiffness points and the nodes, relative to the magnitude of the
/// mean (a shape check: <= 0 for an inverted or degenerate element).
pub fn min_jacobian_ratio(kind: ElementKind, coords: &[[f64; 3]]) -> f64 {
    let nn = kind.num_nodes();
    let (mut n, mut dn) = (vec![0.0; nn], vec![[0.0; 3]; nn]);
    let mean = volume(kind, coords) / kind.ref_volume();
    let mut min = f64::INFINITY;
    let [kr, _] = rules(kind);
    for a in 0..kind.num_corners() {
        kind.eval(kind.ref_node(a), &mut n, &mut dn);
        min = min.min(jacobian(coords, &dn).determinant());
    }
    for (q, _) in kr.points.iter().enumerate() {
        min = min.min(jacobian(coords, &kr.dn[q]).determinant());
    }
    // the mean's size: an inverted element with a constant Jacobian (tet4) has min and
    // mean of one sign, and min / mean would read 1
    min / mean.abs()
}
