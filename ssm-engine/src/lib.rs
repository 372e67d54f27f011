//! # ssm-engine
//!
//! Nonlinear model reduction of mechanical systems, possibly with configuration
//! constraints (DAEs), on spectral submanifolds (SSMs). Models arrive as
//! plugins through the stable ABI of [`ssm_api`].
//!
//! Modules, one concern each:
//! - [`plugin`]: finding and loading plugins, ABI/version checks;
//! - [`scene`]: the TOML scene format, validated with line numbers;
//! - [`layout`]: the declared constraint layout, checked and made canonical;
//! - [`system`]: the engine-side first-order system built from a plugin's model;
//! - [`recast`]: non-polynomial terms turned into a polynomial DAE with
//!   auxiliary states, equilibrium shift, and the physical pencil;
//! - [`reduce`]: models made by reducers, from `[data]` signals and/or a model;
//! - [`spectrum`]: finite spectrum of the (possibly singular) pencil `(A, B)`,
//!   master modes, normalization, spectral quotients and non-resonance checks;
//! - [`poly`]: multi-indices, truncated series, order-by-order composition `F(W(p))`;
//! - [`ssm`]: autonomous SSMs of flows and maps (parametrization method),
//!   polar form, backbones, invariance error, reduced-model transients;
//! - [`frc`]: forced response curves of 2-D SSMs, stability and folds;
//! - [`continuation`]: forced response of several pairs (pseudo-arclength,
//!   folds, branch points with switching, Hopf points);
//! - [`simulate`]: full-system Radau IIA integration of the DAE, consistent
//!   initial values, steady states by criterion (47);
//! - [`validate`]: full against reduced trajectories, distance to the SSM,
//!   steady-state references in parallel;
//! - [`results`]: SSM entries of the summary, backbone and transient files;
//! - [`results_frc`]: `frc.csv`, `frc.svg` and the summary's `frc`;
//! - [`results_validate`]: `validation.csv/svg`, `steady_state.csv` and the
//!   summary's `validation`;
//! - [`results_report`]: the speed-against-error report (`report.csv/md/svg`);
//! - [`plot`]: SVG plots;
//! - [`report`]: `summary.json` and CSV tables, written atomically;
//! - [`job`]: running a scene end to end.

pub mod compare;
pub mod fom;
pub mod model;
pub mod output;
pub mod pipeline;
pub mod poly;
pub mod reduce;
pub mod results;
pub mod results_frc;
pub mod results_frc_multi;
pub mod results_report;
pub mod results_validate;
pub mod rom;
pub mod scene;
pub mod spectrum;
pub mod ssm;

pub use num_complex::Complex64 as C64;
