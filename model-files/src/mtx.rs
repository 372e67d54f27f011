//! Matrix Market files (`coordinate` or `array`, `real` or `integer`,
//! `general`, `symmetric` or `skew-symmetric`), read streaming and written exactly.
//!
//! Written by hand rather than taken from a sparse-matrix crate: the engine
//! needs errors that name the file and line, a progress count, checks of the
//! declared symmetry, and nothing else from such a crate.
//!
//! # References
//! R. F. Boisvert, R. Pozo, K. A. Remington, *The Matrix Market Exchange
//! Formats: Initial Design*, NISTIR 5935 (1996).

use std::io::Write;
use std::path::Path;

use ssm_api::SparseMatrix;

use crate::error::FileError;
use crate::input::excerpt;
use crate::lines::{index, value, LineReader, Progress};

/// Storage of a Matrix Market file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Coordinate,
    Array,
}

/// Symmetry of a Matrix Market file: the part stored and how the rest follows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Symmetry {
    General,
    /// Lower triangle with the diagonal; `a_ji = a_ij`.
    Symmetric,
    /// Strict lower triangle; `a_ji = -a_ij`, zero diagonal.
    Skew,
}

impl Symmetry {
    /// The mirrored value of `v`, when the file stores half the matrix.
    fn mirror(self, v: f64) -> Option<f64> {
        match self {
            Self::General => None,
            Self::Symmetric => Some(v),
            Self::Skew => Some(-v),
        }
    }
}

/// Reads the matrix in `path` (duplicates summed, the stored triangle of a
/// symmetric or skew-symmetric file mirrored). A `coordinate` file keeps its
/// explicit zeros (they are part of its pattern); an `array` file is dense
/// text with no pattern, so its zeros are dropped.
pub fn read_matrix(path: &Path, progress: &mut Progress<'_>) -> Result<SparseMatrix, FileError> {
    let mut r = LineReader::open(path, progress)?;
    let (format, symmetry) = header(&mut r)?;
    let half = symmetry != Symmetry::General;
    let size = match r.next_data(&['%'])? {
        Some(line) => line.to_owned(),
        None => return Err(r.content_error("ends before the size line")),
    };
    let dims: Vec<&str> = size.split_ascii_whitespace().collect();
    let want = if format == Format::Coordinate { 3 } else { 2 };
    if dims.len() != want {
        return Err(r.error(format!(
            "size line '{}': expected {} integers",
            excerpt(&size),
            if want == 3 {
                "'rows cols entries'"
            } else {
                "'rows cols'"
            }
        )));
    }
    let count = |tok: &str| -> Result<usize, FileError> {
        tok.parse::<usize>()
            .ok()
            .filter(|&k| k < u32::MAX as usize)
            .ok_or_else(|| {
                r.error(format!(
                    "size '{}' is not an integer below 2^32 - 1",
                    excerpt(tok)
                ))
            })
    };
    let (rows, cols) = (count(dims[0])?, count(dims[1])?);
    if half && rows != cols {
        return Err(r.error(format!(
            "a symmetric or skew-symmetric matrix must be square, the size line says {rows}x{cols}"
        )));
    }
    let mut m = SparseMatrix::zeros(rows, cols);
    match format {
        Format::Coordinate => {
            let nnz = count(dims[2])?;
            // the declared count is not trusted with memory: the vector grows
            // with the entries actually read
            m.entries.reserve(nnz.min(1 << 20));
            let mut found = 0usize;
            while let Some(line) = r.next_data(&['%'])? {
                if found == nnz {
                    return Err(r.error(format!(
                        "more entries than the {nnz} the size line declares"
                    )));
                }
                let entry = coordinate_entry(line, rows, cols, symmetry);
                let (i, j, v) = entry.map_err(|msg| r.error(msg))?;
                m.push_entry(i, j, v);
                if let Some(w) = symmetry.mirror(v).filter(|_| i != j) {
                    m.push_entry(j, i, w);
                }
                found += 1;
            }
            if found != nnz {
                return Err(r.content_error(format!(
                    "the size line declares {nnz} entries, the file has {found}"
                )));
            }
        }
        Format::Array => {
            // column-major; a symmetric array stores the lower triangle, a
            // skew-symmetric one the strict lower triangle
            let first = move |j: usize| match symmetry {
                Symmetry::General => 0,
                Symmetry::Symmetric => j,
                Symmetry::Skew => j + 1,
            };
            let positions = (0..cols).flat_map(move |j| (first(j)..rows).map(move |i| (i, j)));
            let total = match symmetry {
                Symmetry::General => rows * cols,
                Symmetry::Symmetric => rows * (rows + 1) / 2,
                Symmetry::Skew => rows * rows.saturating_sub(1) / 2,
            };
            let mut positions = positions.peekable();
            let mut found = 0usize;
            while let Some(line) = r.next_data(&['%'])? {
                let Some((i, j)) = positions.next() else {
                    return Err(r.error(format!(
                        "more values than the {total} the size line declares"
                    )));
                };
                let toks: Vec<&str> = line.split_ascii_whitespace().collect();
                if toks.len() != 1 {
                    let msg = format!(
                        "expected one value per line in an array file, found '{}'",
                        excerpt(line)
                    );
                    return Err(r.error(msg));
                }
                let v = value(toks[0]).map_err(|msg| r.error(msg))?;
                if v != 0.0 {
                    m.push_entry(i, j, v);
                    if let Some(w) = symmetry.mirror(v).filter(|_| i != j) {
                        m.push_entry(j, i, w);
                    }
                }
                found += 1;
            }
            if positions.peek().is_some() {
                return Err(r.content_error(format!(
                    "the size line declares {total} values, the file has {found}"
                )));
            }
        }
    }
    Ok(m)
}

fn header(r: &mut LineReader<'_>) -> Result<(Format, Symmetry), FileError> {
    let line = match r.next_line()? {
        Some(line) => line.to_ascii_lowercase(),
        None => return Err(r.content_error("empty file (expected a %%MatrixMarket header)")),
    };
    let toks: Vec<&str> = line.split_ascii_whitespace().collect();
    if toks.first() != Some(&"%%matrixmarket") || toks.len() != 5 || toks[1] != "matrix" {
        return Err(r.error(
            "expected the header '%%MatrixMarket matrix coordinate|array real general|symmetric|skew-symmetric'",
        ));
    }
    let format = match toks[2] {
        "coordinate" => Format::Coordinate,
        "array" => Format::Array,
        other => {
            return Err(r.error(format!(
                "format '{}': expected coordinate or array",
                excerpt(other)
            )))
        }
    };
    match toks[3] {
        "real" | "integer" | "double" => {}
        other => {
            return Err(r.error(format!(
                "field '{}': only real (or integer) matrices are models",
                excerpt(other)
            )))
        }
    }
    let symmetry = match toks[4] {
        "general" => Symmetry::General,
        "symmetric" => Symmetry::Symmetric,
        "skew-symmetric" => Symmetry::Skew,
        other => {
            return Err(r.error(format!(
                "symmetry '{}': expected general, symmetric or skew-symmetric",
                excerpt(other)
            )))
        }
    };
    Ok((format, symmetry))
}

fn coordinate_entry(
    line: &str,
    rows: usize,
    cols: usize,
    symmetry: Symmetry,
) -> Result<(usize, usize, f64), String> {
    let toks: Vec<&str> = line.split_ascii_whitespace().collect();
    if toks.len() != 3 {
        return Err(format!(
            "expected 'row col value', found '{}'",
            excerpt(line)
        ));
    }
    let i = index(toks[0], rows, "row")?;
    let j = index(toks[1], cols, "column")?;
    let v = value(toks[2])?;
    let above = match symmetry {
        Symmetry::General => false,
        Symmetry::Symmetric => i < j,
        Symmetry::Skew => i <= j,
    };
    if above {
        return Err(format!(
            "entry ({}, {}) lies {} the diagonal, but the file is declared {} (such a \
             file stores the {}lower triangle only; declare it general if the matrix is not)",
            i + 1,
            j + 1,
            if i == j { "on" } else { "above" },
            if symmetry == Symmetry::Skew {
                "skew-symmetric"
            } else {
                "symmetric"
            },
            if symmetry == Symmetry::Skew {
                "strict "
            } else {
                ""
            },
        ));
    }
    Ok((i, j, v))
}

/// The entries of `m` summed by position, sorted by column then row; a sum
/// that is zero stays as an explicit zero (it keeps the sparsity pattern, on
/// which sparse factorizations, and so their last digits, depend).
pub fn summed(m: &SparseMatrix) -> Vec<(usize, usize, f64)> {
    let mut e: Vec<(usize, usize, f64)> = m.iter().collect();
    e.sort_by_key(|&(i, j, _)| (j, i));
    let mut out: Vec<(usize, usize, f64)> = Vec::with_capacity(e.len());
    for (i, j, v) in e {
        match out.last_mut() {
            Some(last) if last.0 == i && last.1 == j => last.2 += v,
            _ => out.push((i, j, v)),
        }
    }
    out
}

/// Writes `m` as a `coordinate real general` file (values in shortest
/// round-trip form, so reading gives the same numbers).
pub fn write_matrix(w: &mut impl Write, m: &SparseMatrix, comment: &str) -> std::io::Result<()> {
    let entries = summed(m);
    writeln!(w, "%%MatrixMarket matrix coordinate real general")?;
    writeln!(w, "% {comment}")?;
    writeln!(w, "{} {} {}", m.nrows, m.ncols, entries.len())?;
    for (i, j, v) in entries {
        writeln!(w, "{} {} {v:e}", i + 1, j + 1)?;
    }
    Ok(())
}

/// Writes the column vector `v` as an `array real general` file.
pub fn write_vector(w: &mut impl Write, v: &[f64], comment: &str) -> std::io::Result<()> {
    writeln!(w, "%%MatrixMarket matrix array real general")?;
    writeln!(w, "% {comment}")?;
    writeln!(w, "{} 1", v.len())?;
    for x in v {
        writeln!(w, "{x:e}")?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(name: &str, text: &str) -> Result<Vec<(usize, usize, f64)>, FileError> {
        let path = std::env::temp_dir().join(format!("ssm-mtx-{}-{name}", std::process::id()));
        std::fs::write(&path, text).unwrap();
        let m = read_matrix(&path, &mut |_| {});
        let _ = std::fs::remove_file(&path);
        m.map(|m| summed(&m))
    }

    /// A symmetric array file (column-major lower triangle) with comments,
    /// blank lines and CRLF line ends gives the full symmetric matrix.
    #[test]
    fn symmetric_array_with_crlf_and_comments() {
        let text =
            "%%MatrixMarket matrix array real symmetric\r\n% c\r\n\r\n2 2\r\n4\r\n-1\r\n3\r\n";
        let m = read("sym-array", text).unwrap();
        assert_eq!(
            m,
            vec![(0, 0, 4.0), (1, 0, -1.0), (0, 1, -1.0), (1, 1, 3.0)]
        );
    }

    /// Duplicates are summed; an integer field reads as real; the writer's
    /// text reads back to the same bits (shortest round-trip form).
    #[test]
    fn duplicates_integers_and_exact_round_trip() {
        let text =
            "%%MatrixMarket matrix coordinate integer general\n2 3 3\n1 3 2\n1 3 5\n2 1 -4\n";
        assert_eq!(read("int", text).unwrap(), vec![(1, 0, -4.0), (0, 2, 7.0)]);
        let mut m = SparseMatrix::zeros(2, 2);
        for (i, j, v) in [
            (0, 0, 0.1 + 0.2),
            (1, 0, -1e-300),
            (1, 1, std::f64::consts::PI),
        ] {
            m.push(i, j, v);
        }
        let mut text = Vec::new();
        write_matrix(&mut text, &m, "test").unwrap();
        let back = read("round-trip", std::str::from_utf8(&text).unwrap()).unwrap();
        assert_eq!(back, summed(&m));
    }

    /// A declared count far beyond the entries is an error, not an allocation.
    #[test]
    fn declared_count_is_not_trusted() {
        let text = "%%MatrixMarket matrix coordinate real general\n4000000000 4000000000 4000000000\n1 1 1\n";
        let e = read("count", text).unwrap_err().to_string();
        assert!(
            e.contains("declares 4000000000 entries, the file has 1"),
            "{e}"
        );
    }

    /// Skew-symmetric files (scipy writes them for small skew matrices, e.g. a
    /// gyroscopic matrix) mirror with the opposite sign; an entry on the
    /// diagonal of such a file is an error.
    #[test]
    fn skew_symmetric_coordinate_and_array() {
        let c = "%%MatrixMarket matrix coordinate real skew-symmetric\n2 2 1\n2 1 3.0\n";
        assert_eq!(read("skew-c", c).unwrap(), vec![(1, 0, 3.0), (0, 1, -3.0)]);
        let a = "%%MatrixMarket matrix array real skew-symmetric\n3 3\n1\n0\n2\n";
        assert_eq!(
            read("skew-a", a).unwrap(),
            vec![(1, 0, 1.0), (0, 1, -1.0), (2, 1, 2.0), (1, 2, -2.0)]
        );
        let d = "%%MatrixMarket matrix coordinate real skew-symmetric\n2 2 1\n1 1 3.0\n";
        let e = read("skew-d", d).unwrap_err().to_string();
        assert!(e.contains("line 3") && e.contains("on the diagonal"), "{e}");
    }

    /// A Latin-1 byte in a comment (a unit written by an older scipy) is
    /// skipped; in a data line it is an error at that line; a line without
    /// end beyond 1 MiB is refused at its line instead of being buffered.
    #[test]
    fn non_utf8_comment_and_endless_line() {
        let path = std::env::temp_dir().join(format!("ssm-mtx-{}-latin1", std::process::id()));
        let mut text =
            b"%%MatrixMarket matrix coordinate real general\n% units \xb5m\n1 1 1\n1 1 2.5\n"
                .to_vec();
        std::fs::write(&path, &text).unwrap();
        let m = read_matrix(&path, &mut |_| {}).unwrap();
        assert_eq!(summed(&m), vec![(0, 0, 2.5)]);
        text.extend_from_slice(b"1 1 \xb5\n");
        std::fs::write(&path, &text).unwrap();
        let e = read_matrix(&path, &mut |_| {}).unwrap_err().to_string();
        assert!(e.contains("line 5") && e.contains("not UTF-8"), "{e}");
        let mut long = b"%%MatrixMarket matrix coordinate real general\n1 1 1\n".to_vec();
        long.resize(long.len() + (1 << 21), b' ');
        std::fs::write(&path, &long).unwrap();
        let e = read_matrix(&path, &mut |_| {}).unwrap_err().to_string();
        assert!(e.contains("line 3") && e.contains("longer than"), "{e}");
        let _ = std::fs::remove_file(&path);
    }
}
