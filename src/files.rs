//! Files in and out. Input: only regular files are read, and never more than a stated size
//! (a link to `/dev/zero` or a mistyped multi-gigabyte file is refused before it is read).
//! Output: written to a temporary file in the target directory, then renamed, so a failed run
//! never leaves a half-written file behind; a command's set of files is staged in a temporary
//! directory and moved into place only when complete ([`OutputDir`]). Temporary files and
//! directories are registered and removed when the process is stopped by SIGINT, SIGTERM or
//! SIGHUP ([`stop_cleanly`]); the handler waits for a move in progress to finish, so
//! an output directory is left either as it was or complete.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Temporary files and directories of this process, removed on a stopping signal.
static TEMPORARIES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
/// Held while staged outputs are moved into place (the signal handler waits for it).
static COMMITTING: Mutex<()> = Mutex::new(());
/// Output directories this process created and has not yet written into, deepest last:
/// removed on a stopping signal when still empty ([`NewDirs`]).
static NEW_DIRS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Makes a temporary file or directory at `p` through `make` and registers it, both under the
/// registry's lock: the signal handler, which takes that lock and keeps it until the process
/// ends, sees either both or neither, so nothing made here outlives a stopping signal.
fn make_registered<T>(
    p: &Path,
    make: impl FnOnce(&Path) -> std::io::Result<T>,
) -> std::io::Result<T> {
    let mut temporaries = lock(&TEMPORARIES);
    let made = make(p)?;
    temporaries.push(p.to_path_buf());
    Ok(made)
}

fn unregister(p: &Path) {
    lock(&TEMPORARIES).retain(|q| q != p);
}

/// Registers a file this process made and must not outlive it (a cache build's lock file):
/// a stopping signal removes it like a temporary. [`forget_temporary`] undoes it.
pub fn register_temporary(p: &Path) {
    lock(&TEMPORARIES).push(p.to_path_buf());
}

/// Takes a file registered by [`register_temporary`] off the list (it was removed or kept).
pub fn forget_temporary(p: &Path) {
    unregister(p);
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// What a stopping signal (SIGINT, SIGTERM, SIGHUP) does: removes this process's temporary
/// files and directories (and its new, still empty output directories) and exits with `code`
/// (128 + the signal's number, as a shell reports a process the signal ended). A
/// move of staged outputs in progress is finished first; both locks are then held until the
/// process ends, so the working thread can neither make a new temporary nor move an output
/// while (or after) they are removed. The command-line front end installs it as the signal
/// handler.
pub fn stop_cleanly(code: i32) -> ! {
    let _moving = lock(&COMMITTING);
    let mut temporaries = lock(&TEMPORARIES);
    remove_registered(&mut temporaries, &mut lock(&NEW_DIRS));
    // best effort: a standard error that cannot be written does not change the exit
    let _ = writeln!(
        std::io::stderr(),
        "\nstopped by a signal; temporary files removed, outputs left as they were"
    );
    std::process::exit(code);
}

/// Before the process exits on a failed allocation (from any thread): removes the temporary
/// files and directories and the new, empty output directories, as [`stop_cleanly`] does,
/// and keeps the registries locked until the process ends (nothing new is made or moved
/// meanwhile). Returns false, removing nothing, when a lock is not free at once (a move of
/// outputs under way, or the failing thread holding a registry: waiting could hang).
pub fn remove_temporaries_for_exit() -> bool {
    let (Ok(moving), Ok(mut temporaries), Ok(mut dirs)) = (
        COMMITTING.try_lock(),
        TEMPORARIES.try_lock(),
        NEW_DIRS.try_lock(),
    ) else {
        return false;
    };
    remove_registered(&mut temporaries, &mut dirs);
    std::mem::forget((moving, temporaries, dirs));
    true
}

/// Removes the registered temporary files and directories and the new output directories
/// that are still empty (deepest first), emptying both lists.
fn remove_registered(temporaries: &mut Vec<PathBuf>, new_dirs: &mut Vec<PathBuf>) {
    for p in temporaries.drain(..) {
        if p.is_dir() {
            let _ = std::fs::remove_dir_all(&p);
        } else {
            let _ = std::fs::remove_file(&p);
        }
    }
    for d in new_dirs.drain(..).rev() {
        let _ = std::fs::remove_dir(&d);
    }
}

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
    #[error("the file has {size} bytes and reading it takes about {} GB, more than the {} GB {bound} leaves", crate::text::num(*need as f64 / 1e9), crate::text::num(*available as f64 / 1e9))]
    NoMemory {
        size: u64,
        need: u64,
        available: u64,
        bound: &'static str,
    },
}

/// Size limit of scene, pressure-curve and calibration files (a hand-written table).
pub const LIMIT_TEXT: u64 = 64 << 20;
/// Size limit of rig-data CSVs (long acquisitions at high sample rates).
pub const LIMIT_DATA: u64 = 2 << 30;
/// Size limit of a sweep's part files (`sweep --shard`'s JSON: a few kB per run, so about
/// 100,000 runs per part).
pub const LIMIT_PART: u64 = 512 << 20;
/// Size limit of mesh files: about 20 million nodes in ASCII MSH, beyond what a 24 GB machine
/// can solve (the FE model, not the file, decides; see the size estimate of the scene).
pub const LIMIT_MESH: u64 = 4 << 30;

/// Reads a whole regular file of at most `limit` bytes (links are followed; what they point to
/// must be a regular file).
pub fn read_regular(path: &Path, limit: u64) -> Result<Vec<u8>, ReadError> {
    read_regular_within(path, limit, 1)
}

/// [`read_regular`] of a file whose reading takes `factor` times its size in memory (the text
/// and what is made of it): refused when the machine does not have that
/// ([`crate::machine::available_memory_from`]), instead of aborting in an allocation.
pub fn read_regular_within(path: &Path, limit: u64, factor: u64) -> Result<Vec<u8>, ReadError> {
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
    let need = meta.len().saturating_mul(factor);
    let (available, bound) = crate::machine::available_memory_from();
    let no_memory = || ReadError::NoMemory {
        size: meta.len(),
        need,
        available,
        bound,
    };
    if need > available {
        return Err(no_memory());
    }
    use std::io::Read;
    let mut bytes = Vec::new();
    bytes
        .try_reserve_exact(meta.len() as usize)
        .map_err(|_| no_memory())?;
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
/// of the first byte that is not), without a leading byte-order mark (spreadsheets' "CSV
/// UTF-8" and some editors write one; left in, it would stick to the first header name).
pub fn read_text(path: &Path, limit: u64) -> Result<String, ReadError> {
    read_text_within(path, limit, 1)
}

/// [`read_text`] of a file whose reading takes `factor` times its size ([`read_regular_within`]).
pub fn read_text_within(path: &Path, limit: u64, factor: u64) -> Result<String, ReadError> {
    let mut bytes = read_regular_within(path, limit, factor)?;
    if bytes.starts_with(b"\xEF\xBB\xBF") {
        bytes.drain(..3);
    }
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

/// Feeds every file of `paths` (each at most `limit` bytes) into `h` as its length (8 bytes,
/// little-endian) and its bytes, so that a digest tells files apart by content and by where
/// one ends; the error names the file that could not be read.
pub fn hash_files(
    h: &mut blake3::Hasher,
    paths: &[PathBuf],
    limit: u64,
) -> Result<(), (PathBuf, ReadError)> {
    for p in paths {
        let bytes = read_regular(p, limit).map_err(|e| (p.clone(), e))?;
        h.update(&(bytes.len() as u64).to_le_bytes());
        h.update(&bytes);
    }
    Ok(())
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
            // a device, a pipe or a directory is never replaced by a file (checked up front
            // by the commands, [`check_output_file`]; here for every writer)
            if std::fs::metadata(&path).is_ok_and(|m| !m.is_file()) {
                return Err(exists_as_other(&path, "a file's path").source);
            }
            let file = make_registered(&tmp, |p| std::fs::File::create(p))?;
            let mut w = BufWriter::with_capacity(1 << 20, file);
            fill(&mut w)?;
            w.flush()?;
            w.into_inner().map_err(|e| e.into_error())?.sync_all()
        })();
        if let Err(source) = r {
            let _ = std::fs::remove_file(&tmp);
            unregister(&tmp);
            for (t, _) in &done {
                let _ = std::fs::remove_file(t);
                unregister(t);
            }
            return Err(WriteError { path, source });
        }
        done.push((tmp, path));
    }
    let _moving = lock(&COMMITTING);
    let mut result = Ok(());
    for (tmp, path) in done {
        if result.is_ok() {
            result = std::fs::rename(&tmp, &path).map_err(|source| WriteError { path, source });
        }
        if result.is_err() {
            let _ = std::fs::remove_file(&tmp);
        }
        unregister(&tmp);
    }
    result
}

/// Checks, before work starts, that `dir` exists or can be made and that a file can be
/// created in it, so that work whose result could not be stored is never started.
pub fn check_writable(dir: &Path) -> Result<(), WriteError> {
    let fail = |source| WriteError {
        path: dir.to_path_buf(),
        source,
    };
    // a path that exists as something else than a directory ("File exists (os error 17)"
    // from create_dir_all) is said as such
    if dir.exists() && !dir.is_dir() {
        return Err(exists_as_other(dir, "a directory"));
    }
    std::fs::create_dir_all(dir).map_err(fail)?;
    let probe = dir.join(format!(".probe.{}.tmp", std::process::id()));
    make_registered(&probe, |p| std::fs::File::create(p)).map_err(fail)?;
    let removed = std::fs::remove_file(&probe);
    unregister(&probe);
    removed.map_err(fail)
}

/// The error for `path`, which exists as something else than `wanted` ("a directory", "a
/// file's path"): "exists and is not a directory: give a directory".
fn exists_as_other(path: &Path, wanted: &str) -> WriteError {
    let what = wanted.strip_suffix("'s path").unwrap_or(wanted);
    WriteError {
        path: path.to_path_buf(),
        source: std::io::Error::new(
            std::io::ErrorKind::AlreadyExists,
            format!("exists and is not {what}: give {wanted}"),
        ),
    }
}

/// Checks, before work starts, that output file `path` can be written: its directory can be
/// made and written ([`check_writable`]) and `path` is not something else than a file (a
/// `--vtu /proc/x.vtu` was refused only after its modal solve). Returns the directories it
/// made: they are removed again, when empty, unless kept ([`NewDirs::keep`]) once the file
/// is written, so a run that fails leaves no empty directory behind.
pub fn check_output_file(path: &Path) -> Result<NewDirs, WriteError> {
    if path.exists() && !path.is_file() {
        return Err(exists_as_other(path, "a file's path"));
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    // said before anything is made
    if dir.exists() && !dir.is_dir() {
        return Err(exists_as_other(dir, "a directory"));
    }
    let made = NewDirs::create(dir)?;
    check_writable(dir)?;
    Ok(made)
}

/// Refuses output file `path` when it is one of the run's input files `inputs` (the same file
/// by device and inode, whatever the paths say), which writing it would replace.
pub fn check_not_an_input(path: &Path, inputs: &[&Path]) -> Result<(), WriteError> {
    use std::os::unix::fs::MetadataExt;
    let Ok(out) = std::fs::metadata(path) else {
        return Ok(());
    };
    let same = |m: &std::fs::Metadata| (m.dev(), m.ino()) == (out.dev(), out.ino());
    match inputs
        .iter()
        .find(|i| std::fs::metadata(i).is_ok_and(|m| same(&m)))
    {
        Some(input) => Err(WriteError {
            path: path.to_path_buf(),
            source: std::io::Error::new(
                std::io::ErrorKind::AlreadyExists,
                format!("is the input {}: give another path", input.display()),
            ),
        }),
        None => Ok(()),
    }
}

/// The first entry of directory `dir` that is not a regular file (a directory, a device, a
/// link to one) and whose name matches one of `outputs` (a name, or `prefix*suffix`).
fn taken_output(dir: &Path, outputs: &[&str]) -> Option<PathBuf> {
    std::fs::read_dir(dir).ok()?.flatten().find_map(|e| {
        let name = e.file_name().to_string_lossy().into_owned();
        let file = std::fs::metadata(e.path()).is_ok_and(|m| m.is_file());
        (is_output(&name, outputs) && !file).then(|| e.path())
    })
}

/// Removes the staging directories of `target` (beside it in `parent`, or inside it) that
/// processes no longer running left: an abort (an allocation the standard library could not
/// make) ends a run without its cleanup. A directory whose process id is alive, or reused by
/// another process, is left.
fn remove_stale_staging(target: &Path, parent: &Path) {
    let Some(name) = target.file_name().map(|n| n.to_string_lossy().into_owned()) else {
        return;
    };
    let beside = format!(".{name}.");
    let stale = |dir: &Path, pid_of: &dyn Fn(&str) -> Option<i32>| {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for e in entries.flatten() {
            let n = e.file_name().to_string_lossy().into_owned();
            let is_dir = e.file_type().is_ok_and(|t| t.is_dir());
            if let Some(pid) = pid_of(&n).filter(|&p| is_dir && !process_alive(p)) {
                log::warn!(
                    "{}: removing a staging directory left by process {pid}",
                    e.path().display()
                );
                let _ = std::fs::remove_dir_all(e.path());
            }
        }
    };
    stale(parent, &|n| {
        n.strip_prefix(beside.as_str())?
            .strip_suffix(".tmp")?
            .parse()
            .ok()
    });
    stale(target, &|n| {
        n.strip_prefix(".linercav-staging.")?.parse().ok()
    });
}

/// Whether process `pid` exists (signal 0: EPERM means it does, under another user).
fn process_alive(pid: i32) -> bool {
    if pid <= 0 {
        return true;
    }
    // SAFETY: kill with signal 0 sends nothing; it only checks that the process exists
    let r = unsafe { libc::kill(pid, 0) };
    r == 0 || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM)
}

/// Whether file name `name` is one of `outputs` (names, or patterns with one `*`).
fn is_output(name: &str, outputs: &[&str]) -> bool {
    outputs.iter().any(|o| match o.split_once('*') {
        Some((pre, suf)) => {
            name.len() >= pre.len() + suf.len() && name.starts_with(pre) && name.ends_with(suf)
        }
        None => name == *o,
    })
}

/// Checks, before any work, that output directory `dir` is a directory (or missing) and
/// holds no directory or other non-file under a name the command writes (`outputs`: names,
/// or patterns with one `*`), so such a clash stops the command at once, not after its runs.
pub fn check_output_names(dir: &Path, outputs: &[&str]) -> Result<(), WriteError> {
    if dir.exists() && !dir.is_dir() {
        return Err(WriteError {
            path: dir.to_path_buf(),
            source: std::io::Error::new(
                std::io::ErrorKind::AlreadyExists,
                "exists and is not a directory",
            ),
        });
    }
    match taken_output(dir, outputs) {
        Some(taken) => Err(WriteError {
            path: taken,
            source: std::io::Error::new(
                std::io::ErrorKind::AlreadyExists,
                "exists and is not a file, and the command writes an output of that name: remove or rename it",
            ),
        }),
        None => Ok(()),
    }
}

/// Output directories made for a command (the missing ones of a path): removed again, when
/// still empty, if the command fails (dropped without [`NewDirs::keep`]) or is stopped by a
/// signal, so a failed run leaves no empty directory behind. Only empty directories are ever
/// removed: a part directory that other shards wrote into stays.
pub struct NewDirs {
    made: Vec<PathBuf>,
}

impl NewDirs {
    /// Creates `dir` and its missing parents.
    pub fn create(dir: &Path) -> Result<Self, WriteError> {
        let missing: Vec<PathBuf> = dir
            .ancestors()
            .filter(|a| !a.as_os_str().is_empty())
            .take_while(|a| std::fs::symlink_metadata(a).is_err())
            .map(Path::to_path_buf)
            .collect();
        let mut made = Vec::new();
        let mut registry = lock(&NEW_DIRS);
        for d in missing.iter().rev() {
            match std::fs::create_dir(d) {
                Ok(()) => {
                    registry.push(d.clone());
                    made.push(d.clone());
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && d.is_dir() => {}
                Err(source) => {
                    drop(registry);
                    drop(Self { made });
                    return Err(WriteError {
                        path: d.clone(),
                        source,
                    });
                }
            }
        }
        Ok(Self { made })
    }

    /// The outputs are written: the directories stay.
    pub fn keep(mut self) {
        let made = std::mem::take(&mut self.made);
        lock(&NEW_DIRS).retain(|d| !made.contains(d));
    }
}

impl Drop for NewDirs {
    fn drop(&mut self) {
        let mut registry = lock(&NEW_DIRS);
        for d in self.made.iter().rev() {
            let _ = std::fs::remove_dir(d);
            registry.retain(|x| x != d);
        }
    }
}

/// A set of output files written all-or-nothing: the command writes into [`OutputDir::path`]
/// (a temporary directory), and [`OutputDir::commit`] moves the files into the target
/// directory only when all are written. When the target does not exist the staging directory
/// is made beside it and renamed onto it (one atomic step); when it exists (a `reports/` with
/// its own README) the files are renamed into it one by one while the signal handler waits.
/// Before anything moves, every target name is checked: one taken by a directory or another
/// non-file stops the commit with nothing moved. Dropped without a commit, the staging
/// directory is removed.
pub struct OutputDir {
    target: PathBuf,
    staging: PathBuf,
    committed: bool,
    /// The names the command writes (for the files an earlier run left: [`OutputDir::commit`]).
    outputs: Vec<String>,
}

impl OutputDir {
    /// Creates the staging directory for `target` (and the target's parent directories), so an
    /// unwritable output is found before any work starts; so is a name the command writes
    /// (`outputs`: file names, or patterns with one `*` such as `sweep_*.png`) that the target
    /// holds as a directory or another non-file.
    pub fn create(target: &Path, outputs: &[&str]) -> Result<Self, WriteError> {
        let fail = |source| WriteError {
            path: target.to_path_buf(),
            source,
        };
        check_output_names(target, outputs)?;
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        if let Some(file) = parent.ancestors().find(|a| a.exists() && !a.is_dir()) {
            return Err(fail(std::io::Error::new(
                std::io::ErrorKind::NotADirectory,
                format!("{} is a file, not a directory", file.display()),
            )));
        }
        std::fs::create_dir_all(&parent).map_err(fail)?;
        remove_stale_staging(target, &parent);
        let staging = if target.is_dir() {
            target.join(format!(".linercav-staging.{}", std::process::id()))
        } else {
            temp_path(target)
        };
        let _ = std::fs::remove_dir_all(&staging);
        make_registered(&staging, |p| std::fs::create_dir(p)).map_err(fail)?;
        Ok(Self {
            target: target.to_path_buf(),
            staging,
            committed: false,
            outputs: outputs.iter().map(|o| o.to_string()).collect(),
        })
    }

    /// Where the files are written until the commit.
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// The final path of a file written at `staged` (inside [`OutputDir::path`]).
    pub fn final_path(&self, staged: &Path) -> PathBuf {
        match staged.strip_prefix(&self.staging) {
            Ok(rel) => self.target.join(rel),
            Err(_) => staged.to_path_buf(),
        }
    }

    /// Moves the staged files into place (see the type's documentation).
    pub fn commit(mut self) -> Result<(), WriteError> {
        let fail = |path: &Path, source| WriteError {
            path: path.to_path_buf(),
            source,
        };
        let _moving = lock(&COMMITTING);
        if !self.target.exists() {
            std::fs::rename(&self.staging, &self.target).map_err(|e| fail(&self.target, e))?;
            unregister(&self.staging);
            self.committed = true;
            return Ok(());
        }
        let mut names = Vec::new();
        for entry in std::fs::read_dir(&self.staging).map_err(|e| fail(&self.staging, e))? {
            let entry = entry.map_err(|e| fail(&self.staging, e))?;
            let to = self.target.join(entry.file_name());
            if let Ok(meta) = std::fs::symlink_metadata(&to) {
                if !meta.is_file() {
                    return Err(fail(
                        &to,
                        std::io::Error::new(
                            std::io::ErrorKind::AlreadyExists,
                            "the name is taken by a directory or another non-file; nothing was written",
                        ),
                    ));
                }
            }
            names.push((entry.path(), to));
        }
        for (from, to) in &names {
            std::fs::rename(from, to).map_err(|e| fail(to, e))?;
        }
        let _ = std::fs::remove_dir(&self.staging);
        unregister(&self.staging);
        self.committed = true;
        self.warn_of_older_outputs(&names);
        Ok(())
    }

    /// Warns of the files of the target directory that this command writes by name (its exact
    /// names, not its patterns such as `*.png`, which other commands' files match) but this run
    /// did not (`written`): an earlier run's `--maps` or sampled sweep, which would read as
    /// this run's. They are left in place.
    fn warn_of_older_outputs(&self, written: &[(PathBuf, PathBuf)]) {
        let Ok(entries) = std::fs::read_dir(&self.target) else {
            return;
        };
        let mut older: Vec<String> = entries
            .flatten()
            .filter(|e| e.file_type().is_ok_and(|t| t.is_file()))
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| self.outputs.iter().any(|o| !o.contains('*') && o == n))
            .filter(|n| {
                !written
                    .iter()
                    .any(|(_, to)| to.file_name().is_some_and(|f| f == n.as_str()))
            })
            .collect();
        if !older.is_empty() {
            older.sort();
            log::warn!(
                "{}: {} not written by this run (an earlier run's)",
                self.target.display(),
                older.join(", ")
            );
        }
    }
}

impl Drop for OutputDir {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.staging);
            unregister(&self.staging);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Regression (session 70's hostile sweep): an aborted run's staging directory stayed
    /// beside its output (`.fo_x.PID.tmp`) through later runs; the next output directory made
    /// there removes those of processes no longer running, and keeps this process's own.
    #[test]
    fn regression_a_dead_run_s_staging_is_removed_by_the_next() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out");
        let dead = dir.path().join(".out.999999999.tmp");
        let ours = dir.path().join(format!(".out.{}.tmp", std::process::id()));
        let other = dir.path().join(".other.999999999.tmp");
        for d in [&dead, &ours, &other] {
            std::fs::create_dir(d).unwrap();
        }
        remove_stale_staging(&target, dir.path());
        assert!(!dead.exists(), "a dead process's staging is removed");
        assert!(
            ours.exists() && other.exists(),
            "live or unrelated ones stay"
        );
    }
}
