//! Models made by reducers: the `[data]` signals read from CSV files, the
//! reducer run through its plugin, and the reduced model's outputs completed
//! through the lift `z ~ V y + z0` from the full model's.

pub mod galerkin;
pub mod hyper;
pub mod pod;
pub mod pod_model;

use std::path::{Path, PathBuf};

use ssm_api::{Diagnostic, Lift, Model, Output, Signals, Trajectory, Weight};
use ssm_model_files::input::{self, excerpt, InputError, InputFile};

/// Relative tolerance on the sampling period: every step `t_{k+1} - t_k` must
/// equal the mean step to this fraction.
const UNIFORM_TOL: f64 = 1e-6;

/// A `[data]` file that cannot be used; each names the file (and line).
#[derive(Debug, thiserror::Error)]
pub enum SignalsError {
    /// The file cannot be read (not a regular file, too large, not text:
    /// [`ssm_model_files::input`]).
    #[error(transparent)]
    Read(#[from] InputError),
    /// The header is missing or does not start with `t`.
    #[error("{path}, line 1: {message}")]
    Header {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A value is not a number, or a row has the wrong number of columns.
    #[error("{path}, line {line}: {message}")]
    Row {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The samples are not uniformly spaced, or the files disagree on the period.
    #[error(
        "{path}, line {line}: {message}; the data must be sampled uniformly (resample it first)"
    )]
    NonUniform {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A requested column is not in a file, or the files have different columns.
    #[error("{path}: {message}")]
    Columns {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
}

/// One parsed file: observable names, times, rows of values and the
/// 1-based line of each row.
struct Table {
    names: Vec<String>,
    t: Vec<f64>,
    rows: Vec<Vec<f64>>,
    lines: Vec<usize>,
}

fn read_table(path: &Path) -> Result<Table, SignalsError> {
    let text = InputFile::open(path, input::DATA)?.read_text()?;
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let header = |message: String| SignalsError::Header {
        path: path.to_owned(),
        message,
    };
    let (_, head) = lines
        .next()
        .ok_or_else(|| header("the file is empty".into()))?;
    let cols: Vec<String> = head.split(',').map(|c| c.trim().to_owned()).collect();
    if cols.first().map(String::as_str) != Some("t") || cols.len() < 2 {
        return Err(header(format!(
            "the header must be 't,<observable>,...', found '{}'",
            excerpt(head)
        )));
    }
    let mut t = Vec::new();
    let mut rows = Vec::new();
    let mut numbers = Vec::new();
    for (i, line) in lines {
        let row_err = |message: String| SignalsError::Row {
            path: path.to_owned(),
            line: i + 1,
            message,
        };
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if fields.len() != cols.len() {
            return Err(row_err(format!(
                "{} values, the header names {} columns",
                fields.len(),
                cols.len()
            )));
        }
        let mut vals = Vec::with_capacity(fields.len());
        for (c, f) in fields.iter().enumerate() {
            let v: f64 = f.parse().map_err(|_| {
                row_err(format!(
                    "column '{}': '{}' is not a number",
                    excerpt(&cols[c]),
                    excerpt(f)
                ))
            })?;
            if !v.is_finite() {
                return Err(row_err(format!(
                    "column '{}': {v} is not finite",
                    excerpt(&cols[c])
                )));
            }
            vals.push(v);
        }
        t.push(vals[0]);
        rows.push(vals[1..].to_vec());
        numbers.push(i + 1);
    }
    if t.len() < 2 {
        return Err(SignalsError::Row {
            path: path.to_owned(),
            line: 2,
            message: format!("{} samples; at least two are needed", t.len()),
        });
    }
    Ok(Table {
        names: cols[1..].to_vec(),
        t,
        rows,
        lines: numbers,
    })
}

/// The sampling period of `table` (its mean step), when every step equals
/// the typical (median) one to [`UNIFORM_TOL`]; else the first step that
/// does not, at its line.
fn period_of(path: &Path, table: &Table) -> Result<f64, SignalsError> {
    let steps: Vec<f64> = table.t.windows(2).map(|w| w[1] - w[0]).collect();
    let mut sorted = steps.clone();
    sorted.sort_by(f64::total_cmp);
    let typical = sorted[sorted.len() / 2];
    let at = |k: usize, message: String| SignalsError::NonUniform {
        path: path.to_owned(),
        line: table.lines[k + 1],
        message,
    };
    // the values are finite (checked above): no step is NaN
    if typical <= 0.0 {
        let k = steps.iter().position(|s| *s <= 0.0).unwrap_or(0);
        return Err(at(k, "time does not increase".into()));
    }
    if let Some(k) = steps
        .iter()
        .position(|s| (s - typical).abs() > UNIFORM_TOL * typical)
    {
        return Err(at(
            k,
            format!(
                "step {:e} from the sample at line {}, where the typical step is {typical:e}",
                steps[k], table.lines[k]
            ),
        ));
    }
    let n = table.t.len();
    Ok((table.t[n - 1] - table.t[0]) / (n - 1) as f64)
}

/// Reads the `[data]` files into [`Signals`]: uniformly sampled, the same
/// period in every file, the requested `columns` (default: all) in that order.
pub fn read_signals(
    files: &[PathBuf],
    columns: Option<&[String]>,
) -> Result<Signals, SignalsError> {
    let mut period: Option<(f64, PathBuf)> = None;
    let mut names: Option<Vec<String>> = None;
    let mut trajectories = Vec::with_capacity(files.len());
    for path in files {
        let table = read_table(path)?;
        let dt = period_of(path, &table)?;
        match &period {
            Some((p, first)) if (dt - p).abs() > UNIFORM_TOL * p => {
                return Err(SignalsError::NonUniform {
                    path: path.clone(),
                    line: table.lines[1],
                    message: format!("sampling period {dt:e}, but {} has {p:e}", first.display()),
                })
            }
            Some(_) => {}
            None => period = Some((dt, path.clone())),
        }
        let wanted: Vec<String> = columns.map_or_else(|| table.names.clone(), <[String]>::to_vec);
        let mut idx = Vec::with_capacity(wanted.len());
        for w in &wanted {
            let k =
                table
                    .names
                    .iter()
                    .position(|c| c == w)
                    .ok_or_else(|| SignalsError::Columns {
                        path: path.clone(),
                        message: format!(
                            "no column '{}' (it has: {})",
                            excerpt(w),
                            excerpt(&table.names.join(", "))
                        ),
                    })?;
            idx.push(k);
        }
        match &names {
            Some(first) if *first != wanted => {
                return Err(SignalsError::Columns {
                    path: path.clone(),
                    message: format!(
                        "columns {} differ from the first file's {}",
                        excerpt(&wanted.join(", ")),
                        excerpt(&first.join(", "))
                    ),
                })
            }
            Some(_) => {}
            None => names = Some(wanted),
        }
        let samples = table
            .rows
            .iter()
            .flat_map(|r| idx.iter().map(move |&k| r[k]))
            .collect();
        trajectories.push(Trajectory {
            source: path.display().to_string().as_str().into(),
            t0: table.t[0],
            samples,
        });
    }
    Ok(Signals {
        names: names
            .unwrap_or_default()
            .iter()
            .map(|s| s.as_str().into())
            .collect(),
        period: period.map_or(0.0, |p| p.0),
        trajectories: trajectories.into_iter().collect(),
    })
}

/// What a reducer made, for `summary.json`.
#[derive(Debug, Clone)]
pub struct Reduction {
    /// Plugin that offered the reducer.
    pub plugin: String,
    /// Reducer name.
    pub reducer: String,
    /// States of the input model, when there was one.
    pub n_input_states: Option<usize>,
    /// Trajectories and samples of the input signals, when there were any.
    pub n_trajectories: usize,
    /// States of the reduced model.
    pub n_reduced_states: usize,
    /// The lift back to the full coordinates.
    pub lift: Option<Lift>,
    /// The reducer's diagnostics.
    pub diagnostics: Vec<Diagnostic>,
    /// Outputs composed through the lift from the full model's.
    pub lifted_outputs: Vec<String>,
    /// The `[data]` signals the reducer was given.
    pub signals: Option<Signals>,
}

/// Adds to `reduced` every output of `full` it lacks, as `w^T V` through the
/// lift (the reduced model keeps its own outputs); returns their names.
pub fn lift_outputs(reduced: &mut Model, full: &Model, lift: &Lift) -> Vec<String> {
    let n_red = reduced.states.len();
    let mut basis_rows: Vec<Vec<(usize, f64)>> = vec![Vec::new(); lift.basis.nrows as usize];
    for (r, c, v) in lift.basis.iter() {
        if r < basis_rows.len() && c < n_red {
            basis_rows[r].push((c, v));
        }
    }
    let mut added = Vec::new();
    for o in full.outputs.iter() {
        if reduced.outputs.iter().any(|r| r.name == o.name) {
            continue;
        }
        let mut w = vec![0.0; n_red];
        for wt in o.weights.iter() {
            for &(c, v) in basis_rows.get(wt.state as usize).into_iter().flatten() {
                w[c] += wt.value * v;
            }
        }
        reduced.outputs.push(Output {
            name: o.name.clone(),
            weights: w
                .iter()
                .enumerate()
                .filter(|(_, v)| **v != 0.0)
                .map(|(k, &v)| Weight {
                    state: k as u32,
                    value: v,
                })
                .collect(),
        });
        added.push(o.name.to_string());
    }
    added
}
