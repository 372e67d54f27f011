//! `outputs.csv`: named outputs as rows `name,dof` or `name,dof,weight`
//! (1-based dof, weight 1 when left out); rows of the same name are summed,
//! so an output may be a weighted sum of displacements. A first row
//! `name,dof[,weight]` is a header; `#` and `%` lines are comments.

use std::collections::HashMap;
use std::io::Write;
use std::path::Path;

use crate::error::FileError;
use crate::input::excerpt;
use crate::lines::{index, value, LineReader, Progress};

/// A named output: `(name, [(0-based dof, weight)])`.
pub type NamedOutput = (String, Vec<(usize, f64)>);

/// Reads the outputs of a model with `n_dof` displacements.
pub fn read_outputs(
    path: &Path,
    n_dof: usize,
    progress: &mut Progress<'_>,
) -> Result<Vec<NamedOutput>, FileError> {
    let mut r = LineReader::open(path, progress)?;
    let mut outputs: Vec<NamedOutput> = Vec::new();
    let mut position: HashMap<String, usize> = HashMap::new();
    let mut first = true;
    while let Some(line) = r.next_data(&['#', '%'])? {
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if std::mem::take(&mut first) && fields.get(1) == Some(&"dof") {
            continue;
        }
        let parsed = row(&fields, n_dof);
        let (name, dof, w) = parsed.map_err(|msg| r.error(msg))?;
        match position.get(&name) {
            Some(&k) => outputs[k].1.push((dof, w)),
            None => {
                position.insert(name.clone(), outputs.len());
                outputs.push((name, vec![(dof, w)]));
            }
        }
    }
    Ok(outputs)
}

/// A name `outputs.csv` can hold: non-empty letters, digits, `_`, `.`, `-`.
pub fn valid_name(name: &str) -> bool {
    !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_alphanumeric() || "_.-".contains(c))
}

fn row(fields: &[&str], n_dof: usize) -> Result<(String, usize, f64), String> {
    if !(2..=3).contains(&fields.len()) {
        return Err(format!(
            "expected 'name,dof' or 'name,dof,weight', found {} fields",
            fields.len()
        ));
    }
    let name = fields[0];
    if !valid_name(name) {
        return Err(format!(
            "output name '{}' must be non-empty letters, digits, '_', '.' or '-'",
            excerpt(name)
        ));
    }
    let dof = index(fields[1], n_dof, "dof")?;
    let w = match fields.get(2) {
        Some(tok) => value(tok)?,
        None => 1.0,
    };
    Ok((name.to_owned(), dof, w))
}

/// Writes `outputs` (one row per weight).
pub fn write_outputs(w: &mut impl Write, outputs: &[NamedOutput]) -> std::io::Result<()> {
    writeln!(w, "name,dof,weight")?;
    for (name, weights) in outputs {
        for &(dof, x) in weights {
            if x == 1.0 {
                writeln!(w, "{name},{}", dof + 1)?;
            } else {
                writeln!(w, "{name},{},{x:e}", dof + 1)?;
            }
        }
    }
    Ok(())
}
