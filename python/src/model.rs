//! Models from arrays and from model folders: both fill the engine's
//! [`ModelFiles`] and take the path of the `matrix-model` plugin
//! (`mechanical_from_files`, then the engine's validation), so a model
//! given as arrays is the same model as its folder.

use std::path::PathBuf;
use std::sync::Arc;

use numpy::{Complex64, PyArray1, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{raise, Failure, Family};
use ssm_api::{PolyVector, SparseMatrix};
use ssm_core::spectrum::{self, SpectrumOptions};
use ssm_core::System;
use ssm_engine::plan::budget::Limits;
use ssm_model_files::{mass_defect, ModelFiles};

/// Indices as Python hands them over: 32- or 64-bit (scipy's choice),
/// borrowed.
#[derive(FromPyObject)]
enum Indices<'py> {
    /// `int32` indices.
    Narrow(PyReadonlyArray1<'py, i32>),
    /// `int64` indices.
    Wide(PyReadonlyArray1<'py, i64>),
}

impl Indices<'_> {
    /// The `k`-th index (negative values stay negative, for the checks).
    fn at(&self, view: &IndexView<'_>, k: usize) -> i64 {
        match (self, view) {
            (Indices::Narrow(_), IndexView::Narrow(v)) => i64::from(v[k]),
            (Indices::Wide(_), IndexView::Wide(v)) => v[k],
            _ => -1,
        }
    }

    /// A view of the indices (any strides; no copy).
    fn view(&self) -> IndexView<'_> {
        match self {
            Indices::Narrow(a) => IndexView::Narrow(a.as_array()),
            Indices::Wide(a) => IndexView::Wide(a.as_array()),
        }
    }

    fn len(&self) -> usize {
        match self {
            Indices::Narrow(a) => a.as_array().len(),
            Indices::Wide(a) => a.as_array().len(),
        }
    }
}

/// A borrowed view of [`Indices`].
enum IndexView<'a> {
    Narrow(numpy::ndarray::ArrayView1<'a, i32>),
    Wide(numpy::ndarray::ArrayView1<'a, i64>),
}

/// Bytes a stored matrix entry costs while a model is built and kept (its
/// triplet, the first-order system's `A` and `B`, their validation and the
/// copy the POD study keeps; measured: 430-460 bytes per entry of a chain
/// of 10^6 and 3 x 10^6 masses with Rayleigh damping, peak resident memory).
const BYTES_PER_ENTRY: f64 = 500.0;

/// Bytes a degree of freedom costs beside its entries (names, outputs,
/// vectors of the first-order system).
const BYTES_PER_DOF: f64 = 200.0;

impl MatrixIn<'_> {
    /// Stored entries (a dense array: its nonzeros, counted in place).
    fn entries(&self) -> usize {
        match self {
            MatrixIn::Dense(a) => a.as_array().iter().filter(|x| **x != 0.0).count(),
            MatrixIn::Compressed(_, _, _, data) => data.as_array().len(),
            MatrixIn::Coordinates(_, _, values) => values.as_array().len(),
        }
    }
}

/// A matrix as Python hands it over, its buffers borrowed, not copied: a
/// dense `float64` array (any strides), scipy's compressed rows or columns
/// `("csr" | "csc", indptr, indices, data)`, or coordinates `(rows, cols,
/// values)`, 0-based.
#[derive(FromPyObject)]
enum MatrixIn<'py> {
    /// A dense array.
    Dense(PyReadonlyArray2<'py, f64>),
    /// Compressed sparse rows or columns.
    Compressed(
        String,
        Indices<'py>,
        Indices<'py>,
        PyReadonlyArray1<'py, f64>,
    ),
    /// Coordinates.
    Coordinates(Indices<'py>, Indices<'py>, PyReadonlyArray1<'py, f64>),
}

/// A force tensor as `(indices, values)`: row `r` of `indices` is
/// `(i, j, k)` (`f_i += v x_j x_k`) or `(i, j, k, l)`, 0-based.
type Tensor<'py> = (PyReadonlyArray2<'py, i64>, PyReadonlyArray1<'py, f64>);

/// A model of the engine: its first-order system `B z' = A z + F(z)` (a
/// mechanical model `M x'' + C x' + K x + f(x) = eps fext cos(Omega t)` with
/// constraints, in the engine's form).
#[pyclass(module = "ssm._ssm", frozen)]
pub struct Model {
    pub(crate) system: Arc<System>,
    /// What the reducer that made the model reported (name, numbers, text).
    pub(crate) diagnostics: Vec<(String, Vec<f64>, String)>,
    /// The model as its source gave it, before validation (the POD study
    /// projects it); `None` for a model a reducer identified from data.
    pub(crate) full: Option<Arc<ssm_api::Model>>,
}

/// The slice of a read-only array, or the error naming `arg`.
fn slice<'a, T: numpy::Element>(
    py: Python<'_>,
    a: &'a PyReadonlyArray1<'_, T>,
    arg: &str,
) -> PyResult<&'a [T]> {
    a.as_slice().map_err(|_| {
        raise(
            py,
            Family::Input,
            format!("{arg}: the array is not contiguous"),
        )
    })
}

/// The `nrows x ncols` matrix `arg` read straight from the buffers of
/// `given` (the engine's matrix is the one copy): indices in range, values
/// finite, zeros left out.
fn matrix(
    py: Python<'_>,
    arg: &str,
    given: &MatrixIn<'_>,
    (nrows, ncols): (usize, usize),
) -> PyResult<SparseMatrix> {
    let fail = |message: String| raise(py, Family::Input, format!("{arg}: {message}"));
    let mut m = SparseMatrix::zeros(nrows, ncols);
    let mut put = |i: i64, j: i64, x: f64| -> PyResult<()> {
        let (Some(r), Some(c)) = (index(i, nrows), index(j, ncols)) else {
            return Err(fail(format!(
                "entry ({i}, {j}) lies outside the {nrows} x {ncols} matrix"
            )));
        };
        if !x.is_finite() {
            return Err(fail(format!(
                "entry ({i}, {j}) is {x}; every value must be finite"
            )));
        }
        m.push(r, c, x);
        Ok(())
    };
    match given {
        MatrixIn::Dense(a) => {
            let a = a.as_array();
            if a.dim() != (nrows, ncols) {
                return Err(fail(format!(
                    "shape {:?}, expected ({nrows}, {ncols})",
                    a.dim()
                )));
            }
            for ((i, j), &x) in a.indexed_iter() {
                if x != 0.0 {
                    put(i as i64, j as i64, x)?;
                }
            }
        }
        MatrixIn::Compressed(format, indptr, indices, data) => {
            let by_rows = match format.as_str() {
                "csr" => true,
                "csc" => false,
                other => return Err(fail(format!("format '{other}' is not csr or csc"))),
            };
            let major = if by_rows { nrows } else { ncols };
            let (ptr, idx, data) = (indptr.view(), indices.view(), data.as_array());
            if indptr.len() != major + 1 || indices.len() != data.len() {
                return Err(fail(format!(
                    "indptr of {} entries, {} indices and {} values for {major} {}",
                    indptr.len(),
                    indices.len(),
                    data.len(),
                    if by_rows { "rows" } else { "columns" }
                )));
            }
            for outer in 0..major {
                let (start, end) = (indptr.at(&ptr, outer), indptr.at(&ptr, outer + 1));
                let (Some(start), Some(end)) =
                    (index(start, data.len() + 1), index(end, data.len() + 1))
                else {
                    return Err(fail(format!(
                        "indptr[{outer}..] = {start}, {end} outside 0..={}",
                        data.len()
                    )));
                };
                if end < start {
                    return Err(fail(format!("indptr decreases at {outer}")));
                }
                for k in start..end {
                    let inner = indices.at(&idx, k);
                    let (i, j) = if by_rows {
                        (outer as i64, inner)
                    } else {
                        (inner, outer as i64)
                    };
                    put(i, j, data[k])?;
                }
            }
        }
        MatrixIn::Coordinates(rows, cols, vals) => {
            let (r, c, v) = (rows.view(), cols.view(), vals.as_array());
            if rows.len() != v.len() || cols.len() != v.len() {
                return Err(fail(format!(
                    "{} row indices, {} column indices and {} values",
                    rows.len(),
                    cols.len(),
                    v.len()
                )));
            }
            for (k, &x) in v.iter().enumerate() {
                put(rows.at(&r, k), cols.at(&c, k), x)?;
            }
        }
    }
    Ok(m)
}

/// `i` as an index below `n`.
fn index(i: i64, n: usize) -> Option<usize> {
    usize::try_from(i).ok().filter(|&i| i < n)
}

/// The degree-`degree` tensor `arg` added to `poly` (`n_eq` equations in
/// `n` displacements).
fn tensor(
    py: Python<'_>,
    arg: &str,
    (idx, vals): &Tensor<'_>,
    degree: usize,
    poly: &mut PolyVector,
    n: usize,
) -> PyResult<()> {
    let idx = idx.as_array();
    let v = slice(py, vals, arg)?;
    if idx.ncols() != degree + 1 || idx.nrows() != v.len() {
        return Err(raise(
            py,
            Family::Input,
            format!(
                "{arg}: indices of shape ({}, {}) and {} values; a degree-{degree} tensor takes indices of shape (k, {}) and k values",
                idx.nrows(),
                idx.ncols(),
                v.len(),
                degree + 1
            ),
        ));
    }
    let n_eq = poly.n_eq as usize;
    let mut factors = Vec::with_capacity(degree);
    for (row, &x) in idx.rows().into_iter().zip(v) {
        let Some(eq) = index(row[0], n_eq) else {
            return Err(raise(
                py,
                Family::Input,
                format!("{arg}: equation index {} outside 0..{n_eq}", row[0]),
            ));
        };
        factors.clear();
        for &j in row.iter().skip(1) {
            let Some(j) = index(j, n) else {
                return Err(raise(
                    py,
                    Family::Input,
                    format!("{arg}: displacement index {j} outside 0..{n}"),
                ));
            };
            factors.push((j, 1));
        }
        if !x.is_finite() {
            return Err(raise(
                py,
                Family::Input,
                format!("{arg}: a value is {x}; every value must be finite"),
            ));
        }
        poly.push(eq, x, &factors);
    }
    Ok(())
}

/// The engine's model of the folder contents `files`, named `name`, and
/// the model as given (for the POD study).
fn build(
    files: ModelFiles,
    name: &str,
    rayleigh: Option<(f64, f64)>,
) -> Result<(System, ssm_api::Model), Failure> {
    if let Some(problem) = mass_defect(&files.mass, files.constraint_jacobian.is_some()) {
        return Err(Failure(Family::Model, format!("M: {problem}")));
    }
    let mechanical =
        ssm_plugin_kit::mechanical_from_files(files, name, rayleigh.map(|(a, b)| [a, b]))
            .map_err(|e| Failure(Family::Input, format!("outputs: {e}")))?;
    let model = mechanical
        .into_model()
        .map_err(|e| Failure::of(Family::Model, e))?;
    let system =
        System::from_model(name, model.clone()).map_err(|e| Failure::of(Family::Model, e))?;
    Ok((system, model))
}

#[pymethods]
impl Model {
    /// The model `M x'' + C x' + K x + f2(x) + f3(x) = eps fext cos(Omega t)`
    /// with constraints `G x + g2(x) + g3(x) = 0`, from 0-based coordinate
    /// arrays: each matrix dense, compressed (`("csr" | "csc", indptr,
    /// indices, data)`) or coordinates, its buffers read in place (see
    /// `ssm.from_arrays`, which hands scipy's buffers over).
    #[staticmethod]
    #[pyo3(signature = (name, n, mass, stiffness, damping=None, rayleigh=None, f2=None, f3=None, constraints=None, g2=None, g3=None, fext=None, outputs=Vec::new()))]
    #[allow(clippy::too_many_arguments)]
    fn from_coo(
        py: Python<'_>,
        name: &str,
        n: usize,
        mass: MatrixIn<'_>,
        stiffness: MatrixIn<'_>,
        damping: Option<MatrixIn<'_>>,
        rayleigh: Option<(f64, f64)>,
        f2: Option<Tensor<'_>>,
        f3: Option<Tensor<'_>>,
        constraints: Option<(usize, MatrixIn<'_>)>,
        g2: Option<Tensor<'_>>,
        g3: Option<Tensor<'_>>,
        fext: Option<PyReadonlyArray1<'_, f64>>,
        outputs: Vec<(String, Vec<(usize, f64)>)>,
    ) -> PyResult<Model> {
        if n == 0 {
            return Err(raise(
                py,
                Family::Input,
                "M: the model has no degree of freedom",
            ));
        }
        if u32::try_from(n).is_err() {
            return Err(raise(
                py,
                Family::Input,
                format!(
                    "M: {n} degrees of freedom; the engine takes at most {}",
                    u32::MAX
                ),
            ));
        }
        // the engine's one gate, before anything is allocated: the model's
        // matrices, first-order system and the copy the POD study keeps
        let entries = [Some(&mass), Some(&stiffness), damping.as_ref()]
            .into_iter()
            .flatten()
            .chain(constraints.as_ref().map(|(_, g)| g))
            .map(MatrixIn::entries)
            .sum::<usize>()
            + [&f2, &f3, &g2, &g3]
                .into_iter()
                .flatten()
                .map(|(idx, _)| idx.as_array().len())
                .sum::<usize>();
        let damped = if rayleigh.is_some() { 2.0 } else { 1.0 };
        let bytes = BYTES_PER_ENTRY * entries as f64 * damped + BYTES_PER_DOF * n as f64;
        let limits = Limits::of_machine();
        if bytes > limits.bytes {
            return Err(raise(
                py,
                Family::Input,
                format!(
                    "M: a model of {n} degrees of freedom and {entries} stored entries needs about {:.1} GB to build; this process may use {:.1} GB ({})",
                    bytes / 1e9,
                    limits.bytes / 1e9,
                    limits.memory_source
                ),
            ));
        }
        let mass = matrix(py, "M", &mass, (n, n))?;
        if let Some((i, j, a, b)) = mass.asymmetry(1e-12) {
            return Err(raise(
                py,
                Family::Input,
                format!("M: not symmetric: M[{i}, {j}] = {a} but M[{j}, {i}] = {b}"),
            ));
        }
        let stiffness = matrix(py, "K", &stiffness, (n, n))?;
        let damping = damping.map(|c| matrix(py, "C", &c, (n, n))).transpose()?;
        if let (Some(_), Some(_)) = (&damping, rayleigh) {
            return Err(raise(
                py,
                Family::Input,
                "rayleigh: give C or Rayleigh damping, not both",
            ));
        }
        let mut internal_force = PolyVector::zeros(n, n);
        if let Some(t) = &f2 {
            tensor(py, "f2", t, 2, &mut internal_force, n)?;
        }
        if let Some(t) = &f3 {
            tensor(py, "f3", t, 3, &mut internal_force, n)?;
        }
        let nc = constraints.as_ref().map_or(0, |(nc, _)| *nc);
        let constraint_jacobian = constraints
            .map(|(nc, g)| matrix(py, "G", &g, (nc, n)))
            .transpose()?;
        let mut constraint_terms = PolyVector::zeros(nc, n);
        for (arg, t, degree) in [("g2", &g2, 2), ("g3", &g3, 3)] {
            if let Some(t) = t {
                if nc == 0 {
                    return Err(raise(py, Family::Input, format!("{arg}: give G first")));
                }
                tensor(py, arg, t, degree, &mut constraint_terms, n)?;
            }
        }
        let load = match fext {
            Some(f) => {
                let f = slice(py, &f, "fext")?;
                if f.len() != n || f.iter().any(|v| !v.is_finite()) {
                    return Err(raise(
                        py,
                        Family::Input,
                        format!("fext: {} finite values are needed, found {}", n, f.len()),
                    ));
                }
                Some(f.to_vec())
            }
            None => None,
        };
        for (name, weights) in &outputs {
            if let Some((j, _)) = weights.iter().find(|(j, _)| *j >= n) {
                return Err(raise(
                    py,
                    Family::Input,
                    format!("outputs: '{name}' weighs displacement {j}, outside 0..{n}"),
                ));
            }
        }
        let files = ModelFiles {
            mass,
            stiffness,
            damping,
            constraint_jacobian,
            internal_force,
            constraint_terms,
            load,
            outputs,
        };
        let name = name.to_owned();
        let (system, full) =
            crate::work::interruptible(py, None, move |_progress| build(files, &name, rayleigh))?
                .map_err(|f| f.raise(py))?;
        Ok(Model {
            system: Arc::new(system),
            diagnostics: Vec::new(),
            full: Some(Arc::new(full)),
        })
    }

    /// The model of the folder `dir` (the files of `docs/models.md`), with
    /// Rayleigh damping `C = alpha M + beta K` when it has no `C.mtx`.
    #[staticmethod]
    #[pyo3(signature = (dir, rayleigh=None))]
    fn from_files(py: Python<'_>, dir: PathBuf, rayleigh: Option<(f64, f64)>) -> PyResult<Model> {
        let (system, full) = crate::work::interruptible(py, None, move |_progress| {
            let files =
                ModelFiles::read(&dir, &mut |_| {}).map_err(|e| Failure::of(Family::Input, e))?;
            build(files, "model-files", rayleigh)
        })?
        .map_err(|f| f.raise(py))?;
        Ok(Model {
            system: Arc::new(system),
            diagnostics: Vec::new(),
            full: Some(Arc::new(full)),
        })
    }

    /// The model's name.
    #[getter]
    fn name(&self) -> String {
        self.system.name.clone()
    }

    /// States of the first-order system.
    #[getter]
    fn n_states(&self) -> usize {
        self.system.n_states()
    }

    /// What the reducer that identified the model reported (name ->
    /// numbers, or text where it reported no numbers); empty for other
    /// models.
    #[getter]
    fn diagnostics<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (name, values, text) in &self.diagnostics {
            if values.is_empty() {
                d.set_item(name, text)?;
            } else {
                d.set_item(name, PyArray1::from_slice(py, values))?;
            }
        }
        Ok(d)
    }

    /// The names of the model's outputs.
    #[getter]
    fn outputs(&self) -> Vec<String> {
        self.system.outputs.iter().map(|o| o.name.clone()).collect()
    }

    /// The finite eigenvalues of the pencil `(A, B)` (dense up to 100 states,
    /// else the `modes` nearest the origin by the sparse path).
    #[pyo3(signature = (modes=None))]
    fn spectrum<'py>(
        &self,
        py: Python<'py>,
        modes: Option<usize>,
    ) -> PyResult<Bound<'py, PyArray1<Complex64>>> {
        let system = Arc::clone(&self.system);
        let eigenvalues = crate::work::interruptible(py, None, move |_progress| {
            let options = SpectrumOptions {
                method: None,
                modes: modes.unwrap_or(12),
                shift: 0.0,
                normalization: Default::default(),
                velocities: system.velocities(),
            };
            spectrum::compute(system.a.as_ref(), system.b.as_ref(), &options)
                .map(|s| s.eigenvalues)
                .map_err(|e| Failure::of(Family::Spectrum, e))
        })?
        .map_err(|f| f.raise(py))?;
        Ok(PyArray1::from_vec(py, eigenvalues))
    }

    fn __repr__(&self) -> String {
        let outputs = self.outputs();
        // a model from arrays names every coordinate: the first few and
        // the count
        let shown = if outputs.len() > 6 {
            let head: Vec<&str> = outputs[..3].iter().map(String::as_str).collect();
            let tail = &outputs[outputs.len() - 1];
            format!(
                "[{}, ..., {tail}] ({} outputs)",
                head.join(", "),
                outputs.len()
            )
        } else {
            format!("{outputs:?}")
        };
        format!(
            "Model('{}', {} states, outputs {shown})",
            self.system.name,
            self.system.n_states(),
        )
    }
}
