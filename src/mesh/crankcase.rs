//! Parametric crankcase of an in-line engine with wet liners.
//!
//! Frame (shared with the liner, see [`super::liner`]): z is the cylinder axis with z = 0 at the
//! liner bottom; x runs along the crankshaft; the thrust side is +y. Cylinder c (1-based) has
//! its axis at x_c = (c - (N + 1) / 2) p, y = 0 (p the cylinder pitch).
//!
//! Plan: each cylinder owns a cell x in [x_c - p/2, x_c + p/2], y in [-b, b] (b = r_f + t_w,
//! r_f the flange radius, t_w the jacket wall) meshed as an O-grid: ring 0 between the bore
//! r_b (the liner's pilot radius; its outer radius for a plain tube) and r_f, then
//! `wall_layers` rings blending linearly from the circle r_f to the cell rectangle. The circumference is split into four sectors at the rectangle's corner
//! angles (alpha = atan(b / (p/2))) so the rectangle's corners are nodes and neighbouring cells
//! share their boundary nodes; thrust (+y) and anti-thrust lines fall on nodes.
//!
//! Height zones, bottom to top, and what is solid in each:
//! - oil-pan rail (one element layer at the bottom): skirt walls, bulkheads, end walls and an
//!   outward flange (the rail) on both sides;
//! - crank bay (below the liner, down to `skirt_depth`): skirt walls (the wall rings on the
//!   y-sides), bulkheads (all rings on the x-sides, between cylinders and at the ends);
//! - hanging zone (z in [0, z_g], z_g the guide band's lower edge; empty when the band ends the
//!   liner): the wall rings only, ring 0 is the open space around the liner's free lower end;
//! - lower support (z in [z_g, z_g + guide_height]): all rings; its bore (r = r_b) is the
//!   liner's radial guide seat;
//! - water jacket (up to the deck): the wall rings only; ring 0 is the coolant space;
//! - deck (`deck_thickness` below the flange seat): all rings; its top face carries the liner
//!   flange (seat annulus r_b..r_f) under the head-bolt clamp load.
//!
//! Front (gear-end, -x) and rear (flywheel-end, +x) end walls of their own thickness close the
//! block over its full height.
//!
//! Node sets: `seat_c` (deck top, r <= r_f around cylinder c), `guide_c` (support bore,
//! r = r_b, over the guide band), `point_c_k` (jacket wall, thrust side, at the liner's
//! analysis heights, top to bottom), `deck_top`, `pan_rail` (bottom face, z = -skirt_depth).

use super::lattice::{level_at, subdivide, Key, Lattice};
use super::merge::merge;
use super::Mesh;
use std::collections::BTreeMap;
use std::f64::consts::PI;

pub use crate::scene::spec::CrankcaseGeometry;

pub use crate::scene::spec::CrankcaseMeshing;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Zone {
    Rail,
    Bay,
    Hanging,
    Support,
    Jacket,
    Deck,
}

impl CrankcaseGeometry {
    /// Axis x of cylinder `c` (0-based).
    pub fn axis_x(&self, c: usize) -> f64 {
        crate::scene::bore_axis_x(self.cylinders, self.pitch, c)
    }
    /// Half-width b of the block (y extent of a cell).
    pub fn half_width(&self) -> f64 {
        self.flange_radius + self.jacket_wall
    }
    /// Corner angle alpha of a cell rectangle.
    fn corner_angle(&self) -> f64 {
        self.half_width().atan2(self.pitch / 2.0)
    }
}

/// Angle of doubled circumferential index `j2` (of `8 s` per turn, `s` elements per sector);
/// sector 0 spans [-alpha, alpha], 1 [alpha, pi - alpha], 2 and 3 likewise.
fn sector_angle(j2: usize, s: usize, alpha: f64) -> f64 {
    let per = 2 * s;
    let sector = (j2 / per) % 4;
    let u = (j2 % per) as f64 / per as f64;
    let (start, span) = match sector {
        0 => (-alpha, 2.0 * alpha),
        1 => (alpha, PI - 2.0 * alpha),
        2 => (PI - alpha, 2.0 * alpha),
        _ => (PI + alpha, PI - 2.0 * alpha),
    };
    start + u * span
}

/// Point where the ray at angle `th` from the cell centre leaves the rectangle |x| <= a, |y| <= b.
fn rect_point(th: f64, a: f64, b: f64) -> [f64; 2] {
    let (c, s) = (th.cos(), th.sin());
    let t = (a / c.abs().max(1e-300)).min(b / s.abs().max(1e-300));
    [t * c, t * s]
}

/// The z levels of the crankcase's cells: the rail, then the zone limits and the analysis
/// heights as exact levels, subdivided to at most the axial size.
fn z_levels(geo: &CrankcaseGeometry, meshing: &CrankcaseMeshing) -> Vec<f64> {
    let z_bot = -geo.skirt_depth;
    let z_deck = geo.seat_z - geo.deck_thickness;
    let mut z_levels = vec![z_bot, z_bot + geo.rail_height];
    subdivide(
        &mut z_levels,
        z_bot + geo.rail_height,
        0.0,
        meshing.axial_size,
    );
    let guide_top = geo.guide_bottom + geo.guide_height;
    let mut planes = vec![0.0, geo.guide_bottom, guide_top, z_deck];
    planes.extend(geo.analysis_z.iter().copied());
    planes.sort_by(|p, q| p.partial_cmp(q).unwrap());
    planes.dedup_by(|p, q| (*p - *q).abs() < 1e-9);
    for w in planes.windows(2) {
        subdivide(&mut z_levels, w[0], w[1], meshing.axial_size);
    }
    subdivide(&mut z_levels, z_deck, geo.seat_z, meshing.axial_size);
    z_levels
}

/// The zone of cell layer `k` (by its mid-height).
fn zone(geo: &CrankcaseGeometry, z_levels: &[f64], k: usize) -> Zone {
    let zm = 0.5 * (z_levels[k] + z_levels[k + 1]);
    if k == 0 {
        Zone::Rail
    } else if zm < 0.0 {
        Zone::Bay
    } else if zm < geo.guide_bottom {
        Zone::Hanging
    } else if zm < geo.guide_bottom + geo.guide_height {
        Zone::Support
    } else if zm < geo.seat_z - geo.deck_thickness {
        Zone::Jacket
    } else {
        Zone::Deck
    }
}

/// Cylinder `c`'s cell: rings from the bore (the liner's pilot radius) to the flange radius, then the
/// wall out to the cell's rectangle; the jacket and the hanging zone leave the coolant ring
/// (i = 0) open, the bays the y sides.
fn cylinder_cell(
    geo: &CrankcaseGeometry,
    meshing: &CrankcaseMeshing,
    z_levels: &[f64],
    c: usize,
) -> Mesh {
    let (ro, rf) = (geo.bore_radius, geo.flange_radius);
    let (a, b) = (geo.pitch / 2.0, geo.half_width());
    let (alpha, s, nw) = (geo.corner_angle(), meshing.per_sector, meshing.wall_layers);
    let xc = geo.axis_x(c);
    let active = |i: usize, j: usize, k: usize| -> bool {
        let x_side = (j / s) % 2 == 0;
        match zone(geo, z_levels, k) {
            Zone::Deck | Zone::Support => true,
            Zone::Jacket | Zone::Hanging => i >= 1,
            Zone::Bay | Zone::Rail => x_side || i >= 1,
        }
    };
    let coord = |key: Key| -> [f64; 3] {
        let th = sector_angle(key[1], s, alpha);
        let z = level_at(z_levels, key[2]);
        let (x, y) = if key[0] <= 2 {
            let r = ro + (rf - ro) * key[0] as f64 / 2.0;
            (r * th.cos(), r * th.sin())
        } else {
            let t = (key[0] - 2) as f64 / (2 * nw) as f64;
            let p = rect_point(th, a, b);
            (
                (1.0 - t) * rf * th.cos() + t * p[0],
                (1.0 - t) * rf * th.sin() + t * p[1],
            )
        };
        [xc + x, y, z]
    };
    let lat = Lattice {
        cells: [1 + nw, 4 * s, z_levels.len() - 1],
        periodic_j: true,
        active: &active,
        coord: &coord,
    };
    lat.generate(meshing.kind).mesh
}

/// x of the front and rear end walls' inner faces.
fn end_faces(geo: &CrankcaseGeometry) -> (f64, f64) {
    let a = geo.pitch / 2.0;
    (geo.axis_x(0) - a, geo.axis_x(geo.cylinders - 1) + a)
}

/// The end walls: front (-x; i -> -x, j -> -y) and rear (+x; i -> +x, j -> +y).
fn end_walls(geo: &CrankcaseGeometry, meshing: &CrankcaseMeshing, z_levels: &[f64]) -> Vec<Mesh> {
    let (a, b) = (geo.pitch / 2.0, geo.half_width());
    let (alpha, s) = (geo.corner_angle(), meshing.per_sector);
    let (x_front, x_rear) = end_faces(geo);
    let all = |_: usize, _: usize, _: usize| true;
    let mut out = Vec::new();
    for (x0, dir, t, sector) in [
        (x_front, -1.0, geo.front_wall, 2usize),
        (x_rear, 1.0, geo.rear_wall, 0usize),
    ] {
        let coord = |key: Key| -> [f64; 3] {
            let th = sector_angle(sector * 2 * s + key[1], s, alpha);
            let y = rect_point(th, a, b)[1];
            [
                x0 + dir * t * key[0] as f64 / 2.0,
                y,
                level_at(z_levels, key[2]),
            ]
        };
        let lat = Lattice {
            cells: [1, s, z_levels.len() - 1],
            periodic_j: false,
            active: &all,
            coord: &coord,
        };
        out.push(lat.generate(meshing.kind).mesh);
    }
    out
}

/// The oil-pan rails along both sides: x stations from the front end wall to the rear end
/// wall, matching the cells' nodes (doubled for quadratic elements).
fn rails(geo: &CrankcaseGeometry, meshing: &CrankcaseMeshing, z_levels: &[f64]) -> Vec<Mesh> {
    let (a, b) = (geo.pitch / 2.0, geo.half_width());
    let (alpha, s) = (geo.corner_angle(), meshing.per_sector);
    let (x_front, x_rear) = end_faces(geo);
    let mut xs: Vec<f64> = vec![x_front - geo.front_wall, x_front - geo.front_wall / 2.0];
    for c in 0..geo.cylinders {
        let xc = geo.axis_x(c);
        // sector 3 runs from x = -a to x = +a along y = -b
        for j2 in 0..2 * s {
            let th = sector_angle(6 * s + j2, s, alpha);
            xs.push(xc + rect_point(th, a, b)[0]);
        }
    }
    xs.push(x_rear);
    xs.push(x_rear + geo.rear_wall / 2.0);
    xs.push(x_rear + geo.rear_wall);
    let nx = (xs.len() - 1) / 2;
    let all = |_: usize, _: usize, _: usize| true;
    let mut out = Vec::new();
    for side in [-1.0f64, 1.0] {
        // -y side: i -> -y, j -> +x; +y side: i -> +y, j -> -x (right-handed with k -> z)
        let coord = |key: Key| -> [f64; 3] {
            let x = if side < 0.0 {
                xs[key[1]]
            } else {
                xs[xs.len() - 1 - key[1]]
            };
            let y = side * (b + geo.rail_width * key[0] as f64 / 2.0);
            [x, y, level_at(z_levels, key[2])]
        };
        let lat = Lattice {
            cells: [1, nx, 1],
            periodic_j: false,
            active: &all,
            coord: &coord,
        };
        out.push(lat.generate(meshing.kind).mesh);
    }
    out
}

/// The named node sets: per cylinder the seat, the guide and the analysis points; the deck
/// top and the pan rail.
fn named_sets(nodes: &[[f64; 3]], geo: &CrankcaseGeometry) -> BTreeMap<String, Vec<usize>> {
    let (ro, rf) = (geo.bore_radius, geo.flange_radius);
    let guide_top = geo.guide_bottom + geo.guide_height;
    let tol = 1e-6 * geo.pitch;
    let mut sets = BTreeMap::new();
    let select = |pred: &dyn Fn(&[f64; 3]) -> bool| -> Vec<usize> {
        (0..nodes.len()).filter(|&n| pred(&nodes[n])).collect()
    };
    for c in 0..geo.cylinders {
        let xc = geo.axis_x(c);
        let r = |p: &[f64; 3]| ((p[0] - xc).powi(2) + p[1].powi(2)).sqrt();
        sets.insert(
            format!("seat_{}", c + 1),
            select(&|p| (p[2] - geo.seat_z).abs() < tol && r(p) <= rf + tol),
        );
        sets.insert(
            format!("guide_{}", c + 1),
            select(&|p| {
                (r(p) - ro).abs() < tol && p[2] > geo.guide_bottom - tol && p[2] < guide_top + tol
            }),
        );
        for (k, &z) in geo.analysis_z.iter().enumerate() {
            sets.insert(
                format!("point_{}_{}", c + 1, k + 1),
                select(&|p| {
                    (p[0] - xc).abs() < tol && (p[1] - rf).abs() < tol && (p[2] - z).abs() < tol
                }),
            );
        }
    }
    sets.insert(
        "deck_top".into(),
        select(&|p| (p[2] - geo.seat_z).abs() < tol),
    );
    let z_bot = -geo.skirt_depth;
    sets.insert("pan_rail".into(), select(&|p| (p[2] - z_bot).abs() < tol));
    sets
}

/// Generates the crankcase mesh with its named node sets: the cylinder cells, the end walls
/// and the rails, merged.
pub fn generate(geo: &CrankcaseGeometry, meshing: &CrankcaseMeshing) -> Mesh {
    let z = z_levels(geo, meshing);
    let mut parts: Vec<Mesh> = (0..geo.cylinders)
        .map(|c| cylinder_cell(geo, meshing, &z, c))
        .collect();
    parts.extend(end_walls(geo, meshing, &z));
    parts.extend(rails(geo, meshing, &z));
    let mut mesh = merge(parts, 1e-7 * geo.pitch);
    mesh.node_sets = named_sets(&mesh.nodes, geo);
    mesh
}
