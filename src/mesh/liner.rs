//! Parametric wet cylinder liner: an annular tube with a top flange.
//!
//! The wall's outer radius is the wet wall's r_o in the coolant zone and the pilot radius r_p
//! (`pilot_diameter`, the crankcase's bore) on the lower guide band and inside the deck bore,
//! from the deck's underside up to the flange; the element layer next to a pilot edge tapers
//! straight between the two. A plain tube has r_p = r_o.
//!
//! Frame: z is the cylinder axis, z = 0 at the liner bottom and z = `length` at its top (the
//! cylinder-head face). The thrust side is +y (theta = 90 deg), the anti-thrust side -y; x is
//! along the crankshaft. The flange occupies the top `flange_height` between the outer diameter
//! and the flange diameter. Axial lattice planes are placed exactly at the flange underside, the
//! edges of the lower guide band and every analysis point, so those sets are exact node sets.
//!
//! Node sets produced:
//! - `flange_seat`: flange underside (bears on the crankcase deck counterbore),
//! - `flange_top`: flange top face (head-bolt clamp load),
//! - `lower_guide`: outer surface of the guide band, `guide_bottom <= z <= guide_bottom +
//!   guide_height` (radial support in the crankcase; at the liner bottom by default, higher up
//!   for a short-jacket liner whose lower end hangs free in the crank bay),
//! - `bore_thrust`, `bore_antithrust`: bore lines at theta = 90 and 270 deg (piston contact),
//! - `outer_thrust`: coolant-side line at theta = 90 deg,
//! - `coolant_wetted`: the outer surface in the coolant zone, from the guide band's top up to
//!   the deck's underside (the flange underside without a deck): where a coolant layer's
//!   mass acts (`fem::surface`) and the maps are drawn,
//! - `point_1` .. `point_n`: single coolant-side nodes on the thrust side, top to bottom.

use super::lattice::{level_at, subdivide, Key, Lattice};

/// Name of the node set of the liner's wet outer surface (the coolant layer's mass acts there).
pub const COOLANT_WETTED: &str = "coolant_wetted";
use super::Mesh;
use std::f64::consts::PI;

pub use crate::scene::spec::LinerGeometry;

pub use crate::scene::spec::LinerMeshing;

/// The wall's outer radius at each axial level: the pilot radius r_p on the guide band and
/// from the deck's underside up, the wet wall's r_o elsewhere. Between two levels of different
/// radii the element is a straight taper (`level_at` puts mid-side nodes half-way).
fn outer_radii(z_levels: &[f64], geo: &LinerGeometry, deck: Option<f64>) -> Vec<f64> {
    let tol = 1e-9;
    let (g0, g1) = (geo.guide_bottom, geo.guide_bottom + geo.guide_height);
    z_levels
        .iter()
        .map(|&z| {
            let pilot = (z > g0 - tol && z < g1 + tol) || deck.is_some_and(|d| z > d - tol);
            if pilot {
                geo.pilot_diameter / 2.0
            } else {
                geo.outer_diameter / 2.0
            }
        })
        .collect()
}

/// Maps a lattice radius r (levels laid out for the wet wall [r_i, r_o] and the flange
/// [r_o, r_f]) onto a wall whose outer radius is `outer` at this height:
/// r' = r_i + (r - r_i) (outer - r_i) / (r_o - r_i) in the wall, r' = outer + (r - r_o) (r_f -
/// outer) / (r_f - r_o) across the flange (identity where outer = r_o).
fn pilot_radius(r: f64, outer: f64, geo: &LinerGeometry) -> f64 {
    let (ri, ro, rf) = (
        geo.inner_diameter / 2.0,
        geo.outer_diameter / 2.0,
        geo.flange_outer_diameter / 2.0,
    );
    if outer == ro {
        r
    } else if r <= ro {
        ri + (r - ri) * (outer - ri) / (ro - ri)
    } else {
        outer + (r - ro) * (rf - outer) / (rf - ro)
    }
}

/// Generates the liner mesh with its named node sets.
pub fn generate(geo: &LinerGeometry, meshing: &LinerMeshing) -> Mesh {
    let (r_levels, z_levels, deck) = levels(geo, meshing);
    let nr_wall = meshing.radial;
    let nt = meshing.circumferential;
    let z_flange = geo.length - geo.flange_height;
    let k_flange = z_levels
        .iter()
        .position(|&z| (z - z_flange).abs() < 1e-9)
        .expect("flange plane is a level");
    let active = |i: usize, _j: usize, k: usize| i < nr_wall || k >= k_flange;
    let outer = outer_radii(&z_levels, geo, deck);
    let coord = |key: Key| {
        let r = pilot_radius(level_at(&r_levels, key[0]), level_at(&outer, key[2]), geo);
        let th = PI * key[1] as f64 / nt as f64;
        let z = level_at(&z_levels, key[2]);
        [r * th.cos(), r * th.sin(), z]
    };
    let lat = Lattice {
        cells: [r_levels.len() - 1, nt, z_levels.len() - 1],
        periodic_j: true,
        active: &active,
        coord: &coord,
    };
    let lm = lat.generate(meshing.kind);
    let mut mesh = lm.mesh;
    let levels = SetLevels {
        z_levels: &z_levels,
        k_flange,
        nr_wall,
        nt,
    };
    mesh.node_sets.extend(named_sets(&lm.keys, geo, &levels));
    // sort bore lines by height so later stages can interpolate along them
    for name in ["bore_thrust", "bore_antithrust", "outer_thrust"] {
        let nodes = &mesh.nodes;
        if let Some(v) = mesh.node_sets.get_mut(name) {
            v.sort_by(|&a, &b| nodes[a][2].partial_cmp(&nodes[b][2]).unwrap());
        }
    }
    mesh
}

/// The radial and axial lattice levels: the wall's radial layers, then the flange's; axial
/// planes at the liner's ends, the guide band's edges, the flange underside, the analysis
/// points and (when the pilots differ from the wet wall) the deck's underside, returned as
/// the third value.
fn levels(geo: &LinerGeometry, meshing: &LinerMeshing) -> (Vec<f64>, Vec<f64>, Option<f64>) {
    let (ri, ro, rf) = (
        geo.inner_diameter / 2.0,
        geo.outer_diameter / 2.0,
        geo.flange_outer_diameter / 2.0,
    );
    let mut r_levels = vec![ri];
    subdivide(&mut r_levels, ri, ro, (ro - ri) / meshing.radial as f64);
    if rf > ro {
        subdivide(
            &mut r_levels,
            ro,
            rf,
            (rf - ro) / meshing.radial_flange.max(1) as f64,
        );
    }
    let deck = geo.deck_plane();
    let planes = geo.axial_planes();
    let mut z_levels = vec![planes[0]];
    for w in planes.windows(2) {
        subdivide(&mut z_levels, w[0], w[1], meshing.axial_size);
    }
    (r_levels, z_levels, deck)
}

/// The doubled lattice index (mid-side nodes odd) of the wet zone's top: the highest node
/// level at or below the deck's underside (the liner enters the deck bore there; no coolant
/// above it), or the flange underside without a deck (or with one outside the guide band's
/// top .. the flange). The same nodes as the found set's rule, z <= the deck's underside.
fn wet_top_index(geo: &LinerGeometry, z_levels: &[f64]) -> usize {
    let top = (geo.deck_in_wall()).unwrap_or(geo.length - geo.flange_height);
    (0..2 * z_levels.len() - 1)
        .rposition(|k| level_at(z_levels, k) < top + 1e-9)
        .unwrap_or(0)
}

/// Where the named sets lie in the lattice.
struct SetLevels<'a> {
    z_levels: &'a [f64],
    k_flange: usize,
    nr_wall: usize,
    nt: usize,
}

/// The named node sets (module docs) from the nodes' lattice keys (doubled indices).
fn named_sets(
    keys: &[Key],
    geo: &LinerGeometry,
    l: &SetLevels<'_>,
) -> std::collections::BTreeMap<String, Vec<usize>> {
    let top = 2 * (l.z_levels.len() - 1);
    let kf = 2 * l.k_flange;
    let iwall = 2 * l.nr_wall;
    let jthrust = l.nt / 2; // theta = 90 deg in doubled indices (2 nt per turn)
    let janti = 3 * l.nt / 2;
    let z_index = |z: f64| {
        2 * l
            .z_levels
            .iter()
            .position(|&w| (w - z).abs() < 1e-9)
            .expect("plane is a level")
    };
    let guide_top = geo.guide_bottom + geo.guide_height;
    let (kguide0, kguide1) = (z_index(geo.guide_bottom), z_index(guide_top));
    let select = |pred: &dyn Fn(&Key) -> bool| -> Vec<usize> {
        (0..keys.len()).filter(|&n| pred(&keys[n])).collect()
    };
    let mut sets = std::collections::BTreeMap::new();
    sets.insert(
        "flange_seat".into(),
        select(&|k| k[2] == kf && k[0] >= iwall),
    );
    sets.insert(
        "flange_top".into(),
        select(&|k| k[2] == top && k[0] >= iwall),
    );
    sets.insert(
        "lower_guide".into(),
        select(&|k| k[0] == iwall && k[2] >= kguide0 && k[2] <= kguide1),
    );
    sets.insert(
        "bore_thrust".into(),
        select(&|k| k[0] == 0 && k[1] == jthrust),
    );
    sets.insert(
        "bore_antithrust".into(),
        select(&|k| k[0] == 0 && k[1] == janti),
    );
    sets.insert(
        "outer_thrust".into(),
        select(&|k| k[0] == iwall && k[1] == jthrust && k[2] <= kf),
    );
    let kwet = wet_top_index(geo, l.z_levels);
    sets.insert(
        COOLANT_WETTED.into(),
        select(&|k| k[0] == iwall && k[2] >= kguide1 && k[2] <= kwet),
    );
    for (p, d) in geo.analysis_depths.iter().enumerate() {
        let kz = z_index(geo.length - d);
        sets.insert(
            format!("point_{}", p + 1),
            select(&|k| k[0] == iwall && k[1] == jthrust && k[2] == kz),
        );
    }
    sets
}
