//! What `ssm.study` shares with `ssm-engine study`: the figures of a
//! point's run, the points of a seeded sample, a plan at a point, and the
//! store (its `study.json` and its one-row Parquet records), so the two
//! doors write the same store and the same figures.

use std::path::PathBuf;

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyFloat, PyInt, PyList, PyString};

use crate::errors::{raise, Family};
use ssm_engine::plan::budget::Limits;
use ssm_engine::plan::Plan;
use ssm_engine::study::figures;
use ssm_engine::study::points;
use ssm_engine::study::store::{self, Cell, Meta, Store, STORE_VERSION};

/// A record's value as Python sees it (a list of numbers as a list).
fn to_python<'py>(py: Python<'py>, cell: &Cell) -> PyResult<Bound<'py, PyAny>> {
    Ok(match cell {
        Cell::Null => py.None().into_bound(py),
        Cell::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        Cell::Int(i) => i.into_pyobject(py)?.into_any(),
        Cell::Float(x) => PyFloat::new(py, *x).into_any(),
        Cell::Text(s) => PyString::new(py, s).into_any(),
        Cell::List(v) => PyList::new(py, v)?.into_any(),
    })
}

/// A Python value as a record's value: `None`, a bool, an int, a float or
/// a str (lists and tables come as their JSON text).
fn from_python(name: &str, value: &Bound<'_, PyAny>) -> PyResult<Cell> {
    if value.is_none() {
        Ok(Cell::Null)
    } else if value.is_instance_of::<PyBool>() {
        Ok(Cell::Bool(value.extract()?))
    } else if value.is_instance_of::<PyInt>() {
        Ok(value
            .extract()
            .map_or_else(|_| Cell::Text(value.to_string()), Cell::Int))
    } else if value.is_instance_of::<PyFloat>() {
        Ok(Cell::Float(value.extract()?))
    } else if value.is_instance_of::<PyString>() {
        Ok(Cell::Text(value.extract()?))
    } else {
        Err(PyTypeError::new_err(format!(
            "record: '{name}' is a {}; give None, a bool, an int, a float or a str",
            value.get_type().name()?
        )))
    }
}

/// The figures of a run from the files it wrote (`(name, contents)`) and
/// the backbone amplitudes `backbone_at`, as `(name, value)` in order
/// (`ssm_engine::study::figures::figures`).
#[pyfunction]
pub(crate) fn study_figures<'py>(
    py: Python<'py>,
    files: Vec<(String, Vec<u8>)>,
    backbone_at: Vec<f64>,
) -> PyResult<Vec<(String, Bound<'py, PyAny>)>> {
    let out = figures::figures(&files, &backbone_at)
        .map_err(|e| raise(py, Family::Analysis, e.to_string()))?;
    out.iter()
        .map(|(n, c)| Ok((n.clone(), to_python(py, c)?)))
        .collect()
}

/// Checks a parameter's name (`ssm_engine::study::points::check_parameter`).
#[pyfunction]
pub(crate) fn study_check_parameter(py: Python<'_>, name: &str) -> PyResult<()> {
    points::check_parameter(name).map_err(|e| raise(py, Family::Input, e.to_string()))
}

/// `n` points drawn from `ranges` (`(parameter, low, high)`) with `seed`,
/// as `(parameter, value)` lists (`ssm_engine::study::points::sample`).
#[pyfunction]
pub(crate) fn study_sample(
    py: Python<'_>,
    ranges: Vec<(String, f64, f64)>,
    n: usize,
    seed: u64,
) -> PyResult<Vec<Vec<(String, f64)>>> {
    let sampled = points::sample(ranges, n, seed, &Limits::of_machine())
        .map_err(|e| raise(py, Family::Input, e.to_string()))?;
    Ok(sampled
        .values
        .into_iter()
        .map(|p| {
            p.into_iter()
                .map(|(k, v)| (k, v.as_f64().unwrap_or(f64::NAN)))
                .collect()
        })
        .collect())
}

/// The plan `plan` (JSON) with the plan values of `point` (JSON, a list of
/// `[name, value]`) set, as JSON (`ssm_engine::study::points::plan_at`).
#[pyfunction]
pub(crate) fn study_plan_at(py: Python<'_>, plan: &str, point: &str) -> PyResult<String> {
    let input = |e: String| raise(py, Family::Input, e);
    let plan: Plan = serde_json::from_str(plan).map_err(|e| input(format!("plan: {e}")))?;
    let point: Vec<(String, serde_json::Value)> =
        serde_json::from_str(point).map_err(|e| input(format!("point: {e}")))?;
    let at = points::plan_at(&plan, &point).map_err(|e| input(e.to_string()))?;
    serde_json::to_string(&at).map_err(|e| input(e.to_string()))
}

/// Creates the store `dir` for a study (`fingerprint`, its number of
/// `points`, a grid's `dims`) or checks that it holds that study.
#[pyfunction]
#[pyo3(signature = (dir, fingerprint, points, dims=None))]
pub(crate) fn study_open_store(
    py: Python<'_>,
    dir: PathBuf,
    fingerprint: String,
    points: usize,
    dims: Option<Vec<String>>,
) -> PyResult<()> {
    let meta = Meta {
        version: STORE_VERSION,
        fingerprint,
        points,
        dims,
    };
    Store::open(&dir, &meta)
        .map(|_| ())
        .map_err(|e| raise(py, Family::Input, e.to_string()))
}

/// Writes `record` (`(name, value)` pairs) as point `index`'s one-row
/// Parquet file of the store `dir`, atomically.
#[pyfunction]
pub(crate) fn study_write_record(
    py: Python<'_>,
    dir: PathBuf,
    index: usize,
    record: Vec<(String, Bound<'_, PyAny>)>,
) -> PyResult<()> {
    let record = record
        .iter()
        .map(|(n, v)| Ok((n.clone(), from_python(n, v)?)))
        .collect::<PyResult<Vec<_>>>()?;
    let (store, _) = Store::existing(&dir).map_err(|e| raise(py, Family::Input, e.to_string()))?;
    let path = store.record_path(index);
    py.detach(|| store::write_record(&path, &record))
        .map_err(|e| raise(py, Family::Input, e.to_string()))
}
