//! Structured generation on a logical lattice of cells (i, j, k), shared by the parametric
//! generators.
//!
//! Nodes live on the *doubled* lattice: a cell (i, j, k) spans doubled indices
//! [2i, 2i+2] x [2j, 2j+2] x [2k, 2k+2]; corners sit at even indices and mid-edge nodes at the
//! midpoints of the element's edges, so neighbouring cells share nodes exactly (conforming
//! quadratic meshes). Axis 1 may be periodic (the circumferential direction of a tube).
//! Tetrahedral meshes split each cell into the six Kuhn tetrahedra along its main diagonal
//! (conforming because every cell uses the same diagonal direction).

use super::{ElementBlock, Mesh};
use crate::scene::spec::ElementKind;
use std::collections::HashMap;

/// A doubled-lattice index.
pub type Key = [usize; 3];

/// The six Kuhn tetrahedra of the unit cube as paths of corner bit-vectors.
const KUHN: [[usize; 3]; 6] = [
    [0, 1, 2],
    [0, 2, 1],
    [1, 0, 2],
    [1, 2, 0],
    [2, 0, 1],
    [2, 1, 0],
];
/// Gmsh hex corner order as (di, dj, dk) offsets.
const HEX_OFFSETS: [[usize; 3]; 8] = [
    [0, 0, 0],
    [1, 0, 0],
    [1, 1, 0],
    [0, 1, 0],
    [0, 0, 1],
    [1, 0, 1],
    [1, 1, 1],
    [0, 1, 1],
];

/// Lattice description: cell counts, periodicity of axis 1, active cells, coordinate map.
pub struct Lattice<'a> {
    pub cells: [usize; 3],
    pub periodic_j: bool,
    pub active: &'a dyn Fn(usize, usize, usize) -> bool,
    /// Coordinates of a doubled-lattice point.
    pub coord: &'a dyn Fn(Key) -> [f64; 3],
}

/// Mesh plus the doubled-lattice key of every node.
pub struct LatticeMesh {
    pub mesh: Mesh,
    pub keys: Vec<Key>,
}

impl Lattice<'_> {
    fn wrap(&self, mut key: Key) -> Key {
        if self.periodic_j {
            key[1] %= 2 * self.cells[1];
        }
        key
    }

    /// Generates the mesh with elements of `kind`.
    pub fn generate(&self, kind: ElementKind) -> LatticeMesh {
        let mut ids: HashMap<Key, usize> = HashMap::new();
        let mut keys: Vec<Key> = Vec::new();
        let mut nodes: Vec<[f64; 3]> = Vec::new();
        let mut conn: Vec<usize> = Vec::new();
        let mut node = |key: Key, ids: &mut HashMap<Key, usize>| -> usize {
            let key = self.wrap(key);
            *ids.entry(key).or_insert_with(|| {
                keys.push(key);
                nodes.push((self.coord)(key));
                nodes.len() - 1
            })
        };
        let [ni, nj, nk] = self.cells;
        for k in 0..nk {
            for j in 0..nj {
                for i in 0..ni {
                    if !(self.active)(i, j, k) {
                        continue;
                    }
                    let base = [2 * i, 2 * j, 2 * k];
                    let corner = |o: [usize; 3]| -> Key {
                        [base[0] + 2 * o[0], base[1] + 2 * o[1], base[2] + 2 * o[2]]
                    };
                    let mut cells_corners: Vec<Vec<Key>> = Vec::new();
                    if kind.is_tet() {
                        for path in KUHN {
                            let mut o = [0usize; 3];
                            let mut c = vec![corner(o)];
                            for ax in path {
                                o[ax] = 1;
                                c.push(corner(o));
                            }
                            cells_corners.push(c);
                        }
                    } else {
                        cells_corners.push(HEX_OFFSETS.iter().map(|&o| corner(o)).collect());
                    }
                    for mut corners in cells_corners {
                        if kind.is_tet() {
                            // orient positively: signed volume of the corner tetrahedron
                            let p: Vec<[f64; 3]> = corners
                                .iter()
                                .map(|&c| (self.coord)(self.wrap(c)))
                                .collect();
                            if signed_tet_volume(&p) < 0.0 {
                                corners.swap(1, 2);
                            }
                        }
                        let mut elem: Vec<usize> =
                            corners.iter().map(|&c| node(c, &mut ids)).collect();
                        for &(a, b) in kind.mid_edges() {
                            let (ka, kb) = (corners[a], corners[b]);
                            let mid = [
                                (ka[0] + kb[0]) / 2,
                                (ka[1] + kb[1]) / 2,
                                (ka[2] + kb[2]) / 2,
                            ];
                            elem.push(node(mid, &mut ids));
                        }
                        conn.extend(elem);
                    }
                }
            }
        }
        LatticeMesh {
            mesh: Mesh {
                nodes,
                blocks: vec![ElementBlock { kind, conn }],
                ..Default::default()
            },
            keys,
        }
    }
}

/// Signed volume (b - a) . ((c - a) x (d - a)) / 6.
pub fn signed_tet_volume(p: &[[f64; 3]]) -> f64 {
    let d = |i: usize| [p[i][0] - p[0][0], p[i][1] - p[0][1], p[i][2] - p[0][2]];
    let (u, v, w) = (d(1), d(2), d(3));
    (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
        + u[2] * (v[0] * w[1] - v[1] * w[0]))
        / 6.0
}

/// Splits [a, b] into `ceil((b - a) / h)` equal pieces (at least one) and appends the levels
/// after `a`.
pub fn subdivide(levels: &mut Vec<f64>, a: f64, b: f64, h: f64) {
    let n = (((b - a) / h) - 1e-9).ceil().max(1.0) as usize;
    for s in 1..=n {
        levels.push(a + (b - a) * s as f64 / n as f64);
    }
}

/// Coordinate of a doubled index on a level list: even -> level, odd -> midpoint.
pub fn level_at(levels: &[f64], doubled: usize) -> f64 {
    if doubled % 2 == 0 {
        levels[doubled / 2]
    } else {
        0.5 * (levels[doubled / 2] + levels[doubled / 2 + 1])
    }
}
