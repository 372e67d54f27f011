//! # ssm-engine
//!
//! Nonlinear model reduction of mechanical systems, possibly with configuration
//! constraints (DAEs), on spectral submanifolds (SSMs). Models arrive as
//! plugins through the stable ABI of [`ssm_api`].
//!
//! The folders follow the pipeline of a run ([`pipeline::run`]):
//! - [`scene`]: the TOML scene format, validated with line numbers;
//! - [`plan`]: a scene's sections resolved to the span-free [`spec`]s that
//!   the numerics take (code builds specs directly: no TOML below `plan`);
//! - [`model`]: plugins found and loaded, the declared constraint layout, the
//!   engine-side first-order system, the recast of non-polynomial terms;
//! - [`reduce`]: models made by reducers, from `[data]` signals and/or a model;
//! - [`spectrum`]: finite spectrum of the (possibly singular) pencil `(A, B)`,
//!   master modes, normalization, spectral quotients and non-resonance checks;
//! - [`poly`]: multi-indices, truncated series, order-by-order composition `F(W(p))`;
//! - [`ssm`]: autonomous and periodic SSMs of flows and maps (parametrization
//!   method), polar form, invariance error, reduced dynamics;
//! - [`rom`]: answers of the reduced model: backbones, lifted transients,
//!   forced response curves (one pair; several pairs by continuation);
//! - [`fom`]: the full-order model: Radau IIA integration of the DAE,
//!   consistent initial values, steady states by criterion (47);
//! - [`analyses`]: analyses added as vertical slices (one folder each:
//!   spec, run, writer; one registration line), e.g. the damping curve;
//! - [`compare`]: full against reduced (transients, distance to the SSM,
//!   steady-state references) and the speed-against-error report;
//! - [`output`]: writers of `summary.json`, CSV and SVG from typed results
//!   (they compute nothing), written atomically;
//! - [`pipeline`]: running a scene, stage after stage (its model built from
//!   `[model]` or by the reducer of `[reduce]`);
//! - [`number`]: numbers from user input in messages and CSV files.
//!
//! Dependencies point one way: `pipeline` uses every stage, `output` reads
//! the stages' result types, and no two files or folders import each other
//! (checked by the suite's `layers::no_import_cycles_between_files_or_folders`).

pub mod analyses;
pub mod chebyshev;
pub mod compare;
pub mod continuation;
pub mod fom;
pub mod model;
pub mod number;
pub mod output;
pub mod pipeline;
pub mod plan;
pub mod poly;
pub mod reduce;
pub mod rom;
pub mod scene;
pub mod spec;
pub mod spectrum;
pub mod ssm;

pub use num_complex::Complex64 as C64;
