//! Sparse force tensors: `f2.coo` with lines `i j k value` (`f_i += value x_j
//! x_k`) and `f3.coo` with lines `i j k l value` (`f_i += value x_j x_k x_l`),
//! 1-based, `%` comments, duplicates summed; the constraint terms `g2.coo`,
//! `g3.coo` have the constraint index as `i`.

use std::io::Write;
use std::path::Path;

use ssm_api::PolyVector;

use crate::error::FileError;
use crate::input::excerpt;
use crate::lines::{index, value, LineReader, Progress};

/// Adds the terms of the degree-`degree` tensor in `path` to `poly` (rows `i`
/// in `1..=poly.n_eq`, variables in `1..=n_vars`).
///
/// # Panics
/// When `degree` is not 2 or 3 (the files hold those only).
pub fn read_tensor(
    path: &Path,
    degree: usize,
    n_vars: usize,
    poly: &mut PolyVector,
    progress: &mut Progress<'_>,
) -> Result<(), FileError> {
    assert!(
        (2..=3).contains(&degree),
        "force tensors have degree 2 or 3, not {degree}"
    );
    let mut r = LineReader::open(path, progress)?;
    let n_eq = poly.n_eq as usize;
    let mut factors: Vec<(usize, u32)> = Vec::with_capacity(degree);
    while let Some(line) = r.next_data(&['%'])? {
        factors.clear();
        let parsed = term(line, degree, n_eq, n_vars, &mut factors);
        let (eq, coeff) = parsed.map_err(|msg| r.error(msg))?;
        poly.push(eq, coeff, &factors);
    }
    Ok(())
}

fn term(
    line: &str,
    degree: usize,
    n_eq: usize,
    n_vars: usize,
    factors: &mut Vec<(usize, u32)>,
) -> Result<(usize, f64), String> {
    let toks: Vec<&str> = line.split_ascii_whitespace().collect();
    if toks.len() != degree + 2 {
        let names = ["i", "j", "k", "l", "m"];
        return Err(format!(
            "expected '{} value' ({} fields), found '{}'",
            names[..degree + 1].join(" "),
            degree + 2,
            excerpt(line)
        ));
    }
    let eq = index(toks[0], n_eq, "equation index i")?;
    for tok in &toks[1..=degree] {
        factors.push((index(tok, n_vars, "variable index")?, 1));
    }
    Ok((eq, value(toks[degree + 1])?))
}

/// Writes the terms of `poly` of total degree `degree` (in variables
/// `0..n_vars`) as a tensor file; terms in other variables must have been
/// removed by the caller.
pub fn write_tensor(
    w: &mut impl Write,
    poly: &PolyVector,
    degree: u32,
    comment: &str,
) -> std::io::Result<()> {
    writeln!(w, "% {comment}")?;
    for t in poly.terms.iter().filter(|t| t.degree() == degree) {
        write!(w, "{}", t.eq + 1)?;
        for f in t.factors.iter() {
            for _ in 0..f.power {
                write!(w, " {}", f.var + 1)?;
            }
        }
        writeln!(w, " {:e}", t.coeff)?;
    }
    Ok(())
}
