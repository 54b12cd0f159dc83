//! The validated scene: every part of the engine model in SI units, as the stages read it.

#[allow(unused_imports)]
use super::*;

/// Engine layout and operating point, SI.
#[derive(Clone, Debug, PartialEq)]
pub struct Engine {
    pub cylinders: usize,
    pub firing_order: Vec<usize>,
    pub bore: f64,
    pub stroke: f64,
    pub rod_length: f64,
    pub cylinder_pitch: f64,
    pub speed_rpm: f64,
}

/// Bore axis x of cylinder `c` (0-based) of `cylinders` at pitch `pitch`, the block centred on
/// x = 0: x_c = (c - (N - 1) / 2) p.
pub fn bore_axis_x(cylinders: usize, pitch: f64, c: usize) -> f64 {
    (c as f64 - (cylinders as f64 - 1.0) / 2.0) * pitch
}

/// Where a part's mesh comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum MeshSource {
    Liner {
        geometry: LinerGeometry,
        meshing: LinerMeshing,
    },
    File(PathBuf),
}

/// One part: mesh source, material and the sets fixed in a stand-alone modal analysis.
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    pub name: String,
    pub source: MeshSource,
    /// The scene's material; `None` when the mesh file's own materials are used.
    pub material: Option<Elastic>,
    pub fix: Vec<String>,
    /// Unit of a mesh file's lengths (and constants).
    pub mesh_unit: spec::MeshUnit,
    /// Node sets defined by boxes, \[m\] in the part's frame.
    pub box_sets: Vec<(String, [f64; 6])>,
}

/// Modal solver settings.
#[derive(Clone, Debug, PartialEq)]
pub struct Solver {
    pub shift_hz: f64,
    pub guard_modes: usize,
}

impl Solver {
    /// The shift sigma = -(2 pi f_s)^2 [rad^2/s^2].
    pub fn sigma(&self) -> f64 {
        -(2.0 * std::f64::consts::PI * self.shift_hz).powi(2)
    }
}

/// Where the crankcase mesh comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum CrankcaseSource {
    Parametric {
        geometry: CrankcaseGeometry,
        meshing: CrankcaseMeshing,
    },
    File(PathBuf),
}

/// The validated crankcase.
#[derive(Clone, Debug, PartialEq)]
pub struct Crankcase {
    pub source: CrankcaseSource,
    /// The scene's material; `None` when the mesh file's own materials are used.
    pub material: Option<Elastic>,
    /// Unit of a mesh file's lengths (and constants).
    pub mesh_unit: spec::MeshUnit,
    /// Node sets defined by boxes, \[m\] in the engine frame.
    pub box_sets: Vec<(String, [f64; 6])>,
    pub fix: Vec<String>,
    /// Clamp force on each liner flange \[N\].
    pub clamp_force: f64,
}

/// Engine ROM settings, SI.
#[derive(Clone, Debug, PartialEq)]
pub struct Rom {
    pub band_hz: f64,
    /// Cut-off of part and system modes \[Hz\] (band x cutoff factor).
    pub cutoff_hz: f64,
    pub harmonics: usize,
    /// Residual-vector pattern spacing in bore-line nodes (0: none).
    pub residual_vector_spacing: usize,
    /// Components the crankcase is cut into (1: one piece).
    pub crankcase_components: usize,
    /// Shapes per cut between crankcase components.
    pub cut_shapes: usize,
    /// Components' modes up to this multiple of `cutoff_hz`.
    pub component_cutoff_factor: f64,
    /// Shapes added to each cut from a first assembly's imbalance (0: none).
    pub cut_enrichment: usize,
    /// Modelled cylinders, 1-based, ascending.
    pub cylinders: Vec<usize>,
    pub cache_dir: PathBuf,
}

/// Where the cylinder pressure comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum PressureSource {
    File(PathBuf),
    Wiebe(spec::Wiebe),
}

/// Piston data, SI (see [`raw::RawPiston`] for the meaning of each field).
#[derive(Clone, Debug, PartialEq)]
pub struct PistonSpec {
    pub mass: f64,
    pub pin_mass: f64,
    pub tilt_inertia: f64,
    pub cg_above_pin: f64,
    pub cg_lateral: f64,
    pub pin_offset: f64,
    pub crank_offset: f64,
    pub compression_height: f64,
    pub crown_depth_at_tdc: f64,
    pub skirt: spec::SkirtSpec,
    pub contact_damping: f64,
    pub friction: f64,
    /// Pin friction coefficient (0: none), pin radius \[m\] and the slip rate of its torque's
    /// reversal [rad/s].
    pub pin_friction: f64,
    pub pin_radius: f64,
    pub pin_slip_rate: f64,
    /// The oil film; `None` for a dry skirt.
    pub oil: Option<spec::OilSpec>,
}

impl PistonSpec {
    /// The skirt model that runs: the oil film's, or dry without one.
    pub fn lubrication(&self) -> spec::Lubrication {
        self.oil
            .as_ref()
            .map_or(spec::Lubrication::Dry, |o| o.model)
    }
}

/// Operating point besides the speed, SI.
#[derive(Clone, Debug, PartialEq)]
pub struct Operating {
    pub load: f64,
    pub pressure: PressureSource,
    pub crankcase_pa: f64,
}

/// Transient settings, SI.
#[derive(Clone, Debug, PartialEq)]
pub struct TransientSpec {
    pub scheme: spec::SchemeChoice,
    pub step_deg: f64,
    pub cycles: usize,
    /// The last this many cycles are averaged.
    pub averaged_cycles: usize,
    pub adaptive: bool,
    pub damping_ratio: f64,
    pub max_penetration: f64,
    pub mode_cutoff_hz: Option<f64>,
    /// Largest acceptable estimated relative step error of the mean peak.
    pub tolerance: f64,
    /// Sub-steps per base step around slap onsets, and for how long after one \[deg\].
    pub slap_substeps: usize,
    pub slap_span_deg: f64,
    /// Time budget of a decided ranking \[s\].
    pub max_seconds: f64,
}

/// What `simulate` needs beyond the ROM.
#[derive(Clone, Debug, PartialEq)]
pub struct Simulation {
    pub piston: PistonSpec,
    pub operating: Operating,
    pub transient: TransientSpec,
}

/// Coolant state, gap and risk thresholds, SI.
#[derive(Clone, Debug, PartialEq)]
pub struct CavitationSpec {
    pub coolant: crate::coolant::Coolant,
    pub gap: f64,
    /// The thresholds as the scene gives them; [`crate::cavitation::Setup`] resolves them.
    pub thresholds: ThresholdSpec,
    /// The coolant layer's normal mass on the liner's wet surface [kg/m^2] (rho h), when the
    /// scene models it (`coolant_mass = "layer"`).
    pub layer_mass_per_area: Option<f64>,
}

/// A validated scene, SI units.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub path: PathBuf,
    pub title: String,
    pub engine: Engine,
    pub liner: Part,
    /// The liner geometry (also when the mesh comes from a file: interfaces and analysis
    /// heights are defined by it).
    pub liner_geometry: LinerGeometry,
    pub crankcase: Option<Crankcase>,
    pub solver: Solver,
    pub rom: Rom,
    /// Piston, operating point and transient settings, when the scene has all three sections.
    pub simulation: Option<Simulation>,
    pub cavitation: CavitationSpec,
    pub limits: Limits,
    /// What the report adds when asked (`[report]`).
    pub report: ReportSpec,
    /// Values that are accepted but physically doubtful (also logged as warnings on load).
    pub warnings: Vec<String>,
}

/// Optional parts of the report (`[report]`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReportSpec {
    /// The skirt model the scene's is compared against (never the scene's own).
    pub compare_lubrication: Option<super::spec::Lubrication>,
}

/// Resource limits of a run (`[limits]`; see [`budget`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Limits {
    pub max_memory_gb: Option<f64>,
    pub max_hours: Option<f64>,
}

/// Most interface harmonics (see `rom.interface_harmonics`).
pub const MAX_HARMONICS: usize = 64;
/// Most skirt slices per side (see `piston.slices`).
pub const MAX_SLICES: usize = 400;
/// Most guard modes of the Sturm check: it needs a spectral gap among a few extra modes; each
/// one costs a Lanczos vector of the full model.
pub const MAX_GUARD_MODES: usize = 200;

/// Part names a scene knows.
pub const PARTS: [&str; 1] = ["liner"];
