//! Opening a user's input file: the one layer through which every reader of
//! user files goes (scene files, `[data]` CSV, the files of a model folder,
//! the reference's checkpoint), so that they all refuse the same things the
//! same way.
//!
//! - Regular files only: a FIFO, a device, a directory or a socket (or a link
//!   to one) is an [`InputError::NotAFile`]. The path's metadata is looked at
//!   before opening (a device is never opened), the file is opened with
//!   `O_NONBLOCK` (a FIFO swapped in meanwhile does not block the open), and
//!   the decision is taken on the open handle's metadata (what is read is what
//!   was checked).
//! - A size limit per kind of file ([`Limit`]), checked on the handle before
//!   reading and again while reading (a file that grows is cut off with the
//!   same error, not read until memory runs out).
//! - A leading UTF-8 byte-order mark (a CSV saved by a spreadsheet) is
//!   skipped; line numbers count from the file's first line.
//! - Messages quote user text only through [`excerpt`]: at most
//!   [`EXCERPT_CHARS`] characters, control characters escaped.
//!
//! It lives in this crate, the lowest one that reads user files, so that the
//! engine (which depends on it) uses the same layer without a new crate.

use std::fs::{File, Metadata, OpenOptions};
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

/// The UTF-8 byte-order mark.
const BOM: &[u8] = b"\xEF\xBB\xBF";

/// Characters of user text a message quotes at most.
pub const EXCERPT_CHARS: usize = 60;

/// The largest size read of one kind of file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limit {
    /// Bytes.
    pub bytes: u64,
    /// The kind of file, for messages (`"a scene file"`).
    pub what: &'static str,
}

/// Scene files: 16 MiB.
pub const SCENE: Limit = Limit {
    bytes: 16 << 20,
    what: "a scene file",
};

/// `[data]` CSV files, read whole: 1 GiB.
pub const DATA: Limit = Limit {
    bytes: 1 << 30,
    what: "a [data] file",
};

/// Files of a model folder, streamed line by line: 64 GiB.
pub const MODEL: Limit = Limit {
    bytes: 64 << 30,
    what: "a model file",
};

/// Why an input file is not read.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    /// The system refused to open or read it.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// It is not a regular file.
    #[error("{}: is {what}, not a regular file; inputs are read from regular files only", path.display())]
    NotAFile {
        /// The path.
        path: PathBuf,
        /// What it is (`a FIFO`, `a directory`, ...).
        what: &'static str,
    },
    /// It is larger than the limit for its kind.
    #[error("{}: {size} bytes, more than {} allows ({} bytes, {} MiB)", path.display(), limit.what, limit.bytes, limit.bytes >> 20)]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Its size (or the bytes read when it grew while read).
        size: u64,
        /// The limit.
        limit: Limit,
    },
    /// A file the engine writes into has more than one name.
    #[error("{}: has {links} hard links; a file this run also writes must have one name (copy it and use the copy)", path.display())]
    HardLinked {
        /// The file.
        path: PathBuf,
        /// Its number of links.
        links: u64,
    },
    /// It is not UTF-8 text.
    #[error("{}, line {line}: not UTF-8 text", path.display())]
    NotUtf8 {
        /// The file.
        path: PathBuf,
        /// 1-based line of the first byte that is not.
        line: usize,
    },
}

/// An open input file: a regular file within its limit.
#[derive(Debug)]
pub struct InputFile {
    path: PathBuf,
    file: File,
    limit: Limit,
}

impl InputFile {
    /// Opens `path` for reading (a symbolic link is followed; what it names
    /// must be a regular file within `limit`).
    pub fn open(path: &Path, limit: Limit) -> Result<Self, InputError> {
        let io = |source| InputError::Io {
            path: path.to_owned(),
            source,
        };
        check(path, &std::fs::metadata(path).map_err(io)?, limit, false)?;
        let file = options(false, false).open(path).map_err(io)?;
        check(path, &file.metadata().map_err(io)?, limit, false)?;
        Ok(Self {
            path: path.to_owned(),
            file,
            limit,
        })
    }

    /// Opens `path` for reading and writing, a file this run appends to: not
    /// through a symbolic link, and with one name only (writing through a
    /// hard link would change the file under its other name).
    pub fn open_own(path: &Path, limit: Limit) -> Result<Self, InputError> {
        let io = |source| InputError::Io {
            path: path.to_owned(),
            source,
        };
        check(
            path,
            &std::fs::symlink_metadata(path).map_err(io)?,
            limit,
            true,
        )?;
        let file = options(true, true).open(path).map_err(|e| {
            if is_link_refusal(&e) {
                InputError::NotAFile {
                    path: path.to_owned(),
                    what: "a symbolic link",
                }
            } else {
                io(e)
            }
        })?;
        check(path, &file.metadata().map_err(io)?, limit, true)?;
        Ok(Self {
            path: path.to_owned(),
            file,
            limit,
        })
    }

    /// The path it was opened by.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The whole file as text, without a leading byte-order mark.
    pub fn read_text(&mut self) -> Result<String, InputError> {
        let mut bytes = Vec::new();
        (&mut self.file)
            .take(self.limit.bytes + 1)
            .read_to_end(&mut bytes)
            .map_err(|source| InputError::Io {
                path: self.path.clone(),
                source,
            })?;
        if bytes.len() as u64 > self.limit.bytes {
            return Err(self.too_large(bytes.len() as u64));
        }
        if bytes.starts_with(BOM) {
            bytes.drain(..BOM.len());
        }
        String::from_utf8(bytes).map_err(|e| {
            let at = e.utf8_error().valid_up_to();
            let line = 1 + e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count();
            InputError::NotUtf8 {
                path: self.path.clone(),
                line,
            }
        })
    }

    /// A buffered reader of the file from its first byte after a byte-order
    /// mark.
    pub fn into_reader(self) -> Result<InputReader, InputError> {
        let mut reader = BufReader::with_capacity(1 << 16, self.file);
        let start = reader.fill_buf().map_err(|source| InputError::Io {
            path: self.path.clone(),
            source,
        })?;
        if start.starts_with(BOM) {
            reader.consume(BOM.len());
        }
        Ok(InputReader {
            reader,
            path: self.path,
            limit: self.limit,
            read: 0,
        })
    }

    fn too_large(&self, size: u64) -> InputError {
        InputError::TooLarge {
            path: self.path.clone(),
            size,
            limit: self.limit,
        }
    }

    /// The open file, e.g. to lock it before reading.
    pub fn file(&self) -> &File {
        &self.file
    }

    /// The open file (for a file this run also writes).
    pub fn into_file(self) -> File {
        self.file
    }
}

/// An input file read one line at a time, within its limit.
#[derive(Debug)]
pub struct InputReader {
    reader: BufReader<File>,
    path: PathBuf,
    limit: Limit,
    read: u64,
}

impl InputReader {
    /// Appends the next line with its line end (at most `max` bytes of it)
    /// to `buf`; the bytes read, 0 at the end of the file. The whole file
    /// read beyond the limit (it grew) is an [`InputError::TooLarge`].
    pub fn read_line(&mut self, buf: &mut Vec<u8>, max: u64) -> Result<usize, InputError> {
        let n = (&mut self.reader)
            .take(max)
            .read_until(b'\n', buf)
            .map_err(|source| InputError::Io {
                path: self.path.clone(),
                source,
            })?;
        self.read += n as u64;
        if self.read > self.limit.bytes {
            return Err(InputError::TooLarge {
                path: self.path.clone(),
                size: self.read,
                limit: self.limit,
            });
        }
        Ok(n)
    }
}

/// Open options: read (and write), never blocking on a FIFO, not following a
/// final symbolic link when `no_follow`.
fn options(write: bool, no_follow: bool) -> OpenOptions {
    let mut o = OpenOptions::new();
    o.read(true).write(write);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        let follow = if no_follow { libc::O_NOFOLLOW } else { 0 };
        o.custom_flags(libc::O_NONBLOCK | follow);
    }
    #[cfg(not(unix))]
    let _ = no_follow;
    o
}

/// Whether opening failed because the path is a symbolic link (`O_NOFOLLOW`).
fn is_link_refusal(e: &std::io::Error) -> bool {
    #[cfg(unix)]
    {
        e.raw_os_error() == Some(libc::ELOOP)
    }
    #[cfg(not(unix))]
    {
        let _ = e;
        false
    }
}

/// `Ok` for a regular file within `limit` (and, when `own`, with one name).
fn check(path: &Path, meta: &Metadata, limit: Limit, own: bool) -> Result<(), InputError> {
    let not = |what| {
        Err(InputError::NotAFile {
            path: path.to_owned(),
            what,
        })
    };
    let ft = meta.file_type();
    if ft.is_symlink() {
        return not("a symbolic link");
    }
    if ft.is_dir() {
        return not("a directory");
    }
    if !ft.is_file() {
        return not(special_kind(meta));
    }
    if meta.len() > limit.bytes {
        return Err(InputError::TooLarge {
            path: path.to_owned(),
            size: meta.len(),
            limit,
        });
    }
    #[cfg(unix)]
    if own {
        use std::os::unix::fs::MetadataExt;
        if meta.nlink() > 1 {
            return Err(InputError::HardLinked {
                path: path.to_owned(),
                links: meta.nlink(),
            });
        }
    }
    #[cfg(not(unix))]
    let _ = own;
    Ok(())
}

/// What a file that is neither regular, a directory nor a link is.
fn special_kind(meta: &Metadata) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let ft = meta.file_type();
        if ft.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if ft.is_char_device() {
            return "a character device";
        }
        if ft.is_block_device() {
            return "a block device";
        }
        if ft.is_socket() {
            return "a socket";
        }
    }
    let _ = meta;
    "a special file"
}

/// At most [`EXCERPT_CHARS`] characters of `text`, control characters (NUL,
/// escape sequences, line ends) escaped and `...` where it was cut: user text
/// safe to quote in a message.
pub fn excerpt(text: &str) -> String {
    escaped(text, EXCERPT_CHARS)
}

/// At most `max_chars` characters of `text`, escaped as by [`excerpt`] (for
/// a parser's message that quotes the file).
pub fn escaped(text: &str, max_chars: usize) -> String {
    let mut out = String::new();
    for (i, c) in text.chars().enumerate() {
        if i == max_chars {
            out.push_str("...");
            break;
        }
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn excerpts_are_short_and_escaped() {
        assert_eq!(excerpt("a\0b\x1b[2J\n"), "a\\u{0}b\\u{1b}[2J\\n");
        let long = "x".repeat(100);
        assert_eq!(excerpt(&long), format!("{}...", "x".repeat(EXCERPT_CHARS)));
        assert_eq!(excerpt("t,x"), "t,x");
    }
}
