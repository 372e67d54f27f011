//! Writing results: every file of a run is produced in memory first and then
//! written to a temporary name in the output directory and renamed, so an
//! error or a crash never leaves a half-written result.

pub mod plot;

use std::path::{Path, PathBuf};

use crate::spectrum::Spectrum;

/// Failure to write outputs.
#[derive(Debug, thiserror::Error)]
#[error("cannot write {path}: {source}")]
pub struct OutputError {
    /// The file or directory.
    pub path: PathBuf,
    /// The I/O error.
    pub source: std::io::Error,
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

    /// Writes every file into `dir` (created if needed): each to
    /// `.<name>.tmp` first, then all renamed into place.
    pub fn write(&self, dir: &Path) -> Result<(), OutputError> {
        let err = |path: &Path| {
            let path = path.to_owned();
            move |source| OutputError { path, source }
        };
        std::fs::create_dir_all(dir).map_err(err(dir))?;
        let mut staged = Vec::with_capacity(self.files.len());
        for (name, contents) in &self.files {
            let tmp = dir.join(format!(".{name}.tmp"));
            if let Err(e) = std::fs::write(&tmp, contents) {
                for (t, _) in &staged {
                    let _ = std::fs::remove_file(t);
                }
                let _ = std::fs::remove_file(&tmp);
                return Err(err(&tmp)(e));
            }
            staged.push((tmp, dir.join(name)));
        }
        for (tmp, fin) in &staged {
            std::fs::rename(tmp, fin).map_err(err(fin))?;
        }
        Ok(())
    }
}

/// `spectrum.csv`: one finite eigenvalue a row with its frequency, damping
/// ratio and master-pair membership.
pub fn spectrum_csv(spectrum: &Spectrum, master_indices: &[(usize, usize)]) -> String {
    let mut s = String::from("index,re,im,abs,frequency,damping_ratio,master_pair\n");
    for (k, l) in spectrum.eigenvalues.iter().enumerate() {
        let master = master_indices
            .iter()
            .find(|(_, i)| k == *i || k == *i + 1)
            .map_or(String::new(), |(p, _)| p.to_string());
        let abs = l.norm();
        let zeta = if abs > 0.0 { -l.re / abs } else { 0.0 };
        s.push_str(&format!(
            "{},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{}\n",
            k + 1,
            l.re,
            l.im,
            abs,
            l.im.abs(),
            zeta,
            master
        ));
    }
    s
}
