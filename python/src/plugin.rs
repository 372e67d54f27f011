//! Models from plugins: a plugin library by name (searched on
//! `SSM_PLUGIN_PATH`) or by path, one of its models, and its parameters as
//! keyword arguments (handed to the plugin as the TOML table its ABI takes,
//! as a scene's `[model.params]`); or the model a plugin's reducer
//! identifies from sampled signals (a scene's `[reduce]` with `[data]`). A
//! panic inside the plugin stays inside the plugin boundary and becomes a
//! `ModelError`.

use std::path::PathBuf;
use std::sync::Arc;

use numpy::PyReadonlyArray2;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

use crate::errors::{raise, Failure, Family};
use crate::model::Model;
use abi_stable::std_types::ROption;
use ssm_api::{ReducerInfo, ReducerInput, Signals, Trajectory};
use ssm_core::model::plugin::{is_path, Plugin, Registry};
use ssm_core::System;

/// A parameter value as TOML, or the error naming `key`.
fn value(py: Python<'_>, key: &str, v: &Bound<'_, PyAny>) -> PyResult<toml::Value> {
    if v.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return v.extract::<i64>().map(toml::Value::Integer).map_err(|_| {
            raise(
                py,
                Family::Input,
                format!("params: {key}: an integer beyond 64 bits"),
            )
        });
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(v.extract()?));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let items = v
            .try_iter()?
            .map(|item| value(py, key, &item?))
            .collect::<PyResult<Vec<_>>>()?;
        return Ok(toml::Value::Array(items));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        return table(py, d).map(toml::Value::Table);
    }
    // numpy scalars and other numbers
    if let Ok(x) = v.extract::<f64>() {
        return Ok(toml::Value::Float(x));
    }
    Err(raise(
        py,
        Family::Input,
        format!(
            "params: {key}: a {} is not a number, string, boolean, list or table",
            v.get_type().name()?
        ),
    ))
}

/// A dictionary of parameters as a TOML table.
fn table(py: Python<'_>, d: &Bound<'_, PyDict>) -> PyResult<toml::Table> {
    let mut t = toml::Table::new();
    for (k, v) in d.iter() {
        let key: String = k
            .extract()
            .map_err(|_| raise(py, Family::Input, "params: every key must be a string"))?;
        let v = value(py, &key, &v)?;
        t.insert(key, v);
    }
    Ok(t)
}

/// The model `model` of the plugin `plugin` (a name or a path) with the
/// parameters `params`.
#[pyfunction]
#[pyo3(signature = (plugin, model="", params=None))]
pub(crate) fn model_from_plugin(
    py: Python<'_>,
    plugin: &str,
    model: &str,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<Model> {
    let params = match params {
        Some(d) => table(py, d)?.to_string(),
        None => String::new(),
    };
    let (plugin, model) = (plugin.to_owned(), model.to_owned());
    let (system, full) = crate::work::interruptible(py, None, move |_progress| {
        let loaded = load(&plugin)?;
        let m = loaded
            .build_model(&model, &params)
            .map_err(|e| Failure::of(Family::Model, e))?;
        let system = System::from_model(loaded.name(), m.clone())
            .map_err(|e| Failure::of(Family::Model, e))?;
        Ok::<_, Failure>((system, m))
    })?
    .map_err(|f| f.raise(py))?;
    Ok(Model {
        system: Arc::new(system),
        diagnostics: Vec::new(),
        full: Some(Arc::new(full)),
    })
}

/// The plugin `plugin` (a name or a path), loaded.
fn load(plugin: &str) -> Result<Plugin, Failure> {
    if is_path(plugin) {
        Plugin::load(&PathBuf::from(plugin))
    } else {
        Registry::discover(&[]).and_then(|mut r| r.resolve(plugin))
    }
    .map_err(|e| Failure::of(Family::Model, e))
}

/// The model the reducer `reducer` of the plugin `plugin` (default: the NAR
/// identifier linked into this package) identifies from
/// sampled signals: `trajectories` (one `(samples, observables)` array each,
/// C-contiguous float64, checked by the Python layer) of the observables
/// `names` at the sampling period `period`, with the reducer's parameters
/// `params`. The reducer's diagnostics come with the model.
#[pyfunction]
#[pyo3(signature = (plugin, reducer, trajectories, period, names, params=None))]
pub(crate) fn model_from_signals(
    py: Python<'_>,
    plugin: Option<&str>,
    reducer: &str,
    trajectories: Vec<PyReadonlyArray2<'_, f64>>,
    period: f64,
    names: Vec<String>,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<Model> {
    let params = match params {
        Some(d) => table(py, d)?.to_string(),
        None => String::new(),
    };
    // the plugin ABI owns its samples (row-major): one copy of the signals
    let trajectories: Vec<Trajectory> = trajectories
        .iter()
        .enumerate()
        .map(|(k, a)| {
            let samples: Vec<f64> = a.as_array().iter().copied().collect();
            Trajectory {
                source: format!("signals[{k}]").as_str().into(),
                t0: 0.0,
                samples: samples.into(),
            }
        })
        .collect();
    let signals = Signals {
        names: names.iter().map(|n| n.as_str().into()).collect(),
        period,
        trajectories: trajectories.into(),
    };
    let (plugin, reducer) = (plugin.map(str::to_owned), reducer.to_owned());
    let (system, diagnostics) = crate::work::interruptible(py, None, move |_progress| {
        let input = ReducerInput {
            model: ROption::RNone,
            signals: ROption::RSome(signals),
        };
        let unknown = |by: &str, offered: &[ReducerInfo]| {
            let names: Vec<&str> = offered.iter().map(|r| r.name.as_str()).collect();
            Failure(
                Family::Input,
                format!(
                    "reducer: {by} has no reducer '{reducer}'; it offers: {}",
                    if names.is_empty() {
                        "none".into()
                    } else {
                        names.join(", ")
                    }
                ),
            )
        };
        let (origin, reduced) = match plugin {
            // the NAR identifier linked into this package
            None => {
                let offered = nar_identifier::reducers();
                if !offered.iter().any(|r| r.name.as_str() == reducer) {
                    return Err(unknown("the NAR identifier", &offered));
                }
                let reduced = nar_identifier::reduce(&reducer, &params, &input)
                    .map_err(|e| Failure::of(Family::Model, e))?;
                ("nar-identifier".to_owned(), reduced)
            }
            Some(plugin) => {
                let loaded = load(&plugin)?;
                let offered = match loaded.reducers() {
                    Some(list) => list.map_err(|e| Failure::of(Family::Model, e))?,
                    None => Vec::new(),
                };
                let Some(info) = offered.iter().find(|r| r.name.as_str() == reducer) else {
                    return Err(unknown(&format!("plugin '{}'", loaded.name()), &offered));
                };
                if info.needs.model() {
                    return Err(Failure(
                        Family::Input,
                        format!("reducer: '{reducer}' reduces a model, not signals"),
                    ));
                }
                let reduced = loaded
                    .reduce(&reducer, &params, &input)
                    .map_err(|e| Failure::of(Family::Model, e))?;
                (loaded.name().to_owned(), reduced)
            }
        };
        let diagnostics = reduced
            .diagnostics
            .iter()
            .map(|d| (d.name.to_string(), d.values.to_vec(), d.text.to_string()))
            .collect::<Vec<_>>();
        let system = System::from_model(&origin, reduced.model)
            .map_err(|e| Failure::of(Family::Model, e))?;
        Ok((system, diagnostics))
    })?
    .map_err(|f| f.raise(py))?;
    Ok(Model {
        system: Arc::new(system),
        diagnostics,
        full: None,
    })
}
