//! `rom`, `modes --assembly`, `shapes`: the engine reduced-order model from a scene, through
//! the cache.
//!
//! Cache key: the canonical JSON of everything the reduction depends on (liner and crankcase
//! geometry, meshing or mesh-file contents, materials, fixed sets, clamp force, cut-off,
//! harmonics, modelled cylinders, ROM format). Operating and piston data are not in it, so a
//! what-if run on speed, pressure, clearance or pin offset reuses the ROM.

use super::progress::Progress;
use crate::error::{Error, Result};
use crate::fem::element::check_mesh as check_and_compact;
use crate::fem::surface::SurfaceMass;
use crate::mesh::{crankcase, liner, Mesh};
use crate::reduce::cache::{self, Lookup};
use crate::reduce::rom::{build, EngineRom, RomBuild, RomInputs, ROM_FORMAT};
use crate::scene::budget::{self, Limits};
use crate::scene::{CrankcaseSource, MeshSource, Scene};
use std::path::{Path, PathBuf};
use std::time::Instant;

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
    pub replaced: Option<String>,
}

fn file_digest(path: &Path) -> Result<String> {
    let bytes = crate::files::read_regular(path, crate::files::LIMIT_MESH)
        .map_err(|e| Error::Input(format!("{}: cannot read mesh file: {e}", path.display())))?;
    Ok(blake3::hash(&bytes).to_hex().to_string())
}

/// Loads and checks the liner and crankcase meshes of a scene.
pub fn load_meshes(scene: &Scene) -> Result<(Mesh, Mesh)> {
    let cc = scene.crankcase.as_ref().ok_or_else(|| {
        Error::Input(format!(
            "{}: the scene has no [crankcase] section; the engine model needs one",
            scene.path.display()
        ))
    })?;
    let (mut lm, lfile) = match &scene.liner.source {
        MeshSource::Liner { geometry, meshing } => (liner::generate(geometry, meshing), None),
        MeshSource::File(p) => (crate::mesh::read(p)?, Some(p.display().to_string())),
    };
    check_and_compact(&mut lm).map_err(|source| Error::Mesh {
        file: lfile.clone(),
        source,
    })?;
    for sm in liner_surface_mass(scene) {
        if let Err(e) = crate::fem::surface::boundary_faces(&lm, &sm.set) {
            return Err(Error::Input(format!(
                "{}: cavitation.coolant_mass = \"layer\" needs the liner's wet outer surface as node set '{}' covering whole element faces{}: {e}",
                scene.path.display(),
                sm.set,
                lfile
                    .as_ref()
                    .map(|f| format!(" (a physical group of {f})"))
                    .unwrap_or_default()
            )));
        }
    }
    let (mut cm, cfile) = match &cc.source {
        CrankcaseSource::Parametric { geometry, meshing } => {
            (crankcase::generate(geometry, meshing), None)
        }
        CrankcaseSource::File(p) => (crate::mesh::read(p)?, Some(p.display().to_string())),
    };
    check_and_compact(&mut cm).map_err(|source| Error::Mesh {
        file: cfile,
        source,
    })?;
    // a mesh from a file is sized only once read: the engine model it makes is checked now
    if lfile.is_some() || matches!(cc.source, CrankcaseSource::File(_)) {
        let dofs = 3 * (cm.nodes.len() + scene.rom.cylinders.len() * lm.nodes.len());
        let est = budget::fe_model(dofs, "the ROM build");
        Limits::of(scene).check(scene, &est)?;
    }
    for name in &cc.fix {
        if cm.node_set(name).is_none() {
            return Err(Error::Input(format!(
                "{}: crankcase.fix: unknown set '{name}'; the crankcase mesh has: {}",
                scene.path.display(),
                cm.set_names().join(", ")
            )));
        }
    }
    Ok((lm, cm))
}

/// The canonical description hashed into the cache key.
pub fn key_description(scene: &Scene) -> Result<String> {
    let cc = scene
        .crankcase
        .as_ref()
        .ok_or_else(|| Error::Input("no crankcase".into()))?;
    let liner_src = match &scene.liner.source {
        MeshSource::Liner { geometry, meshing } => {
            serde_json::json!({"geometry": geometry, "meshing": meshing})
        }
        MeshSource::File(p) => serde_json::json!({"file": file_digest(p)?}),
    };
    let cc_src = match &cc.source {
        CrankcaseSource::Parametric { geometry, meshing } => {
            serde_json::json!({"geometry": geometry, "meshing": meshing})
        }
        CrankcaseSource::File(p) => serde_json::json!({"file": file_digest(p)?}),
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

/// Builds the ROM of a loaded scene (no cache). `keep_bases` keeps full bases for recovery.
pub fn build_rom(scene: &Scene, keep_bases: bool) -> Result<(RomBuild, Mesh, Mesh)> {
    let (lm, cm) = load_meshes(scene)?;
    let inputs = rom_inputs(scene, &lm, &cm, keep_bases);
    let progress = Progress::new();
    let b = build(&inputs, &|msg| progress.phase(msg))?;
    drop(progress);
    Ok((b, lm, cm))
}

/// The ROM build inputs of a scene whose meshes are loaded.
pub fn rom_inputs<'a>(
    scene: &Scene,
    lm: &'a Mesh,
    cm: &'a Mesh,
    keep_bases: bool,
) -> RomInputs<'a> {
    let cc = scene
        .crankcase
        .as_ref()
        .expect("load_meshes checked the crankcase");
    let g = &scene.liner_geometry;
    let e = &scene.engine;
    let axis_x: Vec<f64> = (0..e.cylinders)
        .map(|c| (c as f64 - (e.cylinders as f64 - 1.0) / 2.0) * e.cylinder_pitch)
        .collect();
    RomInputs {
        liner: lm,
        liner_material: scene.liner.material,
        liner_surface_mass: liner_surface_mass(scene),
        crankcase: cm,
        crankcase_material: cc.material,
        crankcase_fix: cc.fix.clone(),
        liner_outer_radius: g.outer_diameter / 2.0,
        flange_radius: g.flange_outer_diameter / 2.0,
        seat_z: g.length - g.flange_height,
        guide_height: g.guide_height,
        guide_bottom: g.guide_bottom,
        analysis_points: g.analysis_depths.len(),
        axis_x,
        pitch: e.cylinder_pitch,
        cylinders: scene.rom.cylinders.clone(),
        clamp_force: cc.clamp_force,
        band_hz: scene.rom.band_hz,
        cutoff_hz: scene.rom.cutoff_hz,
        harmonics: scene.rom.harmonics,
        residual_vector_spacing: scene.rom.residual_vector_spacing,
        keep_bases,
    }
}

/// Gets the ROM of a scene: from the cache when a valid entry exists, else built (and stored).
pub fn get_rom(scene: &Scene, opts: &CacheOptions) -> Result<LoadedRom> {
    let t = Instant::now();
    let dir = opts
        .dir
        .clone()
        .unwrap_or_else(|| scene.rom.cache_dir.clone());
    let description = key_description(scene)?;
    let key = cache::key_of(&description);
    let path = cache::path_for(&dir, &key);
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
    // nothing is built that the machine cannot hold or whose result cannot be stored
    let limits = Limits::of(scene);
    if let Some(est) = budget::rom_build(scene) {
        limits.check(scene, &est)?;
    }
    // one builder per entry: processes that missed it at the same time wait for the lock and
    // then find what the builder stored
    let _lock = if opts.no_cache {
        None
    } else {
        cache::check_writable(&dir)?;
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
    let (b, _, _) = build_rom(scene, false)?;
    let rom = b.rom.clone();
    if rom.info.system_modes == 0 {
        return Err(Error::Input(format!(
            "{}: the engine has no mode below the cut-off {} Hz (rom.band_hz x rom.cutoff_factor): raise rom.band_hz",
            scene.path.display(),
            crate::text::num(scene.rom.cutoff_hz)
        )));
    }
    rom.validate().map_err(|e| {
        Error::Failure(format!(
            "{}: the built ROM is inconsistent: {e}",
            scene.path.display()
        ))
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

/// JSON report of the `rom` command.
#[derive(serde::Serialize)]
pub struct RomReport {
    pub full_dofs: usize,
    pub reduced_dofs: usize,
    pub cutoff_hz: f64,
    pub band_hz: f64,
    pub cache: &'static str,
    pub seconds: f64,
    pub build_seconds: f64,
    pub system_modes: usize,
    pub estimated_error: f64,
    pub modes_per_part: serde_json::Value,
    pub parts: Vec<crate::reduce::rom::PartInfo>,
    pub left_out: Vec<String>,
    pub cache_file: Option<String>,
    pub first_frequencies_hz: Vec<f64>,
}

impl RomReport {
    pub fn new(l: &LoadedRom) -> Self {
        let i = &l.rom.info;
        let mut per = serde_json::Map::new();
        for p in &i.parts {
            per.insert(p.name.clone(), serde_json::json!(p.stats.normal_modes));
        }
        Self {
            full_dofs: i.full_dofs,
            reduced_dofs: i.reduced_dofs,
            cutoff_hz: i.cutoff_hz,
            band_hz: i.band_hz,
            cache: l.cache,
            seconds: l.seconds,
            build_seconds: i.build_seconds,
            system_modes: i.system_modes,
            estimated_error: i.estimated_error,
            modes_per_part: serde_json::Value::Object(per),
            parts: i.parts.clone(),
            left_out: i.left_out.clone(),
            cache_file: l.cache_file.as_ref().map(|p| p.display().to_string()),
            first_frequencies_hz: l.rom.frequencies_hz.iter().take(20).copied().collect(),
        }
    }

    pub fn to_text(&self) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "engine ROM ({} cache, {:.2} s; built in {:.1} s)",
            self.cache, self.seconds, self.build_seconds
        );
        let _ = writeln!(s, "  full DOFs        {}", self.full_dofs);
        let _ = writeln!(s, "  reduced DOFs     {}", self.reduced_dofs);
        let _ = writeln!(
            s,
            "  band / cut-off   {:.0} Hz / {:.0} Hz",
            self.band_hz, self.cutoff_hz
        );
        let _ = writeln!(
            s,
            "  system modes     {} below the cut-off",
            self.system_modes
        );
        for p in &self.parts {
            let st = &p.stats;
            let _ = writeln!(
                s,
                "  {:<10} x{}  {} DOFs -> {} interface + {} modes (<= {:.0} Hz) + {} attachment, {:.1} s",
                p.name, p.copies, st.full_dofs, st.constraint_modes, st.normal_modes, st.highest_mode_hz, st.attachment_modes, st.seconds
            );
        }
        let _ = writeln!(
            s,
            "  estimated error  {:.2e} (relative frequency change in the band at 2/3 cut-off)",
            self.estimated_error
        );
        for l in &self.left_out {
            let _ = writeln!(s, "  left out: {l}");
        }
        let f: Vec<String> = self
            .first_frequencies_hz
            .iter()
            .map(|f| format!("{f:.1}"))
            .collect();
        let _ = writeln!(s, "  first modes [Hz]: {}", f.join(", "));
        s
    }
}

pub use crate::reduce::rom::ShapeMode;

/// `shapes` JSON: per system mode, the normalised thrust-side radial amplitude at each
/// cylinder's analysis points (cylinder-major, points top to bottom).
#[derive(serde::Serialize)]
pub struct ShapesReport {
    pub modes: Vec<ShapeMode>,
    pub cylinders: Vec<usize>,
    pub cache: &'static str,
}

impl ShapesReport {
    pub fn to_text(&self) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "mode-shape coefficients (radial, thrust side; rows: cylinders {:?}; columns: points top to bottom)",
            self.cylinders
        );
        for m in &self.modes {
            let _ = writeln!(s, "{:9.1} Hz", m.frequency_hz);
            for (c, row) in self.cylinders.iter().zip(&m.coefficients) {
                let v: Vec<String> = row.iter().map(|x| format!("{x:+.3}")).collect();
                let _ = writeln!(s, "   cyl {c}: {}", v.join("  "));
            }
        }
        s
    }
}
