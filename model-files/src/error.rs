//! What can be wrong with a model folder: every error names the file and,
//! where there is one, the line.

use std::path::PathBuf;

/// An error in one file of a model folder.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    /// The file could not be opened, read or written.
    #[error("{}: {source}", file.display())]
    Io {
        /// The file.
        file: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// A line of the file is wrong.
    #[error("{}, line {line}: {message}", file.display())]
    Line {
        /// The file.
        file: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong and what was expected.
        message: String,
    },
    /// The file as a whole is wrong (its size against the other files, a
    /// missing entry count).
    #[error("{}: {message}", file.display())]
    Content {
        /// The file.
        file: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The file is not a regular file, too large, or not text
    /// ([`crate::input`]).
    #[error(transparent)]
    Input(#[from] crate::input::InputError),
    /// A required file is missing.
    #[error("{}: required file missing ({what})", file.display())]
    Missing {
        /// The file that should be there.
        file: PathBuf,
        /// What it holds.
        what: &'static str,
    },
}

/// Why a model cannot be written in the file format.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The model is not in the mechanical form the files hold.
    #[error("model '{model}' cannot be written as files: {reason}")]
    Unsupported {
        /// Model name.
        model: String,
        /// What the format cannot hold, and what would.
        reason: String,
    },
    /// Writing a file failed.
    #[error(transparent)]
    File(#[from] FileError),
}
