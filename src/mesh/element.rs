//! Element kinds and their topology: node ordering, edges, faces, reference nodes. The shape
//! functions on them are in `fem::shape`.
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
use crate::scene::spec::ElementKind;

pub(crate) const TET10_EDGES: [(usize, usize); 6] =
    [(0, 1), (1, 2), (2, 0), (3, 0), (3, 2), (3, 1)];
const HEX20_EDGES: [(usize, usize); 12] = [
    (0, 1),
    (0, 3),
    (0, 4),
    (1, 2),
    (1, 5),
    (2, 3),
    (2, 6),
    (3, 7),
    (4, 5),
    (4, 7),
    (5, 6),
    (6, 7),
];
pub(crate) const HEX_CORNERS: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];
const TET_CORNERS: [[f64; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
];
/// Corner-node faces with outward normals (right-hand rule), Gmsh corner numbering.
const TET_FACES: [&[usize]; 4] = [&[0, 2, 1], &[0, 1, 3], &[0, 3, 2], &[1, 2, 3]];
const HEX_FACES: [&[usize]; 6] = [
    &[0, 3, 2, 1],
    &[4, 5, 6, 7],
    &[0, 1, 5, 4],
    &[1, 2, 6, 5],
    &[2, 3, 7, 6],
    &[3, 0, 4, 7],
];

impl ElementKind {
    /// Number of nodes.
    pub fn num_nodes(self) -> usize {
        match self {
            Self::Tet4 => 4,
            Self::Tet10 => 10,
            Self::Hex8 => 8,
            Self::Hex20 => 20,
        }
    }
    /// Number of corner (vertex) nodes.
    pub fn num_corners(self) -> usize {
        match self {
            Self::Tet4 | Self::Tet10 => 4,
            Self::Hex8 | Self::Hex20 => 8,
        }
    }
    /// Edges carrying mid-edge nodes (node `num_corners() + k` sits on edge k).
    pub fn mid_edges(self) -> &'static [(usize, usize)] {
        match self {
            Self::Tet10 => &TET10_EDGES,
            Self::Hex20 => &HEX20_EDGES,
            _ => &[],
        }
    }
    /// Faces as corner-node lists with outward orientation.
    pub fn faces(self) -> &'static [&'static [usize]] {
        match self {
            Self::Tet4 | Self::Tet10 => &TET_FACES,
            Self::Hex8 | Self::Hex20 => &HEX_FACES,
        }
    }
    pub fn is_tet(self) -> bool {
        matches!(self, Self::Tet4 | Self::Tet10)
    }
    /// Gmsh element type number.
    pub fn gmsh_type(self) -> u32 {
        match self {
            Self::Tet4 => 4,
            Self::Tet10 => 11,
            Self::Hex8 => 5,
            Self::Hex20 => 17,
        }
    }
    pub fn from_gmsh_type(t: u32) -> Option<Self> {
        match t {
            4 => Some(Self::Tet4),
            11 => Some(Self::Tet10),
            5 => Some(Self::Hex8),
            17 => Some(Self::Hex20),
            _ => None,
        }
    }
    /// Reference coordinates of node `a`.
    pub fn ref_node(self, a: usize) -> [f64; 3] {
        let corners: &[[f64; 3]] = if self.is_tet() {
            &TET_CORNERS
        } else {
            &HEX_CORNERS
        };
        let nc = self.num_corners();
        if a < nc {
            corners[a]
        } else {
            let (p, q) = self.mid_edges()[a - nc];
            let (p, q) = (corners[p], corners[q]);
            [
                0.5 * (p[0] + q[0]),
                0.5 * (p[1] + q[1]),
                0.5 * (p[2] + q[2]),
            ]
        }
    }
    /// Reference-element volume (hex 8, tet 1/6).
    pub fn ref_volume(self) -> f64 {
        if self.is_tet() {
            1.0 / 6.0
        } else {
            8.0
        }
    }
}
