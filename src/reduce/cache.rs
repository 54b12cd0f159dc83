//! On-disk cache of engine ROMs.
//!
//! File `rom-<key>.bin` in the cache directory, `key` the BLAKE3 hash of the canonical JSON of
//! everything the reduction depends on (see [`crate::app::rom`]). Layout: magic `LCAVROM\0`,
//! format version (u32 LE), payload length (u64 LE), BLAKE3 hash of the payload (32 bytes),
//! payload (bincode of [`EngineRom`]). A file whose magic, version, length or hash does not
//! match is treated as absent (and overwritten by the rebuild), never trusted. Files are
//! written to a temporary name and renamed.

use super::rom::{EngineRom, ROM_FORMAT};
use crate::files::{write_atomic, WriteError};
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"LCAVROM\0";

/// Outcome of a cache lookup.
pub enum Lookup {
    Hit(Box<EngineRom>),
    Miss,
    /// A file was there but failed the integrity check (reason).
    Corrupt(String),
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

/// Reads and verifies a cached ROM.
pub fn load(path: &Path) -> Lookup {
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(_) => return Lookup::Miss,
    };
    match decode(&bytes) {
        Ok(rom) => Lookup::Hit(Box::new(rom)),
        Err(msg) => Lookup::Corrupt(msg),
    }
}

fn decode(bytes: &[u8]) -> Result<EngineRom, String> {
    let header = 8 + 4 + 8 + 32;
    if bytes.len() < header {
        return Err(format!("truncated header ({} bytes)", bytes.len()));
    }
    if &bytes[..8] != MAGIC {
        return Err("not a linercav ROM file".into());
    }
    let version = u32::from_le_bytes(bytes[8..12].try_into().unwrap());
    if version != ROM_FORMAT {
        return Err(format!("format version {version}, expected {ROM_FORMAT}"));
    }
    let len = u64::from_le_bytes(bytes[12..20].try_into().unwrap()) as usize;
    let payload = &bytes[header..];
    if payload.len() != len {
        return Err(format!(
            "payload is {} bytes, header says {len} (truncated?)",
            payload.len()
        ));
    }
    if blake3::hash(payload).as_bytes() != &bytes[20..52] {
        return Err("checksum mismatch (corrupt file)".into());
    }
    bincode::deserialize(payload).map_err(|e| format!("cannot decode: {e}"))
}

/// Writes a ROM atomically.
pub fn store(path: &Path, rom: &EngineRom) -> Result<(), WriteError> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|source| WriteError {
            path: dir.to_path_buf(),
            source,
        })?;
    }
    let payload = bincode::serialize(rom).expect("ROM serialises");
    write_atomic(path, |w| {
        w.write_all(MAGIC)?;
        w.write_all(&ROM_FORMAT.to_le_bytes())?;
        w.write_all(&(payload.len() as u64).to_le_bytes())?;
        w.write_all(blake3::hash(&payload).as_bytes())?;
        w.write_all(&payload)
    })
}
