//! The reducer entry (API 1.1): a plugin turns sampled signals and/or a model
//! into a reduced [`Model`] (flow or map), with an optional lift back to the
//! full coordinates and named diagnostics.
//!
//! Reducers are what the NAR identifier (signals -> map model; Szalai, Ehrhardt
//! & Haller 2017) and POD with constraint reduction (model + snapshots ->
//! reduced model; Stadlmayr, Witteveen & Steiner 2017) are; everything the
//! engine computes downstream (spectrum, SSM, backbone, forced response)
//! works on the reduced model as on any other.

use abi_stable::std_types::{ROption, RString, RVec};
use abi_stable::StableAbi;

use crate::listing::ParamInfo;
use crate::model::{Model, SparseMatrix, StateInfo};

/// What a reducer takes: sampled signals, a model, or both (bit set; a
/// transparent `u8` so that later versions can add kinds of input).
#[repr(transparent)]
#[derive(StableAbi, Clone, Copy, PartialEq, Eq, Hash)]
pub struct InputNeeds(pub u8);

#[allow(non_upper_case_globals)]
impl InputNeeds {
    /// Sampled signals only (`[data]`).
    pub const Signals: Self = Self(1);
    /// A model only (`[model]`).
    pub const Model: Self = Self(2);
    /// Both a model and signals (e.g. snapshots of its simulation).
    pub const Both: Self = Self(3);

    /// Whether signals are required.
    pub fn signals(self) -> bool {
        self.0 & 1 != 0
    }

    /// Whether a model is required.
    pub fn model(self) -> bool {
        self.0 & 2 != 0
    }
}

impl std::fmt::Debug for InputNeeds {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match (self.signals(), self.model()) {
            (true, true) => f.write_str("signals and a model"),
            (true, false) => f.write_str("signals"),
            (false, true) => f.write_str("a model"),
            (false, false) => write!(f, "input kind {}", self.0),
        }
    }
}

/// Listing of one reducer a plugin offers.
#[repr(C)]
#[derive(StableAbi, Clone, Debug, PartialEq)]
pub struct ReducerInfo {
    /// Reducer name (`[reduce] reducer = ...`).
    pub name: RString,
    /// One line on what it does and which paper/equations it implements.
    pub description: RString,
    /// Parameters with defaults (`[reduce.params]`).
    pub params: RVec<ParamInfo>,
    /// What input it needs.
    pub needs: InputNeeds,
}

/// One sampled trajectory: `n_samples` rows of `n_observables` values
/// (row-major), at times `t0 + k T`.
#[repr(C)]
#[derive(StableAbi, Clone, Debug, PartialEq)]
pub struct Trajectory {
    /// Where it came from (a file name), for error messages.
    pub source: RString,
    /// Time of the first sample.
    pub t0: f64,
    /// Samples, row-major (`samples[k * n_observables + j]` is observable `j` at sample `k`).
    pub samples: RVec<f64>,
}

/// Uniformly sampled signals of named observables, one or more trajectories.
#[repr(C)]
#[derive(StableAbi, Clone, Debug, PartialEq)]
pub struct Signals {
    /// Observable names (the CSV columns after `t`).
    pub names: RVec<RString>,
    /// Sampling period `T`.
    pub period: f64,
    /// The trajectories.
    pub trajectories: RVec<Trajectory>,
}

impl Signals {
    /// Number of observables.
    pub fn n_observables(&self) -> usize {
        self.names.len()
    }

    /// Number of samples of trajectory `k`.
    pub fn n_samples(&self, k: usize) -> usize {
        self.trajectories[k].samples.len() / self.n_observables().max(1)
    }

    /// Sample `i` of trajectory `k` (one value per observable).
    pub fn sample(&self, k: usize, i: usize) -> &[f64] {
        let m = self.n_observables();
        &self.trajectories[k].samples[i * m..(i + 1) * m]
    }
}

/// What a reducer is given.
#[repr(C)]
#[derive(StableAbi, Clone, Debug, PartialEq)]
pub struct ReducerInput {
    /// The model of `[model]`, as its plugin built it.
    pub model: ROption<Model>,
    /// The signals of `[data]`.
    pub signals: ROption<Signals>,
}

/// The map from reduced to full coordinates `z ~ V y + z0`.
#[repr(C)]
#[derive(StableAbi, Clone, Debug, PartialEq)]
pub struct Lift {
    /// `V` (`N x n`): full states by reduced states.
    pub basis: SparseMatrix,
    /// `z0` (`N`), empty for zero.
    pub offset: RVec<f64>,
    /// Names and tags of the `N` full states.
    pub full_states: RVec<StateInfo>,
}

/// A named diagnostic of a reduction (fit residual, captured energy, singular
/// values, removed constraints, ...), written to `summary.json`.
#[repr(C)]
#[derive(StableAbi, Clone, Debug, PartialEq)]
pub struct Diagnostic {
    /// Name (a JSON key).
    pub name: RString,
    /// Numbers (one for a scalar; empty when the diagnostic is text only).
    pub values: RVec<f64>,
    /// Text (empty when numeric only).
    pub text: RString,
}

impl Diagnostic {
    /// A numeric diagnostic.
    pub fn values(name: &str, values: &[f64]) -> Self {
        Self {
            name: name.into(),
            values: values.iter().copied().collect(),
            text: RString::new(),
        }
    }

    /// A text diagnostic.
    pub fn text(name: &str, text: &str) -> Self {
        Self {
            name: name.into(),
            values: RVec::new(),
            text: text.into(),
        }
    }
}

/// What a reducer returns.
#[repr(C)]
#[derive(StableAbi, Clone, Debug, PartialEq)]
pub struct Reduced {
    /// The reduced model (flow or map).
    pub model: Model,
    /// The lift back to the full coordinates, when there are any.
    pub lift: ROption<Lift>,
    /// Diagnostics for `summary.json`.
    pub diagnostics: RVec<Diagnostic>,
}
