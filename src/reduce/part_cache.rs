//! The component cache: each part's Craig-Bampton reduction stored on its own, keyed by the
//! part's own inputs, so a what-if that changes the liner re-reduces the liner only and the
//! engine ROM is assembled from the cached crankcase in seconds.
//!
//! Key: BLAKE3 of everything [`super::craig_bampton::reduce`] reads, in a fixed binary order
//! (the format version, the part's name, its mesh: nodes, elements, materials; the node sets it
//! uses; its material, surface masses, fixed sets, interface shapes, loads and outputs; the
//! cut-off). Hashing the loaded inputs rather than the scene keys means nothing a reduction
//! depends on can be left out of its key. File `part-<name>-<key>.bin` beside the ROM files,
//! with the same integrity checks (magic, version, length, checksum, stored key, consistency).

use super::cache::{self, CacheReadError, Entry, Invalid, Lookup};
use super::craig_bampton::{CbSettings, CbStats, FixedModes, Part, PartReduction};
use crate::fem::dofs::DofMap;
use crate::files::WriteError;
use crate::linalg::dense::{from_faer, Dense};
use faer::Mat;
use serde::{Deserialize, Serialize};
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Version of the stored part reductions and of their key (raise it when the reduction's
/// method or stored layout changes).
pub const PART_FORMAT: u32 = 1;

/// A part's reduction as stored (no basis).
#[derive(Serialize, Deserialize)]
pub struct StoredPart {
    k: Dense,
    m: Dense,
    interface_cols: Vec<Range<usize>>,
    modes: Range<usize>,
    mode_frequencies_hz: Vec<f64>,
    attachments: Range<usize>,
    outputs: Dense,
    loads: Dense,
    dof: Vec<usize>,
    n_free: usize,
    stats: CbStats,
}

impl Entry for StoredPart {
    const MAGIC: &'static [u8; 8] = b"LCAVPRT\0";
    const FORMAT: u32 = PART_FORMAT;
    /// The reduced matrices square and finite, the column ranges inside them.
    fn validate(&self) -> Result<(), Invalid> {
        let n = self.k.nrows();
        let shapes_ok = self.k.ncols() == n
            && self.m.dim() == (n, n)
            && self.outputs.ncols() == n
            && self.loads.nrows() == n;
        let ranges_ok = self
            .interface_cols
            .iter()
            .chain([&self.modes, &self.attachments])
            .all(|r| r.start <= r.end && r.end <= n)
            && self.mode_frequencies_hz.len() == self.modes.len();
        let finite = [&self.k, &self.m, &self.outputs, &self.loads]
            .iter()
            .all(|d| d.iter().all(|v| v.is_finite()));
        if shapes_ok && ranges_ok && finite {
            Ok(())
        } else {
            Err(Invalid::Part)
        }
    }
}

fn to_faer(d: &Dense) -> Mat<f64> {
    Mat::from_fn(d.nrows(), d.ncols(), |i, j| d[[i, j]])
}

impl StoredPart {
    fn of(r: &PartReduction) -> Self {
        Self {
            k: from_faer(&r.k),
            m: from_faer(&r.m),
            interface_cols: r.interface_cols.clone(),
            modes: r.modes.clone(),
            mode_frequencies_hz: r.mode_frequencies_hz.clone(),
            attachments: r.attachments.clone(),
            outputs: from_faer(&r.outputs),
            loads: from_faer(&r.loads),
            dof: r.dofs.dof.clone(),
            n_free: r.dofs.n_free,
            stats: r.stats.clone(),
        }
    }
    fn into_reduction(self) -> PartReduction {
        PartReduction {
            k: to_faer(&self.k),
            m: to_faer(&self.m),
            interface_cols: self.interface_cols,
            modes: self.modes,
            mode_frequencies_hz: self.mode_frequencies_hz,
            attachments: self.attachments,
            outputs: to_faer(&self.outputs),
            loads: to_faer(&self.loads),
            basis: None,
            fixed_modes: None,
            dofs: DofMap {
                dof: self.dof,
                n_free: self.n_free,
            },
            stats: self.stats,
        }
    }
}

/// Feeds numbers to a hasher in a fixed little-endian layout.
struct KeyHasher(blake3::Hasher);

impl KeyHasher {
    fn usize(&mut self, v: usize) {
        self.0.update(&(v as u64).to_le_bytes());
    }
    fn f64(&mut self, v: f64) {
        self.0.update(&v.to_bits().to_le_bytes());
    }
    fn str(&mut self, s: &str) {
        self.usize(s.len());
        self.0.update(s.as_bytes());
    }
    fn list(&mut self, v: &[usize]) {
        self.usize(v.len());
        v.iter().for_each(|&x| self.usize(x));
    }
    fn floats(&mut self, v: &[f64]) {
        self.usize(v.len());
        v.iter().for_each(|&x| self.f64(x));
    }
    fn set(&mut self, p: &Part<'_>, name: &str) {
        self.str(name);
        self.list(p.mesh.node_set(name).unwrap_or(&[]));
    }
}

/// The cache key of one part's reduction (32 hex characters): see the module doc.
pub fn key(p: &Part<'_>, settings: &CbSettings) -> String {
    key_with(p, settings.cutoff_hz, true)
}

/// The cache key of a part's fixed-interface modes: the part's key without its interface
/// shapes (the interior model holds every interface node, whatever the shapes), the modes'
/// own format and the cut-off.
pub fn modes_key(p: &Part<'_>, cutoff_hz: f64) -> String {
    key_with(p, cutoff_hz, false)
}

/// The key of [`key`], with the interface shapes hashed or (`shapes` false: the
/// fixed-interface modes' key, marked as such) only their node sets.
fn key_with(p: &Part<'_>, cutoff_hz: f64, shapes: bool) -> String {
    let mut h = KeyHasher(blake3::Hasher::new());
    if !shapes {
        h.str("fixed-interface modes");
    }
    h.usize(PART_FORMAT as usize);
    h.str(p.name);
    let mesh = p.mesh;
    h.floats(mesh.nodes.as_flattened());
    h.usize(mesh.blocks.len());
    for b in &mesh.blocks {
        h.str(&format!("{:?}", b.kind));
        h.list(&b.conn);
    }
    h.usize(mesh.materials.len());
    for m in &mesh.materials {
        h.floats(&[m.elastic.young, m.elastic.poisson, m.elastic.density]);
    }
    h.list(
        &mesh
            .element_material
            .iter()
            .map(|&m| m as usize)
            .collect::<Vec<_>>(),
    );
    let e = p.material;
    h.floats(&[e.young, e.poisson, e.density]);
    h.usize(p.surface.len());
    for s in p.surface {
        h.set(p, &s.set);
        h.f64(s.mass_per_area);
    }
    h.usize(p.fix.len());
    p.fix.iter().for_each(|f| h.set(p, f));
    h.usize(p.interfaces.len());
    for b in p.interfaces {
        h.set(p, &b.set);
        if shapes {
            h.usize(b.psi.ncols());
            let psi: Vec<f64> = (0..b.psi.ncols())
                .flat_map(|j| (0..b.psi.nrows()).map(move |i| b.psi[(i, j)]))
                .collect();
            h.floats(&psi);
        }
    }
    h.usize(p.loads.len());
    for l in p.loads {
        h.usize(l.entries.len());
        for (node, f) in &l.entries {
            h.usize(*node);
            h.floats(f);
        }
    }
    h.usize(p.outputs.len());
    for o in p.outputs {
        h.usize(o.node);
        h.floats(&o.dir);
    }
    h.f64(cutoff_hz);
    h.0.finalize().to_hex()[..32].to_string()
}

/// The cache key of data computed from a mesh alone (a substructuring cut's shapes): the
/// format, `name`, the mesh (nodes, elements, materials, every node set), the material, the
/// fixed sets and the method's numbers `extra` (32 hex characters).
pub fn mesh_key(
    name: &str,
    mesh: &crate::mesh::Mesh,
    material: &crate::scene::spec::Elastic,
    fix: &[String],
    extra: &[f64],
) -> String {
    let p = Part {
        name,
        mesh,
        material,
        surface: &[],
        fix,
        interfaces: &[],
        loads: &[],
        outputs: &[],
    };
    let mut h = KeyHasher(blake3::Hasher::new());
    h.str(&key(
        &p,
        &CbSettings {
            cutoff_hz: 0.0,
            keep_basis: false,
        },
    ));
    h.usize(mesh.node_sets.len());
    for name in mesh.node_sets.keys() {
        h.set(&p, name);
    }
    h.floats(extra);
    h.0.finalize().to_hex()[..32].to_string()
}

/// A dense matrix computed from a mesh (a cut's shapes), as stored.
#[derive(Serialize, Deserialize)]
pub struct StoredMatrix(Dense);

impl Entry for StoredMatrix {
    const MAGIC: &'static [u8; 8] = b"LCAVMAT\0";
    const FORMAT: u32 = PART_FORMAT;
    fn validate(&self) -> Result<(), Invalid> {
        if self.0.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(Invalid::NotFinite {
                what: "stored matrix".into(),
            })
        }
    }
}

/// The matrix of cache file `file` under `key` in `dir` when a valid entry exists, else made by
/// `make` (and stored when `dir` is given; by one process at a time). A corrupt entry is
/// reported and replaced ([`cached_matrices`] of one file).
pub fn cached_matrix(
    dir: Option<&Path>,
    file: &str,
    key: &str,
    make: impl FnOnce() -> Result<Mat<f64>, super::craig_bampton::ReduceError>,
) -> Result<(Mat<f64>, Source), PartCacheError> {
    let (mut made, source) = cached_matrices(dir, &[file.to_string()], key, || Ok(vec![make()?]))?;
    Ok((made.remove(0), source))
}

/// The matrices of cache files `files` under `key` in `dir` when every one has a valid entry,
/// else all made by `make` (one per file, and stored when `dir` is given). A corrupt entry is
/// reported and all are made again. One process makes them at a time: processes that miss
/// the entries at once (the component tasks of an array job on a shared cache directory)
/// queue on a lock beside the first file ([`super::cache::BuildLock`]) and then read what
/// the first stored, instead of each making them.
pub fn cached_matrices(
    dir: Option<&Path>,
    files: &[String],
    key: &str,
    make: impl FnOnce() -> Result<Vec<Mat<f64>>, PartCacheError>,
) -> Result<(Vec<Mat<f64>>, Source), PartCacheError> {
    let Some(dir) = dir else {
        return Ok((make()?, Source::Reduced));
    };
    let paths: Vec<PathBuf> = files
        .iter()
        .map(|f| dir.join(format!("{f}-{key}.bin")))
        .collect();
    if let Some(found) = load_matrices(&paths, key)? {
        return Ok((found, Source::Cached));
    }
    let Some(first) = paths.first() else {
        return Ok((make()?, Source::Reduced));
    };
    let lock = cache::BuildLock::acquire(first, |l| {
        log::warn!(
            "another process is making the cache entries {} (lock {}); waiting for it",
            files.join(", "),
            l.display()
        )
    })?;
    if lock.waited {
        if let Some(found) = load_matrices(&paths, key)? {
            return Ok((found, Source::Cached));
        }
    }
    let made = make()?;
    for (path, m) in paths.iter().zip(&made) {
        cache::store(path, key, &StoredMatrix(from_faer(m)))?;
    }
    Ok((made, Source::Reduced))
}

/// The matrices at `paths` under `key` when every one has a valid entry (a corrupt one is
/// reported), else None.
fn load_matrices(paths: &[PathBuf], key: &str) -> Result<Option<Vec<Mat<f64>>>, PartCacheError> {
    let mut found = Vec::with_capacity(paths.len());
    for path in paths {
        match cache::load::<StoredMatrix>(path, key)? {
            Lookup::Hit(stored) => found.push(to_faer(&stored.0)),
            Lookup::Corrupt(reason) => {
                log::warn!("{}: {reason}; computing it again", path.display());
                return Ok(None);
            }
            Lookup::Miss => return Ok(None),
        }
    }
    Ok(Some(found))
}

/// Path of a part's entry in the cache directory.
pub fn path_for(dir: &Path, part: &str, key: &str) -> PathBuf {
    dir.join(format!("part-{part}-{key}.bin"))
}

/// A part's fixed-interface modes as stored between the two passes of enriched cuts.
#[derive(Serialize, Deserialize)]
pub struct StoredModes {
    lambdas: Vec<f64>,
    vectors: Dense,
}

impl Entry for StoredModes {
    const MAGIC: &'static [u8; 8] = b"LCAVMOD\0";
    const FORMAT: u32 = PART_FORMAT;
    /// One column per eigenvalue, finite, the eigenvalues ascending and not negative beyond
    /// roundoff.
    fn validate(&self) -> Result<(), Invalid> {
        let sorted = self.lambdas.windows(2).all(|w| w[0] <= w[1]);
        let finite = self
            .lambdas
            .iter()
            .chain(self.vectors.iter())
            .all(|v| v.is_finite());
        if self.vectors.ncols() == self.lambdas.len() && sorted && finite {
            Ok(())
        } else {
            Err(Invalid::Part)
        }
    }
}

/// Where the fixed-interface modes of the components' first pass wait for their second pass
/// (enriched cuts, `substructure/enrich.rs`): files `modes-<part>-<key>.bin` in the component
/// cache directory, each removed once that component's final reduction is stored (a component
/// task of a job array finds the first pass's modes there), or in a temporary directory of
/// the build when there is no cache (removed with the store).
pub struct ModeStore {
    dir: PathBuf,
    _temp: Option<tempfile::TempDir>,
}

impl ModeStore {
    /// The store in the cache directory `dir`, else in a new temporary directory.
    pub fn new(dir: Option<&Path>) -> Result<Self, WriteError> {
        if let Some(d) = dir {
            return Ok(Self {
                dir: d.to_path_buf(),
                _temp: None,
            });
        }
        let base = std::env::temp_dir();
        let temp = tempfile::Builder::new()
            .prefix("linercav-modes-")
            .tempdir_in(&base)
            .map_err(|source| WriteError { path: base, source })?;
        Ok(Self {
            dir: temp.path().to_path_buf(),
            _temp: Some(temp),
        })
    }

    fn path(&self, p: &Part<'_>, cutoff_hz: f64) -> (PathBuf, String) {
        let key = modes_key(p, cutoff_hz);
        (self.dir.join(format!("modes-{}-{key}.bin", p.name)), key)
    }

    /// Stores part `p`'s modes at `cutoff_hz`.
    pub fn save(&self, p: &Part<'_>, cutoff_hz: f64, m: &FixedModes) -> Result<(), WriteError> {
        let (path, key) = self.path(p, cutoff_hz);
        let stored = StoredModes {
            lambdas: m.lambdas.clone(),
            vectors: from_faer(&m.vectors),
        };
        cache::store(&path, &key, &stored)
    }

    /// Part `p`'s modes at `cutoff_hz` when stored and valid (a corrupt file is reported and
    /// ignored: the modes are solved for).
    pub fn load(&self, p: &Part<'_>, cutoff_hz: f64) -> Result<Option<FixedModes>, CacheReadError> {
        let (path, key) = self.path(p, cutoff_hz);
        Ok(match cache::load::<StoredModes>(&path, &key)? {
            Lookup::Hit(s) => Some(FixedModes {
                lambdas: s.lambdas,
                vectors: to_faer(&s.vectors),
            }),
            Lookup::Corrupt(reason) => {
                log::warn!("{}: {reason}; solving for the modes again", path.display());
                None
            }
            Lookup::Miss => None,
        })
    }

    /// Removes part `p`'s stored modes (done with them).
    pub fn remove(&self, p: &Part<'_>, cutoff_hz: f64) {
        let _ = std::fs::remove_file(self.path(p, cutoff_hz).0);
    }
}

/// Where a reduction came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Source {
    /// Reduced in this run.
    Reduced,
    /// Read from the component cache.
    Cached,
}

/// The reduction of `p`: from the cache directory `dir` when a valid entry exists, else
/// reduced (and stored when `dir` is given). A corrupt entry is reported and replaced.
pub fn reduce_cached(
    p: &Part<'_>,
    settings: &CbSettings,
    dir: Option<&Path>,
) -> Result<(PartReduction, Source), PartCacheError> {
    reduce_cached_with(p, settings, dir, None)
}

/// [`reduce_cached`] of a component whose fixed-interface modes a first pass may have left in
/// `modes`: on a cache miss they are read from there instead of solved for, and removed once
/// the reduction is made (and stored).
pub fn reduce_cached_with(
    p: &Part<'_>,
    settings: &CbSettings,
    dir: Option<&Path>,
    modes: Option<&ModeStore>,
) -> Result<(PartReduction, Source), PartCacheError> {
    let reduce = || -> Result<PartReduction, PartCacheError> {
        let known = match modes {
            Some(store) => store.load(p, settings.cutoff_hz)?,
            None => None,
        };
        Ok(super::craig_bampton::reduce_with(p, settings, known)?)
    };
    // the first pass's modes are done with once the part's reduction is at hand
    let forget = || {
        if let Some(store) = modes {
            store.remove(p, settings.cutoff_hz);
        }
    };
    let Some(dir) = dir.filter(|_| !settings.keep_basis) else {
        let r = reduce()?;
        forget();
        return Ok((r, Source::Reduced));
    };
    let key = key(p, settings);
    let path = path_for(dir, p.name, &key);
    match cache::load::<StoredPart>(&path, &key)? {
        Lookup::Hit(stored) => {
            forget();
            return Ok((stored.into_reduction(), Source::Cached));
        }
        Lookup::Corrupt(reason) => {
            log::warn!(
                "{}: {reason}; reducing the {} again",
                path.display(),
                p.name
            )
        }
        Lookup::Miss => {}
    }
    let r = reduce()?;
    cache::store(&path, &key, &StoredPart::of(&r))?;
    forget();
    Ok((r, Source::Reduced))
}

/// Failures of a cached reduction.
#[derive(Debug, thiserror::Error)]
pub enum PartCacheError {
    #[error(transparent)]
    Reduce(#[from] super::craig_bampton::ReduceError),
    #[error(transparent)]
    Read(#[from] CacheReadError),
    #[error(transparent)]
    Write(#[from] WriteError),
}
