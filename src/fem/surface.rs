//! Non-structural mass carried by a part's surface in the normal direction: the coolant layer
//! on the wet side of a liner.
//!
//! A mass `mu` per unit area that moves with the wall's normal velocity only (fluid slides
//! freely along the wall) has the kinetic energy T = 1/2 int( mu (n . u_dot)^2 ) dA, so its
//! consistent mass matrix on a face with shape functions N_a is
//!   M_ab,ij = int( mu N_a N_b n_i n_j ) dA,
//! n the unit outward normal. Faces are those of the part's elements whose corner nodes all lie
//! in a named node set and that no other element shares (boundary faces). The element's own
//! shape functions restricted to the face are used, so the matrix is scattered like an element
//! matrix (nodes off the face have N = 0 there) and needs no new sparsity.
//!
//! Face integration: a quadrilateral face (hexahedra) is mapped from [-1, 1]^2 bilinearly in
//! reference coordinates and integrated with 3 x 3 Gauss points (exact for N_a N_b on a flat
//! 20-node face: degree 4 per direction); a triangular face (tetrahedra) from the unit triangle
//! with a collapsed 3 x 3 Gauss rule (exact to degree 4). dA = |x_s x x_t| ds dt with
//! x_s = J xi_s, J = dx/dxi of the element.

use super::quadrature::gauss_legendre;
use crate::mesh::Mesh;
use crate::scene::spec::ElementKind;
use std::collections::HashMap;

/// A normal mass per unit area on the boundary faces of a node set.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SurfaceMass {
    /// Node set whose boundary faces carry the mass.
    pub set: String,
    /// Mass per unit area [kg/m^2] (coolant layer: rho h).
    pub mass_per_area: f64,
}

/// One boundary face: the element (nodes) and the face's corner list in element numbering.
#[derive(Clone, Debug)]
pub struct Face {
    pub kind: ElementKind,
    pub nodes: Vec<usize>,
    pub corners: &'static [usize],
}

/// Failures of the surface-mass set-up.
#[derive(Debug, thiserror::Error)]
pub enum SurfaceError {
    #[error("unknown node set '{set}' for the surface mass; the mesh has: {available}")]
    UnknownSet { set: String, available: String },
    #[error("node set '{0}' bounds no element face (its nodes must cover whole boundary faces)")]
    NoFaces(String),
}

/// The boundary faces whose corner nodes all lie in `set`.
pub fn boundary_faces(mesh: &Mesh, set: &str) -> Result<Vec<Face>, SurfaceError> {
    let nodes = mesh.node_set(set).ok_or_else(|| SurfaceError::UnknownSet {
        set: set.to_string(),
        available: mesh.set_names().join(", "),
    })?;
    let mut in_set = vec![false; mesh.nodes.len()];
    for &n in nodes {
        in_set[n] = true;
    }
    // count every face (by its sorted corner nodes) over all elements: boundary faces once
    let mut count: HashMap<Vec<usize>, usize> = HashMap::new();
    let mut candidates = Vec::new();
    for (kind, el) in mesh.elements() {
        for &face in kind.faces() {
            let mut key: Vec<usize> = face.iter().map(|&a| el[a]).collect();
            key.sort_unstable();
            *count.entry(key.clone()).or_default() += 1;
            if face.iter().all(|&a| in_set[el[a]]) {
                candidates.push((
                    key,
                    Face {
                        kind,
                        nodes: el.to_vec(),
                        corners: face,
                    },
                ));
            }
        }
    }
    let faces: Vec<Face> = candidates
        .into_iter()
        .filter(|(key, _)| count[key] == 1)
        .map(|(_, f)| f)
        .collect();
    if faces.is_empty() {
        return Err(SurfaceError::NoFaces(set.to_string()));
    }
    Ok(faces)
}

/// A face quadrature point in element reference coordinates, with the face parameters'
/// tangents d xi / ds, d xi / dt and the weight of the parameter domain.
struct FacePoint {
    xi: [f64; 3],
    xi_s: [f64; 3],
    xi_t: [f64; 3],
    weight: f64,
}

/// Face quadrature: points (s, t) of the face parameter domain mapped to element reference
/// coordinates.
fn face_points(kind: ElementKind, corners: &[usize]) -> Vec<FacePoint> {
    let c: Vec<[f64; 3]> = corners.iter().map(|&a| kind.ref_node(a)).collect();
    let g = gauss_legendre(3);
    let mut out = Vec::new();
    if c.len() == 4 {
        // bilinear map of [-1, 1]^2 onto the (flat, axis-aligned) reference face
        let w = |s: f64, t: f64| {
            [
                (1.0 - s) * (1.0 - t) / 4.0,
                (1.0 + s) * (1.0 - t) / 4.0,
                (1.0 + s) * (1.0 + t) / 4.0,
                (1.0 - s) * (1.0 + t) / 4.0,
            ]
        };
        let ws = |t: f64| {
            [
                -(1.0 - t) / 4.0,
                (1.0 - t) / 4.0,
                (1.0 + t) / 4.0,
                -(1.0 + t) / 4.0,
            ]
        };
        let wt = |s: f64| {
            [
                -(1.0 - s) / 4.0,
                -(1.0 + s) / 4.0,
                (1.0 + s) / 4.0,
                (1.0 - s) / 4.0,
            ]
        };
        for &(t, wgt_t) in &g {
            for &(s, wgt_s) in &g {
                let (n, ds, dt) = (w(s, t), ws(t), wt(s));
                let mut xi = [0.0; 3];
                let mut xs = [0.0; 3];
                let mut xt = [0.0; 3];
                for k in 0..4 {
                    for i in 0..3 {
                        xi[i] += n[k] * c[k][i];
                        xs[i] += ds[k] * c[k][i];
                        xt[i] += dt[k] * c[k][i];
                    }
                }
                out.push(FacePoint {
                    xi,
                    xi_s: xs,
                    xi_t: xt,
                    weight: wgt_s * wgt_t,
                });
            }
        }
    } else {
        // collapsed rule on the unit triangle: s = u, t = (1 - u) v, Jacobian (1 - u)
        let xs: [f64; 3] = std::array::from_fn(|i| c[1][i] - c[0][i]);
        let xt: [f64; 3] = std::array::from_fn(|i| c[2][i] - c[0][i]);
        for &(u, wu) in &g {
            for &(v, wv) in &g {
                let (u, v) = ((u + 1.0) / 2.0, (v + 1.0) / 2.0);
                let (s, t) = (u, (1.0 - u) * v);
                let xi = std::array::from_fn(|i| c[0][i] + s * xs[i] + t * xt[i]);
                out.push(FacePoint {
                    xi,
                    xi_s: xs,
                    xi_t: xt,
                    weight: wu * wv / 4.0 * (1.0 - u),
                });
            }
        }
    }
    out
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Consistent normal-mass matrix of one face (3n x 3n over the element's n nodes, node-major,
/// row-major): M_ab,ij = int( mu N_a N_b n_i n_j ) dA. Also returns the face area.
pub fn face_mass(face: &Face, coords: &[[f64; 3]], mu: f64) -> (Vec<f64>, f64) {
    let nn = face.kind.num_nodes();
    let nd = 3 * nn;
    let mut me = vec![0.0; nd * nd];
    let mut n = vec![0.0; nn];
    let mut dn = vec![[0.0; 3]; nn];
    let mut area = 0.0;
    for FacePoint {
        xi,
        xi_s,
        xi_t,
        weight: w,
    } in face_points(face.kind, face.corners)
    {
        face.kind.eval(xi, &mut n, &mut dn);
        // J[i][k] = dx_i / dxi_k; tangents x_s = J xi_s, x_t = J xi_t
        let mut x_s = [0.0; 3];
        let mut x_t = [0.0; 3];
        for (a, x) in coords.iter().enumerate() {
            let ds: f64 = (0..3).map(|k| dn[a][k] * xi_s[k]).sum();
            let dt: f64 = (0..3).map(|k| dn[a][k] * xi_t[k]).sum();
            for i in 0..3 {
                x_s[i] += x[i] * ds;
                x_t[i] += x[i] * dt;
            }
        }
        let nv = cross(x_s, x_t);
        let da = (nv[0] * nv[0] + nv[1] * nv[1] + nv[2] * nv[2]).sqrt();
        if da == 0.0 {
            continue;
        }
        let unit = [nv[0] / da, nv[1] / da, nv[2] / da];
        let wa = w * da;
        area += wa;
        for a in 0..nn {
            if n[a] == 0.0 {
                continue;
            }
            for b in 0..nn {
                let s = mu * wa * n[a] * n[b];
                if s == 0.0 {
                    continue;
                }
                for i in 0..3 {
                    for j in 0..3 {
                        me[(3 * a + i) * nd + 3 * b + j] += s * unit[i] * unit[j];
                    }
                }
            }
        }
    }
    (me, area)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One element of `kind` on its reference shape (hexahedra mapped to the unit cube), the
    /// nodes of its face z = `z_face` in the set "face".
    fn single(kind: ElementKind, z_face: f64) -> Mesh {
        let nodes: Vec<[f64; 3]> = (0..kind.num_nodes())
            .map(|a| {
                let r = kind.ref_node(a);
                if kind.is_tet() {
                    r
                } else {
                    [(r[0] + 1.0) / 2.0, (r[1] + 1.0) / 2.0, (r[2] + 1.0) / 2.0]
                }
            })
            .collect();
        let face: Vec<usize> = (0..nodes.len())
            .filter(|&a| nodes[a][2] == z_face)
            .collect();
        let conn = (0..nodes.len()).collect();
        let mut mesh = Mesh {
            nodes,
            blocks: vec![crate::mesh::ElementBlock { kind, conn }],
            ..Mesh::default()
        };
        mesh.node_sets.insert("face".into(), face);
        mesh
    }

    /// Total normal mass of a flat face: a rigid unit motion along the normal gives
    /// u^T M u = mu A exactly (the quadrature is exact for N_a N_b on flat faces); tangential
    /// motion gives zero (the layer slides). Unit cube top (A = 1), unit tetrahedron bottom
    /// (A = 1/2).
    #[test]
    fn flat_face_carries_mu_times_area_in_the_normal_direction_only() {
        for (kind, z_face, a_exact) in [
            (ElementKind::Hex8, 1.0, 1.0),
            (ElementKind::Hex20, 1.0, 1.0),
            (ElementKind::Tet4, 0.0, 0.5),
            (ElementKind::Tet10, 0.0, 0.5),
        ] {
            let mesh = single(kind, z_face);
            let faces = boundary_faces(&mesh, "face").unwrap();
            assert_eq!(faces.len(), 1, "{kind:?}");
            let coords = mesh.coords_of(&faces[0].nodes);
            let (me, area) = face_mass(&faces[0], &coords, 2.5);
            assert!((area - a_exact).abs() < 1e-14, "{kind:?}: area {area}");
            let nd = 3 * kind.num_nodes();
            let quad = |dir: usize| -> f64 {
                let mut s = 0.0;
                for a in 0..kind.num_nodes() {
                    for b in 0..kind.num_nodes() {
                        s += me[(3 * a + dir) * nd + 3 * b + dir];
                    }
                }
                s
            };
            assert!(
                (quad(2) - 2.5 * a_exact).abs() < 1e-13,
                "{kind:?}: {}",
                quad(2)
            );
            assert!(quad(0).abs() < 1e-15 && quad(1).abs() < 1e-15, "{kind:?}");
        }
    }

    #[test]
    fn a_set_without_whole_faces_is_an_error_naming_it() {
        let mut mesh = single(ElementKind::Hex8, 1.0);
        mesh.node_sets.insert("one".into(), vec![0]);
        let e = boundary_faces(&mesh, "one").unwrap_err().to_string();
        assert!(e.contains("'one'"), "{e}");
        let e = boundary_faces(&mesh, "nope").unwrap_err().to_string();
        assert!(e.contains("nope"), "{e}");
    }
}
