//! Models from plugins: a plugin library by name (searched on
//! `SSM_PLUGIN_PATH`) or by path, one of its models, and its parameters as
//! keyword arguments (handed to the plugin as the TOML table its ABI takes,
//! as a scene's `[model.params]`). A panic inside the plugin stays inside
//! the plugin boundary and becomes a `ModelError`.

use std::path::PathBuf;
use std::sync::Arc;

use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

use crate::errors::{raise, Failure, Family};
use crate::model::Model;
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
    let system = py
        .detach(move || {
            let loaded = if is_path(&plugin) {
                Plugin::load(&PathBuf::from(&plugin))
            } else {
                Registry::discover(&[]).and_then(|mut r| r.resolve(&plugin))
            }
            .map_err(|e| Failure::of(Family::Model, e))?;
            let m = loaded
                .build_model(&model, &params)
                .map_err(|e| Failure::of(Family::Model, e))?;
            System::from_model(loaded.name(), m).map_err(|e| Failure::of(Family::Model, e))
        })
        .map_err(|f| f.raise(py))?;
    Ok(Model {
        system: Arc::new(system),
    })
}
