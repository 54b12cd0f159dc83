//! The library's front door: load a scene, get or build its ROM, run the engine cycles and
//! evaluate the cavitation risk; for the single-part commands, a part's checked mesh and
//! material ([`load_part`]); variants of a scene run in parallel on shared ROMs ([`Variants`],
//! the sweeps' and the report's runs), and the transients behind a design-review report
//! ([`report_runs`]); and the commands of the command-line tool as functions that take a
//! request and return a serialisable report, writing their files atomically ([`simulate`],
//! [`sweep`], [`modes`], [`rom`], ...). The command line (`src/main.rs`, `src/cli/`) and the
//! tests go through here; each re-exported item belongs to its pipeline stage
//! (docs/physics.md), the items defined here join the scene to the stages:
//!
//! ```no_run
//! use linercav::api::*;
//! let scene = load_scene("models/engine.toml".as_ref(), &["piston.clearance_um=120".into()])?;
//! let rom = get_rom(&scene, &CacheOptions::default(), &|_| {})?.rom;
//! let piston = piston_of(&scene)?;
//! let settings = settings_of(simulation(&scene)?, scene.rom.band_hz);
//! let result = run_cycle(&scene, &rom, &piston, settings, |_, _| {})
//!     .map_err(|source| Error::Transient { path: scene.path.clone(), source })?;
//! let risk = evaluate_scene(&scene, &rom, &result)?;
//! # Ok::<(), linercav::api::Error>(())
//! ```

pub mod cavitation;
pub mod compare;
pub mod export;
pub mod full_modes;
pub mod full_order;
pub mod maps;
pub mod modes;
pub mod progress;
pub mod rank;
pub mod rom;
pub mod rom_tradeoff;
pub mod simulate;
pub mod summary;
pub mod sweep;

use crate::analysis::refine::{initial, located, next_unsampled, Maximum, Sample};
pub use crate::cavitation::evaluate::{evaluate, Evaluation};
pub use crate::error::{Error, Result};
use crate::fem::element::check_mesh as check_and_compact;
use crate::mesh::checks::CheckReport;
use crate::mesh::{liner, Mesh};
pub use crate::piston::setup::{piston_of, simulation};
pub use crate::piston::Piston;
pub use crate::reduce::rom::EngineRom;
use crate::reduce::scene_rom::key_description;
pub use crate::reduce::scene_rom::{build_rom, get_rom, CacheOptions, LoadedRom};
pub use crate::report::figures::SweepPoint;
pub use crate::report::records::{CylinderReport, PointPeaks, SimulateReport};
use crate::scene::spec::Elastic;
pub use crate::scene::Scene;
use crate::scene::{MeshSource, PARTS};
pub use crate::transient::cycle::{CycleResult, CycleSettings};
pub use crate::transient::engine::{run_cycle, run_half_step, settings_of};
pub use crate::transient::verify::TradeoffPoint;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Loads and validates a scene with its `--set` overrides, and resolves its cavitation
/// thresholds, so that thresholds out of order are refused (exit 2, naming the file) before
/// any work starts.
pub fn load_scene(path: &Path, sets: &[String]) -> Result<Scene> {
    let scene = Scene::load(path, sets)?;
    crate::cavitation::Setup::new(&scene.cavitation).map_err(|e| {
        // thresholds out of order come from the calibration file when one is given
        let key = match scene.cavitation.thresholds {
            crate::scene::spec::ThresholdSpec::Calibrated { .. } => "cavitation.calibration_file",
            crate::scene::spec::ThresholdSpec::Scene { .. } => "cavitation",
        };
        crate::scene::SceneError::Field {
            path: path.to_path_buf(),
            key: key.into(),
            msg: e.to_string(),
        }
    })?;
    Ok(scene)
}

/// The cavitation risk of a run of `scene` on `rom` ([`evaluate`] with the scene's coolant
/// state and thresholds, in the ROM's band).
pub fn evaluate_scene(scene: &Scene, rom: &EngineRom, result: &CycleResult) -> Result<Evaluation> {
    Ok(evaluate(
        result,
        rom,
        &crate::cavitation::Setup::new(&scene.cavitation)?,
        &scene.engine.firing_order,
        scene.rom.band_hz,
    ))
}

/// Where the model of a command comes from: a scene part, or a bare mesh file in its unit
/// with a material (None: the deck's own).
#[derive(Clone, Debug)]
pub enum ModelInput {
    Scene {
        scene: PathBuf,
        part: String,
        sets: Vec<String>,
    },
    Mesh {
        mesh: PathBuf,
        unit: crate::mesh::MeshUnit,
        material: Option<Elastic>,
        fix: Vec<String>,
        /// `--set` overrides: with a bare mesh only `limits.max_memory_gb` and
        /// `limits.max_hours` ([`mesh_limits`]).
        sets: Vec<String>,
    },
}

impl ModelInput {
    /// The file the model is read from: the scene or the mesh.
    pub fn path(&self) -> &Path {
        match self {
            ModelInput::Scene { scene, .. } => scene,
            ModelInput::Mesh { mesh, .. } => mesh,
        }
    }
}

/// The limits of work on a bare mesh: the machine's ([`crate::scene::budget::Limits::machine`])
/// with `limits.max_memory_gb=GB` and `limits.max_hours=H` from `sets` (the only scene keys
/// that apply without a scene); any other key, or a value that is not a positive number, is
/// refused naming it.
pub fn mesh_limits(sets: &[String]) -> Result<crate::scene::budget::Limits> {
    let (mut gb, mut hours) = (None, None);
    for set in sets {
        let bad = |msg: &str| Error::Argument {
            flag: format!("--set {set}"),
            msg: msg.into(),
        };
        let (key, value) = set
            .split_once('=')
            .ok_or_else(|| bad("expected KEY=VALUE"))?;
        let slot = match key.trim() {
            "limits.max_memory_gb" => &mut gb,
            "limits.max_hours" => &mut hours,
            _ => {
                return Err(bad(
                    "with --mesh only limits.max_memory_gb and limits.max_hours apply (the other keys are a scene's)",
                ))
            }
        };
        let v: f64 = value
            .trim()
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite() && *v > 0.0)
            .ok_or_else(|| bad("expected a positive number"))?;
        *slot = Some(v);
    }
    Ok(crate::scene::budget::Limits::machine().with(gb, hours))
}

/// A checked mesh with its material, the sets to fix, and the mesh-check findings.
pub struct LoadedPart {
    pub mesh: Mesh,
    /// The given material, or (when `material_source` is deck) the deck's first: each element
    /// carries its own then.
    pub material: Elastic,
    pub material_source: crate::mesh::import::MaterialSource,
    pub fix: Vec<String>,
    pub checks: CheckReport,
    pub label: String,
    /// Shift frequency of the modal solve \[Hz\].
    pub shift_hz: f64,
    pub guard_modes: usize,
    /// The limits the work on the part must stay within (the scene's, or the machine's for a
    /// bare mesh), and the file a refusal names (the mesh file, else the scene).
    pub limits: crate::scene::budget::Limits,
    pub limits_file: std::path::PathBuf,
}

/// A mesh as read: the mesh, its file (None when generated), the material, where it came
/// from, and a warning when a given material replaced the deck's different one.
type ReadMesh = (
    Mesh,
    Option<String>,
    Elastic,
    crate::mesh::import::MaterialSource,
    Option<String>,
);

/// A part's mesh: generated, or a file read in `unit`, with its material resolved.
fn read_mesh(
    source: &MeshSource,
    unit: crate::mesh::MeshUnit,
    unit_key: &str,
    given: Option<Elastic>,
    material_key: &str,
) -> Result<ReadMesh> {
    use crate::mesh::import;
    match source {
        MeshSource::Liner { geometry, meshing } => {
            let m = given.ok_or_else(|| Error::Argument {
                flag: material_key.into(),
                msg: "missing: the parametric mesh needs a material".into(),
            })?;
            Ok((
                liner::generate(geometry, meshing),
                None,
                m,
                import::MaterialSource::Given,
                None,
            ))
        }
        MeshSource::File(p) => {
            let mut mesh = import::read_si(p, unit, unit_key)
                .map_err(crate::reduce::scene_rom::SceneRomError::from)?;
            let (m, src, warning) = import::resolve_material(&mut mesh, given, p, material_key)
                .map_err(crate::reduce::scene_rom::SceneRomError::from)?;
            Ok((mesh, Some(p.display().to_string()), m, src, warning))
        }
    }
}

/// Sizes a generated liner's assembly before the mesh is made (`liner.mesh.radial = 100000`
/// ran for minutes at 6-12 GB, and aborted under an address-space cap); its solve is checked
/// once the factor's size is known (`crate::scene::budget::modal_solve`).
fn check_generated(
    sc: &Scene,
    source: &MeshSource,
    limits: &crate::scene::budget::Limits,
) -> Result<()> {
    if let MeshSource::Liner { geometry, meshing } = source {
        let dofs = crate::scene::budget::liner_dofs(geometry, meshing);
        let kind = std::iter::once(meshing.kind);
        let mut est = crate::scene::budget::assembly(dofs.min(1e18) as usize, kind);
        est.keys = "liner.mesh (radial, radial_flange, circumferential, axial_size_mm)";
        limits.check(sc, &est)?;
    }
    Ok(())
}

/// A bare mesh file read in `unit`, with the material of the flags (checked) or the deck's.
fn read_bare_mesh(
    mesh: &std::path::Path,
    unit: crate::mesh::MeshUnit,
    material: Option<Elastic>,
) -> Result<ReadMesh> {
    if let Some(m) = material {
        m.validate().map_err(|m| Error::Argument {
            flag: "--youngs/--poisson/--density".into(),
            msg: m.to_string(),
        })?;
        if let Some(w) = m.structural_warning("--youngs") {
            log::warn!("{w}");
        }
    }
    read_mesh(
        &MeshSource::File(mesh.to_path_buf()),
        unit,
        "--unit",
        material,
        "--youngs/--poisson/--density",
    )
}

/// A scene part's box sets added to its mesh; one that selects no node is refused (a fixed
/// box of none left the part free under "fixed: NAME").
fn add_box_sets(
    mesh: &mut Mesh,
    (scene, part): (&Path, &str),
    sets: &[(String, [f64; 6])],
) -> Result<()> {
    for (name, b) in sets {
        if crate::mesh::find::box_set(mesh, part, name, b).nodes == 0 {
            return Err(Error::Argument {
                flag: format!("{}: {part}.sets.{name}.box_mm", scene.display()),
                msg: format!("selects no node of the {part} mesh"),
            });
        }
    }
    Ok(())
}

/// Why `--part` cannot take `part`: the crankcase's modes are the engine's, any other name
/// is unknown.
fn unknown_part(part: &str) -> String {
    if part == "crankcase" {
        "takes the liner only (the crankcase is held by the liners and the mounts): its modes \
         come with the engine's, `modes SCENE --assembly`, or on its own from `export-mesh \
         SCENE --part crankcase --out F.bdf` (a deck with its material and sets) then `modes \
         --mesh F.bdf --fix SET`"
            .to_string()
    } else {
        format!("unknown; --part takes: {}", PARTS.join(", "))
    }
}

/// Resolves a [`ModelInput`] to a checked mesh and material. `extra_fix` adds sets to fix.
pub fn load_part(input: &ModelInput, extra_fix: &[String]) -> Result<LoadedPart> {
    // a scene's own limits (`limits.max_memory_gb`), the machine's (with `--set limits.*`) for
    // a bare mesh
    let limits;
    let material_warning;
    let (mesh, file, material, material_source, mut fix, label, shift_hz, guard_modes) = match input
    {
        ModelInput::Scene { scene, part, sets } => {
            let sc = load_scene(scene, sets)?;
            limits = crate::scene::budget::Limits::of(&sc);
            let p = sc.part(part).ok_or_else(|| Error::Argument {
                flag: format!("{}: part '{part}'", scene.display()),
                msg: unknown_part(part),
            })?;
            check_generated(&sc, &p.source, &limits)?;
            let (mut mesh, file, material, src, warning) = read_mesh(
                &p.source,
                p.mesh_unit,
                &format!("{part}.mesh_unit"),
                p.material,
                &format!("{part}.material"),
            )?;
            add_box_sets(&mut mesh, (scene, part), &p.box_sets)?;
            material_warning = warning;
            (
                mesh,
                file,
                material,
                src,
                p.fix.clone(),
                format!("{} / {part}", scene.display()),
                sc.solver.shift_hz,
                sc.solver.guard_modes,
            )
        }
        ModelInput::Mesh {
            mesh,
            unit,
            material,
            fix,
            sets,
        } => {
            limits = mesh_limits(sets)?;
            let (m, file, material, src, warning) = read_bare_mesh(mesh, *unit, *material)?;
            material_warning = warning;
            (
                m,
                file,
                material,
                src,
                fix.clone(),
                mesh.display().to_string(),
                100.0,
                4,
            )
        }
    };
    fix.extend_from_slice(extra_fix);
    let mut mesh = mesh;
    let mut checks = check_and_compact(&mut mesh).map_err(|source| Error::Mesh {
        file: file.clone(),
        source,
    })?;
    checks.warnings.extend(material_warning);
    // the assembly, estimated on the nodes the elements use (unused GRIDs inflated it: 3M of
    // them, 355 GB); the solve is checked once its factor's size is known
    // (`crate::scene::budget::modal_solve`)
    let limits_file = match (&file, input) {
        (Some(f), _) => std::path::PathBuf::from(f),
        (None, ModelInput::Scene { scene, .. }) => scene.clone(),
        (None, ModelInput::Mesh { mesh, .. }) => mesh.clone(),
    };
    if file.is_some() {
        let kinds = mesh.blocks.iter().map(|b| b.kind);
        let est = crate::scene::budget::assembly(3 * mesh.nodes.len(), kinds);
        limits.check_at(&limits_file, &est)?;
    }
    for name in &fix {
        if mesh.node_set(name).is_none() {
            return Err(Error::Argument {
                flag: format!("{label}: group '{name}' to fix"),
                msg: format!("unknown; the mesh has: {}", mesh.set_names().join(", ")),
            });
        }
    }
    Ok(LoadedPart {
        mesh,
        material,
        material_source,
        fix,
        checks,
        label,
        shift_hz,
        guard_modes,
        limits,
        limits_file,
    })
}

/// `e` of the variant with the overrides `extra`, named by them (a sampled run's value is not
/// the range the user gave: the run says which value failed); the base scene's as it is.
/// Loads the variant `extra` of the scene at `path` with the overrides `base` and checks what
/// its runs read before any ROM is built (its simulation and piston: the pressure curve, the
/// hot skirt); a failure names the variant.
fn load_variant(path: &Path, base: &[String], extra: &[String]) -> Result<Scene> {
    let mut sets = base.to_vec();
    sets.extend(extra.iter().cloned());
    let sc = load_scene(path, &sets).map_err(|e| run_named(extra, e))?;
    simulation(&sc).map_err(|e| run_named(extra, e.into()))?;
    crate::piston::setup::piston_of(&sc).map_err(|e| run_named(extra, e.into()))?;
    Ok(sc)
}

/// Checks each of `variants` as [`Variants::prepare`] does and keeps nothing: a sweep's shard
/// refuses a bad value in another shard's runs as the whole sweep would, before its own.
pub fn check_variants_load(
    path: &Path,
    base: &[String],
    variants: impl Iterator<Item = Vec<String>>,
) -> Result<()> {
    for extra in variants {
        load_variant(path, base, &extra)?;
    }
    Ok(())
}

fn run_named(extra: &[String], e: Error) -> Error {
    if extra.is_empty() {
        return e;
    }
    Error::Run {
        name: extra.join(" "),
        source: Box::new(e),
    }
}

/// Refuses, before any ROM is built or any run starts, variants the limits do not allow: a run
/// whose own transient is beyond its scene's limits (as `simulate` refuses it), and a ROM to
/// build (not among `loaded`, the reduction inputs of the ROMs at hand) beyond them
/// ([`crate::reduce::scene_rom::check_build`]). Before, a sweep checked its base scene only
/// and each ROM as it came to it (a second variant's ROM was refused after the first one's
/// build).
fn check_variants(
    (scenes, variants): (&[Scene], &[Vec<String>]),
    descriptions: &[String],
    loaded: &[String],
    cache: &CacheOptions,
) -> Result<()> {
    use crate::scene::budget::{Estimate, Limits};
    let mut total = (0.0_f64, 0.0_f64);
    for (sc, extra) in scenes.iter().zip(variants) {
        if let Some(est) = crate::scene::budget::transient(sc) {
            Limits::of(sc)
                .check(sc, &est)
                .map_err(|e| run_named(extra, e.into()))?;
            total = (total.0 + est.seconds, total.1.max(est.memory));
        }
    }
    // together: in parallel on the machine's cores, against the last scene's limits (a
    // sweep's base design)
    if let (Some(last), true) = (scenes.last(), scenes.len() > 1) {
        // the runs share rayon's threads (RAYON_NUM_THREADS where a scheduler sets it)
        let cores = rayon::current_num_threads().max(1) as f64;
        let est = Estimate {
            what: "the runs together",
            memory: total.1 * cores.min(scenes.len() as f64) + scenes.len() as f64 * 50e3,
            seconds: total.0 / cores,
            keys: "the design (fewer values or runs, or more shards), transient.step_deg or transient.cycles",
            detail: format!("{} runs, {} cores", scenes.len(), cores),
        };
        Limits::of(last).check(last, &est)?;
    }
    let mut seen: Vec<&String> = loaded.iter().collect();
    for (sc, d) in scenes.iter().zip(descriptions) {
        if !seen.contains(&d) {
            crate::reduce::scene_rom::check_build(sc, d, cache)?;
            seen.push(d);
        }
    }
    Ok(())
}

/// Variants of one scene: each a list of `--set` overrides added to the base ones, loaded and
/// checked before any run, with one ROM per distinct reduction input (loaded or built one
/// after the other).
pub struct Variants {
    pub scenes: Vec<Scene>,
    pub roms: Vec<LoadedRom>,
    /// Index into `roms` of each scene's ROM.
    pub rom_of: Vec<usize>,
    /// The reduction input (key description) of each of `roms`.
    keys: Vec<String>,
}

impl Variants {
    /// Loads the variants `variants` of the scene at `path` with the overrides `base`: a bad
    /// value stops here, before any run. `progress` hears the phases of a ROM build.
    pub fn prepare(
        path: &Path,
        base: &[String],
        variants: &[Vec<String>],
        cache: &CacheOptions,
        progress: &dyn Fn(&str),
    ) -> Result<Self> {
        let none = Self {
            scenes: Vec::new(),
            roms: Vec::new(),
            rom_of: Vec::new(),
            keys: Vec::new(),
        };
        none.then(path, base, variants, cache, progress)
    }

    /// Other variants of the same scene on the ROMs loaded so far (a ROM not loaded yet is
    /// loaded or built as in [`Variants::prepare`]; indices into `roms` stay valid).
    pub fn then(
        mut self,
        path: &Path,
        base: &[String],
        variants: &[Vec<String>],
        cache: &CacheOptions,
        progress: &dyn Fn(&str),
    ) -> Result<Self> {
        let scenes: Vec<Scene> = variants
            .iter()
            .map(|extra| load_variant(path, base, extra))
            .collect::<Result<_>>()?;
        let descriptions: Vec<String> = scenes
            .iter()
            .map(key_description)
            .collect::<std::result::Result<_, _>>()?;
        check_variants((&scenes, variants), &descriptions, &self.keys, cache)?;
        let mut rom_of = Vec::with_capacity(scenes.len());
        for (sc, k) in scenes.iter().zip(descriptions) {
            let idx = match self.keys.iter().position(|x| *x == k) {
                Some(i) => i,
                None => {
                    self.roms.push(get_rom(sc, cache, progress)?);
                    self.keys.push(k);
                    self.roms.len() - 1
                }
            };
            rom_of.push(idx);
        }
        self.scenes = scenes;
        self.rom_of = rom_of;
        Ok(self)
    }

    /// Runs every variant's engine cycles in parallel (`labels[k]` names variant k in a
    /// failure; the first variant maps the liners' wet surfaces when `map_first`); `done()`
    /// is called after each run. Returns the results with each run's wall time \[s\], in the
    /// variants' order.
    pub fn run(
        &self,
        labels: &[String],
        map_first: bool,
        done: impl Fn() + Sync,
    ) -> Result<Vec<(CycleResult, f64)>> {
        // every variant's mode cut-off checked before any run starts
        for (sc, &ri) in self.scenes.iter().zip(&self.rom_of) {
            crate::transient::engine::check_mode_cutoff(sc, simulation(sc)?, &self.roms[ri].rom)?;
        }
        self.scenes
            .par_iter()
            .zip(self.rom_of.par_iter())
            .zip(labels.par_iter())
            .enumerate()
            .map(|(k, ((sc, &ri), name))| {
                let t = Instant::now();
                let piston = piston_of(sc)?;
                let sim = simulation(sc)?;
                let rom = &self.roms[ri].rom;
                let mut settings = settings_of(sim, sc.rom.band_hz);
                settings.surface_maps = map_first && k == 0;
                let res = run_cycle(sc, rom, &piston, settings, |_, _| {}).map_err(|source| {
                    Error::Run {
                        name: name.clone(),
                        source: Box::new(Error::Transient {
                            path: sc.path.clone(),
                            source,
                        }),
                    }
                })?;
                done();
                Ok((res, t.elapsed().as_secs_f64()))
            })
            .collect()
    }
}

/// Ranges of the report's sweeps (the scene's own value is added when outside).
pub const CLEARANCE_RANGE_UM: (f64, f64) = (40.0, 120.0);
pub const PIN_OFFSET_RANGE_MM: (f64, f64) = (-1.0, 1.0);

/// Runs of each report sweep, the scene's own included when it lies in the range: the ends and
/// the middle of the range first, the rest placed where the maximum of the engine's largest
/// mean slap force or peak acceleration can lie ([`crate::analysis::refine`], as
/// `sweep --refine`), two at a time (one per sweep).
pub const REPORT_SWEEP_RUNS: usize = 9;

/// The transients behind a design-review report of a scene.
pub struct ReportRuns {
    /// The scene's own run, on `rom`.
    pub base: CycleResult,
    /// The whole-run step check: the scene's run repeated at half its step
    /// ([`crate::transient::engine::run_half_step`]), and its wall time \[s\].
    pub half_step: CycleResult,
    pub half_step_seconds: f64,
    pub rom: LoadedRom,
    /// The clearance \[um\] and pin-offset \[mm\] sweeps, the scene's run included, ascending.
    pub clearance: Vec<SweepPoint>,
    pub pin_offset: Vec<SweepPoint>,
    /// Where each sweep's largest engine-wide mean slap force and peak acceleration lie.
    pub clearance_maximum: BTreeMap<&'static str, Maximum>,
    pub pin_offset_maximum: BTreeMap<&'static str, Maximum>,
    /// Speed against error of the fast path on the reference window.
    pub tradeoff: Vec<TradeoffPoint>,
    pub evaluation: Evaluation,
    /// The scene's run mapped over every liner's wet outer surface (empty when the liner mesh
    /// has no `coolant_wetted` set).
    pub maps: Vec<crate::cavitation::maps::LinerMap>,
    /// The scene and its sweeps under another skirt model, when the scene asks
    /// (`report.compare_lubrication`).
    pub skirts: Option<crate::report::comparison::SkirtComparison>,
}

/// What a report run varies.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Swept {
    Scene,
    Clearance(f64),
    PinOffset(f64),
}

impl Swept {
    /// The `--set` overrides of the run.
    fn sets(self) -> Vec<String> {
        match self {
            Swept::Scene => Vec::new(),
            Swept::Clearance(v) => vec![format!("piston.clearance_um={v}")],
            Swept::PinOffset(v) => vec![format!("piston.pin_offset_mm={v}")],
        }
    }
}

/// The whole-run step check of `base`, a run of `scene` on `rom`: its cycles repeated at half
/// the step it was made at ([`run_half_step`]), with the wall time \[s\]; `on_step(k, n)` hears
/// the steps.
pub fn half_step_check(
    scene: &Scene,
    rom: &EngineRom,
    piston: &Piston,
    base: &CycleResult,
    on_step: impl FnMut(usize, usize) + Send,
) -> Result<(CycleResult, f64)> {
    let t = Instant::now();
    let step_deg = base.stats.dt_s * scene.engine.speed_rpm * 6.0;
    let settings = settings_of(simulation(scene)?, scene.rom.band_hz);
    let half =
        run_half_step(scene, rom, piston, settings, step_deg, on_step).map_err(|source| {
            Error::Transient {
                path: scene.path.clone(),
                source,
            }
        })?;
    Ok((half, t.elapsed().as_secs_f64()))
}

/// The quantities the report's sweeps refine on: the engine's largest mean slap force and its
/// largest mean peak negative acceleration, each with its standard error (as `sweep --refine`).
fn refined_quantities(r: &CycleResult) -> Vec<(f64, f64)> {
    let slap = r
        .peaks
        .iter()
        .map(|c| (c.slap_force.value, c.slap_force.se))
        .fold((f64::MIN, 0.0), |m, x| if x.0 > m.0 { x } else { m });
    let p = SweepPoint::of(0.0, r);
    vec![slap, (p.largest_m_s2, p.largest_se_m_s2)]
}

/// Names of [`refined_quantities`] in the report's `*_maximum`.
const REFINED: [&str; 2] = ["peak_slap_force_n", "peak_negative_m_s2"];

/// One report sweep as it grows: its points (the scene's own run first) and the samples the
/// refinement places its next runs from.
struct ReportSweep {
    range: (f64, f64),
    points: Vec<SweepPoint>,
    samples: Vec<Sample>,
    round: usize,
}

impl ReportSweep {
    fn new(range: (f64, f64), own: f64, base: &CycleResult) -> Self {
        let mut s = ReportSweep {
            range,
            points: vec![SweepPoint::of(own, base)],
            samples: Vec::new(),
            round: 0,
        };
        if own >= range.0 && own <= range.1 {
            s.samples.push(Sample {
                x: own,
                y: refined_quantities(base),
            });
        }
        s
    }

    /// Adds a what-if run at `x` with its change against the scene's own run.
    fn add(&mut self, x: f64, r: &CycleResult) {
        let mut p = SweepPoint::of(x, r);
        p.set_change(&self.points[0]);
        self.points.push(p);
        self.samples.push(Sample {
            x,
            y: refined_quantities(r),
        });
    }

    /// The next value to run, while the sweep has fewer than [`REPORT_SWEEP_RUNS`] runs.
    fn next(&mut self) -> Option<f64> {
        if self.samples.len() >= REPORT_SWEEP_RUNS {
            return None;
        }
        next_unsampled(
            &self.samples,
            &[],
            &mut self.round,
            self.range,
            REPORT_SWEEP_RUNS,
        )
    }

    /// The points by value, and the located maxima.
    fn finish(mut self) -> (Vec<SweepPoint>, BTreeMap<&'static str, Maximum>) {
        self.points.sort_by(|a, b| a.value.total_cmp(&b.value));
        let maxima = REFINED
            .iter()
            .enumerate()
            .filter_map(|(q, name)| located(&self.samples, q).map(|m| (*name, m)))
            .collect();
        (self.points, maxima)
    }
}

/// Each report job's overrides and its label (the scene's path for the scene itself).
fn job_labels(scene: &Scene, jobs: &[Swept]) -> (Vec<Vec<String>>, Vec<String>) {
    let extra: Vec<Vec<String>> = jobs.iter().map(|j| j.sets()).collect();
    let labels = extra
        .iter()
        .map(|e| match e.is_empty() {
            true => scene.path.display().to_string(),
            false => e.join(" "),
        })
        .collect();
    (extra, labels)
}

/// Adds a finished run to its sweep (clearance: 0, pin offset: 1).
fn add_run(sweeps: &mut [ReportSweep; 2], job: &Swept, r: &CycleResult) {
    match *job {
        Swept::Clearance(v) => sweeps[0].add(v, r),
        Swept::PinOffset(v) => sweeps[1].add(v, r),
        Swept::Scene => {}
    }
}

/// The sweeps' further runs, placed adaptively ([`ReportSweep::next`]) one per sweep at a
/// time on the variants' ROMs, until neither sweep asks for another.
fn place_sweep_runs(
    mut variants: Variants,
    sweeps: &mut [ReportSweep; 2],
    scene: &Scene,
    (path, sets): (&Path, &[String]),
    cache: &CacheOptions,
) -> Result<Variants> {
    loop {
        let batch: Vec<Swept> = [
            sweeps[0].next().map(Swept::Clearance),
            sweeps[1].next().map(Swept::PinOffset),
        ]
        .into_iter()
        .flatten()
        .collect();
        if batch.is_empty() {
            return Ok(variants);
        }
        let (extra, names) = job_labels(scene, &batch);
        variants = variants.then(path, sets, &extra, cache, &|_| {})?;
        for (job, (r, _)) in batch.iter().zip(variants.run(&names, false, || {})?) {
            add_run(sweeps, job, &r);
        }
    }
}

/// Runs the report's transients of `scene` (loaded from `path` with `sets`): the scene and the
/// first points of its clearance sweep over [`CLEARANCE_RANGE_UM`] and pin-offset sweep over
/// [`PIN_OFFSET_RANGE_MM`] (the ends and the middle; the scene's own values not run twice) in
/// parallel on shared ROMs, then each sweep's further runs placed adaptively, one per sweep at
/// a time, up to [`REPORT_SWEEP_RUNS`]; the speed-against-error windows, and the risk
/// evaluation of the scene's run. `phase` hears what is being done.
pub fn report_runs(
    path: &Path,
    sets: &[String],
    scene: &Scene,
    cache: &CacheOptions,
    phase: &dyn Fn(&str),
) -> Result<ReportRuns> {
    let sim = simulation(scene)?;
    let cur_c = sim.piston.skirt.clearance * 1e6;
    let cur_o = sim.piston.pin_offset * 1e3;
    let first = |(lo, hi): (f64, f64), own: f64| -> Vec<f64> {
        initial(lo, hi, REPORT_SWEEP_RUNS)
            .into_iter()
            .filter(|&v| (v - own).abs() > 1e-9)
            .collect()
    };
    let mut jobs = vec![Swept::Scene];
    jobs.extend(
        first(CLEARANCE_RANGE_UM, cur_c)
            .into_iter()
            .map(Swept::Clearance),
    );
    jobs.extend(
        first(PIN_OFFSET_RANGE_MM, cur_o)
            .into_iter()
            .map(Swept::PinOffset),
    );
    phase("engine ROM");
    let (extra, names) = job_labels(scene, &jobs);
    let mut variants = Variants::prepare(path, sets, &extra, cache, phase)?;
    let scene_rom = variants.rom_of[0];
    maps::check_maps(scene, &variants.roms[scene_rom].rom)?;
    phase("transients: the scene, clearance and pin-offset sweeps");
    let mut results = variants
        .run(&names, true, || {})?
        .into_iter()
        .map(|(r, _)| r);
    let base = results.next().expect("the scene's run");
    let mut sweeps = [
        ReportSweep::new(CLEARANCE_RANGE_UM, cur_c, &base),
        ReportSweep::new(PIN_OFFSET_RANGE_MM, cur_o, &base),
    ];
    for (job, r) in jobs.iter().skip(1).zip(results) {
        add_run(&mut sweeps, job, &r);
    }
    phase("sweeps: runs placed where the maxima can lie");
    variants = place_sweep_runs(variants, &mut sweeps, scene, (path, sets), cache)?;
    let [clearance, pin_offset] = sweeps;
    let (clearance, clearance_maximum) = clearance.finish();
    let (pin_offset, pin_offset_maximum) = pin_offset.finish();
    let evaluation = evaluate_scene(scene, &variants.roms[scene_rom].rom, &base)?;
    let mut skirts = None;
    if let Some(other) = compare::checked_request(scene)? {
        phase("the scene and its sweeps with the other skirt model (report.compare_lubrication)");
        let side = compare::SceneSide {
            base: &base,
            evaluation: &evaluation,
            clearance: &clearance,
            pin_offset: &pin_offset,
        };
        let (v, c) = compare::compare_skirts(variants, scene, (path, sets), cache, other, &side)?;
        variants = v;
        skirts = Some(c);
    }
    let Variants { mut roms, .. } = variants;
    let rom = roms.swap_remove(scene_rom);
    let piston = piston_of(scene)?;
    let settings = settings_of(sim, scene.rom.band_hz);
    // the speed-against-error windows and the whole-run step check side by side
    phase("speed against error (window runs) and whole-run step check (half the step)");
    let (tradeoff, check) = rayon::join(
        || crate::transient::verify::tradeoff(scene, &rom.rom, &piston, &settings),
        || half_step_check(scene, &rom.rom, &piston, &base, |_, _| {}),
    );
    let tradeoff = tradeoff?;
    let (half_step, half_step_seconds) = check?;
    let maps = maps::maps_of(scene, &base)?;
    Ok(ReportRuns {
        maps,
        base,
        half_step,
        half_step_seconds,
        rom,
        clearance,
        pin_offset,
        clearance_maximum,
        pin_offset_maximum,
        tradeoff,
        evaluation,
        skirts,
    })
}
