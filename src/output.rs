//! Writing files, the bottom layer every writer uses: CSV, JSON and bytes, each
//! written to a temporary file in the destination folder and renamed into place,
//! so an interrupted run never leaves a half-written result (DESIGN.md,
//! conventions); a file a writer streams (a video) the same way
//! ([`write_through_temporary`]).
//!
//! A whole output folder (one experiment) is written the same way by
//! [`write_folder`]: into a fresh staging folder beside it, then renamed into place,
//! under an advisory lock ([`OutputLock`]) so two runs never write one folder.
//! Files and folders get the permissions the user's umask allows (0666 and 0777
//! masked), like any file a shell command creates.

use std::collections::BTreeSet;
use std::fs::Permissions;
use std::io::Write;
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};

use serde::Serialize;

/// Errors while writing files; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// File-system failure.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file being written.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// Serialisation failure.
    #[error("cannot serialise {path}: {reason}")]
    Serialise {
        /// The file being written.
        path: PathBuf,
        /// Why.
        reason: String,
    },
    /// An output folder whose path is taken by a file.
    #[error("cannot write into {path}: it is a file, not a folder (give another output path)")]
    NotAFolder {
        /// The path that should have been a folder.
        path: PathBuf,
    },
    /// Another run holds the output folder's lock.
    #[error(
        "{path} is being written by another eulerdisk run (lock {lock} is held); \
         wait for it or give another output folder"
    )]
    Locked {
        /// The output folder.
        path: PathBuf,
        /// The lock file.
        lock: PathBuf,
    },
}

pub(crate) fn io_error(path: &Path) -> impl FnOnce(std::io::Error) -> OutputError + '_ {
    move |source| OutputError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// The folder a path lives in (`.` for a bare file name).
fn parent_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// Checks that `dir` can be an output folder: neither it nor a folder above it is
/// a file (checked before work starts, so the user hears it at once).
///
/// # Errors
/// `NotAFolder` naming the file in the way.
pub fn check_folder(dir: &Path) -> Result<(), OutputError> {
    match dir.ancestors().find(|a| a.is_file()) {
        Some(file) => Err(OutputError::NotAFolder {
            path: file.to_path_buf(),
        }),
        None => Ok(()),
    }
}

/// Creates `dir` and its parents; a file in the way is named as such (not "File
/// exists").
///
/// # Errors
/// `NotAFolder` when `dir` or one of its ancestors is a file; `Io` otherwise.
pub fn create_folder(dir: &Path) -> Result<(), OutputError> {
    check_folder(dir)?;
    std::fs::create_dir_all(dir).map_err(io_error(dir))
}

/// Writes `bytes` to `path` atomically (temporary file in the same folder, then rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let dir = parent_of(path);
    create_folder(dir)?;
    let mut tmp = tempfile::Builder::new()
        .permissions(Permissions::from_mode(0o666))
        .tempfile_in(dir)
        .map_err(io_error(path))?;
    tmp.write_all(bytes).map_err(io_error(path))?;
    tmp.persist(path).map_err(|e| OutputError::Io {
        path: path.to_path_buf(),
        source: e.error,
    })?;
    Ok(())
}

/// Writes a value as pretty JSON, atomically.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), OutputError> {
    let text = serde_json::to_string_pretty(value).map_err(|e| OutputError::Serialise {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    write_atomic(path, text.as_bytes())
}

/// Writes records as CSV with a header row, atomically. An empty table still gets
/// its header (the field names of `T::default()`), so a reader always finds the
/// columns. Fields holding a comma, a quote or a line break are quoted.
pub fn write_csv<T: Serialize + Default>(path: &Path, records: &[T]) -> Result<(), OutputError> {
    let serialise = |e: csv::Error| OutputError::Serialise {
        path: path.to_path_buf(),
        reason: e.to_string(),
    };
    let mut writer = csv::Writer::from_writer(Vec::new());
    for record in records {
        writer.serialize(record).map_err(serialise)?;
    }
    if records.is_empty() {
        writer.serialize(T::default()).map_err(serialise)?;
    }
    let mut bytes = writer
        .into_inner()
        .map_err(|e| serialise(e.into_error().into()))?;
    if records.is_empty() {
        // Only the header line of the default row.
        let header_end = bytes.iter().position(|&b| b == b'\n').map_or(0, |i| i + 1);
        bytes.truncate(header_end);
    }
    write_atomic(path, &bytes)
}

/// Writes a table of text cells as CSV under `header`, atomically, quoting fields
/// that hold a comma, a quote or a line break.
///
/// # Errors
/// `Serialise` when a row's width differs from the header's; `Io` when the file
/// cannot be written.
pub fn write_csv_rows(
    path: &Path,
    header: &[&str],
    rows: &[Vec<String>],
) -> Result<(), OutputError> {
    let serialise = |e: csv::Error| OutputError::Serialise {
        path: path.to_path_buf(),
        reason: e.to_string(),
    };
    let mut writer = csv::Writer::from_writer(Vec::new());
    writer.write_record(header).map_err(serialise)?;
    for row in rows {
        writer.write_record(row).map_err(serialise)?;
    }
    let bytes = writer
        .into_inner()
        .map_err(|e| serialise(e.into_error().into()))?;
    write_atomic(path, &bytes)
}

/// PNG bytes of an image.
///
/// # Errors
/// The encoder failed (out of memory).
pub fn png_bytes(image: &image::RgbImage) -> Result<Vec<u8>, image::ImageError> {
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write_to(&mut bytes, image::ImageFormat::Png)?;
    Ok(bytes.into_inner())
}
/// Writes `path` through a temporary file beside it: `write` writes the temporary
/// path it is given (a video encoder that opens the file itself), which is then
/// renamed over `path`; on failure the temporary file is removed and `path` is left
/// as it was.
///
/// # Errors
/// Whatever `write` returns; `Io` when the folder cannot be made or the rename fails.
pub fn write_through_temporary<T, E: From<OutputError>>(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<T, E>,
) -> Result<T, E> {
    let dir = parent_of(path);
    create_folder(dir)?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let extension = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.partial-{}{extension}", std::process::id()));
    match write(&tmp) {
        Ok(value) => {
            std::fs::rename(&tmp, path).map_err(io_error(path))?;
            Ok(value)
        }
        Err(e) => {
            // Best effort: a half-written temporary file is useless.
            let _ = std::fs::remove_file(&tmp);
            Err(e)
        }
    }
}

/// An advisory lock (`flock`) on one output folder, held until dropped: whoever
/// holds it is the only eulerdisk run writing that folder. The lock belongs to the
/// folder's real path (symbolic links resolved), so two spellings of one folder
/// share one lock. The lock file `.NAME.lock` sits beside the folder, so the
/// folder itself can be replaced as a whole while the lock is held, and is removed
/// when the lock is released: a run leaves no lock file behind.
#[derive(Debug)]
pub struct OutputLock {
    folder: PathBuf,
    lock: PathBuf,
    file: std::fs::File,
}

impl OutputLock {
    /// Takes the lock on `folder`, or fails at once when another run holds it.
    ///
    /// # Errors
    /// `Locked` when another process holds it; `NotAFolder`/`Io` when the lock file
    /// cannot be created.
    pub fn acquire(folder: &Path) -> Result<Self, OutputError> {
        let real = real_path(folder)?;
        let lock = sibling(&real, "lock");
        loop {
            let file = std::fs::OpenOptions::new()
                .create(true)
                .truncate(false)
                .write(true)
                .open(&lock)
                .map_err(io_error(&lock))?;
            match file.try_lock() {
                Ok(()) => {}
                Err(std::fs::TryLockError::WouldBlock) => {
                    return Err(OutputError::Locked {
                        path: folder.to_path_buf(),
                        lock,
                    });
                }
                Err(std::fs::TryLockError::Error(e)) => return Err(io_error(&lock)(e)),
            }
            // The holder before us removes the file as it lets go: a lock taken on
            // a removed file guards nothing, so take the file now at the path.
            if same_file(&file, &lock) {
                return Ok(OutputLock {
                    folder: folder.to_path_buf(),
                    lock,
                    file,
                });
            }
        }
    }

    /// The locked folder.
    pub fn folder(&self) -> &Path {
        &self.folder
    }
}

impl Drop for OutputLock {
    /// Removes the lock file while still holding the lock (see [`OutputLock::acquire`]).
    fn drop(&mut self) {
        if same_file(&self.file, &self.lock) {
            // Best effort: a lock file left behind is removed by the next run.
            let _ = std::fs::remove_file(&self.lock);
        }
    }
}

/// Whether the open `file` is the file now at `path`.
fn same_file(file: &std::fs::File, path: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (file.metadata(), std::fs::metadata(path)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

/// `path` with every symbolic link resolved: the folder itself when it exists,
/// else its parent (created if missing) and its name.
fn real_path(path: &Path) -> Result<PathBuf, OutputError> {
    check_folder(path)?;
    if let Ok(real) = path.canonicalize() {
        return Ok(real);
    }
    let parent = parent_of(path);
    create_folder(parent)?;
    let real_parent = parent.canonicalize().map_err(io_error(parent))?;
    Ok(match path.file_name() {
        Some(name) => real_parent.join(name),
        None => real_parent,
    })
}

/// `.NAME.WHAT` beside `path` (hidden, so a study never takes it for footage).
fn sibling(path: &Path, what: &str) -> PathBuf {
    let name = path
        .file_name()
        .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
    parent_of(path).join(format!(".{name}.{what}"))
}

/// `NAME` of what a run writing folder `NAME` keeps beside it (given without its
/// leading dot): its lock file `NAME.lock`, its staging and replaced folders
/// `NAME.staging-…`, `NAME.replaced-…` ([`write_folder`]).
fn leftover_owner(hidden: &str) -> Option<&str> {
    hidden.strip_suffix(".lock").or_else(|| {
        [".staging-", ".replaced-"]
            .iter()
            .find_map(|kind| hidden.rfind(kind).map(|i| &hidden[..i]))
    })
}

/// Removes, below `dir` (itself included, hidden folders excepted), the lock
/// files, staging and replaced folders that killed runs left: those of every
/// folder whose lock is free (a live run holds the lock of what it writes, so its
/// files stay). Best effort, like a cleanup.
pub fn remove_stale(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut owners = BTreeSet::new();
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        match name.strip_prefix('.') {
            Some(hidden) => {
                if let Some(owner) = leftover_owner(hidden) {
                    owners.insert(owner.to_string());
                }
            }
            None if entry.path().is_dir() => remove_stale(&entry.path()),
            None => {}
        }
    }
    for owner in owners {
        let dest = dir.join(&owner);
        if let Ok(lock) = OutputLock::acquire(&dest) {
            remove_leftovers(
                dir,
                &[&sibling(&dest, "staging-"), &sibling(&dest, "replaced-")],
            );
            drop(lock);
        }
    }
}

/// Copies the folder `from` into the existing folder `to`, file by file: a hard
/// link where the file system allows it (the two folders then share the bytes),
/// else a copy.
///
/// # Errors
/// `Io` naming the file that could not be read or written.
pub fn copy_tree(from: &Path, to: &Path) -> Result<(), OutputError> {
    for entry in std::fs::read_dir(from).map_err(io_error(from))? {
        let source = entry.map_err(io_error(from))?.path();
        let Some(name) = source.file_name() else {
            continue;
        };
        let target = to.join(name);
        if source.is_dir() {
            create_folder(&target)?;
            copy_tree(&source, &target)?;
        } else if std::fs::hard_link(&source, &target).is_err() {
            std::fs::copy(&source, &target).map_err(io_error(&source))?;
        }
    }
    Ok(())
}

/// Writes a whole output folder atomically: `fill` writes into a fresh staging
/// folder beside `dest`, which then replaces `dest` by renames, so `dest` holds
/// either the previous complete run or this one, never a mixture (a failed `fill`
/// leaves the previous folder untouched). Takes `dest`'s [`OutputLock`] for the
/// duration, and first removes staging folders that a killed run left behind.
///
/// # Errors
/// `Locked` when another run writes `dest`; whatever `fill` returns; `Io` when the
/// renames fail.
pub fn write_folder<T, E: From<OutputError>>(
    dest: &Path,
    fill: impl FnOnce(&Path) -> Result<T, E>,
) -> Result<T, E> {
    check_folder(dest)?;
    let _lock = OutputLock::acquire(dest)?;
    let parent = parent_of(dest);
    let staging_prefix = sibling(dest, "staging-");
    let replaced_prefix = sibling(dest, "replaced-");
    remove_leftovers(parent, &[&staging_prefix, &replaced_prefix]);
    let file_name = |p: &Path| {
        p.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    let staging = tempfile::Builder::new()
        .prefix(&file_name(&staging_prefix))
        .permissions(Permissions::from_mode(0o777))
        .tempdir_in(parent)
        .map_err(|e| E::from(io_error(dest)(e)))?;
    let value = fill(staging.path())?;
    let staged = staging.keep();
    let rename = |from: &Path, to: &Path| std::fs::rename(from, to).map_err(io_error(dest));
    if dest.exists() {
        let old = PathBuf::from(format!(
            "{}{}",
            replaced_prefix.display(),
            std::process::id()
        ));
        rename(dest, &old)?;
        rename(&staged, dest)?;
        std::fs::remove_dir_all(&old).map_err(io_error(&old))?;
    } else {
        rename(&staged, dest)?;
    }
    Ok(value)
}

/// Best effort: staging and replaced folders of a killed run (the caller holds the
/// lock, so no live run owns them).
fn remove_leftovers(parent: &Path, prefixes: &[&Path]) {
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if prefixes
            .iter()
            .any(|p| path.to_string_lossy().starts_with(&*p.to_string_lossy()))
        {
            let _ = std::fs::remove_dir_all(&path);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 13.7: outputs written through temporary files were 0600 whatever the
    /// umask; they now get 0666 minus the umask like the plots (the test process's
    /// umask is read back from a file it creates the ordinary way).
    #[test]
    fn outputs_get_the_umask_permissions() {
        let dir = tempfile::tempdir().unwrap();
        let plain = dir.path().join("plain");
        std::fs::write(&plain, b"x").unwrap();
        let expected = plain.metadata().unwrap().permissions().mode() & 0o777;
        let json = dir.path().join("a.json");
        write_json(&json, &1).unwrap();
        assert_eq!(
            json.metadata().unwrap().permissions().mode() & 0o777,
            expected
        );
        let folder = dir.path().join("exp");
        write_folder::<_, OutputError>(&folder, |d| write_json(&d.join("r.json"), &2)).unwrap();
        let mode = folder.metadata().unwrap().permissions().mode() & 0o777;
        assert_eq!(
            mode,
            expected | ((expected & 0o444) >> 2),
            "folders get x where r"
        );
    }

    /// Issue 73.10: a table with no rows was a 0-byte file; it now holds its header,
    /// and a cell with a comma or a quote reads back whole.
    #[test]
    fn a_csv_table_always_has_its_header() {
        #[derive(Serialize, Default)]
        struct Row {
            index: usize,
            reason: String,
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("flags.csv");
        write_csv::<Row>(&path, &[]).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "index,reason\n");
        let rows = [Row {
            index: 3,
            reason: "a \"jump\", then more".into(),
        }];
        write_csv(&path, &rows).unwrap();
        let mut reader = csv::Reader::from_path(&path).unwrap();
        let record = reader.records().next().unwrap().unwrap();
        assert_eq!(&record[1], rows[0].reason);
    }

    /// Issue 13.6: an output path that is a file was reported as "File exists (os
    /// error 17)"; the message now says it is a file.
    #[test]
    fn an_output_path_that_is_a_file_is_named_as_such() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("out");
        std::fs::write(&file, b"x").unwrap();
        let err = write_json(&file.join("result.json"), &1)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("it is a file") && !err.contains("os error"),
            "{err}"
        );
        let err = write_folder::<_, OutputError>(&file, |_| Ok(()))
            .unwrap_err()
            .to_string();
        assert!(err.contains("it is a file"), "{err}");
    }

    /// Issue 13.1: a folder holds one complete run or the previous one. A run that
    /// fails half-way leaves the previous folder as it was; a complete run replaces
    /// it as a whole (no file of the old run survives beside the new ones).
    #[test]
    fn a_folder_holds_one_complete_run_or_the_previous_one() {
        let dir = tempfile::tempdir().unwrap();
        let dest = dir.path().join("exp");
        write_folder::<_, OutputError>(&dest, |d| {
            write_json(&d.join("result.json"), &"old")?;
            write_json(&d.join("old-only.json"), &"old")
        })
        .unwrap();
        let failed = write_folder::<(), OutputError>(&dest, |d| {
            write_json(&d.join("frames.csv"), &"new")?;
            Err(OutputError::Serialise {
                path: d.join("frames.csv"),
                reason: "disk full".into(),
            })
        });
        assert!(failed.is_err());
        let read = |f: &str| std::fs::read_to_string(dest.join(f)).ok();
        assert_eq!(read("result.json").as_deref(), Some("\"old\""));
        assert_eq!(read("frames.csv"), None, "nothing of the failed run");
        write_folder::<_, OutputError>(&dest, |d| write_json(&d.join("result.json"), &"new"))
            .unwrap();
        assert_eq!(read("result.json").as_deref(), Some("\"new\""));
        assert_eq!(read("old-only.json"), None, "nothing of the old run");
        let names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names, ["exp"], "no staging folder or lock file left behind");
    }

    /// Issue 73.5: the lock was taken on the path as spelled, so `-o out` and
    /// `-o link-to-out` wrote one folder at once. The lock belongs to the real path,
    /// and no lock file is left once it is released.
    #[test]
    fn a_folder_reached_through_a_link_shares_its_lock() {
        let dir = tempfile::tempdir().unwrap();
        let real = dir.path().join("out");
        std::fs::create_dir(&real).unwrap();
        let link = dir.path().join("link-to-out");
        std::os::unix::fs::symlink(&real, &link).unwrap();
        let held = OutputLock::acquire(&real).unwrap();
        let err = OutputLock::acquire(&link).unwrap_err().to_string();
        assert!(err.contains("another eulerdisk run"), "{err}");
        let err = OutputLock::acquire(&dir.path().join("./link-to-out/../out"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("another eulerdisk run"), "{err}");
        drop(held);
        let again = OutputLock::acquire(&link).unwrap();
        drop(again);
        let mut names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["link-to-out", "out"], "no lock file left");
    }

    /// Issue 13.1: two runs cannot write one folder at once; the second is told who
    /// holds it.
    #[test]
    fn a_held_lock_refuses_a_second_writer() {
        let dir = tempfile::tempdir().unwrap();
        let dest = dir.path().join("exp");
        let held = OutputLock::acquire(&dest).unwrap();
        let err = write_folder::<_, OutputError>(&dest, |_| Ok(()))
            .unwrap_err()
            .to_string();
        assert!(err.contains("another eulerdisk run"), "{err}");
        drop(held);
        write_folder::<_, OutputError>(&dest, |_| Ok(())).unwrap();
    }
}
