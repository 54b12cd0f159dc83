//! Atomic file output: write to a temporary file in the target directory, then rename, so a
//! failed run never leaves a half-written file behind.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// An output file that could not be written.
#[derive(Debug, thiserror::Error)]
#[error("{}: cannot write: {source}", path.display())]
pub struct WriteError {
    pub path: PathBuf,
    pub source: std::io::Error,
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
