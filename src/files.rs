//! Files in and out. Input: only regular files are read, and never more than a stated size
//! (a link to `/dev/zero` or a mistyped multi-gigabyte file is refused before it is read).
//! Output: written to a temporary file in the target directory, then renamed, so a failed run
//! never leaves a half-written file behind.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// An output file that could not be written.
#[derive(Debug, thiserror::Error)]
#[error("{}: cannot write: {source}", path.display())]
pub struct WriteError {
    pub path: PathBuf,
    pub source: std::io::Error,
}

/// Why an input file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    #[error("cannot read the file: {0}")]
    Io(#[from] std::io::Error),
    #[error("not a regular file (a device, directory or pipe); give a file")]
    NotRegular,
    #[error("the file has {size} bytes, more than the {limit} bytes accepted for this input")]
    TooLarge { size: u64, limit: u64 },
    #[error("line {line}: byte 0x{byte:02x} is not UTF-8 text")]
    NotText { line: usize, byte: u8 },
}

/// Size limit of scene, pressure-curve and calibration files (a hand-written table).
pub const LIMIT_TEXT: u64 = 64 << 20;
/// Size limit of rig-data CSVs (long acquisitions at high sample rates).
pub const LIMIT_DATA: u64 = 2 << 30;
/// Size limit of mesh files: about 20 million nodes in ASCII MSH, beyond what a 24 GB machine
/// can solve (the FE model, not the file, decides; see the size estimate of the scene).
pub const LIMIT_MESH: u64 = 4 << 30;

/// Reads a whole regular file of at most `limit` bytes (links are followed; what they point to
/// must be a regular file).
pub fn read_regular(path: &Path, limit: u64) -> Result<Vec<u8>, ReadError> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(ReadError::NotRegular);
    }
    if meta.len() > limit {
        return Err(ReadError::TooLarge {
            size: meta.len(),
            limit,
        });
    }
    use std::io::Read;
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    // `take` guards against a file that grows while it is read
    std::fs::File::open(path)?
        .take(limit + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(ReadError::TooLarge {
            size: bytes.len() as u64,
            limit,
        });
    }
    Ok(bytes)
}

/// Reads a whole regular text file of at most `limit` bytes (UTF-8; the error names the line
/// of the first byte that is not).
pub fn read_text(path: &Path, limit: u64) -> Result<String, ReadError> {
    let bytes = read_regular(path, limit)?;
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let bytes = e.as_bytes();
        let line = 1 + bytes[..at].iter().filter(|&&b| b == b'\n').count();
        ReadError::NotText {
            line,
            byte: bytes[at],
        }
    })
}

fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

/// Writes `path` through `fill`, atomically.
pub fn write_atomic(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), WriteError> {
    write_all_atomic(vec![(path.to_path_buf(), Box::new(fill))])
}

/// Fills one output file.
pub type Filler<'a> = Box<dyn FnOnce(&mut dyn Write) -> std::io::Result<()> + 'a>;

/// Writes several files so that either all appear or none: each goes to a temporary name first,
/// and the renames happen only when every file was written.
pub fn write_all_atomic(files: Vec<(PathBuf, Filler<'_>)>) -> Result<(), WriteError> {
    let mut done: Vec<(PathBuf, PathBuf)> = Vec::new();
    for (path, fill) in files {
        let tmp = temp_path(&path);
        let r = (|| {
            let file = std::fs::File::create(&tmp)?;
            let mut w = BufWriter::with_capacity(1 << 20, file);
            fill(&mut w)?;
            w.flush()?;
            w.into_inner().map_err(|e| e.into_error())?.sync_all()
        })();
        if let Err(source) = r {
            let _ = std::fs::remove_file(&tmp);
            for (t, _) in &done {
                let _ = std::fs::remove_file(t);
            }
            return Err(WriteError { path, source });
        }
        done.push((tmp, path));
    }
    for (tmp, path) in done {
        std::fs::rename(&tmp, &path).map_err(|source| WriteError { path, source })?;
    }
    Ok(())
}
