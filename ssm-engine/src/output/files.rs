//! The files of a run, written as one set: into a fresh private directory
//! beside the output directory, then swapped into place with one rename.
//!
//! What this guarantees, for any number of concurrent runs into one `--out`
//! and for failures at any point: the output directory holds either the
//! complete old result set or the complete new one, never a mix and never a
//! stale file of an earlier scene; files are created with `O_EXCL` in a
//! directory only this run knows, so a link planted anywhere is never
//! followed; nothing is written outside `--out` and its temporary sibling.
//! A directory that is not an earlier set of the same kind (not empty, no
//! [`MARKER`], no `summary.json`; a run's result set, which has a
//! `summary.json`, against a model export, which has not) is never replaced,
//! and [`check_not_input`] keeps a run from writing over its own inputs.

use std::fs::{self, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// File that marks a directory as an `ssm-engine` result set.
pub const MARKER: &str = ".ssm-engine-output";

/// The file a run's result set has and a model export has not.
const SUMMARY: &str = "summary.json";

/// Failure to write outputs.
#[derive(Debug, thiserror::Error)]
#[error("cannot write {path}: {source}")]
pub struct OutputError {
    /// The file or directory.
    pub path: PathBuf,
    /// The I/O error.
    pub source: std::io::Error,
}

fn error(path: &Path, source: std::io::Error) -> OutputError {
    OutputError {
        path: path.to_owned(),
        source,
    }
}

fn refuse(path: &Path, why: &str) -> OutputError {
    error(path, std::io::Error::other(why.to_owned()))
}

/// An output directory that is, or holds, an input of the run.
#[derive(Debug, thiserror::Error)]
#[error("the output directory {} is or holds {}, an input of this run, which writing the results there would delete: choose another output directory (--out, or the DIR of export)", out.display(), input.display())]
pub struct InputInOutput {
    /// The output directory.
    pub out: PathBuf,
    /// The input it is or holds.
    pub input: PathBuf,
}

/// `Ok` when the output directory `out` is none of `inputs` and holds none
/// of them, comparing canonical paths (links resolved; a part of `out` that
/// does not exist yet is taken as written). Inputs that do not exist are
/// skipped: nothing of theirs can be deleted.
pub fn check_not_input(out: &Path, inputs: &[PathBuf]) -> Result<(), InputInOutput> {
    let out_canon = canonical_to_be(out);
    for input in inputs {
        if let Ok(c) = fs::canonicalize(input) {
            if c.starts_with(&out_canon) {
                return Err(InputInOutput {
                    out: out.to_owned(),
                    input: input.clone(),
                });
            }
        }
    }
    Ok(())
}

/// The canonical form of `path`, which may not exist yet: its longest
/// existing ancestor canonicalized, the rest appended (`..` and `.` in it
/// resolved as written).
fn canonical_to_be(path: &Path) -> PathBuf {
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_owned());
    let mut rest = Vec::new();
    let mut base = absolute.as_path();
    let mut canon = loop {
        if let Ok(c) = fs::canonicalize(base) {
            break c;
        }
        match (base.parent(), base.file_name()) {
            (Some(parent), Some(name)) => {
                rest.push(name.to_owned());
                base = parent;
            }
            _ => break base.to_owned(),
        }
    };
    for part in rest.iter().rev() {
        if part == ".." {
            canon.pop();
        } else if part != "." {
            canon.push(part);
        }
    }
    canon
}

/// The files of one run, written together by [`OutputSet::write`].
#[derive(Debug, Default, Clone)]
pub struct OutputSet {
    /// `(file name, contents)`.
    pub files: Vec<(String, Vec<u8>)>,
}

impl OutputSet {
    /// Adds a file.
    pub fn add(&mut self, name: &str, contents: impl Into<Vec<u8>>) {
        self.files.push((name.to_owned(), contents.into()));
    }

    /// The contents of `name`, if present.
    pub fn get(&self, name: &str) -> Option<&[u8]> {
        self.files
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, c)| c.as_slice())
    }

    /// Replaces the result set in `dir` by this one, atomically (see the
    /// module documentation); `dir` and its parents are created if needed.
    pub fn write(&self, dir: &Path) -> Result<(), OutputError> {
        for (name, _) in &self.files {
            if name.is_empty() || name.contains(['/', '\\']) || name.starts_with('.') {
                return Err(refuse(dir, &format!("invalid output file name '{name}'")));
            }
        }
        let dir_name = dir
            .file_name()
            .ok_or_else(|| refuse(dir, "the output directory needs a name (not '/' or '..')"))?
            .to_string_lossy()
            .into_owned();
        let parent = match dir.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_owned(),
            _ => PathBuf::from("."),
        };
        fs::create_dir_all(&parent).map_err(|e| error(&parent, e))?;
        check_replaceable(dir, self.is_result_set())?;
        let staging = parent.join(format!(".{dir_name}.tmp-{}", unique()));
        create_private_dir(&staging).map_err(|e| error(&staging, e))?;
        let filled = self.fill(&staging);
        let swapped = filled.and_then(|()| swap_into_place(&staging, dir, self.is_result_set()));
        // the staging directory now holds the old set, or the failed new one
        let _ = fs::remove_dir_all(&staging);
        swapped
    }

    /// Whether this is a run's result set (it has a `summary.json`), not a
    /// model export.
    fn is_result_set(&self) -> bool {
        self.get(SUMMARY).is_some()
    }

    /// Writes every file and the marker into the fresh directory `staging`.
    fn fill(&self, staging: &Path) -> Result<(), OutputError> {
        let marker = format!("written by ssm-engine {}\n", env!("CARGO_PKG_VERSION"));
        let all = self
            .files
            .iter()
            .map(|(n, c)| (n.as_str(), c.as_slice()))
            .chain([(MARKER, marker.as_bytes())]);
        for (name, contents) in all {
            let path = staging.join(name);
            let mut f = OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&path)
                .map_err(|e| error(&path, e))?;
            f.write_all(contents).map_err(|e| error(&path, e))?;
        }
        set_public(staging).map_err(|e| error(staging, e))
    }
}

/// A name no other run of this or another process uses.
fn unique() -> String {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos());
    format!(
        "{}-{nanos}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    )
}

#[cfg(unix)]
fn create_private_dir(path: &Path) -> std::io::Result<()> {
    use std::os::unix::fs::DirBuilderExt;
    fs::DirBuilder::new().mode(0o700).create(path)
}

#[cfg(not(unix))]
fn create_private_dir(path: &Path) -> std::io::Result<()> {
    fs::create_dir(path)
}

#[cfg(unix)]
fn set_public(path: &Path) -> std::io::Result<()> {
    use std::os::unix::fs::PermissionsExt;
    fs::set_permissions(path, fs::Permissions::from_mode(0o755))
}

#[cfg(not(unix))]
fn set_public(_path: &Path) -> std::io::Result<()> {
    Ok(())
}

/// `Ok` when `dir` does not exist, or is a real directory that is empty or an
/// earlier set of the same kind: a run's result set (`result_set`, it has a
/// `summary.json`) or a model export (the [`MARKER`] without a summary).
fn check_replaceable(dir: &Path, result_set: bool) -> Result<(), OutputError> {
    let meta = match fs::symlink_metadata(dir) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(error(dir, e)),
        Ok(m) => m,
    };
    if meta.file_type().is_symlink() {
        return Err(refuse(
            dir,
            "the output directory is a symbolic link; give the directory it points to as --out",
        ));
    }
    if !meta.is_dir() {
        return Err(refuse(
            dir,
            "exists and is not a directory; choose another output directory (--out, or the DIR of export)",
        ));
    }
    let mut entries = fs::read_dir(dir).map_err(|e| error(dir, e))?;
    let has =
        |name: &str| fs::symlink_metadata(dir.join(name)).is_ok_and(|m| m.file_type().is_file());
    if entries.next().is_none() {
        return Ok(());
    }
    let (summary, marker) = (has(SUMMARY), has(MARKER));
    if summary && !result_set {
        return Err(refuse(
            dir,
            "holds a run's result set (summary.json), not a model export; it is not replaced by an export: choose another DIR",
        ));
    }
    if marker && !summary && result_set {
        return Err(refuse(
            dir,
            "holds a model export (no summary.json), not a run's result set; it is not replaced by a run: choose another output directory",
        ));
    }
    if summary || marker {
        return Ok(());
    }
    Err(refuse(
        dir,
        "is not empty and holds no ssm-engine result set (or model export); it is not replaced: choose another output directory (--out, or the DIR of export)",
    ))
}

/// Puts the complete set in `staging` (a run's result set when `result_set`)
/// at `dir`; afterwards `staging` holds the
/// old set (or nothing).
fn swap_into_place(staging: &Path, dir: &Path, result_set: bool) -> Result<(), OutputError> {
    // a concurrent run may create or replace `dir` between our steps; each
    // attempt either completes a whole swap or changes nothing
    for _ in 0..8 {
        match fs::rename(staging, dir) {
            Ok(()) => return Ok(()),
            Err(e) if !dir_exists(dir) => return Err(error(dir, e)),
            Err(_) => {}
        }
        check_replaceable(dir, result_set)?;
        match exchange(staging, dir) {
            Ok(()) => return Ok(()),
            Err(e) if e.raw_os_error() == Some(libc::ENOENT) => continue,
            Err(e) if e.raw_os_error() == Some(libc::EINVAL) => {
                return replace_in_two_steps(staging, dir)
            }
            Err(e) => return Err(error(dir, e)),
        }
    }
    Err(refuse(
        dir,
        "kept changing under concurrent runs; the new result set was not placed",
    ))
}

fn dir_exists(dir: &Path) -> bool {
    fs::symlink_metadata(dir).is_ok_and(|m| m.is_dir())
}

/// Swaps two directories in one step (Linux `renameat2(RENAME_EXCHANGE)`).
#[cfg(target_os = "linux")]
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    use std::ffi::CString;
    use std::os::unix::ffi::OsStrExt;
    let ca = CString::new(a.as_os_str().as_bytes()).map_err(std::io::Error::other)?;
    let cb = CString::new(b.as_os_str().as_bytes()).map_err(std::io::Error::other)?;
    // SAFETY: both paths are valid NUL-terminated strings that outlive the call.
    let r = unsafe {
        libc::renameat2(
            libc::AT_FDCWD,
            ca.as_ptr(),
            libc::AT_FDCWD,
            cb.as_ptr(),
            libc::RENAME_EXCHANGE,
        )
    };
    if r == 0 {
        Ok(())
    } else {
        Err(std::io::Error::last_os_error())
    }
}

#[cfg(not(target_os = "linux"))]
fn exchange(_a: &Path, _b: &Path) -> std::io::Result<()> {
    Err(std::io::Error::from_raw_os_error(libc::EINVAL))
}

/// Without an exchange: the old set is moved aside, then the new one in. For
/// a moment `dir` is absent, but it never holds a mix.
fn replace_in_two_steps(staging: &Path, dir: &Path) -> Result<(), OutputError> {
    let mut aside = staging.as_os_str().to_owned();
    aside.push(".old");
    let aside = PathBuf::from(aside);
    fs::rename(dir, &aside).map_err(|e| error(dir, e))?;
    match fs::rename(staging, dir) {
        Ok(()) => {
            let _ = fs::remove_dir_all(&aside);
            Ok(())
        }
        Err(e) => {
            // put the old set back
            let _ = fs::rename(&aside, dir);
            Err(error(dir, e))
        }
    }
}
