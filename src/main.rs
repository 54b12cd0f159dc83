//! linercav command-line front end: parses arguments, calls the library, prints the result and
//! maps errors to exit codes (0 ok, 2 bad input, 1 failure), printing the whole cause chain.

mod cli;

use clap::{Args, Parser, Subcommand};
use linercav::api::{cavitation, export, modes, rom, simulate, sweep, ModelInput};
use linercav::error::Error;
use linercav::scene::spec::Elastic;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// mimalloc instead of the system allocator: the transient's contact step makes a few hundred
/// small allocations per time step, and glibc's malloc/free took ~9 % of a cycle.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// mimalloc keeps freed pages for reuse; the large solves hand them back when they let arrays
/// go before a factorisation (`linercav::machine::release_memory`).
fn release_freed_memory() {
    // SAFETY: mi_collect only frees what mimalloc itself holds unused; any thread may call it.
    unsafe { libmimalloc_sys::mi_collect(true) }
}

/// mimalloc (v3) options `arena_reserve` and `arena_max_object_size` (their places in
/// `mi_option_t`; values in KiB) and their defaults (1 and 2 GiB), by which their places are
/// checked before they are set.
const MI_ARENA_RESERVE: (libmimalloc_sys::mi_option_t, std::os::raw::c_long) = (23, 1 << 20);
const MI_ARENA_MAX_OBJECT_SIZE: (libmimalloc_sys::mi_option_t, std::os::raw::c_long) =
    (45, 2 << 20);

/// Under an address-space limit (`ulimit -v`, `prlimit --as`), blocks of 64 MiB and more come
/// straight from the operating system and go back to it when freed, and arenas are reserved
/// 64 MiB at a time: mimalloc's arenas stay reserved once made (1 GiB at a time, growing), so
/// the address space the default engine's `modes --assembly --full` mapped was 2.9 times its
/// peak resident memory (13.2 against 4.6 GB), and a cap checked against the resident
/// estimate could abort a run in an allocation. Without a limit nothing changes: the limit on
/// resident memory (the machine's, a cgroup's) does not count reserved address space.
///
/// It runs from the ELF constructors (`.init_array`), before the Rust runtime's first
/// allocation: called from `main` it came after mimalloc had reserved its first 1 GiB arena,
/// and a run of the default liner mapped 2.0 GB for 0.6 GB resident.
extern "C" fn fit_allocator_to_address_space() {
    if !linercav::machine::address_space_capped() {
        return;
    }
    // SAFETY: mi_option_get and mi_option_set read and write one option's value; called
    // before any other thread exists.
    unsafe {
        let options = [MI_ARENA_RESERVE, MI_ARENA_MAX_OBJECT_SIZE];
        // another mimalloc, or the options set by the environment: leave them
        if options
            .iter()
            .any(|&(o, default)| libmimalloc_sys::mi_option_get(o) != default)
        {
            return;
        }
        for (o, _) in options {
            libmimalloc_sys::mi_option_set(o, 64 << 10);
        }
    }
}

#[used]
#[link_section = ".init_array"]
static FIT_ALLOCATOR: extern "C" fn() = fit_allocator_to_address_space;

/// Transparent huge pages off for the process (`prctl(PR_SET_THP_DISABLE)`), unless the
/// environment sets mimalloc's own `MIMALLOC_ALLOW_THP`, which then decides (mimalloc does the
/// same `prctl` for `MIMALLOC_ALLOW_THP=0`). The setting passes to the processes linercav
/// starts; one started from it cannot turn huge pages back on.
///
/// mimalloc asks for huge pages on its arenas (`madvise(MADV_HUGEPAGE)`), and a first touch
/// of a huge page that the kernel must first assemble (compaction, or memory a virtual machine's
/// host has taken back) costs 1-2 s per GB on the 2-core machine, against 0.2-0.4 s per GB
/// for small pages; the solves gain little from huge pages (whole-process figures against
/// `MIMALLOC_ALLOW_THP=1`: benches/RESULTS.md, docs/performance.md, session 69).
extern "C" fn small_pages() {
    // SAFETY: getenv reads the environment the C runtime set before the constructors ran
    // (no thread exists yet to change it); PR_SET_THP_DISABLE takes one integer flag and
    // touches no memory of ours (a kernel without it returns an error: the default stays).
    unsafe {
        if !libc::getenv(c"MIMALLOC_ALLOW_THP".as_ptr()).is_null() {
            return;
        }
        libc::prctl(libc::PR_SET_THP_DISABLE, 1, 0, 0, 0);
    }
}

#[used]
#[link_section = ".init_array"]
static SMALL_PAGES: extern "C" fn() = small_pages;

#[derive(Parser)]
#[command(
    name = "linercav",
    version,
    about = "Piston-slap-induced cavitation risk of wet cylinder liners"
)]
struct Cli {
    /// Print the phases of long computations (ROM build, system modes) on stderr.
    #[arg(long, short, global = true)]
    verbose: bool,
    #[command(subcommand)]
    command: Command,
}

/// The model: a scene file with a part, or a bare Gmsh mesh with its material.
#[derive(Args, Clone)]
struct ModelArgs {
    /// Scene file (TOML).
    scene: Option<PathBuf>,
    /// Part of the scene: liner (the default) or crankcase; `modes` takes the liner only (the
    /// crankcase's modes come with the engine's: --assembly).
    #[arg(long)]
    part: Option<String>,
    /// Override any scene field: --set liner.mesh.radial=3 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    sets: Vec<String>,
    /// Mesh file instead of a scene: Gmsh MSH 4.1 (.msh), Nastran bulk data (.bdf, .nas) or
    /// Abaqus input (.inp), by extension.
    #[arg(long, conflicts_with = "scene")]
    mesh: Option<PathBuf>,
    /// Length unit of --mesh: m (SI constants) or mm (mm-t-s: E in MPa, rho in t/mm^3).
    #[arg(long, value_name = "m|mm", default_value = "m", value_parser = ["m", "mm"])]
    unit: String,
    /// Young's modulus [Pa] (with --mesh; optional when the mesh defines its materials, and
    /// then it overrides them, with --poisson and --density; SI whatever --unit).
    #[arg(long, value_name = "PA", allow_negative_numbers = true)]
    youngs: Option<f64>,
    /// Poisson's ratio (with --mesh).
    #[arg(long, value_name = "NU", allow_negative_numbers = true)]
    poisson: Option<f64>,
    /// Density [kg/m^3] (with --mesh).
    #[arg(long, value_name = "KG_M3", allow_negative_numbers = true)]
    density: Option<f64>,
    /// Physical group / node set to clamp (repeatable).
    #[arg(long = "fix", value_name = "GROUP")]
    fix: Vec<String>,
}

impl ModelArgs {
    /// Refuses the material flags of a bare mesh (`--youngs`, `--poisson`, `--density`) with
    /// a scene, whose parts take their materials from the scene (they were ignored); and, with
    /// `unit`, `--unit mm` too (a scene's unit is its own; `export-mesh` writes in `--unit`).
    fn refuse_mesh_flags(&self, unit: bool) -> Result<(), Error> {
        let given = [
            ("--youngs", self.youngs.is_some()),
            ("--poisson", self.poisson.is_some()),
            ("--density", self.density.is_some()),
            ("--unit", unit && self.unit != "m"),
        ];
        match given.iter().find(|g| g.1) {
            Some((flag, _)) => Err(Error::Argument {
                flag: flag.to_string(),
                msg: "applies to --mesh only: a scene's parts take their materials and unit from the scene (set them there, or with --set)".into(),
            }),
            None => Ok(()),
        }
    }

    fn input(&self) -> Result<ModelInput, Error> {
        match (&self.scene, &self.mesh) {
            (Some(scene), None) => {
                self.refuse_mesh_flags(false)?;
                Ok(ModelInput::Scene {
                    scene: scene.clone(),
                    part: self.part.clone().unwrap_or_else(|| "liner".into()),
                    sets: self.sets.clone(),
                })
            }
            (None, Some(mesh)) => {
                let unit =
                    linercav::mesh::MeshUnit::parse(&self.unit).ok_or_else(|| Error::Argument {
                        flag: "--unit".into(),
                        msg: format!("expected m or mm, got {}", self.unit),
                    })?;
                let material = match (self.youngs, self.poisson, self.density) {
                    (None, None, None) => None,
                    // SI whatever the mesh's unit, as the flags' names say
                    (Some(young), Some(poisson), Some(density)) => Some(Elastic {
                        young,
                        poisson,
                        density,
                    }),
                    _ => {
                        return Err(Error::Argument {
                            flag: "--youngs/--poisson/--density".into(),
                            msg: "give all three, or none to use the mesh's own materials".into(),
                        })
                    }
                };
                Ok(ModelInput::Mesh {
                    mesh: mesh.clone(),
                    unit,
                    material,
                    fix: Vec::new(),
                    sets: self.sets.clone(),
                })
            }
            _ => Err(Error::Argument {
                flag: "model".into(),
                msg: "give a scene file or --mesh FILE.msh".into(),
            }),
        }
    }
}

/// ROM cache options.
#[derive(Args, Clone)]
struct CacheArgs {
    /// Build the ROM without reading or writing the cache.
    #[arg(long)]
    no_cache: bool,
    /// Cache directory (default: the scene's rom.cache_dir).
    #[arg(long, value_name = "DIR")]
    cache_dir: Option<PathBuf>,
}

impl CacheArgs {
    fn options(&self) -> rom::CacheOptions {
        rom::CacheOptions {
            no_cache: self.no_cache,
            dir: self.cache_dir.clone(),
        }
    }
}

#[derive(Subcommand)]
enum Command {
    /// Lowest natural frequencies and modes of a part (ARPACK shift-invert, certified).
    Modes {
        #[command(flatten)]
        model: ModelArgs,
        #[command(flatten)]
        options: ModesOptions,
        #[command(flatten)]
        cache: CacheArgs,
    },
    /// Build or load the engine reduced-order model and describe it.
    Rom {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Override any scene field (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
        /// Print JSON on stdout.
        #[arg(long)]
        json: bool,
        #[command(flatten)]
        cache: CacheArgs,
        /// Reduce only component I of the engine's N into the component cache and stop: one
        /// task of a job array; a later `rom` assembles the engine from the cached components
        /// in seconds. N = 2 (1 liner, 2 crankcase), or 1 + rom.crankcase_components when the
        /// crankcase is substructured (2.. its components). `auto` takes I/N from a Slurm job
        /// array (SLURM_ARRAY_TASK_ID/MIN/MAX) or a Kubernetes Indexed Job
        /// (JOB_COMPLETION_INDEX).
        #[arg(long, value_name = "I/N|auto")]
        component: Option<String>,
    },
    /// What the reduction costs: the ROM built at several cut-off factors against one full
    /// coupled FE solve (frequency error and MAC of the modes below the band, build times);
    /// prints a table, and with --out writes rom_tradeoff.png, .json and .txt.
    RomTradeoff {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Override any scene field (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
        /// Cut-off factors (cut-off = factor x rom.band_hz), each >= 1.
        #[arg(long, value_delimiter = ',', default_value = "1.5,2,2.5,3")]
        factors: Vec<f64>,
        /// Directory for the PNG, JSON and text table.
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
        /// Print JSON on stdout.
        #[arg(long)]
        json: bool,
    },
    /// Mode-shape coefficients: radial thrust-side amplitude of each system mode at every
    /// cylinder's analysis points, normalised per mode.
    Shapes {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Override any scene field (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
        /// Print JSON on stdout.
        #[arg(long)]
        json: bool,
        #[command(flatten)]
        cache: CacheArgs,
    },
    /// Piston-slap transient of the engine on the ROM: peak liner accelerations per cylinder
    /// and analysis point, side and slap forces, time series, solver statistics.
    Simulate(SimulateArgs),
    /// Write K.mtx and M.mtx (Matrix Market, symmetric, constrained DOFs removed).
    ExportMatrices {
        #[command(flatten)]
        model: ModelArgs,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
    },
    /// Design-review report of a scene: slap transient, cavitation verdict, spectra and modal
    /// correlation, clearance and pin-offset sweeps, speed against error (PNGs, summary.md,
    /// summary.json).
    Report {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Override any scene field (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
        /// Output directory.
        #[arg(long, default_value = "reports")]
        out: PathBuf,
        #[command(flatten)]
        cache: CacheArgs,
    },
    /// What-if sweep: the Cartesian product of the varied keys, run in parallel on the cached
    /// ROM; sweep.csv (tidy), sweep.json and a PNG per numeric key in DIR.
    Sweep(SweepArgs),
    /// Merges the parts of a sharded sweep (checked: one study, every run exactly once) into
    /// the outputs of the unsharded sweep.
    SweepMerge {
        /// Part directories (their part-*.json) or part files.
        #[arg(required = true, value_name = "PART_DIR")]
        parts: Vec<PathBuf>,
        /// Output directory.
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// Print JSON on stdout.
        #[arg(long)]
        json: bool,
    },
    /// Coolant properties at a state: vapour pressure, density, speed of sound, Vccv and (with
    /// a gap) the acceleration thresholds.
    Coolant {
        /// Coolant temperature [C].
        #[arg(long, value_name = "T", allow_negative_numbers = true)]
        temp_c: f64,
        /// Static pressure [kPa absolute].
        #[arg(long, value_name = "P", allow_negative_numbers = true)]
        static_kpa: f64,
        /// Ethylene glycol mass fraction.
        #[arg(
            long,
            value_name = "F",
            default_value_t = 0.0,
            allow_negative_numbers = true
        )]
        glycol: f64,
        /// Coolant gap [mm].
        #[arg(long, value_name = "H", allow_negative_numbers = true)]
        gap_mm: Option<f64>,
        /// Print JSON on stdout.
        #[arg(long)]
        json: bool,
    },
    /// Calibrate the acceleration criterion from rig data (CSV: time_s, acceleration_m_s2,
    /// pressure_kpa): events, k_p, onset and high-risk thresholds.
    Calibrate {
        /// Rig data CSV.
        #[arg(long, value_name = "FILE.csv")]
        data: PathBuf,
        /// Coolant gap [mm].
        #[arg(long, value_name = "H", allow_negative_numbers = true)]
        gap_mm: f64,
        /// Static coolant pressure [kPa absolute].
        #[arg(long, value_name = "P", allow_negative_numbers = true)]
        static_kpa: f64,
        /// Coolant temperature [C].
        #[arg(long, value_name = "T", allow_negative_numbers = true)]
        temp_c: f64,
        /// Ethylene glycol mass fraction.
        #[arg(
            long,
            value_name = "FRACTION",
            default_value_t = 0.0,
            allow_negative_numbers = true
        )]
        glycol: f64,
        /// Quiet time that separates events [ms].
        #[arg(long, value_name = "MS", default_value_t = 2.0)]
        quiet_ms: f64,
        /// Print JSON on stdout (loadable as cavitation.calibration_file in a scene).
        #[arg(long)]
        json: bool,
        /// Draw the peak scatter with the fit and Ca against |a| into this PNG.
        #[arg(long, value_name = "FILE")]
        png: Option<PathBuf>,
    },
    /// Write a part's mesh (--part liner|crankcase of a scene, or --mesh) by the output's
    /// extension: .msh (Gmsh MSH 4.1), .bdf/.nas (Nastran bulk data), .inp (Abaqus input), in
    /// --unit (m, or mm with E in MPa and rho in t/mm^3), with its node sets (generated, named
    /// or found from the geometry) and materials.
    ExportMesh {
        #[command(flatten)]
        model: ModelArgs,
        /// Write no node or element sets (a deck as another tool would hold it).
        #[arg(long)]
        no_sets: bool,
        /// Output file.
        #[arg(long)]
        out: PathBuf,
    },
}

/// The options of `simulate`.
/// `sweep`'s arguments.
#[derive(clap::Args)]
struct SweepArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// A varied key and its values: --vary piston.clearance_um=40,80,120 (repeatable; the
    /// runs are the Cartesian grid).
    #[arg(long = "vary", value_name = "KEY=V1,V2,...")]
    vary: Vec<String>,
    /// A random design instead of a grid: Latin hypercube or Monte Carlo with N runs over
    /// the --range keys.
    #[arg(long, value_name = "lhs:N|mc:N")]
    sample: Option<String>,
    /// A sampled key, uniform over [LO, HI] (repeatable; with --sample).
    #[arg(long = "range", value_name = "KEY=LO:HI", allow_hyphen_values = true)]
    ranges: Vec<String>,
    /// Seed of the sample (default 1): the same seed gives the same runs everywhere.
    #[arg(long, value_name = "S")]
    seed: Option<u64>,
    /// Run only shard I of N (1-based) and write its part into --out PART_DIR; without it,
    /// taken from a Slurm job array (SLURM_ARRAY_TASK_ID/MIN/MAX) or a Kubernetes Indexed
    /// Job (JOB_COMPLETION_INDEX with --shards).
    #[arg(long, value_name = "I/N")]
    shard: Option<String>,
    /// Number of shards of a Kubernetes Indexed Job (its completions).
    #[arg(long, value_name = "N")]
    shards: Option<usize>,
    /// One key refined adaptively over [LO, HI] (with --runs): the runs placed where the
    /// largest slap force and peak acceleration can lie and where the response changes
    /// faster than its uncertainty; sweep.json gets each one's located maximum.
    #[arg(long, value_name = "KEY=LO:HI", allow_hyphen_values = true)]
    refine: Option<String>,
    /// Number of runs of --refine (3-1000).
    #[arg(long, value_name = "N")]
    runs: Option<usize>,
    /// Fixed overrides for every run (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    sets: Vec<String>,
    /// Output directory (sweep.csv, sweep.json, PNGs; a sample adds probabilities.csv and
    /// sweep_statistics.png); a shard's part directory. Without it only the summary prints.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Print JSON on stdout.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    cache: CacheArgs,
}

#[derive(clap::Args)]
struct SimulateArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Override any scene field: --set piston.clearance_um=120 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    sets: Vec<String>,
    /// Print JSON on stdout.
    #[arg(long)]
    json: bool,
    /// Write time_series.csv and simulate.json into this directory.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Also run the full-order FE model on a window around firing TDC of the first
    /// cylinder (330-420 deg, both models at the slap sub-step, step_deg / slap_substeps) and
    /// report the ROM's error, its step uncertainty and the speed-up there.
    #[arg(long)]
    full_order: bool,
    /// Also repeat every cycle at half the step (about twice the transient's time) and
    /// report each peak's whole-run step error, which holds what the firing-slap estimate
    /// does not: the coarse step's shift of the cycles' statistics between the slaps.
    #[arg(long)]
    check_step: bool,
    /// Also map the peak negative acceleration over every node of each liner's wet outer
    /// surface: per cylinder the largest mean and where it lies in the output, and with
    /// --out liner_maps.png (unrolled) and liner_maps.vtu (ParaView).
    #[arg(long)]
    maps: bool,
    /// Decide the cylinder ranking: with the whole-run step check, add realisations (the run
    /// repeated with the damping perturbed at 1e-6) until every neighbour pair is separated
    /// or tied within 2 % of the mean peak, or the scene's transient.max_seconds is reached.
    #[arg(long)]
    rank: bool,
    #[command(flatten)]
    cache: CacheArgs,
}

fn run(cli: Cli, started: Instant) -> Result<(), Error> {
    match cli.command {
        Command::Modes {
            model,
            options,
            cache,
        } => modes_command(&model, options, &cache, started)?,
        Command::ExportMatrices { model, out } => export_matrices_command(&model, &out)?,
        Command::Report {
            scene,
            sets,
            out,
            cache,
        } => {
            let r = linercav::api::summary::run(&scene, &sets, &out, &cache.options())?;
            say(&format!(
                "{}report written to {}\n",
                r.to_text(),
                out.display()
            ))?;
        }
        Command::Rom {
            scene,
            sets,
            json,
            cache,
            component,
        } => rom_command(&scene, &sets, json, &cache, component.as_deref(), started)?,
        Command::RomTradeoff {
            scene,
            sets,
            factors,
            out,
            json,
        } => {
            let r = linercav::api::rom_tradeoff::run(&scene, &sets, &factors, out.as_deref())?;
            print_report(json, &r, || r.to_text())?;
        }
        Command::Shapes {
            scene,
            sets,
            json,
            cache,
        } => shapes_command(&scene, &sets, json, &cache)?,
        Command::Simulate(args) => simulate_command(args, started)?,
        Command::Sweep(args) => sweep_command(args, started)?,
        Command::SweepMerge { parts, out, json } => {
            let r = sweep::merge(&parts, &out, started)?;
            print_report(json, &r, || r.to_text())?;
        }
        Command::Coolant {
            temp_c,
            static_kpa,
            glycol,
            gap_mm,
            json,
        } => {
            let r = cavitation::coolant(temp_c, static_kpa, glycol, gap_mm)?;
            print_report(json, &r, || r.to_text())?;
        }
        Command::Calibrate {
            data,
            gap_mm,
            static_kpa,
            temp_c,
            glycol,
            quiet_ms,
            json,
            png,
        } => {
            let req = cavitation::CalibrateRequest {
                data,
                gap_mm,
                static_kpa,
                temp_c,
                glycol,
                quiet_ms,
                png,
            };
            let r = cavitation::calibrate(&req)?;
            print_report(json, &r, || cavitation::calibration_text(&r))?;
        }
        Command::ExportMesh {
            model,
            no_sets,
            out,
        } => export_mesh_command(&model, no_sets, &out)?,
    }
    Ok(())
}

/// `export-matrices`: K.mtx and M.mtx of a part or a mesh.
fn export_matrices_command(model: &ModelArgs, out: &Path) -> Result<(), Error> {
    if model.scene.is_some() {
        model.refuse_mesh_flags(true)?;
    }
    let r = export::export_matrices(&model.input()?, &model.fix, out)?;
    say(&format!(
        "wrote {} and {} ({} DOFs, {} lower-triangle entries)\n",
        r.files[0].display(),
        r.files[1].display(),
        r.dofs,
        r.nnz_lower
    ))
}

/// `export-mesh`: a part's or a mesh's mesh as a deck in `--unit`.
fn export_mesh_command(model: &ModelArgs, no_sets: bool, out: &Path) -> Result<(), Error> {
    if !model.fix.is_empty() {
        return Err(Error::Argument {
            flag: "--fix".into(),
            msg: "does not apply to export-mesh: the mesh is written with its node sets (clamping is a choice of an analysis)".into(),
        });
    }
    let unit = linercav::mesh::MeshUnit::parse(&model.unit).unwrap_or_default();
    let n = export::export_mesh(&model.input()?, out, unit, !no_sets)?;
    say(&format!("wrote {} ({n} nodes)\n", out.display()))
}

/// `sweep`: a designed study of the scene (grid, sample or adaptive refinement), printed (or as
/// JSON) and with `--out` written.
fn sweep_command(args: SweepArgs, started: Instant) -> Result<(), Error> {
    let req = sweep::SweepRequest {
        scene: args.scene,
        sets: args.sets,
        vary: args.vary,
        sample: args.sample,
        ranges: args.ranges,
        seed: args.seed,
        shard: args.shard,
        shards: args.shards,
        out: args.out,
        cache: args.cache.options(),
        refine: args.refine,
        runs: args.runs,
    };
    let r = sweep::run(&req, started)?;
    print_report(args.json, &r, || r.to_text())?;
    Ok(())
}

/// `simulate`: the transient of the scene, printed (or as JSON) and with `--out` written.
fn simulate_command(args: SimulateArgs, started: Instant) -> Result<(), Error> {
    let req = simulate::SimulateRequest {
        scene: args.scene,
        sets: args.sets,
        out: args.out,
        cache: args.cache.options(),
        full_order: args.full_order,
        check_step: args.check_step,
        maps: args.maps,
        rank: args.rank,
    };
    let report = simulate::run(&req, started)?;
    print_report(args.json, &report, || report.to_text())?;
    Ok(())
}

/// `rom`: the engine ROM from the cache or built, described; with `--component` one
/// component's reduction into the component cache.
fn rom_command(
    scene: &std::path::Path,
    sets: &[String],
    json: bool,
    cache: &CacheArgs,
    component: Option<&str>,
    started: Instant,
) -> Result<(), Error> {
    let sc = linercav::api::load_scene(scene, sets)?;
    if let Some(c) = component {
        let done = rom::reduce_component(&sc, &cache.options(), c)?;
        print_report(json, &done, || rom::component_text(&done))?;
        return Ok(());
    }
    let loaded = rom::get_rom_with_progress(&sc, &cache.options())?;
    let mut report = rom::RomReport::new(&loaded);
    report.seconds = started.elapsed().as_secs_f64();
    report.substructured = linercav::scene::budget::Split::substructured(&sc);
    print_report(json, &report, || report.to_text())?;
    Ok(())
}

/// `shapes`: the mode-shape coefficients of the engine ROM's system modes.
fn shapes_command(
    scene: &std::path::Path,
    sets: &[String],
    json: bool,
    cache: &CacheArgs,
) -> Result<(), Error> {
    let sc = linercav::api::load_scene(scene, sets)?;
    let loaded = rom::get_rom_with_progress(&sc, &cache.options())?;
    let report = rom::ShapesReport {
        modes: loaded.rom.shapes(),
        cylinders: loaded.rom.cylinders.iter().map(|c| c.cylinder).collect(),
        cache: loaded.cache,
    };
    print_report(json, &report, || report.to_text())?;
    Ok(())
}

/// Options of the `modes` command besides the model and the cache.
#[derive(Args)]
struct ModesOptions {
    /// Number of modes (rigid-body modes included).
    #[arg(long)]
    count: usize,
    /// Shift frequency f_s of sigma = -(2 pi f_s)^2 [Hz] (default: the scene's, or 100); one so close to zero that rigid-body modes' residuals are round-off against it (below 1e-8 of the model's eigenvalue scale) is moved away from it, with a warning.
    #[arg(long, value_name = "HZ", allow_negative_numbers = true)]
    shift_hz: Option<f64>,
    /// Solve at the shift as given, even far below the wanted modes (by default such a shift
    /// is moved to them, with a warning).
    #[arg(long)]
    keep_shift: bool,
    /// Print JSON on stdout.
    #[arg(long)]
    json: bool,
    /// Write the mode shapes to a VTU file for ParaView.
    #[arg(long, value_name = "FILE.vtu")]
    vtu: Option<PathBuf>,
    /// Coupled engine modes (crankcase + liners) instead of one part.
    #[arg(long)]
    assembly: bool,
    /// With --assembly: the full FE model (the reference).
    #[arg(long, requires = "assembly", conflicts_with = "rom")]
    full: bool,
    /// With --assembly: the engine ROM.
    #[arg(long, requires = "assembly")]
    rom: bool,
}

/// `modes`: a part's certified modes, or the coupled engine's (`--assembly`); a failed Sturm
/// certification exits 1.
fn modes_command(
    model: &ModelArgs,
    o: ModesOptions,
    cache: &CacheArgs,
    started: Instant,
) -> Result<(), Error> {
    let ModesOptions {
        count,
        shift_hz,
        keep_shift,
        json,
        vtu,
        assembly,
        full,
        rom: _,
    } = o;
    if assembly {
        let scene_path = model.scene.clone().ok_or_else(|| Error::Argument {
            flag: "--assembly".into(),
            msg: "needs a scene file".into(),
        })?;
        // the coupled engine has no part to choose or fix, and no shift to keep
        let single = [
            ("--part", model.part.is_some()),
            ("--fix", !model.fix.is_empty()),
            ("--shift-hz", shift_hz.is_some()),
            ("--keep-shift", keep_shift),
        ];
        if let Some((flag, _)) = single.iter().find(|g| g.1) {
            return Err(Error::Argument {
                flag: flag.to_string(),
                msg: "applies to a part's modes, not to --assembly (the coupled engine)".into(),
            });
        }
        model.refuse_mesh_flags(true)?;
        let scene = linercav::api::load_scene(&scene_path, &model.sets)?;
        let report = modes::run_assembly(
            &scene,
            count,
            full,
            vtu.as_deref(),
            &cache.options(),
            started,
        )?;
        print_report(json, &report, || report.to_text())?;
        linercav::eigen::certify::system_verdict(report.sturm_count_ok)?;
        return Ok(());
    }
    if model.scene.is_some() {
        model.refuse_mesh_flags(true)?;
    }
    let req = modes::ModesRequest {
        input: model.input()?,
        count,
        extra_fix: if model.scene.is_some() || model.mesh.is_some() {
            model.fix.clone()
        } else {
            vec![]
        },
        vtu,
        shift_hz,
        keep_shift,
    };
    let report = modes::run(&req, started)?;
    print_report(json, &report, || report.to_text())?;
    // warnings go to standard error, as every command's do (the text and the JSON are the
    // result; the JSON also lists them)
    for w in &report.warnings {
        tell(&format!("warning: {w}\n"));
    }
    linercav::eigen::certify::verdict(
        report.sturm.as_ref(),
        report.max_residual,
        report.m_orthogonality_error,
    )?;
    Ok(())
}

/// Prints a report as JSON (`--json`) or as text ([`say`]).
fn print_report<T: serde::Serialize>(
    json: bool,
    report: &T,
    text: impl FnOnce() -> String,
) -> Result<(), Error> {
    if json {
        say(&(serde_json::to_string_pretty(report).expect("serialisable") + "\n"))
    } else {
        say(&text())
    }
}

/// Writes `text` to standard output. A reader that went away (a closed pipe: `| head`) ends
/// the process as SIGPIPE would, with 141 (128 + 13; the outputs are written by then); any
/// other failure (a full disk) is an error naming standard output (exit 2), not a panic.
fn say(text: &str) -> Result<(), Error> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => std::process::exit(141),
        Err(source) => Err(linercav::files::WriteError {
            path: "standard output".into(),
            source,
        }
        .into()),
    }
}

/// Writes `text` to standard error, best effort: a standard error that cannot be written (a
/// full disk) loses the message but does not end the run or change its exit code.
fn tell(text: &str) {
    use std::io::Write;
    let _ = std::io::stderr().lock().write_all(text.as_bytes());
}

/// OpenBLAS (ARPACK's BLAS) starts its worker threads when the library loads, before `main`,
/// and they spin on `sched_yield` for a while: on a 2-core machine that halves the speed of
/// the single-threaded transient. ARPACK's vector-sized BLAS calls gain nothing from them
/// (rayon and faer do the parallel work), so unless the user chose a thread count, the
/// process re-executes itself once with OPENBLAS_NUM_THREADS=1.
fn single_threaded_blas() {
    use std::os::unix::process::CommandExt;
    if std::env::var_os("OPENBLAS_NUM_THREADS").is_some() {
        return;
    }
    let Ok(exe) = std::env::current_exe() else {
        return;
    };
    // exec only returns on failure; then run on as we are
    let _ = std::process::Command::new(exe)
        .args(std::env::args_os().skip(1))
        .env("OPENBLAS_NUM_THREADS", "1")
        .exec();
}

/// Warnings of the library (`log::warn!`) on stderr, each distinct message once (a sweep loads
/// its scene once per run).
struct StderrLog {
    said: std::sync::Mutex<std::collections::HashSet<String>>,
}

impl log::Log for StderrLog {
    fn enabled(&self, m: &log::Metadata) -> bool {
        m.level() <= log::max_level()
    }
    fn log(&self, r: &log::Record) {
        if !self.enabled(r.metadata()) {
            return;
        }
        let msg = r.args().to_string();
        if r.level() > log::Level::Warn {
            tell(&format!("{msg}\n"));
            return;
        }
        let mut said = self.said.lock().unwrap_or_else(|p| p.into_inner());
        if said.insert(msg.clone()) {
            tell(&format!("warning: {msg}\n"));
        }
    }
    fn flush(&self) {}
}

/// Refuses a `--set` key given twice on the command line (each would replace the last).
fn check_sets() -> Result<(), Error> {
    linercav::scene::overrides::check_repeated(&set_arguments())
        .map_err(linercav::scene::SceneError::from)?;
    Ok(())
}

/// The values of every `--set` on the command line, in order (`--set K=V` and `--set=K=V`).
fn set_arguments() -> Vec<String> {
    // lossy: a path that is not UTF-8 is not a --set value
    let args: Vec<String> = std::env::args_os()
        .map(|a| a.to_string_lossy().into_owned())
        .collect();
    let mut out = Vec::new();
    for (i, a) in args.iter().enumerate() {
        if a == "--set" {
            out.extend(args.get(i + 1).cloned());
        } else if let Some(v) = a.strip_prefix("--set=") {
            out.push(v.to_string());
        }
    }
    out
}

fn main() {
    single_threaded_blas();
    linercav::machine::set_memory_release(release_freed_memory);
    cli::install();
    static LOG: std::sync::OnceLock<StderrLog> = std::sync::OnceLock::new();
    let logger = LOG.get_or_init(|| StderrLog {
        said: Default::default(),
    });
    let started = Instant::now();
    let cli = Cli::parse();
    if log::set_logger(logger).is_ok() {
        log::set_max_level(if cli.verbose {
            log::LevelFilter::Info
        } else {
            log::LevelFilter::Warn
        });
    }
    if let Err(e) = check_sets().and_then(|()| run(cli, started)) {
        let mut said = e.to_string();
        let mut message = format!("error: {said}");
        let mut source = std::error::Error::source(&e);
        while let Some(s) = source {
            // a cause whose text the message already carries is not repeated
            let text = s.to_string();
            if !said.contains(&text) {
                message.push_str(&format!("\n  caused by: {text}"));
                said.push_str(&text);
            }
            source = s.source();
        }
        tell(&(message + "\n"));
        std::process::exit(e.exit_code());
    }
}
