//! What a scene will cost, estimated before any work starts, and the refusal of work beyond
//! the machine (`[limits]`).
//!
//! The estimates are deliberately simple and calibrated on the default engine (measured on the
//! 2-core, 24 GB development machine; see the constants): they need to be right within a factor
//! of about two, to tell a run that fits from one that cannot (a mistyped `radial = 300`, a
//! step of 1e-4 deg, a material so soft that every mode lies in the band), not to plan a
//! schedule. Every refusal names the estimate, the limit and the keys that drive it.

use super::spec::CrankcaseMeshing;
use super::spec::ElementKind;
use super::spec::{LinerGeometry, LinerMeshing};
use super::{CrankcaseSource, MeshSource, Scene, SceneError};
use crate::text::num;

/// Cycles queued for the liner maps at most (`transient::cycle` surface record).
const QUEUED_CYCLES: usize = 8;

/// Full DOFs of the default engine's ROM build (six liners and the crankcase).
const REF_DOFS: f64 = 367_842.0;
/// Peak memory of that build [bytes] (`/usr/bin/time -v linercav rom models/engine.toml
/// --no-cache`).
const REF_BUILD_BYTES: f64 = 5.0e9;
/// Wall time of that build [s].
const REF_BUILD_SECONDS: f64 = 93.0;
/// Wall time of one transient step per cylinder with 12 slices per side [s] (default engine:
/// 0.25 s per 2880-step cycle with six cylinders, incl. the step-error windows).
const STEP_SECONDS_PER_CYLINDER: f64 = 15e-6;
/// A lubricated skirt's step costs this many times [`STEP_SECONDS_PER_CYLINDER`]: the film's
/// Newton iteration and all cylinders in one contact step (default engine, squeeze, 4 cycles
/// at 1/4 deg: 15.8-17.0 s against the dry estimate's 1.24 s, 13-14 times; the small test
/// engine: 2.4 s against 0.41 s, 6 times; session 62, after the film's derivatives were
/// formed from one matrix per line; 23 and 11 times in session 53). The larger, rounded up.
const FILM_STEP_FACTOR: f64 = 15.0;

/// An estimate of one piece of work.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    /// What is estimated ("the ROM build", "the transient", ...).
    pub what: &'static str,
    /// Peak memory \[bytes\].
    pub memory: f64,
    /// Wall time on this machine \[s\].
    pub seconds: f64,
    /// The keys to change to make it smaller, and the sizes behind the estimate.
    pub keys: &'static str,
    pub detail: String,
}

/// The limits a run must stay within.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// \[bytes\]
    pub memory: f64,
    /// \[s\]
    pub seconds: f64,
    /// Whether the memory limit was given in the scene (else it is the machine's).
    pub memory_from_scene: bool,
    /// What bounds the machine's memory ([`crate::machine::available_memory_from`]).
    pub memory_bound: &'static str,
}

impl Limits {
    /// The machine's limits without a scene (a bare `--mesh`): 80 % of the available memory
    /// (all of it under an address-space limit, the process's own, whose share already
    /// carries its margin: [`crate::machine::address_space_left`]), 24 h.
    pub fn machine() -> Self {
        let (bytes, bound) = crate::machine::available_memory_from();
        Self {
            memory: Self::share(bound) * bytes as f64,
            seconds: 24.0 * 3600.0,
            memory_from_scene: false,
            memory_bound: bound,
        }
    }

    /// The part of the memory available under `bound` that a run may take.
    fn share(bound: &str) -> f64 {
        if bound == crate::machine::ADDRESS_SPACE_BOUND {
            1.0
        } else {
            0.8
        }
    }

    /// `limits.max_memory_gb` or 80 % of the memory available now; `limits.max_hours` or 24 h.
    pub fn of(scene: &Scene) -> Self {
        Self::machine().with(scene.limits.max_memory_gb, scene.limits.max_hours)
    }

    /// These limits with a memory limit of `max_memory_gb` and a time limit of `max_hours`
    /// where given.
    pub fn with(self, max_memory_gb: Option<f64>, max_hours: Option<f64>) -> Self {
        Self {
            memory: max_memory_gb.map_or(self.memory, |gb| gb * 1e9),
            seconds: max_hours.map_or(self.seconds, |h| h * 3600.0),
            memory_from_scene: max_memory_gb.is_some() || self.memory_from_scene,
            memory_bound: self.memory_bound,
        }
    }

    /// Refuses an estimate beyond the limits (exit 2 with the estimate and the keys).
    pub fn check(&self, scene: &Scene, est: &Estimate) -> Result<(), SceneError> {
        self.check_at(&scene.path, est)
    }

    /// As [`Limits::check`], naming `path` (a scene or a mesh file).
    pub fn check_at(&self, path: &std::path::Path, est: &Estimate) -> Result<(), SceneError> {
        let gb = |b: f64| format!("{} GB", num(b / 1e9));
        let hours = |s: f64| format!("{} h", num(s / 3600.0));
        let (over, limit_text) = if est.memory > self.memory {
            (
                format!("needs about {} of memory", gb(est.memory)),
                if self.memory_from_scene {
                    format!("limits.max_memory_gb allows {}", gb(self.memory))
                } else {
                    let share = Self::share(self.memory_bound);
                    let of_it = if share < 1.0 {
                        format!(" ({:.0} % of it is the limit)", 100.0 * share)
                    } else {
                        String::new()
                    };
                    format!(
                        "{} leaves {} available{of_it}",
                        self.memory_bound,
                        gb(self.memory / share)
                    )
                },
            )
        } else if est.seconds > self.seconds {
            (
                format!("would take about {}", hours(est.seconds)),
                format!("limits.max_hours allows {}", hours(self.seconds)),
            )
        } else {
            return Ok(());
        };
        // a limit of the process's address space is a hard one: no key lifts it
        let capped = est.memory > self.memory
            && !self.memory_from_scene
            && self.memory_bound == crate::machine::ADDRESS_SPACE_BOUND;
        let or_else = if capped {
            "or run under a higher address-space limit"
        } else {
            "or raise limits.max_memory_gb / limits.max_hours if the estimate is known to be pessimistic"
        };
        Err(SceneError::TooLarge {
            path: path.to_path_buf(),
            msg: format!(
                "{} {over} ({}), {limit_text}: change {}, {or_else}",
                est.what, est.detail, est.keys
            ),
        })
    }
}

/// Nodes per lattice cell of a structured mesh with many cells: one vertex per cell, plus the
/// edge nodes of the quadratic kinds (three per brick; seven with the face diagonals of the
/// tetrahedra a brick is split into).
fn nodes_per_cell(kind: ElementKind) -> f64 {
    match kind {
        ElementKind::Hex20 => 4.0,
        ElementKind::Tet10 => 7.0,
        ElementKind::Hex8 | ElementKind::Tet4 => 1.0,
    }
}

/// Axial element levels of a length `l` at size `h` plus the exact planes (`extra`).
fn levels(l: f64, h: f64, extra: usize) -> f64 {
    (l / h).ceil() + extra as f64
}

/// Axial cells of a generated liner: (the tube's, the flange's), from its planes
/// ([`LinerGeometry::axial_planes`]) each gap cut into ceil(gap / h) cells, as the mesh is.
fn liner_axial_cells(g: &LinerGeometry, m: &LinerMeshing) -> (f64, f64) {
    let z_flange = g.length - g.flange_height;
    let planes = g.axial_planes();
    let cells = |w: &[f64]| (((w[1] - w[0]) / m.axial_size) - 1e-9).ceil().max(1.0);
    let all: f64 = planes.windows(2).map(cells).sum();
    let flange: f64 = planes
        .windows(2)
        .filter(|w| w[0] >= z_flange - 1e-9)
        .map(cells)
        .sum();
    (all, flange)
}

/// Full DOFs of one generated liner: 3 per node of its lattice (`mesh::liner`), n_c cells
/// around, the wall's n_r layers over all n_z axial cells and the flange's n_f over its n_zf:
/// corners n_c ((n_r + 1)(n_z + 1) + n_f (n_zf + 1)), and for hex20 a node on every edge:
/// as many around as corners, n_c (n_r (n_z + 1) + n_f (n_zf + 1)) radial and
/// n_c ((n_r + 1) n_z + n_f n_zf) axial. Tetrahedral lattices: 1 (tet4) or 7 (tet10) per cell.
pub fn liner_dofs(g: &LinerGeometry, m: &LinerMeshing) -> f64 {
    let (nz, nzf) = liner_axial_cells(g, m);
    let nr = m.radial as f64;
    let nf = if g.flange_outer_diameter > g.outer_diameter {
        m.radial_flange.max(1) as f64
    } else {
        0.0
    };
    let nc = m.circumferential as f64;
    let corners = nc * ((nr + 1.0) * (nz + 1.0) + nf * (nzf + 1.0));
    let nodes = match m.kind {
        ElementKind::Hex8 => corners,
        ElementKind::Hex20 => {
            2.0 * corners
                + nc * (nr * (nz + 1.0) + nf * (nzf + 1.0))
                + nc * ((nr + 1.0) * nz + nf * nzf)
        }
        ElementKind::Tet4 | ElementKind::Tet10 => {
            nc * (nr * nz + nf * nzf) * nodes_per_cell(m.kind)
        }
    };
    3.0 * nodes
}

/// Estimated lattice cells of the generated crankcase: per cylinder (1 + wall layers) rings of
/// 4 s elements around the bore over N_z axial levels (bay, jacket and deck).
pub fn crankcase_elements(
    cylinders: usize,
    height: f64,
    points: usize,
    m: &CrankcaseMeshing,
) -> f64 {
    let nz = levels(height, m.axial_size, 2 * points + 6);
    cylinders as f64 * (1 + m.wall_layers) as f64 * 4.0 * m.per_sector as f64 * nz
}

/// Estimated full DOFs of the engine model (`None` when a mesh comes from a file: the file's
/// own counts are checked when it is read).
pub fn engine_dofs(scene: &Scene) -> Option<f64> {
    let MeshSource::Liner { geometry, meshing } = &scene.liner.source else {
        return None;
    };
    let liner = liner_dofs(geometry, meshing) / 3.0;
    let cc = match scene.crankcase.as_ref().map(|c| &c.source) {
        Some(CrankcaseSource::Parametric {
            geometry: cg,
            meshing: cm,
        }) => {
            crankcase_elements(
                cg.cylinders,
                cg.skirt_depth + cg.seat_z,
                geometry.analysis_depths.len(),
                cm,
            ) * nodes_per_cell(cm.kind)
        }
        Some(CrankcaseSource::File(_)) => return None,
        None => 0.0,
    };
    Some(3.0 * (cc + scene.rom.cylinders.len() as f64 * liner))
}

/// What a whole engine's FE model takes whatever its size \[bytes\]: the test engine's full
/// modal solve (`modes --assembly --full`, 29.6k DOFs) peaked at 0.50 GB resident against the
/// 0.17 GB of the power law below, ran out of a 1.5 GB address-space cap it had been let into
/// and aborted under 1.55 GB with a floor of 0.4 GB (it needs about 1.6 GB of address space);
/// 0.6 GB refuses it below 1.77 GB.
const FE_MODEL_FLOOR_BYTES: f64 = 0.6e9;

/// A modal solve or ROM build of a model with `dofs` full DOFs n: memory and time scale as
/// nested-dissection fill, M = M_0 (n / n_0)^{4/3} + `FE_MODEL_FLOOR_BYTES` and
/// t = t_0 (n / n_0)^{3/2}, from the default engine's build (also for a mesh read from a file,
/// sized once read).
pub fn fe_model(dofs: usize, what: &'static str) -> Estimate {
    let r = dofs as f64 / REF_DOFS;
    Estimate {
        what,
        memory: REF_BUILD_BYTES * r.powf(4.0 / 3.0) + FE_MODEL_FLOOR_BYTES,
        seconds: REF_BUILD_SECONDS * r.powf(1.5),
        keys: "the mesh (a coarser one)",
        detail: format!("{} DOFs", num(dofs as f64)),
    }
}

/// The full coupled engine model of `scene` held whole ([`fe_model`] of [`engine_dofs`]):
/// its modal solve (`modes --assembly --full`, `rom-tradeoff`'s reference) or, with `window`,
/// the full-order window of `simulate --full-order`, which holds the factor of K_eff with the
/// contact columns K_eff^-1 B and the ROM beside it: 1.25 times (measured 6.2 GB on the
/// default engine's 352k DOFs, 0.47 GB on the test engine's 29.6k; the window was not sized,
/// and aborted in an allocation under a 1.15 GB cap). `None` for an engine read from files
/// (sized once read).
pub fn full_model(scene: &Scene, what: &'static str, window: bool) -> Option<Estimate> {
    let dofs = engine_dofs(scene)?;
    let mut est = fe_model(dofs.min(1e18) as usize, what);
    if window {
        est.memory *= 1.25;
    }
    est.keys = "liner.mesh.* / crankcase.mesh.* (element counts and sizes)";
    Some(est)
}

/// Stored entries per row of K (both triangles) of a mesh of `kind`, rounded up from measured
/// meshes: 138 for the default liner (hex20), 39 for the 754k-DOF tet4 casting; tet10 and hex8
/// from their node graphs' degrees, with room.
fn entries_per_row(kind: ElementKind) -> f64 {
    match kind {
        ElementKind::Tet4 => 60.0,
        ElementKind::Tet10 => 110.0,
        ElementKind::Hex8 => 90.0,
        ElementKind::Hex20 => 150.0,
    }
}

/// Assembling K and M of a mesh read from a file, checked before the assembly starts: the
/// pattern's rows (8 bytes an entry), the values of K and M (16) and the node graph with the
/// assembler's maps (a third more), at the rows per DOF of the mesh's densest element kind
/// (`entries_per_row`); time at 10 us per DOF (the 754k-DOF tet4 casting: 7-10 s). What the
/// modal solve needs beyond it is checked once the factor's size is known
/// ([`modal_solve`]).
pub fn assembly(dofs: usize, kinds: impl Iterator<Item = ElementKind>) -> Estimate {
    let rows = kinds.map(entries_per_row).fold(0.0, f64::max);
    Estimate {
        what: "assembling the model",
        memory: 24.0 * rows * dofs as f64 * 4.0 / 3.0,
        seconds: 1e-5 * dofs as f64,
        keys: "the mesh (a coarser one)",
        detail: format!("{} DOFs", num(dofs as f64)),
    }
}

/// What one modal solve will hold, known exactly once the symbolic analysis has run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolveSizes {
    pub dofs: usize,
    /// Entries of the factor L.
    pub factor_entries: usize,
    /// The numeric factorisation's scratch \[bytes\].
    pub factor_scratch: usize,
    /// K, M and their pattern \[bytes\], and whether they stay in memory beside the factor
    /// (they wait on disk when the factor is large, `linalg::spill`).
    pub model: usize,
    pub model_resident: bool,
    /// The mass compressed for the products (it stays in memory) \[bytes\].
    pub mass: usize,
    /// The lower triangle of K - sigma M that a factorisation reads \[bytes\].
    pub lower: usize,
    /// n-vectors alive beside the factor at most (the shift check's block, or ARPACK's basis
    /// with the eigenvectors).
    pub columns: usize,
}

/// The modal solve once the factor's size is known (after the symbolic analysis): the factor
/// (8 bytes an entry) with the compressed mass and the model when it stays in memory, beside
/// the larger of the factorisation's own (its scratch and the lower triangle it reads) and
/// the iteration's (n-vectors: the shift check's block, or ARPACK's basis with the
/// eigenvectors), with 20 % for the allocator and the analysis, and 50 MB for the process:
/// M = 1.2 (8 nnz(L) + mass + model + max(scratch + lower, 8 n c)) + 50 MB.
/// Measured: the 754k-DOF casting peaks at 4.66-4.84 GB (estimate 5.51 GB), the default liner
/// (48.7k DOFs) at 0.65-0.70 GB (estimate 0.74 GB). Time: the solves and
/// factorisations read the factor some 150 times, at about 5 GB/s (the casting: 96-115 s
/// for 458M entries).
pub fn modal_solve(s: &SolveSizes) -> Estimate {
    let resident = if s.model_resident { s.model } else { 0 };
    let factorising = s.factor_scratch + s.lower;
    let iterating = 8 * s.dofs * s.columns;
    let bytes = 8 * s.factor_entries + s.mass + resident + factorising.max(iterating);
    Estimate {
        what: "the modal solve",
        memory: 1.2 * bytes as f64 + 50e6,
        seconds: 2.4e-7 * s.factor_entries as f64,
        keys: "the mesh (a coarser one), or --count",
        detail: format!(
            "{} DOFs, {} factor entries",
            num(s.dofs as f64),
            num(s.factor_entries as f64)
        ),
    }
}

/// Memory of the generated meshes per node \[bytes\]: coordinates, connectivity, sets and the
/// compaction's maps (`linercav export-mesh models/engine.toml --part crankcase`: 43 MB peak
/// with 117k nodes in all, 87 MB with 248k at `crankcase.mesh.per_sector = 24`, i.e. about
/// 340 bytes per node), rounded up.
const MESH_BYTES_PER_NODE: f64 = 400.0;

/// Generating a scene's meshes (`None` when a mesh comes from a file: the file's own counts are
/// checked once read): memory from the estimated nodes ([`engine_dofs`] / 3), time at 2 us per
/// node (the same measurement).
pub fn meshes(scene: &Scene) -> Option<Estimate> {
    let nodes = engine_dofs(scene)? / 3.0;
    Some(Estimate {
        what: "generating the meshes",
        memory: MESH_BYTES_PER_NODE * nodes,
        seconds: 2e-6 * nodes,
        keys: "liner.mesh.* / crankcase.mesh.* (element counts and sizes)",
        detail: format!("{} nodes", num(nodes)),
    })
}

/// Factor entries of the default crankcase's interior (75,810 DOFs, hex20, METIS order):
/// 50.9M; at 992k DOFs 1,664M, i.e. growth as n^1.355 (measured with the refined settings of
/// issue 37).
const REF_PART_DOFS: f64 = 75_810.0;
const REF_FACTOR_ENTRIES: f64 = 50.9e6;
const FACTOR_EXPONENT: f64 = 1.355;
/// Bytes per DOF of a part's two assembled models (full and interior: pattern, K and M, about
/// 142 stored entries per row for hex20, 24 bytes each, twice).
const MODEL_BYTES_PER_DOF: f64 = 2.0 * 142.0 * 24.0;
/// Wall time of the default engine's ROM build from an empty cache on the 2-core machine [s]
/// (session 38: the parts one after the other, 80 s; benches/RESULTS.md) and its two parts' DOFs.
const REF_ROM_SECONDS: f64 = 80.0;
const REF_ROM_DOFS: f64 = 75_810.0 + 48_672.0;

/// Peak memory of one part's Craig-Bampton reduction \[bytes\]: its factor (8 bytes an entry,
/// grown from the default crankcase's as n^1.355), its two assembled models, and the basis
/// block of n x `columns` (constraint modes, modes, attachment candidates).
pub fn part_reduction_bytes(dofs: f64, columns: f64) -> f64 {
    8.0 * REF_FACTOR_ENTRIES * (dofs / REF_PART_DOFS).powf(FACTOR_EXPONENT)
        + MODEL_BYTES_PER_DOF * dofs
        + 8.0 * dofs * columns
}

/// How the crankcase is cut for its reduction (`rom.crankcase_components`, `rom.cut_shapes`,
/// `rom.component_cutoff_factor`).
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Split {
    pub components: usize,
    pub cut_shapes: usize,
    /// `rom.component_cutoff_factor`.
    pub cutoff_factor: f64,
    /// `rom.cut_enrichment`.
    pub enrichment: usize,
    /// One task of a component job array (`rom --component`, 0-based: the liner, then the
    /// crankcase's components): only its own reduction is estimated.
    #[serde(skip)]
    pub task: Option<usize>,
}

impl Split {
    pub const ONE_PIECE: Split = Split {
        components: 1,
        cut_shapes: 0,
        cutoff_factor: 1.0,
        enrichment: 0,
        task: None,
    };

    /// The split a scene asks for.
    pub fn of(scene: &Scene) -> Self {
        Split {
            components: scene.rom.crankcase_components,
            cut_shapes: scene.rom.cut_shapes,
            cutoff_factor: scene.rom.component_cutoff_factor,
            enrichment: scene.rom.cut_enrichment,
            task: None,
        }
    }

    /// The split of a scene whose crankcase is cut (none for one piece): what `rom` reports.
    pub fn substructured(scene: &Scene) -> Option<Self> {
        (scene.rom.crankcase_components > 1).then(|| Self::of(scene))
    }
}

/// Fixed-interface modes a liner's basis is counted with (the generated liners keep 6-9 below
/// the default cut-offs).
const LINER_MODES: f64 = 20.0;

/// Columns of a liner's reduction ([`rom_split`]): 2 (2 n_c + n_m + n_l) + n_l for n_c
/// interface columns and n_l loads. Measured (task peaks of `rom --component 1/2`, which hold
/// the engine's meshes too): the default liner, 48,672 DOFs with 156 + 119, 1.06 GB; the small
/// engine's liner at 3 mm, 48,816 DOFs with 108 + 363, 1.16 GB (the 400 columns counted
/// before gave 0.66 and 0.76 GB for them).
pub fn liner_columns(interface_cols: f64, loads: f64) -> f64 {
    2.0 * (2.0 * interface_cols + LINER_MODES + loads) + loads
}

/// Loads of a generated liner's reduction: a contact load at every node of its two bore
/// lines (a node per axial level of the tube, and one between for a quadratic element) and the
/// clamp's (`rom::inputs`); the same count on a liner read from a file is its bore sets' sizes
/// plus one.
pub fn liner_loads(g: &LinerGeometry, m: &LinerMeshing) -> f64 {
    let (nz, _) = liner_axial_cells(g, m);
    let per_line = match m.kind {
        ElementKind::Hex20 | ElementKind::Tet10 => 2.0 * nz + 1.0,
        ElementKind::Hex8 | ElementKind::Tet4 => nz + 1.0,
    };
    2.0 * per_line + 1.0
}

/// The ROM build from its parts' DOFs: their peaks add (conservative: the parts are reduced one
/// after the other; measured, the whole build's peak is the larger part's plus 0.03 GB). The
/// crankcase's basis holds twice its interface columns (constraint modes and their inertia
/// loads) plus modes and loads. A liner's ([`liner_columns`]) holds its basis block
/// [constraint modes | modes | attachment candidates: its `liner_loads` loads and the
/// constraint modes' inertia] twice (the block and its products) and its loads once more.
/// Time grows as (n_c + n_l)^1.5 from the default engine's build.
///
/// With the crankcase of `cylinders` cut as `split` asks
/// (`reduce::substructure`): the crankcase's peak is that of its largest component
/// (ceil(cylinders / components) cylinders' share of its DOFs and interface columns, plus two
/// cuts' shapes, and its modes: 100 columns grown as the cube of its cut-off factor, a solid's
/// mode count) and of the dense assembly of the components (n_A^2, about six matrices of it);
/// time adds over the components. A cut carries at most its own DOFs ([`cut_columns`]), so a
/// `cut_shapes` above them (every cut DOF kept) is not counted.
pub fn rom_split(
    crankcase_dofs: f64,
    (liner_dofs, liner_loads): (f64, f64),
    interface_cols: f64,
    cylinders: usize,
    split: Split,
) -> Estimate {
    let Split {
        components,
        cut_shapes,
        cutoff_factor,
        enrichment,
        task,
    } = split;
    let (cyl, n) = (cylinders.max(1) as f64, components.max(1) as f64);
    let share = (cyl / n).ceil() / cyl;
    let shapes = cut_columns(crankcase_dofs, cut_shapes, enrichment);
    // an enriched split reduces every component twice (the first pass has the slab's shapes)
    let passes = if components > 1 && enrichment > 0 {
        2.0
    } else {
        1.0
    };
    let (cuts, modes) = if components > 1 {
        (2.0 * shapes, 100.0 * cutoff_factor.powi(3))
    } else {
        (0.0, 100.0)
    };
    let piece_dofs = crankcase_dofs * share;
    let piece_cols = interface_cols * share + cuts;
    let piece = part_reduction_bytes(piece_dofs, 2.0 * piece_cols + modes);
    let n_a = if components > 1 {
        2.0 * interface_cols + (n - 1.0) * shapes
    } else {
        0.0
    };
    let cc = piece + 6.0 * 8.0 * n_a * n_a;
    let liner = part_reduction_bytes(liner_dofs, liner_columns(interface_cols / cyl, liner_loads));
    let t = reduction_seconds;
    let split = if components > 1 {
        format!(
            ", in {components} components of about {} DOFs",
            num(piece_dofs.round())
        )
    } else {
        String::new()
    };
    // a component task reduces its component only: the liner, or one crankcase piece; the
    // process holds both meshes and the engine's inputs beside it, measured at 1.4-2.1 times
    // the part's own estimate plus 0.13 GB on the small engine and a 53k-DOF liner (the whole
    // build's sum of both parts hides it), so twice the part plus 0.1 GB, never more than
    // the whole build
    if let Some(task) = task {
        let parts = ((liner, liner_dofs), (piece, piece_dofs), cc + liner);
        return task_estimate(task, parts, (components, cylinders), (passes - 1.0) * n);
    }
    Estimate {
        what: "the ROM build",
        memory: cc + liner,
        seconds: passes * n * t(piece_dofs) + t(liner_dofs),
        // the larger part's remedy first: substructuring bounds the crankcase, not a liner
        keys: if liner > cc {
            "liner.mesh.* (element counts and sizes; the liner is reduced in one piece), rom.crankcase_components (the crankcase cut into up to engine.cylinders components: memory bounded by one), crankcase.mesh.* or rom.interface_harmonics"
        } else {
            "rom.crankcase_components (the crankcase cut into up to engine.cylinders components: memory bounded by one), liner.mesh.* / crankcase.mesh.* (element counts and sizes) or rom.interface_harmonics"
        },
        detail: format!(
            "crankcase {} DOFs{split}, liner {} DOFs, {} interface columns",
            num(crankcase_dofs.round()),
            num(liner_dofs.round()),
            num(interface_cols)
        ),
    }
}

/// Seconds of one part's (or component's) reduction of `dofs` DOFs, scaled from the measured
/// reference as dofs^1.5.
fn reduction_seconds(dofs: f64) -> f64 {
    REF_ROM_SECONDS * (dofs / REF_ROM_DOFS).powf(1.5)
}

/// A component task's estimate (`task` 0 the liner, else a crankcase piece): `parts` the
/// liner's and a piece's bytes and DOFs and the whole build's bytes; `first_passes` the
/// components' first passes it may make (an enriched split without its shapes cached).
fn task_estimate(
    task: usize,
    ((liner, liner_dofs), (piece, piece_dofs), whole): ((f64, f64), (f64, f64), f64),
    (components, cylinders): (usize, usize),
    first_passes: f64,
) -> Estimate {
    let t = reduction_seconds;
    let (part, dofs) = if task == 0 {
        (liner, liner_dofs)
    } else {
        (piece, piece_dofs)
    };
    Estimate {
        what: "the component task",
        memory: (2.0 * part + 0.1e9).min(whole),
        // without the enriched shapes cached, the task makes them: every component's first pass
        seconds: if task == 0 {
            t(dofs)
        } else {
            (first_passes + 1.0) * t(dofs)
        },
        keys: if task == 0 {
            "liner.mesh.* (element counts and sizes)"
        } else if components < cylinders {
            "rom.crankcase_components (more, smaller components) or crankcase.mesh.* (element counts and sizes)"
        } else {
            "crankcase.mesh.* (element counts and sizes; the crankcase is in as many components as it has cylinders)"
        },
        detail: format!(
            "{} of about {} DOFs",
            if task == 0 {
                "the liner"
            } else {
                "a crankcase component"
            },
            num(dofs.round())
        ),
    }
}

/// Columns one cut between components carries. A cut of at most 2 `cut_shapes` + 16 DOFs
/// keeps every one (`reduce::substructure::cut_shapes`), so up to that many; a larger cut
/// carries `cut_shapes` (counted as that bound) and the `enrichment` added to them. The cut's DOFs are not known before the mesh: estimated as
/// 2 n^(2/3) for a part of n DOFs, an estimate, not a bound (a cube's section is 1.44
/// n^(2/3); measured cuts: 939 DOFs at 76k and 15,777 at 2.7M against 3,600 and 39,000 so
/// estimated, but the test engine with a 500 mm skirt holds 3,597 against 4,300).
pub fn cut_columns(part_dofs: f64, cut_shapes: usize, enrichment: usize) -> f64 {
    let kept_whole = 2.0 * cut_shapes as f64 + 16.0;
    let cut = 2.0 * part_dofs.max(0.0).powf(2.0 / 3.0);
    if cut <= kept_whole {
        cut
    } else {
        kept_whole + enrichment as f64
    }
}

/// The ROM build of a scene with generated meshes cut as `split` asks (usually
/// [`Split::of`] the scene), from its parts' estimated DOFs ([`rom_split`]).
pub fn rom_build(scene: &Scene, split: Split) -> Option<Estimate> {
    let (cc, liner) = part_dofs(scene)?;
    let cylinders = scene.crankcase.as_ref().map_or(0, |c| match &c.source {
        CrankcaseSource::Parametric { geometry, .. } => geometry.cylinders,
        CrankcaseSource::File(_) => 0,
    });
    Some(rom_split(
        cc,
        liner,
        (cylinders * interface_columns(scene.rom.harmonics)) as f64,
        cylinders,
        split,
    ))
}

/// Interface columns of one cylinder: (2N + 1) harmonics x 2 profiles x 6 directions (seat
/// radial, tangential, axial; guide the same).
pub fn interface_columns(harmonics: usize) -> usize {
    (2 * harmonics + 1) * 2 * 6
}

/// Estimated DOFs of the generated crankcase, and the DOFs and reduction loads of one
/// generated liner ([`liner_dofs`], [`liner_loads`]; `None` when a mesh comes from a file).
fn part_dofs(scene: &Scene) -> Option<(f64, (f64, f64))> {
    let MeshSource::Liner { geometry, meshing } = &scene.liner.source else {
        return None;
    };
    let liner = (
        liner_dofs(geometry, meshing),
        liner_loads(geometry, meshing),
    );
    let cc = match scene.crankcase.as_ref().map(|c| &c.source) {
        Some(CrankcaseSource::Parametric {
            geometry: cg,
            meshing: cm,
        }) => {
            3.0 * crankcase_elements(
                cg.cylinders,
                cg.skirt_depth + cg.seat_z,
                geometry.analysis_depths.len(),
                cm,
            ) * nodes_per_cell(cm.kind)
        }
        _ => return None,
    };
    Some((cc, liner))
}

/// The transient of `simulate`: steps N = cycles 720 / step (plus the step-error windows),
/// t = N n_cyl t_1 max(1, slices / 12), times `FILM_STEP_FACTOR` for a lubricated skirt;
/// memory per cylinder and step of a cycle, 8 bytes each:
/// the points' two rolling series (up to twice their length while they grow), their spectra's
/// power sums and frequencies, and three cycles of the eight piston series.
pub fn transient(scene: &Scene) -> Option<Estimate> {
    let lubricated = scene.simulation.as_ref()?.piston.oil.is_some();
    transient_as(scene, lubricated)
}

/// [`transient`] with the skirt dry or `lubricated` whatever the scene's (the report's
/// comparison of skirt models).
pub fn transient_as(scene: &Scene, lubricated: bool) -> Option<Estimate> {
    let sim = scene.simulation.as_ref()?;
    let t = &sim.transient;
    let per_cycle = 720.0 / t.step_deg;
    let steps = per_cycle * t.cycles as f64 * 1.2;
    let ncyl = scene.rom.cylinders.len() as f64;
    let slices = sim.piston.skirt.slices as f64;
    let points = scene.liner_geometry.analysis_depths.len() as f64;
    let film = if lubricated { FILM_STEP_FACTOR } else { 1.0 };
    Some(Estimate {
        what: "the transient",
        memory: per_cycle * ncyl * (5.0 * points + 24.0) * 8.0 + ncyl * slices * 2.0 * 1e4,
        seconds: steps * ncyl * STEP_SECONDS_PER_CYLINDER * (slices / 12.0).max(1.0) * film,
        keys: "transient.step_deg, transient.cycles, piston.slices, piston.lubrication",
        detail: format!(
            "{} steps of {} cylinders",
            num(steps.round()),
            ncyl as usize
        ),
    })
}

/// Time of the liner maps per surface node and sample of a mapped cycle [s] (default engine:
/// 7.8 s of CPU for 20 cycles of 6 x 1,968 nodes x 2,880 samples, on the core the transient
/// leaves idle; `benches/liner_maps.sh`).
const MAP_SECONDS_PER_NODE_SAMPLE: f64 = 12e-9;

/// The liner maps of a run (`report`, `simulate --maps`) on a ROM whose cylinders have
/// `surface_nodes` wet-surface nodes each, `coordinates` = modes + contact DOFs: in memory
/// (8 bytes each) the surface rows in four copies per cylinder (the ROM's, the mapper's and the
/// brackets' unweighted and weighted), per cycle the record segment, its second differences,
/// filtered series and one cylinder's coordinates (4 (S + 2 margin) m), and the record
/// segments of the cycles queued for the maps; the time per node and sample of the averaged
/// cycles.
pub fn maps(scene: &Scene, surface_nodes: &[usize], coordinates: usize) -> Option<Estimate> {
    let t = &scene.simulation.as_ref()?.transient;
    let per_cycle = 720.0 / t.step_deg;
    let nodes: f64 = surface_nodes.iter().map(|&n| n as f64).sum();
    let m = coordinates as f64;
    Some(Estimate {
        what: "mapping the liners",
        memory: 8.0 * (4.0 * nodes * m + (4.0 + QUEUED_CYCLES as f64) * 1.1 * per_cycle * m),
        seconds: t.averaged_cycles as f64 * nodes * per_cycle * MAP_SECONDS_PER_NODE_SAMPLE,
        keys: "liner.mesh (the wet surface's nodes), transient.step_deg, transient.averaged_cycles",
        detail: format!(
            "{} wet-surface nodes, {} coordinates, {} samples a cycle",
            num(nodes),
            coordinates,
            num(per_cycle.round())
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Regression baseline of the estimate's calibration (not an independent validation: its
    /// 1.2 and 50 MB were chosen on these two measurements): against the measured peaks
    /// (`/usr/bin/time` maximum resident set, whole process) the estimate must not fall below
    /// a peak (a run that cannot fit would start) nor exceed the lowest by more than 25 %
    /// (runs that fit would be refused). Sizes as `modes -v` analysed them.
    #[test]
    fn regression_the_modal_solve_estimate_brackets_the_measured_peaks() {
        let casting = SolveSizes {
            dofs: 754_194,
            factor_entries: 458_010_558,
            factor_scratch: 485_144_960,
            model: 714_437_960,
            model_resident: false,
            mass: 157_423_200,
            lower: 242_168_352,
            columns: 76,
        };
        let liner = SolveSizes {
            dofs: 48_672,
            factor_entries: 26_436_528,
            factor_scratch: 108_343_936,
            model: 161_632_520,
            model_resident: true,
            mass: 35_831_808,
            lower: 54_137_088,
            columns: 76,
        };
        // (sizes, lowest and highest measured peak [bytes]): the 754k-DOF tet4 casting, 20
        // modes (sessions 56-57); the default liner, 20 modes (session 57)
        for (s, low, high) in [(casting, 4.66e9, 4.84e9), (liner, 0.65e9, 0.70e9)] {
            let est = modal_solve(&s).memory;
            assert!(est >= high && est <= 1.25 * low, "{est} vs {low}-{high}");
        }
    }

    /// Regression: a `cut_shapes` above what a cut holds keeps every cut DOF
    /// (`reduce::substructure::cut_shapes`), so it costs what that exact cut costs. Counting the
    /// number asked for, the small engine in 2 components with `rom.cut_shapes=100000` was
    /// refused for 507 GB (crankcase 14,400 DOFs; its cut has fewer than 1,000).
    #[test]
    fn regression_cut_shapes_beyond_the_cut_are_not_counted() {
        let split = |cut_shapes| Split {
            components: 2,
            cut_shapes,
            cutoff_factor: 1.0,
            enrichment: 0,
            task: None,
        };
        let est = |shapes| rom_split(14_400.0, (9_216.0, 55.0), 216.0, 2, split(shapes)).memory;
        assert_eq!(est(100_000), est(10_000));
        assert!(est(100_000) < 1e9, "{}", est(100_000));
        // below the cut's estimated size the shapes asked for count, up to 2 x + 16 of them
        // (a cut that small is kept whole)
        assert!(est(50) < est(100));
    }

    /// Regression: a liner's reduction was counted with 400 columns whatever its loads; the
    /// small engine's liner at 3 mm (48,816 DOFs, 108 interface columns, 363 loads) was
    /// estimated at 0.76 GB and its build measured at 1.19 GB peak (the liner's task 1.16 GB,
    /// the crankcase's 0.26 GB). With the measured sizes (crankcase 10,080 DOFs) the estimate
    /// now covers the measured peak, and more loads cost more; so does the estimate from the
    /// scene.
    #[test]
    fn regression_a_liners_loads_count_in_its_reduction() {
        let est = |loads| rom_split(10_080.0, (48_816.0, loads), 216.0, 2, Split::ONE_PIECE);
        assert!(est(363.0).memory >= 1.19e9, "{}", est(363.0).memory);
        assert!(est(363.0).memory > est(55.0).memory + 0.3e9);
        assert_eq!(
            liner_columns(108.0, 363.0),
            2.0 * (216.0 + 20.0 + 363.0) + 363.0
        );
        // and from the scene, as a build is refused: the liner's DOFs and loads are counted
        // as its mesh will have them (tests/liner.rs)
        let scene = Scene::load(
            std::path::Path::new("tests/fixtures/engine_small.toml"),
            &["liner.mesh.axial_size_mm=3".to_string()],
        )
        .unwrap();
        let est = rom_build(&scene, Split::of(&scene)).unwrap().memory;
        assert!(est >= 1.19e9, "{est}");
    }

    /// Regression: a ROM build refused for a large liner (357k DOFs) suggested cutting the
    /// crankcase into components first, which leaves the liner's reduction as it was.
    #[test]
    fn regression_the_larger_parts_remedy_comes_first() {
        let liner = rom_split(110_592.0, (357_000.0, 119.0), 936.0, 6, Split::ONE_PIECE);
        assert!(liner.keys.starts_with("liner.mesh"), "{}", liner.keys);
        let crankcase = rom_split(2.88e6, (45_504.0, 119.0), 936.0, 6, Split::ONE_PIECE);
        assert!(
            crankcase.keys.starts_with("rom.crankcase_components"),
            "{}",
            crankcase.keys
        );
    }
}
