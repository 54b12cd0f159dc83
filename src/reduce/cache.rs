//! On-disk cache of engine ROMs and of the parts' reductions they are assembled from
//! ([`super::part_cache`]).
//!
//! File `rom-<key>.bin` in the cache directory, `key` the BLAKE3 hash of the canonical JSON of
//! everything the reduction depends on (its description is made by the `rom` command). Layout:
//! magic (`LCAVROM\0` for a ROM, `LCAVPRT\0` for a part),
//! format version (u32 LE), payload length (u64 LE), BLAKE3 hash of the payload (32 bytes),
//! payload (bincode of the key description and the entry). A file is trusted only when
//! it is a regular file whose magic, version, length and hash match, whose stored key
//! description is the one asked for, and whose entry passes its `validate` ([`EngineRom::validate`] for a ROM); otherwise it
//! is reported and rebuilt. Files are written to a temporary name and renamed.

use super::rom::{EngineRom, ROM_FORMAT};
use crate::files::{read_regular, write_atomic, ReadError, WriteError};
use std::path::{Path, PathBuf};

const HEADER: usize = 8 + 4 + 8 + 32;

/// What a cache file can hold: its magic and its own consistency check.
pub trait Entry: serde::Serialize + serde::de::DeserializeOwned {
    const MAGIC: &'static [u8; 8];
    /// Format version in the header: an entry of another version is rebuilt.
    const FORMAT: u32;
    fn validate(&self) -> Result<(), Invalid>;
}

/// What an entry's own consistency check found wrong (a forged or mis-written file whose hash
/// is valid).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Invalid {
    #[error("{what}: {rows} x {cols}, expected {want_rows} x {want_cols} (row-major)")]
    Shape {
        what: String,
        rows: usize,
        cols: usize,
        want_rows: usize,
        want_cols: usize,
    },
    #[error("{what}: an entry is not finite")]
    NotFinite { what: String },
    #[error("{frequencies} frequencies for {system_modes} system modes and {residual_vectors} residual vectors (at least one system mode needed)")]
    ModeCount {
        frequencies: usize,
        system_modes: usize,
        residual_vectors: usize,
    },
    #[error("a frequency is negative or not finite")]
    Frequency,
    #[error("the frequencies are not in ascending order")]
    Order,
    #[error("no cylinder")]
    NoCylinder,
    #[error("cylinder {0}: bore lines, points or preload inconsistent or not finite")]
    CylinderRows(usize),
    #[error("inconsistent part reduction (shapes, ranges or non-finite values)")]
    Part,
}

impl Entry for EngineRom {
    const MAGIC: &'static [u8; 8] = b"LCAVROM\0";
    const FORMAT: u32 = ROM_FORMAT;
    fn validate(&self) -> Result<(), Invalid> {
        EngineRom::validate(self)
    }
}

/// Why a cache file that exists is not trusted.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Corruption {
    #[error("{0} bytes, more than the machine's available memory")]
    TooLarge(u64),
    #[error("truncated header ({0} bytes)")]
    Header(usize),
    #[error("not a linercav cache file of this kind")]
    Magic,
    #[error("format version {found}, expected {expected}")]
    Version { found: u32, expected: u32 },
    #[error("payload is {found} bytes, header says {header} (truncated?)")]
    Length { found: u64, header: u64 },
    #[error("checksum mismatch (corrupt file)")]
    Checksum,
    #[error("cannot decode: {0}")]
    Decode(String),
    #[error("made from other inputs than its name says (a copied or forged file)")]
    Description,
    #[error("inconsistent entry: {0}")]
    Invalid(#[from] Invalid),
}

/// Outcome of a cache lookup.
pub enum Lookup<T = EngineRom> {
    Hit(Box<T>),
    Miss,
    /// A file was there but failed the integrity check.
    Corrupt(Corruption),
}

/// Path of the cache file for `key`.
pub fn path_for(dir: &Path, key: &str) -> PathBuf {
    dir.join(format!("rom-{key}.bin"))
}

/// Hash of a key description (hex, 32 characters).
pub fn key_of(description: &str) -> String {
    let h = blake3::hash(description.as_bytes());
    h.to_hex()[..32].to_string()
}

/// A cache file that exists but cannot be read (permissions, a device or directory in its
/// place): an error, not a silent miss.
#[derive(Debug, thiserror::Error)]
#[error("{}: cannot read the ROM cache file: {source} (remove it, or run with --no-cache)", path.display())]
pub struct CacheReadError {
    pub path: PathBuf,
    pub source: ReadError,
}

/// Reads and verifies a cache entry made from `description`.
pub fn load<T: Entry>(path: &Path, description: &str) -> Result<Lookup<T>, CacheReadError> {
    // the stored payload never exceeds what the machine can hold
    let limit = crate::machine::available_memory();
    let bytes = match read_regular(path, limit) {
        Ok(b) => b,
        Err(ReadError::Io(e))
            if matches!(
                e.kind(),
                std::io::ErrorKind::NotFound | std::io::ErrorKind::NotADirectory
            ) =>
        {
            return Ok(Lookup::Miss)
        }
        Err(ReadError::TooLarge { size, .. }) => {
            return Ok(Lookup::Corrupt(Corruption::TooLarge(size)))
        }
        Err(source) => {
            return Err(CacheReadError {
                path: path.to_path_buf(),
                source,
            })
        }
    };
    Ok(match decode(&bytes, description) {
        Ok(rom) => Lookup::Hit(Box::new(rom)),
        Err(msg) => Lookup::Corrupt(msg),
    })
}

fn decode<T: Entry>(bytes: &[u8], description: &str) -> Result<T, Corruption> {
    if bytes.len() < HEADER {
        return Err(Corruption::Header(bytes.len()));
    }
    if &bytes[..8] != T::MAGIC {
        return Err(Corruption::Magic);
    }
    let version = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
    if version != T::FORMAT {
        return Err(Corruption::Version {
            found: version,
            expected: T::FORMAT,
        });
    }
    let len = u64::from_le_bytes(bytes[12..20].try_into().expect("8 bytes"));
    let payload = &bytes[HEADER..];
    if payload.len() as u64 != len {
        return Err(Corruption::Length {
            found: payload.len() as u64,
            header: len,
        });
    }
    if blake3::hash(payload).as_bytes() != &bytes[20..52] {
        return Err(Corruption::Checksum);
    }
    // bincode's length prefixes are bounded by the payload it reads from
    let (stored, entry): (String, T) = bincode::options()
        .with_fixint_encoding()
        .with_limit(len)
        .deserialize(payload)
        .map_err(|e| Corruption::Decode(e.to_string()))?;
    if stored != description {
        return Err(Corruption::Description);
    }
    entry.validate()?;
    Ok(entry)
}

use bincode::Options;

/// The exclusive right to build one cache entry: an advisory lock (flock) on `<entry>.lock`
/// beside it. Processes that miss the same entry at once (the shards of an array job on a
/// shared cache directory) queue on it: one builds and stores, the others then find the entry.
/// The holder removes the lock file before it lets go (a build leaves nothing behind, also
/// when it fails, and when a stopping signal ends the process: the file is registered with
/// the temporaries), so a process that locked a file no longer at the path locks again; a
/// process that is killed lets go by itself (its file stays, empty, and is reused).
pub struct BuildLock {
    /// Held for the lock: closing it lets go.
    _file: std::fs::File,
    path: PathBuf,
    /// Whether another process held the lock when it was asked for.
    pub waited: bool,
}

impl BuildLock {
    /// Takes the lock of the cache entry `path`, waiting for a holder; `on_wait` runs once
    /// when it has to wait.
    pub fn acquire(path: &Path, on_wait: impl FnOnce(&Path)) -> Result<Self, WriteError> {
        use std::os::unix::fs::{MetadataExt, OpenOptionsExt};
        let not_a_file = || {
            std::io::Error::other(
                "exists and is not a regular file (a pipe, socket or device): remove it",
            )
        };
        let lock = path.with_extension("lock");
        let fail = |source| WriteError {
            path: lock.clone(),
            source,
        };
        let mut on_wait = Some(on_wait);
        let mut waited = false;
        loop {
            // not blocking on a pipe put at the lock's path (its open waited for a reader
            // forever); anything but a file there is refused
            let file = std::fs::OpenOptions::new()
                .create(true)
                .truncate(false)
                .write(true)
                .custom_flags(libc::O_NONBLOCK)
                .open(&lock)
                .map_err(|e| match e.raw_os_error() {
                    Some(libc::ENXIO) => fail(not_a_file()),
                    _ => fail(e),
                })?;
            if !file.metadata().map_err(fail)?.is_file() {
                return Err(fail(not_a_file()));
            }
            if flock(&file, libc::LOCK_EX | libc::LOCK_NB).is_err() {
                if let Some(f) = on_wait.take() {
                    f(&lock);
                }
                waited = true;
                flock(&file, libc::LOCK_EX).map_err(fail)?;
            }
            // the holder before us may have removed the file we locked: lock the current one
            let ours = file.metadata().map_err(fail)?;
            match std::fs::metadata(&lock) {
                Ok(now) if now.ino() == ours.ino() && now.dev() == ours.dev() => {
                    // a stopping signal (which skips Drop) removes it as well
                    crate::files::register_temporary(&lock);
                    return Ok(Self {
                        _file: file,
                        path: lock,
                        waited,
                    });
                }
                _ => continue,
            }
        }
    }
}

impl Drop for BuildLock {
    /// Removes the lock file, then lets go of the lock (closing the file).
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
        crate::files::forget_temporary(&self.path);
    }
}

/// flock(2) on an open file (std's File::lock needs Rust 1.89; the crate's MSRV is 1.84).
fn flock(file: &std::fs::File, op: libc::c_int) -> std::io::Result<()> {
    use std::os::fd::AsRawFd;
    loop {
        // SAFETY: the descriptor is open for the call's duration (borrowed from `file`)
        if unsafe { libc::flock(file.as_raw_fd(), op) } == 0 {
            return Ok(());
        }
        let e = std::io::Error::last_os_error();
        if e.kind() != std::io::ErrorKind::Interrupted {
            return Err(e);
        }
    }
}

/// Writes a cache entry made from `description` atomically.
pub fn store<T: Entry>(path: &Path, description: &str, entry: &T) -> Result<(), WriteError> {
    if let Some(dir) = path.parent() {
        crate::files::check_writable(dir)?;
    }
    let payload = bincode::options()
        .with_fixint_encoding()
        .serialize(&(description, entry))
        .expect("cache entries serialise");
    write_atomic(path, |w| {
        w.write_all(T::MAGIC)?;
        w.write_all(&T::FORMAT.to_le_bytes())?;
        w.write_all(&(payload.len() as u64).to_le_bytes())?;
        w.write_all(blake3::hash(&payload).as_bytes())?;
        w.write_all(&payload)
    })
}
