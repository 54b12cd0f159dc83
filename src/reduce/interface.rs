//! Interface fields: the a-priori shapes that carry the liner-crankcase coupling.
//!
//! A liner touches the crankcase on two circular interfaces around the bore axis: the flange
//! seat (an annulus r_in <= r <= r_out at one height, bonded: all three displacement components
//! coupled) and the lower guide (a band z0 <= z <= z1 on the liner outer radius, a radial
//! support: only the radial component coupled). On either interface the displacement field is
//! expanded in circumferential harmonics times a linear profile across the interface width:
//!
//!   u(r, theta, z) = sum_{n=0..N} sum_{t in cos,sin} sum_{p in 1,zeta} sum_{d} q_{n,t,p,d} t(n theta) p(zeta) e_d(theta)
//!
//! with zeta in [-1, 1] the normalised radius (seat) or height (guide) and e_d the cylindrical
//! unit vectors (radial, tangential, axial). Rigid motions of the liner (translations, tilts,
//! rotation about the axis) lie in the span for N >= 1, and the liner's ovalling shapes
//! (n = 2, 3, ...) up to N. Both parts evaluate the same field at their own interface nodes, so
//! the meshes need not match; the coupling is exact in the span and converges as N grows
//! (tests/rom.rs prints the convergence). This is the interface reduction of the Craig-Bampton
//! step: a few hundred interface coordinates per cylinder instead of thousands of nodal DOFs.

use faer::Mat;

/// Cylindrical direction of an interface shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Direction {
    Radial,
    Tangential,
    Axial,
}

/// Geometry of one circular interface around a bore axis.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum InterfaceShape {
    /// Annulus at one height; zeta from the radius.
    Seat { r_in: f64, r_out: f64 },
    /// Band on a cylinder; zeta from the height.
    Guide { z0: f64, z1: f64 },
}

/// Number of shapes for `harmonics` N and `dirs` directions: (2N + 1) x 2 x dirs.
pub fn count(harmonics: usize, dirs: usize) -> usize {
    (2 * harmonics + 1) * 2 * dirs
}

/// Interface shapes evaluated at `nodes` (coordinates), about the axis through (`cx`, 0)
/// parallel to z. Returns a dense matrix with 3 rows per node (x, y, z components, node-major)
/// and one column per shape, columns ordered (n, cos/sin, profile, direction).
pub fn shapes(
    nodes: &[[f64; 3]],
    cx: f64,
    shape: InterfaceShape,
    harmonics: usize,
    dirs: &[Direction],
) -> Mat<f64> {
    let ncol = count(harmonics, dirs.len());
    let mut psi = Mat::<f64>::zeros(3 * nodes.len(), ncol);
    for (a, p) in nodes.iter().enumerate() {
        let (dx, dy) = (p[0] - cx, p[1]);
        let r = (dx * dx + dy * dy).sqrt();
        let th = dy.atan2(dx);
        let zeta = match shape {
            InterfaceShape::Seat { r_in, r_out } => (2.0 * r - r_in - r_out) / (r_out - r_in),
            InterfaceShape::Guide { z0, z1 } => (2.0 * p[2] - z0 - z1) / (z1 - z0),
        };
        let (c, s) = (th.cos(), th.sin());
        let e = |d: Direction| -> [f64; 3] {
            match d {
                Direction::Radial => [c, s, 0.0],
                Direction::Tangential => [-s, c, 0.0],
                Direction::Axial => [0.0, 0.0, 1.0],
            }
        };
        let mut col = 0;
        for n in 0..=harmonics {
            let trig: &[f64] = if n == 0 {
                &[1.0]
            } else {
                &[(n as f64 * th).cos(), (n as f64 * th).sin()]
            };
            for &t in trig {
                for prof in [1.0, zeta] {
                    for &d in dirs {
                        let v = e(d);
                        for i in 0..3 {
                            psi[(3 * a + i, col)] = t * prof * v[i];
                        }
                        col += 1;
                    }
                }
            }
        }
        debug_assert_eq!(col, ncol);
    }
    psi
}

/// Smallest singular value relative to the largest of `psi` (rank check of an interface:
/// a value near zero means the part's interface nodes cannot carry every shape, e.g. all seat
/// nodes on one radius).
pub fn conditioning(psi: &Mat<f64>) -> f64 {
    let gram = psi.transpose() * psi;
    match gram.self_adjoint_eigenvalues(faer::Side::Lower) {
        Ok(ev) => {
            let max = ev.last().copied().unwrap_or(0.0);
            let min = ev.first().copied().unwrap_or(0.0);
            if max > 0.0 {
                (min.max(0.0) / max).sqrt()
            } else {
                0.0
            }
        }
        Err(_) => 0.0,
    }
}
