//! Output files written whole or not at all.
//!
//! A file servobus writes (a log, a plot, a motion, a calibration) goes to a
//! temporary file beside its target and is renamed over the target only
//! once it is complete and on disk ([`AtomicFile::commit`]). Until then an
//! existing file is untouched; a file not committed (an error, a refused
//! run, a panic) has its temporary removed when it is dropped. Only a
//! process killed outright (SIGKILL, power loss) can leave a temporary
//! behind, and then the target is still the old file, whole. Targets that
//! are not regular files are written in place (see [`AtomicFile`]).

use std::fs::{self, File, OpenOptions, Permissions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};

/// Why an output file could not be written; every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The path names a directory, not a file.
    #[error("{0} is a directory, not a file")]
    IsDirectory(PathBuf),
    /// The directory the file would be written in does not exist.
    #[error("{path}: the directory {dir} does not exist")]
    NoDirectory {
        /// The file to write.
        path: PathBuf,
        /// Its directory.
        dir: PathBuf,
    },
    /// The file exists and is read-only: it is not replaced.
    #[error("{0} is read-only")]
    ReadOnly(PathBuf),
    /// Creating, writing or syncing the file (or its temporary) failed.
    #[error("cannot write {path}: {source}")]
    Write {
        /// The file to write.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: io::Error,
    },
    /// The complete new file could not be renamed over the target (which is
    /// left as it was).
    #[error("cannot replace {path} with its new version: {source}")]
    Replace {
        /// The file to write.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: io::Error,
    },
}

impl OutputError {
    /// The file that could not be written.
    pub fn path(&self) -> &Path {
        match self {
            OutputError::IsDirectory(p) | OutputError::ReadOnly(p) => p,
            OutputError::NoDirectory { path, .. }
            | OutputError::Write { path, .. }
            | OutputError::Replace { path, .. } => path,
        }
    }

    /// Whether the path itself cannot be an output (a directory, a missing
    /// directory, a read-only file), as opposed to a write that failed: the
    /// former is the caller's input to correct.
    pub fn is_bad_path(&self) -> bool {
        matches!(
            self,
            OutputError::IsDirectory(_)
                | OutputError::NoDirectory { .. }
                | OutputError::ReadOnly(_)
        )
    }
}

/// Where the bytes for a target go.
enum Plan {
    /// Not a regular file: written in place.
    Direct,
    /// A regular file (existing or not) replaced by a rename: `dest` is the
    /// file renamed over (a symbolic link resolved), `keep` the permissions
    /// of the file it replaces.
    Replace {
        dest: PathBuf,
        keep: Option<Permissions>,
    },
}

/// Decides how `target` is written, refusing what cannot be.
fn plan(target: &Path) -> Result<Plan, OutputError> {
    let write_err = |source| OutputError::Write {
        path: target.to_path_buf(),
        source,
    };
    match fs::metadata(target) {
        Ok(m) if m.is_dir() => Err(OutputError::IsDirectory(target.to_path_buf())),
        Ok(m) if !m.is_file() => Ok(Plan::Direct),
        Ok(m) => {
            if m.permissions().readonly() {
                return Err(OutputError::ReadOnly(target.to_path_buf()));
            }
            let link = fs::symlink_metadata(target).map_err(write_err)?;
            let dest = if link.file_type().is_symlink() {
                fs::canonicalize(target).map_err(write_err)?
            } else {
                target.to_path_buf()
            };
            Ok(Plan::Replace {
                dest,
                keep: Some(m.permissions()),
            })
        }
        Err(e) if e.kind() == io::ErrorKind::NotFound => {
            let dir = directory_of(target);
            if !dir.is_dir() {
                return Err(OutputError::NoDirectory {
                    path: target.to_path_buf(),
                    dir: dir.to_path_buf(),
                });
            }
            Ok(Plan::Replace {
                dest: target.to_path_buf(),
                keep: None,
            })
        }
        Err(e) => Err(write_err(e)),
    }
}

/// The directory `path` is in (`.` for a bare name).
fn directory_of(path: &Path) -> &Path {
    path.parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
}

/// Distinguishes the temporaries of one process for one target.
static SERIAL: AtomicU32 = AtomicU32::new(0);

/// The base of the temporaries of `dest` (see [`temp::base`]).
fn temp_base(dest: &Path) -> io::Result<String> {
    let name = dest
        .file_name()
        .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "the path has no file name"))?;
    Ok(temp::base(&name.to_string_lossy()))
}

/// Creates a new temporary file beside `dest`: `.<name>.<pid>.tmp`, or
/// `.<name>.<pid>.<n>.tmp` when that one exists already (a long name cut,
/// see [`temp`]).
fn create_temp(dest: &Path) -> io::Result<(PathBuf, File)> {
    let base = temp_base(dest)?;
    let dir = directory_of(dest);
    let pid = std::process::id();
    let mut last = None;
    for attempt in 0..16 {
        let temp = if attempt == 0 {
            dir.join(format!("{base}.{pid}.tmp"))
        } else {
            let n = SERIAL.fetch_add(1, Ordering::Relaxed);
            dir.join(format!("{base}.{pid}.{n}.tmp"))
        };
        match OpenOptions::new().write(true).create_new(true).open(&temp) {
            Ok(file) => return Ok((temp, file)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => last = Some(e),
            Err(e) => return Err(e),
        }
    }
    Err(last.unwrap_or_else(|| io::Error::from(io::ErrorKind::AlreadyExists)))
}

/// Checks, without creating or changing `path`, that it could be written
/// by an [`AtomicFile`]: not a directory, not read-only, in a directory
/// that exists and in which a file can be created (one is created and
/// removed at once). A target that is not a regular file is not opened.
///
/// # Errors
/// The [`OutputError`] that [`AtomicFile::create`] would meet.
pub fn check_output(path: impl AsRef<Path>) -> Result<(), OutputError> {
    let target = path.as_ref();
    if let Plan::Replace { dest, .. } = plan(target)? {
        let (temp, file) = create_temp(&dest).map_err(|source| OutputError::Write {
            path: target.to_path_buf(),
            source,
        })?;
        drop(file);
        // Nothing to undo if the removal fails: the file is empty.
        let _ = fs::remove_file(temp);
    }
    Ok(())
}

/// Writes `bytes` to `path` whole: the old file, if any, stays as it was
/// until the new one is complete (see [`AtomicFile`]).
///
/// # Errors
/// An [`OutputError`] naming `path`; nothing is left of the attempt.
pub fn write_atomic(path: impl AsRef<Path>, bytes: &[u8]) -> Result<(), OutputError> {
    let mut file = AtomicFile::create(path)?;
    file.file
        .write_all(bytes)
        .map_err(|source| file.write_error(source))?;
    file.commit()
}

/// A file written to a temporary beside its target and renamed over it by
/// [`commit`](AtomicFile::commit); dropped without a commit, it removes its
/// temporary and leaves the target untouched.
///
/// The temporary is `.<name>.<pid>.tmp` in the target's directory (so that
/// the rename stays on one file system; a name too long for that is cut and
/// hashed, so the temporary's name is legal whenever the target's is).
/// Temporaries of the same target that a killed run left (their process
/// no longer runs) are removed when it is created. A target that is not a regular
/// file (`/dev/stdout`, `/dev/null`, a FIFO, a terminal) is written in
/// place instead, as nothing can be renamed over it: a failed write may
/// leave part of the output there ([`is_direct`](AtomicFile::is_direct)). A
/// symbolic link to a regular file is followed (the file is replaced, the
/// link stays); a replaced file keeps its permission bits; a directory or a
/// read-only file is never a target.
///
/// Its [`Write`] errors carry an [`OutputError::Write`] naming the target.
///
/// ```
/// use std::io::Write;
/// use servobus_io::AtomicFile;
///
/// let dir = std::env::temp_dir().join(format!("atomic-doc-{}", std::process::id()));
/// std::fs::create_dir_all(&dir).unwrap();
/// let path = dir.join("log.csv");
/// std::fs::write(&path, "old").unwrap();
///
/// let mut file = AtomicFile::create(&path).unwrap();
/// file.write_all(b"new").unwrap();
/// assert_eq!(std::fs::read_to_string(&path).unwrap(), "old");
/// file.commit().unwrap();
/// assert_eq!(std::fs::read_to_string(&path).unwrap(), "new");
/// # std::fs::remove_dir_all(&dir).unwrap();
/// ```
#[derive(Debug)]
pub struct AtomicFile {
    /// The path as given (named in errors).
    target: PathBuf,
    /// The file renamed over; `None` for a target written directly.
    dest: Option<PathBuf>,
    /// The temporary while not committed; `None` once committed, and for a
    /// target written directly.
    temp: Option<PathBuf>,
    file: File,
}

impl AtomicFile {
    /// Starts writing `path`: creates its temporary (or, for a target that
    /// is not a regular file, opens it for writing).
    ///
    /// # Errors
    /// [`OutputError::IsDirectory`], [`OutputError::ReadOnly`] or
    /// [`OutputError::NoDirectory`] for a path that cannot be a target;
    /// [`OutputError::Write`] when the temporary cannot be created.
    pub fn create(path: impl AsRef<Path>) -> Result<Self, OutputError> {
        let target = path.as_ref().to_path_buf();
        let write_err = |source| OutputError::Write {
            path: target.clone(),
            source,
        };
        match plan(&target)? {
            Plan::Direct => {
                let file = OpenOptions::new()
                    .write(true)
                    .open(&target)
                    .map_err(write_err)?;
                Ok(AtomicFile {
                    target,
                    dest: None,
                    temp: None,
                    file,
                })
            }
            Plan::Replace { dest, keep } => {
                // What killed runs left of this target goes first.
                if let Ok(base) = temp_base(&dest) {
                    temp::remove_stale(directory_of(&dest), &base);
                }
                let (temp, file) = create_temp(&dest).map_err(write_err)?;
                let atomic = AtomicFile {
                    target,
                    dest: Some(dest),
                    temp: Some(temp),
                    file,
                };
                if let (Some(keep), Some(temp)) = (keep, &atomic.temp) {
                    if let Err(e) = fs::set_permissions(temp, keep) {
                        // Dropping `atomic` removes the temporary.
                        return Err(atomic.write_error(e));
                    }
                }
                Ok(atomic)
            }
        }
    }

    /// The target, as given to [`create`](AtomicFile::create).
    pub fn path(&self) -> &Path {
        &self.target
    }

    /// Whether the target is written in place (not a regular file), so
    /// that a failed write may leave part of the output in it.
    pub fn is_direct(&self) -> bool {
        self.dest.is_none()
    }

    /// Makes the written bytes the target: syncs them to disk and renames
    /// the temporary over the target (a target written directly is only
    /// flushed).
    ///
    /// # Errors
    /// [`OutputError::Write`] when the bytes cannot be synced,
    /// [`OutputError::Replace`] when the rename fails; either way the target
    /// is as it was and the temporary is removed.
    pub fn commit(mut self) -> Result<(), OutputError> {
        self.file.flush().map_err(|e| self.write_error(e))?;
        let (Some(dest), Some(temp)) = (self.dest.clone(), self.temp.clone()) else {
            return Ok(());
        };
        self.file.sync_all().map_err(|e| self.write_error(e))?;
        fs::rename(&temp, &dest).map_err(|source| OutputError::Replace {
            path: self.target.clone(),
            source,
        })?;
        self.temp = None;
        // The rename itself reaches the disk with the directory; a failure
        // here loses nothing that was there before, so it is not an error.
        if let Ok(dir) = File::open(directory_of(&dest)) {
            let _ = dir.sync_all();
        }
        Ok(())
    }

    /// `source` as a write error naming the target.
    fn write_error(&self, source: io::Error) -> OutputError {
        OutputError::Write {
            path: self.target.clone(),
            source,
        }
    }

    /// `source` as an I/O error whose message names the target.
    fn io_error(&self, source: io::Error) -> io::Error {
        if source.kind() == io::ErrorKind::Interrupted {
            return source; // retried by the caller, never shown
        }
        io::Error::new(source.kind(), self.write_error(source))
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.file.write(buf).map_err(|e| self.io_error(e))
    }

    fn flush(&mut self) -> io::Result<()> {
        self.file.flush().map_err(|e| self.io_error(e))
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if let Some(temp) = self.temp.take() {
            // Not committed: the target keeps what it had.
            let _ = fs::remove_file(temp);
        }
    }
}

mod temp;

#[cfg(test)]
mod tests;
