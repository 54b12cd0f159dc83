//! A piston in its bore: the bore lines' locations, the skirt slices that can touch them at a
//! step, the piston at rest, and the residual response at the analysis points. Shared by the
//! engine cycle and the windows.

use super::contact::{self, Body, FilmGroup, Location, Slice};
use crate::linalg::dense::{row, Dense};
use crate::piston::Piston;

/// Location of height `z` on a bore line with ascending node heights `zs`, DOFs from `first`.
fn locate(zs: &[f64], z: f64, first: usize) -> Option<Location> {
    let n = zs.len();
    if n < 2 || z < zs[0] || z > zs[n - 1] {
        return None;
    }
    let i = zs.partition_point(|&a| a <= z).clamp(1, n - 1);
    let t = (z - zs[i - 1]) / (zs[i] - zs[i - 1]);
    Some(Location {
        dofs: [first + i - 1, first + i],
        weights: [1.0 - t, t],
    })
}

/// A cylinder's two bore lines: node heights (ascending) and the first contact DOF (thrust
/// nodes from `first`, then the anti-thrust nodes).
pub(crate) struct BoreLines<'a> {
    pub thrust_z: &'a [f64],
    pub antithrust_z: &'a [f64],
    pub first: usize,
}

/// Piston `body` in its bore at this step: its loads (pin depth) and the bore lines it can
/// touch, `liner_top` the height of the liner's top.
pub(crate) struct PistonInBore<'a, 'p> {
    pub piston: &'p Piston,
    pub loads: &'a crate::piston::PistonLoads,
    pub liner_top: f64,
    pub bore: &'a BoreLines<'a>,
    pub body: usize,
}

/// Appends the slices of piston `body` that lie on the bore lines at this step's pin depth, and
/// their (body, thrust side, slice, height) to `meta`. A slice at height
/// z = liner_top - pin_depth + h_i outside the bore line's node range has no liner to touch.
pub(crate) fn push_slices<'p>(
    at: &PistonInBore<'_, 'p>,
    prev_penetration: &dyn Fn(bool, usize) -> (f64, f64),
    slices: &mut Vec<Slice<'p>>,
    meta: &mut Vec<(usize, bool, usize, f64)>,
) {
    let PistonInBore {
        piston,
        loads,
        liner_top,
        bore,
        body,
    } = *at;
    let skirt = &piston.skirt;
    let nt = bore.thrust_z.len();
    for (side, zs, first) in [
        (true, bore.thrust_z, bore.first),
        (false, bore.antithrust_z, bore.first + nt),
    ] {
        for i in 0..skirt.heights.len() {
            let z = liner_top - loads.pin_depth + skirt.heights[i];
            if let Some(at) = locate(zs, z, first) {
                slices.push(Slice {
                    body,
                    row: piston.slice_row(i, side),
                    force_row: piston.slice_force_row(i, side, loads),
                    gap: skirt.gaps[i],
                    law: &skirt.laws[i],
                    damping: piston.contact_damping,
                    at,
                    prev_penetration: prev_penetration(side, i).0,
                    prev_rate: prev_penetration(side, i).1,
                });
                meta.push((body, side, i, z));
            }
        }
    }
}

/// The oil films of a step's slices: one group per piston side, its slices in skirt order
/// (`meta`: body, thrust side, skirt slice, height of each slice, as [`push_slices`] gives
/// them); `axial(b)` is body b's axial velocity [m/s]. None for a dry skirt.
pub(crate) fn film_groups<'p>(
    piston: &'p Piston,
    meta: &[(usize, bool, usize, f64)],
    axial: &dyn Fn(usize) -> f64,
) -> Vec<FilmGroup<'p>> {
    let Some(film) = piston.film.as_ref() else {
        return Vec::new();
    };
    let mut out: Vec<FilmGroup<'p>> = Vec::new();
    for (k, &(b, side, i, _)) in meta.iter().enumerate() {
        let same = out.last().is_some_and(|g| {
            let &(gb, gs, gi, _) = &meta[*g.slices.last().expect("a group has a slice")];
            gb == b && gs == side && gi + 1 == i
        });
        if same {
            out.last_mut().expect("checked").slices.push(k);
        } else {
            out.push(FilmGroup {
                slices: vec![k],
                first: i,
                film,
                axial_velocity: axial(b),
            });
        }
    }
    out
}

/// The pin's friction torque on the tilt under `loads` ([`contact::TiltFriction`]; zero
/// without pin friction).
pub fn tilt_friction(piston: &Piston, loads: &crate::piston::PistonLoads) -> contact::TiltFriction {
    contact::TiltFriction {
        max_torque: loads.pin_torque,
        rod_rate: loads.rod_rate,
        slip_rate: piston.pin_slip_rate,
    }
}

/// The piston at rest, centred, at its own crank angle `deg`: acceleration from the loads.
pub fn body_at_rest(piston: &Piston, deg: f64) -> Body {
    let mass = piston.mass_matrix();
    let f = piston.loads(deg).force;
    let det = mass[0][0] * mass[1][1] - mass[0][1] * mass[1][0];
    Body {
        mass,
        a: [
            (mass[1][1] * f[0] - mass[0][1] * f[1]) / det,
            (mass[0][0] * f[1] - mass[1][0] * f[0]) / det,
        ],
        applied: f,
        ..Body::default()
    }
}

/// Residual point displacement R_pc F of `forces` at `locs` (contact DOFs interpolated).
pub fn residual_displacement(r: &Dense, locs: &[Location], forces: &[f64]) -> Vec<f64> {
    (0..r.nrows())
        .map(|p| {
            let row = row(r, p);
            locs.iter()
                .zip(forces)
                .filter(|(_, &f)| f != 0.0)
                .map(|(at, &f)| {
                    (at.weights[0] * row[at.dofs[0]] + at.weights[1] * row[at.dofs[1]]) * f
                })
                .sum()
        })
        .collect()
}
