//! Line-by-line reading of a text file with the line number at hand, so that
//! every parse error names its file and line; the files are streamed, never
//! held whole in memory.

use std::path::{Path, PathBuf};

use crate::error::FileError;
use crate::input::{excerpt, InputFile, InputReader, MODEL};

/// The longest line read (1 MiB): a file without line ends is an error, not
/// a buffer the size of the file.
pub(crate) const MAX_LINE: usize = 1 << 20;

/// Bytes read so far (over all files of a folder), for a progress display.
pub type Progress<'a> = dyn FnMut(u64) + 'a;

/// A text file read one line at a time.
pub(crate) struct LineReader<'p> {
    file: PathBuf,
    reader: InputReader,
    bytes: Vec<u8>,
    buf: String,
    line: usize,
    progress: &'p mut Progress<'p>,
}

impl<'p> LineReader<'p> {
    /// Opens `path` (a regular file within [`MODEL`], see [`crate::input`]).
    pub(crate) fn open(path: &Path, progress: &'p mut Progress<'_>) -> Result<Self, FileError> {
        let reader = InputFile::open(path, MODEL)?.into_reader()?;
        Ok(Self {
            file: path.to_owned(),
            reader,
            bytes: Vec::new(),
            buf: String::new(),
            line: 0,
            progress,
        })
    }

    /// The next line without its line end (`None` at the end of the file).
    /// A comment line (`%` or `#` first) that is not UTF-8 (a Latin-1 unit
    /// symbol, say) reads as an empty comment; any other such line is an error,
    /// as is a line longer than [`MAX_LINE`] bytes.
    pub(crate) fn next_line(&mut self) -> Result<Option<&str>, FileError> {
        self.bytes.clear();
        let n = self
            .reader
            .read_line(&mut self.bytes, MAX_LINE as u64 + 1)?;
        if n == 0 {
            return Ok(None);
        }
        self.line += 1;
        if n > MAX_LINE {
            return Err(self.error(format!("line longer than {MAX_LINE} bytes")));
        }
        (self.progress)(n as u64);
        self.buf.clear();
        match std::str::from_utf8(&self.bytes) {
            Ok(text) => self.buf.push_str(text),
            Err(_) => {
                let first = self.bytes.iter().find(|b| !b.is_ascii_whitespace());
                if !matches!(first, Some(b'%' | b'#')) {
                    return Err(self.error("not UTF-8 text"));
                }
                self.buf.push('%');
            }
        }
        Ok(Some(self.buf.trim_end_matches(['\n', '\r'])))
    }

    /// The next line that is neither blank nor a comment starting with one of
    /// `comments`.
    pub(crate) fn next_data(&mut self, comments: &[char]) -> Result<Option<&str>, FileError> {
        loop {
            // re-borrow per iteration: the returned line lives in self.buf
            let skip = match self.next_line()? {
                None => return Ok(None),
                Some(l) => {
                    let t = l.trim();
                    t.is_empty() || t.starts_with(comments)
                }
            };
            if !skip {
                return Ok(Some(self.buf.trim()));
            }
        }
    }

    /// An error at the current line.
    pub(crate) fn error(&self, message: impl Into<String>) -> FileError {
        FileError::Line {
            file: self.file.clone(),
            line: self.line,
            message: message.into(),
        }
    }

    /// An error about the whole file.
    pub(crate) fn content_error(&self, message: impl Into<String>) -> FileError {
        FileError::Content {
            file: self.file.clone(),
            message: message.into(),
        }
    }
}

/// A 1-based index `tok` in `1..=max`, returned 0-based.
pub(crate) fn index(tok: &str, max: usize, what: &str) -> Result<usize, String> {
    let i: usize = tok
        .parse()
        .map_err(|_| format!("{what} '{}' is not a positive integer", excerpt(tok)))?;
    if i == 0 || i > max {
        return Err(format!(
            "{what} {i} is outside 1..={max} (indices are 1-based)"
        ));
    }
    Ok(i - 1)
}

/// A finite real number.
pub(crate) fn value(tok: &str) -> Result<f64, String> {
    let x: f64 = tok
        .parse()
        .map_err(|_| format!("value '{}' is not a number", excerpt(tok)))?;
    if !x.is_finite() {
        return Err(format!("value '{}' is not finite", excerpt(tok)));
    }
    Ok(x)
}
