//! What the ROM build reads: its inputs, its errors, the interface fields of both parts, the
//! preload loads, the liner's contact and point rows, the crankcase's outputs, the components.

use crate::fem::surface::SurfaceMass;
use crate::mesh::liner::COOLANT_WETTED;
use crate::mesh::Mesh;
use crate::reduce::craig_bampton::{CbSettings, InterfaceBlock, Load, Output, Part};
use crate::reduce::engine;
use crate::reduce::interface::{self, Direction, InterfaceShape};
use crate::reduce::part_cache::PartCacheError;
use crate::scene::spec::Elastic;

/// Everything the build needs, already loaded and checked.
pub struct RomInputs<'a> {
    pub liner: &'a Mesh,
    pub liner_material: Elastic,
    /// Normal surface masses on the liner (the coolant layer on its wet outer surface).
    pub liner_surface_mass: Vec<SurfaceMass>,
    pub crankcase: &'a Mesh,
    pub crankcase_material: Elastic,
    pub crankcase_fix: Vec<String>,
    /// Radii and heights that define the interfaces \[m\]: the bore (the liner's pilot
    /// radius), the flange, the seat height and the guide band.
    pub bore_radius: f64,
    /// No crankcase node may lie inside this radius of a bore axis along the liner
    /// (`check_fit`): the bore radius for a generated crankcase; a crankcase deck's bores
    /// follow a stepped liner's own pilots (a lower guide narrower than the deck's pilot),
    /// so only its wet wall r_o is certain.
    pub fit_radius: f64,
    /// The crankcase is a deck (not generated): the overlap refusals name its placement as a
    /// cause.
    pub crankcase_deck: bool,
    pub flange_radius: f64,
    pub seat_z: f64,
    pub guide_height: f64,
    /// Height of the guide band's lower edge above the liner bottom \[m\].
    pub guide_bottom: f64,
    pub analysis_points: usize,
    /// Bore axis x of every cylinder (all cylinders of the crankcase).
    pub axis_x: Vec<f64>,
    pub pitch: f64,
    /// Modelled cylinders, 1-based.
    pub cylinders: Vec<usize>,
    pub clamp_force: f64,
    pub band_hz: f64,
    pub cutoff_hz: f64,
    pub harmonics: usize,
    /// Residual-vector load patterns: a hat function every this many bore-line nodes on each
    /// side (1: every node; 0: none, static correction only).
    pub residual_vector_spacing: usize,
    /// Components the crankcase is cut into (1: reduced in one piece; [`crate::reduce::substructure`]).
    pub crankcase_components: usize,
    /// Shapes per cut between crankcase components.
    pub cut_shapes: usize,
    /// Components' modes up to this multiple of `cutoff_hz`.
    pub component_cutoff_factor: f64,
    /// Shapes added to each cut from a first assembly (0: none).
    pub cut_enrichment: usize,
    /// Keep full bases for recovery (mode shapes on the meshes).
    pub keep_bases: bool,
    /// The component cache directory: each part's reduction read from it or stored in it
    /// ([`crate::reduce::part_cache`]; not with `keep_bases`).
    pub part_cache: Option<std::path::PathBuf>,
}

/// Failures of the ROM build, naming part and set.
#[derive(Debug, thiserror::Error)]
pub enum RomError {
    #[error(transparent)]
    Reduce(#[from] crate::reduce::craig_bampton::ReduceError),
    #[error("part '{part}': node set '{set}': {msg}")]
    Set {
        part: String,
        set: String,
        msg: String,
    },
    /// The crankcase does not leave room for a liner (1-based cylinder).
    #[error("the crankcase around cylinder {cylinder}'s liner: {msg}")]
    Fit { cylinder: usize, msg: String },
    #[error("engine assembly: {0}")]
    System(#[from] engine::SystemError),
    /// The component cache could not be read or written (the reduction itself succeeded or
    /// was not started).
    #[error(transparent)]
    PartCache(Box<PartCacheError>),
}

impl From<PartCacheError> for RomError {
    fn from(e: PartCacheError) -> Self {
        match e {
            PartCacheError::Reduce(r) => RomError::Reduce(r),
            other => RomError::PartCache(Box::new(other)),
        }
    }
}

impl RomError {
    /// 2 when the input (meshes, sets, scene) is at fault, 1 for numerical failures.
    pub fn exit_code(&self) -> i32 {
        use crate::fem::model::ModelError;
        use crate::reduce::craig_bampton::ReduceError;
        match self {
            RomError::Set { .. } | RomError::Fit { .. } | RomError::PartCache(_) => 2,
            RomError::Reduce(ReduceError::Interface { .. }) => 2,
            RomError::Reduce(
                ReduceError::TooManyModes { .. } | ReduceError::Substructure { .. },
            ) => 2,
            RomError::Reduce(ReduceError::Model {
                source: ModelError::Set(_) | ModelError::NoDofs | ModelError::Surface(_),
                ..
            }) => 2,
            _ => 1,
        }
    }
}

pub(crate) fn set<'m>(mesh: &'m Mesh, part: &str, name: &str) -> Result<&'m [usize], RomError> {
    match mesh.node_set(name) {
        Some(s) if !s.is_empty() => Ok(s),
        Some(_) => Err(RomError::Set {
            part: part.into(),
            set: name.into(),
            msg: "is empty".into(),
        }),
        None => Err(RomError::Set {
            part: part.into(),
            set: name.into(),
            msg: format!("is missing (the mesh has: {})", mesh.set_names().join(", ")),
        }),
    }
}

pub(super) fn block(
    mesh: &Mesh,
    part: &str,
    name: &str,
    cx: f64,
    shape: InterfaceShape,
    harmonics: usize,
    dirs: &[Direction],
) -> Result<InterfaceBlock, RomError> {
    let nodes = set(mesh, part, name)?;
    let coords = mesh.coords_of(nodes);
    let psi = interface::shapes(&coords, cx, shape, harmonics, dirs);
    let cond = interface::conditioning(&psi);
    if cond < 1e-6 {
        return Err(RomError::Set {
            part: part.into(),
            set: name.into(),
            msg: format!(
                "cannot carry the interface field (conditioning {cond:.1e}): {}; too few nodes, or all on one radius/height; refine the mesh there or lower rom.interface_harmonics",
                spread(&coords, cx)
            ),
        });
    }
    Ok(InterfaceBlock {
        set: name.into(),
        psi,
    })
}

/// Refuses a crankcase node inside cylinder `c`'s liner (0-based): within r_fit - tol of the
/// bore axis between the liner's bottom and its flange's underside, or within r_f - tol
/// between the underside and the liner's top (a counterbore narrower than the flange; before,
/// only the first was checked and such a deck ran with the parts overlapping, exit 0).
/// `top` is the liner's top z.
fn overlap(inp: &RomInputs<'_>, c: usize, top: f64, tol: f64) -> Result<(), RomError> {
    let xc = inp.axis_x[c];
    let radius = |p: &[f64; 3]| (p[0] - xc).hypot(p[1]);
    let inside = |p: &[f64; 3]| {
        let (r, z) = (radius(p), p[2]);
        (r < inp.fit_radius - tol && z > tol && z < inp.seat_z - tol)
            || (r < inp.flange_radius - tol && z > inp.seat_z + tol && z < top - tol)
    };
    let Some(n) = inp.crankcase.nodes.iter().position(inside) else {
        return Ok(());
    };
    let p = inp.crankcase.nodes[n];
    let mm = |v: f64| crate::text::num(v * 1e3);
    let (place, cause) = if p[2] < inp.seat_z {
        (
            format!(
                "inside the liner (radius {} mm) below its flange",
                mm(inp.fit_radius)
            ),
            "a crankcase bore narrower than the liner",
        )
    } else {
        (
            format!(
                "inside the liner's flange (radius {} mm)",
                mm(inp.flange_radius)
            ),
            "a counterbore narrower than the liner's flange",
        )
    };
    let frame = if inp.crankcase_deck {
        format!(
            ", or a crankcase deck off the engine frame: bore axes at x = {} mm, y = 0, z up; a tilt of even a fraction of a degree",
            inp.axis_x.iter().map(|&x| mm(x)).collect::<Vec<_>>().join(", ")
        )
    } else {
        String::new()
    };
    Err(RomError::Fit {
        cylinder: c + 1,
        msg: format!(
            "crankcase node {} at ({}, {}, {}) mm is {} mm from the bore axis (x = {} mm, y = 0), {place}: the parts overlap ({cause}{frame})",
            n + 1,
            mm(p[0]),
            mm(p[1]),
            mm(p[2]),
            mm(radius(&p)),
            mm(xc),
        ),
    })
}

/// Where an interface set's nodes `coords` lie about the bore axis at x = `cx`: their count
/// and the ranges of radius and height, in mm (what a conditioning refusal needs to be acted on).
fn spread(coords: &[[f64; 3]], cx: f64) -> String {
    let range = |v: Vec<f64>| {
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let mm = |x: f64| crate::text::num(x * 1e3);
        if hi - lo < 1e-9 {
            mm(lo)
        } else {
            format!("{}..{}", mm(lo), mm(hi))
        }
    };
    if coords.is_empty() {
        return "no nodes".into();
    }
    format!(
        "its {} node(s) at r = {} mm about the bore axis, z = {} mm",
        coords.len(),
        range(coords.iter().map(|p| (p[0] - cx).hypot(p[1])).collect()),
        range(coords.iter().map(|p| p[2]).collect())
    )
}

/// Checks that the crankcase leaves room for each liner and seats it where the liner's
/// flange is (part and set named in the error).
pub(super) fn check_fit(inp: &RomInputs<'_>) -> Result<(), RomError> {
    let tol = 1e-4 * inp.pitch;
    let top = inp
        .liner
        .nodes
        .iter()
        .map(|p| p[2])
        .fold(f64::NEG_INFINITY, f64::max);
    for (c, &xc) in inp.axis_x.iter().enumerate() {
        overlap(inp, c, top, tol)?;
        let seat = set(inp.crankcase, "crankcase", &format!("seat_{}", c + 1))?;
        for &n in seat {
            let p = inp.crankcase.nodes[n];
            let r = (p[0] - xc).hypot(p[1]);
            if (p[2] - inp.seat_z).abs() > tol || r > inp.flange_radius + tol {
                return Err(RomError::Set {
                    part: "crankcase".into(),
                    set: format!("seat_{}", c + 1),
                    msg: format!(
                        "node {} at {:?} is not under the liner flange (z = {} m, r <= {} m)",
                        n + 1,
                        p,
                        inp.seat_z,
                        inp.flange_radius
                    ),
                });
            }
        }
    }
    for &n in set(inp.liner, "liner", "flange_seat")? {
        let z = inp.liner.nodes[n][2];
        if (z - inp.seat_z).abs() > tol {
            return Err(RomError::Set {
                part: "liner".into(),
                set: "flange_seat".into(),
                msg: format!(
                    "node {} is at z = {z} m, not at the flange underside z = {} m",
                    n + 1,
                    inp.seat_z
                ),
            });
        }
    }
    Ok(())
}

/// Interface shape blocks of the liner (in its own frame) and of the crankcase (per bore):
/// seat (radial, tangential, axial; shared), guide radial (shared), guide tangential/axial
/// (private to each part).
pub fn interface_blocks(
    inp: &RomInputs<'_>,
) -> Result<(Vec<InterfaceBlock>, Vec<InterfaceBlock>), RomError> {
    use Direction::*;
    let nh = inp.harmonics;
    let (seat, guide) = seat_and_guide(inp);
    let liner = liner_blocks(inp, inp.liner, 0.0)?;
    let cm = inp.crankcase;
    let mut cc = Vec::new();
    for (c, &xc) in inp.axis_x.iter().enumerate() {
        let k = c + 1;
        cc.push(block(
            cm,
            "crankcase",
            &format!("seat_{k}"),
            xc,
            seat,
            nh,
            &[Radial, Tangential, Axial],
        )?);
        cc.push(block(
            cm,
            "crankcase",
            &format!("guide_{k}"),
            xc,
            guide,
            nh,
            &[Radial],
        )?);
        cc.push(block(
            cm,
            "crankcase",
            &format!("guide_{k}"),
            xc,
            guide,
            nh,
            &[Tangential, Axial],
        )?);
    }
    Ok((liner, cc))
}

/// The two interface fields' shapes: the seat (the flange annulus between the liner's outer
/// radius and the flange's) and the guide (the lower guide band).
pub(super) fn seat_and_guide(inp: &RomInputs<'_>) -> (InterfaceShape, InterfaceShape) {
    (
        InterfaceShape::Seat {
            r_in: inp.bore_radius,
            r_out: inp.flange_radius,
        },
        InterfaceShape::Guide {
            z0: inp.guide_bottom,
            z1: inp.guide_bottom + inp.guide_height,
        },
    )
}

/// The liner's interface blocks on `mesh` about a bore axis at x = `cx` (0: its own frame):
/// seat (radial, tangential, axial), guide radial, guide tangential/axial.
pub fn liner_blocks(
    inp: &RomInputs<'_>,
    mesh: &Mesh,
    cx: f64,
) -> Result<Vec<InterfaceBlock>, RomError> {
    use Direction::*;
    let nh = inp.harmonics;
    let (seat, guide) = seat_and_guide(inp);
    Ok(vec![
        block(
            mesh,
            "liner",
            "flange_seat",
            cx,
            seat,
            nh,
            &[Radial, Tangential, Axial],
        )?,
        block(mesh, "liner", "lower_guide", cx, guide, nh, &[Radial])?,
        block(
            mesh,
            "liner",
            "lower_guide",
            cx,
            guide,
            nh,
            &[Tangential, Axial],
        )?,
    ])
}

/// The head-bolt preload as loads: the clamp force pressing each liner's flange top down
/// (spread evenly over the `flange_top` nodes) and its reaction pulling the deck up around each
/// bore (the `deck_top` nodes outside the flange within half a pitch of the bore axis, one load
/// per cylinder; none when the crankcase mesh has no `deck_top` set).
pub struct PreloadLoads {
    pub liner: Load,
    pub crankcase: Vec<Load>,
}

/// Builds [`PreloadLoads`] from the meshes' sets.
pub fn preload_loads(inp: &RomInputs<'_>) -> Result<PreloadLoads, RomError> {
    let top = set(inp.liner, "liner", "flange_top")?;
    let fz = -inp.clamp_force / top.len() as f64;
    let liner = Load {
        name: "clamp".into(),
        entries: top.iter().map(|&n| (n, [0.0, 0.0, fz])).collect(),
    };
    let cm = inp.crankcase;
    let mut crankcase = Vec::new();
    if let Some(deck) = cm.node_set("deck_top") {
        let tol = 1e-6 * inp.pitch;
        for (c, &xc) in inp.axis_x.iter().enumerate() {
            let bolts: Vec<usize> = deck
                .iter()
                .copied()
                .filter(|&n| {
                    let p = cm.nodes[n];
                    let r = ((p[0] - xc).powi(2) + p[1].powi(2)).sqrt();
                    (p[0] - xc).abs() < inp.pitch / 2.0 - tol && r > inp.flange_radius + tol
                })
                .collect();
            if !bolts.is_empty() {
                let f = inp.clamp_force / bolts.len() as f64;
                crankcase.push(Load {
                    name: format!("bolts_{}", c + 1),
                    entries: bolts.iter().map(|&n| (n, [0.0, 0.0, f])).collect(),
                });
            }
        }
    }
    Ok(PreloadLoads { liner, crankcase })
}

/// The liner's rows of the reduction: one unit load per bore node (thrust +y, anti-thrust
/// -y) and the clamp load; outputs at the bore nodes and the analysis points.
pub(super) struct LinerRows {
    pub(super) thrust: Vec<usize>,
    pub(super) anti: Vec<usize>,
    pub(super) points: Vec<usize>,
    pub(super) loads: Vec<Load>,
    /// Column of the clamp load among `loads`.
    pub(super) clamp_load: usize,
    /// The wet outer surface's nodes (`coolant_wetted`; empty without it), whose outputs
    /// follow the points'.
    pub(super) surface: Vec<usize>,
    pub(super) outputs: Vec<Output>,
}

impl LinerRows {
    pub(super) fn new(inp: &RomInputs<'_>, clamp: Load) -> Result<Self, RomError> {
        let lm = inp.liner;
        let thrust = set(lm, "liner", "bore_thrust")?.to_vec();
        let anti = set(lm, "liner", "bore_antithrust")?.to_vec();
        let points = (1..=inp.analysis_points)
            .map(|k| Ok(set(lm, "liner", &format!("point_{k}"))?[0]))
            .collect::<Result<Vec<_>, RomError>>()?;
        let radial = |nodes: &[usize], name: &str, dir: [f64; 3]| -> Vec<Load> {
            nodes
                .iter()
                .map(|&n| Load {
                    name: format!("{name}_{n}"),
                    entries: vec![(n, dir)],
                })
                .collect()
        };
        let mut loads = radial(&thrust, "thrust", [0.0, 1.0, 0.0]);
        loads.extend(radial(&anti, "antithrust", [0.0, -1.0, 0.0]));
        loads.push(clamp);
        let clamp_load = loads.len() - 1;
        let output = |dir: [f64; 3]| move |&node: &usize| Output { node, dir };
        let mut outputs: Vec<Output> = thrust.iter().map(output([0.0, 1.0, 0.0])).collect();
        outputs.extend(anti.iter().map(output([0.0, -1.0, 0.0])));
        outputs.extend(points.iter().map(output([0.0, 1.0, 0.0])));
        let mut surface = lm.node_set(COOLANT_WETTED).unwrap_or(&[]).to_vec();
        surface.sort_unstable();
        surface.dedup();
        // outward radial, (x, y, 0) / r in the liner's frame (its axis is z); a node on the
        // axis has no radial direction and is left out
        surface.retain(|&n| lm.nodes[n][0].hypot(lm.nodes[n][1]) > 0.0);
        outputs.extend(surface.iter().map(|&node| {
            let [x, y, _] = lm.nodes[node];
            let r = x.hypot(y);
            Output {
                node,
                dir: [x / r, y / r, 0.0],
            }
        }));
        Ok(LinerRows {
            thrust,
            anti,
            points,
            loads,
            clamp_load,
            surface,
            outputs,
        })
    }
}

/// The crankcase's outputs: the radial (y) acceleration points of every cylinder,
/// cylinder-major.
pub(super) fn crankcase_outputs(inp: &RomInputs<'_>) -> Result<Vec<Output>, RomError> {
    let mut out = Vec::new();
    for k in 1..=inp.axis_x.len() {
        for p in 1..=inp.analysis_points {
            out.push(Output {
                node: set(inp.crankcase, "crankcase", &format!("point_{k}_{p}"))?[0],
                dir: [0.0, 1.0, 0.0],
            });
        }
    }
    Ok(out)
}

/// The engine's parts, liner and crankcase.
pub const COMPONENTS: [&str; 2] = ["liner", "crankcase"];

/// The engine's components in the order of their task indices (1-based in `rom --component`):
/// the liner, then the crankcase, or each of its `crankcase_components` when it is
/// substructured (`crankcase.1`, ...).
pub fn component_names(crankcase_components: usize) -> Vec<String> {
    let mut names = vec![COMPONENTS[0].to_string()];
    if crankcase_components <= 1 {
        names.push(COMPONENTS[1].to_string());
    } else {
        names.extend((1..=crankcase_components).map(|c| format!("{}.{c}", COMPONENTS[1])));
    }
    names
}

/// What the parts' reductions read besides the inputs: interface fields, loads, outputs.
pub(super) struct PartData {
    pub(super) liner_blocks: Vec<InterfaceBlock>,
    pub(super) cc_blocks: Vec<InterfaceBlock>,
    pub(super) rows: LinerRows,
    pub(super) cc_loads: Vec<Load>,
    pub(super) cc_outputs: Vec<Output>,
}

impl PartData {
    pub(super) fn new(inp: &RomInputs<'_>) -> Result<Self, RomError> {
        check_fit(inp)?;
        let preload = preload_loads(inp)?;
        let rows = LinerRows::new(inp, preload.liner)?;
        let (liner_blocks, cc_blocks) = interface_blocks(inp)?;
        Ok(Self {
            liner_blocks,
            cc_blocks,
            rows,
            cc_loads: preload.crankcase,
            cc_outputs: crankcase_outputs(inp)?,
        })
    }

    /// The liner (once, in its own frame) and the crankcase as parts to reduce.
    pub(super) fn parts<'a>(&'a self, inp: &'a RomInputs<'a>) -> [Part<'a>; 2] {
        [
            Part {
                name: COMPONENTS[0],
                mesh: inp.liner,
                material: &inp.liner_material,
                surface: &inp.liner_surface_mass,
                fix: &[],
                interfaces: &self.liner_blocks,
                loads: &self.rows.loads,
                outputs: &self.rows.outputs,
            },
            Part {
                name: COMPONENTS[1],
                mesh: inp.crankcase,
                material: &inp.crankcase_material,
                surface: &[],
                fix: &inp.crankcase_fix,
                interfaces: &self.cc_blocks,
                loads: &self.cc_loads,
                outputs: &self.cc_outputs,
            },
        ]
    }
}

pub(super) fn cb_settings(inp: &RomInputs<'_>) -> CbSettings {
    CbSettings {
        cutoff_hz: inp.cutoff_hz,
        keep_basis: inp.keep_bases,
    }
}

/// The crankcase's cut planes when it is substructured (`crankcase_components` > 1, no full
/// bases asked for): the cylinders shared out evenly, each cut midway between the bores of
/// neighbouring groups.
pub(super) fn crankcase_split(inp: &RomInputs<'_>) -> Option<crate::reduce::substructure::Split> {
    let (n, nc) = (inp.axis_x.len(), inp.crankcase_components);
    if nc <= 1 {
        return None;
    }
    let cuts_x = (1..nc)
        .map(|j| {
            let first = j * n / nc;
            (inp.axis_x[first - 1] + inp.axis_x[first]) / 2.0
        })
        .collect();
    Some(crate::reduce::substructure::Split {
        cuts_x,
        cut_shapes: inp.cut_shapes,
        component_cutoff_factor: inp.component_cutoff_factor,
        enrichment: inp.cut_enrichment,
    })
}

#[cfg(test)]
mod tests {
    use super::spread;

    #[test]
    fn a_refused_sets_nodes_are_described_about_the_axis() {
        // a flange rim: four nodes on one radius and height about x = 0.076 m
        let rim: Vec<[f64; 3]> = (0..4)
            .map(|k| {
                let t = k as f64 * std::f64::consts::FRAC_PI_2;
                [0.076 + 0.074 * t.cos(), 0.074 * t.sin(), 0.248]
            })
            .collect();
        assert_eq!(
            spread(&rim, 0.076),
            "its 4 node(s) at r = 74 mm about the bore axis, z = 248 mm"
        );
        let band = [[0.0675, 0.0, 0.01], [0.0, 0.07, 0.04]];
        assert_eq!(
            spread(&band, 0.0),
            "its 2 node(s) at r = 67.5..70 mm about the bore axis, z = 10..40 mm"
        );
        assert_eq!(spread(&[], 0.0), "no nodes");
    }
}
