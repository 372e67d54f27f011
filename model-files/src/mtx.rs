//! Matrix Market files (`coordinate` or `array`, `real` or `integer`,
//! `general` or `symmetric`), read streaming and written exactly.
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

use ssm_api::{SparseMatrix, Triplet};

use crate::error::FileError;
use crate::lines::{index, value, LineReader, Progress};

/// Storage of a Matrix Market file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Coordinate,
    Array,
}

/// Reads the matrix in `path` (duplicates summed, a symmetric file's lower
/// triangle mirrored).
pub fn read_matrix(path: &Path, progress: &mut Progress<'_>) -> Result<SparseMatrix, FileError> {
    let mut r = LineReader::open(path, progress)?;
    let (format, symmetric) = header(&mut r)?;
    let size = match r.next_data(&['%'])? {
        Some(line) => line.to_owned(),
        None => return Err(r.content_error("ends before the size line")),
    };
    let dims: Vec<&str> = size.split_ascii_whitespace().collect();
    let want = if format == Format::Coordinate { 3 } else { 2 };
    if dims.len() != want {
        return Err(r.error(format!(
            "size line '{size}': expected {} integers",
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
            .ok_or_else(|| r.error(format!("size '{tok}' is not an integer below 2^32")))
    };
    let (rows, cols) = (count(dims[0])?, count(dims[1])?);
    if symmetric && rows != cols {
        return Err(r.error(format!(
            "a symmetric matrix must be square, the size line says {rows}x{cols}"
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
                let entry = coordinate_entry(line, rows, cols, symmetric);
                let (i, j, v) = entry.map_err(|msg| r.error(msg))?;
                store(&mut m, i, j, v);
                if symmetric && i != j {
                    store(&mut m, j, i, v);
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
            // column-major; a symmetric array stores the lower triangle only
            let positions: Box<dyn Iterator<Item = (usize, usize)>> = if symmetric {
                Box::new((0..cols).flat_map(move |j| (j..rows).map(move |i| (i, j))))
            } else {
                Box::new((0..cols).flat_map(move |j| (0..rows).map(move |i| (i, j))))
            };
            let total = if symmetric {
                rows * (rows + 1) / 2
            } else {
                rows * cols
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
                    let msg =
                        format!("expected one value per line in an array file, found '{line}'");
                    return Err(r.error(msg));
                }
                let v = value(toks[0]).map_err(|msg| r.error(msg))?;
                store(&mut m, i, j, v);
                if symmetric && i != j {
                    store(&mut m, j, i, v);
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

/// Adds an entry, keeping explicit zeros (they are part of the pattern).
fn store(m: &mut SparseMatrix, i: usize, j: usize, value: f64) {
    m.entries.push(Triplet {
        row: i as u32,
        col: j as u32,
        value,
    });
}

fn header(r: &mut LineReader<'_>) -> Result<(Format, bool), FileError> {
    let line = match r.next_line()? {
        Some(line) => line.to_ascii_lowercase(),
        None => return Err(r.content_error("empty file (expected a %%MatrixMarket header)")),
    };
    let toks: Vec<&str> = line.split_ascii_whitespace().collect();
    if toks.first() != Some(&"%%matrixmarket") || toks.len() != 5 || toks[1] != "matrix" {
        return Err(r.error(
            "expected the header '%%MatrixMarket matrix coordinate|array real general|symmetric'",
        ));
    }
    let format = match toks[2] {
        "coordinate" => Format::Coordinate,
        "array" => Format::Array,
        other => return Err(r.error(format!("format '{other}': expected coordinate or array"))),
    };
    match toks[3] {
        "real" | "integer" | "double" => {}
        other => {
            return Err(r.error(format!(
                "field '{other}': only real (or integer) matrices are models"
            )))
        }
    }
    let symmetric = match toks[4] {
        "general" => false,
        "symmetric" => true,
        other => return Err(r.error(format!("symmetry '{other}': expected general or symmetric"))),
    };
    Ok((format, symmetric))
}

fn coordinate_entry(
    line: &str,
    rows: usize,
    cols: usize,
    symmetric: bool,
) -> Result<(usize, usize, f64), String> {
    let toks: Vec<&str> = line.split_ascii_whitespace().collect();
    if toks.len() != 3 {
        return Err(format!("expected 'row col value', found '{line}'"));
    }
    let i = index(toks[0], rows, "row")?;
    let j = index(toks[1], cols, "column")?;
    let v = value(toks[2])?;
    if symmetric && i < j {
        return Err(format!(
            "entry ({}, {}) lies above the diagonal, but the file is declared symmetric \
             (a symmetric file stores the lower triangle only; declare it general if the \
             matrix is not symmetric)",
            i + 1,
            j + 1
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
}
