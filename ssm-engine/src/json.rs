//! Small shapes shared by the typed entries of `summary.json` and
//! `identified.json`: complex numbers, a number or a list, a reducer's
//! diagnostics, and the work of a stage's sparse linear algebra.

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use ssm_core::C64;

/// A complex number.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Complex {
    /// Real part.
    pub re: f64,
    /// Imaginary part.
    pub im: f64,
}

impl From<C64> for Complex {
    fn from(z: C64) -> Self {
        Complex { re: z.re, im: z.im }
    }
}

/// One value for one master pair, a list (one per pair) for several.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum PerPair<T> {
    /// The SSM has one master pair.
    One(T),
    /// One per master pair.
    Each(Vec<T>),
}

impl<T: Clone> PerPair<T> {
    /// `values[0]` alone when `one_pair`, else all of them.
    pub fn of(values: &[T], one_pair: bool) -> Self {
        match (one_pair, values.first()) {
            (true, Some(v)) => PerPair::One(v.clone()),
            _ => PerPair::Each(values.to_vec()),
        }
    }
}

/// One diagnostic of a reducer: text, a number, a list, or both a list and
/// text (a number that is not finite is null).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum DiagnosticValue {
    /// Text alone.
    Text(String),
    /// One number.
    Number(Option<f64>),
    /// Several numbers (or none).
    Numbers(Vec<Option<f64>>),
    /// Numbers and text.
    Both {
        /// The numbers.
        values: Vec<Option<f64>>,
        /// The text.
        text: String,
    },
}

/// A reducer's diagnostics by name.
pub type Diagnostics = BTreeMap<String, DiagnosticValue>;

/// `list` by name: text, one number, a list, or both.
pub fn diagnostics(list: &[ssm_api::Diagnostic]) -> Diagnostics {
    let finite = |v: &f64| v.is_finite().then_some(*v);
    list.iter()
        .map(|d| {
            let v = match (d.values.len(), d.text.is_empty()) {
                (_, false) if d.values.is_empty() => DiagnosticValue::Text(d.text.to_string()),
                (1, true) => DiagnosticValue::Number(finite(&d.values[0])),
                (_, true) => DiagnosticValue::Numbers(d.values.iter().map(finite).collect()),
                _ => DiagnosticValue::Both {
                    values: d.values.iter().map(finite).collect(),
                    text: d.text.to_string(),
                },
            };
            (d.name.to_string(), v)
        })
        .collect()
}

/// The work of one stage's sparse linear algebra with the full system's
/// matrices (`Lambda B - A`); the seconds are in `timing_s`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LinearWork {
    /// Symbolic factorizations (sparsity analyses).
    pub symbolic_factorizations: usize,
    /// Numeric factorizations.
    pub numeric_factorizations: usize,
    /// Solves (each with its residual check and refinement).
    pub solves: usize,
    /// Krylov steps of the band solves made through a factorization at a
    /// nearby value: directions added to a band's shared search space and
    /// terms of a band's Taylor series in `Omega` (each a refined solve
    /// through that factorization and products with `A` and `B`).
    pub krylov_iterations: usize,
}

impl LinearWork {
    /// The work counted by a homological solver.
    pub fn of(counts: ssm_core::ssm::SolveCounts) -> Self {
        LinearWork {
            symbolic_factorizations: counts.symbolic,
            numeric_factorizations: counts.factorizations,
            solves: counts.solves,
            krylov_iterations: counts.iterations,
        }
    }
}
