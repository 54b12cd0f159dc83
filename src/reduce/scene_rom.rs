//! The engine ROM of a scene, through the cache: the meshes of the scene's liner and
//! crankcase, the canonical description hashed into the cache key, the build inputs, and the
//! cache lookup with one builder per entry.
//!
//! Cache key: the canonical JSON of everything the reduction depends on (liner and crankcase
//! geometry, meshing or mesh-file contents, materials, fixed sets, clamp force, cut-off,
//! harmonics, modelled cylinders, ROM format). Operating and piston data are not in it, so a
//! what-if run on speed, pressure, clearance or pin offset reuses the ROM.

use super::cache::{self, CacheReadError, Lookup};
use super::rom::{build, EngineRom, RomBuild, RomError, RomInputs, ROM_FORMAT};
use crate::fem::element::check_mesh as check_and_compact;
use crate::fem::surface::SurfaceMass;
use crate::files::WriteError;
use crate::mesh::checks::MeshError;
use crate::mesh::collect::DeckError;
use crate::mesh::find::{self, FoundInterfaces, LinerShape};
use crate::mesh::{crankcase, import, liner, Mesh, MeshUnit};
use crate::scene::budget::{self, Limits};
use crate::scene::spec::Elastic;
use crate::scene::{CrankcaseSource, MeshSource, Scene, SceneError};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Why a scene's ROM could not be had.
#[derive(Debug, thiserror::Error)]
pub enum SceneRomError {
    #[error("{}: the scene has no [crankcase] section; the engine model needs one", path.display())]
    NoCrankcase { path: PathBuf },
    #[error("{}: cannot read mesh file: {source}", path.display())]
    MeshFile {
        path: PathBuf,
        source: crate::files::ReadError,
    },
    #[error(transparent)]
    Msh(#[from] DeckError),
    #[error(transparent)]
    Import(#[from] crate::mesh::import::ImportError),
    #[error("{}: {source}", file.as_deref().unwrap_or("mesh"))]
    Mesh {
        file: Option<String>,
        #[source]
        source: MeshError,
    },
    #[error("{}: cavitation.coolant_mass = \"layer\" needs the liner's wet outer surface as node set '{set}' covering whole element faces{}: {msg}", path.display(), file.as_ref().map(|f| format!(" (a physical group of {f})")).unwrap_or_default())]
    WetSurface {
        path: PathBuf,
        set: String,
        file: Option<String>,
        msg: String,
    },
    #[error("{}: {key}.{name}.box_mm selects no node of the {part} mesh, which spans ({}) mm: a set of no nodes holds or finds nothing", path.display(), extent.iter().map(|v| crate::text::num(v * 1e3)).collect::<Vec<_>>().join(", "))]
    EmptyBoxSet {
        path: PathBuf,
        key: &'static str,
        part: &'static str,
        name: String,
        /// The mesh's bounding box \[m\]: x0, y0, z0, x1, y1, z1.
        extent: Box<[f64; 6]>,
    },
    #[error("{}: crankcase.fix: unknown set '{name}'; the crankcase mesh has: {}", path.display(), have.join(", "))]
    UnknownFixSet {
        path: PathBuf,
        name: String,
        have: Vec<String>,
    },
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Cache(#[from] CacheReadError),
    #[error(transparent)]
    Write(#[from] WriteError),
    #[error(transparent)]
    Rom(#[from] RomError),
    #[error(transparent)]
    Modal(#[from] crate::eigen::modal::ModalError),
    #[error("{}: the engine has no mode below the cut-off {} Hz (rom.band_hz x rom.cutoff_factor): raise rom.band_hz", path.display(), crate::text::num(*cutoff_hz))]
    NoSystemMode { path: PathBuf, cutoff_hz: f64 },
    #[error("{}: the {part} mesh is in {pieces} disconnected pieces ({sizes} elements): an engine part must be one piece (a separate body is held by nothing, and it throws off where the part is found); join the pieces (shared nodes) or remove the stray elements", file.display())]
    Pieces {
        file: PathBuf,
        part: &'static str,
        pieces: usize,
        sizes: String,
    },
    #[error("{}: the built ROM is inconsistent: {msg}", path.display())]
    Inconsistent { path: PathBuf, msg: String },
}

/// Refuses a part's mesh file (`file`, read into `mesh`) that is not one connected piece.
fn one_piece(mesh: &Mesh, file: Option<&Path>, part: &'static str) -> Result<()> {
    let Some(file) = file else {
        return Ok(());
    };
    let sizes = crate::mesh::checks::piece_sizes(mesh);
    if sizes.len() <= 1 {
        return Ok(());
    }
    let listed: Vec<String> = sizes.iter().map(|n| n.to_string()).collect();
    Err(SceneRomError::Pieces {
        file: file.to_path_buf(),
        part,
        pieces: sizes.len(),
        sizes: listed.join(", "),
    })
}

impl SceneRomError {
    /// 2 for what the user can correct (scene, meshes, cache directory), 1 for a failed or
    /// inconsistent build.
    pub fn exit_code(&self) -> i32 {
        match self {
            SceneRomError::Rom(e) => e.exit_code(),
            SceneRomError::Modal(e) => e.exit_code(),
            SceneRomError::Inconsistent { .. } => 1,
            _ => 2,
        }
    }
}

type Result<T> = std::result::Result<T, SceneRomError>;

/// Cache policy of a command.
#[derive(Clone, Debug, Default)]
pub struct CacheOptions {
    /// Build without reading or writing the cache.
    pub no_cache: bool,
    /// Cache directory overriding the scene's.
    pub dir: Option<PathBuf>,
}

/// The ROM of a scene and where it came from.
pub struct LoadedRom {
    pub rom: EngineRom,
    pub cache: &'static str,
    pub seconds: f64,
    pub cache_file: Option<PathBuf>,
    /// Present when the ROM was built in this run with bases kept.
    pub build: Option<RomBuild>,
    /// A corrupt cache file that was replaced (reason).
    pub replaced: Option<cache::Corruption>,
}

/// BLAKE3 of a mesh file and of every file it includes (in the order found).
fn file_digest(path: &Path) -> Result<String> {
    let mut h = blake3::Hasher::new();
    // an include that is not there is the reader's to report, with the file and line that
    // name it (the key of a deck that cannot be read is never used)
    let mut files = crate::mesh::deck_files(path);
    files.retain(|p| p == path || p.exists());
    crate::files::hash_files(&mut h, &files, crate::files::LIMIT_MESH)
        .map_err(|(path, source)| SceneRomError::MeshFile { path, source })?;
    Ok(h.finalize().to_hex().to_string())
}

/// The scene's crankcase; the engine model needs one.
fn crankcase_of(scene: &Scene) -> Result<&crate::scene::Crankcase> {
    scene
        .crankcase
        .as_ref()
        .ok_or_else(|| SceneRomError::NoCrankcase {
            path: scene.path.clone(),
        })
}

/// A scene's meshes, SI, in their frames, with every set the build needs, and what was found.
pub struct EngineMeshes {
    pub liner: Mesh,
    pub crankcase: Mesh,
    pub liner_material: Elastic,
    pub crankcase_material: Elastic,
    /// The liner's radii and heights (measured on a file's mesh, else the scene's).
    pub shape: LinerShape,
    /// Guide band [z0, z1] in the liner frame \[m\].
    pub guide: [f64; 2],
    /// What was found on imported meshes (None when both are generated).
    pub found: Option<FoundInterfaces>,
}

/// The scene's liner shape (the generator's).
fn scene_shape(scene: &Scene) -> LinerShape {
    let g = &scene.liner_geometry;
    LinerShape {
        inner_radius: g.inner_diameter / 2.0,
        outer_radius: g.outer_diameter / 2.0,
        flange_radius: g.flange_outer_diameter / 2.0,
        pilot_radius: g.pilot_diameter / 2.0,
        length: g.length,
        seat_z: g.length - g.flange_height,
        tol: 1e-6 * g.length,
    }
}

/// Reads one part's mesh (generated, or a file in its unit with its box sets and material).
fn part_mesh(
    generated: impl FnOnce() -> Mesh,
    file: Option<&Path>,
    unit: MeshUnit,
    part: &str,
    given: Option<Elastic>,
    scene_path: &Path,
) -> Result<(Mesh, Elastic, String)> {
    let key = format!("{part}.material");
    let Some(p) = file else {
        let m = given.ok_or_else(|| SceneError::Field {
            path: scene_path.to_path_buf(),
            key: key.clone(),
            msg: "missing: the parametric mesh needs a material".into(),
        })?;
        return Ok((generated(), m, format!("{part}: scene")));
    };
    let mut mesh = import::read_si(p, unit, &format!("{part}.mesh_unit"))?;
    let deck_has = !mesh.materials.is_empty();
    let (m, src, warning) = import::resolve_material(&mut mesh, given, p, &key)?;
    if let Some(w) = warning {
        crate::text::warn(w);
    }
    let note = match src {
        import::MaterialSource::Given if deck_has => {
            format!("{part}: scene (overrides the deck's)")
        }
        import::MaterialSource::Given => format!("{part}: scene"),
        import::MaterialSource::Deck => format!(
            "{part}: deck ({})",
            mesh.materials
                .iter()
                .map(|m| m.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    Ok((mesh, m, note))
}

/// Checks a part's mesh and compacts away the nodes no element uses ([`check_and_compact`],
/// warning of them for a mesh file), before any set is found on it: a deck's stray nodes (a
/// counterbore's elements taken out, construction points) were taken for its surfaces (the
/// counterbore's floor found at the height of nodes no element held; exit 2 with a
/// conditioning message).
fn checked(mesh: &mut Mesh, file: Option<&Path>) -> Result<()> {
    let report = check_and_compact(mesh).map_err(|source| SceneRomError::Mesh {
        file: file.map(|p| p.display().to_string()),
        source,
    })?;
    // (a file in pieces is refused next, `one_piece`; a generated mesh has no stray nodes)
    if let (Some(p), true) = (file, report.removed_nodes > 0) {
        crate::text::warn(format!(
            "{}: {} node(s) belong to no solid element and were left out",
            p.display(),
            report.removed_nodes
        ));
    }
    Ok(())
}

/// The engine's meshes (checked and compacted, [`checked`]): each liner
/// surface-mass set a boundary surface, the engine model a mesh file makes within the
/// limits (a file is sized only once read), and every fixed crankcase set present.
fn check_engine_meshes(
    scene: &Scene,
    (cc, split): (&crate::scene::Crankcase, budget::Split),
    (lm, cm): (&mut Mesh, &mut Mesh),
    (lfile, cfile): (Option<&Path>, Option<&Path>),
) -> Result<()> {
    for sm in liner_surface_mass(scene) {
        if let Err(e) = crate::fem::surface::boundary_faces(lm, &sm.set) {
            return Err(SceneRomError::WetSurface {
                path: scene.path.clone(),
                set: sm.set.clone(),
                file: lfile.map(|p| p.display().to_string()),
                msg: e.to_string(),
            });
        }
    }
    // a mesh from a file is sized only once read: the engine model it makes is checked now
    if lfile.is_some() || cfile.is_some() {
        let cylinders = axis_x(scene).len();
        let loads = match &scene.liner.source {
            MeshSource::Liner { geometry, meshing } => budget::liner_loads(geometry, meshing),
            // the bore lines are found by now (`import::complete_engine`)
            _ => {
                let line = |name| lm.node_set(name).map_or(0, <[usize]>::len);
                (line("bore_thrust") + line("bore_antithrust") + 1) as f64
            }
        };
        let est = budget::rom_split(
            3.0 * cm.nodes.len() as f64,
            (3.0 * lm.nodes.len() as f64, loads),
            (cylinders * budget::interface_columns(scene.rom.harmonics)) as f64,
            cylinders,
            split,
        );
        Limits::of(scene).check(scene, &est)?;
    }
    for name in &cc.fix {
        if cm.node_set(name).is_none() {
            return Err(SceneRomError::UnknownFixSet {
                path: scene.path.clone(),
                name: name.clone(),
                have: cm.set_names().iter().map(|s| s.to_string()).collect(),
            });
        }
    }
    Ok(())
}

/// Refuses a scene box set (`[part.sets.NAME] box_mm`) that selected no node of `mesh`: a
/// fixed set of none left the engine unheld (exit 1, "singular"), found after the build.
fn non_empty(scene: &Scene, mesh: &Mesh, (part, name): (&'static str, &str)) -> Result<()> {
    if mesh.node_set(name).is_some_and(|s| !s.is_empty()) {
        return Ok(());
    }
    let (lo, hi) = mesh.bounding_box();
    let extent = [lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]];
    Err(SceneRomError::EmptyBoxSet {
        path: scene.path.clone(),
        key: if part == "liner" {
            "liner.sets"
        } else {
            "crankcase.sets"
        },
        part,
        name: name.to_string(),
        extent: Box::new(extent),
    })
}

/// Loads and checks the liner and crankcase meshes of a scene: files read in their units,
/// materials resolved, both put into their frames with every set (found from the geometry where
/// a deck does not name it; box sets of the scene added), then checked.
pub fn load_meshes(scene: &Scene) -> Result<EngineMeshes> {
    load_meshes_for(scene, budget::Split::of(scene))
}

/// Refuses an engine model (its ROM, its full model) of a crankcase held by no node set:
/// its reduced stiffness was singular, a failure named by no key. The meshes alone
/// (`export-mesh`, a free-free crankcase deck) need none.
pub fn check_held(scene: &Scene) -> Result<()> {
    if crankcase_of(scene)?.fix.is_empty() {
        return Err(SceneRomError::Scene(SceneError::Field {
            path: scene.path.clone(),
            key: "crankcase.fix".into(),
            msg: "is empty: the engine must be held (name node sets of its mounts, e.g. [\"pan_rail\"])".into(),
        }));
    }
    Ok(())
}

/// [`load_meshes`] for the reduction `split` says (a component task sizes only its own
/// component once a mesh file is read).
fn load_meshes_for(scene: &Scene, split: budget::Split) -> Result<EngineMeshes> {
    let cc = crankcase_of(scene)?;
    // generated meshes are sized before they are made (`export-mesh` of a liner with
    // `radial = 100000` ran on at many GB)
    if let Some(est) = budget::meshes(scene) {
        Limits::of(scene).check(scene, &est)?;
    }
    let lfile = match &scene.liner.source {
        MeshSource::File(p) => Some(p.as_path()),
        MeshSource::Liner { .. } => None,
    };
    let cfile = match &cc.source {
        CrankcaseSource::File(p) => Some(p.as_path()),
        CrankcaseSource::Parametric { .. } => None,
    };
    let (mut lm, liner_material, lnote) = part_mesh(
        || match &scene.liner.source {
            MeshSource::Liner { geometry, meshing } => liner::generate(geometry, meshing),
            MeshSource::File(_) => unreachable!("a file is read"),
        },
        lfile,
        scene.liner.mesh_unit,
        "liner",
        scene.liner.material,
        &scene.path,
    )?;
    let (mut cm, crankcase_material, cnote) = part_mesh(
        || match &cc.source {
            CrankcaseSource::Parametric { geometry, meshing } => {
                crankcase::generate(geometry, meshing)
            }
            CrankcaseSource::File(_) => unreachable!("a file is read"),
        },
        cfile,
        cc.mesh_unit,
        "crankcase",
        cc.material,
        &scene.path,
    )?;
    checked(&mut lm, lfile)?;
    checked(&mut cm, cfile)?;
    one_piece(&lm, lfile, "liner")?;
    one_piece(&cm, cfile, "crankcase")?;
    let mut boxes = Vec::new();
    for (name, b) in &cc.box_sets {
        boxes.push(find::box_set(&mut cm, "crankcase", name, b));
        non_empty(scene, &cm, ("crankcase", name))?;
    }
    let imported = lfile.is_some() || cfile.is_some();
    let axis_x = axis_x(scene);
    let depths = &scene.liner_geometry.analysis_depths;
    let mut found = if imported {
        let frame = import::EngineFrame {
            axis_x: &axis_x,
            depths,
            bore: scene.engine.bore,
            liner_unit_key: "liner.mesh_unit",
        };
        Some(import::complete_engine(
            &mut lm,
            &mut cm,
            scene_shape(scene),
            lfile,
            cfile,
            &frame,
        )?)
    } else {
        None
    };
    for (name, b) in &scene.liner.box_sets {
        boxes.push(find::box_set(&mut lm, "liner", name, b));
        non_empty(scene, &lm, ("liner", name))?;
    }
    if let Some(f) = found.as_mut() {
        f.sets.extend(boxes);
        f.materials = vec![lnote, cnote];
    }
    check_engine_meshes(scene, (cc, split), (&mut lm, &mut cm), (lfile, cfile))?;
    if let Some(f) = found.as_mut() {
        list_fixed_sets(f, fixed_sets(&cm, cc, cfile.is_some()));
    }
    let shape = found
        .as_ref()
        .and_then(|f| f.liner)
        .unwrap_or_else(|| scene_shape(scene));
    let g = &scene.liner_geometry;
    let guide = found
        .as_ref()
        .and_then(|f| f.guide_band)
        .unwrap_or([g.guide_bottom, g.guide_bottom + g.guide_height]);
    Ok(EngineMeshes {
        liner: lm,
        crankcase: cm,
        liner_material,
        crankcase_material,
        shape,
        guide,
        found,
    })
}

/// Adds the fixed sets `fixed` to what was found: a set already listed (found from the
/// geometry, a box) is marked as fixed there, not listed twice.
fn list_fixed_sets(found: &mut FoundInterfaces, fixed: Vec<find::FoundSet>) {
    for set in fixed {
        match found
            .sets
            .iter_mut()
            .find(|s| s.part == set.part && s.name == set.name)
        {
            Some(listed) => listed.detail = format!("{}; {}", listed.detail, set.detail),
            None => found.sets.push(set),
        }
    }
}

/// The listing's lines of the crankcase's fixed sets (`crankcase.fix`), with their node counts:
/// a deck's sets, or the generator's when the crankcase is not `from_file`.
fn fixed_sets(cm: &Mesh, cc: &crate::scene::Crankcase, from_file: bool) -> Vec<find::FoundSet> {
    cc.fix
        .iter()
        .filter_map(|name| {
            cm.node_set(name).map(|nodes| find::FoundSet {
                part: "crankcase".into(),
                name: name.clone(),
                source: if from_file { "deck" } else { "generator" }.into(),
                nodes: nodes.len(),
                detail: "fixed (crankcase.fix)".into(),
            })
        })
        .collect()
}

/// Bore axis x of every cylinder of the engine frame: x_c = (c - (N - 1) / 2) p, c 0-based.
pub fn axis_x(scene: &Scene) -> Vec<f64> {
    let e = &scene.engine;
    (0..e.cylinders)
        .map(|c| crate::scene::bore_axis_x(e.cylinders, e.cylinder_pitch, c))
        .collect()
}

/// The canonical description hashed into the cache key.
pub fn key_description(scene: &Scene) -> Result<String> {
    let cc = crankcase_of(scene)?;
    // a generated mesh's box sets count too (a moved fixed box hit the cache of the old
    // one), added only when there are any so that the keys of other builds stay
    let with_sets = |mut v: serde_json::Value, sets: &[(String, [f64; 6])]| {
        if !sets.is_empty() {
            v["sets"] = serde_json::json!(sets);
        }
        v
    };
    let liner_src = match &scene.liner.source {
        MeshSource::Liner { geometry, meshing } => with_sets(
            serde_json::json!({"geometry": geometry, "meshing": meshing}),
            &scene.liner.box_sets,
        ),
        MeshSource::File(p) => {
            serde_json::json!({"file": file_digest(p)?, "unit": scene.liner.mesh_unit, "sets": scene.liner.box_sets})
        }
    };
    let cc_src = match &cc.source {
        CrankcaseSource::Parametric { geometry, meshing } => with_sets(
            serde_json::json!({"geometry": geometry, "meshing": meshing}),
            &cc.box_sets,
        ),
        CrankcaseSource::File(p) => {
            serde_json::json!({"file": file_digest(p)?, "unit": cc.mesh_unit, "sets": cc.box_sets})
        }
    };
    let mut d = serde_json::json!({
        "format": ROM_FORMAT,
        "liner": liner_src,
        "liner_geometry": scene.liner_geometry,
        "liner_material": scene.liner.material,
        "crankcase": cc_src,
        "crankcase_material": cc.material,
        "crankcase_fix": cc.fix,
        "clamp_force": cc.clamp_force,
        "pitch": scene.engine.cylinder_pitch,
        "cylinder_count": scene.engine.cylinders,
        "band_hz": scene.rom.band_hz,
        "cutoff_hz": scene.rom.cutoff_hz,
        "harmonics": scene.rom.harmonics,
        "residual_vector_spacing": scene.rom.residual_vector_spacing,
        "cylinders": scene.rom.cylinders,
    });
    // only when substructured, so one-piece builds keep the keys of earlier builds
    if scene.rom.crankcase_components > 1 {
        d["crankcase_components"] = serde_json::json!(scene.rom.crankcase_components);
        d["cut_shapes"] = serde_json::json!(scene.rom.cut_shapes);
        // only when raised, so builds at the default keep their keys
        if scene.rom.component_cutoff_factor != 1.0 {
            d["component_cutoff_factor"] = serde_json::json!(scene.rom.component_cutoff_factor);
        }
        if scene.rom.cut_enrichment > 0 {
            d["cut_enrichment"] = serde_json::json!(scene.rom.cut_enrichment);
        }
    }
    // only when present, so the keys of dry scenes stay those of earlier builds
    let surface = liner_surface_mass(scene);
    if !surface.is_empty() {
        d["liner_surface_mass"] = serde_json::json!(surface);
    }
    Ok(d.to_string())
}

/// The liner's normal surface masses: the coolant layer on `coolant_wetted` when modelled.
pub fn liner_surface_mass(scene: &Scene) -> Vec<SurfaceMass> {
    scene
        .cavitation
        .layer_mass_per_area
        .map(|mu| SurfaceMass {
            set: liner::COOLANT_WETTED.into(),
            mass_per_area: mu,
        })
        .into_iter()
        .collect()
}

/// Builds the ROM of a loaded scene (not through the ROM cache; through the component cache
/// `part_cache` when given). `keep_bases` keeps full bases for recovery; `progress` is told
/// each phase.
pub fn build_rom(
    scene: &Scene,
    keep_bases: bool,
    part_cache: Option<&Path>,
    progress: &dyn Fn(&str),
) -> Result<(RomBuild, Mesh, Mesh)> {
    // before any faer product of the build (the interface fields' checks included)
    crate::linalg::thread_count_invariant();
    let said = crate::text::said_count();
    let em = load_meshes(scene)?;
    let mut inputs = rom_inputs(scene, &em, keep_bases);
    inputs.part_cache = part_cache.map(Path::to_path_buf);
    let mut b = build(&inputs, progress)?;
    b.rom.info.interfaces = em.found.clone();
    b.rom.info.warnings = crate::text::said_since(said);
    Ok((b, em.liner, em.crankcase))
}

/// The ROM build inputs of a scene whose meshes are loaded.
pub fn rom_inputs<'a>(scene: &Scene, em: &'a EngineMeshes, keep_bases: bool) -> RomInputs<'a> {
    let cc = scene
        .crankcase
        .as_ref()
        .expect("load_meshes checked the crankcase");
    let e = &scene.engine;
    RomInputs {
        liner: &em.liner,
        liner_material: em.liner_material,
        liner_surface_mass: liner_surface_mass(scene),
        crankcase: &em.crankcase,
        crankcase_material: em.crankcase_material,
        crankcase_fix: cc.fix.clone(),
        bore_radius: em.shape.pilot_radius,
        fit_radius: match cc.source {
            CrankcaseSource::File(_) => em.shape.outer_radius,
            CrankcaseSource::Parametric { .. } => em.shape.pilot_radius,
        },
        crankcase_deck: matches!(cc.source, CrankcaseSource::File(_)),
        flange_radius: em.shape.flange_radius,
        seat_z: em.shape.seat_z,
        guide_height: em.guide[1] - em.guide[0],
        guide_bottom: em.guide[0],
        analysis_points: scene.liner_geometry.analysis_depths.len(),
        axis_x: axis_x(scene),
        pitch: e.cylinder_pitch,
        cylinders: scene.rom.cylinders.clone(),
        clamp_force: cc.clamp_force,
        band_hz: scene.rom.band_hz,
        cutoff_hz: scene.rom.cutoff_hz,
        harmonics: scene.rom.harmonics,
        residual_vector_spacing: scene.rom.residual_vector_spacing,
        crankcase_components: scene.rom.crankcase_components,
        cut_shapes: scene.rom.cut_shapes,
        component_cutoff_factor: scene.rom.component_cutoff_factor,
        cut_enrichment: scene.rom.cut_enrichment,
        keep_bases,
        part_cache: None,
    }
}

/// Refuses, before anything is built, a ROM build of `scene` (whose reduction input is
/// `description`, [`key_description`]) that its limits do not allow, where the build would
/// happen: the cache is bypassed or holds no entry for it. A set of scenes checks every
/// build it needs this way before the first.
pub fn check_build(scene: &Scene, description: &str, opts: &CacheOptions) -> Result<()> {
    let (_, path) = cache_entry(scene, description, opts);
    if !opts.no_cache && path.is_file() {
        return Ok(());
    }
    check_build_limits(scene)
}

/// The cache directory of `scene` under `opts` and the entry of the reduction input
/// `description` in it.
fn cache_entry(scene: &Scene, description: &str, opts: &CacheOptions) -> (PathBuf, PathBuf) {
    let dir = opts
        .dir
        .clone()
        .unwrap_or_else(|| scene.rom.cache_dir.clone());
    let path = cache::path_for(&dir, &cache::key_of(description));
    (dir, path)
}

/// Refuses a ROM build of `scene` that its limits do not allow: nothing is built that the
/// machine cannot hold or whose result cannot be stored.
pub fn check_build_limits(scene: &Scene) -> Result<()> {
    check_held(scene)?;
    if let Some(est) = budget::rom_build(scene, budget::Split::of(scene)) {
        Limits::of(scene).check(scene, &est)?;
    }
    Ok(())
}

/// Gets the ROM of a scene: from the cache when a valid entry exists, else built (and stored);
/// `progress` is told the build's phases.
pub fn get_rom(scene: &Scene, opts: &CacheOptions, progress: &dyn Fn(&str)) -> Result<LoadedRom> {
    let t = Instant::now();
    let description = key_description(scene)?;
    let (dir, path) = cache_entry(scene, &description, opts);
    let mut replaced = None;
    let found = |rom: Box<EngineRom>, how: &'static str, path: PathBuf| LoadedRom {
        rom: *rom,
        cache: how,
        seconds: t.elapsed().as_secs_f64(),
        cache_file: Some(path),
        build: None,
        replaced: None,
    };
    if !opts.no_cache {
        match cache::load(&path, &description)? {
            Lookup::Hit(rom) => return Ok(found(rom, "hit", path)),
            Lookup::Corrupt(reason) => {
                log::warn!("{}: {reason}; rebuilding the ROM", path.display());
                replaced = Some(reason);
            }
            Lookup::Miss => {}
        }
    }
    check_build_limits(scene)?;
    // one builder per entry: processes that missed it at the same time wait for the lock and
    // then find what the builder stored
    let _lock = if opts.no_cache {
        None
    } else {
        crate::files::check_writable(&dir)?;
        let lock = cache::BuildLock::acquire(&path, |l| {
            log::warn!(
                "another process is building this ROM (lock {}); waiting for it",
                l.display()
            )
        })?;
        if lock.waited {
            if let Lookup::Hit(rom) = cache::load(&path, &description)? {
                return Ok(found(rom, "waited", path));
            }
        }
        Some(lock)
    };
    let part_cache = (!opts.no_cache).then_some(dir.as_path());
    let (b, _, _) = build_rom(scene, false, part_cache, progress)?;
    let rom = b.rom.clone();
    if rom.info.system_modes == 0 {
        return Err(SceneRomError::NoSystemMode {
            path: scene.path.clone(),
            cutoff_hz: scene.rom.cutoff_hz,
        });
    }
    rom.validate().map_err(|e| SceneRomError::Inconsistent {
        path: scene.path.clone(),
        msg: e.to_string(),
    })?;
    if !opts.no_cache {
        cache::store(&path, &description, &rom)?;
    }
    Ok(LoadedRom {
        rom,
        cache: if opts.no_cache { "bypassed" } else { "miss" },
        seconds: t.elapsed().as_secs_f64(),
        cache_file: (!opts.no_cache).then_some(path),
        build: None,
        replaced,
    })
}

/// One component's reduction done for a scheduler's task.
#[derive(Debug, serde::Serialize)]
pub struct ComponentDone {
    /// "liner", "crankcase" or a crankcase component ("crankcase.2").
    pub component: String,
    /// Its index among the engine's components (1-based) and their number.
    pub index: usize,
    pub count: usize,
    /// Reduced now, or found in the component cache.
    pub source: super::part_cache::Source,
    pub full_dofs: usize,
    pub reduced_dofs: usize,
    pub seconds: f64,
}

/// Reduces component `index` (1-based, of [`super::rom::COMPONENTS`]) of the scene's engine into
/// the component cache of `opts` (its directory or the scene's `rom.cache_dir`), where a later
/// `rom` finds it: one task of a component job array. Refused with `--no-cache` (nothing
/// would keep the result).
pub fn reduce_component(scene: &Scene, opts: &CacheOptions, index: usize) -> Result<ComponentDone> {
    let t = Instant::now();
    let names = super::rom::component_names(scene.rom.crankcase_components);
    if opts.no_cache || index == 0 || index > names.len() {
        return Err(SceneRomError::Scene(SceneError::Field {
            path: scene.path.clone(),
            key: "--component".into(),
            msg: format!(
                "must be I/{} with I in 1..={} (the engine's components: {}) and a cache to keep it in (not --no-cache)",
                names.len(),
                names.len(),
                names.join(", ")
            ),
        }));
    }
    let dir = opts
        .dir
        .clone()
        .unwrap_or_else(|| scene.rom.cache_dir.clone());
    crate::files::check_writable(&dir)?;
    // the task's own component is sized, not the engine's build
    let split = budget::Split {
        task: Some(index - 1),
        ..budget::Split::of(scene)
    };
    if let Some(est) = budget::rom_build(scene, split) {
        Limits::of(scene).check(scene, &est)?;
    }
    check_held(scene)?;
    let em = load_meshes_for(scene, split)?;
    let mut inputs = rom_inputs(scene, &em, false);
    inputs.part_cache = Some(dir);
    let (r, source) = super::rom::reduce_component(&inputs, index - 1)?;
    Ok(ComponentDone {
        component: names[index - 1].clone(),
        index,
        count: names.len(),
        source,
        full_dofs: r.stats.full_dofs,
        reduced_dofs: r.size(),
        seconds: t.elapsed().as_secs_f64(),
    })
}

/// The full coupled FE model of a scene (every part DOF plus the interface fields, no modal
/// truncation) with its lowest modes, and the placed meshes its shapes live on.
pub struct SceneFullModes {
    pub modes: super::full::FullModes,
    pub system: super::full::FullSystem,
    pub liner_mesh: Mesh,
    pub crankcase_mesh: Mesh,
    /// Bore axis x of every cylinder \[m\].
    pub axis_x: Vec<f64>,
}

/// Builds the full coupled model of `scene` and solves its lowest `count` modes with the
/// scene's shift, certified (Sturm count with the scene's guard modes): the reference of
/// `modes --assembly --full` and `rom-tradeoff`.
pub fn full_modes(scene: &Scene, count: usize) -> Result<SceneFullModes> {
    check_held(scene)?;
    let em = load_meshes(scene)?;
    let inp = rom_inputs(scene, &em, false);
    let axis_x = inp.axis_x.clone();
    let mut system = super::full::FullSystem::build(&inp)?;
    let (sol, _) = crate::eigen::modal::certified_modes(
        &mut system.km,
        &system.analysis,
        count,
        scene.solver.sigma(),
        scene.solver.guard_modes,
        true,
        None,
    )?;
    let modes = super::full::FullModes {
        frequencies_hz: (0..sol.modes.count())
            .map(|j| sol.modes.frequency_hz(j))
            .collect(),
        residuals: sol.residuals.clone(),
        sturm_ok: sol.sturm.as_ref().is_some_and(|s| s.ok),
        dofs: system.dofs(),
        shapes: (0..sol.modes.count())
            .map(|j| system.part_displacements(sol.modes.vector(j)))
            .collect(),
    };
    Ok(SceneFullModes {
        modes,
        system,
        liner_mesh: em.liner.clone(),
        crankcase_mesh: em.crankcase.clone(),
        axis_x,
    })
}
