//! Raw scene structures, exactly as written in the TOML file. Units are SI unless the key names
//! another (`bore_mm`); unknown keys are rejected. `scene::validate` turns these into the
//! validated model.

use serde::Deserialize;
use std::collections::BTreeMap;

/// A whole scene file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawScene {
    /// Free text shown in reports.
    #[serde(default)]
    pub title: String,
    pub engine: RawEngine,
    /// Named isotropic materials, referred to by parts.
    pub materials: BTreeMap<String, RawMaterial>,
    pub liner: RawLiner,
    /// The crankcase; needed by the engine commands (`rom`, `modes --assembly`, `shapes`).
    #[serde(default)]
    pub crankcase: Option<RawCrankcase>,
    #[serde(default)]
    pub solver: RawSolver,
    /// Engine reduced-order model settings.
    #[serde(default)]
    pub rom: RawRom,
    /// Piston, skirt and contact (needed by `simulate`).
    #[serde(default)]
    pub piston: Option<RawPiston>,
    /// Operating point: load and cylinder pressure (needed by `simulate`).
    #[serde(default)]
    pub operating: Option<RawOperating>,
    /// Time integration (needed by `simulate`).
    #[serde(default)]
    pub transient: Option<RawTransient>,
    /// Coolant state and cavitation criteria (risk classes in `simulate`, `sweep`, `report`).
    #[serde(default)]
    pub cavitation: RawCavitation,
    /// What a run may take: work estimated beyond it is refused before it starts.
    #[serde(default)]
    pub limits: RawLimits,
    /// Optional parts of the design-review report (`linercav report`).
    #[serde(default)]
    pub report: RawReport,
}

/// `[report]`: what `linercav report` adds to its standard content when asked.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawReport {
    /// Another skirt model to compare the scene's against: "dry", "squeeze" or "mixed", not
    /// the scene's own `piston.lubrication`. The report then runs the scene, and its
    /// clearance and pin-offset sweeps at the same values, with that skirt as well (the oil
    /// film's data from `[piston.oil]`), and adds the section "Skirt models compared" to
    /// summary.md, `skirt_comparison` to summary.json and `skirt_comparison.png`. A
    /// lubricated run costs about 13 dry ones (docs/validation.md); a run that stops (a
    /// starved film's, exit 1) stops the report, as any of its runs does. Default: none.
    #[serde(default)]
    pub compare_lubrication: Option<RawLubrication>,
}

/// Resource limits. Before any work starts, linercav estimates the memory and time the scene
/// implies (mesh sizes, modes in the band, time steps, sweep runs) and refuses, naming the
/// estimate and the key that drives it, what exceeds these limits.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawLimits {
    /// Memory a run may use \[GB\]; default: 80 % of the memory the machine has available when
    /// the run starts. Raise it only when the estimate is known to be pessimistic.
    #[serde(default)]
    pub max_memory_gb: Option<f64>,
    /// Wall time a run (a sweep: all its runs) may take on this machine \[h\]; default 24.
    #[serde(default)]
    pub max_hours: Option<f64>,
}

/// Coolant and cavitation thresholds. Defaults: the reference study's coolant (water at 90 C,
/// 240 kPa, 4.7 mm gap); k_p derived from its 1189 m/s^2 high-risk threshold
/// (`cavitation::criteria`); high risk where Ca = 1; onset at 917/1189 of it (the study's
/// transition band).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawCavitation {
    /// Coolant temperature \[C\], 0-150.
    #[serde(default = "default_coolant_temp")]
    pub coolant_temp_c: f64,
    /// Static coolant pressure at the liner [kPa absolute], above the vapour pressure, at most
    /// 10000.
    #[serde(default = "default_static_kpa")]
    pub static_pressure_kpa: f64,
    /// Ethylene glycol mass fraction, 0-0.8.
    #[serde(default)]
    pub glycol: f64,
    /// Coolant gap between liner and crankcase wall \[mm\], > 0, at most 100.
    #[serde(default = "default_gap_mm")]
    pub gap_mm: f64,
    /// Wall-pressure transfer p_r = p_s + k_p a [Pa per m/s^2], in [0, 1e6]; default derived (see
    /// above).
    #[serde(default)]
    pub k_p_pa_per_m_s2: Option<f64>,
    /// Risk thresholds on the peak negative acceleration [m/s^2], in (0, 1e6]; defaults derived
    /// (see above).
    #[serde(default)]
    pub onset_m_s2: Option<f64>,
    #[serde(default)]
    pub high_risk_m_s2: Option<f64>,
    /// JSON written by `linercav calibrate --json` (path relative to the scene): its onset,
    /// high-risk and k_p replace the defaults; not allowed together with the three keys above.
    #[serde(default)]
    pub calibration_file: Option<String>,
    /// Coolant carried by the liner's wet outer surface (the guide band's top up to the deck's
    /// underside, where the liner enters the deck bore, or to the flange without one; node
    /// set `coolant_wetted`): "none" (default; the reference study's model) or
    /// "layer": the gap's coolant column moves with the wall's normal motion, a normal mass
    /// rho h per unit area (rho of the coolant above, h = `gap_mm`; the same column whose
    /// pressure difference rho a h the cavitation number uses). Part of the ROM: a scene with
    /// "layer" builds and caches its own, one per value of rho h (so a sweep over the coolant
    /// temperature, glycol or gap with the layer on builds one ROM per value).
    #[serde(default = "default_coolant_mass")]
    pub coolant_mass: String,
}

impl Default for RawCavitation {
    fn default() -> Self {
        Self {
            coolant_temp_c: default_coolant_temp(),
            static_pressure_kpa: default_static_kpa(),
            glycol: 0.0,
            gap_mm: default_gap_mm(),
            k_p_pa_per_m_s2: None,
            onset_m_s2: None,
            high_risk_m_s2: None,
            calibration_file: None,
            coolant_mass: default_coolant_mass(),
        }
    }
}
fn default_coolant_mass() -> String {
    "none".into()
}
fn default_coolant_temp() -> f64 {
    90.0
}
fn default_static_kpa() -> f64 {
    240.0
}
fn default_gap_mm() -> f64 {
    4.7
}

/// The crankcase: parametric (dimensions below) or a Gmsh mesh with the same named sets.
/// Dimensions that follow from the engine and liner (bore positions, seat and guide radii and
/// heights) are taken from there.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawCrankcase {
    /// Name of an entry of `[materials]`; required for the parametric mesh; with a
    /// `mesh_file` that defines materials (MAT1/PSOLID, *MATERIAL/*SOLID SECTION) optional,
    /// and when given it replaces the deck's materials.
    #[serde(default)]
    pub material: Option<String>,
    /// Length unit of `mesh_file`: "m" (default; SI constants) or "mm" (the mm-t-s system:
    /// E in MPa, rho in t/mm^3).
    #[serde(default)]
    pub mesh_unit: Option<String>,
    /// Node sets of the crankcase defined by geometry: `[crankcase.sets.NAME] box_mm = [x0,
    /// y0, z0, x1, y1, z1]` selects the nodes inside the box, e.g. the fixed set named in
    /// `fix`: in the crankcase mesh's own coordinates as read (a deck's, before linercav
    /// seats it on the liners; the engine frame for a generated crankcase), in mm whatever
    /// the mesh's unit.
    #[serde(default)]
    pub sets: BTreeMap<String, RawBoxSet>,
    /// Deck plate thickness below the liner flange seat \[mm\]. This and the other crankcase
    /// walls, rails and bay depth lie in [1 mm, 5 bores].
    pub deck_thickness_mm: f64,
    /// Water-jacket outer wall thickness at the thrust/anti-thrust side, at the cylinder centre
    /// line \[mm\] (the wall thickens towards the cylinder junctions).
    pub jacket_wall_mm: f64,
    /// Depth of the crank bay (skirt) below the liner bottom \[mm\].
    pub skirt_depth_mm: f64,
    /// Front (gear-end) wall thickness \[mm\].
    pub front_wall_mm: f64,
    /// Rear (flywheel-end) wall thickness \[mm\].
    pub rear_wall_mm: f64,
    /// Oil-pan rail: outward flange width \[mm\] and height \[mm\] at the skirt bottom.
    pub rail_width_mm: f64,
    pub rail_height_mm: f64,
    /// Head-bolt clamp force carried by each liner flange \[kN\] (bolt preload from torque:
    /// F = T / (k d)); pushes the flange down and pulls the deck up (the bolt reaction); > 0
    /// and at most 500 MPa over the bore area (5.2 MN at 115 mm; engines clamp with 10-40 MPa).
    pub flange_clamp_kn: f64,
    /// Node sets held fixed (engine mounting; at least one for the engine's ROM and its full
    /// model, none for a free-free `modes --part crankcase`); the parametric mesh offers
    /// `pan_rail`.
    #[serde(default)]
    pub fix: Vec<String>,
    /// Optional mesh file (Gmsh MSH 4.1 `.msh`, Nastran `.bdf`/`.nas`, Abaqus `.inp`; path
    /// relative to the scene file) replacing the parametric one. Its bores' axes at the
    /// engine frame's (x_c = (c - (N + 1) / 2) pitch, y = 0, z up) to its mesh tolerance;
    /// linercav seats it on the liners' flanges (a z move) and finds the `seat_<c>`,
    /// `guide_<c>`, `point_<c>_<k>` and `deck_top` sets it does not name (see the README).
    #[serde(default)]
    pub mesh_file: Option<String>,
    pub mesh: RawCrankcaseMesh,
}

/// A node set defined by geometry.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawBoxSet {
    /// The box's corners [x0, y0, z0, x1, y1, z1] \[mm\], x0 <= x1, y0 <= y1, z0 <= z1.
    pub box_mm: [f64; 6],
}

/// Density of the parametric crankcase mesh.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawCrankcaseMesh {
    /// "hex20" (the one element of the generated crankcase; "tet10" is refused: its split
    /// of the lattice inverts tetrahedra where the walls blend between bores).
    #[serde(default = "default_element")]
    pub element: String,
    /// Elements per quarter of each bore's circumference, even, >= 2.
    pub per_sector: usize,
    /// Element rings through the jacket wall, >= 1.
    pub wall_layers: usize,
    /// Target axial element size \[mm\].
    pub axial_size_mm: f64,
}

/// Engine reduced-order model (Craig-Bampton) settings.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawRom {
    /// Highest frequency of interest \[Hz\] (spectra, responses), in (0, 50000].
    #[serde(default = "default_band")]
    pub band_hz: f64,
    /// Cut-off of part and system modes as a multiple of `band_hz`, in [1, 10] (default 2.5).
    #[serde(default = "default_cutoff_factor")]
    pub cutoff_factor: f64,
    /// Highest circumferential harmonic N of the interface fields, >= 1.
    #[serde(default = "default_harmonics")]
    pub interface_harmonics: usize,
    /// Residual vectors of the contact loads: a hat-shaped load pattern every this many
    /// bore-line nodes per side (1: every node; 0: none, static correction only). They give the
    /// liner wall its local mass at the slap: with them the ROM matches the full-order model on
    /// the slap window (default 2 on the default engine: 1.57 %; every node 1.03 %; none ~50 %;
    /// docs/physics.md), every node at ~1.5x the modes and cycle time of every 2nd node.
    #[serde(default = "default_residual_spacing")]
    pub residual_vector_spacing: usize,
    /// Components the crankcase is cut into for its reduction (substructuring), 1..=cylinders:
    /// planes midway between bores, the cylinders shared out evenly, each component reduced on
    /// its own. 1 reduces it in one piece; more bound the memory by one component (a
    /// production-size crankcase) at a cost in accuracy set by `cut_shapes` (frequencies above
    /// the one-piece build's by 1e-4 to 5e-4 on the default engine in 3 components, 3e-4 to
    /// 3e-3 refined to 725k DOFs in 6; docs/physics.md). `rom`'s estimated error measures the
    /// modal truncation only, not the cuts'.
    #[serde(default = "default_components")]
    pub crankcase_components: usize,
    /// Shapes carried by each cut between crankcase components (traces of the lowest free modes
    /// of a slab around the cut), >= 6 (a cut's rigid motions; fewer than about 20 leave the
    /// frequencies percent-level high: +17 to +67 % with 1 on the test engine, 7.4e-3 with
    /// 20, 7.4e-4 with 80, 3.3e-4 median with the default on the default engine); a cut with at most 2 x this + 16 DOFs keeps every DOF
    /// (exact coupling: a large value such as 100000 asks for it; the build's estimate then
    /// counts every DOF of a cut at its estimated size, not the number given).
    #[serde(default = "default_cut_shapes")]
    pub cut_shapes: usize,
    /// Modes of each crankcase component up to this multiple of the part's cut-off (band_hz x
    /// cutoff_factor), in [1, 4] (default 1). The components' own truncation: on the default
    /// engine in 3 components with every cut DOF kept, 1 leaves the system frequencies below
    /// half the cut-off within 1.05e-5 of the one-piece build and 1.5 within 5.6e-7 (MAC 1 -
    /// 2e-9), at 1.2x the build time; with reduced cuts (200 shapes) the cut's error (3e-4)
    /// dominates and a higher factor buys nothing (docs/physics.md).
    #[serde(default = "default_component_cutoff_factor")]
    pub component_cutoff_factor: f64,
    /// Shapes added to each cut between crankcase components from a first assembly: the cut's
    /// force imbalance under the part's static shapes and modes, answered by the slab around
    /// the cut, its leading directions (0: none, the default; at most 10000). The components
    /// are reduced twice (the second time with the first pass's modes), and each cut's slab
    /// solves the compressed imbalances of the crankcase's static shapes and modes (about 4
    /// times the build time at 2.7M DOFs in 6 components: 43 min; the enriched shapes are
    /// cached with the crankcase, so a liner-only what-if does not repeat them). On the default
    /// engine in 3 components, 100 slab shapes with 200 added and
    /// `component_cutoff_factor = 1.5` keep the system frequencies below half the cut-off
    /// within 3.4e-6 of the one-piece build (200 slab shapes alone: 5.1e-3), MAC >= 0.99999
    /// for every mode (docs/physics.md).
    #[serde(default)]
    pub cut_enrichment: usize,
    /// Cylinders whose liners are modelled (1-based, each once); empty = all.
    #[serde(default)]
    pub cylinders: Vec<usize>,
    /// Directory of the ROM cache, relative to the scene file.
    #[serde(default = "default_cache_dir")]
    pub cache_dir: String,
}

impl Default for RawRom {
    fn default() -> Self {
        Self {
            band_hz: default_band(),
            cutoff_factor: default_cutoff_factor(),
            interface_harmonics: default_harmonics(),
            residual_vector_spacing: default_residual_spacing(),
            crankcase_components: default_components(),
            cut_shapes: default_cut_shapes(),
            component_cutoff_factor: default_component_cutoff_factor(),
            cut_enrichment: 0,
            cylinders: Vec::new(),
            cache_dir: default_cache_dir(),
        }
    }
}
fn default_band() -> f64 {
    3000.0
}
fn default_cutoff_factor() -> f64 {
    2.5
}
fn default_components() -> usize {
    1
}
fn default_cut_shapes() -> usize {
    200
}
fn default_component_cutoff_factor() -> f64 {
    1.0
}
fn default_residual_spacing() -> usize {
    2
}
fn default_harmonics() -> usize {
    6
}
fn default_cache_dir() -> String {
    ".linercav-cache".into()
}

/// Engine layout and operating point.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawEngine {
    /// Number of cylinders in line, >= 1.
    pub cylinders: usize,
    /// Firing order, a permutation of 1..=cylinders.
    pub firing_order: Vec<usize>,
    /// Cylinder bore \[mm\], in [20, 1500]; must equal the liner's inner diameter.
    pub bore_mm: f64,
    /// Piston stroke \[mm\].
    pub stroke_mm: f64,
    /// Connecting-rod length, centre to centre \[mm\]; longer than half the stroke, at most 10
    /// strokes.
    pub rod_length_mm: f64,
    /// Distance between neighbouring bore axes \[mm\]; larger than the liner flange diameter.
    pub cylinder_pitch_mm: f64,
    /// Engine speed \[rpm\], at least 50, with a mean piston speed 2 stroke n / 60 of at most 30 m/s.
    pub speed_rpm: f64,
}

/// An isotropic linear-elastic material.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawMaterial {
    /// Young's modulus \[Pa\], in [1e3, 1e14] (warned outside 1e9-1e12, the structural metals
    /// and composites).
    pub youngs_pa: f64,
    /// Poisson's ratio, in (-1, 0.5).
    pub poisson: f64,
    /// Density [kg/m^3], in [1, 1e5]; with E, a bar wave speed sqrt(E / rho) of at most 50
    /// km/s (diamond's is 17 km/s: mm-t-s constants read as SI are refused; E in MPa beside
    /// rho in kg/m^3 is warned of by the modulus range). The same bounds hold for the
    /// materials of a deck's solids and `--youngs/--density`.
    pub density_kg_m3: f64,
}

/// The wet liner: parametric geometry, or a Gmsh mesh file with the same named sets.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawLiner {
    /// Name of an entry of `[materials]`; required for the parametric mesh; with a
    /// `mesh_file` that defines materials optional, and when given it replaces them.
    #[serde(default)]
    pub material: Option<String>,
    /// Length unit of `mesh_file`: "m" (default; SI constants) or "mm" (the mm-t-s system:
    /// E in MPa, rho in t/mm^3).
    #[serde(default)]
    pub mesh_unit: Option<String>,
    /// Node sets of the liner defined by geometry: `[liner.sets.NAME] box_mm = [x0, y0, z0,
    /// x1, y1, z1]` in the liner's own frame (axis z, z = 0 at the liner bottom), mm.
    #[serde(default)]
    pub sets: BTreeMap<String, RawBoxSet>,
    /// Outer (coolant-side) diameter \[mm\].
    pub outer_diameter_mm: f64,
    /// Inner (bore) diameter \[mm\].
    pub inner_diameter_mm: f64,
    /// Overall length \[mm\].
    pub length_mm: f64,
    /// Diameter of the top flange \[mm\]; equal to the outer diameter for no flange.
    pub flange_outer_diameter_mm: f64,
    /// Height of the top flange \[mm\].
    pub flange_height_mm: f64,
    /// Height (axial length) of the lower guide band, the liner's radial support in the
    /// crankcase \[mm\].
    pub guide_height_mm: f64,
    /// Depth of the guide band's top edge below the liner top \[mm\]. Omitted: the band ends the
    /// liner (depth = length - guide height). Smaller: a short-jacket liner, supported part-way
    /// down, its lower end hanging free in the crank bay; the coolant zone (flange to guide)
    /// shortens, which stiffens the liner's ovalling.
    #[serde(default)]
    pub guide_depth_mm: Option<f64>,
    /// Diameter of the liner's pilot surfaces, the guide band and the part inside the crankcase
    /// deck, which is also the crankcase's bore there \[mm\]. Omitted: `outer_diameter_mm` (a
    /// plain tube). Given, the wet wall between the pilots has `outer_diameter_mm` and the
    /// crankcase depends on this diameter only, so a wet-wall what-if re-reduces the liner alone.
    #[serde(default)]
    pub pilot_diameter_mm: Option<f64>,
    /// Depth of the first analysis point below the liner top \[mm\].
    pub analysis_first_depth_mm: f64,
    /// Spacing of the analysis points, top to bottom \[mm\] (paper: 25), at least 1.
    pub analysis_spacing_mm: f64,
    /// Number of analysis points (paper: 4).
    pub analysis_points: usize,
    /// Optional mesh file of the liner (Gmsh MSH 4.1 `.msh`, Nastran `.bdf`/`.nas`, Abaqus
    /// `.inp`; path relative to the scene file); replaces the parametric mesh. It may lie
    /// anywhere in any orientation: linercav places it on its bore's axis in the liner's own
    /// frame and finds the sets it does not name (see the README).
    #[serde(default)]
    pub mesh_file: Option<String>,
    /// Node sets held fixed in a stand-alone modal analysis (`modes --part liner`); empty for
    /// free-free.
    #[serde(default)]
    pub fix: Vec<String>,
    pub mesh: RawLinerMesh,
}

/// Density of the parametric liner mesh.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawLinerMesh {
    /// "hex20" (default, best accuracy per DOF), "tet10", "hex8" (incompatible modes), "tet4".
    #[serde(default = "default_element")]
    pub element: String,
    /// Elements around the circumference, a multiple of 4 and >= 8.
    pub circumferential: usize,
    /// Elements through the wall, >= 1.
    pub radial: usize,
    /// Elements across the flange overhang, >= 1.
    #[serde(default = "one")]
    pub radial_flange: usize,
    /// Target axial element size \[mm\].
    pub axial_size_mm: f64,
}

fn default_element() -> String {
    "hex20".into()
}
fn one() -> usize {
    1
}

/// Numerical settings of the modal solve.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawSolver {
    /// Frequency f_s of the negative shift sigma = -(2 pi f_s)^2 \[Hz\], > 0; well below the
    /// first elastic mode, so rigid-body modes stay regular. A shift closer to zero than 1e-8
    /// of a part's eigenvalue scale trace(K) / trace(M) (about 30 Hz on the default liner) is
    /// moved away from it, with a warning: there a free body's rigid-body modes would fail
    /// their certificate on round-off.
    #[serde(default = "default_shift_hz")]
    pub shift_hz: f64,
    /// Extra modes computed beyond the request to place the Sturm check in a spectral gap.
    #[serde(default = "default_guard")]
    pub guard_modes: usize,
}

impl Default for RawSolver {
    fn default() -> Self {
        Self {
            shift_hz: default_shift_hz(),
            guard_modes: default_guard(),
        }
    }
}
fn default_shift_hz() -> f64 {
    100.0
}
fn default_guard() -> usize {
    4
}

/// The piston, its skirt and contact (needed by `simulate`, `sweep`, `report`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawPiston {
    /// Piston with rings, without the pin \[kg\], > 0: 200-10,000 kg per m^3 of bore cubed
    /// (warned outside), 10-100,000 (refused outside).
    pub mass_kg: f64,
    /// Pin plus the rod small-end share \[kg\], >= 0.
    pub pin_mass_kg: f64,
    /// Tilt inertia of the piston about the pin axis [kg m^2], > mass x cg_above_pin^2:
    /// 0.02-1 times mass x bore^2 (warned outside), 0.001-100 (refused outside).
    pub tilt_inertia_kg_m2: f64,
    /// Centre of gravity above the pin axis \[mm\] (negative: below).
    #[serde(default)]
    pub cg_above_pin_mm: f64,
    /// Centre of gravity beside the pin toward thrust \[mm\]; less than the bore's radius.
    #[serde(default)]
    pub cg_offset_mm: f64,
    /// Pin offset from the piston axis toward the thrust side \[mm\] (paper sweeps -1..+1); less
    /// than the bore's radius, warned beyond 5 % of the bore (engines use 0-2 %).
    #[serde(default)]
    pub pin_offset_mm: f64,
    /// Crankshaft axis offset from the bore axis toward thrust \[mm\]; less than the bore's
    /// radius.
    #[serde(default)]
    pub crank_offset_mm: f64,
    /// Pin axis to crown top \[mm\].
    pub compression_height_mm: f64,
    /// Crown below the liner top at top dead centre \[mm\], >= 0.
    pub crown_depth_at_tdc_mm: f64,
    /// Skirt length \[mm\] and skirt top above the pin axis \[mm\].
    pub skirt_length_mm: f64,
    pub pin_below_skirt_top_mm: f64,
    /// Cold diametral clearance at the widest skirt height \[um\], >= 0; at most 2 % of the bore
    /// (warned above 0.5 %: running clearances are 0.05-0.2 %).
    pub clearance_um: f64,
    /// Radial barrel drop at the farther skirt end \[um\], in [0, 5000] (from the widest height,
    /// `barrel_max_below_pin_mm`).
    #[serde(default)]
    pub barrel_um: f64,
    /// Height of the barrel's widest point below the pin axis \[mm\]: on the skirt, from
    /// -pin_below_skirt_top_mm (its top) to skirt_length_mm - pin_below_skirt_top_mm (its
    /// bottom).
    #[serde(default)]
    pub barrel_max_below_pin_mm: f64,
    /// Ovality: thrust-axis minus pin-axis skirt diameter \[um\], in [0, 5000].
    #[serde(default)]
    pub ovality_um: f64,
    /// Skirt slices per side, >= 10.
    pub slices: usize,
    /// Penalty stiffness per slice [N/m] (full-arc contact), in (0, 1e12].
    pub contact_stiffness_n_per_m: f64,
    /// Contact damping per slice [N s/m], >= 0: a damping ratio c / (2 sqrt(k m)) on the
    /// piston's mass and the slice's stiffness above 10 is warned of, above 1,000 refused.
    pub contact_damping_n_s_per_m: f64,
    /// Coulomb friction coefficient of the skirt, in [0, 1] (0: no friction).
    #[serde(default)]
    pub friction: f64,
    /// Friction coefficient of the pin journal, in [0, 1] (0: no pin friction, the reference
    /// study's model; 0.02-0.08 for a lubricated pin \[assumption\]). The joint's torque
    /// mu r_pin F_pin tanh((beta' - phi') / w_s) drags the piston's tilt toward the rod's
    /// rotation (docs/physics.md).
    #[serde(default)]
    pub pin_friction: f64,
    /// Pin diameter \[mm\], from a tenth of the bore to less than the bore; none: 0.4 x bore
    /// (heavy-duty diesels use 0.38-0.42). Used by `pin_friction` only.
    #[serde(default)]
    pub pin_diameter_mm: Option<f64>,
    /// Slip rate w_s over which the pin's torque reverses [rad/s], in [1e-4, 1e4]: at a
    /// relative rate of w_s it reaches tanh(1) = 76 % of its Coulomb value (the journal's
    /// boundary friction at near-zero sliding; the rod turns at up to r omega / l, 64 rad/s on
    /// the default engine). Default 1.
    #[serde(default = "default_pin_slip")]
    pub pin_slip_rad_s: f64,
    /// The skirt's oil film: "dry" (default: the penalty contact alone, the reference study's
    /// model), "squeeze" (the Reynolds squeeze and sliding film, cavitated by the Reynolds
    /// condition: no suction, the film ruptures where p = dp/dx = 0) or "mixed"
    /// (the film plus Greenwood-Tripp asperity contact). The film's data: `[piston.oil]`.
    /// The lubricated transient is experimental: verified and converged with the step, about
    /// 10-14 times the cost of a dry run (docs/validation.md).
    #[serde(default)]
    pub lubrication: RawLubrication,
    /// Oil film data (used when `lubrication` is not "dry"; every key has a default).
    #[serde(default)]
    pub oil: RawOil,
    pub thermal: RawThermal,
}

fn default_pin_slip() -> f64 {
    1.0
}

/// `piston.lubrication`: a name (read from a string, so that another type is told what is
/// expected).
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(try_from = "String")]
pub enum RawLubrication {
    #[default]
    Dry,
    Squeeze,
    Mixed,
}

impl TryFrom<String> for RawLubrication {
    type Error = String;
    fn try_from(name: String) -> Result<Self, String> {
        match name.as_str() {
            "dry" => Ok(Self::Dry),
            "squeeze" => Ok(Self::Squeeze),
            "mixed" => Ok(Self::Mixed),
            other => Err(format!(
                "unknown model `{other}`, expected one of `dry`, `squeeze`, `mixed`"
            )),
        }
    }
}

/// The skirt's oil film (`[piston.oil]`), defaults of a heavy-duty diesel with a 15W-40 class
/// oil \[assumption\].
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawOil {
    /// Oil available on the liner \[um\], in (0, 1000]: a gap larger than it is not wetted
    /// (partial flooding; a large value floods the skirt). Below 3 (the film's gap floor) a
    /// starved film, warned of: it may stop the run (exit 1; docs/validation.md). Default 20.
    #[serde(default = "default_supply")]
    pub supply_um: f64,
    /// Vogel viscosity mu = a exp(b / (T + c)) at the film temperature T \[deg C\] (the mean of
    /// the skirt's, linear from its top to its bottom, and the liner's bore temperature):
    /// a \[mPa s\] > 0, b \[deg C\] > 0, c \[deg C\] with T + c > 0 (`[piston.oil]` is read
    /// for a dry skirt too), and for a film between 0.1 mPa s and 10^7 mPa s at the film's
    /// temperatures. Defaults 0.1366, 826.9, 85.3: 100 mPa s at 40 deg C, 11.8 at 100, 6.4 at
    /// 130.
    #[serde(default = "default_vogel_a")]
    pub vogel_a_mpa_s: f64,
    #[serde(default = "default_vogel_b")]
    pub vogel_b_c: f64,
    #[serde(default = "default_vogel_c")]
    pub vogel_c_c: f64,
    /// Greenwood-Tripp (used by `mixed`, checked for any skirt): composite roughness sigma
    /// \[um\] in [0.001, 100]
    /// (default 1.0), the roughness parameter eta beta sigma in [1e-4, 1] (default 0.04), the
    /// slope parameter sigma / beta in [1e-6, 1] (default 0.001) and the composite modulus E'
    /// \[GPa\] in [1, 1000], 1 / E' = (1 - nu_1^2) / E_1 + (1 - nu_2^2) / E_2 (default 82: a
    /// steel skirt on a cast-iron liner).
    #[serde(default = "default_roughness")]
    pub roughness_um: f64,
    #[serde(default = "default_ebs")]
    pub eta_beta_sigma: f64,
    #[serde(default = "default_sob")]
    pub sigma_over_beta: f64,
    #[serde(default = "default_modulus")]
    pub asperity_modulus_gpa: f64,
}
impl Default for RawOil {
    fn default() -> Self {
        Self {
            supply_um: default_supply(),
            vogel_a_mpa_s: default_vogel_a(),
            vogel_b_c: default_vogel_b(),
            vogel_c_c: default_vogel_c(),
            roughness_um: default_roughness(),
            eta_beta_sigma: default_ebs(),
            sigma_over_beta: default_sob(),
            asperity_modulus_gpa: default_modulus(),
        }
    }
}
fn default_supply() -> f64 {
    20.0
}
fn default_vogel_a() -> f64 {
    0.1366
}
fn default_vogel_b() -> f64 {
    826.9
}
fn default_vogel_c() -> f64 {
    85.3
}
fn default_roughness() -> f64 {
    1.0
}
fn default_ebs() -> f64 {
    0.04
}
fn default_sob() -> f64 {
    1e-3
}
fn default_modulus() -> f64 {
    82.0
}

/// Temperatures and expansion coefficients giving the hot clearance.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawThermal {
    /// Linear expansion of the piston skirt [1/K].
    pub piston_expansion_per_k: f64,
    /// Skirt temperature at its top and bottom [deg C] (linear in between).
    pub skirt_top_temp_c: f64,
    pub skirt_bottom_temp_c: f64,
    /// Linear expansion of the liner [1/K] and its bore temperature [deg C].
    pub liner_expansion_per_k: f64,
    pub liner_temp_c: f64,
    /// Temperature at which the clearance is given [deg C].
    #[serde(default = "default_ref_temp")]
    pub reference_temp_c: f64,
}
fn default_ref_temp() -> f64 {
    20.0
}

/// Operating point besides the speed (`engine.speed_rpm`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawOperating {
    /// Load as a fraction of rated, in [0, 1] (scales heat release and boost of the built-in curve).
    pub load: f64,
    /// Measured cylinder pressure, CSV `crank_angle_deg,pressure_bar` (absolute; path relative
    /// to the scene; the cylinder's own angle, firing TDC at 360); replaces the built-in curve.
    /// The two columns are found by their header names, in any order; other columns are not
    /// read (each row still needs as many fields as the header). The table covers the whole 0-720 deg cycle, samples at most 45 deg apart (the wrap
    /// through 720/0 included), pressures in (0, 1000] bar, and is interpolated linearly and
    /// periodically.
    #[serde(default)]
    pub pressure_file: Option<String>,
    /// Crankcase pressure under the piston [bar absolute], in (0, 10].
    #[serde(default = "default_cc_bar")]
    pub crankcase_pressure_bar: f64,
    pub combustion: RawCombustion,
}
fn default_cc_bar() -> f64 {
    1.0
}

/// Built-in Wiebe pressure curve at full load; its peak must not exceed 1000 bar (the bound of
/// a pressure table's values).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawCombustion {
    /// Geometric compression ratio, > 1.
    pub compression_ratio: f64,
    /// Intake (boost) pressure at full load [bar absolute], >= 1.
    pub intake_bar: f64,
    /// Exhaust back-pressure above intake \[bar\].
    pub exhaust_over_intake_bar: f64,
    /// Start of combustion [deg crank angle; firing TDC = 360].
    pub start_deg: f64,
    /// Duration of combustion \[deg\], in [5, 720] (burns last 40-120 deg; a shorter one than
    /// 5 deg falls between the built-in curve's 0.1-deg integration steps).
    pub duration_deg: f64,
    /// Wiebe parameters a in [0.001, 50] and m in [0, 20].
    pub wiebe_a: f64,
    pub wiebe_m: f64,
    /// Net heat released per cycle at full load \[J\].
    pub heat_release_j: f64,
    /// Polytropic exponent of the closed cycle, in (1, 1.67).
    pub polytropic: f64,
    /// Exhaust valve opening \[deg\], between 450 and 700.
    pub evo_deg: f64,
}

/// Time integration of the slap transient.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawTransient {
    /// "newmark" (average acceleration) or "hht". Default: "newmark" for a dry skirt, "hht"
    /// for a lubricated one: the squeeze film is a stiff damper on the liner's light modes
    /// (c dt / m of order 1e3 for a 10 um film, an estimate), on which the average-acceleration
    /// rule rings with a factor near
    /// -1 per step and grows where the film opens (c ~ h^-3 falls); HHT damps that ringing
    /// (factor -0.82 per step at alpha -0.05). The default engine's squeeze run stopped in
    /// its sixth cycle with "newmark" and runs through with "hht" (docs/validation.md).
    #[serde(default)]
    pub scheme: Option<String>,
    /// HHT alpha in [-1/3, 0] (used by scheme "hht", given or a lubricated skirt's default;
    /// checked under either scheme).
    #[serde(default = "default_alpha")]
    pub hht_alpha: f64,
    /// Crank-angle step \[deg\]; 720 must be a whole multiple of it.
    pub step_deg: f64,
    /// Engine cycles run from rest, >= 1.
    pub cycles: usize,
    /// The last this many cycles are averaged (>= 1; more than `cycles`: all of them, warned
    /// when that includes the start-up cycle from rest of a run of several; default 1: the
    /// last cycle alone). Each reported peak is the mean over them of the per-cycle peak, with
    /// its sample standard deviation and largest value: piston slap on a ringing liner is not
    /// periodic (the default engine's consecutive cycles differ by 20-40 %), so one cycle's
    /// peak is one draw, and the mean is the quantity that converges with the step.
    #[serde(default = "one")]
    pub averaged_cycles: usize,
    /// Halve steps whose contact iteration fails or that penetrate too deep.
    #[serde(default = "yes")]
    pub adaptive: bool,
    /// Modal damping ratio of the engine's system modes, in [0, 1).
    pub damping_ratio: f64,
    /// Largest acceptable skirt penetration \[um\], at least 0.1 (the contact carries its load
    /// through penetrations of a few um); deeper stops the run.
    pub max_penetration_um: f64,
    /// Integrate system modes up to this frequency \[Hz\] only; the modes above respond
    /// statically to every cylinder's contact forces (at the contact, the liner's and the
    /// crankcase's analysis points and the liner maps). Default: every mode of the ROM (up to
    /// the ROM cut-off).
    #[serde(default)]
    pub mode_cutoff_hz: Option<f64>,
    /// Accuracy of the peaks: the largest acceptable estimated relative step error of the
    /// mean peak negative acceleration, in (0, 1) (default 0.05). Every run estimates it by
    /// re-running each cylinder's firing slap at half the step (2 |P_h - P_h/2|, conservative:
    /// it assumes first-order convergence); above the tolerance the step is halved and the run
    /// repeated, at most twice (each costs twice the time); what was reached is reported
    /// (`stats.step_error_estimate`, per point `peak_negative_step_error_m_s2`). Measured on
    /// the default engine at 0.25 deg with its slap sub-steps (pooled realisations,
    /// benches/convergence.sh): estimate 2.1 %, error of the mean against a step 64 times
    /// finer +0.24 %, the cylinders' worst points -1.9 .. +2.9 % (their estimates 0.4-2.0 %
    /// under-state cylinders 1, 3, 4 and 5: 2.0, 1.3, 1.3 and 0.6 % against 2.9, 2.0, 1.9 and
    /// 2.8 %; `simulate --check-step` measures the whole step error).
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
    /// Sub-steps per base step while a slap is resolved, 1-64 (1: none; default 3). A base
    /// step in which a cylinder side comes into contact is re-taken as this many sub-steps, and
    /// so are the base steps of the next `slap_span_deg`: the impacts, where the step's error is
    /// made, are integrated at the finer step, the rest of the cycle at the base step.
    #[serde(default = "default_slap_substeps")]
    pub slap_substeps: usize,
    /// How long after a contact onset the base steps are sub-stepped [deg crank angle], >= 0
    /// (default 1.5: the contact periods of an impact and its first rebounds).
    #[serde(default = "default_slap_span")]
    pub slap_span_deg: f64,
    /// Time budget of a decided ranking (`simulate --rank`, `report`) \[s\], > 0 (default
    /// 90), beyond the run and its half-step check. The ranking adds realisations (the run and its half-step check repeated with the
    /// damping ratio perturbed at 1e-6, which decorrelates the slap history) while a neighbour
    /// pair of cylinders is neither separated nor tied at the resolution and the next
    /// realisation is expected to finish within the budget; it says where it stopped and why.
    #[serde(default = "default_max_seconds")]
    pub max_seconds: f64,
}
fn default_max_seconds() -> f64 {
    90.0
}
fn default_slap_substeps() -> usize {
    3
}
fn default_slap_span() -> f64 {
    1.5
}
fn default_tolerance() -> f64 {
    0.05
}
fn default_alpha() -> f64 {
    -0.05
}
fn yes() -> bool {
    true
}
