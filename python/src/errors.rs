//! The engine's errors as the exceptions of `ssm.errors` (the Python
//! package defines the classes and their hierarchy; this module raises
//! them by name, with the engine's message).

use pyo3::prelude::*;

/// An exception family of `ssm.errors`.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Family {
    /// An argument the engine cannot take (shape, dtype, value, index).
    Input,
    /// The model is inconsistent (the engine's `ModelError`, a build error).
    Model,
    /// The spectrum could not be computed.
    Spectrum,
    /// The SSM could not be computed.
    Expansion,
    /// An answer read off the SSM could not be produced.
    Analysis,
}

impl Family {
    fn class(self) -> &'static str {
        match self {
            Family::Input => "InputError",
            Family::Model => "ModelError",
            Family::Spectrum => "SpectrumError",
            Family::Expansion => "ExpansionError",
            Family::Analysis => "AnalysisError",
        }
    }
}

/// An error of `family` with `message`, raised as its class of
/// `ssm.errors` (or as the error of importing it).
pub(crate) fn raise(py: Python<'_>, family: Family, message: impl Into<String>) -> PyErr {
    let message = message.into();
    let made = py
        .import("ssm.errors")
        .and_then(|m| m.getattr(family.class()))
        .and_then(|class| class.call1((message,)));
    match made {
        Ok(instance) => PyErr::from_value(instance),
        Err(e) => e,
    }
}

/// A failure inside a computation that ran without the GIL: its family and
/// message, raised once the GIL is back.
#[derive(Debug)]
pub(crate) struct Failure(pub Family, pub String);

impl Failure {
    /// The failure of `family` for the error `e`.
    pub(crate) fn of(family: Family, e: impl std::fmt::Display) -> Self {
        Self(family, e.to_string())
    }

    /// As a Python exception.
    pub(crate) fn raise(self, py: Python<'_>) -> PyErr {
        raise(py, self.0, self.1)
    }
}
