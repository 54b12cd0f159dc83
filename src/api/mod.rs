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
pub mod export;
pub mod full_modes;
pub mod full_order;
pub mod maps;
pub mod modes;
pub mod progress;
pub mod rom;
pub mod rom_tradeoff;
pub mod simulate;
pub mod summary;
pub mod sweep;

pub use crate::cavitation::evaluate::{evaluate, Evaluation};
pub use crate::error::{Error, Result};
use crate::fem::element::check_mesh as check_and_compact;
use crate::fem::material::Elastic;
use crate::mesh::checks::CheckReport;
use crate::mesh::{liner, Mesh};
pub use crate::piston::setup::{piston_of, simulation};
pub use crate::piston::Piston;
pub use crate::reduce::rom::EngineRom;
use crate::reduce::scene_rom::key_description;
pub use crate::reduce::scene_rom::{build_rom, get_rom, CacheOptions, LoadedRom};
pub use crate::report::figures::SweepPoint;
pub use crate::report::records::{CylinderReport, PointPeaks, SimulateReport};
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
        crate::scene::SceneError::Field {
            path: path.to_path_buf(),
            key: "cavitation".into(),
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
    },
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
}

/// A part's mesh: generated, or a file read in `unit`, with its material resolved.
fn read_mesh(
    source: &MeshSource,
    unit: crate::mesh::MeshUnit,
    unit_key: &str,
    given: Option<Elastic>,
    material_key: &str,
) -> Result<(
    Mesh,
    Option<String>,
    Elastic,
    crate::mesh::import::MaterialSource,
)> {
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
            ))
        }
        MeshSource::File(p) => {
            let mut mesh = import::read_si(p, unit, unit_key)
                .map_err(crate::reduce::scene_rom::SceneRomError::from)?;
            let (m, src) = import::resolve_material(&mut mesh, given, p, material_key)
                .map_err(crate::reduce::scene_rom::SceneRomError::from)?;
            Ok((mesh, Some(p.display().to_string()), m, src))
        }
    }
}

/// Resolves a [`ModelInput`] to a checked mesh and material. `extra_fix` adds sets to fix.
pub fn load_part(input: &ModelInput, extra_fix: &[String]) -> Result<LoadedPart> {
    let (mesh, file, material, material_source, mut fix, label, shift_hz, guard_modes) = match input
    {
        ModelInput::Scene { scene, part, sets } => {
            let sc = load_scene(scene, sets)?;
            let p = sc.part(part).ok_or_else(|| Error::Argument {
                flag: format!("{}: part '{part}'", scene.display()),
                msg: format!("unknown; the scene has: {}", PARTS.join(", ")),
            })?;
            // a generated mesh is sized before it is made (`liner.mesh.radial = 100000` ran
            // for minutes at 6-12 GB, and aborted under an address-space cap)
            if let MeshSource::Liner { geometry, meshing } = &p.source {
                let dofs = crate::scene::budget::liner_dofs(geometry, meshing);
                let mut est =
                    crate::scene::budget::fe_model(dofs.min(1e18) as usize, "the modal solve");
                est.keys = "liner.mesh (radial, radial_flange, circumferential, axial_size_mm)";
                crate::scene::budget::Limits::of(&sc).check(&sc, &est)?;
            }
            let (mut mesh, file, material, src) = read_mesh(
                &p.source,
                p.mesh_unit,
                &format!("{part}.mesh_unit"),
                p.material,
                &format!("{part}.material"),
            )?;
            for (name, b) in &p.box_sets {
                crate::mesh::find::box_set(&mut mesh, part, name, b);
            }
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
        } => {
            if let Some(m) = material {
                m.validate().map_err(|m| Error::Argument {
                    flag: "--youngs/--poisson/--density".into(),
                    msg: m.to_string(),
                })?;
            }
            let (m, file, material, src) = read_mesh(
                &MeshSource::File(mesh.clone()),
                *unit,
                "--unit",
                *material,
                "--youngs/--poisson/--density",
            )?;
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
    let checks = check_and_compact(&mut mesh).map_err(|source| Error::Mesh {
        file: file.clone(),
        source,
    })?;
    // estimated on the nodes the elements use (unused GRIDs inflated it: 3M of them, 355 GB)
    if let Some(f) = &file {
        let est = crate::scene::budget::fe_model(3 * mesh.nodes.len(), "the modal solve");
        crate::scene::budget::Limits::machine().check_at(std::path::Path::new(f), &est)?;
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
    })
}

/// Variants of one scene: each a list of `--set` overrides added to the base ones, loaded and
/// checked before any run, with one ROM per distinct reduction input (loaded or built one
/// after the other).
pub struct Variants {
    pub scenes: Vec<Scene>,
    pub roms: Vec<LoadedRom>,
    /// Index into `roms` of each scene's ROM.
    pub rom_of: Vec<usize>,
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
        let scenes: Vec<Scene> = variants
            .iter()
            .map(|extra| {
                let mut sets = base.to_vec();
                sets.extend(extra.iter().cloned());
                let sc = load_scene(path, &sets)?;
                simulation(&sc)?;
                Ok(sc)
            })
            .collect::<Result<_>>()?;
        let mut roms: Vec<LoadedRom> = Vec::new();
        let mut rom_keys: BTreeMap<String, usize> = BTreeMap::new();
        let mut rom_of = Vec::with_capacity(scenes.len());
        for sc in &scenes {
            let k = key_description(sc)?;
            let idx = match rom_keys.get(&k) {
                Some(&i) => i,
                None => {
                    roms.push(get_rom(sc, cache, progress)?);
                    rom_keys.insert(k, roms.len() - 1);
                    roms.len() - 1
                }
            };
            rom_of.push(idx);
        }
        Ok(Self {
            scenes,
            roms,
            rom_of,
        })
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

/// Values of the report's sweeps (the scene's own value is added when missing).
pub const CLEARANCES_UM: [f64; 3] = [40.0, 80.0, 120.0];
pub const PIN_OFFSETS_MM: [f64; 3] = [-1.0, 0.0, 1.0];

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
    /// Speed against error of the fast path on the reference window.
    pub tradeoff: Vec<TradeoffPoint>,
    pub evaluation: Evaluation,
    /// The scene's run mapped over every liner's wet outer surface (empty when the liner mesh
    /// has no `coolant_wetted` set).
    pub maps: Vec<crate::cavitation::maps::LinerMap>,
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
    on_step: impl FnMut(usize, usize),
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

/// Runs the report's transients of `scene` (loaded from `path` with `sets`): the scene, its
/// clearance sweep over [`CLEARANCES_UM`] and pin-offset sweep over [`PIN_OFFSETS_MM`] (the
/// scene's own values not run twice) in parallel on shared ROMs, the speed-against-error
/// windows, and the risk evaluation of the scene's run. `phase` hears what is being done.
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
    let mut jobs = vec![Swept::Scene];
    jobs.extend(
        CLEARANCES_UM
            .iter()
            .filter(|&&c| (c - cur_c).abs() > 1e-9)
            .map(|&c| Swept::Clearance(c)),
    );
    jobs.extend(
        PIN_OFFSETS_MM
            .iter()
            .filter(|&&o| (o - cur_o).abs() > 1e-9)
            .map(|&o| Swept::PinOffset(o)),
    );
    let extra: Vec<Vec<String>> = jobs.iter().map(|j| j.sets()).collect();
    let labels: Vec<String> = extra
        .iter()
        .map(|e| match e.is_empty() {
            true => scene.path.display().to_string(),
            false => e.join(" "),
        })
        .collect();
    phase("engine ROM");
    let variants = Variants::prepare(path, sets, &extra, cache, phase)?;
    maps::check_maps(scene, &variants.roms[variants.rom_of[0]].rom)?;
    phase("transients: the scene, clearance and pin-offset sweeps");
    let mut results = variants
        .run(&labels, true, || {})?
        .into_iter()
        .map(|(r, _)| r);
    let base = results.next().expect("the scene's run");
    let mut clearance = vec![SweepPoint::of(cur_c, &base)];
    let mut pin_offset = vec![SweepPoint::of(cur_o, &base)];
    // each what-if with its change against the scene's own run
    let own = SweepPoint::of(cur_c, &base);
    let changed = |v: f64, r: &CycleResult| {
        let mut p = SweepPoint::of(v, r);
        p.set_change(&own);
        p
    };
    for (job, r) in jobs.iter().skip(1).zip(results) {
        match *job {
            Swept::Clearance(v) => clearance.push(changed(v, &r)),
            Swept::PinOffset(v) => pin_offset.push(changed(v, &r)),
            Swept::Scene => {}
        }
    }
    clearance.sort_by(|a, b| a.value.total_cmp(&b.value));
    pin_offset.sort_by(|a, b| a.value.total_cmp(&b.value));
    let Variants {
        mut roms, rom_of, ..
    } = variants;
    let rom = roms.swap_remove(rom_of[0]);
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
    let evaluation = evaluate_scene(scene, &rom.rom, &base)?;
    let maps = maps::maps_of(scene, &base)?;
    Ok(ReportRuns {
        maps,
        base,
        half_step,
        half_step_seconds,
        rom,
        clearance,
        pin_offset,
        tradeoff,
        evaluation,
    })
}
