//! Building the engine ROM from a scene: meshes, interface fields, one liner reduction reused
//! for every modelled cylinder, the crankcase reduction, assembly, system modes, static
//! correction and preload.

use super::craig_bampton::{
    CbSettings, CbStats, InterfaceBlock, Load, Output, Part, PartReduction,
};
use super::engine::{self, assemble, hz, residual_flexibility, Dense, Placement, SystemModes};
use super::interface::{self, Direction, InterfaceShape};
use super::part_cache::{reduce_cached, PartCacheError, Source};
use crate::fem::material::Elastic;
use crate::fem::surface::SurfaceMass;
use crate::mesh::liner::COOLANT_WETTED;
use crate::mesh::Mesh;
use faer::{Mat, MatRef};
use std::time::Instant;

/// Version of the ROM layout; part of the cache key (5: matrices stored as ndarray arrays;
/// 9: residual vectors and residual flexibility from the dropped modes' exact flexibility).
pub const ROM_FORMAT: u32 = 9;

/// Reduced data of one modelled cylinder. Mode rows hold the displacement of mass-normalised
/// system modes along the stated direction.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct CylinderRom {
    /// 1-based cylinder number.
    pub cylinder: usize,
    pub axis_x: f64,
    /// Heights of the bore-line nodes (ascending) on the thrust (+y) and anti-thrust (-y) side.
    pub thrust_z: Vec<f64>,
    pub antithrust_z: Vec<f64>,
    /// Outward radial displacement of the bore-line nodes (nodes x modes).
    pub thrust_modes: Dense,
    pub antithrust_modes: Dense,
    /// Liner analysis points, radial toward the coolant (+y), top to bottom (points x modes).
    pub point_modes: Dense,
    /// Crankcase jacket-wall points facing them (+y).
    pub crankcase_point_modes: Dense,
    /// Head-bolt preload displacement at the bore-line nodes and points \[m\].
    pub preload_thrust: Vec<f64>,
    pub preload_antithrust: Vec<f64>,
    pub preload_points: Vec<f64>,
    /// Residual flexibility of the dropped system modes between the analysis points and this
    /// cylinder's contact DOFs (points x (thrust, anti-thrust nodes)) [m/N]: the quasi-static
    /// part of a point's response to a contact force near it, u_p = phi_p . eta + R_pc F.
    pub point_residual: Dense,
    /// Offset of this cylinder's contact DOFs (thrust, then anti-thrust) in the residual
    /// flexibility matrix.
    pub contact_offset: usize,
    /// The liner's wet outer surface, for the liner maps (no nodes when the liner mesh has no
    /// `coolant_wetted` set).
    pub surface: SurfaceRows,
}

/// Rows of a liner's wet outer surface (node set `coolant_wetted`), each like an analysis
/// point's: u_n = phi_n . eta + R_nc F along the outward radial direction (x, y, 0) / r.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct SurfaceRows {
    /// Liner mesh node of each row, ascending.
    pub nodes: Vec<usize>,
    /// Outward radial displacement of the modes (nodes x modes).
    pub modes: Dense,
    /// Residual flexibility to this cylinder's contact DOFs (nodes x contact DOFs) [m/N].
    pub residual: Dense,
}

/// Per-part summary.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct PartInfo {
    pub name: String,
    pub stats: CbStats,
    /// How many copies of this reduction the engine uses.
    pub copies: usize,
    /// Reduced in the build, or read from the component cache.
    pub source: Source,
}

/// What the ROM holds and how it was made.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct RomInfo {
    pub full_dofs: usize,
    pub reduced_dofs: usize,
    pub system_modes: usize,
    /// Residual vectors (pseudo-modes above the cut-off) of the contact load patterns,
    /// appended to the system modes ([`engine::residual_vectors`]).
    pub residual_vectors: usize,
    pub band_hz: f64,
    pub cutoff_hz: f64,
    pub interface_harmonics: usize,
    pub parts: Vec<PartInfo>,
    pub build_seconds: f64,
    /// Largest relative change of a system frequency below the band when the part-mode
    /// cut-off is lowered to 2/3 of its value: an upper estimate of the truncation error.
    pub estimated_error: f64,
    pub left_out: Vec<String>,
    /// Interfaces, points and materials found on imported meshes (none for generated ones).
    pub interfaces: Option<crate::mesh::find::FoundInterfaces>,
}

/// The cached engine reduced-order model.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct EngineRom {
    /// System modes kept (below the cut-off), ascending, then the residual vectors' pseudo-modes
    /// (above the cut-off, ascending) \[Hz\].
    pub frequencies_hz: Vec<f64>,
    pub cylinders: Vec<CylinderRom>,
    /// Residual flexibility of the dropped modes at all contact DOFs [m/N].
    pub residual_flexibility: Dense,
    pub info: RomInfo,
}

impl EngineRom {
    /// Checks what a checksum cannot (a forged or mis-written file with a valid hash): at least
    /// one system mode, frequencies finite, non-negative and ascending within the system and
    /// the residual-vector groups, every matrix's dimensions consistent with the mode count and
    /// the contact DOFs, and every entry finite. Returns what is wrong.
    pub fn validate(&self) -> Result<(), String> {
        let i = &self.info;
        let nm = self.frequencies_hz.len();
        if i.system_modes == 0 || nm != i.system_modes + i.residual_vectors {
            return Err(format!(
                "{} frequencies for {} system modes and {} residual vectors (at least one system mode needed)",
                nm, i.system_modes, i.residual_vectors
            ));
        }
        let f = &self.frequencies_hz;
        if f.iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
            return Err("a frequency is negative or not finite".into());
        }
        let ascending = |s: &[f64]| s.windows(2).all(|w| w[0] <= w[1]);
        if !ascending(&f[..i.system_modes]) || !ascending(&f[i.system_modes..]) {
            return Err("the frequencies are not in ascending order".into());
        }
        if self.cylinders.is_empty() {
            return Err("no cylinder".into());
        }
        let contact: usize = self
            .cylinders
            .iter()
            .map(|c| c.thrust_z.len() + c.antithrust_z.len())
            .sum();
        let square = &self.residual_flexibility;
        check_dense("residual flexibility", square, contact, contact)?;
        for c in &self.cylinders {
            let (nt, na) = (c.thrust_z.len(), c.antithrust_z.len());
            let np = c.point_modes.nrows();
            let at = |what: &str| format!("cylinder {}: {what}", c.cylinder);
            check_dense(&at("thrust modes"), &c.thrust_modes, nt, nm)?;
            check_dense(&at("anti-thrust modes"), &c.antithrust_modes, na, nm)?;
            check_dense(&at("point modes"), &c.point_modes, np, nm)?;
            let ncp = c.crankcase_point_modes.nrows();
            check_dense(
                &at("crankcase point modes"),
                &c.crankcase_point_modes,
                ncp,
                nm,
            )?;
            check_dense(&at("point residual"), &c.point_residual, np, nt + na)?;
            let ns = c.surface.nodes.len();
            check_dense(&at("surface modes"), &c.surface.modes, ns, nm)?;
            check_dense(&at("surface residual"), &c.surface.residual, ns, nt + na)?;
            let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
            if c.preload_thrust.len() != nt
                || c.preload_antithrust.len() != na
                || c.preload_points.len() != np
                || !finite(&c.preload_thrust)
                || !finite(&c.preload_antithrust)
                || !finite(&c.preload_points)
                || !finite(&c.thrust_z)
                || !finite(&c.antithrust_z)
                || np == 0
                || nt == 0
                || na == 0
                || c.contact_offset + nt + na > contact
            {
                return Err(at(
                    "bore lines, points or preload inconsistent or not finite",
                ));
            }
        }
        Ok(())
    }
}

/// A stored matrix has the expected dimensions and finite entries.
fn check_dense(what: &str, d: &Dense, rows: usize, cols: usize) -> Result<(), String> {
    if d.nrows() != rows || d.ncols() != cols || !d.is_standard_layout() {
        return Err(format!(
            "{what}: {} x {}, expected {rows} x {cols} (row-major)",
            d.nrows(),
            d.ncols(),
        ));
    }
    if d.iter().any(|x| !x.is_finite()) {
        return Err(format!("{what}: an entry is not finite"));
    }
    Ok(())
}

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
    /// Components the crankcase is cut into (1: reduced in one piece; [`super::substructure`]).
    pub crankcase_components: usize,
    /// Shapes per cut between crankcase components.
    pub cut_shapes: usize,
    /// Keep full bases for recovery (mode shapes on the meshes).
    pub keep_bases: bool,
    /// The component cache directory: each part's reduction read from it or stored in it
    /// ([`super::part_cache`]; not with `keep_bases`).
    pub part_cache: Option<std::path::PathBuf>,
}

/// Failures of the ROM build, naming part and set.
#[derive(Debug, thiserror::Error)]
pub enum RomError {
    #[error(transparent)]
    Reduce(#[from] super::craig_bampton::ReduceError),
    #[error("part '{part}': node set '{set}': {msg}")]
    Set {
        part: String,
        set: String,
        msg: String,
    },
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
        use super::craig_bampton::ReduceError;
        use crate::fem::model::ModelError;
        match self {
            RomError::Set { .. } | RomError::PartCache(_) => 2,
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

fn block(
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
                "cannot carry the interface field (conditioning {cond:.1e}): too few nodes, or all on one radius/height; refine the mesh there or lower rom.interface_harmonics"
            ),
        });
    }
    Ok(InterfaceBlock {
        set: name.into(),
        psi,
    })
}

/// Checks that the crankcase leaves room for each liner and seats it where the liner's
/// flange is (part and set named in the error).
fn check_fit(inp: &RomInputs<'_>) -> Result<(), RomError> {
    let tol = 1e-4 * inp.pitch;
    for (c, &xc) in inp.axis_x.iter().enumerate() {
        if let Some(n) = inp.crankcase.nodes.iter().position(|p| {
            let r = ((p[0] - xc).powi(2) + p[1].powi(2)).sqrt();
            r < inp.bore_radius - tol && p[2] > tol && p[2] < inp.seat_z - tol
        }) {
            return Err(RomError::Set {
                part: "crankcase".into(),
                set: format!("bore {}", c + 1),
                msg: format!(
                    "crankcase node {} at {:?} lies inside the liner of cylinder {}: the parts overlap",
                    n + 1,
                    inp.crankcase.nodes[n],
                    c + 1
                ),
            });
        }
        let seat = set(inp.crankcase, "crankcase", &format!("seat_{}", c + 1))?;
        for &n in seat {
            let p = inp.crankcase.nodes[n];
            let r = ((p[0] - xc).powi(2) + p[1].powi(2)).sqrt();
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

/// A built ROM plus (on request) what is needed to recover full mode shapes.
pub struct RomBuild {
    pub rom: EngineRom,
    pub liner: PartReduction,
    pub crankcase: PartReduction,
    /// Global index of each liner coordinate, per modelled cylinder (same order as
    /// `rom.cylinders`), and of each crankcase coordinate.
    pub liner_maps: Vec<Vec<usize>>,
    pub crankcase_map: Vec<usize>,
    pub system: SystemModes,
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
fn seat_and_guide(inp: &RomInputs<'_>) -> (InterfaceShape, InterfaceShape) {
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

/// Contact load patterns for the residual vectors: on each bore line (sides of `sides` nodes,
/// repeated for `cylinders`), hat functions w_i = max(0, 1 - |i - c| / e) centred every e =
/// `spacing` nodes and at the last node; e = 1 gives one unit load per node, e = 0 none.
pub fn hat_patterns(sides: &[usize], cylinders: usize, spacing: usize) -> Mat<f64> {
    let per: usize = sides.iter().sum();
    let rows = per * cylinders;
    let mut cols: Vec<Vec<(usize, f64)>> = Vec::new();
    if spacing > 0 {
        for c in 0..cylinders {
            let mut r0 = c * per;
            for &nn in sides {
                let mut centres: Vec<usize> = (0..nn).step_by(spacing).collect();
                if nn > 0 && centres.last() != Some(&(nn - 1)) {
                    centres.push(nn - 1);
                }
                for &cn in &centres {
                    let col = (0..nn)
                        .filter_map(|i| {
                            let w = 1.0 - (i as f64 - cn as f64).abs() / spacing as f64;
                            (w > 0.0).then_some((r0 + i, w))
                        })
                        .collect();
                    cols.push(col);
                }
                r0 += nn;
            }
        }
    }
    let mut p = Mat::<f64>::zeros(rows, cols.len());
    for (j, col) in cols.iter().enumerate() {
        for &(i, w) in col {
            p[(i, j)] = w;
        }
    }
    p
}

/// The liner's rows of the reduction: one unit load per bore node (thrust +y, anti-thrust
/// -y) and the clamp load; outputs at the bore nodes and the analysis points.
struct LinerRows {
    thrust: Vec<usize>,
    anti: Vec<usize>,
    points: Vec<usize>,
    loads: Vec<Load>,
    /// Column of the clamp load among `loads`.
    clamp_load: usize,
    /// The wet outer surface's nodes (`coolant_wetted`; empty without it), whose outputs
    /// follow the points'.
    surface: Vec<usize>,
    outputs: Vec<Output>,
}

impl LinerRows {
    fn new(inp: &RomInputs<'_>, clamp: Load) -> Result<Self, RomError> {
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
fn crankcase_outputs(inp: &RomInputs<'_>) -> Result<Vec<Output>, RomError> {
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

/// Global layout of the engine's reduced coordinates: the crankcase first, then per modelled
/// cylinder the liner's coordinates, its interface columns shared with the crankcase's.
fn layout(
    liner: &PartReduction,
    crankcase: &PartReduction,
    cylinders: &[usize],
) -> (Vec<usize>, Vec<Vec<usize>>, usize) {
    let n_c = crankcase.size();
    let mut next = n_c;
    let mut liner_maps = Vec::new();
    for &cyl in cylinders {
        let c = cyl - 1;
        let mut map = vec![usize::MAX; liner.size()];
        for (b, cc_b) in [(0usize, 3 * c), (1, 3 * c + 1)] {
            for (lj, gj) in liner.interface_cols[b]
                .clone()
                .zip(crankcase.interface_cols[cc_b].clone())
            {
                map[lj] = gj;
            }
        }
        for slot in map.iter_mut() {
            if *slot == usize::MAX {
                *slot = next;
                next += 1;
            }
        }
        liner_maps.push(map);
    }
    ((0..n_c).collect(), liner_maps, next)
}

/// Rows `r0..r0 + nr` of a part's output matrix in global coordinates (columns scattered
/// through `map`).
fn scatter_rows(rows: &Mat<f64>, map: &[usize], r0: usize, nr: usize, n_g: usize) -> Mat<f64> {
    let mut g = Mat::<f64>::zeros(nr, n_g);
    for i in 0..nr {
        for j in 0..rows.ncols() {
            g[(i, map[j])] += rows[(r0 + i, j)];
        }
    }
    g
}

/// The engine's modal basis: the `kept` system modes below the cut-off, then the residual
/// vectors of the contact load patterns (pseudo-modes above it) with their eigenvalues `mu`.
struct Basis {
    kept: usize,
    mu: Vec<f64>,
    /// Global coordinates x (kept + residual) modes.
    modes: Mat<f64>,
    /// The residual vectors scaled by mu^-1/2: their static flexibility is (G Ys)(G Ys)^T.
    ys: Mat<f64>,
}

/// The basis from the system modes and W = F_d G_c^T, the dropped modes' flexibility at the
/// contact rows ([`SystemModes::dropped_flexibility`]).
fn basis(
    sys: &SystemModes,
    kept: usize,
    w: MatRef<'_, f64>,
    patterns: &Mat<f64>,
) -> Result<Basis, RomError> {
    let n_g = sys.vectors.nrows();
    let (ya, mu) = engine::residual_vectors(sys, kept, w, patterns)?;
    let mut modes = Mat::<f64>::zeros(n_g, kept + mu.len());
    modes
        .as_mut()
        .subcols_mut(0, kept)
        .copy_from(sys.vectors.as_ref().subcols(0, kept));
    modes.as_mut().subcols_mut(kept, mu.len()).copy_from(&ya);
    let ys = Mat::from_fn(n_g, mu.len(), |i, j| ya[(i, j)] / mu[j].sqrt());
    Ok(Basis {
        kept,
        mu,
        modes,
        ys,
    })
}

/// The preload in global coordinates: the liners' clamp loads and the bolts' reactions.
fn preload_vector(
    liner: &PartReduction,
    clamp_load: usize,
    liner_maps: &[Vec<usize>],
    crankcase: &PartReduction,
    n_g: usize,
) -> Mat<f64> {
    let mut f = Mat::<f64>::zeros(n_g, 1);
    for map in liner_maps {
        for j in 0..liner.size() {
            f[(map[j], 0)] += liner.loads[(j, clamp_load)];
        }
    }
    for l in 0..crankcase.loads.ncols() {
        for j in 0..crankcase.size() {
            f[(j, 0)] += crankcase.loads[(j, l)];
        }
    }
    f
}

/// Residual cross flexibility points x contact not carried by the modes:
/// G_p F_d G_c^T - (G_p Ys)(G_c Ys)^T, F_d the flexibility of the dropped system modes, with
/// `w` = F_d G_c^T (global x contact rows) and G_p / G_c the point / contact rows of `g_all`
/// (contact rows first).
fn point_residual(g_all: &Mat<f64>, w: MatRef<'_, f64>, b: &Basis, ncon: usize) -> Dense {
    let np = g_all.nrows() - ncon;
    let gys = g_all * &b.ys;
    let r = g_all.as_ref().subrows(ncon, np) * w
        - gys.as_ref().subrows(ncon, np) * gys.as_ref().subrows(0, ncon).transpose();
    crate::linalg::dense::from_faer(&r)
}

/// What [`cylinder_rom`] needs of the assembled engine.
struct Assembled<'a> {
    inp: &'a RomInputs<'a>,
    rows: &'a LinerRows,
    liner: &'a PartReduction,
    liner_maps: &'a [Vec<usize>],
    crankcase: &'a PartReduction,
    crankcase_map: &'a [usize],
    /// Global coordinates.
    n_g: usize,
    /// W = F_d G_c^T for every modelled cylinder's contact rows (cylinder-major columns).
    w: &'a Mat<f64>,
    basis: &'a Basis,
    /// The static preload displacement (global coordinates x 1).
    u0: &'a Mat<f64>,
}

/// One modelled cylinder's rows of the ROM: its liner's contact and point rows `g_all` (global
/// coordinates) projected on the modes, the crankcase's point rows, the preload.
fn cylinder_rom(a: &Assembled<'_>, cyl: usize, g_all: &Mat<f64>, idx: usize) -> CylinderRom {
    let (inp, r) = (a.inp, a.rows);
    let (nt, na, np) = (r.thrust.len(), r.anti.len(), r.points.len());
    let offset = idx * (nt + na);
    let modes_rows = g_all * &a.basis.modes;
    let pre = g_all * a.u0;
    let c = cyl - 1;
    let n_g = a.n_g;
    let w = a.w.as_ref().subcols(idx * (nt + na), nt + na);
    let g_cc = scatter_rows(
        &a.crankcase.outputs,
        a.crankcase_map,
        c * inp.analysis_points,
        inp.analysis_points,
        n_g,
    );
    let cc_modes = &g_cc * &a.basis.modes;
    let sub = |r0: usize, nr: usize| {
        crate::linalg::dense::from_faer(&modes_rows.as_ref().subrows(r0, nr).to_owned())
    };
    let zs = |nodes: &[usize]| {
        nodes
            .iter()
            .map(|&n| inp.liner.nodes[n][2])
            .collect::<Vec<_>>()
    };
    let column = |r0: usize, nr: usize| (0..nr).map(|i| pre[(r0 + i, 0)]).collect();
    CylinderRom {
        cylinder: cyl,
        axis_x: inp.axis_x[c],
        thrust_z: zs(&r.thrust),
        antithrust_z: zs(&r.anti),
        thrust_modes: sub(0, nt),
        antithrust_modes: sub(nt, na),
        point_modes: sub(nt + na, np),
        crankcase_point_modes: crate::linalg::dense::from_faer(&cc_modes),
        preload_thrust: column(0, nt),
        preload_antithrust: column(nt, na),
        preload_points: column(nt + na, np),
        point_residual: point_residual(g_all, w, a.basis, nt + na),
        contact_offset: offset,
        surface: surface_rows(a, idx, g_all.as_ref().subrows(0, nt + na), w),
    }
}

/// A cylinder's wet-surface rows ([`SurfaceRows`]) from the liner's outputs after the points
/// (`G_s`, liner coordinates), gathered through the cylinder's map into global coordinates:
/// modes G_s Y, and the residual flexibility to the contact rows `g_c` as in
/// [`point_residual`], G_s [F_d g_c^T] - (G_s Ys)(g_c Ys)^T with `w` = F_d g_c^T (global x
/// contact rows).
fn surface_rows(
    a: &Assembled<'_>,
    idx: usize,
    g_c: MatRef<'_, f64>,
    w: MatRef<'_, f64>,
) -> SurfaceRows {
    let r = a.rows;
    let ns = r.surface.len();
    if ns == 0 {
        return SurfaceRows {
            nodes: Vec::new(),
            modes: Dense::zeros((0, a.basis.modes.ncols())),
            residual: Dense::zeros((0, g_c.nrows())),
        };
    }
    let (map, outputs) = (&a.liner_maps[idx], &a.liner.outputs);
    let s0 = outputs.nrows() - ns;
    let gather = |m: MatRef<'_, f64>| Mat::from_fn(map.len(), m.ncols(), |i, j| m[(map[i], j)]);
    let g_s = outputs.as_ref().subrows(s0, ns);
    let modes = g_s * gather(a.basis.modes.as_ref());
    let gys_c = g_c * &a.basis.ys;
    let residual = g_s * gather(w) - (g_s * gather(a.basis.ys.as_ref())) * gys_c.transpose();
    SurfaceRows {
        nodes: r.surface.clone(),
        modes: crate::linalg::dense::from_faer(&modes),
        residual: crate::linalg::dense::from_faer(&residual),
    }
}

/// Relative error bound of the smaller system's band eigenvalues in [`truncation_error`]: the
/// estimate is a frequency change of order 1e-2 printed to three digits.
const ESTIMATE_TOL: f64 = 1e-6;

/// Error estimate of the Craig-Bampton truncation: the largest relative change of the system
/// frequencies in the band when the parts' mode cut-off is lowered to 2/3 (NaN when that
/// smaller system cannot be solved). The smaller system's band eigenvalues come from block
/// Lanczos when it is large ([`engine::lowest_eigenvalues`]), else (or when that gives no
/// answer) they are refined from the full system's modes restricted to its coordinates (a
/// block of up to max(400, 3/2 x kept) of them: as many as the system's solve returned, kept
/// + 64 after block Lanczos) rather than solved densely from scratch.
fn truncation_error(
    inp: &RomInputs<'_>,
    parts: &[(&PartReduction, &[usize])],
    kg: &Mat<f64>,
    mg: &Mat<f64>,
    sys: &SystemModes,
) -> f64 {
    let limit = inp.cutoff_hz * 2.0 / 3.0;
    let mut keep = vec![true; kg.nrows()];
    for (p, map) in parts {
        for (j, f) in p.modes.clone().zip(&p.mode_frequencies_hz) {
            if *f > limit {
                keep[map[j]] = false;
            }
        }
    }
    let idx: Vec<usize> = (0..kg.nrows()).filter(|&i| keep[i]).collect();
    let kk = Mat::from_fn(idx.len(), idx.len(), |i, j| kg[(idx[i], idx[j])]);
    let mm = Mat::from_fn(idx.len(), idx.len(), |i, j| mg[(idx[i], idx[j])]);
    let band = (2.0 * std::f64::consts::PI * inp.band_hz).powi(2);
    let in_band = sys.lambdas.iter().take_while(|&&l| l <= band).count();
    let cut = (2.0 * std::f64::consts::PI * inp.cutoff_hz).powi(2);
    let kept = sys.lambdas.iter().take_while(|&&l| l <= cut).count();
    let p = idx
        .len()
        .min(400.max(3 * kept / 2))
        .max(in_band)
        .min(sys.vectors.ncols());
    let lanczos = (idx.len() > engine::LANCZOS_ABOVE)
        .then(|| engine::lowest_eigenvalues(&kk, &mm, in_band, 1.1 * band, ESTIMATE_TOL))
        .flatten();
    let smaller = match lanczos {
        Some(l2) => Ok(l2),
        None => {
            let start = Mat::from_fn(idx.len(), p, |i, j| sys.vectors[(idx[i], j)]);
            engine::refined_eigenvalues(&kk, &mm, start.as_ref())
        }
    };
    match smaller {
        Ok(l2) => sys.lambdas[..in_band]
            .iter()
            .zip(&l2)
            .map(|(a, b)| (hz(*b) - hz(*a)).abs() / hz(*a))
            .fold(0.0, f64::max),
        Err(_) => f64::NAN,
    }
}

/// What the ROM leaves out, in words for the report.
fn left_out(inp: &RomInputs<'_>, n_g: usize, b: &Basis) -> Vec<String> {
    let mut out = Vec::new();
    let missing: Vec<String> = (1..=inp.axis_x.len())
        .filter(|c| !inp.cylinders.contains(c))
        .map(|c| c.to_string())
        .collect();
    if !missing.is_empty() {
        out.push(format!(
            "liners of cylinders {} (their bores are free; rom.cylinders)",
            missing.join(", ")
        ));
    }
    out.push(format!(
        "system modes above the cut-off {:.0} Hz ({} of {}), represented {} at the contact DOFs",
        inp.cutoff_hz,
        n_g - b.kept,
        n_g,
        if b.mu.is_empty() {
            "statically".to_string()
        } else {
            format!("by {} residual vectors (static part exact)", b.mu.len())
        }
    ));
    if inp.crankcase.node_set("deck_top").is_none() {
        out.push(
            "head-bolt reaction on the deck (the crankcase mesh has no 'deck_top' set)".into(),
        );
    }
    out
}

/// Builds the engine ROM: Craig-Bampton reductions of the liner and the crankcase, their
/// assembly over the modelled cylinders, the system modes below the cut-off with residual
/// vectors of the contact load patterns, the preload, and per cylinder the rows the transient
/// needs.
pub fn build(inp: &RomInputs<'_>, progress: &dyn Fn(&str)) -> Result<RomBuild, RomError> {
    let t0 = Instant::now();
    let progress = |what: &str| {
        log::info!("{:7.2} s  {what}", t0.elapsed().as_secs_f64());
        progress(what)
    };
    crate::linalg::thread_count_invariant();
    let data = PartData::new(inp)?;
    let rows = &data.rows;
    let (liner, crankcase, sources) = reduce_parts(inp, &data, &progress)?;
    progress("assembling the engine");
    let (crankcase_map, liner_maps, n_g) = layout(&liner, &crankcase, &inp.cylinders);
    let mut placements = vec![Placement {
        part: &crankcase,
        map: crankcase_map.clone(),
    }];
    placements.extend(liner_maps.iter().map(|map| Placement {
        part: &liner,
        map: map.clone(),
    }));
    let (kg, mg) = assemble(n_g, &placements);
    progress("system modes");
    let omega_c2 = (2.0 * std::f64::consts::PI * inp.cutoff_hz).powi(2);
    let sys = engine::system_modes(kg.clone(), &mg, omega_c2)?;
    let kept = sys.lambdas.iter().take_while(|&&l| l <= omega_c2).count();
    let ncon = rows.thrust.len() + rows.anti.len();
    let n_rows = ncon + rows.points.len();
    let (g_rows, gc) = output_rows(&liner, &liner_maps, ncon, n_rows, n_g);
    progress("residual vectors");
    let patterns = hat_patterns(
        &[rows.thrust.len(), rows.anti.len()],
        g_rows.len(),
        inp.residual_vector_spacing,
    );
    let w = sys.dropped_flexibility(kept, gc.as_ref());
    let basis = basis(&sys, kept, w.as_ref(), &patterns)?;
    let f = preload_vector(&liner, rows.clamp_load, &liner_maps, &crankcase, n_g);
    let u0 = sys.static_solve(f.as_ref());
    let assembled = Assembled {
        inp,
        rows,
        liner: &liner,
        liner_maps: &liner_maps,
        crankcase: &crankcase,
        crankcase_map: &crankcase_map,
        n_g,
        w: &w,
        basis: &basis,
        u0: &u0,
    };
    let cylinders = inp
        .cylinders
        .iter()
        .zip(&g_rows)
        .enumerate()
        .map(|(idx, (&cyl, g_all))| cylinder_rom(&assembled, cyl, g_all, idx))
        .collect();
    let gcs = &gc * &basis.ys;
    let rflex = residual_flexibility(gc.as_ref(), w.as_ref()) - &gcs * gcs.transpose();
    progress("error estimate");
    let mut parts: Vec<(&PartReduction, &[usize])> = vec![(&crankcase, &crankcase_map)];
    parts.extend(liner_maps.iter().map(|m| (&liner, m.as_slice())));
    let estimated_error = truncation_error(inp, &parts, &kg, &mg, &sys);
    log::info!("{:7.2} s  built", t0.elapsed().as_secs_f64());
    let info = RomInfo {
        full_dofs: crankcase.stats.full_dofs + inp.cylinders.len() * liner.stats.full_dofs,
        reduced_dofs: n_g,
        system_modes: kept,
        residual_vectors: basis.mu.len(),
        band_hz: inp.band_hz,
        cutoff_hz: inp.cutoff_hz,
        interface_harmonics: inp.harmonics,
        parts: vec![
            PartInfo {
                name: "liner".into(),
                stats: liner.stats.clone(),
                copies: inp.cylinders.len(),
                source: sources[0],
            },
            PartInfo {
                name: "crankcase".into(),
                stats: crankcase.stats.clone(),
                copies: 1,
                source: sources[1],
            },
        ],
        build_seconds: t0.elapsed().as_secs_f64(),
        estimated_error,
        left_out: left_out(inp, n_g, &basis),
        interfaces: None,
    };
    let rom = EngineRom {
        frequencies_hz: sys.lambdas[..kept]
            .iter()
            .chain(&basis.mu)
            .map(|&l| hz(l))
            .collect(),
        cylinders,
        residual_flexibility: crate::linalg::dense::from_faer(&rflex),
        info,
    };
    Ok(RomBuild {
        rom,
        liner,
        crankcase,
        liner_maps,
        crankcase_map,
        system: sys,
    })
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
struct PartData {
    liner_blocks: Vec<InterfaceBlock>,
    cc_blocks: Vec<InterfaceBlock>,
    rows: LinerRows,
    cc_loads: Vec<Load>,
    cc_outputs: Vec<Output>,
}

impl PartData {
    fn new(inp: &RomInputs<'_>) -> Result<Self, RomError> {
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
    fn parts<'a>(&'a self, inp: &'a RomInputs<'a>) -> [Part<'a>; 2] {
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

fn cb_settings(inp: &RomInputs<'_>) -> CbSettings {
    CbSettings {
        cutoff_hz: inp.cutoff_hz,
        keep_basis: inp.keep_bases,
    }
}

/// The Craig-Bampton reductions of the liner and the crankcase ([`reduce_cached`]), through the
/// component cache when the inputs name one, one after the other: each uses both cores in its
/// block solves and products, and run at once the two gave results that differed from run to
/// run in the last bits (their allocations interleave, and the dense kernels' rounding depends
/// on the data's alignment), for about 5 s gained on the default engine.
fn reduce_parts(
    inp: &RomInputs<'_>,
    data: &PartData,
    progress: &dyn Fn(&str),
) -> Result<(PartReduction, PartReduction, [Source; 2]), RomError> {
    // refused before any work: the liner's reduction would be lost
    if inp.keep_bases && inp.crankcase_components > 1 {
        return Err(super::craig_bampton::ReduceError::Substructure {
            part: COMPONENTS[1].into(),
            msg: "mode shapes on the meshes need the crankcase's full basis, which a substructured reduction does not keep: set rom.crankcase_components = 1 for this command".into(),
        }
        .into());
    }
    let settings = cb_settings(inp);
    let [liner, crankcase] = data.parts(inp);
    let dir = inp.part_cache.as_deref();
    progress("reducing the liner");
    let (l, ls) = reduce_cached(&liner, &settings, dir)?;
    progress("reducing the crankcase");
    let (c, cs) = match crankcase_split(inp) {
        Some(split) => super::substructure::reduce_split(&crankcase, &settings, &split, dir)?,
        None => reduce_cached(&crankcase, &settings, dir)?,
    };
    Ok((l, c, [ls, cs]))
}

/// The crankcase's cut planes when it is substructured (`crankcase_components` > 1, no full
/// bases asked for): the cylinders shared out evenly, each cut midway between the bores of
/// neighbouring groups.
fn crankcase_split(inp: &RomInputs<'_>) -> Option<super::substructure::Split> {
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
    Some(super::substructure::Split {
        cuts_x,
        cut_shapes: inp.cut_shapes,
    })
}

/// One component's reduction into the component cache (`inp.part_cache`), for a scheduler's
/// task: `index` 0 the liner, then the crankcase or its components ([`component_names`]). A
/// later build finds it there.
pub fn reduce_component(
    inp: &RomInputs<'_>,
    index: usize,
) -> Result<(PartReduction, Source), RomError> {
    crate::linalg::thread_count_invariant();
    let data = PartData::new(inp)?;
    let [liner, crankcase] = data.parts(inp);
    let (settings, dir) = (cb_settings(inp), inp.part_cache.as_deref());
    Ok(match (index, crankcase_split(inp)) {
        (0, _) => reduce_cached(&liner, &settings, dir)?,
        (_, None) => reduce_cached(&crankcase, &settings, dir)?,
        (c, Some(split)) => {
            super::substructure::reduce_one(&crankcase, &settings, &split, dir, c - 1)?
        }
    })
}

/// The liner's output rows (contact DOFs, then points) scattered onto each modelled
/// cylinder's reduced DOFs, and the contact rows of all cylinders stacked (`gc`, the first
/// `ncon` rows of each).
fn output_rows(
    liner: &PartReduction,
    liner_maps: &[Vec<usize>],
    ncon: usize,
    n_rows: usize,
    n_g: usize,
) -> (Vec<Mat<f64>>, Mat<f64>) {
    let g_rows: Vec<Mat<f64>> = liner_maps
        .iter()
        .map(|map| scatter_rows(&liner.outputs, map, 0, n_rows, n_g))
        .collect();
    let mut gc = Mat::<f64>::zeros(ncon * g_rows.len(), n_g);
    for (i, g) in g_rows.iter().enumerate() {
        gc.as_mut()
            .subrows_mut(i * ncon, ncon)
            .copy_from(g.as_ref().subrows(0, ncon));
    }
    (g_rows, gc)
}

/// One system mode, the normalised thrust-side radial amplitude at each
/// cylinder's analysis points (cylinder-major, points top to bottom).
#[derive(serde::Serialize)]
pub struct ShapeMode {
    pub frequency_hz: f64,
    pub coefficients: Vec<Vec<f64>>,
}

impl EngineRom {
    /// Mode-shape coefficients: c_{cyl,p} = phi(point) / max |phi(points)| over all cylinders and
    /// points of that mode (so the largest is +-1; the sign shows the phase between cylinders).
    pub fn shapes(&self) -> Vec<ShapeMode> {
        let rom = self;
        (0..rom.frequencies_hz.len())
            .map(|j| {
                let raw: Vec<Vec<f64>> = rom
                    .cylinders
                    .iter()
                    .map(|c| {
                        (0..c.point_modes.nrows())
                            .map(|p| c.point_modes[[p, j]])
                            .collect()
                    })
                    .collect();
                let max = raw.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
                let scale = if max > 0.0 { 1.0 / max } else { 0.0 };
                ShapeMode {
                    frequency_hz: rom.frequencies_hz[j],
                    coefficients: raw
                        .into_iter()
                        .map(|r| r.into_iter().map(|v| v * scale).collect())
                        .collect(),
                }
            })
            .collect()
    }
}
